// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file brickmap_lookup_test.cpp
/// BrickMap::lookup against a straightforward reference: the texture3d rules
/// of docs/bkm-format.md written out plainly over bricks read with
/// read_brick (all 512 samples, from the file, no cache), with the
/// arithmetic of the lookups before their layout was optimised (issue 17).
/// The optimised path (packed bricks, branch-free corners, the descent) must
/// give the same bits in any order of lookups and with any cache size.

#include <gtest/gtest.h>

#include "test_util.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include "sss/brick/brickmap.h"
#include "sss/cloud/point_cloud.h"
#include "sss/cloud/synthetic.h"

using sss::BrickMap;
using sss::BrickMapBuildOptions;
using sss::ChannelType;
using sss::PointCloud;

namespace {

using sss::test::TempDir;

constexpr int kEdge = 7;       // sample steps per brick edge
constexpr int kCoordBits = 20; // node coordinates at the deepest depth a file may use
constexpr double kCos55 = 0.57357643635104609611;

/// The reference lookup: every step spelled out, bricks by read_brick.
class ReferenceLookup {
public:
    explicit ReferenceLookup(const BrickMap& map) : m_map(map) {
        const sss::BrickMapInfo& info = map.info();
        m_ds = info.data_size;
        for (int a = 0; a < 3; ++a) m_cube_min[a] = info.cube_min[a];
        m_side = info.cube_side;
        m_inv_side = 1.0 / info.cube_side;
    }

    bool lookup(const glm::vec3& p, const glm::vec3& n, float filter_radius, float* out) {
        std::fill(out, out + m_ds, 0.0f);
        double u[3];
        for (int a = 0; a < 3; ++a) {
            u[a] = (double(p[a]) - m_cube_min[a]) * m_inv_side;
            if (!(u[a] >= 0.0 && u[a] <= 1.0)) return false;
        }
        int order[4];
        int count = 0;
        const double nx = n.x, ny = n.y, nz = n.z;
        const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
        if (!m_map.info().ignore_normals && len > 0.0 && std::isfinite(len)) {
            const double c[3] = {nx / len, ny / len, nz / len};
            const double m[3] = {std::abs(c[0]), std::abs(c[1]), std::abs(c[2])};
            int axes[3] = {0, 1, 2};
            if (m[axes[1]] > m[axes[0]]) std::swap(axes[0], axes[1]);
            if (m[axes[2]] > m[axes[1]]) std::swap(axes[1], axes[2]);
            if (m[axes[1]] > m[axes[0]]) std::swap(axes[0], axes[1]);
            for (int k = 0; k < 3; ++k) {
                const int a = axes[k];
                if (k == 0 || std::abs(c[a]) >= kCos55)
                    order[count++] = 1 + 2 * a + (c[a] < 0.0 ? 1 : 0);
            }
        }
        order[count++] = 0;
        std::vector<float> scratch(static_cast<std::size_t>(m_ds));
        for (int k = 0; k < count; ++k) {
            if (lookup_tree(order[k], u, filter_radius, out, scratch.data())) return true;
            std::fill(out, out + m_ds, 0.0f);
        }
        return false;
    }

private:
    struct Brick {
        bool exists = false;
        std::vector<float> data;
        std::vector<uint8_t> present;
    };

    const Brick& brick(int tree, int depth, const uint32_t q[3]) {
        const int shift = kCoordBits - depth;
        const auto key =
            std::make_tuple(tree, depth, q[0] >> shift, q[1] >> shift, q[2] >> shift);
        auto it = m_bricks.find(key);
        if (it == m_bricks.end()) {
            Brick b;
            b.exists = m_map.read_brick(tree, depth, q[0] >> shift, q[1] >> shift,
                                        q[2] >> shift, b.data, b.present);
            it = m_bricks.emplace(key, std::move(b)).first;
        }
        return it->second;
    }

