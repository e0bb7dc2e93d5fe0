// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file rib_motion_test.cpp
/// Tests of motion blur in the RIB (rib_motion.cpp): Shutter, transformation
/// blocks (a moving CTM, composed with later transformations and with
/// ObjectInstance), deformation blocks (one primitive with a shape per time),
/// primitive_at's interpolation, a moving camera, and the errors that name
/// the statement.
///
/// Suite names all start with "RibMotion".

#include <gtest/gtest.h>

#include <string>

#include <glm/vec4.hpp>

#include "sss/scene/rib.h"
#include "sss/scene/scene.h"
#include "sss/util/error.h"

namespace {

sss::Scene scene_of(const std::string& options, const std::string& world) {
    return sss::parse_rib(options + "\nWorldBegin\n" + world + "\nWorldEnd\n", "m.rib");
}

glm::dvec3 origin_of(const sss::Matrix4& m) {
    return glm::dvec3(m * glm::dvec4(0.0, 0.0, 0.0, 1.0));
}

std::string error_of(const std::string& options, const std::string& world,
                     bool lenient = false) {
    sss::RibReadOptions o;
    o.lenient = lenient;
    try {
        sss::parse_rib(options + "\nWorldBegin\n" + world + "\nWorldEnd\n", "m.rib", o);
    } catch (const std::exception& e) {
        return e.what();
    }
    return "";
}

} // namespace

TEST(RibMotion, ShutterIsReadAndChecked) {
    const sss::Scene s = scene_of("Shutter 0.25 0.75", "");
    EXPECT_DOUBLE_EQ(s.options.camera.shutter_open, 0.25);
    EXPECT_DOUBLE_EQ(s.options.camera.shutter_close, 0.75);
    EXPECT_TRUE(s.options.camera.motion_blur());
    EXPECT_FALSE(scene_of("", "").options.camera.motion_blur());
    EXPECT_NE(error_of("Shutter 1 0", "").find("closes"), std::string::npos);
}

TEST(RibMotion, MovingTransformGivesEveryLaterPrimitiveItsMotion) {
    const sss::Scene s = scene_of("", "AttributeBegin\n"
                                      "MotionBegin [0 1]\n"
                                      "Translate 0 0 0\n"
                                      "Translate 2 0 0\n"
                                      "MotionEnd\n"
                                      "Scale 2 2 2\n"
                                      "Sphere 1 -1 1 360\n"
                                      "AttributeEnd\n"
                                      "Sphere 1 -1 1 360\n");
    ASSERT_EQ(s.primitives.size(), 2u);
    const sss::Primitive& moving = s.primitives[0];
    ASSERT_TRUE(moving.motion);
    ASSERT_EQ(moving.motion->transform_times.size(), 2u);
    EXPECT_EQ(origin_of(moving.motion->transforms[0]), glm::dvec3(0.0));
    EXPECT_EQ(origin_of(moving.motion->transforms[1]), glm::dvec3(2.0, 0.0, 0.0));
    // The Scale after the block applies at every time.
    EXPECT_DOUBLE_EQ(moving.motion->transforms[1][0][0], 2.0);
    EXPECT_EQ(moving.object_to_world, moving.motion->transforms[0]);
    // Half way: half way along, the transform interpolated linearly.
    const sss::Primitive half = sss::primitive_at(moving, 0.5);
    EXPECT_FALSE(half.motion);
    EXPECT_NEAR(origin_of(half.object_to_world).x, 1.0, 1e-12);
    EXPECT_NEAR(origin_of(sss::primitive_at(moving, 7.0).object_to_world).x, 2.0, 1e-12);
    // AttributeEnd restores the CTM, which did not move.
    EXPECT_FALSE(s.primitives[1].motion);
}

TEST(RibMotion, DeformationKeepsOneShapePerTime) {
    const sss::Scene s = scene_of("", "MotionBegin [0 0.5 1]\n"
                                      "Polygon \"P\" [0 0 0 1 0 0 1 1 0]\n"
                                      "Polygon \"P\" [0 0 0 2 0 0 1 1 0]\n"
                                      "Polygon \"P\" [0 0 0 4 0 0 1 1 0]\n"
                                      "MotionEnd\n"
                                      "MotionBegin [0 1]\n"
                                      "Sphere 1 -1 1 360\n"
                                      "Sphere 3 -3 3 360\n"
                                      "MotionEnd\n");
    ASSERT_EQ(s.primitives.size(), 2u);
    const sss::Primitive& poly = s.primitives[0];
    ASSERT_TRUE(poly.motion);
    EXPECT_TRUE(poly.motion->transform_times.empty());
    ASSERT_EQ(poly.motion->shape_params.size(), 3u);
    // Between samples 0.5 and 1: x of the second point from 2 to 4.
    const sss::Primitive at = sss::primitive_at(poly, 0.75);
    EXPECT_DOUBLE_EQ(at.params.find("P")->numbers[3], 3.0);
    EXPECT_DOUBLE_EQ(sss::primitive_at(poly, 0.25).params.find("P")->numbers[3], 1.5);
    EXPECT_DOUBLE_EQ(sss::primitive_at(poly, -1.0).params.find("P")->numbers[3], 1.0);
    const sss::Primitive sphere = sss::primitive_at(s.primitives[1], 0.5);
    EXPECT_DOUBLE_EQ(sphere.args[0], 2.0);
    EXPECT_DOUBLE_EQ(sphere.args[1], -2.0);
}

