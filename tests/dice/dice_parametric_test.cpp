// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file dice_parametric_test.cpp
/// Tests of the dicing of parametric primitives (sss/dice.h): quadric areas
/// against closed forms and independent quadrature, normal orientation under
/// transforms and Orientation, micropolygon size for a fixed spacing and for
/// ShadingRate, patches and patch meshes, the teapot, and malformed input.
///
/// Suite names all start with "DiceParametric".

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "sss/dice/dice.h"
#include "sss/scene/scene.h"
#include "sss/util/error.h"

// The shared normal rule (internal header of the library).
#include "../../src/sss/dice/dice_common.h"

namespace {

using sss::PrimitiveKind;
constexpr double kPi = std::numbers::pi;

sss::Primitive make_prim(PrimitiveKind kind, std::vector<double> args = {},
                         std::shared_ptr<sss::Attributes> attr = nullptr) {
    sss::Primitive p;
    p.kind = kind;
    p.args = std::move(args);
    p.attributes = attr ? attr : std::make_shared<sss::Attributes>();
    p.source = "scene.rib:7";
    return p;
}

sss::DiceControl spacing(double s) {
    sss::DiceControl c;
    c.spacing = s;
    return c;
}

double total_area(const sss::DicedSurface& d) {
    double sum = 0.0;
    for (float a : d.areas) sum += a;
    return sum;
}

void set_param(sss::Primitive& prim, const std::string& name, sss::ParamType type,
               sss::ParamClass storage, std::vector<double> numbers) {
    sss::Param p;
    p.name = name;
    p.type = type;
    p.storage = storage;
    p.numbers = std::move(numbers);
    prim.params.set(p);
}

/// Every array has the right size, every number is finite, normals are unit.
void expect_well_formed(const sss::DicedSurface& d) {
    ASSERT_EQ(d.normals.size(), d.size());
    ASSERT_EQ(d.areas.size(), d.size());
    ASSERT_EQ(d.radii.size(), d.size());
    ASSERT_TRUE(d.colors.empty() || d.colors.size() == d.size());
    ASSERT_EQ(d.vertex_normals.size(), d.vertices.size());
    ASSERT_EQ(d.triangles.size() % 3, 0u);
    for (std::size_t i = 0; i < d.size(); ++i) {
        ASSERT_TRUE(std::isfinite(d.centers[i].x + d.centers[i].y + d.centers[i].z)) << i;
        ASSERT_NEAR(glm::length(d.normals[i]), 1.0f, 1e-4f) << i;
        ASSERT_GT(d.areas[i], 0.0f) << i;
        ASSERT_TRUE(std::isfinite(d.radii[i])) << i;
    }
    for (const auto& n : d.vertex_normals) ASSERT_NEAR(glm::length(n), 1.0f, 1e-4f);
    for (uint32_t t : d.triangles) ASSERT_LT(t, d.vertices.size());
}

/// Relative difference of the diced area from the reference.
double area_error(const sss::Primitive& prim, double s) {
    const sss::DicedSurface d = sss::dice_primitive(prim, spacing(s));
    expect_well_formed(d);
    const double want = sss::quadric_area(prim);
    return std::abs(total_area(d) - want) / want;
}

// ---------------------------------------------------------------------------
// Areas

TEST(DiceParametricArea, ReferenceAreasMatchClosedForms) {
    EXPECT_NEAR(sss::quadric_area(make_prim(PrimitiveKind::Sphere, {2, -5, 5, 360})),
                16 * kPi, 1e-12);
    // Zone of a sphere: 2 pi r h, a third of it for 120 degrees.
    EXPECT_NEAR(sss::quadric_area(make_prim(PrimitiveKind::Sphere, {1, -0.5, 0.25, 120})),
                2 * kPi * 0.75 / 3, 1e-12);
    EXPECT_NEAR(sss::quadric_area(make_prim(PrimitiveKind::Torus, {3, 1, 0, 360, 360})),
                4 * kPi * kPi * 3, 1e-10);
    // Paraboloid z = a rho^2 from the apex: pi/(6a^2) ((1 + 4 a^2 R^2)^1.5 - 1).
    const double a = 2.0 / (1.5 * 1.5);
    const double want =
        kPi / (6 * a * a) * (std::pow(1 + 4 * a * a * 1.5 * 1.5, 1.5) - 1);
    EXPECT_NEAR(sss::quadric_area(make_prim(PrimitiveKind::Paraboloid, {1.5, 0, 2, 360})),
                want, 1e-10 * want);
    // A hyperboloid with both points at radius 1, same angle: a cylinder.
    EXPECT_NEAR(sss::quadric_area(
                    make_prim(PrimitiveKind::Hyperboloid, {1, 0, -1, 1, 0, 1, 360})),
                4 * kPi, 1e-10);
    // Hyperboloid through the axis: the two cones meet at the origin.
    EXPECT_NEAR(sss::quadric_area(
                    make_prim(PrimitiveKind::Hyperboloid, {-1, 0, -1, 1, 0, 1, 360})),
                2 * kPi * std::sqrt(2.0), 1e-10);
    EXPECT_THROW(sss::quadric_area(make_prim(PrimitiveKind::Teapot)), sss::ValueError);
}

TEST(DiceParametricArea, SpheresFullAndPartial) {
    EXPECT_LT(area_error(make_prim(PrimitiveKind::Sphere, {1, -1, 1, 360}), 0.05), 1e-3);
    EXPECT_LT(area_error(make_prim(PrimitiveKind::Sphere, {1.5, -0.4, 1.2, 250}), 0.05),
              1e-3);
    // zmin/zmax beyond the radius are clamped; negative sweep.
    EXPECT_LT(area_error(make_prim(PrimitiveKind::Sphere, {0.7, -3, 0.2, -300}), 0.03),
              1e-3);
    // Coarse dicing still integrates well.
    EXPECT_LT(area_error(make_prim(PrimitiveKind::Sphere, {1, -1, 1, 360}), 0.4), 1e-3);
}

TEST(DiceParametricArea, TorusFullPartialAndSpindle) {
    EXPECT_LT(area_error(make_prim(PrimitiveKind::Torus, {2, 0.5, 0, 360, 360}), 0.05),
              1e-3);
    EXPECT_LT(area_error(make_prim(PrimitiveKind::Torus, {1, 0.3, -45, 200, 300}), 0.03),
              1e-3);
    // Self-intersecting torus (major < minor): |R + r cos phi| changes sign.
    EXPECT_LT(area_error(make_prim(PrimitiveKind::Torus, {0.5, 1, 0, 360, 360}), 0.04),
              1e-3);
}

TEST(DiceParametricArea, CylinderConeDisk) {
    EXPECT_LT(area_error(make_prim(PrimitiveKind::Cylinder, {1, -0.5, 1.5, 360}), 0.05),
              1e-3);
    EXPECT_LT(area_error(make_prim(PrimitiveKind::Cylinder, {0.5, 1, 0, 90}), 0.02),
              1e-3);
    EXPECT_LT(area_error(make_prim(PrimitiveKind::Cone, {2, 1, 360}), 0.05), 1e-3);
    EXPECT_LT(area_error(make_prim(PrimitiveKind::Cone, {-1, 0.5, 135}), 0.02), 1e-3);
    EXPECT_LT(area_error(make_prim(PrimitiveKind::Disk, {0.3, 1, 360}), 0.05), 1e-3);
    EXPECT_LT(area_error(make_prim(PrimitiveKind::Disk, {0, 2, 45}), 0.05), 1e-3);
}

TEST(DiceParametricArea, ParaboloidHyperboloid) {
    EXPECT_LT(area_error(make_prim(PrimitiveKind::Paraboloid, {1, 0, 2, 360}), 0.05),
              1e-3);
    EXPECT_LT(area_error(make_prim(PrimitiveKind::Paraboloid, {0.5, 0.3, 1, 200}), 0.02),
              1e-3);
    // Twisted line: a one-sheet hyperboloid.
    EXPECT_LT(
        area_error(make_prim(PrimitiveKind::Hyperboloid, {1, 0, -1, 0, 1, 1, 360}), 0.05),
        1e-3);
    EXPECT_LT(area_error(
                  make_prim(PrimitiveKind::Hyperboloid, {0.2, 0.5, 0, 1, -0.3, 0.8, 270}),
                  0.03),
              1e-3);
}

TEST(DiceParametricArea, WorldSpaceUnderScaling) {
    // Scale 2 2 2 + Sphere 1 = a sphere of radius 2.
    auto sphere = make_prim(PrimitiveKind::Sphere, {1, -1, 1, 360});
    sphere.object_to_world = glm::scale(sss::Matrix4(1.0), glm::dvec3(2.0));
    const auto big = sss::dice_primitive(sphere, spacing(0.1));
    EXPECT_NEAR(total_area(big), 16 * kPi, 1e-3 * 16 * kPi);

    // Prolate spheroid with semi-axes (2, 1, 1): 2 pi b^2 (1 + a/(b e) asin e).
    sphere.object_to_world = glm::scale(sss::Matrix4(1.0), glm::dvec3(2.0, 1.0, 1.0));
    const double e = std::sqrt(1.0 - 1.0 / 4.0);
    const double spheroid = 2 * kPi * (1 + 2.0 / e * std::asin(e));
    EXPECT_NEAR(total_area(sss::dice_primitive(sphere, spacing(0.05))), spheroid,
                1e-3 * spheroid);

    // Disk of radius 1 stretched to an ellipse with axes 2 and 1; plus a rotation.
    auto disk = make_prim(PrimitiveKind::Disk, {0, 1, 360});
    disk.object_to_world = glm::rotate(sss::Matrix4(1.0), 0.7, glm::dvec3(1, 2, 3)) *
                           glm::scale(sss::Matrix4(1.0), glm::dvec3(2.0, 1.0, 5.0));
    EXPECT_NEAR(total_area(sss::dice_primitive(disk, spacing(0.05))), 2 * kPi,
                2e-3 * kPi);

    // Cylinder stretched along its axis.
    auto cyl = make_prim(PrimitiveKind::Cylinder, {1, 0, 1, 360});
    cyl.object_to_world = glm::translate(sss::Matrix4(1.0), glm::dvec3(5, -3, 2)) *
                          glm::scale(sss::Matrix4(1.0), glm::dvec3(1.0, 1.0, 3.0));
    EXPECT_NEAR(total_area(sss::dice_primitive(cyl, spacing(0.05))), 6 * kPi, 6e-3 * kPi);
}

// ---------------------------------------------------------------------------
// Normals

TEST(DiceParametricNormals, PointOutward) {
    const auto sphere = sss::dice_primitive(
        make_prim(PrimitiveKind::Sphere, {1, -1, 1, 360}), spacing(0.1));
    expect_well_formed(sphere);
    for (std::size_t i = 0; i < sphere.size(); ++i)
        ASSERT_GT(glm::dot(sphere.normals[i], sphere.centers[i]), 0.99f) << i;
    for (std::size_t i = 0; i < sphere.vertices.size(); ++i)
        ASSERT_GT(glm::dot(sphere.vertex_normals[i], sphere.vertices[i]), 0.99f) << i;

    const auto cyl = sss::dice_primitive(
        make_prim(PrimitiveKind::Cylinder, {1, 0, 1, 360}), spacing(0.1));
    for (std::size_t i = 0; i < cyl.size(); ++i) {
        const glm::vec3 radial(cyl.centers[i].x, cyl.centers[i].y, 0.0f);
        ASSERT_GT(glm::dot(cyl.normals[i], radial), 0.99f) << i;
    }

    const auto torus = sss::dice_primitive(
        make_prim(PrimitiveKind::Torus, {2, 0.5, 0, 360, 360}), spacing(0.1));
    for (std::size_t i = 0; i < torus.size(); ++i) {
        const glm::vec3 c = torus.centers[i];
        const glm::vec3 ring = 2.0f * glm::normalize(glm::vec3(c.x, c.y, 0.0f));
        ASSERT_GT(glm::dot(torus.normals[i], c - ring), 0.0f) << i;
    }

    const auto disk =
        sss::dice_primitive(make_prim(PrimitiveKind::Disk, {1, 1, 360}), spacing(0.1));
    expect_well_formed(disk);
    for (std::size_t i = 0; i < disk.size(); ++i) ASSERT_GT(disk.normals[i].z, 0.9999f);
    for (const auto& n : disk.vertex_normals) ASSERT_GT(n.z, 0.9999f); // apex too

    // Cone: out and up; paraboloid: out and down.
    const auto cone =
        sss::dice_primitive(make_prim(PrimitiveKind::Cone, {1, 1, 360}), spacing(0.1));
    expect_well_formed(cone);
    for (std::size_t i = 0; i < cone.size(); ++i) ASSERT_GT(cone.normals[i].z, 0.7f);
    const auto para = sss::dice_primitive(
        make_prim(PrimitiveKind::Paraboloid, {1, 0, 1, 360}), spacing(0.1));
    expect_well_formed(para);
    for (std::size_t i = 0; i < para.size(); ++i) ASSERT_LT(para.normals[i].z, 0.0f);
}

TEST(DiceParametricNormals, OrientationInsideFlipsMirrorDoesNot) {
    auto attr = std::make_shared<sss::Attributes>();
    attr->orientation_inside = true;
    const auto inside = sss::dice_primitive(
        make_prim(PrimitiveKind::Sphere, {1, -1, 1, 360}, attr), spacing(0.1));
    ASSERT_GT(inside.size(), 100u);
    for (std::size_t i = 0; i < inside.size(); ++i)
        ASSERT_LT(glm::dot(inside.normals[i], inside.centers[i]), -0.99f) << i;
    for (std::size_t i = 0; i < inside.vertices.size(); ++i)
        ASSERT_LT(glm::dot(inside.vertex_normals[i], inside.vertices[i]), -0.99f) << i;

    auto mirrored = make_prim(PrimitiveKind::Sphere, {1, -1, 1, 360});
    mirrored.object_to_world = glm::translate(sss::Matrix4(1.0), glm::dvec3(3, 0, 0)) *
                               glm::scale(sss::Matrix4(1.0), glm::dvec3(-1, 1, 1));
    const auto m = sss::dice_primitive(mirrored, spacing(0.1));
    const glm::vec3 centre(3, 0, 0);
    for (std::size_t i = 0; i < m.size(); ++i)
        ASSERT_GT(glm::dot(m.normals[i], m.centers[i] - centre), 0.99f) << i;
    // The triangles wind counter-clockwise around the final normal.
    for (std::size_t t = 0; t < m.triangles.size(); t += 3) {
        const glm::vec3 a = m.vertices[m.triangles[t]];
        const glm::vec3 b = m.vertices[m.triangles[t + 1]];
        const glm::vec3 c = m.vertices[m.triangles[t + 2]];
        ASSERT_GT(glm::dot(glm::cross(b - a, c - a), (a + b + c) / 3.0f - centre), 0.0f);
    }

    // The shared helper.
    const glm::dvec3 n = sss::detail::world_normal(
        glm::scale(sss::Matrix4(1.0), glm::dvec3(-1, 2, 1)), glm::dvec3(1, 1, 0), false);
    EXPECT_NEAR(n.x, -2 / std::sqrt(5.0), 1e-12);
    EXPECT_NEAR(n.y, 1 / std::sqrt(5.0), 1e-12);
}

// ---------------------------------------------------------------------------
// Micropolygon size

TEST(DiceParametricSize, EdgesFollowSpacing) {
    const double s = 0.05;
    const auto cyl = make_prim(PrimitiveKind::Cylinder, {1, 0, 2, 360});
    const auto d = sss::dice_primitive(cyl, spacing(s));
    const double ratio = static_cast<double>(d.size()) * s * s / sss::quadric_area(cyl);
    EXPECT_GT(ratio, 0.8);
    EXPECT_LT(ratio, 1.25);
    for (float r : d.radii) {
        ASSERT_GT(r, 0.5 * s);
        ASSERT_LT(r, 1.0 * s);
    }
    // On a sphere the cells shrink towards the poles, but within a factor.
    const auto sphere = make_prim(PrimitiveKind::Sphere, {1, -1, 1, 360});
    const auto ds = sss::dice_primitive(sphere, spacing(s));
    const double sratio =
        static_cast<double>(ds.size()) * s * s / sss::quadric_area(sphere);
    EXPECT_GT(sratio, 0.8);
    EXPECT_LT(sratio, 2.0);
    for (float r : ds.radii) ASSERT_LT(r, 1.0 * s);
}

TEST(DiceParametricSize, EdgeLengthAt) {
    sss::DiceControl c;
    EXPECT_THROW(c.edge_length_at(glm::dvec3(0, 0, 1), 1.0), sss::ValueError);
    c.spacing = 0.25;
    EXPECT_EQ(c.edge_length_at(glm::dvec3(0, 0, 1), 1.0), 0.25);
    c.spacing = -1;
    EXPECT_THROW(c.edge_length_at(glm::dvec3(0, 0, 1), 1.0), sss::ValueError);

    sss::Camera cam;
    cam.perspective = true;
    cam.fov = 90;
    cam.xres = 400;
    cam.yres = 400;
    c.spacing = 0;
    c.camera = &cam;
    // Euclidean distance from the eye: sideways points are as far as ahead.
    const double ahead = c.edge_length_at(glm::dvec3(0, 0, 10), 1.0);
    EXPECT_NEAR(ahead, cam.pixel_size_at(10.0), 1e-12);
    EXPECT_NEAR(c.edge_length_at(glm::dvec3(6, 8, 0), 1.0), ahead, 1e-12);
    EXPECT_NEAR(c.edge_length_at(glm::dvec3(0, 0, 10), 4.0), 2 * ahead, 1e-12);
    // Never below the near clip.
    cam.near_clip = 0.5;
    EXPECT_NEAR(c.edge_length_at(glm::dvec3(0, 0, 0), 1.0), cam.pixel_size_at(0.5),
                1e-12);
    EXPECT_THROW(c.edge_length_at(glm::dvec3(0, 0, 1), 0.0), sss::ValueError);
}

TEST(DiceParametricSize, ShadingRateFollowsDistance) {
    sss::Camera cam;
    cam.perspective = true;
    cam.fov = 60;
    cam.xres = 320;
    cam.yres = 240;
    sss::DiceControl c;
    c.camera = &cam;
    auto attr = std::make_shared<sss::Attributes>();
    attr->shading_rate = 2.0;
    auto near = make_prim(PrimitiveKind::Sphere, {1, -1, 1, 360}, attr);
    near.object_to_world = glm::translate(sss::Matrix4(1.0), glm::dvec3(0, 0, 8));
    auto far = near;
    far.object_to_world = glm::translate(sss::Matrix4(1.0), glm::dvec3(0, 0, 16));
    const auto dn = sss::dice_primitive(near, c);
    const auto df = sss::dice_primitive(far, c);
    expect_well_formed(dn);
    const double ratio = static_cast<double>(dn.size()) / static_cast<double>(df.size());
    EXPECT_GT(ratio, 3.0); // (16 / 8)^2 = 4 in area
    EXPECT_LT(ratio, 5.0);
    EXPECT_NEAR(total_area(dn), 4 * kPi, 4e-3 * kPi);
    EXPECT_NEAR(total_area(df), 4 * kPi, 4e-3 * kPi);

    // Too close for comfort: the near side gets finer micropolygons than the far side.
    auto close = near;
    close.object_to_world = glm::translate(sss::Matrix4(1.0), glm::dvec3(0, 0, 1.5));
    const auto dc = sss::dice_primitive(close, c);
    float near_r = 1e9f;
    float far_r = 0.0f;
    for (std::size_t i = 0; i < dc.size(); ++i) {
        if (dc.centers[i].z < 0.7f) near_r = std::min(near_r, dc.radii[i]);
        if (dc.centers[i].z > 2.3f) far_r = std::max(far_r, dc.radii[i]);
    }
    EXPECT_LT(near_r * 2.0f, far_r);
    EXPECT_NEAR(total_area(dc), 4 * kPi, 4e-3 * kPi);

    // No camera: the error names the primitive.
    try {
        sss::dice_primitive(near, sss::DiceControl{});
        FAIL() << "expected ValueError";
    } catch (const sss::ValueError& e) {
        EXPECT_NE(std::string(e.what()).find("scene.rib:7"), std::string::npos)
            << e.what();
    }
}

// ---------------------------------------------------------------------------
// Triangles

/// Directed edges (by vertex position) that have no reverse edge: a closed,
/// consistently wound, crack-free surface has none.
std::vector<std::array<glm::vec3, 2>> open_edge_list(const sss::DicedSurface& d) {
    using Key = std::array<float, 6>;
    std::vector<Key> edges;
    for (std::size_t t = 0; t < d.triangles.size(); t += 3)
        for (int k = 0; k < 3; ++k) {
            const glm::vec3 a = d.vertices[d.triangles[t + k]];
            const glm::vec3 b = d.vertices[d.triangles[t + (k + 1) % 3]];
            edges.push_back({a.x, a.y, a.z, b.x, b.y, b.z});
        }
    std::sort(edges.begin(), edges.end());
    std::vector<std::array<glm::vec3, 2>> open;
    for (const Key& e : edges) {
        const Key rev{e[3], e[4], e[5], e[0], e[1], e[2]};
        if (!std::binary_search(edges.begin(), edges.end(), rev))
            open.push_back({glm::vec3(e[0], e[1], e[2]), glm::vec3(e[3], e[4], e[5])});
    }
    return open;
}

std::size_t open_edges(const sss::DicedSurface& d) {
    return open_edge_list(d).size();
}

TEST(DiceParametricTriangles, ClosedSurfacesAreWatertight) {
    const auto sphere = sss::dice_primitive(
        make_prim(PrimitiveKind::Sphere, {1, -1, 1, 360}), spacing(0.03));
    EXPECT_EQ(open_edges(sphere), 0u);
    const auto torus = sss::dice_primitive(
        make_prim(PrimitiveKind::Torus, {1, 0.4, 0, 360, 360}), spacing(0.03));
    EXPECT_EQ(open_edges(torus), 0u);

    // ShadingRate dicing close to the eye: neighbouring sub-patches with
    // different grids are stitched.
    sss::Camera cam;
    cam.perspective = true;
    cam.fov = 60;
    cam.xres = 40;
    cam.yres = 40;
    sss::DiceControl c;
    c.camera = &cam;
    auto close = make_prim(PrimitiveKind::Sphere, {1, -1, 1, 360});
    close.object_to_world = glm::translate(sss::Matrix4(1.0), glm::dvec3(0.3, 0, 1.3));
    const auto dc = sss::dice_primitive(close, c);
    ASSERT_GT(dc.size(), 5000u);
    EXPECT_EQ(open_edges(dc), 0u);

    // A bumpy bicubic patch x = u, y = v (Bezier linear precision), tilted
    // away from the eye: open edges only on its boundary.
    const double bump[16] = {0,    0.3, -0.2, 0.1,  0.2, 0.9,  -0.6, 0,
                             -0.1, 0.4, 0.8,  -0.3, 0,   -0.2, 0.3,  0.2};
    std::vector<double> cp;
    for (int r = 0; r < 4; ++r)
        for (int q = 0; q < 4; ++q)
            cp.insert(cp.end(), {q / 3.0, r / 3.0, bump[4 * r + q]});
    auto patch = make_prim(PrimitiveKind::Patch);
    patch.type = "bicubic";
    set_param(patch, "P", sss::ParamType::Point, sss::ParamClass::Vertex, cp);
    patch.object_to_world =
        glm::translate(sss::Matrix4(1.0), glm::dvec3(-0.5, -0.5, 0.8)) *
        glm::rotate(sss::Matrix4(1.0), -1.2, glm::dvec3(1, 0, 0));
    const auto dp = sss::dice_primitive(patch, c);
    ASSERT_GT(dp.size(), 2000u);
    const glm::mat4 to_patch(glm::inverse(patch.object_to_world));
    std::size_t inner_open = 0;
    const auto on_boundary = [&](glm::vec3 w) {
        const glm::vec3 p(to_patch * glm::vec4(w, 1.0f));
        const float d = std::min(std::min(p.x, 1 - p.x), std::min(p.y, 1 - p.y));
        return std::abs(d) < 1e-4f;
    };
    const auto open = open_edge_list(dp);
    EXPECT_GT(open.size(), 100u);
    for (const auto& e : open)
        if (!on_boundary(e[0]) || !on_boundary(e[1])) ++inner_open;
    EXPECT_EQ(inner_open, 0u);

    // An open surface has open edges only along its boundary.
    const auto cyl = sss::dice_primitive(
        make_prim(PrimitiveKind::Cylinder, {1, 0, 1, 360}), spacing(0.05));
    const std::size_t around = static_cast<std::size_t>(std::ceil(2 * kPi / 0.05));
    EXPECT_GE(open_edges(cyl), 2 * around);
    EXPECT_LE(open_edges(cyl), 3 * around);
}

// ---------------------------------------------------------------------------
// Patches

TEST(DiceParametricPatch, BilinearUnitSquare) {
    auto p = make_prim(PrimitiveKind::Patch);
    p.type = "bilinear";
    set_param(p, "P", sss::ParamType::Point, sss::ParamClass::Vertex,
              {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0});
    const auto d = sss::dice_primitive(p, spacing(0.1));
    expect_well_formed(d);
    EXPECT_NEAR(total_area(d), 1.0, 1e-6);
    EXPECT_EQ(d.size(), 100u);
    for (const auto& n : d.normals) EXPECT_NEAR(n.z, 1.0f, 1e-6f);
    for (const glm::vec3 corner :
         {glm::vec3(0, 0, 0), glm::vec3(1, 0, 0), glm::vec3(0, 1, 0), glm::vec3(1, 1, 0)})
        EXPECT_NE(std::find(d.vertices.begin(), d.vertices.end(), corner),
                  d.vertices.end());
    glm::vec3 lo(1e9f);
    glm::vec3 hi(-1e9f);
    for (const auto& v : d.vertices) {
        lo = glm::min(lo, v);
        hi = glm::max(hi, v);
    }
    EXPECT_EQ(lo, glm::vec3(0, 0, 0));
    EXPECT_EQ(hi, glm::vec3(1, 1, 0));
    EXPECT_EQ(d.triangles.size(), 3u * 200u);
}

TEST(DiceParametricPatch, BicubicBezierFlatAndCurved) {
    // A flat Bezier patch with unevenly spaced control points still covers
    // exactly the unit square (non-uniform parameterisation).
    const double xs[4] = {0, 0.1, 0.6, 1};
    const double ys[4] = {0, 0.45, 0.5, 1};
    std::vector<double> cp;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) cp.insert(cp.end(), {xs[c], ys[r], 0.0});
    auto p = make_prim(PrimitiveKind::Patch);
    p.type = "bicubic";
    set_param(p, "P", sss::ParamType::Point, sss::ParamClass::Vertex, cp);
    const auto d = sss::dice_primitive(p, spacing(0.05));
    expect_well_formed(d);
    EXPECT_NEAR(total_area(d), 1.0, 1e-5);
    for (const auto& n : d.normals) EXPECT_NEAR(n.z, 1.0f, 1e-6f);

