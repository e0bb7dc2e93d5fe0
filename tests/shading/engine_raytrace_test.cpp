// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file engine_raytrace_test.cpp
/// The ray-tracing shadeops of the engine (engine_raytrace.cpp) against a
/// fake ShadingServices whose trace() is an analytic world: gather's sample
/// distributions and passes, its outputs and else branch, trace(),
/// environment("raytrace"), indirectdiffuse(), occlusion() (adaptive
/// sampling, environment maps), shadow()/transmission() through transmit(),
/// rayinfo, ray depths and thread independence.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <numbers>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "engine_test_util.h"

namespace {

using namespace sss;
using namespace sss::test;

constexpr double kPi = std::numbers::pi;

/// Texture services whose environment maps are constant colours by file
/// name (constant_map): what the ray-tracing shadeops hand to environment()
/// is the engine's, how a map is filtered is the texture library's
/// (tests/binding). Other lookups fail as unreadable files.
class ConstantEnvironments final : public TextureServices {
public:
    static ConstantEnvironments& instance() {
        static ConstantEnvironments one;
        return one;
    }
    std::map<std::string, glm::vec3> maps;

    bool texture(const std::string& file, int, int, const TextureOptions&, std::size_t,
                 const float*, const float*, const float*, const float*, const float*,
                 const float*, const uint8_t*, float*, std::string* error) override {
        return fail(file, error);
    }
    bool texture_quad(const std::string& file, int, int, const TextureOptions&,
                      std::size_t, const float* const*, const uint8_t*, float*,
                      std::string* error) override {
        return fail(file, error);
    }
    bool environment(const std::string& file, int channel, int nchannels,
                     const TextureOptions& options, std::size_t count,
                     const glm::vec3* dir, const glm::vec3*, const glm::vec3*,
                     const uint8_t* mask, float* out, std::string* error) override {
        const auto it = maps.find(file);
        if (it == maps.end()) return fail(file, error);
        for (std::size_t i = 0; i < count; ++i) {
            if (mask && !mask[i]) continue;
            const bool zero = glm::dot(dir[i], dir[i]) == 0.0f;
            for (int k = 0; k < nchannels; ++k) {
                const int c = channel + k;
                out[i * nchannels + k] = zero    ? 0.0f
                                         : c < 3 ? it->second[c]
                                                 : options.fill;
            }
        }
        return true;
    }
    bool texture_info(const std::string&, const std::string&, int, float*,
                      std::string*) override {
        return false;
    }
    bool texture3d(const std::string& file, std::span<const std::string>, std::size_t,
                   const glm::vec3*, const glm::vec3*, const float*, const uint8_t*,
                   std::vector<int>&, float*, uint8_t*, std::string* error) override {
        return fail(file, error);
    }

private:
    static bool fail(const std::string& file, std::string* error) {
        if (error) *error = file + ": not a constant environment map";
        return false;
    }
};

/// An analytic world (world space):
///  - None: every ray misses;
///  - All: every ray hits at length 1;
///  - HalfX: the plane x = 2: rays with direction.x > 0 hit it (within tfar).
/// Hits return "Ci" = the ray direction (ci_is_direction) or `ci`, "foo" = 7.
class FakeWorld : public RecordingServices {
public:
    FakeWorld() { texture_services = &ConstantEnvironments::instance(); }
    enum Mode { None, All, HalfX } mode = None;
    bool ci_is_direction = false;
    glm::vec3 ci{0.2f, 0.4f, 0.8f};
    glm::vec3 through{0.25f, 0.5f, 1.0f};

    struct Seen {
        RayKind kind;
        std::string label;
        int depth;
        std::size_t rays;
        std::vector<std::string> outputs;
        uint64_t seed;
        float spread;
    };
    std::vector<Seen> queries;
    std::vector<int> transmit_depths;
    std::size_t transmitted = 0;

