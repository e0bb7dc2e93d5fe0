// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file point_cloud_lookup_reference_test.cpp
/// PointCloudLookup against a brute-force reference: the k + 1 = 9 nearest
/// qualifying points by sorting every point, weighted as documented
/// (point_cloud_lookup.h), on random clouds with and without normals, with
/// filter radii, in coherent and scattered query orders (a result must not
/// depend on the lookups before it), and at the edges: an empty cloud, one point,
/// coincident points, points without normals, fewer points than k, queries far away.
///
/// The reference adds the same terms in the same order as the lookup when
/// averaging the nearest points, so those results agree to the last bit in
/// practice; the tolerance allows 1e-6 relative. Sums within a radius are
/// added in tree order by the lookup, in index order here: 1e-5 relative.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <vector>

#include <glm/geometric.hpp>
#include <oneapi/tbb/parallel_for.h>

#include "sss/cloud/point_cloud.h"
#include "sss/cloud/point_cloud_lookup.h"
#include "sss/util/error.h"

using sss::ChannelType;
using sss::PointCloud;
using sss::PointCloudLookup;

namespace {

/// Deterministic uniform numbers in [0, 1).
struct Rng {
    uint64_t state;
    explicit Rng(uint64_t seed) : state(seed * 0x9E3779B97F4A7C15ull + 1) {}
    double next() {
        uint64_t z = (state += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return double((z ^ (z >> 31)) >> 11) * 0x1.0p-53;
    }
    float range(float lo, float hi) { return lo + float(next()) * (hi - lo); }
    glm::vec3 direction() {
        for (;;) {
            glm::vec3 v(range(-1, 1), range(-1, 1), range(-1, 1));
            float l = glm::length(v);
            if (l > 0.1f && l <= 1.0f) return v / l;
        }
    }
};

/// Channels "a" (float) and "c" (color) with random values.
void add_random_data(PointCloud& cloud, Rng& rng) {
    cloud.add_channel("a", ChannelType::Float);
    cloud.add_channel("c", ChannelType::Color);
    for (float& v : cloud.find_channel("a")->data) v = rng.range(-1.0f, 3.0f);
    for (float& v : cloud.find_channel("c")->data) v = rng.range(0.0f, 1.0f);
}

/// `count` points on a unit sphere with outward normals (or none).
PointCloud sphere_cloud(std::size_t count, bool normals, uint64_t seed) {
    Rng rng(seed);
    PointCloud cloud;
    cloud.resize(count);
    for (std::size_t i = 0; i < count; ++i) {
        const glm::vec3 d = rng.direction();
        cloud.positions[i] = d;
        cloud.normals[i] = normals ? d : glm::vec3(0.0f);
        cloud.radii[i] = 0.01f;
    }
    add_random_data(cloud, rng);
    return cloud;
}

/// `count` points uniform in a box, with random normals (some zero).
PointCloud box_cloud(std::size_t count, uint64_t seed) {
    Rng rng(seed);
    PointCloud cloud;
    cloud.resize(count);
    for (std::size_t i = 0; i < count; ++i) {
        cloud.positions[i] =
            glm::vec3(rng.range(-2, 2), rng.range(-1, 1), rng.range(0, 3));
        cloud.normals[i] = rng.next() < 0.1 ? glm::vec3(0.0f) : 2.0f * rng.direction();
        cloud.radii[i] = 0.05f;
    }
    add_random_data(cloud, rng);
    return cloud;
}

/// Every float of the cloud's float and color channels per point, in
/// channel order (PointCloudLookup's default data).
std::vector<float> point_data(const PointCloud& cloud, std::size_t i) {
    std::vector<float> v;
    for (const sss::Channel& ch : cloud.channels) {
        if (ch.type != ChannelType::Float && ch.type != ChannelType::Color) continue;
        const int c = ch.components();
        for (int k = 0; k < c; ++k) v.push_back(ch.data[i * c + k]);
    }
    return v;
}

/// The documented lookup, by brute force. Returns false on a miss.
bool reference(const PointCloud& cloud, glm::vec3 p, glm::vec3 n, float radius,
               std::vector<float>& out, float* nearest = nullptr) {
    const int ds = int(point_data(cloud, 0).size());
    out.assign(std::size_t(ds), 0.0f);
    const float len = glm::length(n);
    const bool use_normal = len > 0.0f && std::isfinite(len);
    if (use_normal) n /= len;
    struct Cand {
        float d2;
        std::size_t i;
    };
    std::vector<Cand> all;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        glm::vec3 pn = cloud.normals[i];
        const float pl = glm::length(pn);
        pn = (pl > 0.0f && std::isfinite(pl)) ? pn / pl : glm::vec3(0.0f);
        if (use_normal && pn != glm::vec3(0.0f) && !(glm::dot(pn, n) >= 0.5f)) continue;
        const glm::vec3 d = cloud.positions[i] - p;
        all.push_back({glm::dot(d, d), i});
    }
    if (all.empty()) return false;
    // Coincident points tie; the test clouds give them the same data.
    std::stable_sort(all.begin(), all.end(),
                     [](const Cand& a, const Cand& b) { return a.d2 < b.d2; });
    if (radius > 0.0f) {
        std::vector<double> acc(std::size_t(ds), 0.0);
        double wsum = 0.0;
        float closest = std::numeric_limits<float>::infinity();
        for (const Cand& c : all) {
            if (!(c.d2 < radius * radius)) continue;
            const double w = 1.0 - std::sqrt(double(c.d2)) / radius;
            wsum += w;
            closest = std::min(closest, c.d2);
            const std::vector<float> v = point_data(cloud, c.i);
            for (int k = 0; k < ds; ++k) acc[k] += w * v[k];
        }
        if (wsum > 0.0) {
            for (int k = 0; k < ds; ++k) out[k] = float(acc[k] / wsum);
            if (nearest) *nearest = std::sqrt(closest);
            return true;
        }
    }
    const int found = int(std::min<std::size_t>(all.size(), 9));
    const int used = std::min(found, 8);
    const float reach =
        found > 8 ? std::sqrt(all[8].d2) : 2.0f * std::sqrt(all[used - 1].d2);
    std::vector<double> w(static_cast<std::size_t>(used), 0.0);
    double wsum = 0.0;
    for (int k = 0; k < used; ++k) {
        w[k] = reach > 0.0f ? std::max(0.0, 1.0 - std::sqrt(double(all[k].d2)) / reach)
                            : 0.0;
        wsum += w[k];
    }
    if (!(wsum > 0.0)) {
        std::fill(w.begin(), w.end(), 1.0);
        wsum = used;
    }
    for (int c = 0; c < ds; ++c) {
        double acc = 0.0;
        for (int k = 0; k < used; ++k) acc += w[k] * point_data(cloud, all[k].i)[c];
        out[c] = float(acc / wsum);
    }
    if (nearest) *nearest = std::sqrt(all[0].d2);
    return true;
}

struct Query {
    glm::vec3 p, n;
    float radius;
};

/// Compares every query's lookup with the reference; tolerance relative to
/// the values' magnitude (see the file comment).
void expect_matches(const PointCloud& cloud, const PointCloudLookup& lookup,
                    const std::vector<Query>& queries) {
    const int ds = lookup.data_size();
    std::vector<float> got(static_cast<std::size_t>(ds)), want;
    for (std::size_t q = 0; q < queries.size(); ++q) {
        const Query& x = queries[q];
        const bool hit = lookup.lookup(x.p, x.n, x.radius, got.data());
        const bool ref = reference(cloud, x.p, x.n, x.radius, want);
        ASSERT_EQ(hit, ref) << "query " << q;
        const double tol = x.radius > 0.0f ? 1e-5 : 1e-6;
        for (int c = 0; c < ds; ++c)
            ASSERT_NEAR(got[c], want[c], tol * (1.0 + std::fabs(want[c])))
                << "query " << q << " float " << c;
    }
}

/// Queries near the unit sphere: a coherent walk (each next to the last)
/// then scattered ones, with the surface normal, none, or a tilted one.
std::vector<Query> sphere_queries(int count, float radius, uint64_t seed) {
    Rng rng(seed);
    std::vector<Query> qs;
    glm::vec3 d = rng.direction();
    for (int k = 0; k < count; ++k) {
        if (k < count / 2) {
            d = glm::normalize(d + 0.02f * rng.direction()); // a walk
        } else {
            d = rng.direction();
        }
        const glm::vec3 p = d * rng.range(0.97f, 1.03f);
        glm::vec3 n = d;
        if (k % 5 == 3) n = glm::vec3(0.0f);
        if (k % 7 == 4) n = glm::normalize(d + 0.8f * rng.direction());
        qs.push_back({p, n, radius});
    }
    return qs;
}

} // namespace

