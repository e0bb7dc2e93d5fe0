// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file dice_mesh_test.cpp
/// Tests of the dicing of polygons and Catmull–Clark subdivision meshes
/// (sss/dice.h, src/sss/dice_mesh.cpp): exact areas, normal orientation,
/// triangulation of concave polygons and holes, primitive variables, the
/// subdivision rules and tags, and validation errors.
///
/// Suite names all start with "DiceMesh".

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "sss/dice/dice.h"
#include "sss/scene/scene.h"
#include "sss/util/error.h"

namespace {

using glm::dvec3;

constexpr const char* kSource = "mesh_test.rib:42";

sss::Param make_param(const std::string& name, std::vector<double> numbers,
                      sss::ParamType type = sss::ParamType::Point,
                      sss::ParamClass storage = sss::ParamClass::Vertex) {
    sss::Param p;
    p.name = name;
    p.type = type;
    p.storage = storage;
    p.numbers = std::move(numbers);
    return p;
}

std::vector<double> flatten(const std::vector<dvec3>& points) {
    std::vector<double> out;
    for (const dvec3& p : points) out.insert(out.end(), {p.x, p.y, p.z});
    return out;
}

sss::Primitive make_prim(sss::PrimitiveKind kind, const std::vector<dvec3>& points,
                         bool inside = false) {
    sss::Primitive prim;
    prim.kind = kind;
    prim.params.items.push_back(make_param("P", flatten(points)));
    auto attr = std::make_shared<sss::Attributes>();
    attr->orientation_inside = inside;
    prim.attributes = attr;
    prim.source = kSource;
    return prim;
}

sss::DiceControl spacing(double s) {
    sss::DiceControl c;
    c.spacing = s;
    return c;
}

double total_area(const sss::DicedSurface& s) {
    double a = 0.0;
    for (float x : s.areas) a += x;
    return a;
}

/// Every array has the documented size and no value is NaN or infinite.
void expect_well_formed(const sss::DicedSurface& s) {
    const std::size_t n = s.size();
    ASSERT_EQ(s.normals.size(), n);
    ASSERT_EQ(s.areas.size(), n);
    ASSERT_EQ(s.radii.size(), n);
    ASSERT_TRUE(s.colors.empty() || s.colors.size() == n);
    ASSERT_EQ(s.vertex_normals.size(), s.vertices.size());
    ASSERT_EQ(s.triangles.size() % 3, 0u);
    for (uint32_t t : s.triangles) ASSERT_LT(t, s.vertices.size());
    auto finite = [](const glm::vec3& v) {
        return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
    };
    for (std::size_t i = 0; i < n; ++i) {
        ASSERT_TRUE(finite(s.centers[i]));
        ASSERT_NEAR(glm::length(s.normals[i]), 1.0f, 1e-4f);
        ASSERT_TRUE(std::isfinite(s.areas[i]) && s.areas[i] >= 0.0f);
        ASSERT_TRUE(std::isfinite(s.radii[i]) && s.radii[i] >= 0.0f);
    }
    for (std::size_t i = 0; i < s.vertices.size(); ++i) {
        ASSERT_TRUE(finite(s.vertices[i]));
        ASSERT_TRUE(finite(s.vertex_normals[i]));
    }
}

// The 8 corners of an axis-aligned box (bit 0: +x, bit 1: +y, bit 2: +z) and
// its 6 faces wound counter-clockwise seen from outside.
std::vector<dvec3> box_corners(const dvec3& half) {
    std::vector<dvec3> c;
    for (int i = 0; i < 8; ++i)
        c.emplace_back(i & 1 ? half.x : -half.x, i & 2 ? half.y : -half.y,
                       i & 4 ? half.z : -half.z);
    return c;
}
const std::vector<int> kBoxFaces = {0, 2, 3, 1, 4, 5, 7, 6, 0, 1, 5, 4,
                                    2, 6, 7, 3, 0, 4, 6, 2, 1, 3, 7, 5};

std::vector<sss::Primitive> box_polygons(const dvec3& half, const sss::Matrix4& m,
                                         bool inside = false) {
    const std::vector<dvec3> c = box_corners(half);
    std::vector<sss::Primitive> prims;
    for (int f = 0; f < 6; ++f) {
        std::vector<dvec3> loop;
        for (int k = 0; k < 4; ++k) loop.push_back(c[kBoxFaces[4 * f + k]]);
        sss::Primitive p = make_prim(sss::PrimitiveKind::Polygon, loop, inside);
        p.object_to_world = m;
        prims.push_back(p);
    }
    return prims;
}

sss::Primitive box_points_polygons(const dvec3& half) {
    sss::Primitive p = make_prim(sss::PrimitiveKind::PointsPolygons, box_corners(half));
    p.nverts.assign(6, 4);
    p.verts = kBoxFaces;
    return p;
}

sss::Primitive cube_subdivision() {
    sss::Primitive p =
        make_prim(sss::PrimitiveKind::SubdivisionMesh, box_corners(dvec3(0.5)));
    p.type = "catmull-clark";
    p.nverts.assign(6, 4);
    p.verts = kBoxFaces;
    return p;
}

/// A (nx+1) x (ny+1) vertex grid of quads in the z = f(x) surface, unit spacing.
template <typename Height>
sss::Primitive grid_subdivision(int nx, int ny, Height height) {
    std::vector<dvec3> pts;
    for (int j = 0; j <= ny; ++j)
        for (int i = 0; i <= nx; ++i) pts.emplace_back(i, j, height(double(i)));
    sss::Primitive p = make_prim(sss::PrimitiveKind::SubdivisionMesh, pts);
    p.type = "catmull-clark";
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            const int v = j * (nx + 1) + i;
            p.nverts.push_back(4);
            p.verts.insert(p.verts.end(), {v, v + 1, v + nx + 2, v + nx + 1});
        }
    return p;
}

