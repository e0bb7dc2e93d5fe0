// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file brickmap_test.cpp
/// Brick maps: building from clouds, pruning against -maxerror, the 7
/// normal-direction trees, texture3d lookups (levels, filter radius,
/// fallbacks), the .bkm reader's validation of corrupt files, determinism
/// across thread counts, concurrent lookups and the bounded brick cache.

#include <gtest/gtest.h>

#include "test_util.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>
#include <vector>

#include <unistd.h>

#include "sss/brick/brickmap.h"
#include "sss/cloud/point_cloud.h"
#include "sss/cloud/synthetic.h"
#include "sss/util/error.h"
#include "sss/util/threads.h"

namespace fs = std::filesystem;
using sss::BrickMap;
using sss::BrickMapBuildOptions;
using sss::ChannelType;
using sss::PointCloud;

namespace {

using sss::test::Bytes;
using sss::test::read_bytes;
using sss::test::write_bytes;

using sss::test::TempDir;

uint32_t get_u32(const Bytes& b, std::size_t at) {
    uint32_t v = 0;
    for (int i = 3; i >= 0; --i) v = (v << 8) | b[at + i];
    return v;
}
uint64_t get_u64(const Bytes& b, std::size_t at) {
    return uint64_t(get_u32(b, at)) | (uint64_t(get_u32(b, at + 4)) << 32);
}
void put_u32(Bytes& b, std::size_t at, uint32_t v) {
    for (int i = 0; i < 4; ++i) b[at + i] = static_cast<unsigned char>(v >> (8 * i));
}

PointCloud sphere(std::size_t count) {
    sss::SyntheticParams p;
    p.count = count;
    p.light_dir = {0.3, 0.4, 1.0};
    return sss::make_synthetic_cloud(p);
}

/// A flat square of side `size` in z = z0 with normal (0, 0, nz), radii
/// from ptsynth and one constant float channel "v" (no _area).
PointCloud plane(std::size_t count, double size, float z0, float nz, float value) {
    sss::SyntheticParams p;
    p.shape = sss::SyntheticShape::Plane;
    p.count = count;
    p.size = size;
    PointCloud c = sss::make_synthetic_cloud(p);
    c.channels.clear(); // only "v": one float per sample
    for (std::size_t i = 0; i < c.size(); ++i) {
        c.positions[i].z = z0;
        c.normals[i] = {0.0f, 0.0f, nz};
    }
    sss::Channel& v = c.add_channel("v", ChannelType::Float);
    std::fill(v.data.begin(), v.data.end(), value);
    return c;
}

sss::BrickMapBuildReport build(const PointCloud& cloud, const std::string& path,
                               BrickMapBuildOptions options = {}) {
    return sss::build_brick_map({cloud}, options, path);
}

/// Lookups at every point of the cloud with its own normal, filter radius 0;
/// RMS and largest error of channel `name` against the point values.
struct ErrorStats {
    double rms = 0.0;
    double max = 0.0;
    std::size_t missing = 0;
};
ErrorStats error_at_points(const BrickMap& map, const PointCloud& cloud,
                           const std::string& name) {
    const sss::Channel* ch = cloud.find_channel(name);
    const int k = ch->components();
    const int offset = map.channel_offset(name);
    std::vector<float> out(static_cast<std::size_t>(map.info().data_size));
    ErrorStats s;
    double sum = 0.0;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (!map.lookup(cloud.positions[i], cloud.normals[i], 0.0f, out.data())) {
            ++s.missing;
            continue;
        }
        for (int c = 0; c < k; ++c) {
            const double e = double(out[offset + c]) - ch->data[i * k + c];
            sum += e * e;
            s.max = std::max(s.max, std::abs(e));
        }
    }
    s.rms = std::sqrt(sum / double(cloud.size() * k));
    return s;
}

} // namespace

// ---------------------------------------------------------------------------
// Building and accuracy
// ---------------------------------------------------------------------------

TEST(BrickMapBuild, LookupsAtThePointsReproduceSmoothData) {
    TempDir dir;
    const PointCloud cloud = sphere(20000);
    BrickMapBuildOptions o;
    o.channels = {"_radiance_t"};
    const auto report = build(cloud, dir.file("s.bkm"), o);
    EXPECT_EQ(report.points, cloud.size());
    EXPECT_GT(report.bricks_written, 0u);
    EXPECT_LT(report.bricks_written, report.bricks_before_pruning); // pruning happened
    const BrickMap map(dir.file("s.bkm"));
    const ErrorStats e = error_at_points(map, cloud, "_radiance_t");
    EXPECT_EQ(e.missing, 0u);
    // Pruning moves lookups by at most max_error (next test). The rest is the
    // splat: a sample is the area-weighted mean over the points whose
    // footprints reach its cell, within about one finest spacing h of it.
    // N.L is linear on the lit side, so symmetric means are exact there; but
    // where the data is one-sided (the kink of max(0, N.L) at the terminator,
    // the edge of a tree's 55-degree cap near the cube-corner directions) the
    // mean is off by up to the gradient (at most 1 / R) times about h / 2.
    // Here h = 1.84, R = 50: 0.018. Measured: max 0.0091 (terminator), RMS
    // 0.00077.
    const int deepest = static_cast<int>(map.info().levels.size()) - 1;
    const double h = map.info().cube_side / (7.0 * std::ldexp(1.0, deepest));
    EXPECT_LT(e.max, o.max_error + h / (2.0 * 50.0));
    EXPECT_LT(e.rms, o.max_error / 2);
}

