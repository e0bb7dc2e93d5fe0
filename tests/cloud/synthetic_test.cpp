// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file synthetic_test.cpp
/// Tests of the synthetic point clouds (sss/cloud/synthetic.h).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "sss/cloud/synthetic.h"
#include "sss/util/error.h"

// ---------------------------------------------------------------------------
// Synthetic clouds
// ---------------------------------------------------------------------------

namespace {

double area_sum(const sss::PointCloud& cloud) {
    const sss::Channel* area = cloud.find_channel("_area");
    EXPECT_NE(area, nullptr);
    if (!area) return 0.0;
    double sum = 0.0;
    for (float a : area->data) sum += a;
    return sum;
}

void expect_channels(const sss::PointCloud& cloud) {
    const sss::Channel* area = cloud.find_channel("_area");
    const sss::Channel* rad = cloud.find_channel("_radiance_t");
    ASSERT_NE(area, nullptr);
    ASSERT_NE(rad, nullptr);
    EXPECT_EQ(area->type, sss::ChannelType::Float);
    EXPECT_EQ(rad->type, sss::ChannelType::Color);
    EXPECT_EQ(area->data.size(), cloud.size());
    EXPECT_EQ(rad->data.size(), 3 * cloud.size());
    EXPECT_EQ(cloud.normals.size(), cloud.size());
    EXPECT_EQ(cloud.radii.size(), cloud.size());
}

/// Radiance must be light_color * max(0, N.L) + ambient at every point.
void expect_radiance(const sss::PointCloud& cloud, const sss::SyntheticParams& p) {
    const sss::Channel* rad = cloud.find_channel("_radiance_t");
    ASSERT_NE(rad, nullptr);
    glm::dvec3 light = glm::normalize(p.light_dir);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        double cosine = std::max(0.0, glm::dot(glm::dvec3(cloud.normals[i]), light));
        for (int k = 0; k < 3; ++k) {
            double expected = p.light_color[k] * cosine + p.ambient;
            ASSERT_NEAR(rad->data[3 * i + k], expected,
                        1e-5 * (1.0 + std::fabs(expected)))
                << "point " << i;
        }
    }
}

} // namespace

TEST(Synthetic, SphereAreasNormalsRadiance) {
    sss::SyntheticParams p;
    p.shape = sss::SyntheticShape::Sphere;
    p.count = 20000;
    p.size = 50.0;
    p.light_dir = {1, 1, 1};
    sss::PointCloud cloud = sss::make_synthetic_cloud(p);
    ASSERT_EQ(cloud.size(), 20000u);
    expect_channels(cloud);
    const double expected_area = 4.0 * std::numbers::pi * 50.0 * 50.0;
    EXPECT_NEAR(area_sum(cloud), expected_area, 1e-6 * expected_area);
    const double share = expected_area / 20000.0;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        glm::dvec3 n(cloud.normals[i]);
        glm::dvec3 pos(cloud.positions[i]);
        ASSERT_NEAR(glm::length(n), 1.0, 1e-6);
        ASSERT_NEAR(glm::length(pos), 50.0, 50.0 * 1e-6);
        ASSERT_NEAR(glm::dot(n, pos / 50.0), 1.0, 1e-5) << "outward normal";
        ASSERT_NEAR(cloud.radii[i], std::sqrt(2.0 * share) / 2.0, 1e-5);
    }
    expect_radiance(cloud, p);

    // The lattice covers the sphere evenly: the mean position is the centre.
    glm::dvec3 mean(0.0);
    for (const auto& q : cloud.positions) mean += glm::dvec3(q);
    mean /= static_cast<double>(cloud.size());
    EXPECT_LT(glm::length(mean), 0.05);
}

TEST(Synthetic, LightColourAndAmbient) {
    sss::SyntheticParams p;
    p.count = 1000;
    p.size = 2.0;
    p.light_dir = {0, 0, -3};
    p.light_color = {2.0, 1.0, 0.5};
    p.ambient = 0.25;
    sss::PointCloud cloud = sss::make_synthetic_cloud(p);
    expect_radiance(cloud, p);
}

TEST(Synthetic, PlaneGridAreas) {
    sss::SyntheticParams p;
    p.shape = sss::SyntheticShape::Plane;
    p.count = 10000;
    p.size = 30.0;
    sss::PointCloud cloud = sss::make_synthetic_cloud(p);
    ASSERT_EQ(cloud.size(), 10000u);
    expect_channels(cloud);
    EXPECT_NEAR(area_sum(cloud), 900.0, 1e-6 * 900.0);
    const double h = 30.0 / 100.0;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        EXPECT_EQ(cloud.normals[i], glm::vec3(0, 0, 1));
        EXPECT_EQ(cloud.positions[i].z, 0.0f);
        ASSERT_NEAR(cloud.radii[i], h * std::sqrt(2.0) / 2.0, 1e-6);
    }
    expect_radiance(cloud, p);

    // round(sqrt(1000)) = 32 -> 1024 points.
    p.count = 1000;
    EXPECT_EQ(sss::make_synthetic_cloud(p).size(), 1024u);
}