    // Same with the basis spelled out (named_basis), tilted by a transform.
    auto attr = std::make_shared<sss::Attributes>();
    attr->u_basis = *sss::named_basis("bezier");
    attr->v_basis = *sss::named_basis("bezier");
    p.attributes = attr;
    p.object_to_world = glm::rotate(sss::Matrix4(1.0), 1.0, glm::dvec3(1, 1, 0));
    EXPECT_NEAR(total_area(sss::dice_primitive(p, spacing(0.05))), 1.0, 1e-5);

    // A Bezier patch on the cylinder x^2 + z^2 = 1 is only approximately
    // circular; compare with a much finer dicing.
    const double k = 0.5522847498;
    const double arc[4][2] = {{1, 0}, {1, k}, {k, 1}, {0, 1}};
    cp.clear();
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) cp.insert(cp.end(), {arc[c][0], r / 3.0, arc[c][1]});
    auto curved = make_prim(PrimitiveKind::Patch);
    curved.type = "bicubic";
    set_param(curved, "P", sss::ParamType::Point, sss::ParamClass::Vertex, cp);
    const double coarse = total_area(sss::dice_primitive(curved, spacing(0.2)));
    const double fine = total_area(sss::dice_primitive(curved, spacing(0.01)));
    EXPECT_NEAR(coarse, fine, 1e-4 * fine);
    EXPECT_NEAR(fine, kPi / 2, 2e-3);
}

