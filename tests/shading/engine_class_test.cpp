// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file engine_class_test.cpp
/// RSL 2.0 shader classes in the shading engine: the pipelines (a class's
/// surface method gives what the classic shader gives; prelighting,
/// lighting and postlighting; member variables between methods; a class
/// that displaces and shades; a light class), and co-shaders (getshader,
/// getlights, method calls, getvar, a wrapper calling another class's
/// pipeline method) (engine_coshader.cpp).
///
/// Suite names start with "RslEngine".

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "engine_test_util.h"

namespace {

using namespace sss;
using namespace sss::test;

const char* kPointLight = R"(
light pointlight(float intensity = 1; color lightcolor = 1;
                 point from = point "shader" (0, 0, 0);) {
    illuminate(from) { Cl = intensity * lightcolor / (L . L); }
}
)";

const char* kPointLightClass = R"(
class pointlight2(float intensity = 1; color lightcolor = 1;
                  point from = point "shader" (0, 0, 0);) {
    public void light(output vector L; output color Cl) {
        illuminate(from) { Cl = intensity * lightcolor / (L . L); }
    }
}
)";

const char* kPlastic = R"(
surface plastic(float Ka = 1, Kd = .5, Ks = .5, roughness = .1; color specularcolor = 1;) {
    normal Nf = faceforward(normalize(N), I);
    vector V = -normalize(I);
    Oi = Os;
    Ci = Os * (Cs * (Ka * ambient() + Kd * diffuse(Nf)) +
               specularcolor * Ks * specular(Nf, V, roughness));
}
)";

const char* kPlasticClass = R"(
class plastic2(float Ka = 1, Kd = .5, Ks = .5, roughness = .1; color specularcolor = 1;) {
    public void surface(output color Ci, Oi) {
        normal Nf = faceforward(normalize(N), I);
        vector V = -normalize(I);
        Oi = Os;
        Ci = Os * (Cs * (Ka * ambient() + Kd * diffuse(Nf)) +
                   specularcolor * Ks * specular(Nf, V, roughness));
    }
}
)";

/// A grid facing the eye with Cs varying over it, lit by a point light.
struct Lit {
    Engine e;
    ShadingBatch batch = plane_grid(6, 5);
    ShaderInstance light;
    std::vector<const ShaderInstance*> lights;

    explicit Lit(const char* light_source = kPointLight)
        : light(e.instance(light_source, params(), Matrix4(1.0))) {
        light.set_handle("key");
        lights.push_back(&light);
        for (std::size_t i = 0; i < batch.size; ++i)
            batch.Cs.push_back(glm::vec3(batch.u[i], 0.5f, 1.0f - batch.v[i]));
    }
    static ParamList params() {
        ParamList p;
        p.set(point_param("from", {0.3, 0.4, -1.0}));
        p.set(float_param("intensity", 2.0));
        return p;
    }
    std::vector<glm::vec3> shade(const ShaderInstance& s, CoshaderList coshaders = {}) {
        ShadingBatch b = batch;
        e.context.execute(s, b, lights, coshaders);
        return b.Ci;
    }
};

void expect_same(const std::vector<glm::vec3>& got, const std::vector<glm::vec3>& want,
                 float tol = 1e-6f) {
    ASSERT_EQ(got.size(), want.size());
    float biggest = 0.0f;
    for (std::size_t i = 0; i < got.size(); ++i) {
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(got[i][k], want[i][k], tol) << i;
        biggest = std::max(biggest, want[i].x);
    }
    EXPECT_GT(biggest, 0.05f); // something was lit
}

TEST(RslEngineClass, SurfaceMethodGivesTheClassicShadersResult) {
    Lit lit;
    ShaderInstance classic = lit.e.instance(kPlastic);
    ShaderInstance cls = lit.e.instance(kPlasticClass);
    expect_same(lit.shade(cls), lit.shade(classic));
}

TEST(RslEngineClass, StagedLightingGivesClassicDiffuse) {
    Lit lit;
    ShaderInstance classic = lit.e.instance(R"(
surface matte(float Kd = 0.8;) {
    normal Nf = faceforward(normalize(N), I);
    Oi = Os;
    Ci = Oi * Cs * Kd * diffuse(Nf);
}
)");
    // The pattern in prelighting, the light in lighting, the opacity in
    // postlighting: member variables carry the values between them.
    ShaderInstance cls = lit.e.instance(R"(
class matte2(float Kd = 0.8;) {
    varying color m_pattern;
    varying color m_light;
    public void opacity(output color Oi) { Oi = Os; }
    public void prelighting(output color Ci, Oi) { m_pattern = Cs * Kd; }
    public void lighting(output color Ci, Oi) {
        normal Nf = faceforward(normalize(N), I);
        m_light = diffuse(Nf);
        Ci = m_pattern * m_light;
    }
    public void postlighting(output color Ci, Oi) { Ci *= Oi; }
}
)");
    expect_same(lit.shade(cls), lit.shade(classic));
}

