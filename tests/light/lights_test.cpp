// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file lights_test.cpp
/// Tests of the ray tracer (sss/ray_tracer.h), the standard light shaders and
/// irradiance (sss/lights.h) and noise3(): hand-computed irradiance for every
/// light kind, transforms, hard and soft ray-traced shadows, batch against
/// scalar evaluation, and the noise's range and continuity.
///
/// Suite names start with "Lights" or "RayTracer".

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "sss/light/lights.h"
#include "sss/light/ray_tracer.h"
#include "sss/light/shadow_map.h"
#include "sss/scene/scene.h"
#include "sss/util/error.h"

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kTol = 1e-12;

double radians(double degrees) {
    return degrees * kPi / 180.0;
}

sss::Param float_param(const std::string& name, double v) {
    sss::Param p;
    p.name = name;
    p.type = sss::ParamType::Float;
    p.numbers = {v};
    return p;
}

sss::Param vec_param(const std::string& name, sss::ParamType type, glm::dvec3 v) {
    sss::Param p;
    p.name = name;
    p.type = type;
    p.numbers = {v.x, v.y, v.z};
    return p;
}

sss::Param point_param(const std::string& name, glm::dvec3 v) {
    return vec_param(name, sss::ParamType::Point, v);
}

sss::Param string_param(const std::string& name, const std::string& v) {
    sss::Param p;
    p.name = name;
    p.type = sss::ParamType::String;
    p.strings = {v};
    return p;
}

/// A scene holding one light shader call.
sss::Scene one_light(const std::string& shader, std::vector<sss::Param> params,
                     const sss::Matrix4& shader_to_world = sss::Matrix4(1.0)) {
    sss::Scene scene;
    sss::LightInstance light;
    light.shader.name = shader;
    for (auto& p : params) light.shader.params.set(p);
    light.shader.shader_to_world = shader_to_world;
    light.shader.source = "test.rib:7";
    light.handle = "1";
    scene.lights.push_back(light);
    return scene;
}

std::vector<sss::Light> resolve(const sss::Scene& scene,
                                std::vector<std::string>* warnings = nullptr) {
    std::vector<std::string> local;
    return sss::resolve_lights(scene, warnings ? warnings : &local);
}

glm::dvec3 irradiance_of(const std::vector<sss::Light>& lights, glm::dvec3 p,
                         glm::dvec3 n, const sss::RayTracer* tracer = nullptr,
                         uint64_t seed = 0) {
    std::vector<int> active;
    for (std::size_t i = 0; i < lights.size(); ++i) active.push_back(static_cast<int>(i));
    return sss::irradiance(lights, active, p, n, tracer, seed, 1e-4);
}

void expect_gray(const glm::dvec3& e, double v, double tol = kTol) {
    EXPECT_NEAR(e.x, v, tol);
    EXPECT_NEAR(e.y, v, tol);
    EXPECT_NEAR(e.z, v, tol);
}

/// A tracer with one triangle at height z that covers the square
/// [-10, 10]^2 when `full`, or only the half-plane x < 0 of it (the triangle's
/// edge lies on x = 0).
std::unique_ptr<sss::RayTracer> occluder_at(float z, bool full) {
    auto tracer = std::make_unique<sss::RayTracer>();
    if (full) {
        tracer->add_mesh({{-10, -10, z}, {10, -10, z}, {10, 10, z}, {-10, 10, z}},
                         {0, 1, 2, 0, 2, 3});
    } else {
        tracer->add_mesh({{0, -100, z}, {0, 100, z}, {-100, 0, z}}, {0, 1, 2});
    }
    tracer->commit();
    return tracer;
}

} // namespace

// ---------------------------------------------------------------------------
// Light shaders

TEST(LightsTest, PointLightOverhead) {
    auto lights = resolve(one_light(
        "pointlight", {float_param("intensity", 4), point_param("from", {0, 0, 2})}));
    ASSERT_EQ(lights.size(), 1u);
    EXPECT_EQ(lights[0].kind, sss::Light::Kind::Point);
    EXPECT_FALSE(lights[0].shadows);
    // E = 4 / 2^2 * cos 0 = 1.
    expect_gray(irradiance_of(lights, {0, 0, 0}, {0, 0, 1}), 1.0);
    // Facing away: nothing.
    expect_gray(irradiance_of(lights, {0, 0, 0}, {0, 0, -1}), 0.0);
}

TEST(LightsTest, PointLightAtAnAngle) {
    auto lights = resolve(one_light(
        "pointlight", {float_param("intensity", 3), point_param("from", {1, 0, 1})}));
    // d^2 = 2, cos = 1/sqrt(2): E = 3 * 0.70710678 / 2.
    expect_gray(irradiance_of(lights, {0, 0, 0}, {0, 0, 1}), 3.0 * std::sqrt(0.5) / 2.0);
}

TEST(LightsTest, PointLightDefaults) {
    // intensity 1, lightcolor 1, from the shader-space origin.
    auto lights = resolve(one_light("pointlight", {}));
    expect_gray(irradiance_of(lights, {0, 0, -2}, {0, 0, 1}), 0.25);
}