TEST(DiceParametricPatch, VaryingColorsAndNormals) {
    auto cyl = make_prim(PrimitiveKind::Cylinder, {1, 0, 1, 360});
    set_param(cyl, "Cs", sss::ParamType::Color, sss::ParamClass::Varying,
              {1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1});
    const auto d = sss::dice_primitive(cyl, spacing(0.05));
    expect_well_formed(d);
    ASSERT_EQ(d.colors.size(), d.size());
    glm::dvec3 mean(0.0);
    double area = 0.0;
    std::size_t first = 0;
    for (std::size_t i = 0; i < d.size(); ++i) {
        mean += glm::dvec3(d.colors[i]) * static_cast<double>(d.areas[i]);
        area += d.areas[i];
        if (glm::distance(d.centers[i], glm::vec3(1, 0, 0)) <
            glm::distance(d.centers[first], glm::vec3(1, 0, 0)))
            first = i;
    }
    mean /= area;
    EXPECT_NEAR(mean.x, 0.5, 1e-3);
    EXPECT_NEAR(mean.y, 0.5, 1e-3);
    EXPECT_NEAR(mean.z, 0.5, 1e-3);
    EXPECT_NEAR(d.colors[first].x, 1.0f, 0.1f); // the (u, v) = (0, 0) corner is red
    EXPECT_NEAR(d.colors[first].y, 0.0f, 0.1f);

    // User normals on a bilinear patch are used as given (here all +x).
    auto p = make_prim(PrimitiveKind::Patch);
    p.type = "bilinear";
    set_param(p, "P", sss::ParamType::Point, sss::ParamClass::Vertex,
              {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0});
    set_param(p, "N", sss::ParamType::Normal, sss::ParamClass::Varying,
              {1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0});
    const auto dn = sss::dice_primitive(p, spacing(0.25));
    for (const auto& n : dn.normals) EXPECT_NEAR(n.x, 1.0f, 1e-6f);
    for (const auto& n : dn.vertex_normals) EXPECT_NEAR(n.x, 1.0f, 1e-6f);

    set_param(p, "Cs", sss::ParamType::Color, sss::ParamClass::Varying, {1, 0, 0});
    EXPECT_THROW(sss::dice_primitive(p, spacing(0.25)), sss::ValueError);
}

