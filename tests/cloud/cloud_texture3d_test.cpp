// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file cloud_texture3d_test.cpp
/// CloudTexture3d, texture3d on a cloud as the renderer reads it: the nearest
/// points' average near the data, a miss far from it (however large the
/// cloud's extent), the filter radius widening "near", non-finite inputs, and
/// channel ranges.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "sss/cloud/cloud_texture3d.h"
#include "sss/cloud/point_cloud.h"

using sss::ChannelType;
using sss::CloudTexture3d;
using sss::PointCloud;

namespace {

/// A k x k grid of unit spacing in z = 0, normal +z, radius 0.5, with a float
/// channel "_x" = x and a color channel "_c" = (1, 2, 3).
PointCloud grid(int k) {
    PointCloud cloud;
    cloud.resize(std::size_t(k) * k);
    cloud.add_channel("_x", ChannelType::Float);
    cloud.add_channel("_c", ChannelType::Color);
    sss::Channel& x = cloud.channels[0];
    sss::Channel& c = cloud.channels[1];
    for (int j = 0; j < k; ++j)
        for (int i = 0; i < k; ++i) {
            const std::size_t idx = std::size_t(j) * k + i;
            cloud.positions[idx] = glm::vec3(float(i), float(j), 0.0f);
            cloud.normals[idx] = glm::vec3(0.0f, 0.0f, 1.0f);
            cloud.radii[idx] = 0.5f;
            x.data[idx] = float(i);
            c.data[3 * idx + 0] = 1.0f;
            c.data[3 * idx + 1] = 2.0f;
            c.data[3 * idx + 2] = 3.0f;
        }
    return cloud;
}

using Range = sss::PointCloudLookup::Range;

} // namespace

TEST(CloudTexture3d, ChannelsInTheCloudsOrder) {
    const CloudTexture3d tex(grid(4));
    ASSERT_EQ(tex.channels().size(), 2u);
    EXPECT_EQ(tex.channels()[0].name, "_x");
    EXPECT_EQ(tex.channels()[1].offset, 1);
    EXPECT_EQ(tex.channels()[1].floats, 3);
    EXPECT_EQ(tex.data_size(), 4);
    EXPECT_EQ(tex.find("_c"), &tex.channels()[1]);
    EXPECT_EQ(tex.find("nope"), nullptr);
    EXPECT_EQ(tex.cloud().size(), 16u);
}

TEST(CloudTexture3d, NearTheDataFoundFarAMiss) {
    const CloudTexture3d tex(grid(10));
    const Range all[] = {{0, 4}};
    float out[4] = {};
    // On the grid: a constant colour is exact; x is the neighbours' average.
    ASSERT_TRUE(tex.lookup({4.5f, 4.5f, 0.1f}, {0, 0, 1}, 0.0f, all, out));
    EXPECT_NEAR(out[0], 4.5f, 0.3f);
    EXPECT_FLOAT_EQ(out[1], 1.0f);
    EXPECT_FLOAT_EQ(out[3], 3.0f);
    // Four median radii (2 units) is the reach: 5 units above is a miss,
    // outside the box and beside the grid too.
    EXPECT_FALSE(tex.lookup({4.5f, 4.5f, 5.0f}, {0, 0, 1}, 0.0f, all, out));
    EXPECT_FALSE(tex.lookup({40.0f, 4.5f, 0.0f}, {0, 0, 1}, 0.0f, all, out));
    // A filter radius as large as the distance makes it near again.
    EXPECT_TRUE(tex.lookup({4.5f, 4.5f, 5.0f}, {0, 0, 1}, 6.0f, all, out));
}

TEST(CloudTexture3d, RangesPickChannels) {
    const CloudTexture3d tex(grid(6));
    const Range green_then_x[] = {{2, 1}, {0, 1}};
    float out[2] = {};
    ASSERT_TRUE(tex.lookup({2.0f, 3.0f, 0.0f}, {0, 0, 1}, 0.0f, green_then_x, out));
    EXPECT_FLOAT_EQ(out[0], 2.0f);
    EXPECT_NEAR(out[1], 2.0f, 0.3f);
}

TEST(CloudTexture3d, NonFiniteInputs) {
    const CloudTexture3d tex(grid(6));
    const Range all[] = {{0, 4}};
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    float out[4] = {};
    EXPECT_FALSE(tex.lookup({nan, 1.0f, 0.0f}, {0, 0, 1}, 0.0f, all, out));
    EXPECT_FALSE(tex.lookup({inf, 1.0f, 0.0f}, {0, 0, 1}, 0.0f, all, out));
    // A NaN normal is no normal; a NaN or negative radius is 0.
    float ref[4] = {};
    ASSERT_TRUE(tex.lookup({2.0f, 2.0f, 0.0f}, {0, 0, 0}, 0.0f, all, ref));
    ASSERT_TRUE(tex.lookup({2.0f, 2.0f, 0.0f}, {nan, 0, 1}, nan, all, out));
    EXPECT_EQ(std::vector<float>(out, out + 4), std::vector<float>(ref, ref + 4));
    EXPECT_FALSE(tex.lookup({2.0f, 2.0f, 5.0f}, {0, 0, 1}, -6.0f, all, out));
}

TEST(CloudTexture3d, EmptyCloudIsAlwaysAMiss) {
    const CloudTexture3d tex{PointCloud()};
    const Range none[] = {{0, 0}};
    float out[1] = {};
    EXPECT_FALSE(tex.lookup({0, 0, 0}, {0, 0, 1}, 0.0f, none, out));
}
