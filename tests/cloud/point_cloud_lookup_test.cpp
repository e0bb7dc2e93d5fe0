// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file point_cloud_lookup_test.cpp
/// PointCloudLookup, the reference brick maps are checked against: exact
/// constants, linear fields between samples, the two sides of a thin plate,
/// channel selection, misses, the nearest-point fallback and determinism
/// across threads.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <oneapi/tbb/parallel_for.h>

#include "sss/cloud/point_cloud.h"
#include "sss/cloud/point_cloud_lookup.h"
#include "sss/cloud/synthetic.h"
#include "sss/util/error.h"

using sss::ChannelType;
using sss::PointCloud;
using sss::PointCloudLookup;

namespace {

// Deterministic uniform numbers in [0, 1) for test positions.
double unit_hash(uint64_t i) {
    uint64_t z = i * 0x9E3779B97F4A7C15ull + 0x632BE59BD9B4E019ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return double(z >> 11) * 0x1.0p-53;
}

/// A k x k grid of unit spacing in z = height, centred at the origin, with
/// normal (0, 0, nz) and the given jitter (fraction of the spacing).
PointCloud grid_plane(int k, float height, float nz, double jitter, uint64_t seed) {
    PointCloud cloud;
    cloud.resize(std::size_t(k) * k);
    for (int j = 0; j < k; ++j) {
        for (int i = 0; i < k; ++i) {
            std::size_t idx = std::size_t(j) * k + i;
            double jx = (unit_hash(seed + 2 * idx) - 0.5) * jitter;
            double jy = (unit_hash(seed + 2 * idx + 1) - 0.5) * jitter;
            cloud.positions[idx] = glm::vec3(float(i - 0.5 * (k - 1) + jx),
                                             float(j - 0.5 * (k - 1) + jy), height);
            cloud.normals[idx] = glm::vec3(0.0f, 0.0f, nz);
            cloud.radii[idx] = 0.7f;
        }
    }
    return cloud;
}

} // namespace

TEST(PointCloudLookup, ConstantFieldReturnsTheConstant) {
    sss::SyntheticParams sp;
    sp.count = 5000;
    sp.size = 10.0;
    PointCloud cloud = sss::make_synthetic_cloud(sp);
    sss::Channel& ch = cloud.add_channel("_c", ChannelType::Color);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        ch.data[3 * i + 0] = 0.25f;
        ch.data[3 * i + 1] = 1.5f;
        ch.data[3 * i + 2] = -2.0f;
    }
    PointCloudLookup lookup(cloud, {"_c"});
    ASSERT_EQ(lookup.data_size(), 3);
    for (int q = 0; q < 200; ++q) {
        const std::size_t i = std::size_t(unit_hash(q) * cloud.size());
        // Slightly off the surface, with and without a normal, at several radii.
        glm::vec3 p = cloud.positions[i] * 1.01f;
        for (float radius : {0.0f, 0.1f, 1.0f, 5.0f}) {
            for (glm::vec3 n : {cloud.normals[i], glm::vec3(0.0f)}) {
                float out[3] = {9, 9, 9};
                ASSERT_TRUE(lookup.lookup(p, n, radius, out));
                EXPECT_NEAR(out[0], 0.25f, 1e-6f);
                EXPECT_NEAR(out[1], 1.5f, 1e-6f);
                EXPECT_NEAR(out[2], -2.0f, 1e-6f);
            }
        }
    }
}

TEST(PointCloudLookup, LinearFieldBetweenSamples) {
    // f = 1 + 2x - 3y on a jittered unit grid: a symmetric-enough weighted
    // average reproduces a linear field up to the offset of the weights'
    // centroid from the query, a fraction of the spacing.
    PointCloud cloud = grid_plane(41, 0.0f, 1.0f, 0.5, 17);
    sss::Channel& f = cloud.add_channel("f", ChannelType::Float);
    for (std::size_t i = 0; i < cloud.size(); ++i)
        f.data[i] = 1.0f + 2.0f * cloud.positions[i].x - 3.0f * cloud.positions[i].y;
    PointCloudLookup lookup(cloud);
    const double grad = std::sqrt(13.0); // |grad f|, per unit spacing
    double worst_nearest = 0.0, worst_radius = 0.0, sum2 = 0.0;
    int count = 0;
    for (int q = 0; q < 500; ++q) {
        // Random points in the interior, away from the border (15 spacings).
        float x = float((unit_hash(1000 + 2 * q) - 0.5) * 30.0);
        float y = float((unit_hash(1001 + 2 * q) - 0.5) * 30.0);
        const double exact = 1.0 + 2.0 * x - 3.0 * y;
        float out = 0.0f;
        ASSERT_TRUE(lookup.lookup({x, y, 0.0f}, {0, 0, 1}, 0.0f, &out));
        worst_nearest = std::max(worst_nearest, std::fabs(out - exact));
        sum2 += (out - exact) * (out - exact);
        ++count;
        ASSERT_TRUE(lookup.lookup({x, y, 0.0f}, {0, 0, 1}, 3.0f, &out));
        worst_radius = std::max(worst_radius, std::fabs(out - exact));
    }
    // Errors in units of |grad f| x spacing (measured: 8 nearest 0.22 worst,
    // 0.074 RMS; a 3-spacing tent over ~28 points 0.12 worst).
    EXPECT_LT(worst_nearest, 0.3 * grad);
    EXPECT_LT(std::sqrt(sum2 / count), 0.1 * grad);
    EXPECT_LT(worst_radius, 0.15 * grad);
    // A query exactly between four grid points (no jitter) is exact.
    PointCloud regular = grid_plane(8, 0.0f, 1.0f, 0.0, 0);
    sss::Channel& g = regular.add_channel("g", ChannelType::Float);
    for (std::size_t i = 0; i < regular.size(); ++i)
        g.data[i] = 4.0f * regular.positions[i].x + regular.positions[i].y;
    PointCloudLookup exact(regular);
    float out = 1.0f;
    ASSERT_TRUE(exact.lookup({0.0f, 0.0f, 0.0f}, {0, 0, 1}, 1.2f, &out));
    EXPECT_NEAR(out, 0.0f, 1e-5f);
}

