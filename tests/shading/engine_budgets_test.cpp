// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file engine_budgets_test.cpp
/// The shading engine's budgets (docs/limits.md): operations per batch,
/// string and resizable-array lengths, bake3d points and files per job,
/// match()'s patterns and the memory budget. Each hostile shader ends with a
/// typed error naming the shader, its file:line and the limit.

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "engine_test_util.h"
#include "sss/util/limits.h"

namespace sss {
namespace {

using test::Engine;
using test::plane_grid;

/// Lowers limits for one test and restores them after.
class ShaderBudgets : public ::testing::Test {
protected:
    void TearDown() override {
        for (Limit l :
             {Limit::ShaderOperations, Limit::ShaderStringLength,
              Limit::ShaderArrayLength, Limit::Bake3dPoints, Limit::Bake3dFiles})
            set_limit(l, 0);
        unsetenv("SSS_MEMORY_LIMIT");
    }

    /// The error message of running `source` over a 4 x 4 grid (with
    /// `lights`), or "" when it runs.
    template <class Error = ShaderRuntimeError>
    std::string run_error(const std::string& source) {
        ShadingBatch b = plane_grid(4, 4);
        ShaderInstance inst = engine.instance(source);
        try {
            engine.context.execute(inst, b);
        } catch (const Error& e) {
            return e.what();
        }
        return "";
    }

    Engine engine;
};

/// `message` names the RIB call, the shader with its file:line and `limit`.
void expect_names(const std::string& message, int line, const std::string& limit) {
    EXPECT_NE(
        message.find("test.rib:1: test.sl:" + std::to_string(line) + ": shader 't'"),
        std::string::npos)
        << message;
    EXPECT_NE(message.find(limit), std::string::npos) << message;
}

TEST_F(ShaderBudgets, NestedLoopsEachUnderTheLoopGuard) {
    set_limit(Limit::ShaderOperations, 100000);
    const std::string e = run_error(R"(surface t() {
    float x = 0, i, j;
    for (i = 0; i < 1e6; i += 1)
        for (j = 0; j < 1e6; j += 1)
            x += 1;
    Ci = x;
})");
    expect_names(e, 5, "than the limit of 100000");
    EXPECT_NE(e.find("SSS_LIMIT_SHADER_OPERATIONS"), std::string::npos) << e;
}

TEST_F(ShaderBudgets, EmptyLoopsCountTheirIterations) {
    set_limit(Limit::ShaderOperations, 1000);
    // Constant condition, empty body: no op runs per iteration.
    expect_names(run_error("surface t() {\n    while (1) { }\n}"), 2,
                 "SSS_LIMIT_SHADER_OPERATIONS");
}

TEST_F(ShaderBudgets, LoopsThroughInlinedFunctions) {
    set_limit(Limit::ShaderOperations, 50000);
    const std::string e = run_error(R"(float inner(float n) {
    float s = 0, k;
    for (k = 0; k < n; k += 1) s += k;
    return s;
}
float outer(float n) {
    float s = 0, k;
    for (k = 0; k < n; k += 1) s += inner(n);
    return s;
}
surface t() {
    float i, x = 0;
    for (i = 0; i < 1000; i += 1) x += outer(1000);
    Ci = x;
})");
    expect_names(e, 3, "SSS_LIMIT_SHADER_OPERATIONS");
}

TEST_F(ShaderBudgets, GatherBodies) {
    set_limit(Limit::ShaderOperations, 100000);
    // No ray tracer: every sample misses and runs the else body.
    const std::string e = run_error(R"(surface t() {
    float x = 0, i;
    gather("", P, N, PI / 2, 4096) {
        x += 1;
    } else {
        for (i = 0; i < 100; i += 1) x += 1;
    }
    Ci = x;
})");
    expect_names(e, 6, "SSS_LIMIT_SHADER_OPERATIONS");
}