TEST(DiceParametricPatch, PeriodicBsplinePatchMesh) {
    // 8 control points around the z axis (periodic in u), 4 rows up z.
    const int nu = 8;
    const int nv = 4;
    std::vector<double> cp;
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
            const double a = 2 * kPi * i / nu;
            cp.insert(cp.end(), {std::cos(a), std::sin(a), static_cast<double>(j)});
        }
    auto attr = std::make_shared<sss::Attributes>();
    attr->u_basis = *sss::named_basis("b-spline");
    attr->v_basis = *sss::named_basis("b-spline");
    auto mesh = make_prim(PrimitiveKind::PatchMesh, {}, attr);
    mesh.type = "bicubic";
    mesh.nu = nu;
    mesh.nv = nv;
    mesh.uwrap = true;
    mesh.vwrap = false;
    set_param(mesh, "P", sss::ParamType::Point, sss::ParamClass::Vertex, cp);
    const auto d = sss::dice_primitive(mesh, spacing(0.05));
    expect_well_formed(d);
    ASSERT_GT(d.size(), 1000u);
    float zlo = 1e9f;
    float zhi = -1e9f;
    for (std::size_t i = 0; i < d.size(); ++i) {
        const glm::vec3 c = d.centers[i];
        zlo = std::min(zlo, c.z);
        zhi = std::max(zhi, c.z);
        ASSERT_GT(glm::dot(d.normals[i], glm::vec3(c.x, c.y, 0.0f)), 0.0f) << i;
        ASSERT_NEAR(d.normals[i].z, 0.0f, 1e-4f);
        const float rho = std::hypot(c.x, c.y);
        ASSERT_GT(rho, 0.9f); // the uniform B-spline of a regular octagon
        ASSERT_LT(rho, 0.95f);
    }
    // The B-spline in v spans the middle segment: z from 1 to 2.
    EXPECT_NEAR(zlo, 1.0f, 0.03f);
    EXPECT_NEAR(zhi, 2.0f, 0.03f);
    EXPECT_GT(total_area(d), 2 * kPi * 0.9);
    EXPECT_LT(total_area(d), 2 * kPi * 0.95);

    // Bilinear nonperiodic mesh of a 3x2 grid: 2 unit squares.
    auto flat = make_prim(PrimitiveKind::PatchMesh);
    flat.type = "bilinear";
    flat.nu = 3;
    flat.nv = 2;
    set_param(flat, "P", sss::ParamType::Point, sss::ParamClass::Vertex,
              {0, 0, 0, 1, 0, 0, 2, 0, 0, 0, 1, 0, 1, 1, 0, 2, 1, 0});
    set_param(flat, "Cs", sss::ParamType::Color, sss::ParamClass::Uniform,
              {1, 0, 0, 0, 1, 0});
    const auto df = sss::dice_primitive(flat, spacing(0.1));
    expect_well_formed(df);
    EXPECT_NEAR(total_area(df), 2.0, 1e-5);
    for (std::size_t i = 0; i < df.size(); ++i) {
        EXPECT_EQ(df.colors[i].x, df.centers[i].x < 1.0f ? 1.0f : 0.0f);
    }
    // Facevarying: 4 values per patch, not shared across the common edge.
    set_param(flat, "Cs", sss::ParamType::Color, sss::ParamClass::FaceVarying,
              {1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0});
    const auto dfv = sss::dice_primitive(flat, spacing(0.1));
    for (std::size_t i = 0; i < dfv.size(); ++i) {
        EXPECT_EQ(dfv.colors[i].y, dfv.centers[i].x < 1.0f ? 0.0f : 1.0f);
    }

    // Bezier (step 3) needs 4 + 3k points along a nonperiodic direction.
    auto bad = mesh;
    bad.attributes = std::make_shared<sss::Attributes>();
    bad.uwrap = false;
    bad.nu = 5;
    EXPECT_THROW(sss::dice_primitive(bad, spacing(0.1)), sss::ValueError);
}