    /// Trilinear over the present corners, skipping absent ones.
    bool eval_brick(const Brick& b, const double x[3], double weight, float* out) const {
        int i0[3];
        double f[3];
        for (int a = 0; a < 3; ++a) {
            i0[a] = std::min(static_cast<int>(x[a]), 6);
            f[a] = x[a] - i0[a];
        }
        const int base = i0[0] + 8 * i0[1] + 64 * i0[2];
        static constexpr int kOffset[8] = {0, 1, 8, 9, 64, 65, 72, 73};
        double w[8];
        double sum = 0.0;
        for (int c = 0; c < 8; ++c) {
            if (!b.present[base + kOffset[c]]) {
                w[c] = 0.0;
                continue;
            }
            w[c] = ((c & 1) ? f[0] : 1.0 - f[0]) * ((c & 2) ? f[1] : 1.0 - f[1]) *
                   ((c & 4) ? f[2] : 1.0 - f[2]);
            sum += w[c];
        }
        if (!(sum > 0.0)) return false;
        const double scale = weight / sum;
        for (int c = 0; c < 8; ++c) {
            if (w[c] == 0.0) continue;
            const float* v = &b.data[static_cast<std::size_t>(base + kOffset[c]) * m_ds];
            const float wc = static_cast<float>(w[c] * scale);
            for (int k = 0; k < m_ds; ++k) out[k] += wc * v[k];
        }
        return true;
    }

    int eval_level(int tree, int start, const double u[3], const uint32_t q[3],
                   double weight, float* out) {
        for (int d = start; d >= 0; --d) {
            const Brick& b = brick(tree, d, q);
            const double scale = kEdge * double(1u << d);
            double x[3];
            for (int a = 0; a < 3; ++a) {
                const uint32_t node = q[a] >> (kCoordBits - d);
                x[a] =
                    std::clamp(u[a] * scale - kEdge * double(node), 0.0, double(kEdge));
            }
            if (eval_brick(b, x, weight, out)) return d;
        }
        return -1;
    }

    bool lookup_tree(int tree, const double u[3], float filter_radius, float* out,
                     float* scratch) {
        uint32_t q[3];
        for (int a = 0; a < 3; ++a) {
            q[a] = static_cast<uint32_t>(std::min(u[a] * double(1u << kCoordBits),
                                                  double((1u << kCoordBits) - 1)));
        }
        // The deepest data brick on the path from the root (data bricks are
        // closed under "parent of").
        if (!brick(tree, 0, q).exists) return false;
        int deepest = 0;
        while (deepest < kCoordBits && brick(tree, deepest + 1, q).exists) ++deepest;
        if (!(filter_radius > 0.0f))
            return eval_level(tree, deepest, u, q, 1.0, out) >= 0;
        const double level = std::log2(m_side / (kEdge * 2.0 * double(filter_radius)));
        if (!(level > 0.0)) return eval_level(tree, 0, u, q, 1.0, out) >= 0;
        const int d0 = static_cast<int>(std::floor(level));
        const double f = level - d0;
        if (d0 >= deepest) return eval_level(tree, deepest, u, q, 1.0, out) >= 0;
        const int fine = eval_level(tree, d0 + 1, u, q, 1.0, out);
        if (fine < 0) return false;
        if (fine <= d0 || f >= 1.0) return true;
        std::fill(scratch, scratch + m_ds, 0.0f);
        if (eval_level(tree, d0, u, q, 1.0, scratch) < 0) return true;
        const float wf = static_cast<float>(f), wc = static_cast<float>(1.0 - f);
        for (int k = 0; k < m_ds; ++k) out[k] = wf * out[k] + wc * scratch[k];
        return true;
    }