TEST(PointCloudLookupReference, SphereWithNormalsNearest) {
    const PointCloud cloud = sphere_cloud(20000, true, 1);
    const PointCloudLookup lookup(cloud);
    expect_matches(cloud, lookup, sphere_queries(600, 0.0f, 2));
}

TEST(PointCloudLookupReference, SphereWithoutNormalsNearest) {
    const PointCloud cloud = sphere_cloud(5000, false, 3);
    const PointCloudLookup lookup(cloud);
    expect_matches(cloud, lookup, sphere_queries(400, 0.0f, 4));
}

TEST(PointCloudLookupReference, FilterRadius) {
    const PointCloud cloud = sphere_cloud(5000, true, 5);
    const PointCloudLookup lookup(cloud);
    // From fewer than one point in reach (the nearest-point fallback) to
    // many points.
    for (float r : {0.001f, 0.03f, 0.1f, 0.4f})
        expect_matches(cloud, lookup, sphere_queries(150, r, 6));
}

TEST(PointCloudLookupReference, BoxCloudRandomNormals) {
    // Random normals, a tenth of them zero (they qualify for any query normal).
    const PointCloud cloud = box_cloud(8000, 7);
    const PointCloudLookup lookup(cloud);
    Rng rng(8);
    std::vector<Query> qs;
    for (int k = 0; k < 500; ++k) {
        const glm::vec3 p(rng.range(-2.5f, 2.5f), rng.range(-1.5f, 1.5f),
                          rng.range(-0.5f, 3.5f));
        const glm::vec3 n = k % 4 == 0 ? glm::vec3(0.0f) : rng.direction();
        qs.push_back({p, n, k % 3 == 0 ? 0.2f : 0.0f});
    }
    expect_matches(cloud, lookup, qs);
}

