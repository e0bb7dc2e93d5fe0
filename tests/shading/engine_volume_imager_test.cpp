// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file engine_volume_imager_test.cpp
/// Volume and imager shaders in the shading engine: they start from the Ci,
/// Oi (and alpha) of their batch, write them back, leave alone what they do
/// not mention, and volume shaders see lights through illuminance.
///
/// Suite names start with "RslEngine".

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "engine_test_util.h"

namespace {

using namespace sss;
using namespace sss::test;

/// A Points batch of n points, P and I given, with Ci and Oi.
ShadingBatch volume_batch(const std::vector<glm::vec3>& P,
                          const std::vector<glm::vec3>& I,
                          const std::vector<glm::vec3>& Ci,
                          const std::vector<glm::vec3>& Oi) {
    ShadingBatch b;
    b.layout = BatchLayout::Points;
    b.size = P.size();
    b.P = P;
    b.I = I;
    b.Ci = Ci;
    b.Oi = Oi;
    return b;
}

const char* kFog = R"(
volume fog(float distance = 1; color background = 0;)
{
    float amount = 1 - exp(-length(I) / distance);
    Ci = mix(Ci, background, amount);
    Oi = mix(Oi, color(1), amount);
}
)";

TEST(RslEngineVolume, FogMovesTheColourByTheDistanceTravelled) {
    Engine e;
    ParamList params;
    params.set(float_param("distance", 2.0));
    params.set(point_param("background", {0.5, 0.6, 0.7}, ParamType::Color));
    ShaderInstance fog = e.instance(kFog, params);
    ShadingBatch b =
        volume_batch({{0, 0, 1}, {0, 0, 3}, {1, 0, 0}}, {{0, 0, 1}, {0, 0, 3}, {1, 0, 0}},
                     {{1, 0, 0}, {0, 1, 0}, {0.2f, 0.2f, 0.2f}},
                     {{1, 1, 1}, {1, 1, 1}, {0.5f, 0.5f, 0.5f}});
    e.context.execute(fog, b);
    ASSERT_EQ(b.Ci.size(), 3u);
    const glm::vec3 bg(0.5f, 0.6f, 0.7f);
    const float lengths[3] = {1.0f, 3.0f, 1.0f};
    const glm::vec3 ci0[3] = {{1, 0, 0}, {0, 1, 0}, {0.2f, 0.2f, 0.2f}};
    const float oi0[3] = {1.0f, 1.0f, 0.5f};
    for (int k = 0; k < 3; ++k) {
        const float a = 1.0f - std::exp(-lengths[k] / 2.0f);
        for (int c = 0; c < 3; ++c) {
            EXPECT_NEAR(b.Ci[k][c], ci0[k][c] + (bg[c] - ci0[k][c]) * a, 1e-6) << k;
            EXPECT_NEAR(b.Oi[k][c], oi0[k] + (1.0f - oi0[k]) * a, 1e-6) << k;
        }
    }
}

TEST(RslEngineVolume, WhatTheShaderDoesNotMentionStaysAsGiven) {
    Engine e;
    // Writes Ci only: Oi stays as given, not Os.
    ShaderInstance dim = e.instance("volume dim() { Ci *= 0.5; }");
    ShadingBatch b = volume_batch({{0, 0, 1}}, {{0, 0, 1}}, {{0.8f, 0.4f, 0.2f}},
                                  {{0.3f, 0.3f, 0.3f}});
    b.Os = {{1, 1, 1}};
    e.context.execute(dim, b);
    EXPECT_NEAR(b.Ci[0].x, 0.4f, 1e-6);
    EXPECT_NEAR(b.Ci[0].z, 0.1f, 1e-6);
    EXPECT_NEAR(b.Oi[0].x, 0.3f, 1e-6);
    // Mentions neither: nothing changes (a surface shader would give Ci = 0).
    ShaderInstance nothing = e.instance("volume nothing(float k = 1;) { float x = k; }");
    e.context.execute(nothing, b);
    EXPECT_NEAR(b.Ci[0].x, 0.4f, 1e-6);
    EXPECT_NEAR(b.Oi[0].y, 0.3f, 1e-6);
}