    void trace(RayQuery& q) override {
        queries.push_back(
            {q.kind, q.label, q.depth, q.rays.size(), q.outputs, q.seed, q.spread});
        const std::size_t n = q.rays.size();
        q.hit.assign(n, 0);
        q.length.assign(n, std::numeric_limits<float>::infinity());
        q.values.assign(q.outputs.size(), {});
        for (std::size_t k = 0; k < q.outputs.size(); ++k)
            q.values[k].assign(n * q.output_floats[k], 0.0f);
        for (std::size_t r = 0; r < n; ++r) {
            const ShadowRay& ray = q.rays[r];
            float t = std::numeric_limits<float>::infinity();
            if (mode == All) t = 1.0f;
            if (mode == HalfX && ray.direction.x > 0.0f)
                t = (2.0f - ray.origin.x) / ray.direction.x;
            if (!std::isfinite(t) || !(t > 0.0f) || t > ray.tfar) continue;
            q.hit[r] = 1;
            q.length[r] = t;
            for (std::size_t k = 0; k < q.outputs.size(); ++k) {
                float* v = &q.values[k][r * q.output_floats[k]];
                if (q.outputs[k] == "Ci" && q.output_floats[k] == 3) {
                    const glm::vec3 c = ci_is_direction ? ray.direction : ci;
                    v[0] = c.x;
                    v[1] = c.y;
                    v[2] = c.z;
                } else if (q.outputs[k] == "foo" && q.output_floats[k] == 1) {
                    v[0] = 7.0f;
                }
            }
        }
    }
    void transmit(const ShadowRay* rays, std::size_t count, glm::vec3* out,
                  int depth) override {
        (void)rays;
        transmit_depths.push_back(depth);
        transmitted += count;
        for (std::size_t r = 0; r < count; ++r) out[r] = through;
    }
};

struct Rig {
    FakeWorld services;
    ShadingResources resources;
    ShadingContext context{resources, services};

    std::vector<float> run(const std::string& source, ShadingBatch& batch,
                           const std::string& name, LightList lights = {}) {
        ShaderInstance inst(compile_shader(source), {}, Matrix4(1.0), "test.rib:1");
        context.execute(inst, batch, lights);
        TypeSpec type;
        std::vector<float> values;
        EXPECT_TRUE(context.output(name, type, values)) << name;
        EXPECT_EQ(context.nonfinite_points(), 0u) << context.nonfinite_message();
        return values;
    }
};

/// n unrelated points at (i, 0, 0) facing +z (camera = world unless the
/// scene says otherwise), I = P - (0, 0, -4).
ShadingBatch points(std::size_t n, glm::vec3 normal = {0, 0, 1}) {
    ShadingBatch b;
    b.layout = BatchLayout::Points;
    b.size = n;
    for (std::size_t i = 0; i < n; ++i) {
        const float u = (i + 0.5f) / n;
        b.P.push_back(glm::vec3(float(i), 0, 0));
        b.N.push_back(normal);
        b.Ng.push_back(normal);
        b.I.push_back(glm::vec3(float(i), 0, 4));
        b.u.push_back(u);
        b.v.push_back(0.5f);
        b.du.push_back(1.0f / n);
        b.dv.push_back(1.0f);
        b.dPdu.push_back(glm::vec3(1, 0, 0));
        b.dPdv.push_back(glm::vec3(0, 1, 0));
    }
    b.s = b.u;
    b.t = b.v;
    b.seed = 1234;
    return b;
}

/// gather's ray:direction moments about N (current space): E[cos], E[cos^2],
/// the passes per point and the largest angle to N.
const char* kMoments = R"(
surface t(float samples = 256; float angle = 1.5707963; string dist = "cosine";
          output varying float m1 = 0, m2 = 0, passes = 0, widest = 0, hits = 0) {
    vector d = 0;
    normal Nn = normalize(N);
    gather("", P, Nn, angle, samples, "ray:direction", d, "distribution", dist) {
        float c = normalize(d) . Nn;
        m1 += c; m2 += c * c; passes += 1; hits += 1;
        widest = max(widest, acos(clamp(c, -1, 1)));
    } else {
        float c = normalize(d) . Nn;
        m1 += c; m2 += c * c; passes += 1;
        widest = max(widest, acos(clamp(c, -1, 1)));
    }
    m1 /= passes; m2 /= passes;
}
)";

struct Moments {
    double m1 = 0, m2 = 0, widest = 0, hits = 0;
    bool passes_ok = true;
};