TEST(BrickMapBuild, PruningMovesLookupsByAtMostMaxError) {
    // Against the unpruned map (max_error 0): a dropped brick's samples are
    // within max_error, minus what its dropped descendants already cost, of
    // the brick that replaces it.
    TempDir dir;
    PointCloud ramp = plane(20000, 10.0, 0.0f, 1.0f, 0.0f);
    sss::Channel* v = ramp.find_channel("v");
    for (std::size_t i = 0; i < ramp.size(); ++i) {
        const glm::vec3 p = ramp.positions[i];
        v->data[i] = 0.5f + 0.05f * p.x + 0.002f * p.y * p.y;
    }
    PointCloud ball = sphere(20000);
    ball.add_channel("v", ChannelType::Float).data = [&] {
        std::vector<float> d(ball.size());
        for (std::size_t i = 0; i < ball.size(); ++i)
            d[i] = ball.find_channel("_radiance_t")->data[3 * i];
        return d;
    }();
    for (const PointCloud* cloud : {&ramp, &ball}) {
        BrickMapBuildOptions exact;
        exact.max_error = 0.0;
        exact.channels = {"v"};
        build(*cloud, dir.file("exact.bkm"), exact); // drops only exact copies
        const BrickMap reference(dir.file("exact.bkm"));
        for (double max_error : {0.0005, 0.002, 0.01}) {
            BrickMapBuildOptions o = exact;
            o.max_error = max_error;
            build(*cloud, dir.file("pruned.bkm"), o);
            const BrickMap map(dir.file("pruned.bkm"));
            double worst = 0.0;
            for (std::size_t i = 0; i < cloud->size(); ++i) {
                float a, b;
                ASSERT_TRUE(map.lookup(cloud->positions[i], cloud->normals[i], 0.0f, &a));
                ASSERT_TRUE(
                    reference.lookup(cloud->positions[i], cloud->normals[i], 0.0f, &b));
                worst = std::max(worst, double(std::abs(a - b)));
            }
            EXPECT_LE(worst, max_error) << "max_error " << max_error;
        }
    }
}

TEST(BrickMapBuild, LargerMaxErrorGivesSmallerFile) {
    TempDir dir;
    const PointCloud cloud = sphere(20000);
    BrickMapBuildOptions fine, coarse;
    fine.max_error = 0.0005;
    coarse.max_error = 0.02;
    const auto a = build(cloud, dir.file("a.bkm"), fine);
    const auto b = build(cloud, dir.file("b.bkm"), coarse);
    EXPECT_EQ(a.bricks_before_pruning, b.bricks_before_pruning);
    EXPECT_LT(b.bricks_written, a.bricks_written);
    EXPECT_LT(b.file_size, a.file_size);
    EXPECT_EQ(b.file_size, fs::file_size(dir.file("b.bkm")));
    const BrickMap ma(dir.file("a.bkm")), mb(dir.file("b.bkm"));
    EXPECT_LT(mb.info().total_bricks, ma.info().total_bricks);
    EXPECT_EQ(ma.info().total_bricks, a.bricks_written);
}