TEST(PointCloudLookup, DoubleSidedPlateKeepsSidesApart) {
    // A plate 0.02 thick: top faces +z with value 1, bottom faces -z with 5.
    PointCloud top = grid_plane(20, 0.01f, 1.0f, 0.0, 0);
    top.add_channel("v", ChannelType::Float);
    for (float& v : top.find_channel("v")->data) v = 1.0f;
    PointCloud bottom = grid_plane(20, -0.01f, -1.0f, 0.0, 0);
    bottom.add_channel("v", ChannelType::Float);
    for (float& v : bottom.find_channel("v")->data) v = 5.0f;
    PointCloud plate = top;
    plate.append(bottom);
    PointCloudLookup lookup(plate);
    for (float radius : {0.0f, 0.5f, 2.0f}) {
        float out = 0.0f;
        ASSERT_TRUE(lookup.lookup({0.3f, -0.2f, 0.01f}, {0, 0, 1}, radius, &out));
        EXPECT_FLOAT_EQ(out, 1.0f) << "radius " << radius;
        ASSERT_TRUE(lookup.lookup({0.3f, -0.2f, -0.01f}, {0, 0, -1}, radius, &out));
        EXPECT_FLOAT_EQ(out, 5.0f) << "radius " << radius;
        // 50 degrees off the normal still counts as the same side.
        glm::vec3 tilted(std::sin(0.87f), 0.0f, std::cos(0.87f));
        ASSERT_TRUE(lookup.lookup({0.3f, -0.2f, 0.0f}, tilted, radius, &out));
        EXPECT_FLOAT_EQ(out, 1.0f);
        // Without a normal both sides blend (the plate is thinner than the spacing).
        ASSERT_TRUE(lookup.lookup({0.3f, -0.2f, 0.0f}, glm::vec3(0.0f), radius, &out));
        EXPECT_GT(out, 1.5f);
        EXPECT_LT(out, 4.5f);
    }
}

TEST(PointCloudLookup, ChannelSelectionAndOrder) {
    PointCloud cloud = grid_plane(5, 0.0f, 1.0f, 0.0, 0);
    // Add all channels before taking references: add_channel may reallocate.
    cloud.add_channel("a", ChannelType::Float);
    cloud.add_channel("b", ChannelType::Color);
    cloud.add_channel("v", ChannelType::Vector);
    auto& a = *cloud.find_channel("a");
    auto& b = *cloud.find_channel("b");
    auto& v = *cloud.find_channel("v");
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        a.data[i] = 2.0f;
        for (int c = 0; c < 3; ++c) {
            b.data[3 * i + c] = 10.0f + c;
            v.data[3 * i + c] = -1.0f - c;
        }
    }
    // Default: every float and color channel, in file order.
    PointCloudLookup all(cloud);
    ASSERT_EQ(all.channels().size(), 2u);
    EXPECT_EQ(all.channels()[0].first, "a");
    EXPECT_EQ(all.channels()[1].second, ChannelType::Color);
    EXPECT_EQ(all.data_size(), 4);

    // Named: in the order asked for, any type.
    PointCloudLookup picked(cloud, {"v", "a"});
    ASSERT_EQ(picked.data_size(), 4);
    EXPECT_EQ(picked.channels()[0].first, "v");
    EXPECT_EQ(picked.channels()[0].second, ChannelType::Vector);
    float out[4];
    ASSERT_TRUE(picked.lookup({0, 0, 0}, {0, 0, 1}, 0.0f, out));
    EXPECT_FLOAT_EQ(out[0], -1.0f);
    EXPECT_FLOAT_EQ(out[2], -3.0f);
    EXPECT_FLOAT_EQ(out[3], 2.0f);

    EXPECT_THROW(PointCloudLookup(cloud, {"nope"}), sss::ValueError);
    EXPECT_THROW(PointCloudLookup(cloud, {"a", "a"}), sss::ValueError);
}