TEST(RslEngineClass, MemberVariablesKeepTheirValuesBetweenMethods) {
    Engine e;
    ShadingBatch b = plane_grid(4, 3);
    ShaderInstance s = e.instance(R"(
class counter(float k = 3;) {
    float m_start = 5;          // an initialiser
    uniform float m_steps = 0;
    varying float m_value;
    float add(float x) { m_steps += 1; return m_value + x; }
    public void construct() { m_steps = 10; }
    public void begin() { m_value = u * k; m_steps += 1; }
    public void prelighting(output color Ci, Oi) { m_value = add(m_start); }
    public void lighting(output color Ci, Oi) { Ci = color(m_value, m_steps, v); }
}
)");
    e.context.execute(s, b);
    for (std::size_t i = 0; i < b.size; ++i) {
        EXPECT_NEAR(b.Ci[i].x, b.u[i] * 3.0f + 5.0f, 1e-6f) << i;
        EXPECT_EQ(b.Ci[i].y, 12.0f) << i; // construct, begin, add
        EXPECT_NEAR(b.Ci[i].z, b.v[i], 1e-6f) << i;
    }
    // Each batch starts again from the initialisers.
    ShadingBatch again = plane_grid(4, 3);
    e.context.execute(s, again);
    EXPECT_EQ(again.Ci[0].y, 12.0f);
}

TEST(RslEngineClass, ClassThatDisplacesAndShades) {
    Engine e;
    ShaderInstance s = e.instance(R"(
class bumps(float Km = 0.25;) {
    public void displacement(output point P; output normal N) {
        P += Km * u * normalize(N);
        N = calculatenormal(P);
    }
    public void surface(output color Ci, Oi) {
        Oi = 1;
        Ci = color(zcomp(P), xcomp(normalize(N)), 0);
    }
}
)");
    ShadingBatch b = plane_grid(8, 8);
    const std::vector<glm::vec3> before = b.P;
    e.context.execute_as(ShaderKind::Displacement, s, b);
    for (std::size_t i = 0; i < b.size; ++i) {
        // N = (0, 0, -1): the points move towards the eye by Km * u.
        EXPECT_NEAR(b.P[i].z, before[i].z - 0.25f * b.u[i], 1e-5f) << i;
        // The plane now slopes along u (dP/du = (1, 0, -0.25)): the new
        // normal is perpendicular to it.
        const glm::vec3 n = glm::normalize(b.N[i]);
        EXPECT_NEAR(glm::dot(n, glm::vec3(1.0f, 0.0f, -0.25f)), 0.0f, 1e-4f) << i;
        EXPECT_NEAR(std::abs(n.x), 0.25f / std::sqrt(1.0625f), 1e-4f) << i;
    }
    // Shading the displaced points: the surface method sees them.
    e.context.execute(s, b);
    for (std::size_t i = 0; i < b.size; ++i) {
        EXPECT_NEAR(b.Ci[i].x, b.P[i].z, 1e-6f) << i;
        EXPECT_NEAR(b.Ci[i].y, glm::normalize(b.N[i]).x, 1e-5f) << i;
    }
    EXPECT_THROW(e.context.execute_as(ShaderKind::Light, s, b), ValueError);
}

TEST(RslEngineClass, LightClassLightsLikeTheClassicLight) {
    Lit classic(kPointLight);
    Lit cls(kPointLightClass);
    ShaderInstance a = classic.e.instance(kPlastic);
    ShaderInstance b = cls.e.instance(kPlastic);
    expect_same(cls.shade(b), classic.shade(a));
}

// --- co-shaders -----------------------------------------------------------------

const char* kLayer = R"(
class layer(color tint = color(1, 0.5, 0.25); float gain = 2;) {
    uniform float m_calls = 0;
    public color value(float x) { m_calls += 1; return tint * x * gain; }
    public float calls() { return m_calls; }
    public void scale(output color c; float by) { c *= by; }
}
)";

