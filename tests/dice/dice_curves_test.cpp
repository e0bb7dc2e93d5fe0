// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file dice_curves_test.cpp
/// Tests of Points and Curves (dice_curves.cpp): disks and ribbons of the
/// given width facing the camera (or oriented by "N"), their exact areas,
/// primitive variables by storage class, default texture coordinates along
/// and across a curve, and the errors that name the statement.
///
/// Suite names all start with "DiceCurves".

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include <glm/geometric.hpp>

#include "sss/dice/dice.h"
#include "sss/scene/rib.h"
#include "sss/scene/scene.h"
#include "sss/util/error.h"

namespace {

/// A scene with `body` in its world, the eye 6 units in front at (0, 0, -6).
sss::Scene scene_of(const std::string& body) {
    return sss::parse_rib("Format 320 240 1\n"
                          "Projection \"perspective\" \"fov\" 40\n"
                          "Translate 0 0 6\n"
                          "WorldBegin\n" +
                              body + "\nWorldEnd\n",
                          "curves.rib");
}

sss::DicedSurface dice(const sss::Scene& scene, double spacing = 0.01,
                       bool grids = false) {
    sss::DiceControl control;
    control.spacing = spacing;
    control.camera = &scene.options.camera;
    control.grids = grids;
    return sss::dice_primitive(scene.primitives.at(0), control);
}

double total_area(const sss::DicedSurface& d) {
    double a = 0.0;
    for (float x : d.areas) a += x;
    return a;
}

/// The smallest cosine between a micropolygon's normal and the direction
/// from its centre to the eye, that direction taken across `tangent` (a
/// ribbon turns towards the eye about its curve; zero tangent: disks).
double worst_facing(const sss::DicedSurface& d, glm::dvec3 tangent = glm::dvec3(0.0)) {
    const glm::dvec3 eye(0.0, 0.0, -6.0);
    double worst = 1.0;
    for (std::size_t k = 0; k < d.size(); ++k) {
        glm::dvec3 to_eye = eye - glm::dvec3(d.centers[k]);
        to_eye = glm::normalize(to_eye - glm::dot(to_eye, tangent) * tangent);
        worst = std::min(worst, glm::dot(glm::dvec3(d.normals[k]), to_eye));
    }
    return worst;
}

TEST(DiceCurves, PointsAreDisksOfTheirWidthFacingTheEye) {
    const sss::Scene scene = scene_of("Rotate 50 0 1 0\n"
                                      "Points \"P\" [0 0 0 1 0 0 0 1 0] "
                                      "\"width\" [0.5 0.2 0.3]");
    const sss::DicedSurface d = dice(scene);
    const double disks = std::numbers::pi / 4 * (0.25 + 0.04 + 0.09);
    EXPECT_NEAR(total_area(d), disks, 1e-4 * disks);
    EXPECT_GT(worst_facing(d), 0.999);
    ASSERT_FALSE(d.triangles.empty());
}

TEST(DiceCurves, PointsWithNormalsAreOrientedDisksAndCarryTheirColours) {
    const sss::Scene scene =
        scene_of("Points \"P\" [0 0 0 2 0 0] \"constantwidth\" [0.4] "
                 "\"N\" [0 1 0 1 0 0] \"Cs\" [1 0 0 0 0 1]");
    const sss::DicedSurface d = dice(scene);
    ASSERT_EQ(d.colors.size(), d.size());
    EXPECT_NEAR(total_area(d), 2 * std::numbers::pi * 0.04, 1e-5);
    for (std::size_t k = 0; k < d.size(); ++k) {
        const bool first = d.centers[k].x < 1.0f;
        const glm::vec3 n = first ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
        EXPECT_GT(glm::dot(d.normals[k], n), 0.9999f);
        EXPECT_EQ(d.colors[k], first ? glm::vec3(1, 0, 0) : glm::vec3(0, 0, 1));
    }
}

TEST(DiceCurves, ALinearCurveIsARibbonFacingTheEyeWithInterpolatedColours) {
    const sss::Scene scene = scene_of("Curves \"linear\" [3] \"nonperiodic\" "
                                      "\"P\" [-1 0 0 0 0 0 1 0 0] \"constantwidth\" 0.1 "
                                      "\"Cs\" [0 0 0 1 1 1 0 0 0]");
    const sss::DicedSurface d = dice(scene);
    EXPECT_NEAR(total_area(d), 2 * 0.1, 1e-5);
    EXPECT_GT(worst_facing(d, glm::dvec3(1, 0, 0)), 0.9999);
    ASSERT_EQ(d.colors.size(), d.size());
    // Varying Cs runs linearly from the ends (0) to the middle vertex (1).
    for (std::size_t k = 0; k < d.size(); ++k)
        EXPECT_NEAR(d.colors[k].x, 1.0 - std::abs(d.centers[k].x), 0.01);
}

TEST(DiceCurves, ACubicCurveTapersWithItsVaryingWidth) {
    // A straight Bezier segment of length 3 whose width goes 0.1 -> 0.3:
    // the ribbon is a trapezoid of area 3 * 0.2, seen edge-on never.
    const sss::Scene scene = scene_of("Curves \"cubic\" [4] \"nonperiodic\" "
                                      "\"P\" [0 -1.5 0 0 -0.5 0 0 0.5 0 0 1.5 0] "
                                      "\"width\" [0.1 0.3]");
    const sss::DicedSurface d = dice(scene, 0.01, true);
    EXPECT_NEAR(total_area(d), 0.6, 1e-4);
    EXPECT_GT(worst_facing(d, glm::dvec3(0, 1, 0)), 0.999);
    // Default texture coordinates: s across the ribbon, t from 0 at the
    // curve's start to 1 at its end.
    ASSERT_EQ(d.t.size(), d.size());
    for (std::size_t k = 0; k < d.size(); ++k) {
        EXPECT_NEAR(d.t[k], (d.centers[k].y + 1.5) / 3.0, 0.01);
        EXPECT_GE(d.s[k], 0.0f);
        EXPECT_LE(d.s[k], 1.0f);
    }
}

TEST(DiceCurves, CurvesWithNormalsAndPeriodicBSplines) {
    // A closed b-spline loop in the z = 0 plane, its ribbon lying in the
    // plane (N along z): every normal is +-z... as N says, +z.
    const sss::Scene scene =
        scene_of("Basis \"b-spline\" 1 \"b-spline\" 1\n"
                 "Curves \"cubic\" [4] \"periodic\" "
                 "\"P\" [1 0 0 0 1 0 -1 0 0 0 -1 0] "
                 "\"constantwidth\" 0.05 \"N\" [0 0 1 0 0 1 0 0 1 0 0 1]");
    const sss::DicedSurface d = dice(scene);
    ASSERT_GT(d.size(), 10u);
    for (const glm::vec3& n : d.normals) EXPECT_GT(n.z, 0.9999f);
    // The loop closes: its length (area / width) is that of a smooth closed
    // curve around the origin, some 2 pi r for r between 0.5 and 0.7.
    const double length = total_area(d) / 0.05;
    EXPECT_GT(length, 2 * std::numbers::pi * 0.5);
    EXPECT_LT(length, 2 * std::numbers::pi * 0.7);
}

TEST(DiceCurves, BadCurvesAreErrorsNamingTheStatement) {
    const auto message = [](const std::string& body) {
        try {
            const sss::Scene scene = scene_of(body);
            (void)dice(scene);
        } catch (const sss::Error& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    // Bezier curves need 4 + 3k vertices.
    EXPECT_NE(message("Curves \"cubic\" [5] \"nonperiodic\" \"P\" [0 0 0 1 0 0 2 0 0 3 0 "
                      "0 4 0 0]")
                  .find("curves.rib:5: Curves"),
              std::string::npos);
    EXPECT_NE(message("Curves \"quintic\" [2] \"nonperiodic\" \"P\" [0 0 0 1 0 0]")
                  .find("curve type must be linear or cubic"),
              std::string::npos);
    EXPECT_NE(message("Curves \"linear\" [2] \"nonperiodic\" \"P\" [0 0 0 1 0 0] "
                      "\"width\" [1 2 3]")
                  .find("\"width\""),
              std::string::npos);
    EXPECT_NE(message("Points \"P\" [0 0 0] \"constantwidth\" -1").find("width"),
              std::string::npos);
    EXPECT_NE(message("Points \"P\" []").find("curves.rib:5: Points"), std::string::npos);
}

} // namespace
