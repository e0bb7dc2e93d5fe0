// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file dice_nurbs_test.cpp
/// Tests of NuPatch and TrimCurve (dice_nurbs.cpp): a NuPatch with Bezier
/// knots is the bicubic patch, a rational quadratic NuPatch is an exact
/// cylinder, parameters are knot values, vertex-class colours interpolate
/// like the points, and trim loops cut holes (or keep only their inside)
/// of the right area; bad knots are errors naming the statement.
///
/// Suite names all start with "DiceNurbs".

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

sss::Scene scene_of(const std::string& body) {
    return sss::parse_rib("Format 320 240 1\n"
                          "Projection \"perspective\" \"fov\" 40\n"
                          "Translate 0 0 6\n"
                          "WorldBegin\n" +
                              body + "\nWorldEnd\n",
                          "nurbs.rib");
}

sss::DicedSurface dice(const sss::Primitive& prim, bool grids = false) {
    sss::DiceControl control;
    control.spacing = 0.01;
    control.grids = grids;
    return sss::dice_primitive(prim, control);
}

double total_area(const sss::DicedSurface& d) {
    double a = 0.0;
    for (float x : d.areas) a += x;
    return a;
}

const std::string kPoints = "\"P\" [0 0 0 1 0 0.3 2 0 0 3 0 0.2  0 1 1 1 1 2 2 1 2 3 1 0 "
                            "0 2 0 1 2 2 2 2 1 3 2 0  0 3 0 1 3 0 2 3 0.5 3 3 0]";

TEST(DiceNurbs, BezierKnotsGiveTheBicubicPatch) {
    const sss::Scene scene =
        scene_of("NuPatch 4 4 [0 0 0 0 1 1 1 1] 0 1 4 4 [0 0 0 0 1 1 1 1] 0 1 " +
                 kPoints + "\nPatch \"bicubic\" " + kPoints);
    ASSERT_EQ(scene.primitives.size(), 2u);
    const double nurbs = total_area(dice(scene.primitives[0]));
    const double patch = total_area(dice(scene.primitives[1]));
    EXPECT_NEAR(nurbs, patch, 1e-6 * patch);
    EXPECT_GT(patch, 9.0);
}

TEST(DiceNurbs, ARationalQuadraticIsAnExactQuarterCylinderWithKnotParameters) {
    // A quarter circle of radius 1 (weights 1, 1/sqrt 2, 1) swept 2 along z,
    // over knots from 2 to 3 in u and 0 to 5 in v.
    const double s = std::sqrt(0.5);
    const std::string w = std::to_string(s);
    const std::string pw = "\"Pw\" [1 0 0 1  " + w + " " + w + " 0 " + w +
                           "  0 1 0 1  "
                           "1 0 " +
                           std::to_string(2.0) + " 1  " + w + " " + w + " " +
                           std::to_string(2 * s) + " " + w + "  0 1 2 1]";
    const sss::Scene scene =
        scene_of("NuPatch 3 3 [2 2 2 3 3 3] 2 3 2 2 [0 0 5 5] 0 5 " + pw +
                 " \"vertex color Cs\" [1 0 0 1 0 0 1 0 0 0 0 1 0 0 1 0 0 1]");
    const sss::DicedSurface d = dice(scene.primitives.at(0), true);
    EXPECT_NEAR(total_area(d), std::numbers::pi / 2 * 2, 1e-4);
    for (std::size_t k = 0; k < d.size(); ++k) {
        const glm::vec3& c = d.centers[k];
        EXPECT_NEAR(std::hypot(c.x, c.y), 1.0, 1e-5);
        EXPECT_GE(d.u[k], 2.0f);
        EXPECT_LE(d.u[k], 3.0f);
        EXPECT_GE(d.v[k], 0.0f);
        EXPECT_LE(d.v[k], 5.0f);
        // Cs runs from red at z = 0 to blue at z = 2 with the points.
        EXPECT_NEAR(d.colors[k].z, c.z / 2.0, 1e-4);
    }
}

/// A unit-square bilinear NuPatch trimmed by a circle of radius 0.25 in
/// (u, v) (a rational quadratic loop).
std::string trimmed(const std::string& sense) {
    return sense +
           "TrimCurve [1] [3] [0 0 0 0.25 0.25 0.5 0.5 0.75 0.75 1 1 1] [0] [1] [9] "
           "[0.75 0.530330086 0.5 0.176776695 0.25 0.176776695 0.5 0.530330086 0.75] "
           "[0.5 0.530330086 0.75 0.530330086 0.5 0.176776695 0.25 0.176776695 0.5] "
           "[1 0.707106781 1 0.707106781 1 0.707106781 1 0.707106781 1]\n"
           "NuPatch 2 2 [0 0 1 1] 0 1 2 2 [0 0 1 1] 0 1 \"P\" [0 0 0 1 0 0 0 1 0 1 1 0]";
}

TEST(DiceNurbs, TrimCurvesCutHolesOrKeepTheirInside) {
    const double hole = std::numbers::pi / 16;
    const sss::DicedSurface cut = dice(scene_of(trimmed("")).primitives.at(0));
    EXPECT_NEAR(total_area(cut), 1.0 - hole, 0.01);
    EXPECT_TRUE(cut.u.empty()); // the parametric data made for the trim is gone
    const sss::DicedSurface kept =
        dice(scene_of(trimmed("Attribute \"trimcurve\" \"sense\" \"outside\"\n"))
                 .primitives.at(0),
             true);
    EXPECT_NEAR(total_area(kept), hole, 0.01);
    for (std::size_t k = 0; k < kept.size(); ++k)
        EXPECT_LT(std::hypot(kept.u[k] - 0.5, kept.v[k] - 0.5), 0.25);
    // Triangles follow: the ray-traced surface has the hole too.
    EXPECT_LT(cut.triangles.size(),
              dice(scene_of("NuPatch 2 2 [0 0 1 1] 0 1 2 2 [0 0 1 1] "
                            "0 1 \"P\" [0 0 0 1 0 0 0 1 0 1 1 0]")
                       .primitives.at(0))
                  .triangles.size());
}

TEST(DiceNurbs, BadKnotsAndCountsAreErrorsNamingTheStatement) {
    const auto message = [](const std::string& body) {
        try {
            (void)scene_of(body);
        } catch (const sss::Error& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    const std::string p = "\"P\" [0 0 0 1 0 0 0 1 0 1 1 0]";
    EXPECT_NE(message("NuPatch 2 2 [0 1 0 1] 0 1 2 2 [0 0 1 1] 0 1 " + p)
                  .find("must not decrease"),
              std::string::npos);
    EXPECT_NE(message("NuPatch 2 2 [0 0 1] 0 1 2 2 [0 0 1 1] 0 1 " + p)
                  .find("uknot has 3 knots"),
              std::string::npos);
    EXPECT_NE(message("NuPatch 2 2 [0 0 1 1] 0 2 2 2 [0 0 1 1] 0 1 " + p).find("range"),
              std::string::npos);
    EXPECT_NE(message("NuPatch 2 2 [0 0 1 1] 0 1 2 2 [0 0 1 1] 0 1 \"P\" [0 0 0]")
                  .find("nurbs.rib:5: NuPatch"),
              std::string::npos);
    EXPECT_NE(message("TrimCurve [1] [2] [0 0 1 1] [0] [1] [2] [0 1] [0 1] [1 0]")
                  .find("w must be"),
              std::string::npos);
}

} // namespace