Moments moments(Rig& rig, ShadingBatch& b, int samples, double angle,
                const std::string& dist) {
    ParamList params;
    params.set(float_param("samples", samples));
    params.set(float_param("angle", angle));
    params.set(string_param("dist", dist));
    ShaderInstance inst(compile_shader(kMoments), params, Matrix4(1.0), "test.rib:1");
    rig.context.execute(inst, b);
    Moments m;
    TypeSpec type;
    std::vector<float> m1, m2, passes, widest, hits;
    EXPECT_TRUE(rig.context.output("m1", type, m1));
    EXPECT_TRUE(rig.context.output("m2", type, m2));
    EXPECT_TRUE(rig.context.output("passes", type, passes));
    EXPECT_TRUE(rig.context.output("widest", type, widest));
    EXPECT_TRUE(rig.context.output("hits", type, hits));
    for (std::size_t i = 0; i < b.size; ++i) {
        m.m1 += m1[i] / b.size;
        m.m2 += m2[i] / b.size;
        m.hits += hits[i] / b.size;
        m.widest = std::max(m.widest, double(widest[i]));
        m.passes_ok = m.passes_ok && passes[i] == float(samples);
    }
    return m;
}

TEST(EngineRaytrace, GatherCosineAndUniformMoments) {
    Rig rig;
    // A rotated camera: the cone is built in world space about N and the
    // directions come back in the current space.
    rig.services.scene_.options.camera.world_to_camera =
        glm::rotate(Matrix4(1.0), 0.7, glm::dvec3(0.3, 1, 0.2));
    ShadingBatch b = points(16, glm::normalize(glm::vec3(0.2f, -0.3f, 1.0f)));
    const Moments c = moments(rig, b, 256, kPi / 2, "cosine");
    EXPECT_NEAR(c.m1, 2.0 / 3.0, 0.005);
    EXPECT_NEAR(c.m2, 0.5, 0.005);
    EXPECT_TRUE(c.passes_ok);
    EXPECT_LE(c.widest, kPi / 2 + 1e-3);
    ASSERT_FALSE(rig.services.queries.empty());
    EXPECT_EQ(rig.services.queries.back().kind, RayKind::Diffuse);
    EXPECT_EQ(rig.services.queries.back().rays, 16u * 256u);

    const Moments u = moments(rig, b, 256, kPi / 2, "uniform");
    EXPECT_NEAR(u.m1, 0.5, 0.005);
    EXPECT_NEAR(u.m2, 1.0 / 3.0, 0.005);
    EXPECT_TRUE(u.passes_ok);
    EXPECT_EQ(rig.services.queries.back().kind, RayKind::Specular);

    // A narrow cone: uniform over the cap, E[cos] = (1 + cos a) / 2, and no
    // direction outside it.
    const double a = kPi / 6;
    const Moments n = moments(rig, b, 64, a, "uniform");
    EXPECT_NEAR(n.m1, (1 + std::cos(a)) / 2, 0.002);
    EXPECT_LE(n.widest, a + 1e-3);
    EXPECT_GT(n.widest, a * 0.8);
    EXPECT_TRUE(n.passes_ok);
    const Moments nc = moments(rig, b, 64, a, "cosine");
    EXPECT_LE(nc.widest, a + 1e-3);
}