TEST(BrickMapBuild, HeaderRoundTrip) {
    TempDir dir;
    PointCloud cloud = sphere(3000);
    cloud.world_to_eye[3] = 7.0f;
    cloud.world_to_ndc[5] = 2.5f;
    cloud.format = {640.0f, 480.0f, 1.0f};
    BrickMapBuildOptions o;
    o.max_depth = 9;
    o.max_error = 0.004;
    o.provenance = "brickmake (sss) 0.1.0: brickmake in.ptc out.bkm";
    build(cloud, dir.file("h.bkm"), o);
    const BrickMap map(dir.file("h.bkm"));
    const sss::BrickMapInfo& info = map.info();
    EXPECT_EQ(info.version, 2u);
    ASSERT_EQ(info.channels.size(), 2u); // every float and color channel
    EXPECT_EQ(info.channels[0].first, "_area");
    EXPECT_EQ(info.channels[1].first, "_radiance_t");
    EXPECT_EQ(info.channels[1].second, ChannelType::Color);
    EXPECT_EQ(info.data_size, 4);
    EXPECT_EQ(map.channel_index("_radiance_t"), 1);
    EXPECT_EQ(map.channel_offset("_radiance_t"), 1);
    EXPECT_EQ(map.channel_offset("nope"), -1);
    EXPECT_EQ(info.max_depth, 9);
    EXPECT_DOUBLE_EQ(info.max_error, 0.004);
    EXPECT_FALSE(info.ignore_normals);
    EXPECT_FALSE(info.omit_geometry);
    EXPECT_EQ(info.world_to_eye[3], 7.0f);
    EXPECT_EQ(info.world_to_ndc[5], 2.5f);
    EXPECT_EQ(info.format[0], 640.0f);
    EXPECT_EQ(info.provenance, o.provenance);
    const sss::Bounds3 b = cloud.bounds();
    EXPECT_EQ(info.bbox_min.x, b.lo.x);
    EXPECT_EQ(info.bbox_max.z, b.hi.z);
    // The root cube holds the bounds and is about as large as the widest extent.
    for (int a = 0; a < 3; ++a) {
        EXPECT_LT(info.cube_min[a], info.bbox_min[a]);
        EXPECT_GT(info.cube_min[a] + info.cube_side, info.bbox_max[a]);
    }
    EXPECT_LT(info.cube_side, 1.1 * (b.hi.x - b.lo.x));
    EXPECT_EQ(info.trees_used, 6u); // a sphere: every axis, no zero normals
    EXPECT_EQ(info.file_size, fs::file_size(dir.file("h.bkm")));
    std::size_t bricks = 0;
    for (const auto& level : info.levels) bricks += level.bricks;
    EXPECT_EQ(bricks, info.total_bricks);
    ASSERT_FALSE(info.levels.empty());
    EXPECT_EQ(info.levels[0].bricks, 6u); // one root per used tree
}

TEST(BrickMapBuild, ChannelSelectionAndErrors) {
    TempDir dir;
    PointCloud cloud = sphere(2000);
    BrickMapBuildOptions o;
    o.channels = {"_radiance_t"};
    build(cloud, dir.file("c.bkm"), o);
    {
        const BrickMap map(dir.file("c.bkm"));
        ASSERT_EQ(map.info().channels.size(), 1u);
        EXPECT_EQ(map.info().data_size, 3);
    }
    o.channels = {"nope"};
    EXPECT_THROW(build(cloud, dir.file("x.bkm"), o), sss::ValueError);
    o.channels = {"_radiance_t", "_radiance_t"};
    EXPECT_THROW(build(cloud, dir.file("x.bkm"), o), sss::ValueError);
    cloud.add_channel("P2", ChannelType::Point);
    o.channels = {"P2"};
    EXPECT_THROW(build(cloud, dir.file("x.bkm"), o), sss::ValueError);
    EXPECT_FALSE(fs::exists(dir.file("x.bkm")));

    EXPECT_THROW(sss::build_brick_map({}, {}, dir.file("x.bkm")), sss::ValueError);
    EXPECT_THROW(build(PointCloud{}, dir.file("x.bkm")), sss::ValueError);
    PointCloud no_size = plane(100, 1.0, 0.0f, 1.0f, 1.0f); // has no _area
    std::fill(no_size.radii.begin(), no_size.radii.end(), 0.0f);
    EXPECT_THROW(build(no_size, dir.file("x.bkm")),
                 sss::ValueError); // no radius, no _area
    PointCloud only_area = no_size;
    sss::Channel& area = only_area.add_channel("_area", ChannelType::Float);
    std::fill(area.data.begin(), area.data.end(), 0.01f);
    EXPECT_NO_THROW(build(only_area, dir.file("x.bkm"))); // r = sqrt(area / pi)
    PointCloud bad = plane(100, 1.0, 0.0f, 1.0f, 1.0f);
    bad.find_channel("v")->data[17] = std::nanf("");
    try {
        build(bad, dir.file("x.bkm"));
        FAIL() << "NaN accepted";
    } catch (const sss::ValueError& e) {
        EXPECT_NE(std::string(e.what()).find("point 17"), std::string::npos) << e.what();
    }
    BrickMapBuildOptions bad_options;
    bad_options.max_depth = 21;
    EXPECT_THROW(build(cloud, dir.file("x.bkm"), bad_options), sss::ValueError);
    bad_options = {};
    bad_options.max_error = -1.0;
    EXPECT_THROW(build(cloud, dir.file("x.bkm"), bad_options), sss::ValueError);
    bad_options = {};
    bad_options.radius_scale = 0.0;
    EXPECT_THROW(build(cloud, dir.file("x.bkm"), bad_options), sss::ValueError);
}