// ---------------------------------------------------------------------------
// Teapot

TEST(DiceParametricTeapot, ClassicBoundsAndStableArea) {
    const auto teapot = make_prim(PrimitiveKind::Teapot);
    const auto d = sss::dice_primitive(teapot, spacing(0.02));
    expect_well_formed(d);
    glm::vec3 lo(1e9f);
    glm::vec3 hi(-1e9f);
    for (const auto& c : d.centers) {
        lo = glm::min(lo, c);
        hi = glm::max(hi, c);
    }
    const glm::vec3 want_lo(-3.0f, -2.0f, 0.0f);
    const glm::vec3 want_hi(3.434f, 2.0f, 3.15f);
    const glm::vec3 size = want_hi - want_lo;
    for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(lo[k], want_lo[k], 0.01f * size[k]) << k;
        EXPECT_NEAR(hi[k], want_hi[k], 0.01f * size[k]) << k;
    }
    const double fine = total_area(d);
    const double coarse = total_area(sss::dice_primitive(teapot, spacing(0.1)));
    EXPECT_GT(fine, 20.0);
    EXPECT_NEAR(coarse, fine, 5e-3 * fine);
    // Outward: the body's normals point away from the z axis.
    for (std::size_t i = 0; i < d.size(); ++i) {
        const glm::vec3 c = d.centers[i];
        if (c.z > 0.5f && c.z < 2.2f && std::hypot(c.x, c.y) > 1.8f &&
            std::abs(c.x) < 1.5f) {
            ASSERT_GT(glm::dot(d.normals[i], glm::vec3(c.x, c.y, 0.0f)), 0.0f) << i;
        }
    }
}