TEST(EngineRaytrace, GatherOutputsMatchTheWorldAndMissesRunTheElseBody) {
    Rig rig;
    rig.services.mode = FakeWorld::HalfX;
    rig.services.ci_is_direction = true;
    ShadingBatch b = points(4);
    b.ray.depth = 1;
    const char* src = R"(
surface t(output varying float bad = 0, nhit = 0, nmiss = 0, badmiss = 0, keep = 0) {
    color c = color(9, 9, 9);
    float len = 0, foo = 0;
    vector d = 0;
    point o = 0;
    gather("illuminance", P, N, PI / 2, 64, "surface:Ci", c, "ray:length", len,
           "ray:direction", d, "ray:origin", o, "surface:foo", foo, "label", "gi") {
        nhit += 1;
        bad += abs(comp(c, 0) - xcomp(d)) + abs(comp(c, 1) - ycomp(d))
             + abs(comp(c, 2) - zcomp(d)) + abs(len - (2 - xcomp(P)) / xcomp(d))
             + abs(foo - 7) + (xcomp(d) > 0 ? 0 : 1) + distance(o, P);
        c = color(9, 9, 9);
    } else {
        nmiss += 1;
        badmiss += (xcomp(d) > 0 && xcomp(P) < 2 ? 1 : 0) + (len == 1e30 ? 0 : 1);
        keep += c == color(9, 9, 9) ? 0 : 1;
    }
}
)";
    const auto bad = rig.run(src, b, "bad");
    TypeSpec type;
    std::vector<float> nhit, nmiss, badmiss, keep;
    rig.context.output("nhit", type, nhit);
    rig.context.output("nmiss", type, nmiss);
    rig.context.output("badmiss", type, badmiss);
    rig.context.output("keep", type, keep);
    for (std::size_t i = 0; i < 4; ++i) {
        SCOPED_TRACE(i);
        EXPECT_LT(bad[i], 1e-3);
        EXPECT_EQ(nhit[i] + nmiss[i], 64.0f);
        EXPECT_EQ(badmiss[i], 0.0f);
        EXPECT_EQ(keep[i], 0.0f); // surface outputs untouched by misses
        if (i < 2) {
            // Half of the hemisphere faces +x (uniform: exactly half the strata).
            EXPECT_GT(nhit[i], 24.0f);
            EXPECT_LT(nhit[i], 40.0f);
        } else {
            EXPECT_EQ(nhit[i], 0.0f) << "points at x >= 2 are past the plane";
        }
    }
    ASSERT_EQ(rig.services.queries.size(), 1u);
    const FakeWorld::Seen& q = rig.services.queries[0];
    EXPECT_EQ(q.depth, 2);
    EXPECT_EQ(q.label, "gi");
    EXPECT_EQ(q.kind, RayKind::Specular);
    EXPECT_EQ(q.outputs, (std::vector<std::string>{"Ci", "foo"}));
    EXPECT_GT(q.spread, 0.0f);

    // maxdist: a plane 2 away is out of reach of maxdist 1.
    b = points(1);
    const auto far = rig.run(R"(
surface t(output varying float n = 0, len = 0) {
    gather("", P, N, PI / 2, 16, "ray:length", len, "maxdist", 1) { n += 1; }
})",
                             b, "n");
    EXPECT_EQ(far[0], 0.0f);
}

TEST(EngineRaytrace, GatherReturnAndEnvironmentCategory) {
    Rig rig;
    rig.services.mode = FakeWorld::All;
    ShadingBatch b = points(4);
    const auto n = rig.run(R"(
surface t(output varying float n = 0) {
    gather("", P, N, PI / 2, 16) {
        n += 1;
        if (u > 0.5) return;
    } else {
        n += 100;
    }
    n += 1000;
}
)",
                           b, "n");
    EXPECT_EQ(n[0], 1016.0f);
    EXPECT_EQ(n[1], 1016.0f);
    EXPECT_EQ(n[2], 1.0f); // returned in the first hit pass
    EXPECT_EQ(n[3], 1.0f);

    // "environment": blocked rays run the hit body; open ones the else body
    // with environment:color (no map: 0) and environment:direction.
    rig.services.mode = FakeWorld::HalfX;
    rig.services.queries.clear();
    b = points(1);
    const auto e = rig.run(R"(
surface t(output varying float blocked = 0, open = 0, bad = 0) {
    color c = 1;
    vector d = 0;
    gather("environment", P, N, PI / 2, 32, "environment:color", c,
           "environment:direction", d) {
        blocked += 1;
    } else {
        open += 1;
        bad += (xcomp(d) > 0 ? 1 : 0) + (c == color 0 ? 0 : 1);
    }
}
)",
                           b, "bad");
    EXPECT_EQ(e[0], 0.0f);
    ASSERT_EQ(rig.services.queries.size(), 1u);
    EXPECT_EQ(rig.services.queries[0].kind, RayKind::Diffuse);
    EXPECT_TRUE(rig.services.queries[0].outputs.empty());
}

/// A constant environment map of colour c (a name for ConstantEnvironments).
std::string constant_map(const std::string& name, glm::vec3 c);