TEST(BrickMapBuild, MergesClouds) {
    TempDir dir;
    const PointCloud top = plane(2000, 4.0, 1.0f, 1.0f, 1.0f);
    const PointCloud bottom = plane(2000, 4.0, -1.0f, 1.0f, 3.0f);
    const auto report =
        sss::build_brick_map({top, bottom}, BrickMapBuildOptions{}, dir.file("m.bkm"));
    EXPECT_EQ(report.points, top.size() + bottom.size());
    const BrickMap map(dir.file("m.bkm"));
    const int v = map.channel_offset("v");
    std::vector<float> out(static_cast<std::size_t>(map.info().data_size));
    ASSERT_TRUE(map.lookup({0.3f, 0.2f, 1.0f}, {0, 0, 1}, 0.0f, out.data()));
    EXPECT_NEAR(out[v], 1.0f, 1e-5);
    ASSERT_TRUE(map.lookup({0.3f, 0.2f, -1.0f}, {0, 0, 1}, 0.0f, out.data()));
    EXPECT_NEAR(out[v], 3.0f, 1e-5);
}

TEST(BrickMapBuild, OutputDoesNotDependOnThreadCount) {
    TempDir dir;
    const PointCloud cloud = sphere(20000);
    {
        sss::ThreadLimit limit(1);
        build(cloud, dir.file("1.bkm"));
    }
    {
        sss::ThreadLimit limit(2);
        build(cloud, dir.file("2.bkm"));
    }
    {
        sss::ThreadLimit limit(5); // more threads than cores
        build(cloud, dir.file("5.bkm"));
    }
    const Bytes one = read_bytes(dir.file("1.bkm"));
    EXPECT_FALSE(one.empty());
    EXPECT_TRUE(one == read_bytes(dir.file("2.bkm")));
    EXPECT_TRUE(one == read_bytes(dir.file("5.bkm")));
}

TEST(BrickMapBuild, OmitGeometryDropsOccupancyOnly) {
    TempDir dir;
    const PointCloud cloud = sphere(20000);
    BrickMapBuildOptions o;
    o.max_error = 0.01;
    build(cloud, dir.file("g.bkm"), o);
    o.omit_geometry = true;
    build(cloud, dir.file("t.bkm"), o);
    const BrickMap g(dir.file("g.bkm")), t(dir.file("t.bkm"));
    EXPECT_TRUE(t.info().omit_geometry);
    EXPECT_GT(g.info().occupancy_nodes, 0u);
    EXPECT_EQ(t.info().occupancy_nodes, 0u);
    EXPECT_EQ(g.info().total_bricks, t.info().total_bricks);
    EXPECT_LT(t.info().file_size, g.info().file_size);
    // Lookups only use data bricks: identical.
    std::vector<float> a(4), b(4);
    for (std::size_t i = 0; i < cloud.size(); i += 7) {
        const bool fa = g.lookup(cloud.positions[i], cloud.normals[i], 0.0f, a.data());
        const bool fb = t.lookup(cloud.positions[i], cloud.normals[i], 0.0f, b.data());
        ASSERT_EQ(fa, fb);
        ASSERT_EQ(a, b) << "point " << i;
    }
    // The geometry: occupancy of the deepest nodes is kept without their data.
    const auto& levels = g.info().levels;
    const int deepest = static_cast<int>(levels.size()) - 1;
    EXPECT_GT(levels[deepest].occupancy_nodes, 0u);
    std::vector<uint8_t> present;
    std::vector<float> data;
    bool found = false;
    for (int tree = 1; tree < 7 && !found; ++tree) {
        for (uint32_t x = 0; x < (1u << deepest) && !found; ++x) {
            for (uint32_t y = 0; y < (1u << deepest) && !found; ++y) {
                for (uint32_t z = 0; z < (1u << deepest) && !found; ++z) {
                    if (!g.read_occupancy(tree, deepest, x, y, z, present)) continue;
                    if (g.read_brick(tree, deepest, x, y, z, data, present)) continue;
                    found = true;
                    ASSERT_TRUE(g.read_occupancy(tree, deepest, x, y, z, present));
                    EXPECT_GT(std::count(present.begin(), present.end(), 1), 0);
                    EXPECT_FALSE(t.read_occupancy(tree, deepest, x, y, z, present));
                }
            }
        }
    }
    EXPECT_TRUE(found);
}

// ---------------------------------------------------------------------------
// Lookups
// ---------------------------------------------------------------------------

