// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file scene_rays.cpp
/// Secondary rays over the diced scene (scene_rays.h): tracers per kind of
/// ray, hit finding, and the shading of hits by their own surface shaders in
/// per-thread, per-depth shading contexts.

#include "sss/binding/scene_rays.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>
#include <tbb/enumerable_thread_specific.h>

#include "sss/util/hash.h"
#include "sss/util/messages.h"

namespace sss {

namespace {

/// Hit batches: at most this many points per shader execution.
constexpr std::size_t kBatch = 256;
/// Surfaces a ray may pass (one-sided back faces, transparent surfaces)
/// before it counts as a miss, and layers a transmission ray multiplies.
constexpr int kMaxSkips = 32;
/// A transmission ray stops once less than this gets through.
constexpr float kOpaque = 1e-4f;
/// PRMan's defaults: Option "trace" "maxdepth", Attribute "trace"
/// "maxdiffusedepth" and "maxspeculardepth".
constexpr int kDefaultMaxDepth = 10;
constexpr int kDefaultMaxDiffuseDepth = 1;
constexpr int kDefaultMaxSpecularDepth = 2;
/// Above this depth a scene's limit is cut back (each level multiplies the
/// rays; deeper recursion cannot finish).
constexpr int kDepthCap = 64;

/// A guard against ray trees that cannot finish (hit shaders that gather
/// into each other many levels deep with many samples): the rays traced
/// under one top-level query may be at most this many per ray of it; past
/// that, deeper rays miss (with a warning). Two bounces of 128 samples fit.
constexpr uint64_t kTreeRaysPerRay = 16384;
/// Rays traced, and allowed, in the current thread's ray tree.
thread_local uint64_t t_tree_rays = 0;
thread_local uint64_t t_tree_budget = 0;

/// The tracers: diffuse, specular and transmission.
constexpr int kKinds = 3;
int kind_slot(RayKind kind) {
    switch (kind) {
    case RayKind::Diffuse:
        return 0;
    case RayKind::Transmission:
        return 2;
    default:
        return 1; // specular (and camera rays asked of the scene)
    }
}
const char* const kVisibility[kKinds] = {"diffuse", "specular", "transmission"};

/// A ray's hit, found on a primitive.
struct Hit {
    uint32_t ray = 0;
    uint32_t prim = 0;
    uint32_t triangle = 0;
    float b1 = 0.0f, b2 = 0.0f;
    float t = 0.0f;
};

bool contains_raytrace(const Program& program) {
    for (const Symbol& s : program.symbols)
        if (s.kind == SymbolKind::Const && s.type.type == ShadingType::String)
            for (const std::string& str : s.strings)
                if (str == "raytrace") return true;
    return false;
}

} // namespace

std::optional<float> trace_bias(const Primitive& prim) {
    const Attributes& attr = attributes_of(prim);
    const auto trace = attr.groups.find("trace");
    if (trace == attr.groups.end()) return std::nullopt;
    const double b = trace->second.get_float("bias", -1.0);
    if (!(b >= 0.0) || !std::isfinite(b)) return std::nullopt;
    return static_cast<float>(b);
}

bool program_shades_hits(const Program& program) {
    for (const char* op : {"trace", "gather", "indirectdiffuse", "occlusion"})
        if (program_uses(program, op)) return true;
    return program_uses(program, "environment") && contains_raytrace(program);
}

bool program_traces_rays(const Program& program) {
    for (const char* op : {"trace", "gather", "indirectdiffuse", "occlusion"})
        if (program_uses(program, op)) return true;
    return (program_uses(program, "environment") || program_uses(program, "shadow")) &&
           contains_raytrace(program);
}

/// What hit shaders get as their services: the outer job's messages and
/// textures, this scene's rays, and no bake3d.
class HitServices final : public ShadingServices {
public:
    HitServices(const SceneRays::Impl& impl, ShadingServices& outer)
        : m_impl(impl), m_outer(outer) {}
    const Scene& scene() const override { return m_outer.scene(); }
    const RayTracer* occluders() const override;
    void trace(RayQuery& query) override;
    void transmit(const ShadowRay* rays, std::size_t count, glm::vec3* out,
                  int depth) override;
    TextureServices* textures() override { return m_outer.textures(); }
    void bake3d(Bake3dRecord&& record) override { (void)record; }
    void message(const std::string& text) override { m_outer.message(text); }
    void warning(const std::string& text) override { m_outer.warning(text); }
    std::optional<int> frame() const override { return m_outer.frame(); }

private:
    const SceneRays::Impl& m_impl;
    ShadingServices& m_outer;
};

struct SceneRays::Impl {
    const Scene& scene;
    const SceneShaders& shaders;
    const ShadingResources& resources;
    ShadingServices& outer;
    std::vector<RaySurface> surfaces;

