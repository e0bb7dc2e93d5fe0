// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file bench_util.h
/// Small helpers the bench programs share: the thread's CPU time, a fixed
/// random choice of sample points, and a cloud's diffusion problem.

#include <time.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <random>
#include <vector>

#include "sss/cloud/point_cloud.h"
#include "sss/diffusion/diffusion.h"

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

/// The points, normals, areas (_area) and irradiance (_radiance_t) of a
/// baked cloud as a diffusion problem, without profiles.
inline sss::DiffusionProblem cloud_problem(const sss::PointCloud& c) {
    sss::DiffusionProblem pb;
    pb.positions = c.positions;
    pb.normals = c.normals;
    pb.areas = c.find_channel("_area")->data;
    const sss::Channel* rad = c.find_channel("_radiance_t");
    pb.irradiance.resize(c.size());
    for (std::size_t i = 0; i < c.size(); ++i)
        pb.irradiance[i] = {rad->data[3 * i], rad->data[3 * i + 1], rad->data[3 * i + 2]};
    return pb;
}

} // namespace sss_bench
