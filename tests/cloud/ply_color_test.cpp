// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file ply_color_test.cpp
/// The display colour of .ply clouds: uchar red/green/blue made from the
/// `_ssdiffusion` (or first color) channel, clamped and sRGB-encoded, next to
/// the float channels, and skipped when our reader reads the file back.

#include <gtest/gtest.h>

#include "test_util.h"

#include <cstdint>
#include <string>
#include <vector>

#include "sss/cloud/point_cloud.h"
#include "sss/cloud/point_cloud_io.h"
#include "sss/util/error.h"

namespace {

using sss::ChannelType;
using sss::PointCloud;
using sss::test::Bytes;
using sss::test::read_bytes;
using sss::test::TempDir;
using sss::test::write_text;

/// Values chosen away from rounding ties: linear -> sRGB byte.
struct ByteCase {
    float linear;
    uint8_t byte;
};
const ByteCase kCases[] = {{-1.0f, 0},  {0.0f, 0},   {0.001f, 3}, {0.18f, 118},
                           {0.5f, 188}, {1.0f, 255}, {7.5f, 255}, {0.214f, 127}};
constexpr std::size_t kCaseCount = sizeof(kCases) / sizeof(kCases[0]);

/// A cloud of n points with a float, a color and (optionally) _ssdiffusion.
PointCloud make_cloud(std::size_t n, bool diffusion) {
    PointCloud c;
    c.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        c.positions[i] = glm::vec3(float(i), 0.5f * float(i), -1.0f);
        c.normals[i] = glm::vec3(0.0f, 0.0f, 1.0f);
        c.radii[i] = 0.25f;
    }
    auto& area = c.add_channel("_area", ChannelType::Float).data;
    for (std::size_t i = 0; i < n; ++i) area[i] = 0.1f * float(i + 1);
    auto& radiance = c.add_channel("_radiance_t", ChannelType::Color).data;
    for (std::size_t i = 0; i < 3 * n; ++i) radiance[i] = kCases[i % kCaseCount].linear;
    if (diffusion) {
        auto& d = c.add_channel("_ssdiffusion", ChannelType::Color).data;
        for (std::size_t i = 0; i < 3 * n; ++i)
            d[i] = kCases[(i + 1) % kCaseCount].linear;
    }
    return c;
}

/// The header text and the body bytes of a written file.
struct PlyFile {
    std::string header;
    Bytes body;
};

PlyFile read_ply_file(const std::string& path) {
    const Bytes raw = read_bytes(path);
    const std::string all(raw.begin(), raw.end());
    const std::size_t end = all.find("end_header\n");
    EXPECT_NE(end, std::string::npos);
    PlyFile f;
    f.header = all.substr(0, end + 11);
    f.body.assign(raw.begin() + static_cast<std::ptrdiff_t>(end + 11), raw.end());
    return f;
}

TEST(PlyColor, BytesAreClampedAndSrgbEncoded) {
    for (const ByteCase& c : kCases) {
        EXPECT_EQ(sss::ply_display_byte(c.linear), c.byte) << c.linear;
    }
}

TEST(PlyColor, DiffusionChannelShownAsUcharColours) {
    TempDir dir;
    const std::size_t n = 20;
    const PointCloud c = make_cloud(n, true);
    const std::string path = dir.file("c.ply");
    sss::write_point_cloud(c, path);
    const PlyFile f = read_ply_file(path);
    EXPECT_NE(f.header.find("comment sss_display_color _ssdiffusion\n"),
              std::string::npos);
    EXPECT_NE(f.header.find("property float radius\nproperty uchar red\n"
                            "property uchar green\nproperty uchar blue\n"
                            "property float _area\n"),
              std::string::npos)
        << f.header;
    // x y z nx ny nz radius, 3 colour bytes, _area, _radiance_t, _ssdiffusion.
    const std::size_t record = 7 * 4 + 3 + 4 * (1 + 3 + 3);
    ASSERT_EQ(f.body.size(), n * record);
    for (std::size_t i = 0; i < n; ++i) {
        for (std::size_t q = 0; q < 3; ++q) {
            EXPECT_EQ(f.body[i * record + 28 + q],
                      kCases[(3 * i + q + 1) % kCaseCount].byte)
                << "point " << i << " component " << q;
        }
    }
}