TEST(RslEngineVolume, IlluminanceSeesTheLights) {
    Engine e;
    const char* light = R"(
light pointlight(float intensity = 1; point from = point "shader" (0, 0, 0);) {
    illuminate(from) { Cl = intensity / (L . L); }
}
)";
    ParamList lp;
    lp.set(float_param("intensity", 8.0));
    lp.set(point_param("from", {0, 2, 2}));
    ShaderInstance lamp = e.instance(light, lp);
    // In-scattering: the light that reaches the point, and the direction it
    // comes from (L points towards the light inside illuminance).
    ShaderInstance glow = e.instance(R"(
volume glow(output varying float ly = 0;)
{
    color lit = 0;
    illuminance(P) {
        lit += Cl;
        ly = ycomp(normalize(L));
    }
    Ci += lit;
}
)");
    ShadingBatch b =
        volume_batch({{0, 0, 2}, {0, 1, 2}}, {{0, 0, 2}, {0, 1, 2}},
                     {{0, 0, 0}, {0.1f, 0.1f, 0.1f}}, {{1, 1, 1}, {1, 1, 1}});
    const ShaderInstance* lights[] = {&lamp};
    e.context.execute(glow, b, LightList(lights, 1));
    EXPECT_NEAR(b.Ci[0].x, 8.0f / 4.0f, 1e-5);
    EXPECT_NEAR(b.Ci[1].x, 0.1f + 8.0f / 1.0f, 1e-5);
    TypeSpec type;
    std::vector<float> ly;
    ASSERT_TRUE(e.context.output("ly", type, ly));
    EXPECT_NEAR(ly[0], 1.0f, 1e-5);
    EXPECT_NEAR(ly[1], 1.0f, 1e-5);
}

const char* kBackground = R"(
imager background(color bgcolor = 1;)
{
    Ci += (1 - alpha) * bgcolor;
    Oi = 1;
    alpha = 1;
}
)";

TEST(RslEngineImager, BackgroundFillsWhatIsUncovered) {
    Engine e;
    ParamList params;
    params.set(point_param("bgcolor", {0.2, 0.4, 0.6}, ParamType::Color));
    ShaderInstance bg = e.instance(kBackground, params);
    ShadingBatch b;
    b.layout = BatchLayout::Points;
    b.size = 3;
    b.P = {{0.5f, 0.5f, 0}, {1.5f, 0.5f, 0}, {2.5f, 0.5f, 0}};
    b.Ci = {{0, 0, 0}, {0.5f, 0.5f, 0.5f}, {0.25f, 0, 0}}; // premultiplied
    b.alpha = {0.0f, 1.0f, 0.5f};
    b.Oi = {glm::vec3(0.0f), glm::vec3(1.0f), glm::vec3(0.5f)};
    e.context.execute(bg, b);
    ASSERT_EQ(b.alpha.size(), 3u);
    const glm::vec3 want[3] = {
        {0.2f, 0.4f, 0.6f}, {0.5f, 0.5f, 0.5f}, {0.35f, 0.2f, 0.3f}};
    for (int k = 0; k < 3; ++k) {
        for (int c = 0; c < 3; ++c) {
            EXPECT_NEAR(b.Ci[k][c], want[k][c], 1e-6) << k << " " << c;
            EXPECT_NEAR(b.Oi[k][c], 1.0f, 1e-6);
        }
        EXPECT_NEAR(b.alpha[k], 1.0f, 1e-6);
    }
}

TEST(RslEngineImager, SeesThePixelPositionAndLeavesAlphaAlone) {
    Engine e;
    // Ci from P (the raster position); alpha is read, not written.
    ShaderInstance where = e.instance(
        "imager where() { Ci = color(xcomp(P), ycomp(P), zcomp(P) + alpha); }");
    ShadingBatch b;
    b.layout = BatchLayout::Points;
    b.size = 2;
    b.P = {{10.5f, 3.5f, 0}, {0.5f, 7.5f, 0}};
    b.Ci = {glm::vec3(1.0f), glm::vec3(1.0f)};
    b.alpha = {0.25f, 0.75f};
    e.context.execute(where, b);
    EXPECT_NEAR(b.Ci[0].x, 10.5f, 1e-6);
    EXPECT_NEAR(b.Ci[0].y, 3.5f, 1e-6);
    EXPECT_NEAR(b.Ci[0].z, 0.25f, 1e-6);
    EXPECT_NEAR(b.Ci[1].y, 7.5f, 1e-6);
    EXPECT_NEAR(b.Ci[1].z, 0.75f, 1e-6);
    ASSERT_EQ(b.alpha.size(), 2u);
    EXPECT_EQ(b.alpha[0], 0.25f);
    EXPECT_EQ(b.alpha[1], 0.75f);
}

TEST(RslEngineImager, NonFiniteAlphaIsWrittenAsZero) {
    Engine e;
    ShaderInstance bad = e.instance("imager bad() { alpha = alpha / 0; }");
    ShadingBatch b;
    b.layout = BatchLayout::Points;
    b.size = 2;
    b.P = {glm::vec3(0.5f), glm::vec3(1.5f)};
    b.alpha = {1.0f, 0.0f};
    e.context.execute(bad, b);
    EXPECT_EQ(b.alpha[0], 0.0f);
    EXPECT_EQ(b.alpha[1], 0.0f);
    EXPECT_EQ(e.context.nonfinite_points(), 2u);
}

TEST(RslEngineImager, KindsSurviveTheSloFormat) {
    for (const char* source : {kFog, kBackground}) {
        const auto program = compile_shader(source);
        std::stringstream text;
        write_program(*program, text);
        const Program back = read_program(text, "x.slo");
        EXPECT_EQ(back.kind, program->kind);
        EXPECT_EQ(back.name, program->name);
    }
}

} // namespace