TEST(BrickMapLookup, ThinPlateKeepsItsSidesApart) {
    TempDir dir;
    // Two planes 0.01 apart (the point spacing is 0.02): value 1 facing +z,
    // value 0 facing -z.
    const PointCloud upper = plane(10000, 2.0, 0.005f, 1.0f, 1.0f);
    const PointCloud lower = plane(10000, 2.0, -0.005f, -1.0f, 0.0f);
    sss::build_brick_map({upper, lower}, BrickMapBuildOptions{}, dir.file("p.bkm"));
    const BrickMap map(dir.file("p.bkm"));
    EXPECT_EQ(map.info().trees_used, 2u);
    float out[2];
    const int v = map.channel_offset("v");
    for (float x : {-0.9f, -0.31f, 0.0f, 0.42f, 0.87f}) {
        for (float z : {-0.005f, 0.0f, 0.005f}) {
            ASSERT_TRUE(map.lookup({x, 0.13f, z}, {0, 0, 1}, 0.0f, out));
            EXPECT_NEAR(out[v], 1.0f, 1e-5);
            ASSERT_TRUE(map.lookup({x, 0.13f, z}, {0.2f, -0.3f, -1}, 0.0f, out));
            EXPECT_NEAR(out[v], 0.0f, 1e-5);
            // Blurred lookups too: the sides never share a tree.
            ASSERT_TRUE(map.lookup({x, 0.13f, z}, {0, 0, 1}, 0.3f, out));
            EXPECT_NEAR(out[v], 1.0f, 1e-5);
        }
    }
    // -ignorenormals: one tree, the two sides blend.
    BrickMapBuildOptions o;
    o.ignore_normals = true;
    sss::build_brick_map({upper, lower}, o, dir.file("i.bkm"));
    const BrickMap blended(dir.file("i.bkm"));
    EXPECT_TRUE(blended.info().ignore_normals);
    EXPECT_EQ(blended.info().trees_used, 1u);
    ASSERT_TRUE(blended.lookup({0.1f, 0.13f, 0.0f}, {0, 0, 1}, 0.0f, out));
    EXPECT_GT(out[v], 0.2f);
    EXPECT_LT(out[v], 0.8f);
}

TEST(BrickMapLookup, NormalsNearTheBoundaryBetweenAxesFindData) {
    TempDir dir;
    // A plane whose normal is 45 degrees between +x and +z: it goes into both
    // trees, so lookups whose normal tips either way find the same data.
    PointCloud cloud = plane(5000, 2.0, 0.0f, 1.0f, 2.0f);
    const float s = std::sqrt(0.5f);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const glm::vec3 p = cloud.positions[i];
        cloud.positions[i] = {p.x * s, p.y, -p.x * s};
        cloud.normals[i] = {s, 0.0f, s};
    }
    build(cloud, dir.file("d.bkm"));
    const BrickMap map(dir.file("d.bkm"));
    EXPECT_EQ(map.info().trees_used, 2u);
    float out[2];
    for (const glm::vec3 n : {glm::vec3(1.0f, 0.0f, 0.98f), glm::vec3(0.98f, 0.0f, 1.0f),
                              glm::vec3(0.6f, 0.5f, 0.62f)}) {
        ASSERT_TRUE(map.lookup({0.1f, 0.2f, -0.1f}, n, 0.0f, out));
        EXPECT_NEAR(out[map.channel_offset("v")], 2.0f, 1e-5);
    }
}

TEST(BrickMapLookup, ZeroNormalsUseTreeZero) {
    TempDir dir;
    PointCloud cloud = plane(4000, 2.0, 0.0f, 0.0f, 5.0f); // normals (0, 0, 0)
    build(cloud, dir.file("z.bkm"));
    const BrickMap map(dir.file("z.bkm"));
    EXPECT_EQ(map.info().trees_used, 1u);
    EXPECT_EQ(map.bricks_at(0, 0).size(), 1u);
    float out[2];
    ASSERT_TRUE(map.lookup({0.2f, 0.3f, 0.0f}, {0, 0, 0}, 0.0f, out));
    EXPECT_NEAR(out[map.channel_offset("v")], 5.0f, 1e-5);
    // A query with a normal falls back to the no-normal tree.
    ASSERT_TRUE(map.lookup({0.2f, 0.3f, 0.0f}, {0, 1, 0}, 0.0f, out));
    EXPECT_NEAR(out[map.channel_offset("v")], 5.0f, 1e-5);
}

TEST(BrickMapLookup, OffTheSurfaceFallsBackToCoarserData) {
    TempDir dir;
    const PointCloud cloud = plane(10000, 2.0, 0.0f, 1.0f, 1.0f);
    build(cloud, dir.file("o.bkm"));
    const BrickMap map(dir.file("o.bkm"));
    const double side = map.info().cube_side;
    const int deepest = static_cast<int>(map.info().levels.size()) - 1;
    const double h = side / (7.0 * std::ldexp(1.0, deepest)); // finest spacing
    float out[2];
    const int v = map.channel_offset("v");
    // A few finest spacings above the surface there is no fine data: the
    // lookup uses coarser levels and still returns the surface value.
    for (double above : {0.5 * h, 2.0 * h, 5.0 * h, 12.0 * h}) {
        ASSERT_TRUE(map.lookup({0.1f, -0.2f, float(above)}, {0, 0, 1}, 0.0f, out))
            << above;
        EXPECT_NEAR(out[v], 1.0f, 1e-5);
    }
    // Far from the surface, inside the root cube: no level has data there.
    EXPECT_FALSE(map.lookup({0.1f, -0.2f, float(0.45 * side)}, {0, 0, 1}, 0.0f, out));
    // Outside the root cube, and NaN: nothing, output zeroed.
    out[v] = 9.0f;
    EXPECT_FALSE(map.lookup({0.1f, -0.2f, float(side)}, {0, 0, 1}, 0.0f, out));
    EXPECT_EQ(out[v], 0.0f);
    EXPECT_FALSE(map.lookup({std::nanf(""), 0.0f, 0.0f}, {0, 0, 1}, 0.0f, out));
    EXPECT_FALSE(map.lookup({100.0f, 0.0f, 0.0f}, {0, 0, 1}, 0.0f, out));
}

