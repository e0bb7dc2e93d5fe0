// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file engine_lighting_test.cpp
/// Tests of the shading engine's lighting (illuminance, illuminate, solar,
/// ambient/diffuse/specular, categories, ray-traced shadows), derivatives
/// (Du, Dv, Deriv, area, calculatenormal per batch layout). The standard lights written
/// in RSL are compared with the C++ lights (sss/light/lights.h).
///
/// Suite names start with "RslEngine".

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/matrix.hpp>

#include <fstream>

#include "engine_test_util.h"
#include "sss/light/lights.h"
#include "sss/light/ray_tracer.h"
#include "test_util.h"

namespace {

using namespace sss;
using namespace sss::test;

constexpr double kPi = std::numbers::pi;

const char* kPointLight = R"(
light pointlight(float intensity = 1; color lightcolor = 1;
                 point from = point "shader" (0, 0, 0); string shadowname = "";) {
    illuminate(from) {
        Cl = intensity * lightcolor / (L . L);
        if (shadowname != "") Cl *= 1 - shadow(shadowname, Ps);
    }
}
)";

const char* kDistantLight = R"(
light distantlight(float intensity = 1; color lightcolor = 1;
                   point from = point "shader" (0, 0, 0); point to = point "shader" (0, 0, 1);) {
    solar(to - from, 0) { Cl = intensity * lightcolor; }
}
)";

const char* kSpotLight = R"(
light spotlight(float intensity = 1; color lightcolor = 1;
                point from = point "shader" (0, 0, 0); point to = point "shader" (0, 0, 1);
                float coneangle = radians(30); float conedeltaangle = radians(5);
                float beamdistribution = 2;) {
    uniform vector A = normalize(to - from);
    illuminate(from, A, coneangle) {
        float cosangle = (L . A) / length(L);
        float atten = pow(cosangle, beamdistribution) / (L . L);
        atten *= smoothstep(cos(coneangle), cos(coneangle - conedeltaangle), cosangle);
        Cl = atten * intensity * lightcolor;
    }
}
)";

const char* kAmbientLight = R"(
light ambientlight(float intensity = 1; color lightcolor = 1; string __category = "fill";) {
    Cl = intensity * lightcolor;
}
)";

const char* kMatte = R"(
surface matte(float Ka = 1; float Kd = 1;) {
    normal Nf = faceforward(normalize(N), I);
    Oi = Os;
    Ci = Os * Cs * (Ka * ambient() + Kd * diffuse(Nf));
}
)";

/// A lighting setup: the scene's lights as C++ lights and as RSL instances.
struct LightRig {
    Engine engine;
    std::vector<ShaderInstance> instances;
    std::vector<const ShaderInstance*> list;

    void add(const char* source, const std::string& name, ParamList params,
             const Matrix4& shader_to_world) {
        LightInstance li;
        li.shader.name = name;
        li.shader.params = params;
        li.shader.shader_to_world = shader_to_world;
        engine.services.scene_.lights.push_back(li);
        instances.push_back(engine.instance(source, params, shader_to_world));
    }
    LightList lights() {
        list.clear();
        for (const ShaderInstance& i : instances) list.push_back(&i);
        return list;
    }
};

/// Points in camera space around the origin of world space, facing various ways.
ShadingBatch scattered_points(const Matrix4& world_to_camera, int count) {
    ShadingBatch b;
    b.layout = BatchLayout::Points;
    b.size = count;
    const glm::dmat3 nm = glm::transpose(glm::inverse(glm::dmat3(world_to_camera)));
    for (int i = 0; i < count; ++i) {
        const double a = 0.7 * i, c = 0.37 * i;
        const glm::dvec3 pw(std::sin(a) * 0.8, std::cos(c) * 0.6, 0.3 * std::sin(a + c));
        const glm::dvec3 nw = glm::normalize(glm::dvec3(std::cos(a), 0.5, std::sin(c)));
        b.P.push_back(glm::vec3(world_to_camera * glm::dvec4(pw, 1.0)));
        b.N.push_back(glm::vec3(glm::normalize(nm * nw)));
    }
    b.Ng = b.N;
    b.I = b.P;
    return b;
}