TEST(PointCloudLookup, NoQualifyingPointIsAMiss) {
    PointCloud cloud = grid_plane(6, 0.0f, 1.0f, 0.0, 0);
    cloud.add_channel("a", ChannelType::Float);
    for (float& x : cloud.find_channel("a")->data) x = 3.0f;
    PointCloudLookup lookup(cloud);
    for (float radius : {0.0f, 1.0f, 100.0f}) {
        float out = 7.0f;
        EXPECT_FALSE(lookup.lookup({0, 0, 0}, {0, 0, -1}, radius, &out));
        EXPECT_EQ(out, 0.0f);
        // 70 degrees away from every point's normal: also a miss.
        EXPECT_FALSE(lookup.lookup({0, 0, 0}, {std::sin(1.22f), 0, std::cos(1.22f)},
                                   radius, &out));
    }
    // A point without a normal qualifies for any query normal.
    PointCloud sphere_pt;
    sphere_pt.resize(1);
    sphere_pt.radii[0] = 1.0f;
    sphere_pt.add_channel("a", ChannelType::Float).data[0] = 4.0f;
    PointCloudLookup single(sphere_pt);
    float out = 0.0f;
    EXPECT_TRUE(single.lookup({5, 5, 5}, {0, 0, -1}, 0.0f, &out));
    EXPECT_FLOAT_EQ(out, 4.0f);

    PointCloud empty;
    empty.add_channel("a", ChannelType::Float);
    PointCloudLookup none(empty);
    EXPECT_FALSE(none.lookup({0, 0, 0}, glm::vec3(0.0f), 0.0f, &out));
    EXPECT_FALSE(none.lookup({0, 0, 0}, glm::vec3(0.0f), 1.0f, &out));
}

TEST(PointCloudLookup, SmallRadiusFallsBackToNearest) {
    PointCloud cloud = grid_plane(10, 0.0f, 1.0f, 0.3, 5);
    auto& a = cloud.add_channel("a", ChannelType::Float);
    for (std::size_t i = 0; i < cloud.size(); ++i) a.data[i] = cloud.positions[i].x;
    PointCloudLookup lookup(cloud);
    // 10 units above the plate, no point within 0.5: same as the 8 nearest.
    float far_r = 0.0f, nearest = 0.0f;
    ASSERT_TRUE(lookup.lookup({0.2f, 0.1f, 10.0f}, {0, 0, 1}, 0.5f, &far_r));
    ASSERT_TRUE(lookup.lookup({0.2f, 0.1f, 10.0f}, {0, 0, 1}, 0.0f, &nearest));
    EXPECT_EQ(far_r, nearest);
    // A radius covering everything gives a tent average of all points.
    float all = 0.0f;
    ASSERT_TRUE(lookup.lookup({0.0f, 0.0f, 0.0f}, {0, 0, 1}, 1000.0f, &all));
    EXPECT_NEAR(all, 0.0f, 0.05f);
}

TEST(PointCloudLookup, DeterministicAcrossThreads) {
    sss::SyntheticParams sp;
    sp.count = 20000;
    sp.size = 3.0;
    PointCloud cloud = sss::make_synthetic_cloud(sp);
    PointCloudLookup lookup(cloud);
    const int n = 4000;
    const int ds = lookup.data_size();
    std::vector<float> serial(std::size_t(n) * ds), parallel(std::size_t(n) * ds);
    std::vector<uint8_t> hit_s(n), hit_p(n);
    auto query = [&](int q, float* out) {
        glm::vec3 p(float(unit_hash(3 * q) - 0.5) * 7.0f,
                    float(unit_hash(3 * q + 1) - 0.5) * 7.0f,
                    float(unit_hash(3 * q + 2) - 0.5) * 7.0f);
        glm::vec3 nrm = glm::length(p) > 0.0f ? glm::normalize(p) : glm::vec3(0.0f);
        return lookup.lookup(p, nrm, (q % 3) * 0.1f, out);
    };
    for (int q = 0; q < n; ++q) hit_s[q] = query(q, serial.data() + std::size_t(q) * ds);
    tbb::parallel_for(
        0, n, [&](int q) { hit_p[q] = query(q, parallel.data() + std::size_t(q) * ds); });
    EXPECT_EQ(hit_s, hit_p);
    EXPECT_EQ(serial, parallel);
}