TEST(PlyColor, RoundTripKeepsTheChannelsExactlyAndNoColourChannels) {
    TempDir dir;
    const PointCloud c = make_cloud(50, true);
    const std::string path = dir.file("rt.ply");
    sss::write_point_cloud(c, path);
    const PointCloud r = sss::read_point_cloud(path);
    ASSERT_EQ(r.channels.size(), c.channels.size());
    for (std::size_t k = 0; k < c.channels.size(); ++k) {
        EXPECT_EQ(r.channels[k].name, c.channels[k].name);
        EXPECT_EQ(r.channels[k].type, c.channels[k].type);
        EXPECT_EQ(r.channels[k].data, c.channels[k].data); // values out of [0, 1] too
    }
    EXPECT_EQ(r.positions, c.positions);
    EXPECT_EQ(r.radii, c.radii);
    EXPECT_EQ(r.find_channel("red"), nullptr);
    // Written again, the file is the same byte for byte.
    const std::string again = dir.file("again.ply");
    sss::write_point_cloud(r, again);
    EXPECT_EQ(read_bytes(again), read_bytes(path));
}

TEST(PlyColor, FirstColorChannelWithoutDiffusion) {
    TempDir dir;
    const std::size_t n = 8;
    const PointCloud c = make_cloud(n, false);
    EXPECT_EQ(sss::ply_display_channel(c), c.find_channel("_radiance_t"));
    const std::string path = dir.file("bake.ply");
    sss::write_point_cloud(c, path);
    const PlyFile f = read_ply_file(path);
    EXPECT_NE(f.header.find("comment sss_display_color _radiance_t\n"),
              std::string::npos);
    const std::size_t record = 7 * 4 + 3 + 4 * (1 + 3);
    ASSERT_EQ(f.body.size(), n * record);
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t q = 0; q < 3; ++q)
            EXPECT_EQ(f.body[i * record + 28 + q], kCases[(3 * i + q) % kCaseCount].byte);
}

TEST(PlyColor, NoColourWithoutAColorChannel) {
    TempDir dir;
    PointCloud c;
    c.resize(3);
    c.add_channel("_area", ChannelType::Float).data = {1, 2, 3};
    c.add_channel("dir", ChannelType::Vector);
    EXPECT_EQ(sss::ply_display_channel(c), nullptr);
    const std::string path = dir.file("plain.ply");
    sss::write_point_cloud(c, path);
    const PlyFile f = read_ply_file(path);
    EXPECT_EQ(f.header.find("red"), std::string::npos);
    EXPECT_EQ(f.header.find("sss_display_color"), std::string::npos);
    EXPECT_EQ(f.body.size(), 3u * 4u * (7 + 1 + 3));
}

TEST(PlyColor, CloudWithItsOwnRedChannelKeepsIt) {
    // A foreign PLY's uchar red/green/blue become float channels; written
    // again they stay as they are, and no display colour is added.
    TempDir dir;
    PointCloud c = make_cloud(4, true);
    c.add_channel("red", ChannelType::Float).data = {200, 100, 50, 0};
    EXPECT_EQ(sss::ply_display_channel(c), nullptr);
    const std::string path = dir.file("red.ply");
    sss::write_point_cloud(c, path);
    const PlyFile f = read_ply_file(path);
    EXPECT_EQ(f.header.find("uchar"), std::string::npos);
    EXPECT_NE(f.header.find("property float red\n"), std::string::npos);
    const PointCloud r = sss::read_point_cloud(path);
    ASSERT_NE(r.find_channel("red"), nullptr);
    EXPECT_EQ(r.find_channel("red")->data, (std::vector<float>{200, 100, 50, 0}));
}

TEST(PlyColor, CommentWithoutTheColourPropertiesIsAFormatError) {
    TempDir dir;
    const std::string path = dir.file("bad.ply");
    write_text(path, "ply\nformat ascii 1.0\ncomment sss_display_color c\n"
                     "element vertex 1\nproperty float x\nproperty float y\n"
                     "property float z\nproperty uchar red\nproperty uchar green\n"
                     "end_header\n0 0 0 1 2\n");
    try {
        sss::read_point_cloud(path);
        FAIL() << "read a file whose colour properties are missing";
    } catch (const sss::FormatError& e) {
        EXPECT_NE(std::string(e.what()).find("no 'blue' property"), std::string::npos)
            << e.what();
    }
}

} // namespace