void add_tag(sss::Primitive& p, const std::string& name, std::vector<int> ints,
             std::vector<double> floats) {
    p.tags.push_back(name);
    p.tag_nargs.push_back(static_cast<int>(ints.size()));
    p.tag_nargs.push_back(static_cast<int>(floats.size()));
    p.tag_intargs.insert(p.tag_intargs.end(), ints.begin(), ints.end());
    p.tag_floatargs.insert(p.tag_floatargs.end(), floats.begin(), floats.end());
}

/// Expects a ValueError whose message names the primitive's source.
template <typename F>
void expect_value_error(F&& f, const std::string& fragment = "") {
    try {
        f();
        ADD_FAILURE() << "no ValueError";
    } catch (const sss::ValueError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find(kSource), std::string::npos) << what;
        if (!fragment.empty()) {
            EXPECT_NE(what.find(fragment), std::string::npos) << what;
        }
    }
}

// ---------------------------------------------------------------------------
// Polygons

void check_box(const std::vector<sss::Primitive>& prims, const dvec3& centre,
               double expected_area, double step) {
    double area = 0.0;
    for (const sss::Primitive& p : prims) {
        const sss::DicedSurface s = sss::dice_primitive(p, spacing(step));
        expect_well_formed(s);
        area += total_area(s);
        for (std::size_t i = 0; i < s.size(); ++i)
            ASSERT_GT(glm::dot(dvec3(s.normals[i]), dvec3(s.centers[i]) - centre), 0.0);
    }
    EXPECT_NEAR(area, expected_area, 1e-5 * expected_area);
}

TEST(DiceMeshPolygon, BoxOfPolygonsHasExactAreaAndOutwardNormals) {
    check_box(box_polygons(dvec3(1.0, 1.5, 2.0), sss::Matrix4(1.0)), dvec3(0.0), 52.0,
              0.1);
}

TEST(DiceMeshPolygon, BoxUnderScaleAndRotate) {
    // Scale (2, 1, 0.5) of a 2x3x4 box is 4x3x2: area 52 again.
    sss::Matrix4 m = glm::translate(sss::Matrix4(1.0), dvec3(3.0, -1.0, 2.0));
    m = glm::rotate(m, 0.7, glm::normalize(dvec3(1.0, 2.0, -0.5)));
    m = glm::scale(m, dvec3(2.0, 1.0, 0.5));
    check_box(box_polygons(dvec3(1.0, 1.5, 2.0), m), dvec3(3.0, -1.0, 2.0), 52.0, 0.1);
}

TEST(DiceMeshPolygon, MirrorTransformKeepsNormalsOutward) {
    const sss::Matrix4 m = glm::scale(sss::Matrix4(1.0), dvec3(-1.0, 2.0, 1.0));
    // 2x3x4 scaled to 2x6x4: area 2 (12 + 8 + 24) = 88.
    check_box(box_polygons(dvec3(1.0, 1.5, 2.0), m), dvec3(0.0), 88.0, 0.2);
}

TEST(DiceMeshPolygon, PointsPolygonsBox) {
    const sss::Primitive p = box_points_polygons(dvec3(1.0, 1.5, 2.0));
    check_box({p}, dvec3(0.0), 52.0, 0.1);
}

TEST(DiceMeshPolygon, OrientationInsideFlipsGeometricNormals) {
    check_box(box_polygons(dvec3(1.0, 1.5, 2.0), sss::Matrix4(1.0)), dvec3(0.0), 52.0,
              0.5);
    const auto prims = box_polygons(dvec3(1.0, 1.5, 2.0), sss::Matrix4(1.0), true);
    for (const sss::Primitive& p : prims) {
        const sss::DicedSurface s = sss::dice_primitive(p, spacing(0.5));
        ASSERT_GT(s.size(), 0u);
        for (std::size_t i = 0; i < s.size(); ++i)
            ASSERT_LT(glm::dot(dvec3(s.normals[i]), dvec3(s.centers[i])), 0.0);
    }
}

TEST(DiceMeshPolygon, ConcaveLShapeHasExactArea) {
    const std::vector<dvec3> l = {{0, 0, 0}, {2, 0, 0}, {2, 1, 0},
                                  {1, 1, 0}, {1, 2, 0}, {0, 2, 0}};
    for (bool reversed : {false, true}) {
        std::vector<dvec3> loop = l;
        if (reversed) std::reverse(loop.begin(), loop.end());
        const sss::DicedSurface s = sss::dice_primitive(
            make_prim(sss::PrimitiveKind::Polygon, loop), spacing(0.05));
        expect_well_formed(s);
        EXPECT_NEAR(total_area(s), 3.0, 3e-6);
        for (std::size_t i = 0; i < s.size(); ++i) {
            const glm::vec3 c = s.centers[i];
            ASSERT_FALSE(c.x > 1.0f && c.y > 1.0f) << "centre in the notch";
            ASSERT_NEAR(std::abs(s.normals[i].z), 1.0f, 1e-6f);
            ASSERT_GT(s.normals[i].z * (reversed ? -1.0f : 1.0f), 0.0f);
        }
    }
}

TEST(DiceMeshPolygon, StarWithManyReflexVerticesHasExactArea) {
    // A 12-pointed star: area = 12 * (triangle O, outer_k, inner_k) * 2.
    std::vector<dvec3> loop;
    const int points = 12;
    const double r_out = 2.0, r_in = 0.7;
    for (int k = 0; k < 2 * points; ++k) {
        const double a = std::numbers::pi * k / points;
        const double r = k % 2 ? r_in : r_out;
        loop.emplace_back(r * std::cos(a), 0.3, r * std::sin(a)); // in the xz plane
    }
    const double expected =
        2 * points * 0.5 * r_out * r_in * std::sin(std::numbers::pi / points);
    const sss::DicedSurface s =
        sss::dice_primitive(make_prim(sss::PrimitiveKind::Polygon, loop), spacing(0.05));
    expect_well_formed(s);
    EXPECT_NEAR(total_area(s), expected, 1e-5 * expected);
}