glm::dvec3 world_of(const Matrix4& camera_to_world, const glm::vec3& p) {
    return glm::dvec3(camera_to_world * glm::dvec4(glm::dvec3(p), 1.0));
}

TEST(RslEngineLighting, StandardLightsMatchTheCppLights) {
    LightRig rig;
    Matrix4 w2c = glm::rotate(glm::translate(Matrix4(1.0), glm::dvec3(0.2, -0.1, 5.0)),
                              0.4, glm::dvec3(0.3, 1.0, 0.1));
    rig.engine.services.scene_.options.camera.world_to_camera = w2c;
    const Matrix4 moved = glm::translate(Matrix4(1.0), glm::dvec3(0.5, 2.0, -1.0));
    {
        ParamList p;
        p.set(float_param("intensity", 3.0));
        p.set(point_param("from", {0.2, 0.1, 0.3}));
        rig.add(kPointLight, "pointlight", p, moved);
    }
    {
        ParamList p;
        p.set(float_param("intensity", 0.7));
        p.set(point_param("to", {1.0, -1.0, -2.0}));
        rig.add(kDistantLight, "distantlight", p, Matrix4(1.0));
    }
    {
        ParamList p;
        p.set(float_param("intensity", 5.0));
        p.set(point_param("from", {0.0, 3.0, 0.0}));
        p.set(point_param("to", {0.0, 0.0, 0.0}));
        p.set(float_param("coneangle", 0.5));
        rig.add(kSpotLight, "spotlight", p, Matrix4(1.0));
    }
    {
        ParamList p;
        p.set(float_param("intensity", 0.1));
        rig.add(kAmbientLight, "ambientlight", p, Matrix4(1.0));
    }
    std::vector<std::string> warnings;
    const std::vector<Light> lights =
        resolve_lights(rig.engine.services.scene_, &warnings);
    const Matrix4 c2w = glm::inverse(w2c);
    const glm::dmat3 nm = glm::transpose(glm::inverse(glm::dmat3(c2w)));
    ShaderInstance matte = rig.engine.instance(kMatte);
    LightList all = rig.lights();
    int lit = 0;
    // Each light alone, then all of them.
    for (int which = 0; which <= 4; ++which) {
        std::vector<int> active;
        std::vector<const ShaderInstance*> some;
        for (int k = 0; k < 4; ++k)
            if (which == 4 || k == which) {
                active.push_back(k);
                some.push_back(all[k]);
            }
        ShadingBatch b = scattered_points(w2c, 40);
        rig.engine.context.execute(matte, b, some);
        for (std::size_t i = 0; i < b.size; ++i) {
            const glm::dvec3 pw = world_of(c2w, b.P[i]);
            glm::dvec3 nw = glm::normalize(nm * glm::dvec3(b.N[i]));
            // faceforward(N, I): I is the view direction P - E.
            const glm::dvec3 iw = pw - world_of(c2w, glm::vec3(0.0f));
            if (glm::dot(iw, nw) > 0.0) nw = -nw;
            const glm::dvec3 want = irradiance(lights, active, pw, nw, nullptr, i, 0.0);
            for (int k = 0; k < 3; ++k)
                EXPECT_NEAR(b.Ci[i][k], want[k], 1e-4 * (1.0 + want[k]))
                    << "light " << which << " point " << i << " " << k;
            if (which == 4) lit += want.x > 0.1 + 1e-6;
        }
    }
    EXPECT_GT(lit, 10); // not just the ambient light
}