TEST(EngineRaytrace, GatherEnvironmentMapAndSamplebase) {
    Rig rig;
    rig.services.mode = FakeWorld::HalfX;
    const std::string grey = constant_map("gather_grey", glm::vec3(0.25f, 0.5f, 0.75f));
    ShadingBatch b = points(2);
    ParamList params;
    params.set(string_param("map", grey));
    ShaderInstance inst(compile_shader(R"(
surface t(string map = ""; output varying float bad = 0, open = 0, widest = 0, nearest = 1e9) {
    color c = 0;
    point o = 0;
    gather("environment", P, N, PI / 2, 32, "environment:color", c,
           "environmentmap", map) {
    } else {
        open += 1;
        bad += abs(comp(c, 0) - 0.25) + abs(comp(c, 1) - 0.5) + abs(comp(c, 2) - 0.75);
    }
    gather("", P, N, PI / 2, 64, "ray:origin", o, "samplebase", 1, "bias", 0) {
        widest = max(widest, distance(o, P));
        nearest = min(nearest, distance(o, P));
    } else {
        widest = max(widest, distance(o, P));
        nearest = min(nearest, distance(o, P));
    }
}
)"),
                        params, Matrix4(1.0), "test.rib:1");
    rig.context.execute(inst, b);
    TypeSpec type;
    std::vector<float> bad, open, widest, nearest;
    rig.context.output("bad", type, bad);
    rig.context.output("open", type, open);
    rig.context.output("widest", type, widest);
    rig.context.output("nearest", type, nearest);
    // The micropolygon: |dPdu x dPdv| du dv = 1/2: radius sqrt(1 / (2 pi)).
    const float radius = std::sqrt(0.5f / float(kPi));
    for (std::size_t i = 0; i < 2; ++i) {
        EXPECT_LT(bad[i], 1e-4);
        EXPECT_GT(open[i], 8.0f);
        EXPECT_LE(widest[i], radius * 1.0001f);
        EXPECT_GT(widest[i], radius * 0.8f);
        EXPECT_LT(nearest[i], radius * 0.5f);
    }
}

TEST(EngineRaytrace, TraceAndEnvironmentRaytrace) {
    Rig rig;
    rig.services.mode = FakeWorld::HalfX;
    rig.services.ci_is_direction = true;
    ShadingBatch b = points(1);
    b.ray.depth = 3;
    b.ray.kind = RayKind::Specular;
    const auto r = rig.run(R"(
surface t(output varying color hit = 0, miss = 1, cone = 0, env = 0; output varying float envf = 0) {
    hit = trace(P, vector(1, 0, 0), "label", "refl");
    miss = trace(P, vector(-1, 0, 0));
    cone = trace(P, vector(1, 0, 0), "samples", 16, "samplecone", 0.2);
    env = environment("raytrace", vector(1, 0, 0));
    envf = environment("raytrace"[1], vector(-1, 1, 1), "samples", 4, "blur", 0.1);
}
)",
                           b, "hit");
    EXPECT_NEAR(r[0], 1.0f, 1e-6);
    EXPECT_NEAR(r[1], 0.0f, 1e-6);
    EXPECT_NEAR(r[2], 0.0f, 1e-6);
    TypeSpec type;
    std::vector<float> miss, cone, env, envf;
    rig.context.output("miss", type, miss);
    rig.context.output("cone", type, cone);
    rig.context.output("env", type, env);
    rig.context.output("envf", type, envf);
    EXPECT_EQ(miss, (std::vector<float>{0, 0, 0}));
    // The mean direction of a cone of full angle 0.2 about +x.
    EXPECT_GT(cone[0], std::cos(0.1) - 1e-4);
    EXPECT_LT(cone[0], 1.0f);
    EXPECT_NEAR(cone[1], 0.0f, 0.02);
    EXPECT_NEAR(env[0], 1.0f, 1e-6);
    EXPECT_EQ(envf[0], 0.0f); // (-1, 1, 1) misses the plane x = 2
    ASSERT_EQ(rig.services.queries.size(), 5u);
    for (const auto& q : rig.services.queries) {
        EXPECT_EQ(q.depth, 4);
        EXPECT_EQ(q.kind, RayKind::Specular);
        EXPECT_EQ(q.outputs, (std::vector<std::string>{"Ci"}));
    }
    EXPECT_EQ(rig.services.queries[0].label, "refl");
    EXPECT_EQ(rig.services.queries[0].rays, 1u);
    EXPECT_EQ(rig.services.queries[2].rays, 16u);
    EXPECT_EQ(rig.services.queries[4].rays, 4u);
}

/// A constant environment map of colour c, known to ConstantEnvironments.
std::string constant_map(const std::string& name, glm::vec3 c) {
    const std::string file = "sss_raytrace_" + name + ".exr";
    ConstantEnvironments::instance().maps[file] = c;
    return file;
}

