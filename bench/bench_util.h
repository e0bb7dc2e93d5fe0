#pragma once
/// \file bench_util.h
/// Small helpers the bench programs share: the thread's CPU time and a
/// fixed random choice of sample points.

#include <time.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <random>
#include <vector>

namespace sss_bench {

/// CPU time of the calling thread, in seconds.
inline double thread_seconds() {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

/// `count` distinct indices of [0, n) (all of them when count >= n), drawn
/// with `seed`, in increasing order.
inline std::vector<std::size_t> random_samples(std::size_t n, std::size_t count,
                                               uint64_t seed) {
    std::vector<std::size_t> idx(n);
    std::iota(idx.begin(), idx.end(), std::size_t(0));
    std::mt19937_64 rng(seed);
    count = std::min(count, n);
    for (std::size_t k = 0; k < count; ++k) {
        std::uniform_int_distribution<std::size_t> pick(k, n - 1);
        std::swap(idx[k], idx[pick(rng)]);
    }
    idx.resize(count);
    std::sort(idx.begin(), idx.end());
    return idx;
}

} // namespace sss_bench