TEST(PointCloudLookupReference, OrderAndThreadsDoNotChangeResults) {
    const PointCloud cloud = sphere_cloud(20000, true, 9);
    const PointCloudLookup lookup(cloud);
    const PointCloudLookup other(cloud, {"c"}); // interleaved on the same threads
    std::vector<Query> qs = sphere_queries(4000, 0.0f, 10);
    const int ds = lookup.data_size();
    auto run = [&](const std::vector<std::size_t>& order, bool parallel) {
        std::vector<float> out(qs.size() * std::size_t(ds));
        auto one = [&](std::size_t k) {
            const std::size_t q = order[k];
            float scratch[3];
            other.lookup(qs[q].p, -qs[q].n, 0.0f, scratch);
            lookup.lookup(qs[q].p, qs[q].n, 0.0f, out.data() + q * std::size_t(ds));
        };
        if (parallel) {
            oneapi::tbb::parallel_for(std::size_t(0), order.size(), one);
        } else {
            for (std::size_t k = 0; k < order.size(); ++k) one(k);
        }
        return out;
    };
    std::vector<std::size_t> order(qs.size());
    std::iota(order.begin(), order.end(), std::size_t(0));
    const std::vector<float> in_order = run(order, false);
    std::vector<std::size_t> reversed(order.rbegin(), order.rend());
    EXPECT_EQ(run(reversed, false), in_order);
    EXPECT_EQ(run(order, true), in_order);
    Rng rng(11);
    for (std::size_t i = order.size(); i > 1; --i)
        std::swap(order[i - 1], order[std::size_t(rng.next() * double(i))]);
    EXPECT_EQ(run(order, false), in_order);
}

TEST(PointCloudLookupReference, RangesAndNearestDistance) {
    const PointCloud cloud = sphere_cloud(3000, true, 12);
    const PointCloudLookup lookup(cloud); // a (1 float), c (3 floats)
    ASSERT_EQ(lookup.data_size(), 4);
    const std::vector<PointCloudLookup::Range> ranges = {{1, 3}, {0, 1}};
    for (const Query& q : sphere_queries(200, 0.0f, 13)) {
        for (float radius : {0.0f, 0.05f}) {
            float all[4], some[4], nearest = -1.0f, ref_nearest = -2.0f;
            std::vector<float> want;
            ASSERT_TRUE(lookup.lookup(q.p, q.n, radius, all));
            ASSERT_TRUE(lookup.lookup(q.p, q.n, radius, ranges, some, &nearest));
            ASSERT_TRUE(reference(cloud, q.p, q.n, radius, want, &ref_nearest));
            EXPECT_EQ(some[0], all[1]);
            EXPECT_EQ(some[1], all[2]);
            EXPECT_EQ(some[2], all[3]);
            EXPECT_EQ(some[3], all[0]);
            EXPECT_NEAR(nearest, ref_nearest, 1e-6f);
        }
    }
    const std::vector<PointCloudLookup::Range> bad = {{2, 3}};
    float out[4];
    EXPECT_THROW(lookup.lookup({0, 0, 0}, {0, 0, 1}, 0.0f, bad, out), sss::ValueError);
}

TEST(PointCloudLookupReference, EmptyCloud) {
    PointCloud empty;
    empty.add_channel("a", ChannelType::Float);
    const PointCloudLookup lookup(empty);
    float out = 5.0f, nearest = 0.0f;
    const PointCloudLookup::Range all{0, 1};
    for (float r : {0.0f, 1.0f}) {
        EXPECT_FALSE(lookup.lookup({0, 0, 0}, {0, 0, 1}, r, &out));
        EXPECT_EQ(out, 0.0f);
        EXPECT_FALSE(lookup.lookup({0, 0, 0}, {0, 0, 1}, r, {&all, 1}, &out, &nearest));
        EXPECT_TRUE(std::isinf(nearest));
    }
}

