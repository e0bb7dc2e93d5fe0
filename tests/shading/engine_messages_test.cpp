// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file engine_messages_test.cpp
/// Message passing between a surface and its lights: lightsource() inside
/// illuminance, surface() in a light shader, and illuminance's PRMan 13+
/// options "light:NAME" (the light's parameter each iteration),
/// "send:light:NAME" (the lights run with a parameter set) and "lightcache"
/// ("refresh" re-runs the lights).
///
/// Suite names start with "RslEngine".

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "engine_test_util.h"

namespace {

using namespace sss;
using namespace sss::test;

/// A point light at the origin (the eye: it lights the whole plane grid)
/// whose Cl is its intensity, with an output parameter.
const char* kLight = R"(
light msglight(float intensity = 1; output varying float seen = 0;) {
    illuminate(point "shader" (0, 0, 0)) {
        seen = intensity * 10 + xcomp(Ps);
        Cl = intensity;
    }
}
)";

/// A light without an `intensity` parameter, Cl = 0.25.
const char* kOtherLight = R"(
light other(float power = 0.25;) {
    illuminate(point "shader" (0, 0, 0)) { Cl = power; }
}
)";

/// A light whose Cl is the surface's parameter `stage` (surface() message).
const char* kSurfaceReader = R"(
light reader(float dummy = 0;) {
    illuminate(point "shader" (0, 0, 0)) {
        float x = -1;
        float found = surface("stage", x);
        float missing = -2;
        float none = surface("nosuch", missing);
        Cl = color(x, found, none + missing);
    }
}
)";

struct Lights {
    Engine engine;
    std::vector<ShaderInstance> instances;
    std::vector<const ShaderInstance*> list;

    void add(const char* source, ParamList params = {}) {
        instances.push_back(engine.instance(source, params));
    }
    LightList lights() {
        list.clear();
        for (const ShaderInstance& i : instances) list.push_back(&i);
        return list;
    }
    std::vector<float> run(const std::string& source, ShadingBatch& b,
                           const std::string& output) {
        return engine.run(source, b, output, lights());
    }
};

TEST(RslEngineMessages, IlluminanceReceivesTheLightsParameters) {
    Lights rig;
    ParamList two;
    two.set(float_param("intensity", 2));
    rig.add(kLight, two);
    rig.add(kOtherLight);
    ParamList three;
    three.set(float_param("intensity", 3));
    rig.add(kLight, three);
    ShadingBatch b = plane_grid(4, 2);
    // Per light: k is set to the light's intensity before the body; the
    // light without one leaves k alone (-100 from the iteration before).
    const std::vector<float> got = rig.run(R"(
surface s(output varying float got = 0; output varying float seen = 0;) {
    float k = -1, sn = 0;
    illuminance(P, "light:intensity", k, "light:seen", sn) {
        got += k;
        seen += sn;
        k = -100;
        sn = 0;
    }
}
)",
                                           b, "got");
    ASSERT_EQ(got.size(), b.size);
    for (std::size_t i = 0; i < b.size; ++i) EXPECT_EQ(got[i], 2.0f - 100.0f + 3.0f) << i;
    TypeSpec type;
    std::vector<float> seen;
    ASSERT_TRUE(rig.engine.context.output("seen", type, seen));
    for (std::size_t i = 0; i < b.size; ++i)
        EXPECT_EQ(seen[i], (20.0f + b.P[i].x) + (30.0f + b.P[i].x)) << i;
}

TEST(RslEngineMessages, LightsourceInsideIlluminanceOnly) {
    Lights rig;
    ParamList two;
    two.set(float_param("intensity", 2));
    rig.add(kLight, two);
    rig.add(kOtherLight);
    ShadingBatch b = plane_grid(2, 2);
    // Inside: 1 and the value for msglight, 0 (x untouched) for the other;
    // outside illuminance: 0.
    const std::vector<float> got = rig.run(R"(
surface s(output varying float got = 0;) {
    float x = 5;
    float outside = lightsource("intensity", x);
    illuminance(P) {
        float y = -7;
        float r = lightsource("intensity", y);
        got += r * 1000 + y;
    }
    got += outside * 100000 + x * 10000;
}
)",
                                           b, "got");
    for (std::size_t i = 0; i < b.size; ++i)
        EXPECT_EQ(got[i], (1000.0f + 2.0f) + (0.0f - 7.0f) + 50000.0f) << i;
}

TEST(RslEngineMessages, SurfaceFromALightAndLightcacheRefresh) {
    // The light reads the surface's output parameter `stage` when it runs.
    // The second loop reuses the cached light (stage 1 still); "refresh"
    // runs it again and it sees stage 2.
    Lights rig;
    rig.add(kSurfaceReader);
    ShadingBatch b = plane_grid(2, 2);
    rig.run(R"(
surface s(output varying float stage = 1;
          output varying color first = 0; output varying color second = 0;
          output varying color third = 0;) {
    illuminance(P) { first += Cl; }
    stage = 2;
    illuminance(P) { second += Cl; }
    illuminance(P, "lightcache", "refresh") { third += Cl; }
}
)",
            b, "stage");
    const std::vector<std::pair<std::string, glm::vec3>> want = {
        {"first", {1, 1, -2}}, {"second", {1, 1, -2}}, {"third", {2, 1, -2}}};
    for (const auto& [name, value] : want) {
        TypeSpec type;
        std::vector<float> v;
        ASSERT_TRUE(rig.engine.context.output(name, type, v)) << name;
        for (std::size_t i = 0; i < b.size; ++i)
            EXPECT_EQ(glm::vec3(v[3 * i], v[3 * i + 1], v[3 * i + 2]), value)
                << name << " " << i;
    }
}

TEST(RslEngineMessages, SendSetsTheLightsParameterForOneLoop) {
    Lights rig;
    ParamList two;
    two.set(float_param("intensity", 2));
    rig.add(kLight, two);
    ShadingBatch b = plane_grid(2, 2);
    const std::vector<float> got = rig.run(R"(
surface s(output varying float got = 0;) {
    float before = 0, during = 0, after = 0, k = 0;
    illuminance(P) { before += comp(Cl, 0); }
    illuminance(P, "send:light:intensity", 5, "light:intensity", k) {
        during += comp(Cl, 0) * 100 + k;
    }
    illuminance(P) { after += comp(Cl, 0); }
    got = before * 1000000 + during * 100 + after;
}
)",
                                           b, "got");
    for (std::size_t i = 0; i < b.size; ++i)
        EXPECT_EQ(got[i], 2.0f * 1000000 + (5.0f * 100 + 5.0f) * 100 + 2.0f) << i;
}

} // namespace