// ---------------------------------------------------------------------------
// Errors

void expect_value_error(const sss::Primitive& prim, const sss::DiceControl& control,
                        const std::string& fragment) {
    try {
        sss::dice_primitive(prim, control);
        ADD_FAILURE() << "expected ValueError about " << fragment;
    } catch (const sss::ValueError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("scene.rib:7"), std::string::npos) << what;
        EXPECT_NE(what.find(fragment), std::string::npos) << what;
    }
}

TEST(DiceParametricErrors, NameTheSource) {
    auto patch = make_prim(PrimitiveKind::Patch);
    patch.type = "bilinear";
    expect_value_error(patch, spacing(0.1), "\"P\"");
    set_param(patch, "P", sss::ParamType::Point, sss::ParamClass::Vertex,
              {0, 0, 0, 1, 0, 0});
    expect_value_error(patch, spacing(0.1), "\"P\"");
    patch.type = "biquadratic";
    expect_value_error(patch, spacing(0.1), "type");

    expect_value_error(make_prim(PrimitiveKind::Sphere, {0, -1, 1, 360}), spacing(0.1),
                       "radius");
    expect_value_error(make_prim(PrimitiveKind::Torus, {1, -0.5, 0, 360, 360}),
                       spacing(0.1), "radius");
    expect_value_error(make_prim(PrimitiveKind::Sphere, {1, -1, 1}), spacing(0.1),
                       "arguments");
    expect_value_error(make_prim(PrimitiveKind::Cone,
                                 {1, std::numeric_limits<double>::quiet_NaN(), 360}),
                       spacing(0.1), "NaN");
    expect_value_error(make_prim(PrimitiveKind::Paraboloid, {1, 0, 0, 360}), spacing(0.1),
                       "zmax");

    sss::DiceControl few = spacing(0.01);
    few.max_micropolygons = 1000;
    for (const sss::Primitive& prim : {make_prim(PrimitiveKind::Sphere, {1, -1, 1, 360}),
                                       make_prim(PrimitiveKind::Teapot)}) {
        for (bool estimate : {false, true}) {
            try {
                if (estimate)
                    sss::estimate_primitive(prim, few);
                else
                    sss::dice_primitive(prim, few);
                ADD_FAILURE() << "expected a LimitError";
            } catch (const sss::LimitError& e) {
                const std::string what = e.what();
                EXPECT_EQ(e.which(), sss::Limit::PrimitiveMicropolygons);
                EXPECT_NE(what.find("scene.rib:7"), std::string::npos) << what;
                EXPECT_NE(what.find("exceeds the limit of 1000"), std::string::npos)
                    << what;
                EXPECT_NE(what.find("SSS_LIMIT_PRIMITIVE_MICROPOLYGONS"),
                          std::string::npos)
                    << what;
            }
        }
    }
}

} // namespace