TEST(PointCloudLookupReference, OnePointAndFewPoints) {
    for (std::size_t count : {std::size_t(1), std::size_t(2), std::size_t(5),
                              std::size_t(9), std::size_t(10)}) {
        const PointCloud cloud = box_cloud(count, 20 + count);
        const PointCloudLookup lookup(cloud);
        Rng rng(30 + count);
        std::vector<Query> qs;
        for (int k = 0; k < 50; ++k)
            qs.push_back({glm::vec3(rng.range(-3, 3), rng.range(-3, 3), rng.range(-3, 3)),
                          k % 2 ? rng.direction() : glm::vec3(0.0f),
                          k % 3 ? 0.0f : 1.0f});
        expect_matches(cloud, lookup, qs);
    }
}

TEST(PointCloudLookupReference, CoincidentPoints) {
    // 40 points at one place (one leaf, whatever its size), then a cloud
    // whose every point is there three times: ties, all with the same data.
    PointCloud pile;
    pile.resize(40);
    for (std::size_t i = 0; i < pile.size(); ++i) {
        pile.positions[i] = glm::vec3(0.5f, -0.25f, 1.0f);
        pile.normals[i] = glm::vec3(0, 0, 1);
    }
    pile.add_channel("a", ChannelType::Float);
    for (float& v : pile.find_channel("a")->data) v = 2.5f;
    const PointCloudLookup one_place(pile);
    float out = 0.0f;
    for (glm::vec3 p : {glm::vec3(0.5f, -0.25f, 1.0f), glm::vec3(3, 4, 5)}) {
        ASSERT_TRUE(one_place.lookup(p, {0, 0, 1}, 0.0f, &out));
        EXPECT_FLOAT_EQ(out, 2.5f); // all at one distance: the plain mean
    }
    EXPECT_FALSE(one_place.lookup({0, 0, 0}, {0, 0, -1}, 0.0f, &out));

    const PointCloud base = sphere_cloud(2000, true, 40);
    PointCloud tripled = base;
    tripled.append(base);
    tripled.append(base);
    const PointCloudLookup lookup(tripled);
    expect_matches(tripled, lookup, sphere_queries(300, 0.0f, 41));
    expect_matches(tripled, lookup, sphere_queries(100, 0.05f, 42));
}

TEST(PointCloudLookupReference, ZeroNormalsAndOddQueryNormals) {
    // Half the points without normals: they qualify for every query normal.
    PointCloud cloud = sphere_cloud(4000, true, 50);
    for (std::size_t i = 0; i < cloud.size(); i += 2) cloud.normals[i] = glm::vec3(0.0f);
    const PointCloudLookup lookup(cloud);
    std::vector<Query> qs = sphere_queries(300, 0.0f, 51);
    // Normals pointing inwards (only the points without normals qualify),
    // unnormalised, and not finite (then ignored).
    for (std::size_t k = 0; k < qs.size(); ++k) {
        if (k % 3 == 0) qs[k].n = -qs[k].n;
        if (k % 3 == 1) qs[k].n *= 40.0f;
        if (k % 11 == 2)
            qs[k].n = glm::vec3(std::numeric_limits<float>::infinity(), 0, 0);
    }
    expect_matches(cloud, lookup, qs);
}

TEST(PointCloudLookupReference, QueriesFarFromTheData) {
    const PointCloud cloud = sphere_cloud(3000, true, 60);
    const PointCloudLookup lookup(cloud);
    Rng rng(61);
    std::vector<Query> qs;
    for (int k = 0; k < 100; ++k) {
        const glm::vec3 d = rng.direction();
        qs.push_back({d * (k % 2 ? 300.0f : 30.0f), k % 3 ? d : glm::vec3(0.0f), 0.0f});
    }
    expect_matches(cloud, lookup, qs);
    // Much farther, squared distances round to equal floats and the k + 1
    // are decided by ties (tree order here, input order in the reference):
    // still a hit, a weighted mean of the data, and the same every time.
    const sss::Channel& a = *cloud.find_channel("a");
    const auto [lo, hi] = std::minmax_element(a.data.begin(), a.data.end());
    for (int k = 0; k < 50; ++k) {
        const glm::vec3 d = rng.direction();
        float first[4], again[4];
        ASSERT_TRUE(lookup.lookup(d * 1e4f, d, 0.0f, first));
        ASSERT_TRUE(lookup.lookup(d * 1e4f, d, 0.0f, again));
        EXPECT_EQ(std::vector<float>(first, first + 4),
                  std::vector<float>(again, again + 4));
        EXPECT_GE(first[0], *lo - 1e-6f);
        EXPECT_LE(first[0], *hi + 1e-6f);
    }
}