    std::vector<std::unique_ptr<RayTracer>> tracers;
    std::array<int, kKinds> tracer_of{-1, -1, -1};
    std::vector<std::vector<uint32_t>> mesh_prim; ///< per tracer: mesh -> primitive
    /// Per tracer: which primitives it holds, and whether a ray may have to
    /// pass one of them (one-sided or fully transparent).
    std::vector<std::vector<char>> in_tracer;
    std::vector<char> skippable;
    std::size_t triangle_count = 0;
    float extent = 0.0f;

    int max_depth = kDefaultMaxDepth;
    /// Per primitive: what its shading needs and its attributes' choices.
    std::vector<char> parametric;
    std::vector<char> diffuse_primitive_mode, specular_primitive_mode;
    std::vector<char> transmission_shader_mode;
    std::vector<float> bias;         ///< Attribute "trace" "bias", or < 0
    bool transmission_binary = true; ///< opaque occluders, "primitive" mode

    glm::dmat4 to_camera{1.0};
    glm::dmat3 normal_to_camera{1.0};

    mutable std::atomic<uint64_t> rays{0};
    mutable std::atomic<uint64_t> nonfinite{0};
    mutable std::atomic<bool> budget_warned{false};
    std::unique_ptr<HitServices> hit_services;
    mutable tbb::enumerable_thread_specific<std::vector<std::unique_ptr<ShadingContext>>>
        contexts;

    Impl(const Scene& s, const SceneShaders& sh, const ShadingResources& r,
         ShadingServices& o, std::vector<RaySurface> surf)
        : scene(s), shaders(sh), resources(r), outer(o), surfaces(std::move(surf)) {}

    ShadingContext& context_at(int depth) const {
        auto& list = contexts.local();
        const auto d = static_cast<std::size_t>(std::max(depth, 0));
        if (list.size() <= d) list.resize(d + 1);
        if (!list[d])
            list[d] = std::make_unique<ShadingContext>(resources, *hit_services);
        return *list[d];
    }

    const RayTracer* tracer(RayKind kind) const {
        const int t = tracer_of[static_cast<std::size_t>(kind_slot(kind))];
        return t >= 0 ? tracers[static_cast<std::size_t>(t)].get() : nullptr;
    }
    const std::vector<uint32_t>& meshes(RayKind kind) const {
        return mesh_prim[static_cast<std::size_t>(
            tracer_of[static_cast<std::size_t>(kind_slot(kind))])];
    }

    /// Whether rays of `query` may be traced at all (the depth limits).
    bool allowed(const RayQuery& q) const {
        if (q.depth > max_depth) return false;
        if (q.kind == RayKind::Transmission) return true;
        if (q.kind != RayKind::Diffuse && q.kind != RayKind::Specular) return true;
        const bool diffuse = q.kind == RayKind::Diffuse;
        int limit = diffuse ? kDefaultMaxDiffuseDepth : kDefaultMaxSpecularDepth;
        if (q.origin) {
            const Attributes& a = attributes_of(*q.origin);
            const auto it = a.groups.find("trace");
            if (it != a.groups.end())
                limit = it->second.get_int(
                    diffuse ? "maxdiffusedepth" : "maxspeculardepth", limit);
        }
        return q.depth <= limit;
    }

    /// The nearest shaded surface along `ray` (skipping transparent surfaces,
    /// and the faces of one-sided surfaces the query's hitsides excludes);
    /// false for a miss.
    bool find_hit(const RayTracer& rt, const std::vector<uint32_t>& mesh_to_prim,
                  ShadowRay ray, const RayQuery& q, Hit& out) const {
        const float skip_base = 1e-6f * extent;
        for (int k = 0; k < kMaxSkips; ++k) {
            if (!(ray.tnear <= ray.tfar)) return false;
            const RayHit h = rt.intersect(ray);
            rays.fetch_add(1, std::memory_order_relaxed);
            if (!h.hit) return false;
            const uint32_t prim = mesh_to_prim[h.mesh];
            const Attributes& attr = attributes_of(scene.primitives[prim]);
            bool skip = glm::clamp(attr.opacity, 0.0, 1.0) == glm::dvec3(0.0) ||
                        (h.t < q.self_distance && q.origin == &scene.primitives[prim]);
            if (!skip && attr.sides == 1 && q.hitsides != HitSides::Both) {
                const glm::vec3 n =
                    interpolated_normal(prim, h.triangle, h.u, h.v, ray.time);
                glm::vec3 ng = h.geometric_normal;
                if (glm::dot(ng, n) < 0.0f) ng = -ng;
                const bool back = glm::dot(ng, ray.direction) > 0.0f;
                skip = back == (q.hitsides == HitSides::Front);
            }
            if (skip) {
                ray.tnear = h.t + skip_base + 1e-6f * h.t;
                continue;
            }
            out.prim = prim;
            out.triangle = h.triangle;
            out.b1 = h.u;
            out.b2 = h.v;
            out.t = h.t;
            return true;
        }
        return false;
    }

