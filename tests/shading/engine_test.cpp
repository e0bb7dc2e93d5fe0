// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file engine_test.cpp
/// Tests of the shading engine's core (engine.h): binding, parameters,
/// operators with promotions, control flow under varying masks, uniform and
/// varying stores, arrays, spaces, NaN handling, printf.
///
/// Suite names start with "RslEngine".

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "engine_test_util.h"
#include "sss/util/error.h"

namespace {

using namespace sss;
using namespace sss::test;

TEST(RslEngineOps, ArithmeticAndPromotions) {
    Engine e;
    ShadingBatch b = plane_grid(4, 1);
    const char* src = R"(
surface t(output varying color r = 0; output varying float f = 0;
          output varying point p = 0; output uniform matrix m = 1;)
{
    color c = color(1, 2, 3) * 2 + 1;      // (3, 5, 7)
    r = c / color(3, 5, 7) + u;             // 1 + u each
    f = 7 - 2 * 3 + mod(-1, 3) + (1 / 4);  // 1 + 2 + 0.25
    p = point(1, 2, 3) ^ vector(0, 0, 1);  // (2, -1, 0)
    p += vector(-point(1, 1, 1));           // (1, -2, -1)
    matrix a = matrix(2, 0, 0, 0,  0, 2, 0, 0,  0, 0, 2, 0,  1, 2, 3, 1);
    m = a * a / a;                          // = a
}
)";
    ShaderInstance inst = e.instance(src);
    e.context.execute(inst, b);
    TypeSpec ty;
    std::vector<float> r, f, p, m;
    ASSERT_TRUE(e.context.output("r", ty, r));
    ASSERT_TRUE(e.context.output("f", ty, f));
    ASSERT_TRUE(e.context.output("p", ty, p));
    ASSERT_TRUE(e.context.output("m", ty, m));
    for (int i = 0; i < 4; ++i) {
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(r[i * 3 + k], 1.0f + b.u[i], 1e-6);
        EXPECT_NEAR(f[i], 3.25f, 1e-6);
        EXPECT_NEAR(p[i * 3 + 0], 1.0f, 1e-6);
        EXPECT_NEAR(p[i * 3 + 1], -2.0f, 1e-6);
        EXPECT_NEAR(p[i * 3 + 2], -1.0f, 1e-6);
    }
    const float want[16] = {2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 2, 0, 1, 2, 3, 1};
    for (int k = 0; k < 16; ++k) EXPECT_NEAR(m[k], want[k], 1e-5) << k;
}

TEST(RslEngineOps, ComparisonsOnTriplesAndStrings) {
    Engine e;
    ShadingBatch b = plane_grid(2, 1);
    const auto r = e.run(R"(
surface t(output varying float r = 0; string name = "abc";) {
    float x = 0;
    if (color(1, 2, 3) == color(1, 2, 3)) x += 1;
    if (point(1, 2, 3) != point(1, 2, 4)) x += 2;
    if (name == "abc") x += 4;
    if (name != "abd") x += 8;
    if (concat(name, "d") == "abcd") x += 16;
    if (match("^a.c$", name) == 1 && !(1 > 2) && (1 <= 1 || 0 > 1)) x += 32;
    r = x;
}
)",
                         b);
    EXPECT_EQ(r[0], 63.0f);
    EXPECT_EQ(r[1], 63.0f);
}

TEST(RslEngineControl, IfElseUnderPartialMasks) {
    Engine e;
    ShadingBatch b = plane_grid(8, 1);
    const auto r = e.run(R"(
surface t(output varying float r = 0;) {
    if (u < 0.25) {
        r = 1;
    } else if (u < 0.5) {
        r = 2;
        if (u > 0.3) r = 3;
    } else {
        r = 4;
    }
    if (u > 2) r = 100;   // empty branch
}
)",
                         b);
    const float want[8] = {1, 1, 3, 3, 4, 4, 4, 4}; // u = 1/16, 3/16, 5/16 ...
    for (int i = 0; i < 8; ++i) EXPECT_EQ(r[i], want[i]) << i << " u " << b.u[i];
}

