// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// ptbake on diced grids: exact derivatives (area, calculatenormal, Du) from
// the dicer's grids, and displacement shaders.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <string>

#include <glm/geometric.hpp>

#include "sss/bake/bake.h"
#include "sss/rsl/shader_library.h"
#include "sss/scene/rib.h"
#include "test_util.h"

namespace {

const double kPi = 3.14159265358979323846;

/// A scene in `dir` (shaders found next to it) with a bake of `world`.
sss::Scene scene_in(const sss::test::TempDir& dir, const std::string& world) {
    const std::string path = dir.file("scene.rib");
    const std::string text = "Format 200 200 1\nProjection \"perspective\" \"fov\" 40\n"
                             "Translate 0 0 6\nWorldBegin\n" +
                             world + "WorldEnd\n";
    sss::test::write_text(path, text);
    return sss::parse_rib(text, path);
}

/// Bakes area(P) as "a" and calculatenormal(P) as "cn" (world space).
const char* kBakeGeometry = R"(
surface bake_geometry(string filename = "") {
    normal cn = normalize(calculatenormal(P));
    float a = area(P);
    bake3d(filename, "a,cn", P, N, "a", a, "cn", ntransform("world", cn));
    Ci = 1;
}
)";

double channel_sum(const sss::PointCloud& c, const char* name) {
    const sss::Channel* ch = c.find_channel(name);
    return ch ? std::accumulate(ch->data.begin(), ch->data.end(), 0.0) : -1.0;
}

} // namespace

TEST(BakeGrid, AreaAndCalculatenormalAreExactOnGrids) {
    sss::test::TempDir dir;
    sss::test::write_text(dir.file("bake_geometry.sl"), kBakeGeometry);
    const std::string path = dir.file("g.ptc");
    const sss::Scene scene =
        scene_in(dir, "Surface \"bake_geometry\" \"string filename\" [\"" + path +
                          "\"]\nSphere 1 -1 1 360\n");
    sss::BakeOptions opt;
    opt.spacing = 0.04;
    const auto files = sss::bake_clouds(scene, opt, nullptr);
    ASSERT_EQ(files.size(), 1u);
    const sss::PointCloud& c = files[0].second;
    ASSERT_GT(c.size(), 5000u);
    EXPECT_NEAR(channel_sum(c, "a"), 4.0 * kPi, 4.0 * kPi * 1e-2);
    const sss::Channel* cn = c.find_channel("cn");
    ASSERT_NE(cn, nullptr);
    double worst = 1.0;
    for (std::size_t i = 0; i < c.size(); ++i) {
        const glm::dvec3 radial = glm::normalize(glm::dvec3(c.positions[i]));
        const glm::dvec3 n(cn->data[3 * i], cn->data[3 * i + 1], cn->data[3 * i + 2]);
        worst = std::min(worst, glm::dot(n, radial));
    }
    EXPECT_GT(worst, 0.999);
}

namespace {

/// P += amount along N, then N from the displaced grid: a sphere grows.
const char* kGrow = R"(
displacement grow(float amount = 0.1) {
    P += amount * normalize(N);
    N = calculatenormal(P);
}
)";

} // namespace