TEST(DiceMeshPolygon, CollinearAndDuplicateVerticesAreTolerated) {
    // A 2x1 rectangle with a repeated corner and points along its edges.
    const std::vector<dvec3> loop = {{0, 0, 0},   {1, 0, 0}, {2, 0, 0},
                                     {2, 0, 0},   {2, 1, 0}, {1, 1, 0},
                                     {0.5, 1, 0}, {0, 1, 0}, {0, 0.5, 0}};
    const sss::DicedSurface s =
        sss::dice_primitive(make_prim(sss::PrimitiveKind::Polygon, loop), spacing(0.1));
    expect_well_formed(s);
    EXPECT_NEAR(total_area(s), 2.0, 2e-6);
    // A polygon with no area at all dices to nothing (and no NaN).
    const sss::DicedSurface flat = sss::dice_primitive(
        make_prim(sss::PrimitiveKind::Polygon, {{0, 0, 0}, {1, 1, 1}, {2, 2, 2}}),
        spacing(0.1));
    EXPECT_EQ(flat.size(), 0u);
}

TEST(DiceMeshPolygon, GeneralPolygonWithHoles) {
    // 4x4 square, a 2x2 hole in the same winding and a 0.5x0.5 one reversed.
    const std::vector<dvec3> pts = {
        {0, 0, 0}, {4, 0, 0}, {4, 4, 0},     {0, 4, 0},     {1, 1, 0},     {3, 1, 0},
        {3, 3, 0}, {1, 3, 0}, {3.2, 3.2, 0}, {3.2, 3.7, 0}, {3.7, 3.7, 0}, {3.7, 3.2, 0}};
    sss::Primitive p = make_prim(sss::PrimitiveKind::GeneralPolygon, pts);
    p.nverts = {4, 4, 4};
    const sss::DicedSurface s = sss::dice_primitive(p, spacing(0.1));
    expect_well_formed(s);
    EXPECT_NEAR(total_area(s), 16.0 - 4.0 - 0.25, 1e-5 * 12.0);
    for (std::size_t i = 0; i < s.size(); ++i) {
        const glm::vec3 c = s.centers[i];
        ASSERT_FALSE(c.x > 1.0f && c.x < 3.0f && c.y > 1.0f && c.y < 3.0f);
        ASSERT_FALSE(c.x > 3.2f && c.x < 3.7f && c.y > 3.2f && c.y < 3.7f);
        ASSERT_GT(s.normals[i].z, 0.99f);
    }
}

TEST(DiceMeshPolygon, PointsGeneralPolygonsWithHoleAndSharedPoints) {
    // Two faces sharing an edge: a square with a triangular hole, and a plain square.
    const std::vector<dvec3> pts = {{0, 0, 0},     {2, 0, 0},     {2, 2, 0},
                                    {0, 2, 0},     {4, 0, 0},     {4, 2, 0},
                                    {0.5, 0.5, 0}, {1.5, 0.5, 0}, {1, 1.5, 0}};
    sss::Primitive p = make_prim(sss::PrimitiveKind::PointsGeneralPolygons, pts);
    p.nloops = {2, 1};
    p.nverts = {4, 3, 4};
    p.verts = {0, 1, 2, 3, 6, 8, 7, 1, 4, 5, 2};
    const sss::DicedSurface s = sss::dice_primitive(p, spacing(0.1));
    expect_well_formed(s);
    EXPECT_NEAR(total_area(s), 8.0 - 0.5, 1e-5 * 7.5);
    for (std::size_t i = 0; i < s.size(); ++i) {
        const glm::vec3 c = s.centers[i];
        // Inside the hole triangle (0.5,0.5) (1.5,0.5) (1,1.5), with a margin.
        const bool in_hole =
            c.y > 0.51f && c.y < 1.49f && std::abs(c.x - 1.0f) < 0.49f * (1.5f - c.y);
        ASSERT_FALSE(in_hole) << c.x << " " << c.y;
    }
}

TEST(DiceMeshPolygon, MicropolygonCountFollowsSpacing) {
    // A convex quad dices like a REYES grid; triangles into similar pieces.
    const std::vector<std::pair<std::vector<dvec3>, double>> shapes = {
        {{{0, 0, 0}, {3, 0, 0}, {3, 2, 0}, {0, 2, 0}}, 6.0},
        {{{0, 0, 0}, {2, 0, 0}, {1, std::sqrt(3.0), 0}}, std::sqrt(3.0)},
        {{{0, 0, 0}, {2, 0, 0}, {0, 2, 0}}, 2.0}};
    for (const auto& [loop, area] : shapes)
        for (double step : {0.2, 0.05}) {
            const sss::DicedSurface s = sss::dice_primitive(
                make_prim(sss::PrimitiveKind::Polygon, loop), spacing(step));
            EXPECT_NEAR(total_area(s), area, 1e-5 * area);
            const double ratio = double(s.size()) * step * step / area;
            EXPECT_GE(ratio, 1.0) << loop.size() << " corners, spacing " << step;
            // Right triangles are the worst case of similar sub-triangles.
            EXPECT_LE(ratio, loop.size() == 4 || loop[2].x == 1 ? 2.0 : 2.5)
                << loop.size() << " corners, spacing " << step;
            for (float r : s.radii) ASSERT_LE(r, step);
        }
}

