// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file engine_arrays_test.cpp
/// Arrays in the shading engine: resizable arrays (push, pop, resize,
/// reserve, arraylength; varying elements, masked pushes, the length limit,
/// index errors naming the shader's file:line), arrays passed to functions
/// (fixed-length parameters, output parameters that grow the caller's array).
///
/// Suite names start with "RslEngine".

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "engine_test_util.h"

namespace {

using namespace sss;
using namespace sss::test;

/// The message of the ShaderRuntimeError `source` throws on a nu x nv grid.
std::string runtime_error(const std::string& source, int nu = 2, int nv = 2) {
    Engine e;
    ShadingBatch b = plane_grid(nu, nv);
    ShaderInstance inst = e.instance(source);
    try {
        e.context.execute(inst, b);
    } catch (const ShaderRuntimeError& err) {
        return err.what();
    }
    ADD_FAILURE() << "no run-time error";
    return "";
}

TEST(RslEngineArrays, PushThreeValuesLengthAndSum) {
    Engine e;
    ShadingBatch b = plane_grid(4, 2);
    e.run(R"(
surface t() {
    float a[];
    push(a, 1.5);
    push(a, u);
    push(a, 4);
    float sum = 0;
    uniform float i;
    for (i = 0; i < arraylength(a); i += 1)
        sum += a[i];
    Ci = color(arraylength(a), sum, a[1]);
}
)",
          b, "Ci");
    for (std::size_t i = 0; i < b.size; ++i) {
        EXPECT_EQ(b.Ci[i].x, 3.0f) << i;
        EXPECT_EQ(b.Ci[i].y, 1.5f + b.u[i] + 4.0f) << i;
        EXPECT_EQ(b.Ci[i].z, b.u[i]) << i;
    }
}

TEST(RslEngineArrays, PopResizeAndInitialiser) {
    Engine e;
    ShadingBatch b = plane_grid(2, 1);
    e.run(R"(
surface t() {
    float a[] = {1, 2, 3};
    float last = pop(a);    /* 3; {1, 2} */
    resize(a, 4);           /* {1, 2, 0, 0} */
    a[3] = 7;
    resize(a, 3);           /* {1, 2, 0} */
    resize(a, 5);           /* {1, 2, 0, 0, 0}: the 7 is gone */
    reserve(a, 100);        /* a hint: nothing changes */
    float code = 0;
    uniform float i;
    for (i = 0; i < arraylength(a); i += 1)
        code = code * 10 + a[i];
    Ci = color(last, arraylength(a), code);
}
)",
          b, "Ci");
    for (std::size_t i = 0; i < b.size; ++i)
        EXPECT_EQ(b.Ci[i], glm::vec3(3.0f, 5.0f, 12000.0f)) << i;
}

TEST(RslEngineArrays, VaryingElementsGrowingPastTheirCapacity) {
    // 100 pushes reallocate several times; the values of every point survive.
    Engine e;
    ShadingBatch b = plane_grid(4, 4);
    e.run(R"(
surface t() {
    point a[];
    uniform float k;
    float direct = 0;
    for (k = 0; k < 100; k += 1) {
        push(a, P * k);
        direct += zcomp(P * k) + xcomp(P * k);
    }
    float sum = 0;
    for (k = 0; k < arraylength(a); k += 1)
        sum += zcomp(a[k]) + xcomp(a[k]);
    Ci = color(sum - direct, arraylength(a), xcomp(a[99]));
}
)",
          b, "Ci");
    for (std::size_t i = 0; i < b.size; ++i) {
        EXPECT_EQ(b.Ci[i].x, 0.0f) << i;
        EXPECT_EQ(b.Ci[i].y, 100.0f) << i;
        EXPECT_EQ(b.Ci[i].z, b.P[i].x * 99.0f) << i;
    }
}

TEST(RslEngineArrays, PushUnderAVaryingConditionGrowsEveryPoint) {
    // The length is one for the batch; the value is stored where the push
    // ran, the others get 0.
    Engine e;
    ShadingBatch b = plane_grid(4, 1);
    e.run(R"(
surface t() {
    float a[];
    if (u > 0.5)
        push(a, u + 10);
    Ci = color(arraylength(a), a[0], 0);
}
)",
          b, "Ci");
    for (std::size_t i = 0; i < b.size; ++i) {
        EXPECT_EQ(b.Ci[i].x, 1.0f) << i;
        EXPECT_EQ(b.Ci[i].y, b.u[i] > 0.5f ? b.u[i] + 10.0f : 0.0f) << i;
    }
}

TEST(RslEngineArrays, StringsAndColours) {
    Engine e;
    ShadingBatch b = plane_grid(2, 1);
    e.run(R"(
surface t() {
    string s[];
    push(s, "ab");
    push(s, "c");
    color c[] = {color(1, 2, 3)};
    push(c, 0.5);
    Ci = color(concat(s[0], s[1]) == "abc" ? 1 : 0, comp(c[0], 2), comp(c[1], 1));
}
)",
          b, "Ci");
    for (std::size_t i = 0; i < b.size; ++i)
        EXPECT_EQ(b.Ci[i], glm::vec3(1.0f, 3.0f, 0.5f)) << i;
}