TEST(RslEngineLighting, SpecularMatchesTheCppFormula) {
    LightRig rig;
    ParamList p;
    p.set(point_param("from", {1.0, 2.0, -1.0}));
    rig.add(kPointLight, "pointlight", p, Matrix4(1.0));
    ShadingBatch b = scattered_points(Matrix4(1.0), 20);
    ShaderInstance s = rig.engine.instance(R"(
surface t(float roughness = 0.1;) {
    normal Nf = faceforward(normalize(N), I);
    vector V = -normalize(I);
    Ci = specular(Nf, V, roughness) + 0 * phong(Nf, V, 10);
}
)");
    rig.engine.context.execute(s, b, rig.lights());
    for (std::size_t i = 0; i < b.size; ++i) {
        glm::dvec3 n = glm::normalize(glm::dvec3(b.N[i]));
        const glm::dvec3 pp(b.P[i]);
        if (glm::dot(pp, n) > 0) n = -n;
        const glm::dvec3 v = -glm::normalize(pp);
        const glm::dvec3 d = glm::dvec3(1, 2, -1) - pp;
        const glm::dvec3 l = glm::normalize(d);
        double want = 0.0;
        if (glm::dot(n, l) >= 0.0) {
            const double c = glm::dot(n, glm::normalize(l + v));
            if (c > 0) want = std::pow(c, 10.0) / glm::dot(d, d);
        }
        EXPECT_NEAR(b.Ci[i].x, want, 1e-4 * (1 + want)) << i;
    }
}

/// The first point's value of a colour output of the last run.
glm::vec3 first_rgb(Engine& e, const char* name) {
    TypeSpec ty;
    std::vector<float> v;
    EXPECT_TRUE(e.context.output(name, ty, v));
    return v.size() >= 3 ? glm::vec3(v[0], v[1], v[2]) : glm::vec3(-1.0f);
}

TEST(RslEngineLighting, IlluminanceCategoriesAxisAndAmbient) {
    LightRig rig;
    {
        ParamList p;
        p.set(point_param("from", {0, 0, -1}));
        rig.add(R"(
light key(point from = point "shader" (0, 0, 0); string __category = "key,rim";) {
    illuminate(from) { Cl = color(1, 0, 0); }
}
)",
                "key", p, Matrix4(1.0));
    }
    {
        ParamList p;
        rig.add(R"(
light back(point from = point "shader" (0, 0, 5); float __nondiffuse = 1;) {
    illuminate(from) { Cl = color(0, 1, 0); }
}
)",
                "back", p, Matrix4(1.0));
    }
    {
        ParamList p;
        rig.add(kAmbientLight, "ambientlight", p, Matrix4(1.0));
    }
    ShadingBatch b = plane_grid(2, 1);
    ShaderInstance s = rig.engine.instance(R"(
surface t(output varying color all = 0; output varying color key = 0;
          output varying color notkey = 0; output varying color front = 0;
          output varying color amb = 0; output varying color dif = 0; output varying float n = 0;) {
    illuminance(P) { all += Cl; n += 1; }
    illuminance("rim", P) { key += Cl; }
    illuminance("-key", P) { notkey += Cl; }
    illuminance(P, vector(0, 0, -1), PI / 4) { front += Cl; }
    amb = ambient();
    dif = diffuse(vector(0, 0, -1));
}
)");
    rig.engine.context.execute(s, b, rig.lights());
    const auto out = [&](const char* name) { return first_rgb(rig.engine, name); };
    EXPECT_EQ(out("all"), glm::vec3(1, 1, 0));
    EXPECT_EQ(out("key"), glm::vec3(1, 0, 0));
    EXPECT_EQ(out("notkey"), glm::vec3(0, 1, 0));
    EXPECT_EQ(out("front"), glm::vec3(1, 0, 0));
    EXPECT_EQ(out("amb"), glm::vec3(1, 1, 1));
    const glm::vec3 dif = out("dif");
    EXPECT_GT(dif.x, 0.8f);
    EXPECT_EQ(dif.y, 0.0f); // __nondiffuse, and behind
    TypeSpec ty;
    std::vector<float> n;
    rig.engine.context.output("n", ty, n);
    EXPECT_EQ(n[0], 2.0f);
}