TEST(DiceMeshPolygon, SliversAndManySidedPolygonsStayNearTheIdealCount) {
    // A needle 10 long and 0.2 wide, and a 64-sided disk (ear clipping makes
    // long thin triangles): thin triangles are diced in bands along their
    // longest side instead of n x n needles.
    const double step = 0.1;
    std::vector<dvec3> disk;
    for (int k = 0; k < 64; ++k) {
        const double a = 2.0 * std::numbers::pi * k / 64;
        disk.emplace_back(3.0 * std::cos(a), 3.0 * std::sin(a), 0.0);
    }
    const double disk_area = 0.5 * 64 * 9.0 * std::sin(2.0 * std::numbers::pi / 64);
    const std::vector<std::pair<std::vector<dvec3>, double>> shapes = {
        {{{0, 0, 0}, {10, 0, 0}, {5, 0.2, 0}}, 1.0}, {disk, disk_area}};
    for (const auto& [loop, area] : shapes) {
        const sss::DicedSurface s = sss::dice_primitive(
            make_prim(sss::PrimitiveKind::Polygon, loop), spacing(step));
        expect_well_formed(s);
        EXPECT_NEAR(total_area(s), area, 1e-5 * area);
        // Similar pieces of the needle would be 71 x 71 = 5041 (50 per spacing^2).
        const double ratio = double(s.size()) * step * step / area;
        EXPECT_GE(ratio, 1.0);
        EXPECT_LE(ratio, 3.5);
        // A few pieces next to a steep side are stretched; most are compact.
        std::size_t large = 0;
        for (float r : s.radii) {
            ASSERT_LE(r, 2.0 * step);
            if (r > step) ++large;
        }
        EXPECT_LT(large, s.size() / 50);
        for (std::size_t i = 0; i < s.size(); ++i) ASSERT_GT(s.normals[i].z, 0.99f);
    }
}

TEST(DiceMeshPolygon, SharedEdgesAreWatertight) {
    // Two triangles of a unit square, as two faces of one mesh: same piece count.
    sss::Primitive p = make_prim(sss::PrimitiveKind::PointsPolygons,
                                 {{0, 0, 0}, {1, 0, 0}, {1, 1, 0.3}, {0, 1, 0}});
    p.nverts = {3, 3};
    p.verts = {0, 1, 2, 0, 2, 3};
    p.object_to_world = glm::rotate(sss::Matrix4(1.0), 0.3, dvec3(1.0, 1.0, 0.0));
    const sss::DicedSurface s = sss::dice_primitive(p, spacing(0.07));
    // Vertices on the diagonal appear once per triangle, bit-identical.
    std::multiset<std::tuple<float, float, float>> seen;
    for (const glm::vec3& v : s.vertices) seen.insert({v.x, v.y, v.z});
    std::size_t doubled = 0;
    for (const auto& v :
         std::set<std::tuple<float, float, float>>(seen.begin(), seen.end()))
        if (seen.count(v) == 2) ++doubled;
    // n + 1 points on the diagonal, n = ceil(diagonal / 0.07).
    const double diagonal = std::sqrt(2.0 + 0.09);
    EXPECT_EQ(doubled,
              static_cast<std::size_t>(std::ceil(diagonal / (0.07 * std::sqrt(2.0)))) +
                  1);
}

TEST(DiceMeshPolygon, VertexColorsAreInterpolated) {
    // Red = x, green = y at the corners: a linear field is reproduced exactly.
    const std::vector<dvec3> quad = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    sss::Primitive p = make_prim(sss::PrimitiveKind::Polygon, quad);
    p.params.items.push_back(make_param("Cs", {0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1},
                                        sss::ParamType::Color, sss::ParamClass::Varying));
    const sss::DicedSurface s = sss::dice_primitive(p, spacing(0.1));
    ASSERT_EQ(s.colors.size(), s.size());
    for (std::size_t i = 0; i < s.size(); ++i) {
        ASSERT_NEAR(s.colors[i].r, s.centers[i].x, 1e-5f);
        ASSERT_NEAR(s.colors[i].g, s.centers[i].y, 1e-5f);
        ASSERT_NEAR(s.colors[i].b, 1.0f, 1e-6f);
    }
}

TEST(DiceMeshPolygon, UniformAndFaceVaryingColors) {
    sss::Primitive p =
        make_prim(sss::PrimitiveKind::PointsPolygons,
                  {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {2, 0, 0}, {2, 1, 0}});
    p.nverts = {4, 4};
    p.verts = {0, 1, 2, 3, 1, 4, 5, 2};
    sss::Primitive uniform = p;
    uniform.params.items.push_back(make_param(
        "Cs", {1, 0, 0, 0, 0, 1}, sss::ParamType::Color, sss::ParamClass::Uniform));
    sss::DicedSurface s = sss::dice_primitive(uniform, spacing(0.25));
    ASSERT_EQ(s.colors.size(), s.size());
    for (std::size_t i = 0; i < s.size(); ++i)
        ASSERT_EQ(s.colors[i],
                  s.centers[i].x < 1.0f ? glm::vec3(1, 0, 0) : glm::vec3(0, 0, 1));
    // Face-varying: the shared corners get different values in each face.
    sss::Primitive fv = p;
    fv.params.items.push_back(make_param(
        "Cs", {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1},
        sss::ParamType::Color, sss::ParamClass::FaceVarying));
    s = sss::dice_primitive(fv, spacing(0.25));
    for (std::size_t i = 0; i < s.size(); ++i)
        ASSERT_NEAR(s.colors[i].g, s.centers[i].x < 1.0f ? 0.0f : 1.0f, 1e-6f);
}