TEST(Synthetic, PlaneJitterStaysInCells) {
    sss::SyntheticParams p;
    p.shape = sss::SyntheticShape::Plane;
    p.count = 400;
    p.size = 20.0;
    p.jitter = 1.0;
    p.seed = 42;
    sss::PointCloud cloud = sss::make_synthetic_cloud(p);
    ASSERT_EQ(cloud.size(), 400u);
    EXPECT_NEAR(area_sum(cloud), 400.0, 1e-6 * 400.0);
    const double h = 1.0;
    bool moved = false;
    for (std::size_t j = 0; j < 20; ++j) {
        for (std::size_t i = 0; i < 20; ++i) {
            const glm::vec3& q = cloud.positions[j * 20 + i];
            double cx = -10.0 + (i + 0.5) * h, cy = -10.0 + (j + 0.5) * h;
            EXPECT_LE(std::fabs(q.x - cx), 0.5 * h + 1e-5);
            EXPECT_LE(std::fabs(q.y - cy), 0.5 * h + 1e-5);
            if (std::fabs(q.x - cx) > 1e-3) moved = true;
        }
    }
    EXPECT_TRUE(moved);
}

TEST(Synthetic, BoxSurfaceArea) {
    sss::SyntheticParams p;
    p.shape = sss::SyntheticShape::Box;
    p.count = 20000;
    p.size = 40.0;
    p.thickness = 5.0;
    p.light_dir = {0.3, -0.2, 1.0};
    p.jitter = 0.5;
    sss::PointCloud cloud = sss::make_synthetic_cloud(p);
    expect_channels(cloud);
    EXPECT_NEAR(static_cast<double>(cloud.size()), 20000.0, 0.1 * 20000.0);
    const double surface = 2.0 * (40.0 * 40.0 + 2.0 * 40.0 * 5.0);
    EXPECT_NEAR(area_sum(cloud), surface, 1e-6 * surface);
    const glm::dvec3 half(20.0, 20.0, 2.5);
    int faces[6] = {0, 0, 0, 0, 0, 0};
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        glm::dvec3 n(cloud.normals[i]);
        glm::dvec3 q(cloud.positions[i]);
        ASSERT_NEAR(glm::length(n), 1.0, 1e-7);
        int axis = std::fabs(n.x) > 0.5 ? 0 : (std::fabs(n.y) > 0.5 ? 1 : 2);
        ASSERT_NEAR(std::fabs(n[axis]), 1.0, 1e-7) << "axis-aligned normal";
        // On its face, inside the box outline.
        ASSERT_NEAR(q[axis] * n[axis], half[axis], 1e-5);
        for (int k = 0; k < 3; ++k) ASSERT_LE(std::fabs(q[k]), half[k] + 1e-5);
        faces[2 * axis + (n[axis] > 0 ? 0 : 1)]++;
    }
    for (int f : faces) EXPECT_GT(f, 0);
    EXPECT_EQ(faces[4], faces[5]);
    expect_radiance(cloud, p);
}

TEST(Synthetic, Deterministic) {
    for (auto shape : {sss::SyntheticShape::Sphere, sss::SyntheticShape::Plane,
                       sss::SyntheticShape::Box}) {
        sss::SyntheticParams p;
        p.shape = shape;
        p.count = 3000;
        p.jitter = 0.7;
        p.seed = 1234;
        sss::PointCloud a = sss::make_synthetic_cloud(p);
        sss::PointCloud b = sss::make_synthetic_cloud(p);
        ASSERT_EQ(a.size(), b.size());
        EXPECT_EQ(a.positions, b.positions);
        EXPECT_EQ(a.normals, b.normals);
        EXPECT_EQ(a.radii, b.radii);
        EXPECT_EQ(a.find_channel("_radiance_t")->data,
                  b.find_channel("_radiance_t")->data);
        if (shape != sss::SyntheticShape::Sphere) {
            p.seed = 1235;
            EXPECT_NE(sss::make_synthetic_cloud(p).positions, a.positions)
                << "the seed drives the jitter";
        }
    }
}

TEST(Synthetic, RejectsBadParameters) {
    auto bad = [](auto change) {
        sss::SyntheticParams p;
        p.count = 10;
        change(p);
        EXPECT_THROW(sss::make_synthetic_cloud(p), sss::ValueError);
    };
    bad([](sss::SyntheticParams& p) { p.count = 0; });
    bad([](sss::SyntheticParams& p) { p.size = 0.0; });
    bad([](sss::SyntheticParams& p) { p.size = std::nan(""); });
    bad([](sss::SyntheticParams& p) { p.jitter = 1.5; });
    bad([](sss::SyntheticParams& p) { p.light_dir = glm::dvec3(0.0); });
    bad([](sss::SyntheticParams& p) {
        p.shape = sss::SyntheticShape::Box;
        p.thickness = -1.0;
    });
}