TEST(RslEngineLighting, LightShadersSeeNsAndSetLOutsideIlluminate) {
    LightRig rig;
    // The specification's own ambientlight assigns L outside any illuminate.
    rig.add(R"(
light ambientlight(float intensity = 1; color lightcolor = 1;) {
    Cl = intensity * lightcolor;
    L = 0;
}
)",
            "ambientlight", {}, Matrix4(1.0));
    // PRMan's Ns: the normal of the surface being lit.
    {
        ParamList p;
        p.set(point_param("from", {0, 0, -1}));
        rig.add(R"(
light ns(point from = point "shader" (0, 0, 0);) {
    illuminate(from) { Cl = color(xcomp(Ns), ycomp(Ns), zcomp(Ns)); }
}
)",
                "ns", p, Matrix4(1.0));
    }
    ShadingBatch b = plane_grid(2, 1);
    ShaderInstance s = rig.engine.instance(R"(
surface t(output varying color lit = 0; output varying color amb = 0;
          output varying color nn = 0;) {
    illuminance(P) { lit += Cl; }
    amb = ambient();
    nn = color(xcomp(N), ycomp(N), zcomp(N));
}
)");
    rig.engine.context.execute(s, b, rig.lights());
    const auto out = [&](const char* name) { return first_rgb(rig.engine, name); };
    EXPECT_EQ(out("amb"), glm::vec3(1, 1, 1));
    EXPECT_EQ(out("lit"), out("nn"));
    EXPECT_GT(glm::length(out("nn")), 0.5f);
}

/// A square occluder in world space, z = zc, side 2 * half.
void add_square(RayTracer& rt, double zc, double half, double cx = 0.0) {
    std::vector<glm::vec3> v = {{cx - half, -half, zc},
                                {cx + half, -half, zc},
                                {cx + half, half, zc},
                                {cx - half, half, zc}};
    rt.add_mesh(v, {0, 1, 2, 0, 2, 3});
}

TEST(RslEngineLighting, RayTracedShadowsMatchTheCppLights) {
    LightRig rig;
    RayTracer rt;
    add_square(rt, 0.5, 0.3, 0.2);
    rt.commit();
    rig.engine.services.tracer = &rt;
    ParamList p;
    p.set(point_param("from", {0.0, 0.0, -1.0}));
    p.set(string_param("shadowname", "raytrace"));
    rig.add(kPointLight, "pointlight", p, Matrix4(1.0));
    ShadingBatch b = plane_grid(9, 9); // z = 1 plane, N towards the light
    b.ray_offset = 1e-3f;
    ShaderInstance matte = rig.engine.instance(kMatte);
    rig.engine.context.execute(matte, b, rig.lights());
    std::vector<std::string> warnings;
    const std::vector<Light> lights =
        resolve_lights(rig.engine.services.scene_, &warnings);
    int shadowed = 0;
    for (std::size_t i = 0; i < b.size; ++i) {
        const glm::dvec3 want = irradiance(lights, {0}, glm::dvec3(b.P[i]),
                                           glm::dvec3(0, 0, -1), &rt, i, 1e-3);
        EXPECT_NEAR(b.Ci[i].x, want.x, 1e-5) << i;
        shadowed += want.x == 0.0;
    }
    EXPECT_GT(shadowed, 5);
    EXPECT_LT(shadowed, 70);

    // transmission() with a cone: deterministic, between 0 and 1.
    ShaderInstance tr = rig.engine.instance(R"(
surface t() { Ci = transmission(P, point(0, 0, -1), "samples", 16, "samplecone", 0.3); }
)");
    rig.engine.context.execute(tr, b, rig.lights());
    const std::vector<glm::vec3> first = b.Ci;
    rig.engine.context.execute(tr, b, rig.lights());
    EXPECT_EQ(first, b.Ci);
    int partial = 0;
    for (const glm::vec3& c : first) {
        EXPECT_GE(c.x, 0.0f);
        EXPECT_LE(c.x, 1.0f);
        partial += c.x > 0.0f && c.x < 1.0f;
    }
    EXPECT_GT(partial, 0);

    // Depth-map shadows go to the texture services (none here: an error
    // naming the map; tests/binding/shadow_maps_test.cpp reads real maps).
    ShaderInstance dm = rig.engine.instance(R"(
surface t() { Ci = shadow("map.shd", P); }
)");
    try {
        rig.engine.context.execute(dm, b, rig.lights());
        FAIL() << "no error for a shadow map without texture services";
    } catch (const ShaderRuntimeError& e) {
        EXPECT_NE(std::string(e.what()).find("map.shd"), std::string::npos) << e.what();
    }
}

// --- derivatives ----------------------------------------------------------------