TEST(RslEngineCoshader, MethodCallsThroughGetshader) {
    Lit lit;
    ShaderInstance layer = lit.e.instance(kLayer);
    layer.set_handle("base");
    std::vector<const ShaderInstance*> co{&layer};
    ShaderInstance main = lit.e.instance(R"(
class main(string layername = "base";) {
    shader m_layer;
    public void begin() { m_layer = getshader(layername); }
    public void surface(output color Ci, Oi) {
        color c = m_layer->value(u);
        float first = m_layer->calls();
        c = m_layer->value(u) + c;     // the co-shader's members persist
        m_layer->scale(c, 0.5);        // an output argument
        float g = 0, missing = 7;
        float has = getvar(m_layer, "gain", g) + getvar(m_layer, "nothing", missing);
        Ci = c;
        Oi = color(first, m_layer->calls(), has * 10 + g + missing);
    }
}
)");
    ShadingBatch b = lit.batch;
    lit.e.context.execute(main, b, {}, co);
    for (std::size_t i = 0; i < b.size; ++i) {
        const float u = b.u[i];
        // 0.5 * (2 * tint * u * gain) = tint * u * 2
        EXPECT_NEAR(b.Ci[i].x, 2.0f * u, 1e-6f) << i;
        EXPECT_NEAR(b.Ci[i].y, 1.0f * u, 1e-6f) << i;
        EXPECT_NEAR(b.Ci[i].z, 0.5f * u, 1e-6f) << i;
        EXPECT_EQ(b.Oi[i].x, 1.0f);
        EXPECT_EQ(b.Oi[i].y, 2.0f);
        EXPECT_EQ(b.Oi[i].z, 10.0f + 2.0f + 7.0f); // gain found, "nothing" not
    }
    EXPECT_TRUE(lit.e.services.warnings.empty());

    // Without the co-shader the handle is null: calls do nothing, warned.
    ShadingBatch none = lit.batch;
    lit.e.context.execute(main, none);
    EXPECT_EQ(none.Ci[3], glm::vec3(0.0f));
    ASSERT_FALSE(lit.e.services.warnings.empty());
    EXPECT_NE(lit.e.services.warnings[0].find("null shader"), std::string::npos);
}

TEST(RslEngineCoshader, LightsCalledThroughGetlightsGiveDiffuse) {
    Lit lit(kPointLightClass);
    ShaderInstance classic = lit.e.instance(R"(
surface matte(float Kd = 1;) {
    normal Nf = faceforward(normalize(N), I);
    Ci = Cs * Kd * diffuse(Nf);
}
)");
    // The RSL 2.0 way: the surface runs the lights' light() itself.
    ShaderInstance cls = lit.e.instance(R"(
class lambert(float Kd = 1;) {
    public void lighting(output color Ci, Oi) {
        normal Nf = faceforward(normalize(N), I);
        shader lights[] = getlights();
        uniform float i, n = arraylength(lights);
        color sum = 0;
        for (i = 0; i < n; i += 1) {
            vector L;
            color Cl;
            lights[i]->light(L, Cl);
            sum += Cl * max(0, normalize(-L) . Nf);
        }
        shader key = getlight("key");
        float k = 0;
        float found = getvar(key, "intensity", k);
        Ci = Cs * Kd * sum;
        Oi = color(found, k, n);
    }
}
)");
    ShadingBatch b = lit.batch;
    lit.e.context.execute(cls, b, lit.lights);
    expect_same(b.Ci, lit.shade(classic), 1e-5f);
    EXPECT_EQ(b.Oi[0], glm::vec3(1.0f, 2.0f, 1.0f));
}

TEST(RslEngineCoshader, WrapperRunsAnotherClassesPipelineMethod) {
    Lit lit;
    ShaderInstance wrapped = lit.e.instance(kPlasticClass);
    wrapped.set_handle("inner");
    std::vector<const ShaderInstance*> co{&wrapped};
    ShaderInstance wrapper = lit.e.instance(R"(
class wrapper(string wrapped_handle = "inner"; output uniform float ran = 0;) {
    uniform shader _wrapped;
    public void begin() { _wrapped = getshader(wrapped_handle); }
    public void surface(output color Ci, Oi) {
        if (_wrapped != null) _wrapped->surface(Ci, Oi);
        ran = 1;
    }
}
)");
    ShaderInstance direct = lit.e.instance(kPlasticClass);
    const std::vector<glm::vec3> want = lit.shade(direct);
    expect_same(lit.shade(wrapper, co), want);

    // A classic shader called by the name of its type runs its body.
    ShaderInstance classic = lit.e.instance(kPlastic);
    classic.set_handle("inner");
    std::vector<const ShaderInstance*> old{&classic};
    expect_same(lit.shade(wrapper, old), want);
    EXPECT_TRUE(lit.e.services.warnings.empty());
}