TEST(DiceMeshPolygon, UserNormalsAreUsedAndNeverFlipped) {
    const std::vector<dvec3> quad = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    for (bool inside : {false, true}) {
        sss::Primitive p = make_prim(sss::PrimitiveKind::Polygon, quad, inside);
        // Tilted from -x at x = 0 to +x at x = 1 (plus z): interpolated, normalised.
        p.params.items.push_back(make_param("N", {-1, 0, 1, 1, 0, 1, 1, 0, 1, -1, 0, 1},
                                            sss::ParamType::Normal,
                                            sss::ParamClass::Varying));
        p.object_to_world = glm::scale(sss::Matrix4(1.0), dvec3(1.0, 1.0, 2.0));
        const sss::DicedSurface s = sss::dice_primitive(p, spacing(0.1));
        ASSERT_GT(s.size(), 0u);
        for (std::size_t i = 0; i < s.size(); ++i) {
            // World normal = inverse transpose: z component halved.
            const double x = 2.0 * s.centers[i].x - 1.0;
            const dvec3 expected = glm::normalize(dvec3(x, 0.0, 0.5));
            ASSERT_NEAR(glm::length(dvec3(s.normals[i]) - expected), 0.0, 1e-5);
        }
    }
}

TEST(DiceMeshPolygon, LargeMeshDicesToExactArea) {
    // 100 x 100 quads on a wavy sheet (non-planar quads become 2 triangles).
    const int n = 100;
    std::vector<dvec3> pts;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i)
            pts.emplace_back(i * 0.1, j * 0.1,
                             0.2 * std::sin(i * 0.3) * std::cos(j * 0.2));
    sss::Primitive p = make_prim(sss::PrimitiveKind::PointsPolygons, pts);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const int v = j * (n + 1) + i;
            p.nverts.push_back(4);
            p.verts.insert(p.verts.end(), {v, v + 1, v + n + 2, v + n + 1});
        }
    const sss::DicedSurface s = sss::dice_primitive(p, spacing(0.03));
    expect_well_formed(s);
    EXPECT_GT(s.size(), 100000u);
    EXPECT_GT(total_area(s), 100.0);
    for (std::size_t i = 0; i < s.size(); ++i) ASSERT_GT(s.normals[i].z, 0.0f);
}

TEST(DiceMeshPolygon, MalformedPolygonsThrowNamingTheSource) {
    const std::vector<dvec3> quad = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    {
        sss::Primitive p = make_prim(sss::PrimitiveKind::Polygon, quad);
        p.params.items.clear();
        expect_value_error([&] { sss::dice_primitive(p, spacing(0.1)); }, "\"P\"");
    }
    {
        sss::Primitive p = make_prim(sss::PrimitiveKind::Polygon, quad);
        p.params.items[0].numbers.pop_back();
        expect_value_error([&] { sss::dice_primitive(p, spacing(0.1)); });
    }
    {
        sss::Primitive p = make_prim(sss::PrimitiveKind::Polygon, {{0, 0, 0}, {1, 0, 0}});
        expect_value_error([&] { sss::dice_primitive(p, spacing(0.1)); });
    }
    {
        sss::Primitive p = make_prim(sss::PrimitiveKind::Polygon, quad);
        p.params.items[0].numbers[4] = std::numeric_limits<double>::quiet_NaN();
        expect_value_error([&] { sss::dice_primitive(p, spacing(0.1)); }, "finite");
    }
    {
        sss::Primitive p = make_prim(sss::PrimitiveKind::PointsPolygons, quad);
        p.nverts = {4};
        p.verts = {0, 1, 2, 4};
        expect_value_error([&] { sss::dice_primitive(p, spacing(0.1)); }, "out of range");
        p.verts = {0, 1, 2};
        expect_value_error([&] { sss::dice_primitive(p, spacing(0.1)); });
        p.nverts = {2, 2};
        p.verts = {0, 1, 2, 3};
        expect_value_error([&] { sss::dice_primitive(p, spacing(0.1)); }, "at least 3");
    }
    {
        sss::Primitive p = make_prim(sss::PrimitiveKind::GeneralPolygon, quad);
        p.nverts = {3};
        expect_value_error([&] { sss::dice_primitive(p, spacing(0.1)); });
    }
    {
        sss::Primitive p = make_prim(sss::PrimitiveKind::Polygon, quad);
        p.params.items.push_back(make_param(
            "Cs", {1, 0, 0, 0, 1, 0}, sss::ParamType::Color, sss::ParamClass::Varying));
        expect_value_error([&] { sss::dice_primitive(p, spacing(0.1)); }, "\"Cs\"");
    }
    {
        sss::Primitive p = make_prim(sss::PrimitiveKind::Polygon, quad);
        sss::DiceControl c = spacing(0.001);
        c.max_micropolygons = 1000;
        EXPECT_THROW(sss::dice_primitive(p, c), sss::LimitError);
        try {
            sss::estimate_primitive(p, c);
            ADD_FAILURE() << "no LimitError";
        } catch (const sss::LimitError& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find(kSource), std::string::npos) << what;
            EXPECT_NE(what.find("SSS_LIMIT_PRIMITIVE_MICROPOLYGONS"), std::string::npos)
                << what;
        }
    }
}

// ---------------------------------------------------------------------------
// Subdivision meshes

