// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// brickmake benchmark: a 1M-point _ssdiffusion cloud (a lit marble sphere of
// radius 50 mm, diffused by ptfilter's library call) -> brick map, for a few
// -maxerror values: build time, file size, bricks, lookups per second on one
// core (in point order, in random order, in random order with the points'
// filter radii, in random order with the points gathered first) and with all
// threads, the memory of the cached bricks, and
// the lookup error against the point values at the points themselves
// (|lookup - value| in the channel's units and relative to the channel mean).
//
// The one-core rates divide by the thread's CPU time, so that other
// processes on a shared machine do not count against them (the random-order
// rate by the wall clock is printed too); the threaded rate is by the wall
// clock.
//
// usage: brickmap_bench [-n POINTS] [-lookups N] [-maxerror E ...]

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <tbb/parallel_for.h>

#include "bench_util.h"
#include "sss/brick/brickmap.h"
#include "sss/cloud/point_cloud_io.h"
#include "sss/cloud/synthetic.h"
#include "sss/diffusion/ssdiffusion.h"
#include "sss/util/progress.h"
#include "sss/util/threads.h"

namespace {

using sss_bench::thread_seconds;

struct Result {
    double max_error = 0;
    double build_s = 0;
    uint64_t bytes = 0;
    std::size_t bricks = 0;
    double lookups_per_s_1 = 0;
    double lookups_per_s_random = 0;
    double lookups_per_s_random_wall = 0;
    double lookups_per_s_filtered = 0;
    double lookups_per_s_gathered = 0;
    double cache_mb = 0;
    double lookups_per_s_all = 0;
    double rms = 0, p99 = 0, max = 0, mean = 0;
    std::size_t misses = 0;
};

} // namespace