    const BrickMap& m_map;
    int m_ds = 0;
    double m_cube_min[3] = {0, 0, 0};
    double m_side = 1.0;
    double m_inv_side = 1.0;
    std::map<std::tuple<int, int, uint32_t, uint32_t, uint32_t>, Brick> m_bricks;
};

struct Query {
    glm::vec3 p, n;
    float radius;
};

/// Lookups of every kind: at the points, off the surface, with other
/// normals, zero normals, outside the cube, at many filter radii.
std::vector<Query> queries(const PointCloud& cloud, std::size_t count) {
    std::vector<Query> out;
    float extent = 0.0f; // of the points, about the origin
    for (const glm::vec3& p : cloud.positions)
        extent = std::max({extent, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
    uint64_t x = 0x9E3779B97F4A7C15ull;
    auto next = [&] {
        x ^= x << 13, x ^= x >> 7, x ^= x << 17;
        return x;
    };
    auto uniform = [&] { return float((next() >> 40) * 0x1.0p-24); };
    auto offset = [&] {
        return glm::vec3(uniform() - 0.5f, uniform() - 0.5f, uniform() - 0.5f);
    };
    // Filter radii from far below the finest sample spacing to above the
    // root brick's.
    const float radii[] = {1e-5f, 1e-4f, 4e-4f, 1e-3f, 4e-3f, 0.02f, 0.1f, 0.5f};
    for (std::size_t k = 0; k < count; ++k) {
        const std::size_t i = next() % cloud.size();
        Query q{cloud.positions[i], cloud.normals[i],
                radii[next() % 8] * extent * (1 + uniform())};
        switch (k % 8) {
        case 1:
            q.p += offset() * (0.002f * extent);
            break; // near the surface
        case 2:
            q.p += offset() * (0.05f * extent);
            break; // off it: coarser data
        case 3:
            q.n = offset();
            break; // another normal
        case 4:
            q.n = glm::vec3(0.0f);
            break; // no normal
        case 5:
            q.p = offset() * (2.6f * extent);
            break; // anywhere, outside too
        default:
            break;
        }
        if (k % 3 == 0) q.radius = 0.0f;
        out.push_back(q);
    }
    // Normals with two or three equal (or all but equal) largest components:
    // which tree comes first then rests on the rounding of n / |n|.
    const float one = 1.0f, above = std::nextafter(1.0f, 2.0f);
    const glm::vec3 ties[] = {{one, one, 0.2f},     {-one, one, one},
                              {one, above, 0.0f},   {above, -one, 0.5f},
                              {0.3f, one, -above},  {one, one, one},
                              {0.0f, -one, -above}, {1e-30f, 1e-30f, 0.0f}};
    for (std::size_t k = 0; k < count / 4; ++k) {
        const std::size_t i = next() % cloud.size();
        out.push_back({cloud.positions[i], ties[k % 8], k % 2 ? 0.0f : 0.004f * extent});
    }
    return out;
}

PointCloud sphere(std::size_t count) {
    sss::SyntheticParams p;
    p.count = count;
    p.light_dir = {0.3, 0.4, 1.0};
    PointCloud c = sss::make_synthetic_cloud(p);
    // A second colour and a float varying over the surface: 8 floats per
    // sample when all channels are kept (the general path of the blend).
    sss::Channel& tint = c.add_channel("tint", ChannelType::Color);
    for (std::size_t i = 0; i < c.size(); ++i) {
        for (int k = 0; k < 3; ++k)
            tint.data[3 * i + k] = std::sin(3.0f * c.positions[i][k]) + float(k);
    }
    sss::Channel& h = c.add_channel("height", ChannelType::Float);
    for (std::size_t i = 0; i < c.size(); ++i) h.data[i] = c.positions[i].z * 4.0f - 1.0f;
    return c;
}

/// Every query through `map` in the order given by `order` equals the
/// reference, bit for bit (and whether it found data).
void expect_reference(const BrickMap& map, ReferenceLookup& ref,
                      const std::vector<Query>& qs, const std::vector<std::size_t>& order,
                      const std::string& what) {
    const int ds = map.info().data_size;
    std::vector<float> got(static_cast<std::size_t>(ds)), want(got.size());
    std::size_t found = 0, mismatches = 0;
    for (std::size_t i : order) {
        const Query& q = qs[i];
        const bool g = map.lookup(q.p, q.n, q.radius, got.data());
        const bool w = ref.lookup(q.p, q.n, q.radius, want.data());
        found += g ? 1 : 0;
        if (g != w ||
            std::memcmp(got.data(), want.data(), got.size() * sizeof(float)) != 0) {
            if (++mismatches <= 5) {
                ADD_FAILURE() << what << ": query " << i << " p (" << q.p.x << ", "
                              << q.p.y << ", " << q.p.z << ") radius " << q.radius
                              << ": found " << g << " / " << w << ", first value "
                              << got[0] << " / " << want[0];
            }
        }
    }
    EXPECT_EQ(mismatches, 0u) << what;
    // The queries reach data most of the time, and miss it sometimes.
    EXPECT_GT(found, qs.size() / 2) << what;
    EXPECT_LT(found, qs.size()) << what;
}

} // namespace

TEST(BrickMapLookupReference, EqualsTheReferenceInAnyOrderAndCacheSize) {
    TempDir dir;
    const PointCloud cloud = sphere(30000);
    const std::vector<Query> qs = queries(cloud, 6000);
    std::vector<std::size_t> coherent(qs.size()), scattered(qs.size());
    for (std::size_t i = 0; i < qs.size(); ++i) coherent[i] = i;
    // Queries sorted along the points' order are spatially coherent; the
    // scattered order is a fixed random permutation.
    std::sort(coherent.begin(), coherent.end(), [&](std::size_t a, std::size_t b) {
        return std::make_tuple(qs[a].p.z, qs[a].p.y, qs[a].p.x) <
               std::make_tuple(qs[b].p.z, qs[b].p.y, qs[b].p.x);
    });
    scattered = coherent;
    uint64_t x = 12345;
    for (std::size_t i = scattered.size() - 1; i > 0; --i) {
        x = x * 6364136223846793005ull + 1442695040888963407ull;
        std::swap(scattered[i], scattered[(x >> 33) % (i + 1)]);
    }
    // Floats per sample 1, 3, 4 (the specialised blends) and 8 (the general one).
    const std::vector<std::pair<std::vector<std::string>, int>> selections = {
        {{"_area"}, 1}, {{"_radiance_t"}, 3}, {{"_area", "_radiance_t"}, 4}, {{}, 8}};
    for (const auto& [channels, ds] : selections) {
        BrickMapBuildOptions o;
        o.channels = channels;
        const std::string path = dir.file(std::to_string(ds) + "floats.bkm");
        sss::build_brick_map({cloud}, o, path);
        const BrickMap reference_map(path);
        ASSERT_EQ(reference_map.info().data_size, ds);
        ReferenceLookup ref(reference_map);
        const std::string name = std::to_string(ds) + " floats";
        {
            const BrickMap map(path);
            expect_reference(map, ref, qs, coherent, name + ", coherent order");
            expect_reference(map, ref, qs, scattered, name + ", warm cache, scattered");
        }
        {
            const BrickMap map(path);
            expect_reference(map, ref, qs, scattered, name + ", cold cache, scattered");
        }
        {
            // A cache of a few bricks: every lookup loads and evicts.
            const BrickMap map(path, std::size_t(32) << 10);
            expect_reference(map, ref, qs, scattered, name + ", tiny cache, scattered");
        }
    }
}

TEST(BrickMapLookupReference, IgnoreNormalsAndPlanesEqualTheReference) {
    TempDir dir;
    // One tree (-ignorenormals 1): all lookups take tree 0.
    const PointCloud cloud = sphere(8000);
    BrickMapBuildOptions o;
    o.ignore_normals = true;
    o.max_error = 0.0;
    sss::build_brick_map({cloud}, o, dir.file("i.bkm"));
    const BrickMap map(dir.file("i.bkm"));
    ReferenceLookup ref(map);
    const std::vector<Query> qs = queries(cloud, 3000);
    std::vector<std::size_t> order(qs.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = (i * 7919) % order.size();
    expect_reference(map, ref, qs, order, "ignore normals");
}