TEST(BrickMapLookup, LargerFilterRadiusIsSmoother) {
    TempDir dir;
    // Noise on a plane: the finest level follows it, coarser levels average it.
    PointCloud cloud = plane(40000, 2.0, 0.0f, 1.0f, 0.0f);
    sss::Channel* v = cloud.find_channel("v");
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        uint64_t x = (i + 1) * 0x9E3779B97F4A7C15ull;
        x ^= x >> 31;
        x *= 0xBF58476D1CE4E5B9ull;
        x ^= x >> 29;
        v->data[i] = float((x >> 11) * 0x1.0p-53);
    }
    BrickMapBuildOptions o;
    o.max_error = 0.0;
    build(cloud, dir.file("f.bkm"), o);
    const BrickMap map(dir.file("f.bkm"));
    const int off = map.channel_offset("v");
    auto spread = [&](float radius) {
        // Standard deviation of lookups along a line across the plane.
        double sum = 0.0, sum2 = 0.0;
        const int n = 400;
        for (int k = 0; k < n; ++k) {
            float out[2];
            const glm::vec3 p(-0.8f + 1.6f * k / n, 0.137f, 0.0f);
            EXPECT_TRUE(map.lookup(p, {0, 0, 1}, radius, out));
            sum += out[off];
            sum2 += double(out[off]) * out[off];
        }
        const double mean = sum / n;
        return std::sqrt(std::max(0.0, sum2 / n - mean * mean));
    };
    const double s0 = spread(0.0f), s1 = spread(0.02f), s2 = spread(0.08f),
                 s3 = spread(0.3f);
    EXPECT_GT(s0, 0.05); // noise with a standard deviation of 0.29 (uniform)
    EXPECT_LT(s1, s0);
    EXPECT_LT(s2, s1);
    EXPECT_LT(s3, s2);
    EXPECT_LT(s3, 0.02);
    // Radius zero is the finest level; a tiny radius is the same.
    float a[2], b[2];
    ASSERT_TRUE(map.lookup({0.11f, 0.2f, 0.0f}, {0, 0, 1}, 0.0f, a));
    ASSERT_TRUE(map.lookup({0.11f, 0.2f, 0.0f}, {0, 0, 1}, 1e-6f, b));
    EXPECT_EQ(a[off], b[off]);
    // Between two levels the result blends continuously: radii that differ
    // a little give values that differ a little.
    float c[2], d[2];
    ASSERT_TRUE(map.lookup({0.11f, 0.2f, 0.0f}, {0, 0, 1}, 0.05f, c));
    ASSERT_TRUE(map.lookup({0.11f, 0.2f, 0.0f}, {0, 0, 1}, 0.0501f, d));
    EXPECT_NEAR(c[off], d[off], 0.01);
}

TEST(BrickMapLookup, ConcurrentLookupsEqualSingleThreaded) {
    TempDir dir;
    const PointCloud cloud = sphere(20000);
    build(cloud, dir.file("c.bkm"));
    const std::size_t n = cloud.size();
    std::vector<float> expected(n * 4);
    {
        const BrickMap map(dir.file("c.bkm"));
        for (std::size_t i = 0; i < n; ++i)
            map.lookup(cloud.positions[i], cloud.normals[i], 0.05f, &expected[4 * i]);
    }
    // A small cache makes the threads load, evict and reload bricks while
    // others use them.
    for (std::size_t cache : {std::size_t(256) << 20, std::size_t(200) << 10}) {
        const BrickMap map(dir.file("c.bkm"), cache);
        std::vector<float> got(n * 4);
        std::vector<std::thread> threads;
        for (int t = 0; t < 4; ++t) {
            threads.emplace_back([&, t] {
                for (std::size_t k = 0; k < n; ++k) {
                    const std::size_t i =
                        (k * 7919 + t * (n / 4)) % n; // different orders
                    std::vector<float> out(4);
                    map.lookup(cloud.positions[i], cloud.normals[i], 0.05f, out.data());
                    if (i % 4 == std::size_t(t))
                        std::copy(out.begin(), out.end(), &got[4 * i]);
                }
            });
        }
        for (std::thread& th : threads) th.join();
        EXPECT_TRUE(got == expected) << "cache " << cache;
        // Live bricks within the budget, evicted ones awaiting the end of
        // lookups that may still use them within about another budget.
        EXPECT_LE(map.cached_bytes(), 2 * cache + cache / 4 + (std::size_t(20) << 10));
    }
}