TEST(RslEngineControl, NestedLoopsBreakTwoAndContinue) {
    Engine e;
    ShadingBatch b = plane_grid(4, 1);
    // Point i (u = (i + 0.5)/4): k = floor(u * 4) = i.
    const auto r = e.run(R"(
surface t(output varying float r = 0;) {
    float k = floor(u * 4);
    float sum = 0;
    float i, j;
    for (i = 0; i < 5; i += 1) {
        if (i == 1) continue;
        for (j = 0; j < 5; j += 1) {
            if (j == k) continue;
            if (i == 3 && j == k + 1) break 2;
            sum += 1;
        }
    }
    r = sum * 100 + i;
}
)",
                         b);
    for (int k = 0; k < 4; ++k) {
        // Reference in C++.
        float sum = 0;
        int i;
        for (i = 0; i < 5; ++i) {
            if (i == 1) continue;
            bool out = false;
            for (int j = 0; j < 5; ++j) {
                if (j == k) continue;
                if (i == 3 && j == k + 1) {
                    out = true;
                    break;
                }
                sum += 1;
            }
            if (out) break;
        }
        EXPECT_EQ(r[k], sum * 100 + i) << k;
    }
}

TEST(RslEngineControl, WhileLoopsWithVaryingTripCounts) {
    Engine e;
    ShadingBatch b = plane_grid(5, 1);
    const auto r = e.run(R"(
surface t(output varying float r = 0;) {
    float n = floor(u * 5) + 1;
    float c = 0;
    while (c < n) c += 1;
    r = c;
}
)",
                         b);
    for (int i = 0; i < 5; ++i) EXPECT_EQ(r[i], i + 1.0f);
}

TEST(RslEngineControl, ReturnFromFunctionUnderMask) {
    Engine e;
    ShadingBatch b = plane_grid(4, 1);
    const auto r = e.run(R"(
float pick(float x) {
    float y = 10;
    if (x < 0.5) {
        y = 20;
    }
    return y;
}
void addone(output float a) {
    if (a > 0.5) return;
    a = a + 1;
}
surface t(output varying float r = 0;) {
    float a = u;
    addone(a);
    r = pick(u) + a;
}
)",
                         b);
    for (int i = 0; i < 4; ++i) {
        const float u = b.u[i];
        EXPECT_NEAR(r[i], (u < 0.5f ? 20.0f : 10.0f) + (u > 0.5f ? u : u + 1.0f), 1e-6)
            << i;
    }
}

TEST(RslEngineControl, ShaderReturnStopsPoints) {
    Engine e;
    ShadingBatch b = plane_grid(4, 1);
    const auto r = e.run(R"(
surface t(output varying float r = 0;) {
    r = 1;
    if (u > 0.5) return;
    r = 2;
}
)",
                         b);
    for (int i = 0; i < 4; ++i) EXPECT_EQ(r[i], b.u[i] > 0.5f ? 1.0f : 2.0f);
}

TEST(RslEngineControl, UniformStoreUnderPartialMaskWritesIfAnyRuns) {
    Engine e;
    ShadingBatch b = plane_grid(4, 1);
    const auto r = e.run(R"(
surface t(output varying float r = 0; output uniform float w = 0; output uniform float z = 5;) {
    if (u > 0.5) { w = 7; }
    if (u > 2) { z = 9; }
    r = w + z;
}
)",
                         b);
    for (int i = 0; i < 4; ++i) EXPECT_EQ(r[i], 12.0f);
}