    /// The normal at a hit, of the surface as it is at `time` (motion blur).
    glm::vec3 interpolated_normal(uint32_t prim, uint32_t tri, float b1, float b2,
                                  float time) const {
        const DicedSurface& d = *surfaces[prim].diced;
        const uint32_t* v = &d.triangles[3 * std::size_t(tri)];
        if (d.vertex_normals.size() != d.vertices.size()) {
            const glm::vec3 v0 = d.vertex_at(v[0], time);
            return glm::cross(d.vertex_at(v[1], time) - v0, d.vertex_at(v[2], time) - v0);
        }
        return (1.0f - b1 - b2) * d.normal_at(v[0], time) + b1 * d.normal_at(v[1], time) +
               b2 * d.normal_at(v[2], time);
    }

    /// Shades hits[begin, end) (one primitive) and writes the query's
    /// outputs (or, with `oi`, the hit shader's Oi per hit).
    void shade(const RayQuery& q, const std::vector<Hit>& hits, std::size_t begin,
               std::size_t end, RayQuery* results, std::vector<glm::vec3>* oi) const;

    /// The Interior and Exterior shaders on the segments of shaded hits
    /// (batch: one primitive's hits; back[k]: hit k is on a back face, so
    /// its ray travelled inside that primitive): Interior of the primitive
    /// hit from behind, else Exterior of the primitive the rays left.
    void run_volumes(const RayQuery& q, ShadingBatch& batch,
                     const std::vector<char>& back, uint32_t prim_index) const;