/// A sphere of radius r as a grid at cell centres (u around z, v pole to pole).
ShadingBatch sphere_grid(int nu, int nv, double r) {
    ShadingBatch b;
    b.layout = BatchLayout::Grid;
    b.nu = nu;
    b.nv = nv;
    b.size = static_cast<std::size_t>(nu) * nv;
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
            const double u = (i + 0.5) / nu, v = (j + 0.5) / nv;
            const double th = 2 * kPi * u, ph = -kPi / 2 + kPi * v;
            const glm::dvec3 p(r * std::cos(ph) * std::cos(th),
                               r * std::cos(ph) * std::sin(th), r * std::sin(ph));
            b.P.push_back(glm::vec3(p));
            b.N.push_back(glm::vec3(glm::normalize(p)));
            b.u.push_back(static_cast<float>(u));
            b.v.push_back(static_cast<float>(v));
            b.du.push_back(1.0f / nu);
            b.dv.push_back(1.0f / nv);
        }
    b.Ng = b.N;
    return b;
}

TEST(RslEngineDerivatives, SphereNormalsAndArea) {
    Engine e;
    const double r = 1.5;
    ShadingBatch b = sphere_grid(128, 128, r);
    const char* src = R"(
surface t(output varying float a = 0; output varying normal n = 0;) {
    a = area(P);
    n = calculatenormal(P);
}
)";
    ShaderInstance inst = e.instance(src);
    e.context.execute(inst, b);
    TypeSpec ty;
    std::vector<float> a, n;
    e.context.output("a", ty, a);
    e.context.output("n", ty, n);
    double total = 0.0, worst = 1.0;
    for (std::size_t i = 0; i < b.size; ++i) {
        total += a[i];
        worst = std::min(worst,
                         static_cast<double>(glm::dot(
                             glm::vec3(n[i * 3], n[i * 3 + 1], n[i * 3 + 2]), b.N[i])));
    }
    EXPECT_NEAR(total / (4 * kPi * r * r), 1.0, 1e-3);
    EXPECT_GT(worst, 0.995);

    // Reversed orientation flips calculatenormal.
    Primitive prim;
    auto attr = std::make_shared<Attributes>();
    attr->orientation_inside = true;
    prim.attributes = attr;
    b.primitive = &prim;
    e.context.execute(inst, b);
    e.context.output("n", ty, n);
    EXPECT_LT(n[0] * b.N[0].x + n[1] * b.N[0].y + n[2] * b.N[0].z, -0.99f);
}

TEST(RslEngineDerivatives, DuDvDerivOnGridsTripletsAndPoints) {
    Engine e;
    ShadingBatch b = plane_grid(20, 4);
    const char* src = R"(
surface t(output varying float a = 0; output varying float c = 0;
          output varying float d = 0; output varying vector p = 0;) {
    a = Du(s);
    c = Dv(t * t);
    d = Deriv(s * s * s, s);
    p = Du(P);
}
)";
    ShaderInstance inst = e.instance(src);
    e.context.execute(inst, b);
    TypeSpec ty;
    std::vector<float> a, c, d, p;
    e.context.output("a", ty, a);
    e.context.output("c", ty, c);
    e.context.output("d", ty, d);
    e.context.output("p", ty, p);
    for (std::size_t i = 0; i < b.size; ++i) {
        EXPECT_NEAR(a[i], 1.0f, 1e-4) << i;
        EXPECT_NEAR(c[i], 2.0f * b.v[i], 1e-4) << i;            // exact for quadratics
        EXPECT_NEAR(d[i], 3.0f * b.u[i] * b.u[i], 0.006f) << i; // h^2, 2h^2 at edges
        EXPECT_NEAR(p[i * 3], 1.0f, 1e-4);
    }
    // Triplets: forward differences to the helper points.
    ShadingBatch t;
    t.layout = BatchLayout::Triplets;
    t.size = 3;
    t.u = {0.5f, 0.6f, 0.5f};
    t.v = {0.5f, 0.5f, 0.7f};
    t.du = {0.1f, 0.1f, 0.1f};
    t.dv = {0.2f, 0.2f, 0.2f};
    t.P = {{0, 0, 1}, {0.3f, 0, 1}, {0, 0.4f, 1}};
    e.context.execute(inst, t);
    e.context.output("a", ty, a);
    e.context.output("p", ty, p);
    EXPECT_NEAR(a[0], 1.0f, 1e-5);
    EXPECT_NEAR(p[0], 3.0f, 1e-5);
    // Points: Du(P) is dPdu, Du(s) is 0.
    ShadingBatch q;
    q.layout = BatchLayout::Points;
    q.size = 1;
    q.P = {{0, 0, 1}};
    q.dPdu = {{2, 0, 0}};
    q.du = {0.1f};
    e.context.execute(inst, q);
    e.context.output("a", ty, a);
    e.context.output("p", ty, p);
    EXPECT_EQ(a[0], 0.0f);
    EXPECT_EQ(p[0], 2.0f);
}