const char* kIndirect = R"(
surface t(float samples = 256; string envmap = ""; float adaptive = 1;
          output varying color r = 0, ec = 0; output varying vector ed = 0;
          output varying float occ = -1, o2 = -1; output varying color ec2 = 0) {
    color envc = 0;
    vector envd = 0;
    float oc = 0;
    r = indirectdiffuse(P, N, samples, "environmentmap", envmap, "environmentcolor", envc,
                        "environmentdir", envd, "occlusion", oc, "adaptive", adaptive);
    ec = envc; ed = envd; occ = oc;
    color e2 = 0;
    o2 = occlusion(P, N, samples, "environmentmap", envmap, "environmentcolor", e2,
                   "adaptive", adaptive);
    ec2 = e2;
}
)";

struct Hemi {
    glm::vec3 r, ec, ed, ec2;
    float occ, o2;
};

Hemi hemisphere(Rig& rig, ShadingBatch& b, int samples, const std::string& envmap,
                float adaptive = 1) {
    ParamList params;
    params.set(float_param("samples", samples));
    params.set(string_param("envmap", envmap));
    params.set(float_param("adaptive", adaptive));
    ShaderInstance inst(compile_shader(kIndirect), params, Matrix4(1.0), "test.rib:1");
    rig.context.execute(inst, b);
    EXPECT_EQ(rig.context.nonfinite_points(), 0u);
    TypeSpec type;
    std::vector<float> r, ec, ed, ec2, occ, o2;
    rig.context.output("r", type, r);
    rig.context.output("ec", type, ec);
    rig.context.output("ed", type, ed);
    rig.context.output("ec2", type, ec2);
    rig.context.output("occ", type, occ);
    rig.context.output("o2", type, o2);
    Hemi h{};
    const float n = static_cast<float>(b.size);
    for (std::size_t i = 0; i < b.size; ++i) {
        h.r += glm::vec3(r[3 * i], r[3 * i + 1], r[3 * i + 2]) / n;
        h.ec += glm::vec3(ec[3 * i], ec[3 * i + 1], ec[3 * i + 2]) / n;
        h.ed += glm::vec3(ed[3 * i], ed[3 * i + 1], ed[3 * i + 2]) / n;
        h.ec2 += glm::vec3(ec2[3 * i], ec2[3 * i + 1], ec2[3 * i + 2]) / n;
        h.occ += occ[i] / n;
        h.o2 += o2[i] / n;
    }
    return h;
}

TEST(EngineRaytrace, IndirectdiffuseAndOcclusionOfAHalfOccludedHemisphere) {
    Rig rig;
    rig.services.mode = FakeWorld::HalfX;
    ShadingBatch b = points(2); // x = 0 and 1: both see the plane x = 2
    b.ray.depth = 1;
    // No map: the open half gives 0; cosine weights: half the rays hit.
    Hemi h = hemisphere(rig, b, 256, "");
    const glm::vec3 c = rig.services.ci;
    EXPECT_NEAR(h.r.x, c.x / 2, 0.01);
    EXPECT_NEAR(h.r.y, c.y / 2, 0.01);
    EXPECT_NEAR(h.r.z, c.z / 2, 0.01);
    EXPECT_NEAR(h.occ, 0.5, 0.01);
    EXPECT_NEAR(h.o2, 0.5, 0.01);
    EXPECT_EQ(h.ec, glm::vec3(0.0f));
    // The mean open direction: (-4 / (3 pi), 0, 2 / 3) normalised.
    const glm::vec3 want = glm::normalize(glm::vec3(-4.0 / (3 * kPi), 0, 2.0 / 3.0));
    EXPECT_NEAR(h.ed.x, want.x, 0.02);
    EXPECT_NEAR(h.ed.y, want.y, 0.02);
    EXPECT_NEAR(h.ed.z, want.z, 0.02);
    for (const auto& q : rig.services.queries) {
        EXPECT_EQ(q.kind, RayKind::Diffuse);
        EXPECT_EQ(q.depth, 2);
    }
    // Mixed results: both passes are traced (all 256 rays per point).
    std::size_t total = 0;
    for (const auto& q : rig.services.queries) total += q.rays;
    EXPECT_EQ(total, 2u * 2u * 256u);

    // A white map: the open half adds 1/2 of white; environmentcolor = 1/2.
    const std::string white = constant_map("white", glm::vec3(1.0f));
    h = hemisphere(rig, b, 256, white);
    EXPECT_NEAR(h.r.x, c.x / 2 + 0.5, 0.01);
    EXPECT_NEAR(h.r.z, c.z / 2 + 0.5, 0.01);
    EXPECT_NEAR(h.ec.x, 0.5, 0.01);
    EXPECT_NEAR(h.ec2.y, 0.5, 0.01);
}