TEST(RslEngineCoshader, VaryingHandlesCallEachShaderForItsPoints) {
    Engine e;
    ShaderInstance a = e.instance(kLayer);
    a.set_handle("a");
    ParamList p;
    p.set(float_param("gain", 10.0));
    ShaderInstance b = e.instance(kLayer, p);
    b.set_handle("b");
    std::vector<const ShaderInstance*> co{&a, &b};
    ShaderInstance s = e.instance(R"(
surface pick() {
    shader all[] = getshaders();
    shader which = u < 0.5 ? all[0] : all[1];
    Ci = which->value(1);
}
)");
    ShadingBatch batch = plane_grid(4, 2);
    e.context.execute(s, batch, {}, co);
    for (std::size_t i = 0; i < batch.size; ++i)
        EXPECT_EQ(batch.Ci[i].x, batch.u[i] < 0.5f ? 2.0f : 10.0f) << i;
}

TEST(RslEngineCoshader, CoshadersCallCoshaders) {
    Engine e;
    ShaderInstance leaf = e.instance(kLayer);
    leaf.set_handle("leaf");
    // Each call reaches a co-shader not handed out before it ran.
    ShaderInstance mid = e.instance(R"(
class mid() {
    public color value(float x) {
        shader l = getshader("leaf");
        return l->value(x) + l->calls();
    }
}
)");
    mid.set_handle("mid");
    std::vector<const ShaderInstance*> co{&mid, &leaf};
    ShaderInstance s = e.instance(R"(
surface top() {
    shader m = getshader("mid");
    Ci = m->value(u);
    Ci += m->value(u);
}
)");
    ShadingBatch b = plane_grid(3, 2);
    e.context.execute(s, b, {}, co);
    for (std::size_t i = 0; i < b.size; ++i) {
        // leaf: tint * x * 2, then its call count (1, then 2).
        EXPECT_NEAR(b.Ci[i].x, 2 * (2.0f * b.u[i]) + 1 + 2, 1e-5f) << i;
        EXPECT_NEAR(b.Ci[i].z, 2 * (0.5f * b.u[i]) + 1 + 2, 1e-5f) << i;
    }
}

TEST(RslEngineCoshader, CategoriesAndErrors) {
    Engine e;
    ShaderInstance a = e.instance(R"(
class tagged(string __category = "pattern,cheap";) {
    public float one() { return 1; }
    public float loop() { shader me = getshader("a"); return me->loop(); }
}
)");
    a.set_handle("a");
    ShaderInstance b = e.instance(kLayer);
    b.set_handle("b");
    std::vector<const ShaderInstance*> co{&a, &b};
    ShaderInstance count = e.instance(R"(
surface count() {
    shader p[] = getshaders("category", "pattern");
    shader q[] = getshaders("category", "-cheap");
    Ci = color(arraylength(p), arraylength(q), arraylength(getshaders()));
}
)");
    ShadingBatch batch = plane_grid(2, 2);
    e.context.execute(count, batch, {}, co);
    EXPECT_EQ(batch.Ci[0], glm::vec3(1.0f, 1.0f, 2.0f));
    ShaderInstance has = e.instance(R"(
surface has() {
    shader a = getshader("a"), none = getshader("none");
    Ci = color(hasmethod(a, "one"), hasmethod(a, "value"), hasmethod(none, "one"));
    Oi = hasmethod(getshader("b"), "value");
}
)");
    e.context.execute(has, batch, {}, co);
    EXPECT_EQ(batch.Ci[0], glm::vec3(1.0f, 0.0f, 0.0f));
    EXPECT_EQ(batch.Oi[0], glm::vec3(1.0f));

    auto fails = [&](const std::string& body, const std::string& part) {
        ShaderInstance s = e.instance("surface f() { " + body + " }");
        ShadingBatch bb = plane_grid(2, 2);
        try {
            e.context.execute(s, bb, {}, co);
            ADD_FAILURE() << "no error for " << body;
        } catch (const ShaderRuntimeError& err) {
            EXPECT_NE(std::string(err.what()).find(part), std::string::npos)
                << err.what();
            EXPECT_NE(std::string(err.what()).find("test.sl:"), std::string::npos)
                << err.what();
        }
    };
    fails("shader s = getshader(\"a\"); Ci = s->one(2);", "takes 0 arguments, not 1");
    fails("shader s = getshader(\"b\"); Ci = s->value(\"x\");", "is a string");
    fails("shader s = getshader(\"a\"); Ci = s->loop();", "calls itself");
    // A method the shader does not have: nothing runs, warned once.
    ShaderInstance missing = e.instance(
        "surface m() { shader s = getshader(\"a\"); Ci = 5; Ci = s->nothing(); }");
    e.context.execute(missing, batch, {}, co);
    EXPECT_EQ(batch.Ci[0], glm::vec3(0.0f));
    bool warned = false;
    for (const std::string& w : e.services.warnings)
        warned = warned || w.find("has no method 'nothing'") != std::string::npos;
    EXPECT_TRUE(warned);
}

} // namespace
