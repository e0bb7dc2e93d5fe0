// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file vdb_test.cpp
/// OpenVDB output of brick maps: the grids read back against the map's own
/// bricks (the coarser levels, sample for sample) and lookups (the main
/// grids), the transforms in world units, the metadata and the report.

#include <gtest/gtest.h>

#include "test_util.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "sss/brick/brickmap.h"
#include "sss/brick/brickmap_voxels.h"
#include "sss/cloud/point_cloud.h"
#include "sss/cloud/point_cloud_io.h"
#include "sss/cloud/synthetic.h"
#include "sss/util/error.h"
#include "sss/vdb/vdb.h"

namespace {

using sss::BrickMap;
using sss::PointCloud;
using sss::VdbGrid;
using sss::test::TempDir;
using Coord = std::array<int32_t, 3>;

/// A plane (normal +z: one tree) or a sphere (several trees) with a smooth,
/// varying `_radiance_t` and a float channel.
PointCloud test_cloud(sss::SyntheticShape shape) {
    sss::SyntheticParams p;
    p.shape = shape;
    p.count = 4000;
    p.size = 1.0;
    PointCloud c = sss::make_synthetic_cloud(p);
    // Added first: adding a channel may move the others.
    auto& tint = c.add_channel("tint", sss::ChannelType::Float).data;
    auto& rad = c.find_channel("_radiance_t")->data;
    for (std::size_t i = 0; i < c.size(); ++i) {
        const glm::vec3 q = c.positions[i];
        rad[3 * i] = 0.5f + 0.4f * std::sin(3.0f * q.x);
        rad[3 * i + 1] = 0.3f + 0.2f * q.y;
        rad[3 * i + 2] = 0.1f;
        tint[i] = q.x + 2.0f * q.y;
    }
    return c;
}

std::string build_map(const TempDir& dir, const PointCloud& cloud, bool ignore_normals) {
    sss::BrickMapBuildOptions opt;
    opt.max_depth = 6;
    opt.ignore_normals = ignore_normals;
    opt.channels = {"_radiance_t", "tint"}; // 4 floats a sample: colour, then tint
    opt.provenance = "vdb_test";
    const std::string path = dir.file("m.bkm");
    sss::build_brick_map({cloud}, opt, path);
    return path;
}

const VdbGrid& grid_named(const std::vector<VdbGrid>& grids, const std::string& name) {
    for (const VdbGrid& g : grids)
        if (g.info.name == name) return g;
    ADD_FAILURE() << "no grid " << name;
    static const VdbGrid none;
    return none;
}

/// The grid's value at c (components floats), or nullptr.
const float* value_at(const VdbGrid& g, const Coord& c) {
    const auto it = std::lower_bound(g.coords.begin(), g.coords.end(), c);
    if (it == g.coords.end() || *it != c) return nullptr;
    return g.values.data() + (it - g.coords.begin()) * g.components;
}

/// What the map holds at one lattice point of a depth: the trees with
/// geometry there, and the sum of the samples of those that store one.
struct MapPoint {
    int trees = 0;
    int stored = 0;
    std::array<double, 4> sum{};
};

/// Every lattice point of `depth` where some tree has geometry (data bricks'
/// and occupancy-only nodes' presence flags), each tree counted once (the
/// faces neighbouring bricks share).
std::map<Coord, MapPoint> map_points(const BrickMap& map, int depth) {
    std::map<Coord, MapPoint> points;
    std::vector<float> data;
    std::vector<uint8_t> present;
    for (int t = 0; t < 7; ++t) {
        std::map<Coord, bool> in_tree;
        for (const auto& node : map.nodes_at(t, depth)) {
            const bool stored =
                map.read_brick(t, depth, node[0], node[1], node[2], data, present);
            if (!stored)
                EXPECT_TRUE(
                    map.read_occupancy(t, depth, node[0], node[1], node[2], present));
            for (int s = 0; s < 512; ++s) {
                if (!present[s]) continue;
                const Coord c = {int32_t(node[0]) * 7 + s % 8,
                                 int32_t(node[1]) * 7 + (s / 8) % 8,
                                 int32_t(node[2]) * 7 + s / 64};
                if (in_tree[c]) continue;
                in_tree[c] = true;
                MapPoint& m = points[c];
                ++m.trees;
                if (!stored) continue;
                ++m.stored;
                for (int k = 0; k < 4; ++k) m.sum[k] += data[s * 4 + k];
            }
        }
    }
    return points;
}

/// The grids of one depth against the map's bricks: a voxel at every point
/// with geometry, and where every tree there stores a sample, the mean of
/// those samples (lookups at a sample's own position, so to float rounding).
/// Returns how many voxels averaged several trees.
std::size_t expect_grids_match_bricks(const BrickMap& map, const VdbGrid& color,
                                      const VdbGrid& tint, int depth) {
    const std::map<Coord, MapPoint> points = map_points(map, depth);
    EXPECT_EQ(color.coords.size(), points.size()) << color.info.name;
    EXPECT_EQ(tint.coords, color.coords) << tint.info.name;
    std::size_t checked = 0, averaged = 0;
    for (const auto& [c, m] : points) {
        const float* v = value_at(color, c);
        const float* t = value_at(tint, c);
        if (!v || !t) {
            ADD_FAILURE() << color.info.name << ": no voxel at (" << c[0] << " " << c[1]
                          << " " << c[2] << ")";
            continue;
        }
        if (m.stored != m.trees) continue; // a pruned brick: coarser data
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(v[k], m.sum[k] / m.stored, 1e-4);
        EXPECT_NEAR(t[0], m.sum[3] / m.stored, 1e-4);
        ++checked;
        averaged += m.trees > 1;
    }
    EXPECT_GT(checked, 0u) << color.info.name;
    return averaged;
}

void expect_transform(const BrickMap& map, const VdbGrid& g, int depth) {
    const double spacing = map.info().cube_side / (7.0 * std::ldexp(1.0, depth));
    for (int a = 0; a < 3; ++a) {
        EXPECT_NEAR(g.info.voxel_size[a], spacing, 1e-12 * spacing) << g.info.name;
        EXPECT_NEAR(g.info.origin[a], map.info().cube_min[a], 1e-9) << g.info.name;
    }
    EXPECT_TRUE(g.info.linear);
}

std::string meta(const VdbGrid& g, const std::string& key) {
    for (const auto& [k, v] : g.info.metadata)
        if (k == key) return v;
    return "";
}

/// Writes the map's grids and checks every level against the bricks;
/// returns the voxels that averaged several trees.
std::size_t check_all_levels(const BrickMap& map, const TempDir& dir) {
    const std::string out = dir.file("m.vdb");
    const sss::VdbWriteReport report = sss::write_brick_map_vdb(map, out);
    const int depth = report.surface_depth;
    EXPECT_GE(depth, 2);
    const std::vector<VdbGrid> grids = sss::read_vdb_grids(out);
    EXPECT_EQ(grids.size(), 2u * std::size_t(depth + 1));
    EXPECT_EQ(grids.size(), report.grids.size());
    std::size_t averaged = 0;
    for (int level = 0; level <= depth; ++level) {
        const std::string suffix = level ? "_level" + std::to_string(level) : "";
        const VdbGrid& color = grid_named(grids, "_radiance_t" + suffix);
        const VdbGrid& tint = grid_named(grids, "tint" + suffix);
        EXPECT_EQ(color.components, 3);
        EXPECT_EQ(tint.components, 1);
        EXPECT_EQ(color.info.value_type, "vec3s");
        EXPECT_EQ(tint.info.value_type, "float");
        averaged += expect_grids_match_bricks(map, color, tint, depth - level);
        expect_transform(map, color, depth - level);
        expect_transform(map, tint, depth - level);
        EXPECT_EQ(meta(color, "sss_channel"), "_radiance_t");
        EXPECT_EQ(meta(color, "sss_channel_type"), "color");
        EXPECT_EQ(meta(tint, "sss_channel_type"), "float");
        EXPECT_EQ(meta(color, "sss_brick_depth"), std::to_string(depth - level));
        EXPECT_EQ(meta(color, "sss_level"), std::to_string(level));
    }
    return averaged;
}

TEST(VdbOutput, PlaneGridsAreTheBricksSamplesAndLookups) {
    // A plane with normal +z: every point is in tree 5 (+z) only.
    TempDir dir;
    const BrickMap map(build_map(dir, test_cloud(sss::SyntheticShape::Plane), false));
    EXPECT_EQ(check_all_levels(map, dir), 0u);
    // Uniform points: the whole surface reaches the deepest level.
    const int depth = sss::brick_map_surface_depth(map);
    EXPECT_EQ(depth, int(map.info().levels.size()) - 1);
    // Every voxel, pruned bricks' too, is the lookup of that depth.
    const sss::BrickMapVoxels v = sss::brick_map_voxels(map, depth);
    ASSERT_FALSE(v.coords.empty());
    EXPECT_TRUE(std::is_sorted(v.coords.begin(), v.coords.end()));
    float out[4];
    for (std::size_t i = 0; i < v.coords.size(); ++i) {
        glm::vec3 p;
        for (int a = 0; a < 3; ++a)
            p[a] = float(v.origin[a] + v.spacing * v.coords[i][a]);
        ASSERT_TRUE(map.lookup_depth(p, glm::vec3(0, 0, 1), depth, out));
        for (int k = 0; k < 4; ++k) ASSERT_EQ(v.values[4 * i + k], out[k]) << i;
    }
}

TEST(VdbOutput, SphereGridsAverageTheTrees) {
    TempDir dir;
    const BrickMap map(build_map(dir, test_cloud(sss::SyntheticShape::Sphere), false));
    EXPECT_GT(check_all_levels(map, dir), 0u)
        << "no voxel in two trees: nothing averaged";
}

TEST(VdbOutput, IgnoreNormalsGridsAreTreeZero) {
    TempDir dir;
    const BrickMap map(build_map(dir, test_cloud(sss::SyntheticShape::Sphere), true));
    EXPECT_EQ(check_all_levels(map, dir), 0u);
}

TEST(VdbOutput, ReportDescribesTheGrids) {
    TempDir dir;
    const BrickMap map(build_map(dir, test_cloud(sss::SyntheticShape::Plane), false));
    const std::string out = dir.file("d.vdb");
    sss::write_brick_map_vdb(map, out);
    const std::string text = sss::describe_vdb_file(out);
    EXPECT_NE(text.find("format: OpenVDB "), std::string::npos) << text;
    EXPECT_NE(text.find("sss_provenance: vdb_test\n"), std::string::npos) << text;
    EXPECT_NE(text.find("\n  _radiance_t: vec3s, "), std::string::npos) << text;
    EXPECT_NE(text.find("\n  tint_level1: float, "), std::string::npos) << text;
    EXPECT_NE(text.find("sss_channel_type: color"), std::string::npos) << text;
    EXPECT_EQ(sss::vdb_file_problem(out), "");
    EXPECT_TRUE(sss::is_vdb_path("A.VDB"));
    EXPECT_FALSE(sss::is_vdb_path("a.bkm"));
}

TEST(VdbOutput, UnreadableFilesAreTypedErrors) {
    TempDir dir;
    const std::string junk = dir.file("junk.vdb");
    sss::test::write_text(junk, "no grids here\n");
    EXPECT_THROW(sss::read_vdb_grids(junk), sss::FormatError);
    EXPECT_THROW(sss::describe_vdb_file(junk), sss::FormatError);
    EXPECT_NE(sss::vdb_file_problem(junk).find("not a readable OpenVDB file"),
              std::string::npos);
    EXPECT_THROW(sss::read_vdb_grids(dir.file("missing.vdb")), sss::IoError);
}

TEST(VdbOutput, MakeFromFilesLeavesNoScratchMap) {
    TempDir dir;
    const std::string cloud = dir.file("c.ptc");
    const PointCloud c = test_cloud(sss::SyntheticShape::Plane);
    sss::write_point_cloud(c, cloud);
    sss::BrickMapBuildOptions opt;
    opt.max_depth = 5;
    const sss::VdbMakeReport r =
        sss::make_vdb_from_files({cloud}, opt, dir.file("o.vdb"));
    EXPECT_EQ(r.build.points, c.size());
    // _area, _radiance_t and tint, each at the main level and its coarser ones.
    EXPECT_EQ(r.vdb.grids.size(), 3u * std::size_t(r.vdb.surface_depth + 1));
    EXPECT_GT(r.vdb.file_size, 0u);
    std::size_t files = 0;
    for (const auto& e : std::filesystem::directory_iterator(dir.path())) {
        (void)e;
        ++files;
    }
    EXPECT_EQ(files, 2u) << "a scratch file was left next to the output";
}

} // namespace
