// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file dice_estimate_test.cpp
/// Tests of the dicing estimates and guards (sss/dice/dice.h, issue 15):
/// estimate_primitive within a factor of two of what dice_primitive makes,
/// for every family, at a fixed spacing and by ShadingRate; the
/// micropolygon limits (per primitive and per scene) as LimitErrors naming
/// the primitive or scene and the variable; points beyond the coordinate
/// range as errors naming the primitive; and triangle_colors' nearest
/// centre.
///
/// Suite names all start with "DiceEstimate".

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "sss/dice/dice.h"
#include "sss/scene/rib.h"
#include "sss/scene/scene.h"
#include "sss/util/error.h"
#include "sss/util/limits.h"

namespace {

/// A scene with one world of `body` under a camera 6 units away.
sss::Scene scene_of(const std::string& body) {
    return sss::parse_rib("Format 320 240 1\n"
                          "Projection \"perspective\" \"fov\" 40\n"
                          "Translate 0 0 6\n"
                          "WorldBegin\n" +
                              body + "\nWorldEnd\n",
                          "est.rib");
}

const std::vector<std::string> kBodies = {
    "Sphere 1 -1 1 360",
    "Torus 1 0.3 0 360 360",
    "Cone 1 0.5 270",
    "Disk 0 1 360",
    "Hyperboloid 1 0 -1 0.5 0.5 1 360",
    "Paraboloid 1 0 1 360",
    "Geometry \"teapot\"",
    "Patch \"bicubic\" \"P\" [0 0 0 1 0 0 2 0 0 3 0 0 0 1 1 1 1 2 2 1 2 3 1 0 "
    "0 2 0 1 2 2 2 2 1 3 2 0 0 3 0 1 3 0 2 3 0 3 3 0]",
    "PatchMesh \"bilinear\" 3 \"nonperiodic\" 3 \"nonperiodic\" \"P\" "
    "[0 0 0 1 0 0 2 0 0 0 1 0 1 1 1 2 1 0 0 2 0 1 2 0 2 2 0]",
    "Polygon \"P\" [0 0 0 2 0 0 2 1 0 1 1 0 1 2 0 0 2 0]",
    "PointsPolygons [4 4 3] [0 1 2 3 1 4 5 2 3 2 6] \"P\" "
    "[0 0 0 1 0 0 1 1 0 0 1 0 2 0 0.5 2 1 0.5 0.5 2 0.2]",
    "GeneralPolygon [4 4] \"P\" [0 0 0 3 0 0 3 3 0 0 3 0 1 1 0 2 1 0 2 2 0 1 2 0]",
    "SubdivisionMesh \"catmull-clark\" [4 4 4 4 4 4] [0 1 3 2 2 3 5 4 4 5 7 6 6 7 1 0 "
    "1 7 5 3 6 0 2 4] \"P\" [-1 -1 1 1 -1 1 -1 1 1 1 1 1 -1 1 -1 1 1 -1 -1 -1 -1 1 -1 "
    "-1]",
    "Points \"P\" [0 0 0 1 0 0 0 1 0] \"width\" [0.5 0.2 0.3]",
    "Curves \"cubic\" [4 7] \"nonperiodic\" \"P\" [0 0 0 1 1 0 2 0 0 3 1 0 "
    "0 1 1 1 2 1 2 1 1 3 2 1 4 1 1 5 2 1 6 1 1] \"constantwidth\" 0.1",
    "NuPatch 4 3 [0 0 0 1 2 2 2] 0 2 3 2 [0 0 1 1 1] 0 1 \"P\" [0 0 0 1 0 1 2 0 0 3 0 1 "
    "0 1 1 1 1 2 2 1 1 3 1 0 0 2 0 1 2 1 2 2 0 3 2 1]",
};

TEST(DiceEstimate, WithinAFactorOfTwoForEveryFamily) {
    for (const std::string& body : kBodies) {
        const sss::Scene scene = scene_of(body);
        ASSERT_EQ(scene.primitives.size(), 1u) << body;
        const sss::Primitive& prim = scene.primitives[0];
        for (const bool by_rate : {false, true}) {
            sss::DiceControl control;
            if (by_rate)
                control.camera = &scene.options.camera;
            else
                control.spacing = 0.02;
            const sss::DiceEstimate e = sss::estimate_primitive(prim, control);
            const sss::DicedSurface d = sss::dice_primitive(prim, control);
            const double mp = static_cast<double>(d.size());
            const double tris = static_cast<double>(d.triangles.size() / 3);
            const double verts = static_cast<double>(d.vertices.size());
            SCOPED_TRACE(body + (by_rate ? " (ShadingRate)" : " (spacing)"));
            EXPECT_GE(e.micropolygons, 0.5 * mp);
            EXPECT_LE(e.micropolygons, 2.0 * mp);
            EXPECT_GE(e.triangles, 0.5 * tris);
            EXPECT_LE(e.triangles, 2.5 * tris);
            EXPECT_GE(e.vertices, 0.5 * verts);
            EXPECT_LE(e.vertices, 2.5 * verts);
        }
    }
}

TEST(DiceEstimate, UnevenDicingRatesAreEstimatedRegionByRegion) {
    // A patch reaching from near the eye to 4e9 units away: most of it is
    // far and coarse. Estimating every sample cell at the finest rate would
    // ask for billions of micropolygons.
    const sss::Scene scene =
        scene_of("Patch \"bilinear\" \"P\" [-1 -1 0 1 -1 0 -1 1 0 4294967296 1 0]");
    sss::DiceControl control;
    control.camera = &scene.options.camera;
    control.coarsening = 8.0; // as render's triangles of 4 pixels: fast
    const sss::DiceEstimate e = sss::estimate_primitive(scene.primitives[0], control);
    const double mp =
        static_cast<double>(sss::dice_primitive(scene.primitives[0], control).size());
    EXPECT_GE(e.micropolygons, 0.5 * mp);
    EXPECT_LE(e.micropolygons, 3.0 * mp);
}

TEST(DiceEstimate, LimitsNameThePrimitiveTheSceneAndTheVariable) {
    const sss::Scene scene = scene_of("Sphere 1 -1 1 360\nSphere 2 -2 2 360");
    std::vector<sss::DiceRequest> requests(2);
    requests[0].primitive = 0;
    requests[1].primitive = 1;
    for (auto& r : requests) r.control.spacing = 0.05;
    // Per primitive: the second sphere alone is over 15000 (4 x the first).
    requests[0].control.max_micropolygons = requests[1].control.max_micropolygons = 15000;
    try {
        sss::estimate_dicing(scene, requests, "est.rib");
        ADD_FAILURE() << "no LimitError";
    } catch (const sss::LimitError& e) {
        EXPECT_EQ(e.which(), sss::Limit::PrimitiveMicropolygons);
        const std::string what = e.what();
        EXPECT_EQ(what.rfind("est.rib:6: Sphere: ", 0), 0u) << what;
        EXPECT_NE(what.find("SSS_LIMIT_PRIMITIVE_MICROPOLYGONS"), std::string::npos);
    }
    // The scene: both fit alone, not together.
    requests[0].control.max_micropolygons = requests[1].control.max_micropolygons = 1u
                                                                                    << 30;
    const std::vector<sss::DiceEstimate> each =
        sss::estimate_dicing(scene, requests, "est.rib");
    ASSERT_EQ(each.size(), 2u);
    EXPECT_GT(each[1].micropolygons, 3.0 * each[0].micropolygons);
    sss::set_limit(sss::Limit::SceneMicropolygons,
                   static_cast<uint64_t>(each[1].micropolygons * 1.1));
    try {
        sss::estimate_dicing(scene, requests, "est.rib");
        ADD_FAILURE() << "no LimitError";
    } catch (const sss::LimitError& e) {
        EXPECT_EQ(e.which(), sss::Limit::SceneMicropolygons);
        const std::string what = e.what();
        EXPECT_EQ(what.rfind("est.rib: ", 0), 0u) << what;
        EXPECT_NE(what.find("SSS_LIMIT_SCENE_MICROPOLYGONS"), std::string::npos) << what;
    }
    sss::set_limit(sss::Limit::SceneMicropolygons, 0);
    // The default of DiceControl is the limit in force.
    EXPECT_EQ(sss::DiceControl{}.max_micropolygons,
              sss::limit(sss::Limit::PrimitiveMicropolygons));
}

TEST(DiceEstimate, PointsBeyondTheCoordinateRangeNameThePrimitive) {
    const std::vector<std::string> bodies = {
        "Scale 1e20 1e20 1e20 Sphere 1 -1 1 360",
        "Polygon \"P\" [0 0 0 1 0 0 0 2e18 0]",
        "Patch \"bilinear\" \"Pw\" [0 0 0 1 1 0 0 1 0 1 0 1 1 1 0 1e-30]",
        "Translate 0 0 5e18 Geometry \"teapot\"",
        "SubdivisionMesh \"catmull-clark\" [4] [0 1 2 3] \"P\" [0 0 0 1 0 0 1 1 0 0 1 "
        "3e18]",
    };
    for (const std::string& body : bodies) {
        const sss::Scene scene = scene_of(body);
        sss::DiceControl control;
        control.spacing = 1e17;
        for (const bool estimate : {false, true}) {
            SCOPED_TRACE(body + (estimate ? " (estimate)" : " (dice)"));
            try {
                if (estimate)
                    sss::estimate_primitive(scene.primitives[0], control);
                else
                    sss::dice_primitive(scene.primitives[0], control);
                ADD_FAILURE() << "no ValueError";
            } catch (const sss::ValueError& e) {
                const std::string what = e.what();
                EXPECT_EQ(what.rfind("est.rib:", 0), 0u) << what;
                EXPECT_NE(what.find("beyond the coordinate range"), std::string::npos)
                    << what;
            }
        }
    }
}

TEST(DiceEstimate, TriangleColorsTakeTheNearestCentre) {
    // Uneven micropolygons (one corner 4e9 away) used to put every centre
    // into one hash cell; the k-d tree still finds each triangle's own
    // micropolygon: the colours vary over the patch as Cs does.
    const sss::Scene scene =
        scene_of("Patch \"bilinear\" \"P\" [-1 -1 0 1 -1 0 -1 1 0 4294967296 1 0] "
                 "\"Cs\" [1 0 0 0 1 0 0 0 1 1 1 1]");
    sss::DiceControl control;
    control.camera = &scene.options.camera;
    control.coarsening = 32.0;
    const sss::DicedSurface d = sss::dice_primitive(scene.primitives[0], control);
    const std::vector<glm::vec3> colors = sss::triangle_colors(d);
    ASSERT_EQ(colors.size(), d.triangles.size() / 3);
    ASSERT_GT(colors.size(), 1000u);
    std::size_t checked = 0;
    for (std::size_t t = 0; t < colors.size(); t += colors.size() / 50) {
        const glm::vec3 c =
            (d.vertices[d.triangles[3 * t]] + d.vertices[d.triangles[3 * t + 1]] +
             d.vertices[d.triangles[3 * t + 2]]) /
            3.0f;
        float best = INFINITY;
        for (std::size_t i = 0; i < d.size(); ++i) {
            const glm::vec3 e = d.centers[i] - c;
            best = std::min(best, glm::dot(e, e));
        }
        // The colour is one of a centre at the nearest distance.
        bool found = false;
        for (std::size_t i = 0; i < d.size() && !found; ++i) {
            const glm::vec3 e = d.centers[i] - c;
            found = glm::dot(e, e) == best && d.colors[i] == colors[t];
        }
        EXPECT_TRUE(found) << "triangle " << t;
        ++checked;
    }
    EXPECT_GT(checked, 10u);
}

} // namespace