TEST(RslEngineOps, ArraysAndIndexChecks) {
    Engine e;
    ShadingBatch b = plane_grid(4, 1);
    const auto r = e.run(R"(
surface t(output varying float r = 0; float tab[4] = {1, 2, 3, 4};) {
    float a[3] = {5, 6, 7};
    a[floor(u * 3)] = 10;
    r = tab[u * 4] + a[1];
}
)",
                         b);
    // u*4 = 0.5, 1.5, 2.5, 3.5 -> tab 1..4; floor(u*3) = 0, 1, 1, 2 -> a[1] 6, 10, 10, 6
    const float want[4] = {1 + 6, 2 + 10, 3 + 10, 4 + 6};
    for (int i = 0; i < 4; ++i) EXPECT_EQ(r[i], want[i]) << i;

    ShaderInstance bad = e.instance(R"(
surface t(output varying float r = 0;) {
    float a[3] = {5, 6, 7};
    r = a[u * 4];
}
)");
    try {
        e.context.execute(bad, b);
        FAIL() << "no error";
    } catch (const ShaderRuntimeError& err) {
        EXPECT_NE(std::string(err.what()).find("test.sl:4"), std::string::npos)
            << err.what();
        EXPECT_NE(std::string(err.what()).find("out of range"), std::string::npos);
    }
}

TEST(RslEngineParams, DefaultsArgumentsAndPrimvars) {
    Engine e;
    ShadingBatch b = plane_grid(2, 1);
    const char* src = R"(
surface t(float Kd = 0.5; float Ks = Kd * 2; color tint = color(1, 0, 0);
          point from = point "shader" (0, 0, 0); string map = "";
          output varying float r = 0; output varying color c = 0; output varying point f = 0;) {
    r = Kd + Ks;
    c = tint;
    f = from;
}
)";
    // Defaults: Kd 0.5, Ks 1, from = shader origin in camera space.
    e.services.scene_.options.camera.world_to_camera =
        glm::translate(Matrix4(1.0), glm::dvec3(0, 0, 5));
    const Matrix4 shader_to_world = glm::translate(Matrix4(1.0), glm::dvec3(1, 2, 3));
    {
        ShaderInstance inst = e.instance(src, {}, shader_to_world);
        e.context.execute(inst, b);
        TypeSpec ty;
        std::vector<float> r, f;
        e.context.output("r", ty, r);
        e.context.output("f", ty, f);
        EXPECT_FLOAT_EQ(r[0], 1.5f);
        EXPECT_FLOAT_EQ(f[0], 1.0f);
        EXPECT_FLOAT_EQ(f[1], 2.0f);
        EXPECT_FLOAT_EQ(f[2], 8.0f);
    }
    // RIB arguments: Kd given (Ks's default follows it), from converted.
    ParamList params;
    params.set(float_param("Kd", 2.0));
    params.set(point_param("from", {1, 0, 0}));
    params.set(float_param("nosuch", 1.0));
    std::vector<std::string> warnings;
    ShaderInstance inst(compile_shader(src), params, shader_to_world, "x.rib:3",
                        &warnings);
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("nosuch"), std::string::npos);
    // Primitive variable tint, varying.
    ShaderArgument tint;
    tint.name = "tint";
    tint.type = {ShadingType::Color, 0};
    tint.varying = true;
    tint.numbers = {0, 1, 0, 0, 0, 1};
    b.primvars.push_back(tint);
    e.context.execute(inst, b);
    TypeSpec ty;
    std::vector<float> r, c, f;
    e.context.output("r", ty, r);
    e.context.output("c", ty, c);
    e.context.output("f", ty, f);
    EXPECT_FLOAT_EQ(r[1], 6.0f);
    EXPECT_FLOAT_EQ(f[0], 2.0f);
    EXPECT_FLOAT_EQ(f[2], 8.0f);
    EXPECT_FLOAT_EQ(c[1], 1.0f);
    EXPECT_FLOAT_EQ(c[5], 1.0f);
    EXPECT_FLOAT_EQ(c[0], 0.0f);

    // Wrong types are errors naming the parameter.
    ParamList wrong;
    wrong.set(string_param("Kd", "x"));
    EXPECT_THROW(ShaderInstance(compile_shader(src), wrong, Matrix4(1.0), "x.rib:4"),
                 ValueError);
    ParamList wrong2;
    wrong2.set(point_param("tint", {1, 1, 1}));
    EXPECT_THROW(ShaderInstance(compile_shader(src), wrong2, Matrix4(1.0), "x.rib:5"),
                 ValueError);
    EXPECT_EQ(inst.float_parameter("Kd").value_or(-1), 2.0f);
    EXPECT_EQ(inst.string_parameter("map").value_or("?"), "");
}