TEST(DiceMeshSubdivision, CubeBecomesASmoothClosedBlob) {
    // The Catmull-Clark limit of the unit cube lies between radius 0.4197
    // (face centres) and 0.4330 (the corners' limit points, (1/4, 1/4, 1/4)),
    // inside the inscribed sphere; refining further converges to area 2.29940.
    const sss::Primitive cube = cube_subdivision();
    const sss::DicedSurface fine = sss::dice_primitive(cube, spacing(0.01));
    const sss::DicedSurface coarse = sss::dice_primitive(cube, spacing(0.02));
    expect_well_formed(fine);
    const double a_fine = total_area(fine), a_coarse = total_area(coarse);
    const double pi = std::numbers::pi;
    EXPECT_GT(a_fine, 4.0 * pi * 0.4197 * 0.4197);
    EXPECT_LT(a_fine, 4.0 * pi * 0.4331 * 0.4331);
    EXPECT_NEAR(a_fine, 2.29940, 0.001 * 2.29940);
    EXPECT_NEAR(a_coarse, a_fine, 0.005 * a_fine);
    for (std::size_t i = 0; i < fine.size(); ++i) {
        const dvec3 c(fine.centers[i]);
        ASSERT_GT(glm::length(c), 0.4190);
        ASSERT_LT(glm::length(c), 0.4331);
        // Smooth and nearly round: normals close to the radial direction.
        ASSERT_GT(glm::dot(dvec3(fine.normals[i]), glm::normalize(c)), 0.99);
    }
    // Each refined quad is cut so no micropolygon side exceeds the spacing:
    // between 1 and 4 micropolygons per spacing^2 (about 2.4 here).
    const double ratio = double(fine.size()) * 0.01 * 0.01 / a_fine;
    EXPECT_GE(ratio, 1.0);
    EXPECT_LE(ratio, 4.0);
    for (float r : fine.radii) ASSERT_LE(r, 0.01f);
}

TEST(DiceMeshSubdivision, TransformsAndOrientation) {
    sss::Primitive cube = cube_subdivision();
    const double a = total_area(sss::dice_primitive(cube, spacing(0.02)));
    cube.object_to_world = glm::translate(sss::Matrix4(1.0), dvec3(5.0, 0.0, 0.0)) *
                           glm::scale(sss::Matrix4(1.0), dvec3(-2.0, 2.0, 2.0));
    auto inside = std::make_shared<sss::Attributes>();
    for (bool flip : {false, true}) {
        inside->orientation_inside = flip;
        cube.attributes = inside;
        const sss::DicedSurface s = sss::dice_primitive(cube, spacing(0.04));
        EXPECT_NEAR(total_area(s), 4.0 * a, 0.005 * 4.0 * a);
        for (std::size_t i = 0; i < s.size(); ++i) {
            const double d =
                glm::dot(dvec3(s.normals[i]), dvec3(s.centers[i]) - dvec3(5, 0, 0));
            ASSERT_TRUE(flip ? d < 0.0 : d > 0.0);
        }
    }
}

TEST(DiceMeshSubdivision, PentagonsAndTrianglesRefineToo) {
    // A square pyramid: 4 triangles and a quad (the first step makes quads).
    sss::Primitive p =
        make_prim(sss::PrimitiveKind::SubdivisionMesh,
                  {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}, {0, 0, 1.5}});
    p.type = "catmull-clark";
    p.nverts = {4, 3, 3, 3, 3};
    p.verts = {0, 3, 2, 1, 0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4};
    const sss::DicedSurface s = sss::dice_primitive(p, spacing(0.03));
    expect_well_formed(s);
    const dvec3 centre(0.0, 0.0, 0.5);
    for (std::size_t i = 0; i < s.size(); ++i)
        ASSERT_GT(glm::dot(dvec3(s.normals[i]), dvec3(s.centers[i]) - centre), 0.0);
}

TEST(DiceMeshSubdivision, InterpolateBoundaryKeepsTheBoundary) {
    auto flat = [](double) { return 0.0; };
    sss::Primitive grid = grid_subdivision(3, 3, flat);
    add_tag(grid, "interpolateboundary", {}, {});
    const sss::DicedSurface s = sss::dice_primitive(grid, spacing(0.05));
    expect_well_formed(s);
    EXPECT_NEAR(total_area(s), 9.0, 1e-5 * 9.0);
    glm::vec3 lo(1e9f), hi(-1e9f);
    for (const glm::vec3& v : s.vertices) {
        lo = glm::min(lo, v);
        hi = glm::max(hi, v);
    }
    EXPECT_NEAR(lo.x, 0.0f, 1e-6f);
    EXPECT_NEAR(lo.y, 0.0f, 1e-6f);
    EXPECT_NEAR(hi.x, 3.0f, 1e-6f);
    EXPECT_NEAR(hi.y, 3.0f, 1e-6f);
    // Without the tag the boundary still follows the curve rule, but the
    // corners are rounded off: less area.
    const double untagged =
        total_area(sss::dice_primitive(grid_subdivision(3, 3, flat), spacing(0.05)));
    EXPECT_LT(untagged, 9.0 - 0.1);
    EXPECT_GT(untagged, 7.0);
    // "corner" tags on the four corners pin them like interpolateboundary.
    sss::Primitive cornered = grid_subdivision(3, 3, flat);
    add_tag(cornered, "corner", {0, 3, 12, 15}, {10.0});
    EXPECT_NEAR(total_area(sss::dice_primitive(cornered, spacing(0.05))), 9.0,
                1e-5 * 9.0);
}

TEST(DiceMeshSubdivision, CreaseKeepsASharpEdge) {
    // A ridge z = -|x - 2| along x = 2, creased (vertices 2, 7, 12, 17).
    auto ridge = [](double x) { return -std::abs(x - 2.0); };
    auto ridge_height = [&](double sharpness) {
        sss::Primitive p = grid_subdivision(4, 3, ridge);
        add_tag(p, "interpolateboundary", {}, {});
        if (sharpness > 0.0) add_tag(p, "crease", {2, 7, 12, 17}, {sharpness});
        const sss::DicedSurface s = sss::dice_primitive(p, spacing(0.05));
        float top = -1e9f;
        for (const glm::vec3& v : s.vertices) top = std::max(top, v.z);
        return std::make_pair(s, top);
    };
    const auto [sharp, sharp_top] = ridge_height(10.0);
    expect_well_formed(sharp);
    // The crease stays on the original edge line x = 2, z = 0.
    std::size_t on_line = 0;
    for (const glm::vec3& v : sharp.vertices)
        if (std::abs(v.x - 2.0f) < 1e-6f) {
            ASSERT_NEAR(v.z, 0.0f, 1e-6f);
            ++on_line;
        }
    EXPECT_GT(on_line, 10u);
    EXPECT_NEAR(sharp_top, 0.0f, 1e-6f);
    // Normals on the two flanks stay apart next to the crease.
    for (std::size_t i = 0; i < sharp.size(); ++i) {
        const glm::vec3 c = sharp.centers[i], n = sharp.normals[i];
        if (std::abs(c.x - 2.0f) < 0.05f && c.y > 0.5f && c.y < 2.5f) {
            ASSERT_GT(std::abs(n.x), 0.5f) << c.x;
        }
    }
    // Semi-sharp creases lie between smooth and sharp.
    const float smooth_top = ridge_height(0.0).second;
    const float semi_top = ridge_height(1.0).second;
    EXPECT_LT(smooth_top, -0.1f);
    EXPECT_GT(semi_top, smooth_top + 0.01f);
    EXPECT_LT(semi_top, -0.01f);
}