TEST(LightsTest, DistantLight) {
    auto lights = resolve(one_light("distantlight", {float_param("intensity", 2),
                                                     point_param("from", {0, 0, 1}),
                                                     point_param("to", {0, 0, 0})}));
    ASSERT_EQ(lights.size(), 1u);
    EXPECT_EQ(lights[0].kind, sss::Light::Kind::Distant);
    EXPECT_NEAR(lights[0].direction.z, -1.0, kTol);
    // No falloff: the same everywhere.
    expect_gray(irradiance_of(lights, {0, 0, 0}, {0, 0, 1}), 2.0);
    expect_gray(irradiance_of(lights, {5, -3, -100}, {0, 0, 1}), 2.0);
    expect_gray(irradiance_of(lights, {0, 0, 0}, {0, 0, -1}), 0.0);
    // Tilted normal: 2 cos 60.
    expect_gray(irradiance_of(lights, {0, 0, 0}, {std::sin(radians(60)), 0, 0.5}), 1.0,
                1e-12);
}

TEST(LightsTest, DistantLightDefaultsTravelAlongZ) {
    auto lights = resolve(one_light("distantlight", {}));
    EXPECT_NEAR(lights[0].direction.z, 1.0, kTol);
    expect_gray(irradiance_of(lights, {0, 0, 0}, {0, 0, -1}), 1.0);
    expect_gray(irradiance_of(lights, {0, 0, 0}, {0, 0, 1}), 0.0);
}

TEST(LightsTest, SpotLightConeAndFalloff) {
    // Spot 2 units above the origin, pointing down; defaults: cone 30, delta 5, beam 2.
    auto scene = one_light(
        "spotlight", {point_param("from", {0, 0, 2}), point_param("to", {0, 0, 0})});
    auto lights = resolve(scene);
    ASSERT_EQ(lights[0].kind, sss::Light::Kind::Spot);
    EXPECT_NEAR(lights[0].cone_angle, radians(30), kTol);
    EXPECT_NEAR(lights[0].cone_delta, radians(5), kTol);
    EXPECT_EQ(lights[0].beam_distribution, 2.0);

    // On the axis: 1 / 4.
    expect_gray(irradiance_of(lights, {0, 0, 0}, {0, 0, 1}), 0.25);

    // At angle a off the axis on the plane z = 0: d = 2 / cos a, n.L = cos a.
    auto at_angle = [&](double deg) {
        return irradiance_of(lights, {2 * std::tan(radians(deg)), 0, 0}, {0, 0, 1}).x;
    };
    // 20 degrees: inside the full-intensity cone.
    const double c20 = std::cos(radians(20));
    EXPECT_NEAR(at_angle(20), c20 * c20 / (4 / (c20 * c20)) * c20, kTol);
    // 27.5 degrees: in the falloff band between 25 and 30 degrees.
    const double c = std::cos(radians(27.5));
    const double t =
        (c - std::cos(radians(30))) / (std::cos(radians(25)) - std::cos(radians(30)));
    const double s = t * t * (3 - 2 * t);
    EXPECT_GT(s, 0.0);
    EXPECT_LT(s, 1.0);
    EXPECT_NEAR(at_angle(27.5), c * c / (4 / (c * c)) * s * c, kTol);
    // Outside the cone.
    EXPECT_EQ(at_angle(31), 0.0);
    EXPECT_EQ(at_angle(60), 0.0);
}

TEST(LightsTest, SpotLightBeamDistribution) {
    auto with_beam = [](double beam) {
        auto lights = resolve(one_light(
            "spotlight", {point_param("from", {0, 0, 2}), point_param("to", {0, 0, 0}),
                          float_param("beamdistribution", beam),
                          float_param("coneangle", radians(40))}));
        return irradiance_of(lights, {2 * std::tan(radians(20)), 0, 0}, {0, 0, 1}).x;
    };
    // The beam term is cos^beam: beam 0 vs 2 differ by cos^2(20 deg); beam 8 by cos^8.
    const double c = std::cos(radians(20));
    EXPECT_NEAR(with_beam(2) / with_beam(0), c * c, 1e-12);
    EXPECT_NEAR(with_beam(8) / with_beam(0), std::pow(c, 8), 1e-12);
    // Beam 0 over the plane: 1/d^2 * cos = cos^3 / 4.
    EXPECT_NEAR(with_beam(0), c * c * c / 4, kTol);
}

TEST(LightsTest, AmbientLightIgnoresTheNormal) {
    auto lights = resolve(
        one_light("ambientlight",
                  {float_param("intensity", 0.5),
                   vec_param("lightcolor", sss::ParamType::Color, {1, 0.5, 0.25})}));
    ASSERT_EQ(lights[0].kind, sss::Light::Kind::Ambient);
    for (glm::dvec3 n :
         {glm::dvec3(0, 0, 1), glm::dvec3(0, 0, -1), glm::dvec3(1, 0, 0)}) {
        const glm::dvec3 e = irradiance_of(lights, {3, 4, 5}, n);
        EXPECT_NEAR(e.x, 0.5, kTol);
        EXPECT_NEAR(e.y, 0.25, kTol);
        EXPECT_NEAR(e.z, 0.125, kTol);
    }
    // Defaults: white, intensity 1.
    expect_gray(
        irradiance_of(resolve(one_light("ambientlight", {})), {0, 0, 0}, {0, 0, 1}), 1.0);
}