TEST(EngineRaytrace, AdaptiveSamplingIsExactForUniformWorldsWithFewerRays) {
    Rig rig;
    const std::string white = constant_map("white2", glm::vec3(1.0f));
    const std::string grey = constant_map("grey", glm::vec3(0.25f, 0.5f, 0.75f));
    ShadingBatch b = points(3);
    auto rays = [&] {
        std::size_t n = 0;
        for (const auto& q : rig.services.queries) n += q.rays;
        rig.services.queries.clear();
        return n;
    };
    // Nothing in the way, a constant map: every 4th ray suffices.
    rig.services.mode = FakeWorld::None;
    Hemi h = hemisphere(rig, b, 64, grey);
    EXPECT_EQ(rays(), 2u * 3u * 16u);
    EXPECT_NEAR(h.r.x, 0.25f, 1e-5);
    EXPECT_NEAR(h.r.z, 0.75f, 1e-5);
    EXPECT_NEAR(h.ec2.y, 0.5f, 1e-5);
    EXPECT_EQ(h.o2, 0.0f);
    EXPECT_EQ(h.occ, 0.0f);
    // Unoccluded, white: occlusion's environmentcolor is exactly 1.
    h = hemisphere(rig, b, 64, white);
    EXPECT_NEAR(h.ec2.x, 1.0f, 1e-5);
    rays();
    // The same without adaptive sampling: every ray, the same answer.
    h = hemisphere(rig, b, 64, grey, 0);
    EXPECT_EQ(rays(), 2u * 3u * 64u);
    EXPECT_NEAR(h.r.x, 0.25f, 1e-5);
    // Everything hit with one colour: exact too.
    rig.services.mode = FakeWorld::All;
    h = hemisphere(rig, b, 64, "");
    EXPECT_EQ(rays(), 2u * 3u * 16u);
    EXPECT_NEAR(h.r.y, rig.services.ci.y, 1e-6);
    EXPECT_EQ(h.o2, 1.0f);
    // Fewer than 16 samples: never adaptive.
    h = hemisphere(rig, b, 8, "");
    EXPECT_EQ(rays(), 2u * 3u * 8u);
}

TEST(EngineRaytrace, OcclusionUniformDistributionAndConeangle) {
    Rig rig;
    rig.services.mode = FakeWorld::HalfX;
    ShadingBatch b = points(1);
    const auto r = rig.run(R"(
surface t(output varying float a = 0, narrow = 0, far = 0) {
    a = occlusion(P, N, 64, "distribution", "uniform", "adaptive", 0);
    narrow = occlusion(P, normal(1, 0, 0), 16, "coneangle", 0.3);
    far = occlusion(P, normal(1, 0, 0), 16, "maxdist", 1.5);
}
)",
                           b, "a");
    EXPECT_NEAR(r[0], 0.5f, 0.03);
    TypeSpec type;
    std::vector<float> narrow, far;
    rig.context.output("narrow", type, narrow);
    rig.context.output("far", type, far);
    EXPECT_EQ(narrow[0], 1.0f); // every ray of the cone about +x hits
    EXPECT_EQ(far[0], 0.0f);    // the plane is 2 away
    for (const auto& q : rig.services.queries) EXPECT_TRUE(q.outputs.empty());
}