TEST(BrickMapLookup, TinyCacheGivesIdenticalLookups) {
    TempDir dir;
    const PointCloud cloud = sphere(20000);
    build(cloud, dir.file("t.bkm"));
    const BrickMap big(dir.file("t.bkm"));
    const BrickMap tiny(dir.file("t.bkm"), 64u << 10);
    std::vector<float> a(4), b(4);
    for (int pass = 0; pass < 2; ++pass) {
        for (std::size_t i = 0; i < cloud.size(); i += 3) {
            const bool fa =
                big.lookup(cloud.positions[i], cloud.normals[i], 0.0f, a.data());
            const bool fb =
                tiny.lookup(cloud.positions[i], cloud.normals[i], 0.0f, b.data());
            ASSERT_EQ(fa, fb);
            ASSERT_EQ(a, b);
        }
    }
    // Every brick fits in the big cache: loaded once. The tiny one reloads.
    EXPECT_LE(big.bricks_loaded(), big.info().total_bricks);
    EXPECT_GT(tiny.bricks_loaded(), big.bricks_loaded());
    EXPECT_LE(tiny.cached_bytes(), std::size_t(64 + 32) << 10);
    EXPECT_GT(big.cached_bytes(), tiny.cached_bytes());
}

TEST(BrickMapLookup, ReadBrickAndBricksAt) {
    TempDir dir;
    const PointCloud cloud = plane(4000, 2.0, 0.0f, 1.0f, 3.0f);
    build(cloud, dir.file("r.bkm"));
    const BrickMap map(dir.file("r.bkm"));
    const auto roots = map.bricks_at(5, 0); // +z tree
    ASSERT_EQ(roots.size(), 1u);
    EXPECT_EQ(roots[0], (std::array<uint32_t, 3>{0, 0, 0}));
    EXPECT_TRUE(map.bricks_at(1, 0).empty());
    EXPECT_TRUE(map.bricks_at(9, 0).empty());
    std::vector<float> data;
    std::vector<uint8_t> present;
    ASSERT_TRUE(map.read_brick(5, 0, 0, 0, 0, data, present));
    ASSERT_EQ(present.size(), 512u);
    ASSERT_EQ(map.info().data_size, 1);
    ASSERT_EQ(data.size(), 512u);
    int count = 0;
    for (int s = 0; s < 512; ++s) {
        if (!present[s]) {
            EXPECT_EQ(data[s], 0.0f);
            continue;
        }
        ++count;
        EXPECT_NEAR(data[s], 3.0f, 1e-5);
    }
    EXPECT_EQ(static_cast<std::size_t>(count), map.info().levels[0].samples);
    EXPECT_FALSE(map.read_brick(5, 0, 1, 0, 0, data, present));
    EXPECT_FALSE(map.read_brick(5, 30, 0, 0, 0, data, present));
    EXPECT_FALSE(map.read_brick(-1, 0, 0, 0, 0, data, present));
    for (int d = 0; d < static_cast<int>(map.info().levels.size()); ++d) {
        for (const auto& c : map.bricks_at(5, d))
            EXPECT_TRUE(map.read_brick(5, d, c[0], c[1], c[2], data, present));
    }
}

// ---------------------------------------------------------------------------
// Corrupt files
// ---------------------------------------------------------------------------