TEST(LightsTest, LightColorMultiplies) {
    auto lights = resolve(one_light(
        "pointlight", {float_param("intensity", 4), point_param("from", {0, 0, 2}),
                       vec_param("lightcolor", sss::ParamType::Color, {1, 0.5, 0})}));
    const glm::dvec3 e = irradiance_of(lights, {0, 0, 0}, {0, 0, 1});
    EXPECT_NEAR(e.x, 1.0, kTol);
    EXPECT_NEAR(e.y, 0.5, kTol);
    EXPECT_NEAR(e.z, 0.0, kTol);
}

TEST(LightsTest, LightsAddUp) {
    sss::Scene scene = one_light("ambientlight", {float_param("intensity", 0.1)});
    scene.lights.push_back(one_light("pointlight", {float_param("intensity", 4),
                                                    point_param("from", {0, 0, 2})})
                               .lights[0]);
    auto lights = resolve(scene);
    expect_gray(irradiance_of(lights, {0, 0, 0}, {0, 0, 1}), 1.1);
    // Only the active ones count.
    expect_gray(sss::irradiance(lights, {1}, {0, 0, 0}, {0, 0, 1}, nullptr, 0, 1e-4),
                1.0);
    expect_gray(sss::irradiance(lights, {}, {0, 0, 0}, {0, 0, 1}, nullptr, 0, 1e-4), 0.0);
    EXPECT_THROW(sss::irradiance(lights, {2}, {0, 0, 0}, {0, 0, 1}, nullptr, 0, 1e-4),
                 sss::ValueError);
}

TEST(LightsTest, ShaderTransformMovesFrom) {
    // "from" (0,0,1) in a space translated by (0,0,1): world (0,0,2).
    const sss::Matrix4 m = glm::translate(sss::Matrix4(1.0), glm::dvec3(0, 0, 1));
    auto lights = resolve(one_light(
        "pointlight", {float_param("intensity", 4), point_param("from", {0, 0, 1})}, m));
    EXPECT_NEAR(lights[0].from.z, 2.0, kTol);
    expect_gray(irradiance_of(lights, {0, 0, 0}, {0, 0, 1}), 1.0);

    // A rotation turns a distant light: +z rotated 90 degrees about x is -y.
    const sss::Matrix4 r =
        glm::rotate(sss::Matrix4(1.0), radians(90), glm::dvec3(1, 0, 0));
    auto distant = resolve(one_light("distantlight", {}, r));
    EXPECT_NEAR(distant[0].direction.y, -1.0, 1e-12);
    expect_gray(irradiance_of(distant, {0, 0, 0}, {0, 1, 0}), 1.0, 1e-12);
}

TEST(LightsTest, UnknownShaderWarnsAndIsDark) {
    std::vector<std::string> warnings;
    auto lights =
        resolve(one_light("fancylight", {float_param("intensity", 5)}), &warnings);
    ASSERT_EQ(lights.size(), 1u);
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_EQ(warnings[0], "test.rib:7: unknown light shader 'fancylight', ignored");
    EXPECT_EQ(lights[0].color, glm::dvec3(0.0));
    EXPECT_EQ(lights[0].scene_index, 0);
    expect_gray(irradiance_of(lights, {0, 0, 0}, {0, 0, 1}), 0.0);
}

TEST(LightsTest, BadParametersThrow) {
    EXPECT_THROW(resolve(one_light("spotlight", {point_param("from", {0, 0, 1}),
                                                 point_param("to", {0, 0, 1})})),
                 sss::ValueError);
    EXPECT_THROW(resolve(one_light("pointlight_rts", {float_param("samples", 0)})),
                 sss::ValueError);
    EXPECT_THROW(resolve(one_light("pointlight_rts", {float_param("radius", -1)})),
                 sss::ValueError);
    EXPECT_THROW(resolve(one_light("distantlight_rts", {float_param("angle", 200)})),
                 sss::ValueError);
    EXPECT_THROW(resolve(one_light("pointlight", {string_param("intensity", "x")})),
                 sss::ValueError);
    try {
        resolve(one_light("pointlight_rts", {float_param("samples", -3)}));
        FAIL() << "no exception";
    } catch (const sss::ValueError& e) {
        EXPECT_NE(std::string(e.what()).find("test.rib:7"), std::string::npos)
            << e.what();
    }
}

// ---------------------------------------------------------------------------
// Shadows