int main(int argc, char** argv) {
    std::size_t n = 1000000, lookups = 1000000;
    std::vector<double> errors;
    for (int i = 1; i < argc; ++i) {
        std::string o = argv[i];
        if (o == "-n" && i + 1 < argc) {
            n = std::strtoull(argv[++i], nullptr, 10);
        } else if (o == "-lookups" && i + 1 < argc) {
            lookups = std::strtoull(argv[++i], nullptr, 10);
        } else if (o == "-maxerror" && i + 1 < argc) {
            errors.push_back(std::atof(argv[++i]));
        } else {
            std::fprintf(
                stderr,
                "usage: brickmap_bench [-n POINTS] [-lookups N] [-maxerror E ...]\n");
            return 2;
        }
    }
    if (errors.empty()) errors = {0.0005, 0.002, 0.01};
    const int threads = sss::resolve_thread_count(0);

    // The input: what ptfilter writes for a lit marble sphere.
    sss::SyntheticParams sp;
    sp.count = n;
    sp.size = 50.0;
    sp.light_dir = {1, 1, 1};
    sss::Stopwatch prep;
    sss::PointCloud lit = sss::make_synthetic_cloud(sp);
    sss::SsDiffusionOptions so;
    sss::PointCloud cloud = sss::ssdiffusion(lit, so);
    const sss::Channel* ssd = cloud.find_channel("_ssdiffusion");
    double mean = 0;
    for (std::size_t i = 0; i < cloud.size(); ++i) mean += ssd->data[3 * i];
    mean /= double(cloud.size());
    std::printf(
        "brickmap_bench: %zu-point _ssdiffusion sphere (r = 50, marble), prepared in "
        "%.1f s; red mean %.4f; %d threads\n",
        cloud.size(), prep.seconds(), mean, threads);

    const std::string path =
        (std::filesystem::temp_directory_path() / "sss_brickmap_bench.bkm").string();
    std::printf(
        "| maxerror | build s | file MB | bricks | lookups/s 1 core | random order 1 "
        "core | random, wall clock | random, filter radius | random, points "
        "gathered | lookups/s %d threads | cache MB | RMS err | 99%% err | max err | "
        "max / mean | misses |\n",
        threads);
    std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (double e : errors) {
        Result r;
        r.max_error = e;
        sss::BrickMapBuildOptions bo;
        bo.max_error = e;
        sss::Stopwatch build;
        sss::BrickMapBuildReport rep = sss::build_brick_map({cloud}, bo, path);
        r.build_s = build.seconds();
        r.bytes = rep.file_size;
        r.bricks = rep.bricks_written;

        sss::BrickMap map(path);
        const int ds = map.info().data_size;
        const int off = map.channel_offset("_ssdiffusion");
        // Lookups at the points themselves, at the finest level (radius 0).
        const std::size_t m = std::min(lookups, cloud.size());
        const std::size_t stride = std::max<std::size_t>(1, cloud.size() / m);
        std::vector<float> got(m, 0.0f);
        std::vector<uint8_t> ok(m, 0);
        auto one = [&](std::size_t k) {
            std::vector<float> out(ds);
            const std::size_t i = k * stride;
            ok[k] = map.lookup(cloud.positions[i], cloud.normals[i], 0.0f, out.data());
            got[k] = out[off];
        };
        {
            sss::ThreadLimit limit(1);
            for (std::size_t k = 0; k < m; ++k) one(k); // warm the cache
            const double t0 = thread_seconds();
            for (std::size_t k = 0; k < m; ++k) one(k);
            r.lookups_per_s_1 = double(m) / (thread_seconds() - t0);
        }
        // The same lookups in a scattered order (no locality between
        // consecutive lookups): the cost of going to memory. Then with each
        // point's filter radius, which blends two levels (what a renderer's
        // texture3d does with its ray differentials).
        for (const bool filtered : {false, true}) {
            sss::ThreadLimit limit(1);
            std::vector<float> out(ds);
            uint64_t x = 88172645463325252ull;
            sss::Stopwatch wall;
            const double t0 = thread_seconds();
            for (std::size_t k = 0; k < m; ++k) {
                x ^= x << 13, x ^= x >> 7, x ^= x << 17;
                const std::size_t i = x % cloud.size();
                map.lookup(cloud.positions[i], cloud.normals[i],
                           filtered ? cloud.radii[i] : 0.0f, out.data());
            }
            const double cpu = thread_seconds() - t0;
            if (filtered) {
                r.lookups_per_s_filtered = double(m) / cpu;
            } else {
                r.lookups_per_s_random = double(m) / cpu;
                r.lookups_per_s_random_wall = double(m) / wall.seconds();
            }
        }
        {
            // The random order again with the points copied out first, in
            // that order: the lookups alone, without the bench's own cache
            // miss on the cloud per lookup (a renderer has its hit points at
            // hand).
            sss::ThreadLimit limit(1);
            std::vector<glm::vec3> positions(m), normals(m);
            uint64_t x = 88172645463325252ull;
            for (std::size_t k = 0; k < m; ++k) {
                x ^= x << 13, x ^= x >> 7, x ^= x << 17;
                const std::size_t i = x % cloud.size();
                positions[k] = cloud.positions[i];
                normals[k] = cloud.normals[i];
            }
            std::vector<float> out(ds);
            const double t0 = thread_seconds();
            for (std::size_t k = 0; k < m; ++k)
                map.lookup(positions[k], normals[k], 0.0f, out.data());
            r.lookups_per_s_gathered = double(m) / (thread_seconds() - t0);
        }
        {
            sss::Stopwatch t;
            tbb::parallel_for(std::size_t(0), m, [&](std::size_t k) { one(k); });
            r.lookups_per_s_all = double(m) / t.seconds();
        }
        r.cache_mb = double(map.cached_bytes()) / 1048576.0;
        std::vector<double> err;
        err.reserve(m);
        double sum2 = 0;
        for (std::size_t k = 0; k < m; ++k) {
            if (!ok[k]) {
                ++r.misses;
                continue;
            }
            double d = std::abs(double(got[k]) - ssd->data[3 * (k * stride)]);
            err.push_back(d);
            sum2 += d * d;
        }
        std::sort(err.begin(), err.end());
        r.rms = std::sqrt(sum2 / std::max<std::size_t>(1, err.size()));
        r.p99 = err.empty() ? 0 : err[std::size_t(0.99 * (err.size() - 1))];
        r.max = err.empty() ? 0 : err.back();
        std::printf("| %g | %.2f | %.1f | %zu | ", e, r.build_s, r.bytes / 1048576.0,
                    r.bricks);
        for (double rate :
             {r.lookups_per_s_1, r.lookups_per_s_random, r.lookups_per_s_random_wall,
              r.lookups_per_s_filtered, r.lookups_per_s_gathered, r.lookups_per_s_all})
            std::printf("%.2f M | ", rate * 1e-6);
        std::printf("%.1f | %.5f | %.5f | %.5f | %.2f %% | %zu |\n", r.cache_mb, r.rms,
                    r.p99, r.max, 100.0 * r.max / mean, r.misses);
        std::fflush(stdout);
    }
    std::filesystem::remove(path);
    return 0;
}