    void trace(RayQuery& q) const;
    void transmit(const ShadowRay* rays, std::size_t count, glm::vec3* out,
                  int depth) const;
};

void SceneRays::Impl::run_volumes(const RayQuery& q, ShadingBatch& batch,
                                  const std::vector<char>& back,
                                  uint32_t prim_index) const {
    const Primitive* const first = scene.primitives.data();
    const bool known_origin =
        q.origin && q.origin >= first && q.origin < first + scene.primitives.size();
    const std::size_t origin_index = known_origin ? std::size_t(q.origin - first) : 0;
    for (const bool inside : {true, false}) {
        const std::size_t owner = inside ? prim_index : origin_index;
        if (!inside && !known_origin) continue;
        const ShaderInstance* shader =
            (inside ? shaders.interior_of : shaders.exterior_of)[owner];
        if (!shader) continue;
        std::vector<std::size_t> which;
        for (std::size_t k = 0; k < batch.size; ++k)
            if ((back[k] != 0) == inside) which.push_back(k);
        if (which.empty()) continue;
        const std::size_t n = which.size();
        ShadingBatch v;
        v.size = n;
        v.layout = BatchLayout::Points;
        v.primitive = &scene.primitives[owner];
        v.ray = batch.ray;
        v.seed = detail::splitmix64(batch.seed ^ (inside ? 0x696E74ull : 0x657874ull));
        v.ray_offset = batch.ray_offset;
        for (auto* x : {&v.P, &v.I, &v.N, &v.Ng, &v.Ci, &v.Oi}) x->resize(n);
        for (std::size_t j = 0; j < n; ++j) {
            const std::size_t k = which[j];
            v.P[j] = batch.P[k];
            v.I[j] = batch.I[k];
            v.N[j] = batch.N[k];
            v.Ng[j] = batch.Ng[k];
            v.Ci[j] = batch.Ci[k];
            v.Oi[j] = batch.Oi[k];
        }
        ShadingContext& context = context_at(q.depth);
        const auto& lights = shaders.lights_of[owner];
        const auto& coshaders = shaders.coshaders_of[owner];
        context.execute(*shader, v, LightList(lights.data(), lights.size()),
                        CoshaderList(coshaders.data(), coshaders.size()));
        nonfinite.fetch_add(context.nonfinite_points(), std::memory_order_relaxed);
        for (std::size_t j = 0; j < n; ++j) {
            batch.Ci[which[j]] = v.Ci[j];
            batch.Oi[which[j]] = v.Oi[j];
        }
    }
}

const RayTracer* HitServices::occluders() const {
    return m_impl.tracer(RayKind::Transmission);
}
void HitServices::trace(RayQuery& query) {
    m_impl.trace(query);
}
void HitServices::transmit(const ShadowRay* rays, std::size_t count, glm::vec3* out,
                           int depth) {
    m_impl.transmit(rays, count, out, depth);
}

void SceneRays::Impl::shade(const RayQuery& q, const std::vector<Hit>& hits,
                            std::size_t begin, std::size_t end, RayQuery* results,
                            std::vector<glm::vec3>* oi) const {
    const uint32_t prim_index = hits[begin].prim;
    const Primitive& prim = scene.primitives[prim_index];
    const Attributes& attr = attributes_of(prim);
    const DicedSurface& d = *surfaces[prim_index].diced;
    const std::vector<glm::vec3>* colors = surfaces[prim_index].triangle_colors;
    const std::size_t n = end - begin;
    const bool primitive_mode =
        (q.kind == RayKind::Diffuse && diffuse_primitive_mode[prim_index]) ||
        (q.kind == RayKind::Specular && specular_primitive_mode[prim_index]) ||
        (q.kind == RayKind::Transmission && !transmission_shader_mode[prim_index]);

    ShadingBatch batch;
    batch.size = n;
    batch.layout = BatchLayout::Points;
    batch.primitive = &prim;
    for (auto* v : {&batch.P, &batch.N, &batch.Ng, &batch.I, &batch.dPdu, &batch.dPdv,
                    &batch.Cs, &batch.Os})
        v->resize(n);
    batch.du.assign(n, 1.0f);
    batch.dv.assign(n, 1.0f);
    const bool uvst = parametric[prim_index] && d.vertex_uvst.size() == d.vertices.size();
    if (uvst)
        for (auto* v : {&batch.u, &batch.v, &batch.s, &batch.t}) v->resize(n);
    batch.dicing_area.resize(n);
    batch.radius.resize(n);
    batch.seed =
        detail::splitmix64(q.seed ^ (0x5851F42D4C957F2Dull * (hits[begin].ray + 1)));
    batch.ray_offset = bias[prim_index] >= 0.0f ? bias[prim_index] : 1e-5f * extent;
    batch.ray = RayContext{q.depth, q.kind, q.label};
    const glm::dmat3 linear(to_camera);
    std::vector<char> back(n, 0); // the ray reached the hit from behind its surface
    for (std::size_t k = 0; k < n; ++k) {
        const Hit& h = hits[begin + k];
        const ShadowRay& ray = q.rays[h.ray];
        const uint32_t* tri = &d.triangles[3 * std::size_t(h.triangle)];
        const glm::dvec3 v0(d.vertex_at(tri[0], ray.time)),
            v1(d.vertex_at(tri[1], ray.time)), v2(d.vertex_at(tri[2], ray.time));
        const double b1 = h.b1, b2 = h.b2, b0 = 1.0 - b1 - b2;
        const glm::dvec3 p = b0 * v0 + b1 * v1 + b2 * v2;
        glm::dvec3 ng = glm::cross(v1 - v0, v2 - v0);
        const double ngl = glm::length(ng);
        ng = ngl > 0.0 && std::isfinite(ngl) ? ng / ngl : -glm::dvec3(ray.direction);
        glm::dvec3 nn(interpolated_normal(prim_index, h.triangle, h.b1, h.b2, ray.time));
        // The hit's own rays leave at the time it was seen (motion blur).
        if (ray.time != 0.0f) {
            batch.ray_time.resize(n, 0.0f);
            batch.ray_time[k] = ray.time;
        }
        const double nl = glm::length(nn);
        nn = nl > 0.0 && std::isfinite(nl) ? nn / nl : ng;
        if (glm::dot(ng, nn) < 0.0) ng = -ng;
        back[k] = glm::dot(ng, glm::dvec3(ray.direction)) > 0.0;
        // The footprint: the ray's spread at the hit, on the tangent plane.
        const double w = std::max(double(q.spread) * h.t, 1e-6 * extent);
        glm::dvec3 t1 = glm::cross(nn, glm::dvec3(ray.direction));
        if (glm::length(t1) < 1e-6)
            t1 = glm::cross(nn, std::abs(nn.x) < 0.9 ? glm::dvec3(1, 0, 0)
                                                     : glm::dvec3(0, 1, 0));
        t1 = glm::normalize(t1);
        const glm::dvec3 t2 = glm::cross(nn, t1);
        const glm::dvec3 pc = glm::dvec3(to_camera * glm::dvec4(p, 1.0));
        const glm::dvec3 oc =
            glm::dvec3(to_camera * glm::dvec4(glm::dvec3(ray.origin), 1.0));
        batch.P[k] = glm::vec3(pc);
        batch.I[k] = glm::vec3(pc - oc);
        batch.N[k] = glm::vec3(glm::normalize(normal_to_camera * nn));
        batch.Ng[k] = glm::vec3(glm::normalize(normal_to_camera * ng));
        batch.dPdu[k] = glm::vec3(linear * (t1 * w));
        batch.dPdv[k] = glm::vec3(linear * (t2 * w));
        batch.Cs[k] =
            colors && !colors->empty() ? (*colors)[h.triangle] : glm::vec3(attr.color);
        batch.Os[k] = glm::vec3(glm::clamp(attr.opacity, 0.0, 1.0));
        batch.dicing_area[k] = static_cast<float>(w * w);
        batch.radius[k] = static_cast<float>(0.5 * w);
        if (uvst) {
            const glm::vec4 a = (1.0f - h.b1 - h.b2) * d.vertex_uvst[tri[0]] +
                                h.b1 * d.vertex_uvst[tri[1]] +
                                h.b2 * d.vertex_uvst[tri[2]];
            batch.u[k] = a.x;
            batch.v[k] = a.y;
            batch.s[k] = a.z;
            batch.t[k] = a.w;
        }
    }

    if (primitive_mode) {
        batch.Ci = batch.Cs;
        batch.Oi = batch.Os;
    } else {
        ShadingContext& context = context_at(q.depth);
        const auto& lights = shaders.lights_of[prim_index];
        const auto& coshaders = shaders.coshaders_of[prim_index];
        context.execute(*shaders.surface_of[prim_index], batch,
                        LightList(lights.data(), lights.size()),
                        CoshaderList(coshaders.data(), coshaders.size()));
        nonfinite.fetch_add(context.nonfinite_points(), std::memory_order_relaxed);
        if (results) {
            for (std::size_t o = 0; o < q.outputs.size(); ++o) {
                const std::string& name = q.outputs[o];
                const int want = q.output_floats[o];
                std::vector<float>& dst = results->values[o];
                if (name == "Ci" || name == "Oi") continue;
                TypeSpec type;
                std::vector<float> values;
                if (!context.output(name, type, values)) continue;
                const int have = type.floats();
                const int copy = std::min(want, have);
                const std::size_t stride =
                    values.size() >= n * std::size_t(have) ? std::size_t(have) : 0;
                for (std::size_t k = 0; k < n; ++k)
                    for (int c = 0; c < copy; ++c)
                        dst[std::size_t(hits[begin + k].ray) * want + c] =
                            values[k * stride + c];
            }
        }
    }
    if (oi)
        for (std::size_t k = 0; k < n; ++k) (*oi)[begin + k] = batch.Oi[k];
    if (!results) return;
    if (shaders.any_interior_exterior &&
        std::any_of(q.outputs.begin(), q.outputs.end(),
                    [](const std::string& o) { return o == "Ci" || o == "Oi"; }))
        run_volumes(q, batch, back, prim_index);
    // Ci, Oi (and, in primitive mode, Cs and Os) from the batch.
    for (std::size_t o = 0; o < q.outputs.size(); ++o) {
        const std::string& name = q.outputs[o];
        const std::vector<glm::vec3>* src = name == "Ci"                     ? &batch.Ci
                                            : name == "Oi"                   ? &batch.Oi
                                            : primitive_mode && name == "Cs" ? &batch.Cs
                                            : primitive_mode && name == "Os" ? &batch.Os
                                                                             : nullptr;
        if (!src) continue;
        const int want = q.output_floats[o];
        std::vector<float>& dst = results->values[o];
        for (std::size_t k = 0; k < n; ++k)
            for (int c = 0; c < std::min(want, 3); ++c)
                dst[std::size_t(hits[begin + k].ray) * want + c] = (*src)[k][c];
    }
}

void SceneRays::Impl::trace(RayQuery& q) const {
    const std::size_t count = q.rays.size();
    q.hit.assign(count, 0);
    q.length.assign(count, std::numeric_limits<float>::infinity());
    q.values.resize(q.outputs.size());
    q.output_floats.resize(q.outputs.size(), 3);
    for (std::size_t k = 0; k < q.outputs.size(); ++k)
        q.values[k].assign(count * std::size_t(std::max(q.output_floats[k], 0)), 0.0f);
    const RayTracer* rt = tracer(q.kind);
    if (!rt || count == 0 || !allowed(q)) return;
    // A tree starts at a depth-1 query (or at a deeper one asked directly).
    if (q.depth <= 1 || t_tree_budget == 0) {
        t_tree_rays = 0;
        t_tree_budget = std::max<uint64_t>(count, 1) * kTreeRaysPerRay;
    } else if (t_tree_rays + count > t_tree_budget) {
        if (!budget_warned.exchange(true))
            outer.warning("a ray tree grew past " + std::to_string(kTreeRaysPerRay) +
                          " rays per top-level ray (hit shaders tracing many samples "
                          "many levels deep): deeper rays miss; lower the samples or "
                          "Attribute \"trace\" \"maxdiffusedepth\"/\"maxspeculardepth\"");
        return;
    }
    t_tree_rays += count;
    const std::vector<uint32_t>& mesh_to_prim = meshes(q.kind);
    if (q.outputs.empty() && !q.need_length) {
        // Hit or not: Embree's any-hit test over the whole stream, then the
        // exact search only for blocked rays that might have to pass a
        // surface (one-sided, transparent, or the shooter's own triangles).
        std::vector<uint8_t> blocked(count);
        rt->occluded(q.rays.data(), count, blocked.data());
        rays.fetch_add(count, std::memory_order_relaxed);
        const int t = tracer_of[static_cast<std::size_t>(kind_slot(q.kind))];
        const bool own =
            q.self_distance > 0.0f && q.origin && q.origin >= scene.primitives.data() &&
            q.origin < scene.primitives.data() + scene.primitives.size() &&
            in_tracer[static_cast<std::size_t>(t)]
                     [static_cast<std::size_t>(q.origin - scene.primitives.data())];
        const bool exact = own || skippable[static_cast<std::size_t>(t)];
        for (std::size_t r = 0; r < count; ++r) {
            if (!blocked[r]) continue;
            Hit h;
            q.hit[r] = exact ? find_hit(*rt, mesh_to_prim, q.rays[r], q, h) : 1;
        }
        return;
    }
    std::vector<Hit> hits;
    hits.reserve(count);
    for (std::size_t r = 0; r < count; ++r) {
        Hit h;
        if (!find_hit(*rt, mesh_to_prim, q.rays[r], q, h)) continue;
        h.ray = static_cast<uint32_t>(r);
        q.hit[r] = 1;
        q.length[r] = h.t;
        hits.push_back(h);
    }
    if (q.outputs.empty() || hits.empty()) return;
    std::stable_sort(hits.begin(), hits.end(),
                     [](const Hit& a, const Hit& b) { return a.prim < b.prim; });
    std::size_t begin = 0;
    while (begin < hits.size()) {
        std::size_t end = begin;
        while (end < hits.size() && end - begin < kBatch &&
               hits[end].prim == hits[begin].prim)
            ++end;
        shade(q, hits, begin, end, &q, nullptr);
        begin = end;
    }
}

void SceneRays::Impl::transmit(const ShadowRay* in, std::size_t count, glm::vec3* out,
                               int depth) const {
    std::fill(out, out + count, glm::vec3(1.0f));
    const RayTracer* rt = tracer(RayKind::Transmission);
    if (!rt || count == 0) return;
    if (transmission_binary) {
        std::vector<uint8_t> blocked(count);
        rt->occluded(in, count, blocked.data());
        rays.fetch_add(count, std::memory_order_relaxed);
        for (std::size_t r = 0; r < count; ++r)
            if (blocked[r]) out[r] = glm::vec3(0.0f);
        return;
    }
    // Layer by layer: every live ray to its next surface; surfaces whose
    // opacity comes from their shader are shaded together.
    const std::vector<uint32_t>& mesh_to_prim = meshes(RayKind::Transmission);
    const float skip_base = 1e-6f * extent;
    std::vector<ShadowRay> live(in, in + count);
    std::vector<uint32_t> active(count);
    std::iota(active.begin(), active.end(), 0u);
    RayQuery q; // for shading: rays, depth, kind
    q.kind = RayKind::Transmission;
    q.depth = depth;
    q.label = "transmission";
    q.rays.assign(in, in + count); // the hits' I: from the original origins
    q.seed = detail::splitmix64(0x7472616E736D6974ull ^ count);
    for (int layer = 0; layer < kMaxSkips && !active.empty(); ++layer) {
        std::vector<Hit> shaded;
        std::vector<uint32_t> next;
        for (uint32_t r : active) {
            ShadowRay& ray = live[r];
            if (!(ray.tnear <= ray.tfar)) continue;
            const RayHit h = rt->intersect(ray);
            rays.fetch_add(1, std::memory_order_relaxed);
            if (!h.hit) continue;
            ray.tnear = h.t + skip_base + 1e-6f * h.t;
            const uint32_t prim = mesh_to_prim[h.mesh];
            if (transmission_shader_mode[prim] && depth <= max_depth) {
                Hit hit;
                hit.ray = r;
                hit.prim = prim;
                hit.triangle = h.triangle;
                hit.b1 = h.u;
                hit.b2 = h.v;
                hit.t = h.t;
                shaded.push_back(hit);
            } else {
                const glm::dvec3 os =
                    glm::clamp(attributes_of(scene.primitives[prim]).opacity, 0.0, 1.0);
                out[r] *= glm::vec3(1.0 - os);
            }
            next.push_back(r);
        }
        if (!shaded.empty()) {
            std::stable_sort(shaded.begin(), shaded.end(),
                             [](const Hit& a, const Hit& b) { return a.prim < b.prim; });
            std::vector<glm::vec3> oi(shaded.size());
            std::size_t begin = 0;
            while (begin < shaded.size()) {
                std::size_t end = begin;
                while (end < shaded.size() && end - begin < kBatch &&
                       shaded[end].prim == shaded[begin].prim)
                    ++end;
                shade(q, shaded, begin, end, nullptr, &oi);
                begin = end;
            }
            for (std::size_t k = 0; k < shaded.size(); ++k)
                out[shaded[k].ray] *= glm::vec3(1.0f) - glm::clamp(oi[k], 0.0f, 1.0f);
        }
        active.clear();
        for (uint32_t r : next)
            if (std::max({out[r].x, out[r].y, out[r].z}) >= kOpaque) active.push_back(r);
    }
    for (std::size_t r = 0; r < count; ++r)
        if (std::max({out[r].x, out[r].y, out[r].z}) < kOpaque) out[r] = glm::vec3(0.0f);
}

SceneRays::SceneRays(const Scene& scene, const SceneShaders& shaders,
                     const ShadingResources& resources, ShadingServices& outer,
                     std::vector<RaySurface> surfaces)
    : m_impl(
          std::make_unique<Impl>(scene, shaders, resources, outer, std::move(surfaces))) {
    Impl& im = *m_impl;
    const std::size_t count = scene.primitives.size();
    im.surfaces.resize(count);
    im.hit_services = std::make_unique<HitServices>(im, outer);
    im.to_camera = scene.options.camera.world_to_camera;
    im.normal_to_camera = glm::transpose(glm::inverse(glm::dmat3(im.to_camera)));
    {
        const auto it = scene.options.groups.find("trace");
        if (it != scene.options.groups.end())
            im.max_depth = std::clamp(it->second.get_int("maxdepth", kDefaultMaxDepth), 0,
                                      kDepthCap);
    }
    im.parametric.assign(count, 0);
    im.diffuse_primitive_mode.assign(count, 0);
    im.specular_primitive_mode.assign(count, 0);
    im.transmission_shader_mode.assign(count, 0);
    im.bias.assign(count, -1.0f);
    // Which primitives each kind of ray sees; equal sets share a tracer.
    std::array<std::vector<uint32_t>, kKinds> members;
    for (std::size_t i = 0; i < count; ++i) {
        const Primitive& prim = scene.primitives[i];
        const Attributes& attr = attributes_of(prim);
        if (i < shaders.surface_of.size() && shaders.surface_of[i])
            im.parametric[i] = program_reads_parametric(shaders.surface_of[i]->program());
        const auto shade = attr.groups.find("shade");
        if (shade != attr.groups.end()) {
            const ParamList& p = shade->second;
            im.diffuse_primitive_mode[i] =
                p.get_string("diffusehitmode", "") == "primitive";
            im.specular_primitive_mode[i] =
                p.get_string("specularhitmode", "") == "primitive";
            im.transmission_shader_mode[i] =
                p.get_string("transmissionhitmode", "") == "shader";
        }
        if (const std::optional<float> b = trace_bias(prim)) im.bias[i] = *b;
        const RaySurface& s = im.surfaces[i];
        if (!s.diced || s.diced->triangles.empty()) continue;
        for (int k = 0; k < kKinds; ++k)
            if (attr.visible_to(kVisibility[k]))
                members[std::size_t(k)].push_back(static_cast<uint32_t>(i));
        if (attr.visible_to("transmission") &&
            (im.transmission_shader_mode[i] ||
             glm::clamp(attr.opacity, 0.0, 1.0) != glm::dvec3(1.0)))
            im.transmission_binary = false;
    }
    for (int k = 0; k < kKinds; ++k) {
        const auto& m = members[std::size_t(k)];
        if (m.empty()) continue;
        int same = -1;
        for (int j = 0; j < k; ++j)
            if (im.tracer_of[std::size_t(j)] >= 0 && members[std::size_t(j)] == m)
                same = im.tracer_of[std::size_t(j)];
        if (same >= 0) {
            im.tracer_of[std::size_t(k)] = same;
            continue;
        }
        auto rt = std::make_unique<RayTracer>();
        std::vector<uint32_t> mesh_to_prim;
        std::vector<char> in(count, 0);
        char skip = 0;
        for (uint32_t i : m) {
            const Attributes& attr = attributes_of(scene.primitives[i]);
            in[i] = 1;
            skip = skip || attr.sides == 1 ||
                   glm::clamp(attr.opacity, 0.0, 1.0) == glm::dvec3(0.0);
            const DicedSurface& d = *im.surfaces[i].diced;
            rt->add_mesh(d.vertices, d.triangles,
                         d.moving() ? &d.step_vertices : nullptr);
            mesh_to_prim.push_back(i);
            im.triangle_count += d.triangles.size() / 3;
        }
        rt->commit();
        im.extent = std::max(im.extent, rt->scene_extent());
        im.tracer_of[std::size_t(k)] = static_cast<int>(im.tracers.size());
        im.tracers.push_back(std::move(rt));
        im.mesh_prim.push_back(std::move(mesh_to_prim));
        im.in_tracer.push_back(std::move(in));
        im.skippable.push_back(skip);
    }
}

SceneRays::~SceneRays() = default;

void SceneServices::message(const std::string& text) {
    std::lock_guard<std::mutex> lock(m_mutex);
    std::fputs(text.c_str(), stdout);
    if (text.empty() || text.back() != '\n') std::fputc('\n', stdout);
    flush_standard_output();
}

void SceneServices::warning(const std::string& text) {
    std::lock_guard<std::mutex> lock(m_mutex);
    m_warnings.push_back(text);
}

Warnings SceneServices::take_warnings() {
    std::lock_guard<std::mutex> lock(m_mutex);
    Warnings out = std::move(m_warnings);
    m_warnings = Warnings();
    return out;
}

void SceneServices::trace(RayQuery& query) {
    if (m_rays)
        m_rays->trace(query);
    else
        ShadingServices::trace(query);
}

void SceneServices::transmit(const ShadowRay* rays, std::size_t count, glm::vec3* out,
                             int depth) {
    if (m_rays)
        m_rays->transmit(rays, count, out, depth);
    else
        ShadingServices::transmit(rays, count, out, depth);
}

void SceneRays::trace(RayQuery& query) const {
    m_impl->trace(query);
}
void SceneRays::transmit(const ShadowRay* rays, std::size_t count, glm::vec3* out,
                         int depth) const {
    m_impl->transmit(rays, count, out, depth);
}
const RayTracer* SceneRays::occluders() const {
    return m_impl->tracer(RayKind::Transmission);
}
float SceneRays::extent() const {
    return m_impl->extent;
}
uint64_t SceneRays::rays_traced() const {
    return m_impl->rays.load();
}
uint64_t SceneRays::nonfinite_points() const {
    return m_impl->nonfinite.load();
}
std::string invalid_rays_warning(uint64_t count) {
    return std::to_string(count) + (count == 1 ? " ray" : " rays") +
           " with a NaN, infinite or out-of-range origin or direction (from a "
           "shader's arithmetic, or a light beyond +-1e18) were not traced and "
           "count as misses";
}

uint64_t SceneRays::invalid_rays() const {
    uint64_t n = 0;
    for (const auto& t : m_impl->tracers)
        if (t) n += t->invalid_rays();
    return n;
}
std::size_t SceneRays::triangles() const {
    return m_impl->triangle_count;
}

} // namespace sss