TEST(LightsTest, HardShadowBlocksAPointLight) {
    auto occluder = occluder_at(1.0f, true);
    auto shadowed = resolve(one_light(
        "pointlight", {float_param("intensity", 4), point_param("from", {0, 0, 2}),
                       string_param("shadowname", "raytrace")}));
    ASSERT_TRUE(shadowed[0].shadows);
    expect_gray(irradiance_of(shadowed, {0, 0, 0}, {0, 0, 1}, occluder.get()), 0.0);
    // Without the occluder, and without a tracer.
    sss::RayTracer empty;
    empty.commit();
    expect_gray(irradiance_of(shadowed, {0, 0, 0}, {0, 0, 1}, &empty), 1.0);
    expect_gray(irradiance_of(shadowed, {0, 0, 0}, {0, 0, 1}, nullptr), 1.0);
    // An occluder beyond the light does not shadow.
    auto beyond = occluder_at(3.0f, true);
    expect_gray(irradiance_of(shadowed, {0, 0, 0}, {0, 0, 1}, beyond.get()), 1.0);

    // Shadows off: the occluder is ignored.
    auto plain = resolve(one_light(
        "pointlight", {float_param("intensity", 4), point_param("from", {0, 0, 2})}));
    expect_gray(irradiance_of(plain, {0, 0, 0}, {0, 0, 1}, occluder.get()), 1.0);

    // The _rts variant always has shadows.
    auto rts = resolve(one_light(
        "pointlight_rts", {float_param("intensity", 4), point_param("from", {0, 0, 2})}));
    ASSERT_TRUE(rts[0].shadows);
    expect_gray(irradiance_of(rts, {0, 0, 0}, {0, 0, 1}, occluder.get()), 0.0);
}

TEST(LightsTest, ShadowMapNamesReadTheMapQuietly) {
    // A map seen from (0, 0, 2) looking down (camera z = 2 - world z),
    // orthographic over [-2, 2]^2: an occluder at world z = 1 over x < 0.
    auto map = std::make_shared<sss::ShadowMap>();
    map->width = map->height = 4;
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 4; ++x)
            map->depth.push_back(x < 2 ? 1.0f : sss::kNoSurfaceDepth);
    map->world_to_camera = sss::Matrix4(1.0);
    map->world_to_camera[2][2] = -1.0;
    map->world_to_camera[3][2] = 2.0;
    map->world_to_screen = glm::scale(sss::Matrix4(1.0), glm::dvec3(0.5, 0.5, 1.0));
    std::vector<std::string> asked;
    const sss::ShadowMapLoader loader = [&](const std::string& name) {
        asked.push_back(name);
        return map;
    };
    std::vector<std::string> warnings;
    const sss::Scene scene = one_light(
        "spotlight",
        {point_param("from", {0, 0, 2}), point_param("to", {0, 0, 0}),
         float_param("coneangle", 1.2), string_param("shadowname", "spot.shd")});
    auto lights = sss::resolve_lights(scene, &warnings, loader);
    EXPECT_TRUE(warnings.empty());
    EXPECT_EQ(asked, std::vector<std::string>{"spot.shd"});
    EXPECT_FALSE(lights[0].shadows); // no rays: the map
    ASSERT_EQ(lights[0].shadow_maps.size(), 1u);
    EXPECT_NEAR(lights[0].shadow_lookup.bias, sss::kDefaultShadowBias, 1e-7);
    // Under the occluder: dark; beside it: lit (no tracer needed).
    expect_gray(irradiance_of(lights, {-1, 0.1, 0}, {0, 0, 1}), 0.0);
    EXPECT_GT(irradiance_of(lights, {1, 0.1, 0}, {0, 0, 1}).x, 0.01);
    // Above the occluder (camera z 0.5 < 1): lit.
    EXPECT_GT(irradiance_of(lights, {-1, 0.1, 1.5}, {0, 0, 1}).x, 0.01);
    // Without a map reader a named map is an error naming the light.
    try {
        sss::resolve_lights(scene, &warnings);
        FAIL() << "no error without a map reader";
    } catch (const sss::ValueError& e) {
        EXPECT_NE(std::string(e.what()).find("test.rib:7"), std::string::npos)
            << e.what();
        EXPECT_NE(std::string(e.what()).find("spot.shd"), std::string::npos) << e.what();
    }
    // shadowdistant: distantlight's light (intensity 1, no falloff) and map.
    auto distant = sss::resolve_lights(
        one_light("shadowdistant",
                  {point_param("from", {0, 0, 2}), point_param("to", {0, 0, 0}),
                   string_param("shadowname", "d.shd")}),
        &warnings, loader);
    EXPECT_EQ(distant[0].kind, sss::Light::Kind::Distant);
    expect_gray(irradiance_of(distant, {-1, 0.1, 0}, {0, 0, 1}), 0.0);
    expect_gray(irradiance_of(distant, {1, 0.1, 0}, {0, 0, 1}), 1.0);
    // shadowpoint: the map of the axis towards the point (-z here), and a
    // scene bias that is larger than the gap lights everything.
    sss::Scene point = one_light(
        "shadowpoint", {point_param("from", {0, 0, 2}), string_param("sfnz", "nz.shd")});
    asked.clear();
    auto p = sss::resolve_lights(point, &warnings, loader);
    EXPECT_EQ(asked, std::vector<std::string>{"nz.shd"});
    ASSERT_EQ(p[0].shadow_maps.size(), 6u);
    EXPECT_EQ(p[0].shadow_lookup.samples, 16);
    expect_gray(irradiance_of(p, {-1, 0.1, 0}, {0, 0, 1}), 0.0);
    point.options.groups["shadow"].set(float_param("bias", 1.5));
    p = sss::resolve_lights(point, &warnings, loader);
    EXPECT_GT(irradiance_of(p, {-1, 0.1, 0}, {0, 0, 1}).x, 0.01);
}