TEST(EngineRaytrace, ShadowAndTransmissionGoThroughTransmit) {
    Rig rig;
    ShadingBatch b = points(2);
    b.ray.depth = 2;
    const auto light = std::make_shared<ShaderInstance>(
        compile_shader("light l() { illuminate(point(0, 0, 5)) { Cl = 1; } }"),
        ParamList{}, Matrix4(1.0), "light");
    const ShaderInstance* lights[] = {light.get()};
    const auto r = rig.run(R"(
surface t(output varying color sc = 0, tr = 0, tc = 0; output varying float sf = 0) {
    illuminance(P) {
        sc = color shadow("raytrace", P);
        sf = shadow("raytrace", P, "samples", 4, "samplecone", 0.1);
    }
    tr = transmission(P, P + vector(0, 0, 1));
    tc = transmission(P, P + vector(0, 0, 1), "samples", 8, "samplecone", 0.2);
}
)",
                           b, "sc", lights);
    EXPECT_NEAR(r[0], 0.75f, 1e-6);
    EXPECT_NEAR(r[1], 0.5f, 1e-6);
    EXPECT_NEAR(r[2], 0.0f, 1e-6);
    TypeSpec type;
    std::vector<float> sf, tr, tc;
    rig.context.output("sf", type, sf);
    rig.context.output("tr", type, tr);
    rig.context.output("tc", type, tc);
    EXPECT_NEAR(sf[0], (0.75f + 0.5f + 0.0f) / 3, 1e-6);
    EXPECT_NEAR(tr[0], 0.25f, 1e-6);
    EXPECT_NEAR(tr[2], 1.0f, 1e-6);
    EXPECT_NEAR(tc[1], 0.5f, 1e-6);
    // 2 points: 1 + 4 shadow rays, 1 + 8 transmission rays each.
    EXPECT_EQ(rig.services.transmitted, 2u * (1 + 4 + 1 + 8));
    for (int d : rig.services.transmit_depths) EXPECT_EQ(d, 3);
}

TEST(EngineRaytrace, RayinfoDescribesTheIncomingRay) {
    Rig rig;
    ShadingBatch b = points(2);
    b.ray.depth = 2;
    b.ray.kind = RayKind::Diffuse;
    b.ray.label = "x";
    const auto r = rig.run(R"(
surface t(output varying float depth = -1, len = -1, ok = 0, unknown = 5;
          output varying point org = 0; output varying vector dir = 0) {
    string type = "", label = "";
    ok = rayinfo("depth", depth) + rayinfo("type", type) + rayinfo("label", label)
       + rayinfo("origin", org) + rayinfo("direction", dir) + rayinfo("length", len);
    ok += (type == "diffuse" ? 10 : 0) + (label == "x" ? 100 : 0);
    unknown = rayinfo("nosuch", depth) * 1000 + unknown;
}
)",
                           b, "depth");
    EXPECT_EQ(r[0], 2.0f);
    TypeSpec type;
    std::vector<float> ok, len, org, dir, unknown;
    rig.context.output("ok", type, ok);
    rig.context.output("len", type, len);
    rig.context.output("org", type, org);
    rig.context.output("dir", type, dir);
    rig.context.output("unknown", type, unknown);
    for (std::size_t i = 0; i < 2; ++i) {
        EXPECT_EQ(ok[i], 116.0f);
        EXPECT_NEAR(len[i], std::sqrt(float(i * i) + 16.0f), 1e-5);
        // origin = P - I = (0, 0, -4); direction = normalize(I).
        EXPECT_NEAR(org[3 * i + 2], -4.0f, 1e-6);
        EXPECT_NEAR(org[3 * i], 0.0f, 1e-6);
        EXPECT_NEAR(dir[3 * i + 2], 4.0f / len[i], 1e-5);
        EXPECT_EQ(unknown[i], 5.0f);
    }
}

TEST(EngineRaytrace, ResultsDependOnTheSeedOnlyNotTheContext) {
    const char* src = R"(
surface t(output varying float s = 0; output varying color ind = 0) {
    vector d = 0;
    gather("", P, N, 1, 8, "ray:direction", d, "samplebase", 1) { s += xcomp(d); }
    else { s -= ycomp(d); }
    ind = indirectdiffuse(P, N, 32, "samplebase", 0.5);
}
)";
    auto once = [&](uint64_t seed) {
        Rig rig;
        rig.services.mode = FakeWorld::HalfX;
        ShadingBatch b = points(8);
        b.seed = seed;
        std::vector<float> s = rig.run(src, b, "s");
        TypeSpec type;
        std::vector<float> ind;
        rig.context.output("ind", type, ind);
        s.insert(s.end(), ind.begin(), ind.end());
        return std::make_pair(s, rig.services.queries.front().seed);
    };
    const auto a = once(7), b = once(7), c = once(8);
    EXPECT_EQ(a.first, b.first);
    EXPECT_EQ(a.second, b.second);
    EXPECT_NE(a.first, c.first);
    EXPECT_NE(a.second, c.second);
}

} // namespace
