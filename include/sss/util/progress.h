#pragma once
/// \file progress.h
/// Progress lines for render farms (ALF_PROGRESS) and a wall-clock stopwatch.

#include <atomic>
#include <cstdint>
#include <mutex>

namespace sss {

/// Thread-safe progress reporter for render farms: prints "ALF_PROGRESS NN%"
/// on stdout, flushed, each time the integer percentage grows.
class Progress {
public:
    explicit Progress(bool enabled) : m_enabled(enabled) {}
    /// Reports that `done` of `total` units are finished.
    void update(uint64_t done, uint64_t total);
    /// Prints 100% if not printed yet.
    void finish();
    bool enabled() const { return m_enabled; }

private:
    bool m_enabled;
    std::atomic<int> m_last{-1};
    std::mutex m_mutex;
};

/// Wall-clock stopwatch in seconds.
class Stopwatch {
public:
    Stopwatch();
    double seconds() const;

private:
    int64_t m_start_ns;
};

} // namespace sss