TEST(LightsTest, DistantShadowAndRayOffset) {
    auto occluder = occluder_at(1.0f, true);
    auto lights = resolve(one_light("distantlight_rts", {point_param("from", {0, 0, 1}),
                                                         point_param("to", {0, 0, 0})}));
    expect_gray(irradiance_of(lights, {0, 0, 0}, {0, 0, 1}, occluder.get()), 0.0);
    // Above the occluder: lit.
    expect_gray(irradiance_of(lights, {0, 0, 2}, {0, 0, 1}, occluder.get()), 1.0);
    // A point on the occluder's top side is not shadowed by its own surface
    // thanks to the ray offset along n.
    expect_gray(irradiance_of(lights, {0.3, 0.2, 1.0}, {0, 0, 1}, occluder.get()), 1.0);
}

TEST(LightsTest, SoftShadowIsPartial) {
    // A sphere light of radius 0.5 two units up; the occluder at z = 1 covers
    // x < 0, so about half of the emitter is hidden from the origin.
    auto half = occluder_at(1.0f, false);
    auto lights = resolve(one_light(
        "pointlight_rts", {float_param("intensity", 4), point_param("from", {0, 0, 2}),
                           float_param("samples", 16), float_param("radius", 0.5)}));
    EXPECT_EQ(lights[0].samples, 16);
    EXPECT_NEAR(lights[0].size, 0.5, kTol);
    const double e = irradiance_of(lights, {0, 0, 0}, {0, 0, 1}, half.get(), 42).x;
    EXPECT_GT(e, 0.0);
    EXPECT_LT(e, 1.0);
    // Stratified samples: within two samples of one half.
    EXPECT_NEAR(e, 0.5, 2.0 / 16.0);
    // The fraction is a multiple of 1/16 of the unshadowed 1.0.
    EXPECT_NEAR(e * 16, std::round(e * 16), 1e-9);
    // Deterministic for a seed.
    EXPECT_EQ(irradiance_of(lights, {0, 0, 0}, {0, 0, 1}, half.get(), 42).x, e);
    // Away from the edge the shadow is hard again.
    EXPECT_EQ(irradiance_of(lights, {-2, 0, 0}, {0, 0, 1}, half.get(), 42).x, 0.0);
    EXPECT_GT(irradiance_of(lights, {2, 0, 0}, {0, 0, 1}, half.get(), 42).x, 0.0);

    // A point light of radius 0 with 16 samples is a hard shadow: all or nothing.
    auto hard = resolve(one_light("pointlight_rts", {float_param("intensity", 4),
                                                     point_param("from", {0.01, 0, 2}),
                                                     float_param("samples", 16)}));
    // The ray to (0.01, 0, 2) crosses z = 1 at x = 0.005, beside the occluder.
    expect_gray(irradiance_of(hard, {0, 0, 0}, {0, 0, 1}, half.get(), 42),
                4.0 / 4.0001 * (2.0 / std::sqrt(4.0001)), 1e-12);
}

TEST(LightsTest, SoftDistantShadowAndRadiusScale) {
    auto half = occluder_at(1.0f, false);
    auto lights = resolve(one_light(
        "distantlight_rts", {point_param("from", {0, 0, 1}), point_param("to", {0, 0, 0}),
                             float_param("samples", 16), float_param("angle", 20)}));
    EXPECT_NEAR(lights[0].size, radians(10), kTol);
    const double e = irradiance_of(lights, {0, 0, 0}, {0, 0, 1}, half.get(), 7).x;
    EXPECT_GT(e, 0.0);
    EXPECT_LT(e, 1.0);

    // A radius in a space scaled by 2 is twice as large in the world.
    const sss::Matrix4 s = glm::scale(sss::Matrix4(1.0), glm::dvec3(2.0));
    auto scaled = resolve(one_light("pointlight_rts", {float_param("radius", 0.25)}, s));
    EXPECT_NEAR(scaled[0].size, 0.5, 1e-12);
}

