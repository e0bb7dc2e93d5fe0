// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file dice_motion_test.cpp
/// Tests of dicing a moving primitive (dice_moving, DiceJournal): one set of
/// triangles for every time step, the vertices of each step on the surface
/// as it is at that time (a moving transform, a growing sphere, a deforming
/// subdivision mesh under a perspective camera whose dicing rates would
/// differ), and the error when a deformation changes the triangulation.
///
/// Suite names all start with "DiceMotion".

#include <gtest/gtest.h>

#include <cmath>
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
                          "motion.rib");
}

sss::DiceControl camera_control(const sss::Scene& scene) {
    sss::DiceControl control;
    control.camera = &scene.options.camera;
    return control;
}

} // namespace

TEST(DiceMotion, MovingTransformMovesEveryVertex) {
    const sss::Scene scene = scene_of("MotionBegin [0 1]\nTranslate 0 0 0\n"
                                      "Translate 1 0 -3\nMotionEnd\n"
                                      "Sphere 1 -1 1 360\n");
    const sss::Primitive& prim = scene.primitives.at(0);
    const sss::DicedSurface d =
        sss::dice_moving(prim, camera_control(scene), {0.0, 0.5, 1.0});
    ASSERT_EQ(d.step_vertices.size(), 2u);
    ASSERT_TRUE(d.moving());
    ASSERT_GT(d.triangles.size(), 300u);
    for (std::size_t i = 0; i < d.vertices.size(); ++i) {
        const glm::vec3 offset(1.0f, 0.0f, -3.0f);
        EXPECT_NEAR(glm::distance(d.step_vertices[1][i], d.vertices[i] + offset), 0.0f,
                    1e-5f);
        EXPECT_NEAR(glm::distance(d.step_vertices[0][i], d.vertices[i] + 0.5f * offset),
                    0.0f, 1e-5f);
        // Half way between steps 1 and 2 (time 0.75 of the whole).
        EXPECT_NEAR(glm::distance(d.vertex_at(uint32_t(i), 0.75f),
                                  d.vertices[i] + 0.75f * offset),
                    0.0f, 1e-5f);
        EXPECT_NEAR(glm::length(d.normal_at(uint32_t(i), 1.0f)), 1.0f, 1e-4f);
    }
}

TEST(DiceMotion, GrowingSphereHasItsRadiusAtEveryStep) {
    const sss::Scene scene = scene_of("MotionBegin [0 1]\nSphere 1 -1 1 360\n"
                                      "Sphere 2 -2 2 360\nMotionEnd\n");
    const sss::DicedSurface d =
        sss::dice_moving(scene.primitives.at(0), camera_control(scene), {0.0, 1.0});
    ASSERT_EQ(d.step_vertices.size(), 1u);
    // The same triangles; a sphere of radius 2 diced as the one of radius 1.
    const sss::DicedSurface big = sss::dice_primitive(
        sss::primitive_at(scene.primitives.at(0), 1.0), camera_control(scene));
    EXPECT_GT(big.triangles.size(), d.triangles.size());
    for (std::size_t i = 0; i < d.vertices.size(); ++i) {
        EXPECT_NEAR(glm::length(d.vertices[i]), 1.0f, 1e-4f);
        EXPECT_NEAR(glm::length(d.step_vertices[0][i]), 2.0f, 2e-4f);
    }
}

TEST(DiceMotion, DeformingSubdivisionMeshKeepsItsTriangles) {
    // The far face moves away: its dicing rate would drop at the later time.
    const std::string cube_faces =
        "[4 4 4 4 4 4] [0 1 3 2 2 3 5 4 4 5 7 6 6 7 1 0 1 7 5 3 "
        "6 0 2 4] [\"interpolateboundary\"] [0 0] [] []";
    const sss::Scene scene =
        scene_of("MotionBegin [0 1]\n"
                 "SubdivisionMesh \"catmull-clark\" " +
                 cube_faces +
                 " \"P\" [-1 -1 1 1 -1 1 -1 1 1 1 1 1 -1 1 -1 1 1 -1 -1 -1 -1 1 -1 -1]\n"
                 "SubdivisionMesh \"catmull-clark\" " +
                 cube_faces +
                 " \"P\" [-1 -1 4 1 -1 4 -1 1 4 1 1 4 -1 1 -1 1 1 -1 -1 -1 -1 1 -1 -1]\n"
                 "MotionEnd\n");
    const sss::DicedSurface d =
        sss::dice_moving(scene.primitives.at(0), camera_control(scene), {0.0, 1.0});
    ASSERT_EQ(d.step_vertices.size(), 1u);
    float zmax0 = -1e9f, zmax1 = -1e9f;
    for (std::size_t i = 0; i < d.vertices.size(); ++i) {
        zmax0 = std::max(zmax0, d.vertices[i].z);
        zmax1 = std::max(zmax1, d.step_vertices[0][i].z);
    }
    EXPECT_LT(zmax0, 1.0f);
    EXPECT_GT(zmax1, 2.0f);
}

TEST(DiceMotion, ReplayingMoreChoicesThanRecordedIsAnError) {
    sss::DiceJournal journal;
    EXPECT_EQ(journal.note(3.0, "x.rib:1"), 3.0);
    journal.replay();
    EXPECT_EQ(journal.note(5.0, "x.rib:1"), 3.0);
    EXPECT_TRUE(journal.replayed_all());
    EXPECT_THROW(journal.note(5.0, "x.rib:1"), sss::ValueError);
}

TEST(DiceMotion, TriangulationThatChangesIsAnErrorNamingThePrimitive) {
    // A quad that folds from convex to concave: its triangulation flips.
    const sss::Scene scene =
        scene_of("MotionBegin [0 1]\n"
                 "GeneralPolygon [5] \"P\" [0 0 0 2 0 0 2 2 0 1 1.5 0 0 2 0]\n"
                 "GeneralPolygon [5] \"P\" [0 0 0 2 0 0 2 2 0 1 0.2 0 0 2 0]\n"
                 "MotionEnd\n");
    sss::DiceControl control;
    control.spacing = 10.0; // one piece: the triangulation alone decides
    try {
        sss::dice_moving(scene.primitives.at(0), control, {0.0, 1.0});
        SUCCEED(); // the same triangles at both times is fine too
    } catch (const sss::ValueError& e) {
        EXPECT_NE(std::string(e.what()).find("motion.rib:6"), std::string::npos)
            << e.what();
    }
}