TEST(RslEngineArrays, FunctionsGrowTheCallersArray) {
    Engine e;
    ShadingBatch b = plane_grid(2, 2);
    e.run(R"(
void fill(output float v[]; uniform float n) {
    uniform float i;
    for (i = 0; i < n; i += 1)
        push(v, i * 2 + u);
}
float total(float v[]) {
    float s = 0;
    uniform float i;
    for (i = 0; i < arraylength(v); i += 1)
        s += v[i];
    return s;
}
surface t() {
    float a[];
    fill(a, 4);
    fill(a, 1);
    float f[3] = {1, 2, 3};
    Ci = color(arraylength(a), total(a), total(f));
}
)",
          b, "Ci");
    for (std::size_t i = 0; i < b.size; ++i) {
        const float u = b.u[i];
        const float want = ((((0 + u) + (2 + u)) + (4 + u)) + (6 + u)) + (0 + u);
        EXPECT_EQ(b.Ci[i], glm::vec3(5.0f, want, 6.0f)) << i;
    }
}

TEST(RslEngineArrays, FixedLengthArrayParameter) {
    Engine e;
    ShadingBatch b = plane_grid(2, 1);
    e.run(R"(
matrix array_to_mx(float mx[16]) {
    return matrix (mx[0], mx[1], mx[2], mx[3], mx[4], mx[5], mx[6], mx[7],
                   mx[8], mx[9], mx[10], mx[11], mx[12], mx[13], mx[14], mx[15]);
}
surface t() {
    float m[16] = {2,0,0,0, 0,3,0,0, 0,0,4,0, 5,6,7,1};
    matrix x = array_to_mx(m);
    point p = transform(x, point(1, 1, 1));
    Ci = color(determinant(x), xcomp(p), zcomp(p));
}
)",
          b, "Ci");
    for (std::size_t i = 0; i < b.size; ++i)
        EXPECT_EQ(b.Ci[i], glm::vec3(24.0f, 7.0f, 11.0f)) << i;
}

TEST(RslEngineArrays, IndexOutOfRangeNamesTheLine) {
    const std::string what = runtime_error(R"(surface t() {
    float a[] = {1, 2};
    push(a, 3);
    Ci = a[3];
}
)");
    EXPECT_NE(what.find("test.rib:1: test.sl:4: shader 't': array index 3.000000 out "
                        "of range [0, 3)"),
              std::string::npos)
        << what;
}

TEST(RslEngineArrays, AssignOutOfRangeAndEmptyPop) {
    std::string what = runtime_error("surface t() {\n    float a[];\n    a[0] = 1;\n}\n");
    EXPECT_NE(
        what.find("test.sl:3: shader 't': array index 0.000000 out of range [0, 0)"),
        std::string::npos)
        << what;
    what = runtime_error("surface t() {\n    float a[] = {1};\n    float x = pop(a);\n   "
                         " x = pop(a);\n}\n");
    EXPECT_NE(what.find("test.sl:4: shader 't': pop: the array is empty"),
              std::string::npos)
        << what;
}

TEST(RslEngineArrays, LengthLimit) {
    std::string what =
        runtime_error("surface t() {\n    float a[];\n    resize(a, 2000000);\n}\n");
    EXPECT_NE(
        what.find("test.sl:3: shader 't': resize: an array of 2000000 elements "
                  "exceeds the limit of 1000000 (set SSS_LIMIT_SHADER_ARRAY_LENGTH"),
        std::string::npos)
        << what;
    what = runtime_error("surface t() {\n    float a[];\n    resize(a, -1);\n}\n");
    EXPECT_NE(what.find("resize: a negative array length (-1)"), std::string::npos)
        << what;
    // The storage of the whole batch is bounded too: 1e6 matrices over 32 points.
    what = runtime_error(
        "surface t() {\n    varying matrix a[];\n    resize(a, 1000000);\n}\n", 4, 8);
    EXPECT_NE(what.find("test.sl:3: shader 't': a resizable array of 1000000 elements of "
                        "16 floats over 32 points needs more than 268435456 floats"),
              std::string::npos)
        << what;
}

TEST(RslEngineArrays, EveryBatchStartsAfresh) {
    // One instance over batches of different sizes: the storage is reset.
    Engine e;
    ShaderInstance inst = e.instance(R"(
surface t() {
    varying float a[];
    push(a, u);
    push(a, v);
    Ci = color(arraylength(a), a[0], a[1]);
}
)");
    for (int n : {4, 1, 3}) {
        ShadingBatch b = plane_grid(n, 2);
        e.context.execute(inst, b);
        for (std::size_t i = 0; i < b.size; ++i)
            EXPECT_EQ(b.Ci[i], glm::vec3(2.0f, b.u[i], b.v[i])) << n << " " << i;
    }
}

} // namespace