TEST(LightsTest, BatchMatchesScalar) {
    // Occluders: random triangles around the origin; lights of every kind.
    std::mt19937 rng(1234);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    sss::RayTracer tracer;
    std::vector<glm::vec3> verts;
    std::vector<uint32_t> tris;
    for (uint32_t t = 0; t < 60; ++t) {
        const glm::vec3 c(2 * u(rng), 2 * u(rng), 1.5f + u(rng));
        for (int k = 0; k < 3; ++k)
            verts.push_back(c + 0.4f * glm::vec3(u(rng), u(rng), u(rng)));
        tris.insert(tris.end(), {3 * t, 3 * t + 1, 3 * t + 2});
    }
    tracer.add_mesh(verts, tris);
    tracer.commit();

    sss::Scene scene = one_light("ambientlight", {float_param("intensity", 0.05)});
    auto add = [&](const std::string& name, std::vector<sss::Param> params) {
        scene.lights.push_back(one_light(name, std::move(params)).lights[0]);
    };
    add("pointlight_rts",
        {float_param("intensity", 6), point_param("from", {0.5, 0.2, 3}),
         float_param("samples", 9), float_param("radius", 0.3)});
    add("spotlight", {float_param("intensity", 8), point_param("from", {-1, 0, 3}),
                      point_param("to", {0, 0, 0}), float_param("coneangle", radians(50)),
                      string_param("shadowname", "raytrace")});
    add("distantlight_rts",
        {point_param("from", {0.3, 0.1, 1}), point_param("to", {0, 0, 0})});
    add("distantlight_rts",
        {point_param("from", {-0.2, 0.4, 1}), point_param("to", {0, 0, 0}),
         float_param("samples", 4), float_param("angle", 8)});
    add("pointlight", {point_param("from", {0, -2, 1})});
    auto lights = resolve(scene);
    const std::vector<int> active = {0, 1, 2, 3, 4, 5};

    const std::size_t count = 300;
    std::vector<glm::vec3> p(count), n(count);
    for (std::size_t i = 0; i < count; ++i) {
        p[i] = glm::vec3(2 * u(rng), 2 * u(rng), 0.3f * u(rng));
        n[i] =
            glm::normalize(glm::vec3(0.7f * u(rng), 0.7f * u(rng), 1.0f + 0.3f * u(rng)));
        if (i % 17 == 0) n[i] = -n[i]; // some facing away from every light
    }
    const uint64_t seed_base = 1000;
    std::vector<glm::dvec3> batch(count);
    sss::irradiance_batch(lights, active, p.data(), n.data(), count, &tracer, seed_base,
                          1e-3, batch.data());
    int partial = 0, dark = 0;
    for (std::size_t i = 0; i < count; ++i) {
        const glm::dvec3 s =
            sss::irradiance(lights, active, glm::dvec3(p[i]), glm::dvec3(n[i]), &tracer,
                            seed_base + i, 1e-3);
        ASSERT_EQ(batch[i].x, s.x) << i;
        ASSERT_EQ(batch[i].y, s.y) << i;
        ASSERT_EQ(batch[i].z, s.z) << i;
        // A scalar call with the unshadowed tracer for comparison.
        const glm::dvec3 open =
            sss::irradiance(lights, active, glm::dvec3(p[i]), glm::dvec3(n[i]), nullptr,
                            seed_base + i, 1e-3);
        if (s.x < open.x - 1e-12) ++partial;
        if (s.x < open.x * 0.5) ++dark;
    }
    // The scene is meaningful: some points are shadowed.
    EXPECT_GT(partial, 10);
    EXPECT_GT(dark, 0);
    // Odd chunkings give the same values.
    std::vector<glm::dvec3> pieces(count);
    for (std::size_t b = 0; b < count; b += 37)
        sss::irradiance_batch(lights, active, p.data() + b, n.data() + b,
                              std::min<std::size_t>(37, count - b), &tracer,
                              seed_base + b, 1e-3, pieces.data() + b);
    for (std::size_t i = 0; i < count; ++i) ASSERT_EQ(pieces[i], batch[i]) << i;
}

// ---------------------------------------------------------------------------
// Ray tracer