// ---------------------------------------------------------------------------
// Grids and displacement

TEST(DiceParametricGrids, GridsCoverTheCentresWithTheirParameters) {
    sss::DiceControl c = spacing(0.05);
    c.grids = true;
    auto prim = make_prim(PrimitiveKind::Sphere, {2, -2, 2, 360});
    set_param(prim, "s", sss::ParamType::Float, sss::ParamClass::Varying, {0, 4, 0, 4});
    const auto d = sss::dice_primitive(prim, c);
    ASSERT_GT(d.size(), 1000u);
    ASSERT_EQ(d.u.size(), d.size());
    std::size_t next = 0;
    for (const sss::DicedGrid& g : d.grids) {
        EXPECT_EQ(g.first, next); // a sphere has no dropped cells
        next = g.first + g.size();
        for (std::size_t k = g.first; k < next; ++k) {
            EXPECT_GE(d.u[k], 0.0f);
            EXPECT_LE(d.u[k], 1.0f);
            EXPECT_NEAR(d.s[k], 4.0f * d.u[k], 1e-5f); // "s" varying, t defaults to v
            EXPECT_EQ(d.t[k], d.v[k]);
            // The tangents give the normal, and match the grid's steps.
            const glm::vec3 n = glm::cross(d.dPdu[k], d.dPdv[k]);
            EXPECT_GT(glm::dot(glm::normalize(n), d.normals[k]), 0.999f);
            if (k + 1 < next && (k + 1 - g.first) % g.nu != 0) {
                const glm::vec3 step = d.centers[k + 1] - d.centers[k];
                EXPECT_NEAR(glm::length(step), glm::length(d.dPdu[k]) * d.du[k],
                            0.02 * glm::length(step));
            }
        }
    }
    EXPECT_EQ(next, d.size());
}