TEST(RslEngineBind, UnknownFunctionsAndBadProgramsAreRefused) {
    auto prog = std::make_shared<Program>();
    prog->name = "broken";
    prog->files = {"broken.sl"};
    Symbol s;
    s.name = "x";
    s.type = {ShadingType::Float, 0};
    prog->symbols.push_back(s);
    Op op;
    op.name = "frobnicate";
    op.args = {0};
    op.where = {0, 7, 1};
    prog->ops.push_back(op);
    try {
        ShaderInstance inst(prog, {}, Matrix4(1.0), "");
        FAIL();
    } catch (const ValueError& e) {
        EXPECT_NE(std::string(e.what()).find("frobnicate"), std::string::npos);
        EXPECT_NE(std::string(e.what()).find("broken.sl:7"), std::string::npos)
            << e.what();
    }
    prog->ops[0].name = "sin";
    prog->ops[0].args = {0, 3}; // bad symbol index
    EXPECT_THROW(ShaderInstance(prog, {}, Matrix4(1.0), ""), ValueError);
    prog->ops[0].args = {0};
    prog->ops[0].name = "if";
    prog->ops[0].jump = {5, 9, -1, -1}; // out of range
    EXPECT_THROW(ShaderInstance(prog, {}, Matrix4(1.0), ""), ValueError);
    prog->ops[0].name = "sin"; // wrong arity
    prog->ops[0].jump = {-1, -1, -1, -1};
    try {
        ShaderInstance inst(prog, {}, Matrix4(1.0), "");
        FAIL();
    } catch (const ValueError& e) {
        EXPECT_NE(std::string(e.what()).find("sin("), std::string::npos) << e.what();
    }
}

TEST(RslEngineSpaces, TransformRoundTripsAndNamedSpaces) {
    Engine e;
    Camera& cam = e.services.scene_.options.camera;
    cam.world_to_camera = glm::rotate(glm::translate(Matrix4(1.0), glm::dvec3(0, 0, 4)),
                                      0.3, glm::dvec3(0, 1, 0));
    cam.perspective = true;
    cam.fov = 60;
    e.services.scene_.coordinate_systems["lamp"] = glm::scale(
        glm::translate(Matrix4(1.0), glm::dvec3(1, 0, 0)), glm::dvec3(2, 2, 2));
    Primitive prim;
    prim.object_to_world = glm::translate(Matrix4(1.0), glm::dvec3(0, 3, 0));
    ShadingBatch b = plane_grid(3, 1);
    b.primitive = &prim;
    const auto r = e.run(R"(
surface t(output varying float r = 0; output varying point q = 0;) {
    point w = transform("object", "world", P);
    point back = transform("world", "object", w);
    point c = transform("world", "current", transform("current", "world", P));
    vector v = vtransform("object", "world", vector(1, 0, 0));
    point s = transform("screen", transform("raster", transform("NDC", P)));
    point n = transform("NDC", "current", transform("NDC", P));
    r = distance(back, P) + distance(c, P) + distance(n, P)
        + abs(length(v) - 1) + distance(transform("shader", "current", transform("shader", P)), P);
    q = transform("object", "world", point(0, 0, 0));
}
)",
                         b);
    for (int i = 0; i < 3; ++i) EXPECT_LT(r[i], 1e-4f) << i;
    // Finite on its own: NaN would have been written as 0 and passed.
    EXPECT_EQ(e.context.nonfinite_points(), 0u);
    TypeSpec ty;
    std::vector<float> q;
    e.context.output("q", ty, q);
    EXPECT_NEAR(q[0], 0, 1e-5);
    EXPECT_NEAR(q[1], 3, 1e-5);
    EXPECT_NEAR(q[2], 0, 1e-5);
    // point "lamp" (1, 1, 1) is (3, 2, 2) in world space.
    ShadingBatch b2 = plane_grid(1, 1);
    const auto w = e.run(R"(
surface t(output varying point r = 0;) { r = transform("world", point "lamp" (1, 1, 1)); }
)",
                         b2);
    EXPECT_NEAR(w[0], 3, 1e-5);
    EXPECT_NEAR(w[1], 2, 1e-5);
    EXPECT_NEAR(w[2], 2, 1e-5);

    // An unknown space is "current", with a warning (PRMan's leniency).
    ShaderInstance lenient = e.instance(R"(
surface t(output varying point r = 0;) { r = transform("nowhere", P); }
)");
    EXPECT_NO_THROW(e.context.execute(lenient, b));
}