TEST(RayTracerTest, IntersectKnownTriangle) {
    sss::RayTracer tracer;
    // Mesh 0 far away; mesh 1 a triangle in the plane z = 1.
    EXPECT_EQ(
        tracer.add_mesh({{100, 100, 100}, {101, 100, 100}, {100, 101, 100}}, {0, 1, 2}),
        0u);
    EXPECT_EQ(
        tracer.add_mesh({{0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {9, 9, 9}}, {3, 3, 3, 0, 1, 2}),
        1u);
    tracer.commit();

    sss::ShadowRay ray{{0.25f, 0.5f, -1.0f}, {0, 0, 1}, 0.0f, 100.0f};
    const sss::RayHit hit = tracer.intersect(ray);
    ASSERT_TRUE(hit.hit);
    EXPECT_NEAR(hit.t, 2.0f, 1e-6f);
    EXPECT_EQ(hit.mesh, 1u);
    EXPECT_EQ(hit.triangle, 1u);
    EXPECT_NEAR(hit.u, 0.25f, 1e-6f);
    EXPECT_NEAR(hit.v, 0.5f, 1e-6f);
    // (v1 - v0) x (v2 - v0) = +z, up to Embree's orientation convention.
    EXPECT_NEAR(std::abs(hit.geometric_normal.z), 1.0f, 1e-6f);
    EXPECT_NEAR(hit.geometric_normal.x, 0.0f, 1e-6f);
    EXPECT_TRUE(tracer.occluded(ray));

    // The interval matters.
    sss::ShadowRay short_ray = ray;
    short_ray.tfar = 1.9f;
    EXPECT_FALSE(tracer.intersect(short_ray).hit);
    EXPECT_FALSE(tracer.occluded(short_ray));
    sss::ShadowRay late = ray;
    late.tnear = 2.1f;
    EXPECT_FALSE(tracer.occluded(late));
    // Misses beside the triangle.
    sss::ShadowRay beside{{0.75f, 0.75f, -1.0f}, {0, 0, 1}, 0.0f, 100.0f};
    EXPECT_FALSE(tracer.intersect(beside).hit);
    // The closest of two hits.
    sss::ShadowRay diagonal{{100.1f, 100.1f, 0.0f}, {0, 0, 1}, 0.0f, 1e30f};
    const sss::RayHit far = tracer.intersect(diagonal);
    ASSERT_TRUE(far.hit);
    EXPECT_EQ(far.mesh, 0u);
    EXPECT_NEAR(far.t, 100.0f, 1e-4f);

    // Batch occlusion agrees, including an empty interval.
    sss::ShadowRay empty_interval = ray;
    empty_interval.tnear = 5.0f;
    empty_interval.tfar = 1.0f;
    const std::vector<sss::ShadowRay> rays = {ray,      short_ray, beside,
                                              diagonal, late,      empty_interval};
    std::vector<uint8_t> hits(rays.size(), 7);
    tracer.occluded(rays.data(), rays.size(), hits.data());
    EXPECT_EQ(hits, (std::vector<uint8_t>{1, 0, 0, 1, 0, 0}));

    // Box (0,0,1)-(101,101,100) of the vertices the triangles use.
    EXPECT_NEAR(tracer.scene_extent(), std::sqrt(101.0f * 101.0f * 2 + 99.0f * 99.0f),
                1e-3f);
}

TEST(RayTracerTest, EmptySceneAndErrors) {
    sss::RayTracer empty;
    sss::ShadowRay ray{{0, 0, 0}, {0, 0, 1}, 0.0f, 1e30f};
    EXPECT_FALSE(empty.occluded(ray));
    EXPECT_FALSE(empty.intersect(ray).hit);
    empty.commit();
    EXPECT_FALSE(empty.occluded(ray));
    EXPECT_FALSE(empty.intersect(ray).hit);
    uint8_t hit = 9;
    empty.occluded(&ray, 1, &hit);
    EXPECT_EQ(hit, 0);
    EXPECT_EQ(empty.scene_extent(), 0.0f);

    sss::RayTracer tracer;
    EXPECT_THROW(tracer.add_mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {0, 1}),
                 sss::ValueError);
    EXPECT_THROW(tracer.add_mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {0, 1, 3}),
                 sss::ValueError);
    EXPECT_THROW(tracer.add_mesh({{0, 0, NAN}, {1, 0, 0}, {0, 1, 0}}, {0, 1, 2}),
                 sss::ValueError);
    EXPECT_EQ(tracer.add_mesh({{0, 0, 1}, {1, 0, 1}, {0, 1, 1}}, {0, 1, 2}), 0u);
    // Queries need a commit once there is geometry.
    EXPECT_THROW(tracer.occluded(ray), sss::Error);
    tracer.commit();
    EXPECT_TRUE(tracer.occluded(ray));
    // Rays Embree cannot trace are misses, counted (never an abort in Embree).
    const std::vector<sss::ShadowRay> bad = {
        {{0, 0, 0}, {0, 0, NAN}, 0.0f, 1.0f},
        {{NAN, 0, 0}, {0, 0, 1}, 0.0f, 1.0f},
        {{0, 0, 0}, {0, 0, 0}, 0.0f, 1.0f},
        {{0, 0, 2e18f}, {0, 0, -1}, 0.0f, 3e18f},
        {{0, 0, 0}, {0, 0, 1}, -1.0f, 1.0f},
        {{0, 0, 0}, {0, 0, 1}, 0.0f, NAN},
        {{0.1f, 0.1f, 0}, {0, 0, 1}, INFINITY, INFINITY}};
    for (const sss::ShadowRay& r : bad) {
        EXPECT_FALSE(tracer.occluded(r));
        EXPECT_FALSE(tracer.intersect(r).hit);
    }
    EXPECT_EQ(tracer.invalid_rays(), 2 * bad.size());
    std::vector<uint8_t> hits(bad.size(), 9);
    tracer.occluded(bad.data(), bad.size(), hits.data());
    for (uint8_t h : hits) EXPECT_EQ(h, 0);
    EXPECT_EQ(tracer.invalid_rays(), 3 * bad.size());
    // Valid rays in the same batch are still answered.
    std::vector<sss::ShadowRay> mixed = {bad[0], ray, bad[3]};
    tracer.occluded(mixed.data(), mixed.size(), hits.data());
    EXPECT_EQ(hits[0], 0);
    EXPECT_EQ(hits[1], 1);
    EXPECT_EQ(hits[2], 0);
    // Vertices beyond Embree's range would be dropped without a word.
    EXPECT_THROW(tracer.add_mesh({{0, 0, 2e18f}, {1, 0, 0}, {0, 1, 0}}, {0, 1, 2}),
                 sss::ValueError);
    // Adding a mesh later needs a new commit, then sees both meshes.
    EXPECT_EQ(tracer.add_mesh({{0, 0, -1}, {1, 0, -1}, {0, 1, -1}}, {0, 1, 2}), 1u);
    tracer.commit();
    sss::ShadowRay down{{0.1f, 0.1f, 0}, {0, 0, -1}, 0.0f, 10.0f};
    const sss::RayHit h = tracer.intersect(down);
    ASSERT_TRUE(h.hit);
    EXPECT_EQ(h.mesh, 1u);
}

