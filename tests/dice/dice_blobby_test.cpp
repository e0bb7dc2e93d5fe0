// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file dice_blobby_test.cpp
/// Tests of Blobby (blobby.h, dice_blobby.cpp): a lone ellipsoid is the
/// sphere at the analytic iso-radius, closed, of area 4 pi r^2; segments
/// are capsules; add merges blobs that max keeps apart; subtract carves,
/// min intersects, constants shift the level; per-leaf primitive variables
/// blend by the leaves' fields; Orientation turns the normals; bad programs
/// are errors naming the statement, and the opcodes not implemented are
/// errors (-lenient: warnings).
///
/// Suite names all start with "DiceBlobby".

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <memory>
#include <numbers>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "../../src/sss/dice/dice_common.h"
#include "sss/dice/dice.h"
#include "sss/scene/blobby.h"
#include "sss/scene/rib.h"
#include "sss/scene/scene.h"
#include "sss/util/error.h"
#include "sss/util/limits.h"

namespace {

using glm::dvec3;

sss::Scene scene_of(const std::string& body, bool lenient = false) {
    sss::RibReadOptions options;
    options.lenient = lenient;
    return sss::parse_rib("Format 320 240 1\n"
                          "Projection \"perspective\" \"fov\" 40\n"
                          "Translate 0 0 6\n"
                          "WorldBegin\n" +
                              body + "\nWorldEnd\n",
                          "blobby.rib", options);
}

sss::DiceControl control(double spacing = 0.01) {
    sss::DiceControl c;
    c.spacing = spacing;
    return c;
}

/// The 16 floats of a uniform scale by r about (x, y, z), RIB layout.
std::string sphere_matrix(double r, double x = 0.0, double y = 0.0, double z = 0.0) {
    return std::to_string(r) + " 0 0 0 0 " + std::to_string(r) + " 0 0 0 0 " +
           std::to_string(r) + " 0 " + std::to_string(x) + " " + std::to_string(y) + " " +
           std::to_string(z) + " 1 ";
}

/// The radius where a lone blob of support radius R has the field `level`.
double iso_radius(double R, double level = sss::kBlobbyThreshold) {
    return R * std::sqrt(1.0 - std::cbrt(level));
}

/// The soft-object field of a sphere of support radius R about c.
double blob(const dvec3& p, const dvec3& c, double R) {
    const double r2 = glm::dot(p - c, p - c) / (R * R);
    return r2 < 1.0 ? std::pow(1.0 - r2, 3) : 0.0;
}

struct Mesh {
    std::vector<dvec3> P, N;
    std::vector<int> verts;
};

Mesh mesh_of(const sss::Primitive& prim, double spacing = 0.01) {
    const sss::Primitive m = sss::detail::blobby_mesh(prim, control(spacing));
    Mesh out;
    const sss::Param* P = m.params.find("P");
    const sss::Param* N = m.params.find("N");
    if (!P) return out;
    for (std::size_t k = 0; k + 2 < P->numbers.size(); k += 3) {
        out.P.emplace_back(P->numbers[k], P->numbers[k + 1], P->numbers[k + 2]);
        out.N.emplace_back(N->numbers[k], N->numbers[k + 1], N->numbers[k + 2]);
    }
    out.verts = m.verts;
    for (int n : m.nverts) EXPECT_EQ(n, 4);
    return out;
}

/// Whether every edge of the quads is met once each way: closed and
/// consistently oriented.
bool closed(const Mesh& m) {
    std::map<std::pair<int, int>, int> edges;
    for (std::size_t q = 0; q + 3 < m.verts.size(); q += 4)
        for (int k = 0; k < 4; ++k) ++edges[{m.verts[q + k], m.verts[q + (k + 1) % 4]}];
    for (const auto& [e, n] : edges) {
        const auto back = edges.find({e.second, e.first});
        if (back == edges.end() || back->second != n) return false;
    }
    return !edges.empty();
}

/// Connected pieces of the quad mesh.
int components(const Mesh& m) {
    std::vector<int> parent(m.P.size());
    std::iota(parent.begin(), parent.end(), 0);
    const auto root = [&](int a) {
        while (parent[a] != a) a = parent[a] = parent[parent[a]];
        return a;
    };
    for (std::size_t q = 0; q + 3 < m.verts.size(); q += 4)
        for (int k = 1; k < 4; ++k) parent[root(m.verts[q + k])] = root(m.verts[q]);
    int n = 0;
    for (std::size_t v = 0; v < parent.size(); ++v)
        n += root(static_cast<int>(v)) == int(v);
    return n;
}

double total_area(const sss::DicedSurface& d) {
    double a = 0.0;
    for (float x : d.areas) a += x;
    return a;
}

std::string error_of(const std::string& body, bool lenient = false) {
    try {
        const sss::Scene scene = scene_of(body, lenient);
        for (const sss::Primitive& p : scene.primitives)
            (void)sss::dice_primitive(p, control());
    } catch (const sss::Error& e) {
        return e.what();
    }
    return "no error";
}

TEST(DiceBlobby, ALoneEllipsoidIsTheSphereOfTheIsoRadius) {
    const double R = 2.0, r = iso_radius(R);
    const sss::Scene scene =
        scene_of("Blobby 1 [1001 0] [" + sphere_matrix(R) + "] [\"\"]");
    const sss::Primitive& prim = scene.primitives.at(0);
    EXPECT_EQ(prim.kind, sss::PrimitiveKind::Blobby);
    const Mesh m = mesh_of(prim);
    ASSERT_GT(m.P.size(), 1000u);
    EXPECT_TRUE(closed(m));
    EXPECT_EQ(components(m), 1);
    for (std::size_t v = 0; v < m.P.size(); ++v) {
        ASSERT_NEAR(glm::length(m.P[v]), r, 1e-9 * r);
        ASSERT_GT(glm::dot(m.N[v], glm::normalize(m.P[v])), 1.0 - 1e-9);
    }
    // Quads wind anticlockwise seen from outside.
    for (std::size_t q = 0; q < m.verts.size(); q += 4) {
        const dvec3 a = m.P[m.verts[q]], b = m.P[m.verts[q + 1]], c = m.P[m.verts[q + 2]],
                    d = m.P[m.verts[q + 3]];
        ASSERT_GT(glm::dot(glm::cross(c - a, d - b), a + b + c + d), 0.0);
    }
    const sss::DicedSurface d = sss::dice_primitive(prim, control());
    const double sphere = 4.0 * std::numbers::pi * r * r;
    EXPECT_NEAR(total_area(d), sphere, 0.005 * sphere);
    for (std::size_t k = 0; k < d.size(); ++k)
        ASSERT_GT(
            glm::dot(glm::dvec3(d.normals[k]), glm::normalize(glm::dvec3(d.centers[k]))),
            0.99);
    // The estimate is within a factor of about two of what dicing makes.
    const sss::DiceEstimate e = sss::estimate_primitive(prim, control());
    EXPECT_GT(e.micropolygons, 0.9 * static_cast<double>(d.size()));
    EXPECT_LT(e.micropolygons, 4.0 * static_cast<double>(d.size()));
}

TEST(DiceBlobby, AnEllipsoidFollowsItsMatrixAndTheTransform) {
    // Axes 1, 2, 3 about (1, 0, 0), under a world scale of 2 and a shift.
    const sss::Scene scene =
        scene_of("Translate 0 1 0 Scale 2 2 2\n"
                 "Blobby 1 [1001 0] [1 0 0 0 0 2 0 0 0 0 3 0 1 0 0 1] [\"\"]");
    const sss::Primitive& prim = scene.primitives.at(0);
    const Mesh m = mesh_of(prim, 0.02);
    ASSERT_FALSE(m.P.empty());
    const double r = iso_radius(1.0);
    for (const dvec3& p : m.P) {
        const dvec3 q((p.x - 1.0) / 1.0, p.y / 2.0, p.z / 3.0);
        ASSERT_NEAR(glm::length(q), r, 1e-8);
    }
    const sss::DicedSurface d = sss::dice_primitive(prim, control(0.02));
    double top = -1e9;
    for (const glm::vec3& c : d.centers) top = std::max(top, double(c.y));
    EXPECT_NEAR(top, 1.0 + 2.0 * 2.0 * r, 0.01);
}

TEST(DiceBlobby, ABlobSmallerThanAMicropolygonStillShows) {
    // Radius 0.009 at micropolygons of 0.05: still a closed little sphere.
    const sss::Scene scene =
        scene_of("Blobby 1 [1001 0] [" + sphere_matrix(0.02) + "] [\"\"]");
    const Mesh m = mesh_of(scene.primitives.at(0), 0.05);
    EXPECT_TRUE(closed(m));
    ASSERT_GE(m.P.size(), 6u);
    for (const dvec3& p : m.P) ASSERT_NEAR(glm::length(p), iso_radius(0.02), 1e-12);
    const std::size_t made =
        sss::dice_primitive(scene.primitives.at(0), control(0.05)).size();
    EXPECT_GT(made, 0u);
    // Each quad is a micropolygon at least: the estimate counts them.
    const sss::DiceEstimate e =
        sss::estimate_primitive(scene.primitives.at(0), control(0.05));
    EXPECT_GT(e.micropolygons, 0.9 * static_cast<double>(made));
    EXPECT_LT(e.micropolygons, 4.0 * static_cast<double>(made));
}

TEST(DiceBlobby, ASegmentIsACapsule) {
    const sss::Scene scene =
        scene_of("Blobby 1 [1002 0] [-1 0 0 1 0 0 1 " + sphere_matrix(1.0) + "] [\"\"]");
    const sss::Primitive& prim = scene.primitives.at(0);
    const Mesh m = mesh_of(prim);
    const double r = iso_radius(1.0);
    EXPECT_TRUE(closed(m));
    for (const dvec3& p : m.P) {
        const double t = std::clamp(p.x, -1.0, 1.0);
        ASSERT_NEAR(glm::length(p - dvec3(t, 0, 0)), r, 1e-9);
    }
    const double capsule =
        2.0 * std::numbers::pi * r * 2.0 + 4.0 * std::numbers::pi * r * r;
    EXPECT_NEAR(total_area(sss::dice_primitive(prim, control())), capsule,
                0.005 * capsule);
}

TEST(DiceBlobby, AddMergesTheBlobsThatMaxKeepsApart) {
    // Two blobs 1.2 apart: alone each reaches 0.454, but their fields add
    // to 2 (1 - 0.36)^3 = 0.524 > 0.5 between them.
    const std::string blobs =
        "[" + sphere_matrix(1.0, -0.6) + sphere_matrix(1.0, 0.6) + "]";
    const Mesh added =
        mesh_of(scene_of("Blobby 2 [1001 0 1001 16 0 2 0 1] " + blobs + " [\"\"]")
                    .primitives.at(0));
    EXPECT_TRUE(closed(added));
    EXPECT_EQ(components(added), 1);
    const Mesh maxed =
        mesh_of(scene_of("Blobby 2 [1001 0 1001 16 2 2 0 1] " + blobs + " [\"\"]")
                    .primitives.at(0));
    EXPECT_TRUE(closed(maxed));
    EXPECT_EQ(components(maxed), 2);
    const dvec3 a(-0.6, 0, 0), b(0.6, 0, 0);
    for (const dvec3& p : added.P) ASSERT_NEAR(blob(p, a, 1) + blob(p, b, 1), 0.5, 1e-9);
    for (const dvec3& p : maxed.P)
        ASSERT_NEAR(std::max(blob(p, a, 1), blob(p, b, 1)), 0.5, 1e-9);
}

TEST(DiceBlobby, ManyBlobsAddAndMaxLikeTwo) {
    // Ten blobs a unit apart in a row: added, one sausage; their max, ten
    // spheres. (Operators of many operands take a sparse path.)
    std::string floats = "[", leaves, items;
    for (int b = 0; b < 10; ++b) {
        floats += sphere_matrix(1.0, b - 4.5);
        leaves += "1001 " + std::to_string(16 * b) + " ";
        items += std::to_string(b) + " ";
    }
    floats += "]";
    const auto field = [](const dvec3& p, bool add) {
        double f = 0.0;
        for (int b = 0; b < 10; ++b) {
            const double v = blob(p, dvec3(b - 4.5, 0, 0), 1.0);
            f = add ? f + v : std::max(f, v);
        }
        return f;
    };
    for (const bool add : {true, false}) {
        const Mesh m = mesh_of(scene_of("Blobby 10 [" + leaves + (add ? "0" : "2") +
                                        " 10 " + items + "] " + floats + " [\"\"]")
                                   .primitives.at(0),
                               0.02);
        EXPECT_TRUE(closed(m));
        EXPECT_EQ(components(m), add ? 1 : 10);
        for (const dvec3& p : m.P) ASSERT_NEAR(field(p, add), 0.5, 1e-9);
    }
}

TEST(DiceBlobby, SubtractCarvesMinIntersectsAndConstantsShiftTheLevel) {
    const dvec3 big(0.0), small(0.9, 0, 0);
    const std::string floats =
        "[" + sphere_matrix(2.0) + sphere_matrix(1.0, 0.9) + "0.2]";
    // Big minus small: a bite out of the right side.
    const Mesh carved =
        mesh_of(scene_of("Blobby 2 [1001 0 1001 16 4 0 1] " + floats + " [\"\"]")
                    .primitives.at(0));
    EXPECT_TRUE(closed(carved));
    double right = -1e9;
    for (const dvec3& p : carved.P) {
        ASSERT_NEAR(blob(p, big, 2) - blob(p, small, 1), 0.5, 1e-9);
        right = std::max(right, p.x);
    }
    EXPECT_LT(right, iso_radius(2.0) - 0.1);
    // The lens where both are above the level.
    const Mesh lens =
        mesh_of(scene_of("Blobby 2 [1001 0 1001 16 3 2 0 1] " + floats + " [\"\"]")
                    .primitives.at(0));
    EXPECT_TRUE(closed(lens));
    for (const dvec3& p : lens.P) {
        ASSERT_NEAR(std::min(blob(p, big, 2), blob(p, small, 1)), 0.5, 1e-9);
        ASSERT_LE(glm::length(p - small), iso_radius(1.0) + 1e-9);
    }
    // A constant 0.2 added: the surface is where the blob is 0.3.
    const Mesh raised =
        mesh_of(scene_of("Blobby 2 [1001 16 1000 32 0 2 0 1] " + floats + " [\"\"]")
                    .primitives.at(0));
    for (const dvec3& p : raised.P)
        ASSERT_NEAR(glm::length(p - small), iso_radius(1, 0.3), 1e-9);
    // Negate and identity, and x / 0 = 0: no surface, no NaN.
    const Mesh negated = mesh_of(
        scene_of("Blobby 1 [1001 16 6 0 7 1] " + floats + " [\"\"]").primitives.at(0));
    EXPECT_TRUE(negated.P.empty());
    EXPECT_EQ(sss::dice_primitive(scene_of("Blobby 2 [1001 0 1000 16 5 0 1] [" +
                                           sphere_matrix(1.0) + "0] [\"\"]")
                                      .primitives.at(0),
                                  control())
                  .size(),
              0u);
}

TEST(DiceBlobby, PerLeafValuesBlendByTheLeavesFields) {
    const std::string blobs =
        "[" + sphere_matrix(1.0, -0.6) + sphere_matrix(1.0, 0.6) + "]";
    const sss::Scene scene =
        scene_of("Blobby 2 [1001 0 1001 16 0 2 0 1] " + blobs +
                 " [\"\"] \"vertex color Cs\" [1 0 0 0 0 1] \"constant float Ks\" [0.5]");
    const sss::Primitive& prim = scene.primitives.at(0);
    const sss::Primitive m = sss::detail::blobby_mesh(prim, control());
    const sss::Param* cs = m.params.find("Cs");
    const sss::Param* P = m.params.find("P");
    ASSERT_TRUE(cs && P);
    EXPECT_EQ(cs->storage, sss::ParamClass::Vertex);
    EXPECT_EQ(m.params.find("Ks")->storage, sss::ParamClass::Constant);
    for (std::size_t v = 0; v * 3 < P->numbers.size(); ++v) {
        const dvec3 p(P->numbers[3 * v], P->numbers[3 * v + 1], P->numbers[3 * v + 2]);
        const double wa = blob(p, dvec3(-0.6, 0, 0), 1),
                     wb = blob(p, dvec3(0.6, 0, 0), 1);
        ASSERT_NEAR(cs->numbers[3 * v], wa / (wa + wb), 1e-9);
        ASSERT_NEAR(cs->numbers[3 * v + 2], wb / (wa + wb), 1e-9);
        ASSERT_EQ(cs->numbers[3 * v + 1], 0.0);
    }
    // Diced, the far ends are the leaves' own colours, the neck their mean.
    const sss::DicedSurface d = sss::dice_primitive(prim, control());
    ASSERT_EQ(d.colors.size(), d.size());
    for (std::size_t k = 0; k < d.size(); ++k) {
        if (d.centers[k].x < -0.95) {
            ASSERT_GT(d.colors[k].x, 0.95f);
        }
        if (std::abs(d.centers[k].x) < 0.005) {
            ASSERT_NEAR(d.colors[k].x, 0.5f, 0.03f);
        }
    }
}

TEST(DiceBlobby, OrientationInsideTurnsTheNormalsIn) {
    const sss::Scene scene = scene_of("ReverseOrientation Blobby 1 [1001 0] [" +
                                      sphere_matrix(1.0) + "] [\"\"]");
    const sss::Primitive& prim = scene.primitives.at(0);
    const sss::DicedSurface d = sss::dice_primitive(prim, control());
    ASSERT_GT(d.size(), 100u);
    for (std::size_t k = 0; k < d.size(); ++k)
        ASSERT_LT(
            glm::dot(glm::dvec3(d.normals[k]), glm::normalize(glm::dvec3(d.centers[k]))),
            -0.99);
}

TEST(DiceBlobby, TheMicropolygonBudgetBoundsTheGrid) {
    const sss::Scene scene =
        scene_of("Blobby 1 [1001 0] [" + sphere_matrix(1.0) + "] [\"\"]");
    sss::DiceControl c = control(0.0005);
    c.max_micropolygons = 1000;
    EXPECT_THROW((void)sss::dice_primitive(scene.primitives.at(0), c), sss::LimitError);
    c.max_micropolygons = 100000000;
    c.spacing = 0.05;
    EXPECT_GT(sss::dice_primitive(scene.primitives.at(0), c).size(), 100u);
}

TEST(DiceBlobby, BadProgramsAreErrorsNamingTheStatement) {
    const std::string m = "[" + sphere_matrix(1.0) + "]";
    const auto expect = [](const std::string& error, const std::string& part) {
        EXPECT_NE(error.find(part), std::string::npos) << error;
        EXPECT_NE(error.find("blobby.rib:5: Blobby"), std::string::npos) << error;
    };
    expect(error_of("Blobby 1 [1001 4] " + m + " [\"\"]"),
           "needs 16 floats from index 4");
    expect(error_of("Blobby 2 [1001 0 0 2 0 1] " + m + " [\"\"]"),
           "operand 1 is not an earlier item");
    expect(error_of("Blobby 2 [1001 0] " + m + " [\"\"]"),
           "nleaf is 2 but the code has 1");
    expect(error_of("Blobby 1 [1001 0 0 0] " + m + " [\"\"]"), "at least one operand");
    expect(error_of("Blobby 1 [1001] " + m + " [\"\"]"), "cut short");
    expect(error_of("Blobby 1 [1001 0] [1 0 0 0 0 0 0 0 0 0 1 0 0 0 0 1] [\"\"]"),
           "singular");
    expect(error_of("Blobby 1 [1002 0] [0 0 0 1 0 0 0 " + sphere_matrix(1) + "] [\"\"]"),
           "radius must be > 0");
    expect(error_of("Blobby 1 [1000 0] [0.7] [\"\"]"), "not bounded");
    // A blob that the dicing rate resolves, too small for the span of the
    // others: no grid within the limits resolves it. (A speck below the
    // dicing rate may vanish: it would not show.)
    expect(error_of("Blobby 2 [1001 0 1001 16 0 2 0 1] [" + sphere_matrix(0.05) +
                    sphere_matrix(1.0, 100.0) + "] [\"\"]"),
           "grid cells");
    EXPECT_EQ(error_of("Blobby 2 [1001 0 1001 16 0 2 0 1] [" + sphere_matrix(1e-4) +
                       sphere_matrix(1.0, 100.0) + "] [\"\"]"),
              "no error");
    // Overflow: blob x 1e300 x 1e300 is infinite inside the blob.
    expect(error_of("Blobby 3 [1001 0 1000 16 1000 16 1 3 0 1 2] [" + sphere_matrix(1.0) +
                    "1e300] [\"\"]"),
           "not a finite number");
    expect(error_of("Blobby 1 [1001 0] " + m + " [\"\"] \"P\" [0 0 0]"),
           "takes no \"P\"");
    expect(error_of("Blobby 2 [1001 0 1001 0 0 2 0 1] " + m + " [\"\"] \"Cs\" [1 0 0]"),
           "\"Cs\"");
    // Not implemented: errors, and with -lenient warnings.
    expect(error_of("Blobby 1 [1001 0 8 0] " + m + " [\"\"]"), "unknown opcode 8");
    // A ground plane needs its depth map, which the dicer reads only through
    // DiceControl::depth_maps (the renderers' texture library).
    expect(error_of("Blobby 2 [1001 0 1003 0 16 0 2 0 1] [" + sphere_matrix(1) +
                    "0 1 1 1] [\"ground.z\"]"),
           "which only ptbake and render read");
    expect(error_of("Blobby 1 [1001 0] " + m + " [\"\"] \"N\" [0 0 1]"), "\"N\"");
    const sss::Scene lenient =
        scene_of("Blobby 2 [1001 0 1004 0 0 0 0 0 0 2 0 1] [" + sphere_matrix(1) +
                     "] [\"field.so\"]\n"
                     "Blobby 1 [1001 0 8 0] " +
                     m + " [\"\"]",
                 true);
    ASSERT_EQ(lenient.primitives.size(), 1u);
    EXPECT_EQ(lenient.warnings.size(), 2u);
    // The plugin's field is 0: the lone blob remains.
    const Mesh left = mesh_of(lenient.primitives[0]);
    ASSERT_FALSE(left.P.empty());
    for (const dvec3& p : left.P) ASSERT_NEAR(glm::length(p), iso_radius(1.0), 1e-9);
}

TEST(DiceBlobby, AGroundPlaneKeepsTheBlobInFrontOfItsDepthMap) {
    // A wall at z = 1 seen along +z by an orthographic map over x, y in
    // [-2, 2]; a blob (iso radius 0.45) centred at z = 0.7 reaches z = 1.15.
    auto wall = std::make_shared<sss::DepthGrid>();
    wall->width = wall->height = 8;
    wall->depth.assign(64, 1.0f);
    wall->world_to_screen = glm::scale(sss::Matrix4(1.0), glm::dvec3(0.5, 0.5, 1.0));
    sss::DiceControl c = control(0.02);
    std::vector<std::string> asked;
    c.depth_maps = [&](const std::string& name) {
        asked.push_back(name);
        return std::shared_ptr<const sss::DepthGrid>(wall);
    };
    const std::string ball = sphere_matrix(1.0, 0.0, 0.0, 0.7);
    const sss::Scene alone = scene_of("Blobby 1 [1001 0] [" + ball + "] [\"\"]");
    const sss::Scene repelled = scene_of("Blobby 2 [1001 0 1003 0 16 0 2 0 1] [" + ball +
                                         "0.3 0.01 0.1 0.05] [\"wall.z\"]");
    const auto zmax = [&](const sss::Primitive& prim) {
        const sss::Primitive m = sss::detail::blobby_mesh(prim, c);
        const sss::Param* P = m.params.find("P");
        double z = -1e9;
        for (std::size_t k = 2; P && k < P->numbers.size(); k += 3)
            z = std::max(z, P->numbers[k]);
        return z;
    };
    EXPECT_NEAR(zmax(alone.primitives.at(0)), 0.7 + iso_radius(1.0), 0.03);
    const double z = zmax(repelled.primitives.at(0));
    EXPECT_LT(z, 1.0);
    EXPECT_GT(z, 0.85);
    EXPECT_EQ(asked, (std::vector<std::string>{"wall.z"}));
    // Beyond the map (the blob moved to x = 5) nothing repels.
    const sss::Scene off =
        scene_of("Blobby 2 [1001 0 1003 0 16 0 2 0 1] [" +
                 sphere_matrix(1.0, 5.0, 0.0, 0.7) + "0.3 0.01 0.1 0.05] [\"wall.z\"]");
    EXPECT_NEAR(zmax(off.primitives.at(0)), 0.7 + iso_radius(1.0), 0.03);
}

} // namespace