TEST(RslEngineOps, ColourSpacesAndMatrices) {
    Engine e;
    ShadingBatch b = plane_grid(1, 1);
    const auto r = e.run(R"(
surface t(output varying color r = 0; output varying float d = 0;) {
    r = color "hsv" (0, 1, 1);                 // red
    matrix m = translate(matrix 1, vector(1, 2, 3));
    point p = transform(m, point(1, 1, 1));
    d = determinant(scale(matrix 1, point(2, 3, 4))) + comp(m, 3, 0) * 100 + distance(p, point(2, 3, 4)) * 1000;
}
)",
                         b);
    EXPECT_NEAR(r[0], 1, 1e-5);
    EXPECT_NEAR(r[1], 0, 1e-5);
    EXPECT_NEAR(r[2], 0, 1e-5);
    TypeSpec ty;
    std::vector<float> d;
    e.context.output("d", ty, d);
    EXPECT_NEAR(d[0], 24 + 100, 1e-3);
}

TEST(RslEngineOps, NonFiniteResultsAreZeroedAndCounted) {
    Engine e;
    ShadingBatch b = plane_grid(4, 1);
    ShaderInstance inst = e.instance(R"(
surface t() {
    Ci = 1 / (u - u);   // inf
    if (u > 0.5) Ci = 1;
    Oi = 1;
}
)");
    e.context.execute(inst, b);
    EXPECT_EQ(e.context.nonfinite_points(), 2u);
    EXPECT_NE(e.context.nonfinite_message().find("2 points"), std::string::npos);
    for (int i = 0; i < 4; ++i) EXPECT_EQ(b.Ci[i].x, b.u[i] > 0.5f ? 1.0f : 0.0f);
}

TEST(RslEngineStrings, PrintfAndFormat) {
    Engine e;
    ShadingBatch b = plane_grid(3, 1);
    ShaderInstance inst = e.instance(R"(
surface t(output varying float r = 0;) {
    printf("hello %d\n", 3);
    printf("u=%.2f\n", u);
    string s = format("%s-%g", "x", 2.5);
    if (s == "x-2.5") r = 1;
}
)");
    e.context.execute(inst, b);
    ASSERT_EQ(e.services.messages.size(), 4u);
    EXPECT_EQ(e.services.messages[0], "hello 3\n");
    EXPECT_EQ(e.services.messages[1], "u=0.17\n");
    TypeSpec ty;
    std::vector<float> r;
    e.context.output("r", ty, r);
    EXPECT_EQ(r[0], 1.0f);
}

TEST(RslEngineControl, EndlessLoopsAreStopped) {
    Engine e;
    ShadingBatch b = plane_grid(1, 1);
    ShaderInstance inst = e.instance(R"(
surface t() { float x = 0; while (x >= 0) { x += 1; } Ci = x; }
)");
    try {
        e.context.execute(inst, b);
        FAIL() << "no error";
    } catch (const ShaderRuntimeError& err) {
        EXPECT_NE(std::string(err.what()).find("loop does not end"), std::string::npos);
        EXPECT_NE(std::string(err.what()).find("test.sl:2"), std::string::npos)
            << err.what();
    }
}

TEST(RslEngineControl, RandomIsDeterministic) {
    Engine e;
    ShadingBatch b = plane_grid(16, 1);
    b.seed = 42;
    const char* src = R"(
surface t(output varying float r = 0;) { r = random() + 10 * random(); }
)";
    const auto a = e.run(src, b);
    const auto c = e.run(src, b);
    EXPECT_EQ(a, c);
    for (float x : a) {
        EXPECT_GE(x, 0.0f);
        EXPECT_LT(x, 11.0f);
    }
    EXPECT_NE(a[0], a[1]);
}

} // namespace
