// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// texture3d on a point cloud against the brick map made from it: a
// _ssdiffusion sphere (a lit marble sphere of radius 50 mm, diffused by
// ptfilter's library call, 1M points by default) looked up with
// PointCloudLookup (what texture3d does on a .ptc: the 8 nearest points,
// normal-aware) and with BrickMap (what it does on a .bkm, at the finest
// level and at the points' own filter radius), at points on the surface
// that are not the cloud's (a latitude-longitude lattice about as dense as
// the points): in 16 x 16 tiles (as a bucket renderer shades), in rows
// around the sphere, and in a scattered order. Rates are lookups per second of the
// thread's CPU time on one core, so other processes on a shared machine do not count.
//
// Uses only PointCloudLookup's original interface, so that it builds
// against older versions of the library for before/after figures.
//
// usage: ptc_lookup_bench [-n POINTS] [-lookups N] [-maxerror E]

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "bench_util.h"
#include "sss/brick/brickmap.h"
#include "sss/cloud/point_cloud_lookup.h"
#include "sss/cloud/synthetic.h"
#include "sss/diffusion/ssdiffusion.h"
#include "sss/util/progress.h"
#include "sss/util/threads.h"

namespace {

using sss_bench::thread_seconds;

struct Queries {
    std::vector<glm::vec3> p, n;
};

/// About `count` points on the sphere of radius `r`, row by row in
/// latitude, each row's points in order of longitude; with `tile` > 0, in
/// tiles of about tile x tile points (row by row within a tile), as a
/// bucket renderer shades them.
Queries sphere_queries(std::size_t count, float r, int tile) {
    struct Query {
        long key;
        glm::vec3 d;
    };
    std::vector<Query> all;
    const int rows = std::max(1, int(std::sqrt(double(count) / 2.0)));
    const double pi = 3.14159265358979323846;
    const double tile_phi = 2.0 * pi * std::max(tile, 1) / (2.0 * rows);
    for (int j = 0; j < rows; ++j) {
        const double theta = pi * (j + 0.5) / rows;
        const int cols = std::max(1, int(std::lround(2.0 * rows * std::sin(theta))));
        for (int i = 0; i < cols; ++i) {
            const double phi = 2.0 * pi * (i + 0.5) / cols;
            const glm::vec3 d(float(std::sin(theta) * std::cos(phi)),
                              float(std::sin(theta) * std::sin(phi)),
                              float(std::cos(theta)));
            const long key =
                tile > 0 ? long(j / tile) * 1000000L + long(phi / tile_phi) : 0;
            all.push_back({key, d});
        }
    }
    std::stable_sort(all.begin(), all.end(),
                     [](const Query& a, const Query& b) { return a.key < b.key; });
    Queries q;
    for (const Query& x : all) {
        q.p.push_back(r * x.d);
        q.n.push_back(x.d);
    }
    return q;
}

Queries scattered(const Queries& in) {
    Queries q = in;
    uint64_t x = 88172645463325252ull;
    for (std::size_t i = q.p.size(); i > 1; --i) {
        x ^= x << 13, x ^= x >> 7, x ^= x << 17;
        const std::size_t j = x % i;
        std::swap(q.p[i - 1], q.p[j]);
        std::swap(q.n[i - 1], q.n[j]);
    }
    return q;
}

/// Lookups per second of one thread's CPU time, after one warm-up pass.
template <typename F>
double rate(const Queries& q, F&& lookup) {
    sss::ThreadLimit limit(1);
    for (std::size_t k = 0; k < q.p.size(); ++k) lookup(q.p[k], q.n[k]);
    const double t0 = thread_seconds();
    for (std::size_t k = 0; k < q.p.size(); ++k) lookup(q.p[k], q.n[k]);
    return double(q.p.size()) / (thread_seconds() - t0);
}

} // namespace