TEST(DiceMeshSubdivision, CreasingEveryCubeEdgeGivesTheCube) {
    // All 12 edges infinitely sharp: every corner meets 3 creases (a corner),
    // every edge stays straight, and the faces stay flat.
    sss::Primitive cube = cube_subdivision();
    for (int f = 0; f < 6; ++f)
        for (int k = 0; k < 4; ++k) {
            const int a = kBoxFaces[4 * f + k], b = kBoxFaces[4 * f + (k + 1) % 4];
            if (a < b) add_tag(cube, "crease", {a, b}, {10.0});
        }
    const sss::DicedSurface s = sss::dice_primitive(cube, spacing(0.05));
    expect_well_formed(s);
    EXPECT_NEAR(total_area(s), 6.0, 1e-5 * 6.0);
    for (std::size_t i = 0; i < s.size(); ++i) {
        const glm::vec3 c = s.centers[i];
        ASSERT_NEAR(std::max({std::abs(c.x), std::abs(c.y), std::abs(c.z)}), 0.5f, 1e-6f);
        ASSERT_GT(glm::dot(s.normals[i], c), 0.0f);
    }
}

TEST(DiceMeshSubdivision, HoleTagRemovesFaces) {
    sss::Primitive cube = cube_subdivision();
    const double full = total_area(sss::dice_primitive(cube, spacing(0.02)));
    add_tag(cube, "hole", {0}, {});
    add_tag(cube, "unknowntag", {1, 2}, {3.0}); // ignored
    const sss::DicedSurface s = sss::dice_primitive(cube, spacing(0.02));
    // By symmetry every control face owns 1/6 of the limit surface.
    EXPECT_NEAR(total_area(s), full * 5.0 / 6.0, 1e-3 * full);
    // Face 0 is the -z face: nothing is left below the cube's middle there.
    for (std::size_t i = 0; i < s.size(); ++i)
        ASSERT_FALSE(s.centers[i].z < -0.45f && std::abs(s.centers[i].x) < 0.2f &&
                     std::abs(s.centers[i].y) < 0.2f);
}

TEST(DiceMeshSubdivision, VertexColorsAreInterpolated) {
    sss::Primitive grid = grid_subdivision(2, 2, [](double) { return 0.0; });
    add_tag(grid, "interpolateboundary", {}, {});
    std::vector<double> cs;
    for (int j = 0; j <= 2; ++j)
        for (int i = 0; i <= 2; ++i) cs.insert(cs.end(), {i / 2.0, j / 2.0, 0.5});
    grid.params.items.push_back(
        make_param("Cs", cs, sss::ParamType::Color, sss::ParamClass::Vertex));
    const sss::DicedSurface s = sss::dice_primitive(grid, spacing(0.1));
    ASSERT_EQ(s.colors.size(), s.size());
    for (std::size_t i = 0; i < s.size(); ++i) {
        ASSERT_GE(s.colors[i].r, 0.0f);
        ASSERT_LE(s.colors[i].r, 1.0f);
        ASSERT_NEAR(s.colors[i].b, 0.5f, 1e-6f);
    }
    // Linear colours on a flat regular grid: red tracks x closely (the limit
    // positions are pulled slightly towards the middle, the colours are not).
    for (std::size_t i = 0; i < s.size(); ++i)
        ASSERT_NEAR(s.colors[i].r, s.centers[i].x / 2.0f, 0.05f);
}

TEST(DiceMeshSubdivision, MalformedMeshesThrowNamingTheSource) {
    {
        sss::Primitive p = cube_subdivision();
        p.type = "loop";
        expect_value_error([&] { sss::dice_primitive(p, spacing(0.1)); }, "loop");
    }
    {
        sss::Primitive p = cube_subdivision();
        p.verts[5] = 8;
        expect_value_error([&] { sss::dice_primitive(p, spacing(0.1)); }, "out of range");
    }
    {
        sss::Primitive p = cube_subdivision();
        p.params.items[0].numbers[2] = std::numeric_limits<double>::infinity();
        expect_value_error([&] { sss::dice_primitive(p, spacing(0.1)); }, "finite");
    }
    {
        sss::Primitive p = cube_subdivision();
        p.nverts[0] = 2;
        expect_value_error([&] { sss::dice_primitive(p, spacing(0.1)); });
    }
    {
        sss::Primitive p = cube_subdivision();
        p.params.items.clear();
        expect_value_error([&] { sss::dice_primitive(p, spacing(0.1)); }, "\"P\"");
    }
    {
        // Three faces on the edge 0-1: non-manifold.
        sss::Primitive p =
            make_prim(sss::PrimitiveKind::SubdivisionMesh,
                      {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}});
        p.type = "catmull-clark";
        p.nverts = {3, 3, 3};
        p.verts = {0, 1, 2, 1, 0, 3, 0, 1, 4};
        expect_value_error([&] { sss::dice_primitive(p, spacing(0.1)); }, "non-manifold");
    }
    {
        sss::Primitive p = cube_subdivision();
        add_tag(p, "hole", {6}, {});
        expect_value_error([&] { sss::dice_primitive(p, spacing(0.1)); }, "hole");
    }
}

} // namespace