// --- math built-ins --------------------------------------------------------------

TEST(RslEngineBuiltins, ClosedForms) {
    Engine e;
    ShadingBatch b = plane_grid(1, 1);
    const auto r = e.run(R"(
surface t(output varying float r[12] = {0,0,0,0,0,0,0,0,0,0,0,0};) {
    float kr, kt;
    fresnel(vector(0, 0, 1), normal(0, 0, -1), 1 / 1.5, kr, kt);
    r[0] = kr;
    r[1] = kt;
    r[2] = length(refract(normalize(vector(1, 0, 0.1)), normal(0, 0, -1), 1.5)); // TIR
    r[3] = smoothstep(0, 2, 0.5);
    r[4] = mix(2, 4, 0.25);
    r[5] = clamp(5, 0, 3) + clamp(-1, 0, 3);
    r[6] = length(normalize(vector 0));
    r[7] = sign(-3) + 10 * step(1, 2);
    r[8] = min(3, 1, 2) + 10 * max(3, 1, 7);
    r[9] = spline(0.5, 0, 0, 1, 1);
    r[10] = ptlined(point(0, 0, 0), point(1, 0, 0), point(0.5, 2, 0));
    r[11] = depth(point(0, 0, 5.5));
}
)",
                         b);
    const double f0 = std::pow((1.5 - 1) / (1.5 + 1), 2);
    EXPECT_NEAR(r[0], f0, 1e-6);
    EXPECT_NEAR(r[1], 1 - f0, 1e-6);
    EXPECT_EQ(r[2], 0.0f);
    EXPECT_NEAR(r[3], 0.15625f, 1e-6);
    EXPECT_NEAR(r[4], 2.5f, 1e-6);
    EXPECT_EQ(r[5], 3.0f);
    EXPECT_EQ(r[6], 0.0f);
    EXPECT_EQ(r[7], 9.0f);
    EXPECT_EQ(r[8], 71.0f);
    EXPECT_NEAR(r[9], 0.5f, 1e-6);
    EXPECT_NEAR(r[10], 2.0f, 1e-6);
    EXPECT_NEAR(r[11], 5.5f / 1e30, 1e-6);
}

TEST(RslEngineQueries, AttributesAndOptions) {
    Engine e;
    e.services.scene_.options.camera.xres = 320;
    e.services.scene_.options.camera.yres = 240;
    auto attr = std::make_shared<Attributes>();
    attr->groups["identifier"].set(string_param("name", "ball"));
    attr->groups["user"].set(float_param("k", 4));
    attr->shading_rate = 2;
    Primitive prim;
    prim.attributes = attr;
    ShadingBatch b = plane_grid(1, 1);
    b.primitive = &prim;
    const auto r = e.run(R"(
surface t(output varying float r = 0;) {
    string name = "";
    float rate = 0, k = 0, f[3] = {0, 0, 0}, none = 0;
    float ok = attribute("identifier:name", name) + attribute("ShadingRate", rate)
             + attribute("user:k", k) + option("Format", f) + attribute("user:nope", none);
    if (name == "ball") r = ok * 1000 + rate * 100 + k * 10 + f[0] / 320;
}
)",
                         b);
    EXPECT_EQ(r[0], 4000 + 200 + 40 + 1);
}

} // namespace