TEST_F(ShaderBudgets, IlluminanceBodiesAndLightsShareTheBudget) {
    set_limit(Limit::ShaderOperations, 20000);
    ParamList none;
    ShaderInstance light(test::compile_shader(R"(light busy() {
    float i, x = 0;
    for (i = 0; i < 1000; i += 1) x += 1;
    illuminate(point "shader" (0, 0, 0)) { Cl = x; }
})"),
                         none, Matrix4(1.0), "test.rib:1");
    const ShaderInstance* list[] = {&light, &light, &light, &light};
    ShadingBatch b = plane_grid(4, 4);
    ShaderInstance surface = engine.instance(R"(surface t() {
    color c = 0;
    float i;
    for (i = 0; i < 100; i += 1)
        illuminance(P, "lightcache", "refresh") { c += Cl; }
    Ci = c;
})");
    try {
        engine.context.execute(surface, b, list);
        FAIL() << "no error";
    } catch (const ShaderRuntimeError& e) {
        // The light's loop runs out of the batch's budget.
        EXPECT_NE(std::string(e.what()).find("test.sl:3: shader 'busy'"),
                  std::string::npos)
            << e.what();
        EXPECT_NE(std::string(e.what()).find("SSS_LIMIT_SHADER_OPERATIONS"),
                  std::string::npos);
    }
}

TEST_F(ShaderBudgets, TheBudgetIsPerBatch) {
    set_limit(Limit::ShaderOperations, 20000);
    const char* source = R"(surface t(output varying float r = 0) {
    float i;
    for (i = 0; i < 1000; i += 1) r += 1;
})";
    for (int k = 0; k < 5; ++k) {
        ShadingBatch b = plane_grid(4, 4);
        EXPECT_EQ(engine.run(source, b)[0], 1000.0f);
    }
}

TEST_F(ShaderBudgets, StringDoublingWithConcat) {
    set_limit(Limit::ShaderStringLength, 1000);
    const std::string e = run_error(R"(surface t() {
    string s = "ab";
    float i;
    for (i = 0; i < 40; i += 1)
        s = concat(s, s);
    printf("%s", s);
})");
    expect_names(e, 5, "a string of 1024 bytes exceeds the limit of 1000");
    EXPECT_NE(e.find("SSS_LIMIT_SHADER_STRING_LENGTH"), std::string::npos) << e;
}

TEST_F(ShaderBudgets, StringDoublingWithFormat) {
    set_limit(Limit::ShaderStringLength, 1000);
    const std::string e = run_error(R"(surface t() {
    string s = "ab";
    float i;
    for (i = 0; i < 40; i += 1) {
        s = format("%s%s", s, s);
    }
    printf("%s", s);
})");
    expect_names(e, 5, "a string of 1024 bytes exceeds the limit of 1000");
}

TEST_F(ShaderBudgets, ArrayGrowthWithPush) {
    set_limit(Limit::ShaderArrayLength, 1000);
    const std::string e = run_error(R"(surface t() {
    float a[];
    float i;
    for (i = 0; i < 1e6; i += 1)
        push(a, i);
    Ci = arraylength(a);
})");
    expect_names(e, 5, "push: an array of 1001 elements exceeds the limit of 1000");
    EXPECT_NE(e.find("SSS_LIMIT_SHADER_ARRAY_LENGTH"), std::string::npos) << e;
}

TEST_F(ShaderBudgets, ArrayGrowthWithResize) {
    // The default: one million elements.
    const std::string e = run_error(R"(surface t() {
    float a[];
    float n = 1;
    while (n < 1e9) {
        n *= 2;
        resize(a, n);
    }
    Ci = arraylength(a);
})");
    expect_names(e, 6,
                 "resize: an array of 1048576 elements exceeds the limit of 1000000");
}