// ---------------------------------------------------------------------------
// Grids and displacement

TEST(DiceMeshGrids, QuadsAreGridsTrianglesAreNot) {
    sss::DiceControl c = spacing(0.1);
    c.grids = true;
    // A quad and a triangle in one mesh.
    auto prim = make_prim(sss::PrimitiveKind::PointsPolygons,
                          {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {2, 0, 0}});
    prim.nverts = {4, 3};
    prim.verts = {0, 1, 2, 3, 1, 4, 2};
    prim.params.items.push_back(make_param("st", {0, 0, 2, 0, 2, 2, 0, 2, 4, 0},
                                           sss::ParamType::Float,
                                           sss::ParamClass::Vertex));
    prim.params.items.back().array_size = 2;
    const auto d = sss::dice_primitive(prim, c);
    expect_well_formed(d);
    ASSERT_EQ(d.grids.size(), 1u);
    const sss::DicedGrid& g = d.grids[0];
    EXPECT_EQ(g.first, 0u);
    EXPECT_EQ(g.nu, 10);
    EXPECT_EQ(g.nv, 10);
    ASSERT_EQ(d.u.size(), d.size());
    for (std::size_t k = 0; k < g.size(); ++k) {
        EXPECT_NEAR(d.s[k], 2.0f * d.u[k], 1e-5f);
        EXPECT_NEAR(d.t[k], 2.0f * d.v[k], 1e-5f);
        EXPECT_NEAR(d.du[k], 0.1f, 1e-6f);
        EXPECT_NEAR(d.dPdu[k].x, 1.0f, 1e-6f);
        EXPECT_NEAR(d.dPdv[k].y, 1.0f, 1e-6f);
    }
    EXPECT_GT(d.size(), g.size()); // the triangle's points are in no grid

    // Vertices: the quad's grid first ((u, v) = (x, y)), then the
    // triangle's, which has no (u, v) but has "st"; st doubles x and y.
    ASSERT_EQ(d.vertex_uvst.size(), d.vertices.size());
    for (std::size_t k = 0; k < d.vertices.size(); ++k) {
        const glm::vec3& p = d.vertices[k];
        const glm::vec4& a = d.vertex_uvst[k];
        EXPECT_NEAR(a.x, k < 121 ? p.x : 0.0f, 1e-6f);
        EXPECT_NEAR(a.y, k < 121 ? p.y : 0.0f, 1e-6f);
        EXPECT_NEAR(a.z, 2.0f * p.x, 1e-5f);
        EXPECT_NEAR(a.w, 2.0f * p.y, 1e-5f);
    }
    // Without grids: none.
    EXPECT_TRUE(sss::dice_primitive(prim, spacing(0.1)).vertex_uvst.empty());
}

TEST(DiceMeshGrids, DisplacementMovesQuadsTrianglesAndSubdivisionSurfaces) {
    sss::DiceControl c = spacing(0.1);
    c.displace = [](sss::DisplaceGrid& g) {
        for (std::size_t k = 0; k < g.size(); ++k) g.P[k] += 0.25f * g.N[k];
    };
    auto prim = make_prim(sss::PrimitiveKind::PointsPolygons,
                          {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {2, 0, 0}});
    prim.nverts = {4, 3};
    prim.verts = {0, 1, 2, 3, 1, 4, 2};
    const auto d = sss::dice_primitive(prim, c);
    expect_well_formed(d);
    for (const glm::vec3& v : d.vertices) EXPECT_NEAR(v.z, 0.25f, 1e-6f);
    for (const glm::vec3& p : d.centers) EXPECT_NEAR(p.z, 0.25f, 1e-6f);
    for (const glm::vec3& n : d.normals) EXPECT_NEAR(n.z, 1.0f, 1e-6f);
    EXPECT_NEAR(total_area(d), 1.5, 1e-5);

    // A cube's limit surface grows: more area.
    auto cube = make_prim(sss::PrimitiveKind::SubdivisionMesh, {{-1, -1, 1},
                                                                {1, -1, 1},
                                                                {-1, 1, 1},
                                                                {1, 1, 1},
                                                                {-1, 1, -1},
                                                                {1, 1, -1},
                                                                {-1, -1, -1},
                                                                {1, -1, -1}});
    cube.type = "catmull-clark";
    cube.nverts = {4, 4, 4, 4, 4, 4};
    cube.verts = {0, 1, 3, 2, 2, 3, 5, 4, 4, 5, 7, 6, 6, 7, 1, 0, 1, 7, 5, 3, 6, 0, 2, 4};
    const double plain = total_area(sss::dice_primitive(cube, spacing(0.1)));
    const auto grown = sss::dice_primitive(cube, c);
    expect_well_formed(grown);
    EXPECT_GT(total_area(grown), 1.2 * plain);
    EXPECT_TRUE(grown.vertex_uvst.empty());

    // With grids, every vertex has the (u, v) of its refined face, and s, t
    // the same.
    c.grids = true;
    const auto gridded = sss::dice_primitive(cube, c);
    EXPECT_EQ(gridded.vertices, grown.vertices);
    ASSERT_EQ(gridded.vertex_uvst.size(), gridded.vertices.size());
    for (const glm::vec4& a : gridded.vertex_uvst) {
        EXPECT_GE(a.x, 0.0f);
        EXPECT_LE(a.x, 1.0f);
        EXPECT_GE(a.y, 0.0f);
        EXPECT_LE(a.y, 1.0f);
        EXPECT_EQ(a.z, a.x);
        EXPECT_EQ(a.w, a.y);
    }
}