namespace {

/// Opens the file and, if that works, looks up and reads every brick: only
/// FormatError may come out (never a crash or another exception).
void exercise(const std::string& path, sss::BrickMapChecksums checksums) {
    try {
        const BrickMap map(path, 64u << 10, checksums);
        std::vector<float> out(static_cast<std::size_t>(map.info().data_size));
        for (float x : {-0.7f, 0.0f, 0.4f})
            map.lookup({x, 0.1f, 0.0f}, {0, 0, 1}, 0.0f, out.data());
        std::vector<float> data;
        std::vector<uint8_t> present;
        for (int t = 0; t < 7; ++t) {
            for (int d = 0; d < static_cast<int>(map.info().levels.size()); ++d) {
                for (const auto& c : map.bricks_at(t, d)) {
                    map.read_brick(t, d, c[0], c[1], c[2], data, present);
                    map.read_occupancy(t, d, c[0], c[1], c[2], present);
                }
            }
        }
    } catch (const sss::FormatError& e) {
        EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
}

std::string open_error(const std::string& path) {
    try {
        BrickMap map(path);
    } catch (const sss::FormatError& e) {
        return e.what();
    }
    return "";
}

} // namespace

TEST(BrickMapFile, CorruptFilesGiveFormatErrors) {
    TempDir dir;
    PointCloud cloud = plane(3000, 2.0, 0.0f, 1.0f, 1.0f);
    for (std::size_t i = 0; i < cloud.size(); ++i) // varying data: many data bricks
        cloud.find_channel("v")->data[i] = std::sin(7.0f * cloud.positions[i].x);
    BrickMapBuildOptions o;
    o.max_error = 0.0;
    build(cloud, dir.file("good.bkm"), o);
    const Bytes good = read_bytes(dir.file("good.bkm"));
    const std::string bad = dir.file("bad.bkm");
    const uint64_t head = get_u64(good, 280); // first brick
    ASSERT_LT(head, good.size());

    // Truncation anywhere: the header's file size no longer matches.
    for (std::size_t cut = 0; cut < good.size(); cut += (cut < 400    ? 1
                                                         : cut < head ? 7
                                                                      : 97)) {
        write_bytes(bad, Bytes(good.begin(), good.begin() + cut));
        EXPECT_FALSE(open_error(bad).empty()) << "cut at " << cut;
    }
    // Every byte changed: tests/brick/bkm_integrity_test.cpp. Here bytes
    // flipped without the checksums, so that the structural checks of the
    // header, tables and bricks see them: FormatError or a file that reads.
    for (std::size_t at = 0; at < good.size(); at += (at < head ? 3 : 101)) {
        Bytes b = good;
        b[at] ^= 0x5a;
        write_bytes(bad, b);
        exercise(bad, sss::BrickMapChecksums::Ignore);
    }
    const BrickMap intact(dir.file("good.bkm"));
    EXPECT_GT(intact.info().total_bricks, 10u);

    Bytes b = good;
    b[0] = 'X';
    write_bytes(bad, b);
    EXPECT_NE(open_error(bad).find("bad magic"), std::string::npos);
    b = good;
    put_u32(b, 8, 3);
    write_bytes(bad, b);
    EXPECT_NE(open_error(bad).find("unsupported .bkm version 3"), std::string::npos);
    b = good;
    put_u32(b, 24, 0xffffffffu); // channel count
    write_bytes(bad, b);
    EXPECT_NE(open_error(bad).find("channel count"), std::string::npos);
    b = good;
    put_u32(b, 28, 0x7fffffffu); // data size
    write_bytes(bad, b);
    EXPECT_NE(open_error(bad).find("data size"), std::string::npos);
    // A huge node count in the tree directory (entry of tree 5 at the end of
    // the channel table and provenance).
    const std::size_t dir_at = 288 + get_u32(good, 44) + get_u32(good, 40);
    b = good;
    put_u32(b, dir_at + 5 * 16 + 8, 0xfffffff0u);
    write_bytes(bad, b);
    EXPECT_NE(open_error(bad).find("does not fit"), std::string::npos) << open_error(bad);
    // Trailing garbage.
    b = good;
    b.push_back(0);
    write_bytes(bad, b);
    EXPECT_FALSE(open_error(bad).empty());
    // An empty file, and a missing one (IoError, not FormatError).
    write_bytes(bad, {});
    EXPECT_NE(open_error(bad).find("too short"), std::string::npos);
    EXPECT_THROW(BrickMap(dir.file("missing.bkm")), sss::IoError);
    EXPECT_THROW(BrickMap(dir.file("")), sss::IoError);
}

TEST(BrickMapFile, NaNInABrickNamesTheBrick) {
    TempDir dir;
    const PointCloud cloud = plane(3000, 2.0, 0.0f, 1.0f, 1.0f);
    build(cloud, dir.file("n.bkm"));
    Bytes b = read_bytes(dir.file("n.bkm"));
    // The first brick is the +z tree's root (trees 0..4 are empty); its first
    // float follows the 64-byte presence mask.
    const uint64_t first = get_u64(b, 280);
    put_u32(b, first + 64, 0x7fc00000u);
    write_bytes(dir.file("n.bkm"), b);
    // The brick's checksum catches it first; without the checksums, the
    // value check does.
    for (auto mode : {sss::BrickMapChecksums::Verify, sss::BrickMapChecksums::Ignore}) {
        const BrickMap map(dir.file("n.bkm"), 1u << 20, mode); // bricks load on demand
        float out[2];
        try {
            map.lookup({0.1f, 0.1f, 0.0f}, {0, 0, 1}, 1.0f, out);
            FAIL() << "NaN brick accepted";
        } catch (const sss::FormatError& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find("n.bkm"), std::string::npos) << what;
            EXPECT_NE(what.find("tree 5, depth 0"), std::string::npos) << what;
            EXPECT_NE(what.find(mode == sss::BrickMapChecksums::Verify ? "CRC-32"
                                                                       : "non-finite"),
                      std::string::npos)
                << what;
        }
        std::vector<float> data;
        std::vector<uint8_t> present;
        EXPECT_THROW(map.read_brick(5, 0, 0, 0, 0, data, present), sss::FormatError);
    }
}