TEST_F(ShaderBudgets, Bake3dFloodInALoop) {
    set_limit(Limit::Bake3dPoints, 1000);
    const std::string e = run_error(R"(surface t() {
    float i;
    for (i = 0; i < 1e6; i += 1)
        bake3d("flood.ptc", "a", P, N, "a", i);
})");
    expect_names(e, 4,
                 "bake3d \"flood.ptc\": the points baked in one job exceed the limit "
                 "of 1000 (set SSS_LIMIT_BAKE3D_POINTS to raise it)");
    // Nothing past the limit was handed over.
    std::size_t points = 0;
    for (const Bake3dRecord& r : engine.services.bakes) points += r.P.size();
    EXPECT_LE(points, 1000u);
}

TEST_F(ShaderBudgets, Bake3dPointsAreCountedOverTheJob) {
    set_limit(Limit::Bake3dPoints, 40);
    const char* source = R"(surface t() {
    bake3d("job.ptc", "", P, N);
})";
    ShaderInstance inst = engine.instance(source);
    for (int k = 0; k < 2; ++k) {
        ShadingBatch b = plane_grid(4, 4);
        engine.context.execute(inst, b);
    }
    ShadingBatch b = plane_grid(4, 4);
    EXPECT_THROW(engine.context.execute(inst, b), ShaderRuntimeError);
}

TEST_F(ShaderBudgets, Bake3dFilesPerJob) {
    set_limit(Limit::Bake3dFiles, 4);
    const std::string e = run_error(R"(surface t() {
    float i;
    for (i = 0; i < 100; i += 1)
        bake3d(format("part%d.ptc", i), "", P, N);
})");
    expect_names(e, 4,
                 "bake3d \"part4.ptc\": a new file after 4: the files of one job exceeds "
                 "the limit of 4 (set SSS_LIMIT_BAKE3D_FILES to raise it)");
}

TEST_F(ShaderBudgets, RegexBomb) {
    const std::string e = run_error(R"(surface t() {
    float m = 0;
    m = match("((a{1,100}){1,100}){1,100}", "aaaa");
    Ci = m;
})");
    expect_names(e, 3, "more than the bound of 2000");
    EXPECT_NE(e.find("match(\"((a{1,100}){1,100}){1,100}\")"), std::string::npos) << e;
}

TEST_F(ShaderBudgets, InvalidRegex) {
    const std::string e = run_error(R"(surface t() {
    float m = 0;
    m = match("(unclosed", "aaaa");
    Ci = m;
})");
    expect_names(e, 3, "match(\"(unclosed\"): invalid regular expression");
}

TEST_F(ShaderBudgets, ArraysCountAgainstTheMemoryBudget) {
    // 16 points x 1,000,000 floats = 64 MB, over a budget of what the test
    // already uses plus 16 MB.
    const uint64_t budget = resident_memory() + (uint64_t(16) << 20);
    setenv("SSS_MEMORY_LIMIT", std::to_string(budget).c_str(), 1);
    const std::string e = run_error<OutOfMemoryError>(R"(surface t() {
    varying float a[];
    resize(a, 1000000);
    Ci = arraylength(a);
})");
    expect_names(e, 3, "SSS_MEMORY_LIMIT");
    EXPECT_NE(e.find("a resizable array of 1000000 elements over 16 points needs about"),
              std::string::npos)
        << e;
}

TEST_F(ShaderBudgets, StringsCountAgainstTheMemoryBudget) {
    const uint64_t budget = resident_memory() + (uint64_t(48) << 20);
    setenv("SSS_MEMORY_LIMIT", std::to_string(budget).c_str(), 1);
    // Distinct strings of 64 KB per iteration: 64 MB after 1000.
    const std::string e = run_error<OutOfMemoryError>(R"(surface t() {
    string s = "x";
    float i;
    for (i = 0; i < 16; i += 1) s = concat(s, s);
    for (i = 0; i < 100000; i += 1) {
        string t = format("%s%d", s, i);
    }
})");
    expect_names(e, 6, "SSS_MEMORY_LIMIT");
    EXPECT_NE(e.find("the shader's strings"), std::string::npos) << e;
}

} // namespace
} // namespace sss