TEST(RibMotion, ObjectInstanceUnderAMovingTransformMoves) {
    const sss::Scene s = scene_of("", "ObjectBegin \"o\"\n"
                                      "Translate 0 1 0\n"
                                      "Sphere 1 -1 1 360\n"
                                      "ObjectEnd\n"
                                      "MotionBegin [0 1]\n"
                                      "Translate 0 0 0\n"
                                      "Translate 4 0 0\n"
                                      "MotionEnd\n"
                                      "ObjectInstance \"o\"\n");
    ASSERT_EQ(s.primitives.size(), 1u);
    const sss::Primitive& p = s.primitives[0];
    ASSERT_TRUE(p.motion);
    EXPECT_EQ(origin_of(p.motion->transforms[0]), glm::dvec3(0.0, 1.0, 0.0));
    EXPECT_EQ(origin_of(p.motion->transforms[1]), glm::dvec3(4.0, 1.0, 0.0));
}

TEST(RibMotion, MovingCameraKeepsWorldToCameraPerTime) {
    const sss::Scene s = scene_of("Shutter 0 1\n"
                                  "MotionBegin [0 1]\n"
                                  "Translate 0 0 5\n"
                                  "Translate 1 0 5\n"
                                  "MotionEnd",
                                  "");
    const sss::Camera& cam = s.options.camera;
    ASSERT_EQ(cam.motion_times.size(), 2u);
    EXPECT_EQ(origin_of(cam.motion_world_to_camera[1]), glm::dvec3(1.0, 0.0, 5.0));
    EXPECT_EQ(cam.world_to_camera, cam.motion_world_to_camera[0]);
}

TEST(RibMotion, MalformedBlocksAreErrorsNamingTheStatement) {
    // One request per time.
    EXPECT_NE(error_of("", "MotionBegin [0 1]\nTranslate 1 0 0\nMotionEnd")
                  .find("m.rib:5: MotionEnd: MotionBegin gave 2 times but its block "
                        "holds 1 request"),
              std::string::npos);
    EXPECT_NE(error_of("", "MotionBegin [0 1]\nTranslate 1 0 0\nTranslate 1 0 0\n"
                           "Translate 1 0 0\nMotionEnd")
                  .find("m.rib:6: Translate"),
              std::string::npos);
    // Times increase; one kind of request; no nesting.
    EXPECT_NE(error_of("", "MotionBegin [1 0]\nMotionEnd").find("times must increase"),
              std::string::npos);
    EXPECT_NE(
        error_of("", "MotionBegin [0 1]\nTranslate 1 0 0\nRotate 1 0 0 1\nMotionEnd")
            .find("one kind of request"),
        std::string::npos);
    EXPECT_NE(error_of("", "MotionBegin [0 1]\nMotionBegin [0 1]\n").find("nested"),
              std::string::npos);
    // Deformation keeps the topology.
    EXPECT_NE(error_of("", "MotionBegin [0 1]\nPolygon \"P\" [0 0 0 1 0 0 1 1 0]\n"
                           "Polygon \"P\" [0 0 0 1 0 0 1 1 0 0 1 0]\nMotionEnd")
                  .find("same topology"),
              std::string::npos);
}

TEST(RibMotion, OtherRequestsCannotMoveUnlessReadLeniently) {
    const std::string world = "MotionBegin [0 1]\nColor 1 0 0\nColor 0 1 0\nMotionEnd\n"
                              "Sphere 1 -1 1 360";
    EXPECT_NE(error_of("", world).find("motion blur of Color is not supported"),
              std::string::npos);
    sss::RibReadOptions lenient;
    lenient.lenient = true;
    const sss::Scene s =
        sss::parse_rib("WorldBegin\n" + world + "\nWorldEnd\n", "m.rib", lenient);
    ASSERT_EQ(s.primitives.size(), 1u);
    // The first time sample.
    EXPECT_EQ(sss::attributes_of(s.primitives[0]).color, glm::dvec3(1.0, 0.0, 0.0));
    EXPECT_FALSE(s.warnings.empty());
}