TEST(BakeGrid, ConstantDisplacementGrowsTheSphere) {
    sss::test::TempDir dir;
    sss::test::write_text(dir.file("bake_geometry.sl"), kBakeGeometry);
    sss::test::write_text(dir.file("grow.sl"), kGrow);
    const std::string path = dir.file("g.ptc");
    const sss::Scene scene =
        scene_in(dir, "Attribute \"displacementbound\" \"sphere\" [0.1]\n"
                      "Displacement \"grow\" \"float amount\" [0.1]\n"
                      "Surface \"bake_geometry\" \"string filename\" [\"" +
                          path + "\"]\nSphere 1 -1 1 360\n");
    sss::BakeOptions opt;
    opt.spacing = 0.04;
    sss::BakeReport report;
    const auto files = sss::bake_clouds(scene, opt, &report);
    for (const std::string& w : report.warnings) ADD_FAILURE() << "warning: " << w;
    ASSERT_EQ(files.size(), 1u);
    const sss::PointCloud& c = files[0].second;
    ASSERT_GT(c.size(), 5000u);
    const double r = 1.1;
    const double want = 4.0 * kPi * r * r;
    EXPECT_NEAR(channel_sum(c, "_area"), want, want * 1e-2);
    EXPECT_NEAR(channel_sum(c, "a"), want, want * 1e-2);
    double distance = 0.0, normal = 0.0;
    for (std::size_t i = 0; i < c.size(); ++i) {
        const glm::dvec3 p(c.positions[i]);
        distance = std::max(distance, std::abs(glm::length(p) - r));
        normal =
            std::max(normal, glm::length(glm::dvec3(c.normals[i]) - p / glm::length(p)));
    }
    EXPECT_LT(distance, 1e-3);
    EXPECT_LT(normal, 1e-3);
}

TEST(BakeGrid, DisplacementBeyondTheBoundWarnsAndMissingShaderFails) {
    sss::test::TempDir dir;
    sss::test::write_text(dir.file("grow.sl"), kGrow);
    const std::string path = dir.file("g.ptc");
    const std::string bake =
        "Surface \"bake_constant\" \"string filename\" [\"" + path + "\"]\n";
    sss::BakeOptions opt;
    opt.spacing = 0.1;
    sss::BakeReport report;
    sss::bake_clouds(scene_in(dir, "Attribute \"displacementbound\" \"sphere\" [0.05]\n"
                                   "Displacement \"grow\"\n" +
                                       bake + "Sphere 1 -1 1 360\n"),
                     opt, &report);
    bool warned = false;
    for (const std::string& w : report.warnings)
        warned = warned || w.find("displacementbound") != std::string::npos;
    EXPECT_TRUE(warned);
    EXPECT_THROW(sss::bake_clouds(scene_in(dir, "Displacement \"nosuchshader\"\n" + bake +
                                                    "Sphere 1 -1 1 360\n"),
                                  opt, nullptr),
                 sss::ShaderNotFoundError);
}

TEST(BakeGrid, DisplacedPatchesAndPolygonsStayWatertight) {
    // A bilinear patch mesh, a polygon quad and a subdivision cube displaced
    // by a pointwise shader: triangles share their displaced vertices.
    sss::test::TempDir dir;
    sss::test::write_text(dir.file("grow.sl"), kGrow);
    const std::string path = dir.file("g.ptc");
    sss::BakeOptions opt;
    opt.spacing = 0.05;
    sss::BakeReport report;
    const auto files = sss::bake_clouds(
        scene_in(
            dir,
            "Attribute \"displacementbound\" \"sphere\" [0.1]\n"
            "Displacement \"grow\" \"float amount\" [0.05]\n"
            "Surface \"bake_constant\" \"string filename\" [\"" +
                path +
                "\"]\n"
                "Torus 1 0.3 0 360 360\n"
                "Polygon \"P\" [-1 -1 2  1 -1 2  1 1 2  -1 1 2]\n"
                "SubdivisionMesh \"catmull-clark\" [4 4 4 4 4 4]\n"
                "  [0 1 3 2 2 3 5 4 4 5 7 6 6 7 1 0 1 7 5 3 6 0 2 4] "
                "[\"interpolateboundary\"] [0 0] [] []\n"
                "  \"P\" [-0.5 -0.5 0.5 0.5 -0.5 0.5 -0.5 0.5 0.5 0.5 0.5 0.5\n"
                "        -0.5 0.5 -0.5 0.5 0.5 -0.5 -0.5 -0.5 -0.5 0.5 -0.5 -0.5]\n"),
        opt, &report);
    ASSERT_EQ(files.size(), 1u);
    EXPECT_GT(files[0].second.size(), 1000u);
}