// ---------------------------------------------------------------------------
// Noise

TEST(LightsTest, NoiseRangeDeterminismContinuity) {
    std::mt19937 rng(99);
    std::uniform_real_distribution<double> u(-50.0, 50.0);
    double lo = 1.0, hi = 0.0, sum = 0.0;
    const int count = 20000;
    double max_step = 0.0;
    for (int i = 0; i < count; ++i) {
        const glm::dvec3 p(u(rng), u(rng), u(rng));
        const double v = sss::noise3(p);
        ASSERT_GE(v, 0.0);
        ASSERT_LE(v, 1.0);
        ASSERT_EQ(v, sss::noise3(p));
        lo = std::min(lo, v);
        hi = std::max(hi, v);
        sum += v;
        // Continuity: a step of 1e-4 changes the value by at most a few 1e-4.
        const double w = sss::noise3(p + glm::dvec3(1e-4, -0.7e-4, 0.5e-4));
        max_step = std::max(max_step, std::abs(w - v));
    }
    EXPECT_LT(lo, 0.25);
    EXPECT_GT(hi, 0.75);
    EXPECT_NEAR(sum / count, 0.5, 0.02);
    EXPECT_LT(max_step, 1e-3);
    EXPECT_GT(max_step, 0.0);
    // 0.5 on the integer lattice, as signed Perlin noise is 0 there.
    EXPECT_EQ(sss::noise3({3, -7, 12}), 0.5);
    // Pinned values: baked files must not change with a new build. At a cell
    // centre every gradient term is -1, 0 or 1 over 2, and the fade weights are
    // all 1/2, so the value is a multiple of 1/16.
    EXPECT_NEAR(sss::noise3({0.3, 1.7, -2.2}), 0.20975237103664629, 1e-12);
    EXPECT_NEAR(sss::noise3({10.5, -3.25, 7.75}), 0.43973660469055176, 1e-12);
    EXPECT_EQ(sss::noise3({0.5, 0.5, 0.5}), 0.3125);
    EXPECT_NE(sss::noise3({0.3, 1.7, -2.2}), sss::noise3({0.31, 1.7, -2.2}));
    // Periodic with period 256 on the lattice.
    EXPECT_NEAR(sss::noise3({0.3, 1.7, -2.2}), sss::noise3({256.3, 1.7, -2.2}), 1e-9);
    EXPECT_THROW(sss::noise3({NAN, 0, 0}), sss::ValueError);
}

TEST(RayTracerTest, MovingMeshIsWhereItIsAtTheRaysTime) {
    sss::RayTracer tracer;
    // A triangle in z = 1 at time 0 that moves to z = 3 at time 1.
    const std::vector<std::vector<glm::vec3>> steps = {
        {{-1, -1, 3}, {2, -1, 3}, {-1, 2, 3}}};
    tracer.add_mesh({{-1, -1, 1}, {2, -1, 1}, {-1, 2, 1}}, {0, 1, 2}, &steps);
    tracer.commit();
    sss::ShadowRay ray{{0.0f, 0.0f, -1.0f}, {0, 0, 1}, 0.0f, 100.0f};
    EXPECT_NEAR(tracer.intersect(ray).t, 2.0f, 1e-5f);
    ray.time = 1.0f;
    EXPECT_NEAR(tracer.intersect(ray).t, 4.0f, 1e-5f);
    ray.time = 0.25f;
    EXPECT_NEAR(tracer.intersect(ray).t, 2.5f, 1e-5f);
    // Occlusion sees the motion too: a ray ending at z = 2 is blocked only early.
    ray.tfar = 3.0f;
    ray.time = 0.0f;
    EXPECT_TRUE(tracer.occluded(ray));
    ray.time = 0.9f;
    EXPECT_FALSE(tracer.occluded(ray));
    // A time outside [0, 1] is an invalid ray.
    ray.time = 1.5f;
    EXPECT_FALSE(tracer.occluded(ray));
    EXPECT_EQ(tracer.invalid_rays(), 1u);
    // Steps must have every vertex.
    sss::RayTracer bad;
    const std::vector<std::vector<glm::vec3>> short_steps = {{{0, 0, 0}}};
    EXPECT_THROW(bad.add_mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {0, 1, 2}, &short_steps),
                 sss::ValueError);
}