int main(int argc, char** argv) {
    std::size_t n = 1000000, lookups = 1000000;
    double max_error = 0.002;
    for (int i = 1; i < argc; ++i) {
        std::string o = argv[i];
        if (o == "-n" && i + 1 < argc) {
            n = std::strtoull(argv[++i], nullptr, 10);
        } else if (o == "-lookups" && i + 1 < argc) {
            lookups = std::strtoull(argv[++i], nullptr, 10);
        } else if (o == "-maxerror" && i + 1 < argc) {
            max_error = std::atof(argv[++i]);
        } else {
            std::fprintf(
                stderr,
                "usage: ptc_lookup_bench [-n POINTS] [-lookups N] [-maxerror E]\n");
            return 2;
        }
    }
    const float size = 50.0f;
    sss::SyntheticParams sp;
    sp.count = n;
    sp.size = size;
    sp.light_dir = {1, 1, 1};
    sss::Stopwatch prep;
    const sss::PointCloud lit = sss::make_synthetic_cloud(sp);
    sss::SsDiffusionOptions so;
    const sss::PointCloud cloud = sss::ssdiffusion(lit, so);
    const double prep_s = prep.seconds();

    sss::Stopwatch index;
    const sss::PointCloudLookup ptc(cloud, {"_ssdiffusion"});
    const double index_s = index.seconds();

    const std::string path =
        (std::filesystem::temp_directory_path() / "sss_ptc_lookup_bench.bkm").string();
    sss::BrickMapBuildOptions bo;
    bo.max_error = max_error;
    sss::build_brick_map({cloud}, bo, path);
    sss::BrickMap bkm(path);
    const int ds = bkm.info().data_size;
    const int off = bkm.channel_offset("_ssdiffusion");
    const float point_radius = cloud.radii.empty() ? 0.0f : cloud.radii[0];

    std::printf("ptc_lookup_bench: %zu-point _ssdiffusion sphere (r = %g), prepared in "
                "%.1f s; PointCloudLookup indexed in %.2f s; brick map -maxerror %g\n",
                cloud.size(), size, prep_s, index_s, max_error);

    // Differences between the two, so that the lookups cannot be optimised
    // away and their agreement shows.
    double diff = 0.0;
    std::size_t compared = 0;
    const Queries tiles = sphere_queries(lookups, size, 16);
    const Queries rows = sphere_queries(lookups, size, 0);
    const Queries random = scattered(rows);
    std::printf(
        "| order | lookups | .ptc M/s | .bkm radius 0 M/s | .bkm point radius M/s | "
        "ptc / bkm cost (radius 0) | ptc / bkm cost (point radius) |\n");
    std::printf("|---|---|---|---|---|---|---|\n");
    for (const Queries* q : {&tiles, &rows, &random}) {
        std::vector<float> a(3), b(std::size_t(std::max(ds, 1)));
        const double r_ptc = rate(*q, [&](const glm::vec3& p, const glm::vec3& nn) {
            ptc.lookup(p, nn, 0.0f, a.data());
        });
        const double r_bkm0 = rate(*q, [&](const glm::vec3& p, const glm::vec3& nn) {
            bkm.lookup(p, nn, 0.0f, b.data());
        });
        const double r_bkmr = rate(*q, [&](const glm::vec3& p, const glm::vec3& nn) {
            bkm.lookup(p, nn, point_radius, b.data());
        });
        for (std::size_t k = 0; k < q->p.size(); k += 97) {
            if (!ptc.lookup(q->p[k], q->n[k], 0.0f, a.data()) ||
                !bkm.lookup(q->p[k], q->n[k], 0.0f, b.data()))
                continue;
            diff += std::fabs(double(a[0]) - b[off]);
            ++compared;
        }
        std::printf("| %s | %zu | %.3f | %.3f | %.3f | %.2f | %.2f |\n",
                    q == &tiles  ? "16 x 16 tiles"
                    : q == &rows ? "rows"
                                 : "scattered",
                    q->p.size(), r_ptc * 1e-6, r_bkm0 * 1e-6, r_bkmr * 1e-6,
                    r_bkm0 / r_ptc, r_bkmr / r_ptc);
        std::fflush(stdout);
    }
    std::printf("mean |ptc - bkm| (red, radius 0): %.5f over %zu lookups\n",
                diff / double(std::max<std::size_t>(compared, 1)), compared);
    std::filesystem::remove(path);
    return 0;
}
