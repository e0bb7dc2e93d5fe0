// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file engine_light_normal_test.cpp
/// A light shader's N global is the surface normal at Ps (PRMan's
/// convention, which envlight's `illuminate(Ps + N)` relies on): the surface
/// frame's N global, else the batch's N, and the light cache is re-run when
/// the surface's N changes at the same P.
///
/// Suite names start with "RslEngine".

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "engine_test_util.h"

namespace {

using namespace sss;
using namespace sss::test;

const char* kNormalLight = R"(
light nlight() {
    illuminate(Ps + N) { Cl = color(xcomp(N), ycomp(N), zcomp(N)); }
}
)";

glm::vec3 output3(Engine& e, const char* name, std::size_t i) {
    TypeSpec ty;
    std::vector<float> v;
    EXPECT_TRUE(e.context.output(name, ty, v)) << name;
    if (v.size() < 3 * (i + 1)) return glm::vec3(-99.0f);
    return glm::vec3(v[3 * i], v[3 * i + 1], v[3 * i + 2]);
}

TEST(RslEngineLighting, LightShadersSeeTheSurfaceNormal) {
    Engine e;
    ShaderInstance light = e.instance(kNormalLight);
    const std::vector<const ShaderInstance*> lv = {&light};
    LightList lights = lv;
    // Points with different normals (the batch's N).
    ShadingBatch b;
    b.layout = BatchLayout::Points;
    b.size = 3;
    b.P = {{0, 0, 1}, {1, 0, 1}, {0, 1, 2}};
    b.N = {{0, 0, -1}, {0.6f, 0, -0.8f}, {0, 1, 0}};
    b.Ng = b.N;
    b.I = b.P;
    ShaderInstance s = e.instance(R"(
surface t(output varying color first = 0; output varying color second = 0;
          output varying color third = 0; output varying vector Ldir = 0;) {
    illuminance(P) { first += Cl; Ldir = L; }
    N = -N;
    illuminance(P) { second += Cl; }
    N = normal(1, 2, 3);
    illuminance(P) { third += Cl; }
}
)");
    e.context.execute(s, b, lights);
    for (std::size_t i = 0; i < 3; ++i) {
        const glm::vec3 n = b.N[i];
        const glm::vec3 first = output3(e, "first", i);
        EXPECT_NEAR(first.x, n.x, 1e-6) << i;
        EXPECT_NEAR(first.y, n.y, 1e-6) << i;
        EXPECT_NEAR(first.z, n.z, 1e-6) << i;
        // illuminate(Ps + N): the light arrives along N (L towards the light = N).
        const glm::vec3 L = output3(e, "Ldir", i);
        EXPECT_NEAR(L.x, n.x, 1e-5) << i;
        EXPECT_NEAR(L.y, n.y, 1e-5) << i;
        EXPECT_NEAR(L.z, n.z, 1e-5) << i;
        // The surface changed N at the same P: the light ran again with it.
        const glm::vec3 second = output3(e, "second", i);
        EXPECT_NEAR(second.x, -n.x, 1e-6) << i;
        EXPECT_NEAR(second.z, -n.z, 1e-6) << i;
        const glm::vec3 third = output3(e, "third", i);
        EXPECT_NEAR(third.x, 1.0f, 1e-6) << i;
        EXPECT_NEAR(third.y, 2.0f, 1e-6) << i;
        EXPECT_NEAR(third.z, 3.0f, 1e-6) << i;
    }
}

TEST(RslEngineLighting, DiffuseUnderANormalLightIsOne) {
    // A light along each point's own normal: diffuse(N) = Cl (N.L = 1).
    Engine e;
    ShaderInstance light = e.instance(R"(
light nl() { illuminate(Ps + N) { Cl = color(0.5, 1, 2); } }
)");
    const std::vector<const ShaderInstance*> lv = {&light};
    LightList lights = lv;
    ShadingBatch b = plane_grid(2, 2);
    std::vector<float> r = e.run(R"(
surface t(output varying color r = 0;) { r = diffuse(normalize(N)); }
)",
                                 b, "r", lights);
    ASSERT_EQ(r.size(), 12u);
    for (std::size_t i = 0; i < 4; ++i) {
        EXPECT_NEAR(r[3 * i], 0.5f, 1e-5);
        EXPECT_NEAR(r[3 * i + 1], 1.0f, 1e-5);
        EXPECT_NEAR(r[3 * i + 2], 2.0f, 1e-5);
    }
}

TEST(RslEngineLighting, EnvlightWithoutAMapIsAWhiteSky) {
    // shaders/envlight.sl with no map and nothing to occlude it: Cl = 1 along
    // N, so diffuse(N) = intensity * lightcolor for every N; __nonspecular.
    std::ifstream in(std::filesystem::path(SSS_TEST_DATA_DIR) / ".." / ".." / "shaders" /
                     "envlight.sl");
    ASSERT_TRUE(in) << "shaders/envlight.sl";
    std::stringstream text;
    text << in.rdbuf();
    Engine e;
    ParamList p;
    p.set(float_param("intensity", 0.5));
    p.set(float_param("samples", 16));
    ShaderInstance light = e.instance(text.str(), p);
    const std::vector<const ShaderInstance*> lv = {&light};
    LightList lights = lv;
    ShadingBatch b;
    b.layout = BatchLayout::Points;
    b.size = 3;
    b.P = {{0, 0, 1}, {1, 0, 1}, {0, 1, 2}};
    b.N = {{0, 0, -1}, {0.6f, 0, -0.8f}, {0, 1, 0}};
    b.Ng = b.N;
    b.I = b.P;
    std::vector<float> r = e.run(R"(
surface t(output varying color r = 0; output varying color spec = 0;) {
    r = diffuse(normalize(N));
    spec = specular(normalize(N), -normalize(I), 0.1);
}
)",
                                 b, "r", lights);
    ASSERT_EQ(r.size(), 9u);
    for (float v : r) EXPECT_NEAR(v, 0.5f, 1e-5);
    TypeSpec ty;
    std::vector<float> spec;
    ASSERT_TRUE(e.context.output("spec", ty, spec));
    for (float v : spec) EXPECT_EQ(v, 0.0f);
}

} // namespace
