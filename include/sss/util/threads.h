// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file threads.h
/// Thread counts: the cores a job may use (CPU affinity and cgroup quota
/// aware) and a scoped limit on oneTBB's parallelism.

#include <atomic>
#include <cstddef>
#include <memory>

namespace sss {

/// Lowers `first` to `i` if i is smaller: the first bad index of a parallel
/// loop, the same whatever order the threads reach it in (the caller then
/// checks that one element again to report it).
inline void lower_to(std::atomic<std::size_t>& first, std::size_t i) {
    std::size_t seen = first.load();
    while (i < seen && !first.compare_exchange_weak(seen, i)) {
    }
}

/// Resolves a -threads value: N > 0 is exact, 0 = every usable core (CPU
/// affinity and cgroup quota aware), N < 0 = usable cores minus |N| (at least 1).
int resolve_thread_count(int requested);

/// Limits oneTBB parallelism to n threads while alive.
class ThreadLimit {
public:
    explicit ThreadLimit(int n);
    ~ThreadLimit();
    ThreadLimit(const ThreadLimit&) = delete;
    ThreadLimit& operator=(const ThreadLimit&) = delete;

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

} // namespace sss