TEST(DiceParametricGrids, DisplacementMovesVerticesAndCentresWithoutCracks) {
    // ShadingRate dicing close to the eye, so that sub-patches of different
    // grids are stitched: the stitched vertices are displaced too.
    sss::Camera cam;
    cam.perspective = true;
    cam.fov = 60;
    cam.xres = 40;
    cam.yres = 40;
    sss::DiceControl c;
    c.camera = &cam;
    c.grids = true;
    std::size_t calls = 0, points = 0;
    c.displace = [&](sss::DisplaceGrid& g) {
        ++calls;
        for (std::size_t k = 0; k < g.size(); ++k) {
            g.P[k] += 0.1f * g.N[k];
            ++points;
        }
        if (!g.grid) {
            EXPECT_EQ(g.nv, 1);
        }
    };
    auto close = make_prim(PrimitiveKind::Sphere, {1, -1, 1, 360});
    close.object_to_world = glm::translate(sss::Matrix4(1.0), glm::dvec3(0.3, 0, 1.3));
    const auto d = sss::dice_primitive(close, c);
    ASSERT_GT(d.size(), 5000u);
    EXPECT_GT(calls, 2 * d.grids.size());
    EXPECT_EQ(open_edges(d), 0u);
    const glm::vec3 centre(0.3f, 0.0f, 1.3f);
    for (const glm::vec3& v : d.vertices)
        EXPECT_NEAR(glm::length(v - centre), 1.1f, 1e-5f);
    for (const glm::vec3& p : d.centers)
        EXPECT_NEAR(glm::length(p - centre), 1.1f, 1e-5f);
    EXPECT_NEAR(total_area(d), 4 * kPi * 1.21, 4e-3 * kPi * 1.21);
}

TEST(DiceParametricGrids, VerticesCarryTheirParametersStitchedOnesToo) {
    // ShadingRate dicing close to the eye: sub-patches of different grids
    // are stitched with side vertices and fan centres, which get the (u, v,
    // s, t) of their own parameters. A sphere's are known from the position.
    sss::Camera cam;
    cam.perspective = true;
    cam.fov = 60;
    cam.xres = 40;
    cam.yres = 40;
    sss::DiceControl c;
    c.camera = &cam;
    auto close = make_prim(PrimitiveKind::Sphere, {1, -1, 1, 360});
    set_param(close, "s", sss::ParamType::Float, sss::ParamClass::Varying, {0, 4, 0, 4});
    close.object_to_world = glm::translate(sss::Matrix4(1.0), glm::dvec3(0.3, 0, 1.3));
    const auto plain = sss::dice_primitive(close, c);
    EXPECT_TRUE(plain.vertex_uvst.empty());
    c.grids = true;
    const auto d = sss::dice_primitive(close, c);
    EXPECT_EQ(d.vertices, plain.vertices); // the same triangles
    EXPECT_EQ(d.triangles, plain.triangles);
    ASSERT_EQ(d.vertex_uvst.size(), d.vertices.size());
    std::size_t grid_vertices = 0;
    for (const sss::DicedGrid& g : d.grids)
        grid_vertices += std::size_t(g.nu + 1) * std::size_t(g.nv + 1);
    EXPECT_GT(d.vertices.size(), grid_vertices); // some were stitched
    const glm::dvec3 centre(0.3, 0.0, 1.3);
    for (std::size_t k = 0; k < d.vertices.size(); ++k) {
        const glm::dvec3 p = glm::dvec3(d.vertices[k]) - centre;
        const glm::vec4& a = d.vertex_uvst[k];
        EXPECT_NEAR(a.y, (std::atan2(p.z, std::hypot(p.x, p.y)) + kPi / 2) / kPi, 1e-4)
            << k;
        EXPECT_NEAR(a.z, 4.0f * a.x, 1e-5f) << k;
        EXPECT_EQ(a.w, a.y) << k;
        if (std::hypot(p.x, p.y) < 1e-3) continue; // a pole: any u
        double u = std::atan2(p.y, p.x) / (2 * kPi);
        if (u < 0.0) u += 1.0;
        if (a.x > 0.99f && u < 0.01) u += 1.0; // the seam: u = 1 is u = 0
        EXPECT_NEAR(a.x, u, 1e-4) << k;
    }
}
