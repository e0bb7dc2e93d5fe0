// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file engine_raytrace.cpp
/// Ray-tracing shadeops (RISpec 15.5, shading.md 5.5): every ray goes through
/// ShadingServices::trace (rays that find and shade hits) or
/// ShadingServices::transmit (transmittance along segments). docs/shading.md
/// ("Ray tracing") has every parameter and output; in short:
///
///  - Rays are in world space, one RayQuery per op call for all running
///    points and samples, depth = the batch's ShadingBatch::ray.depth + 1.
///    Sample patterns are stratified per point and rotated by
///    point_hash(batch seed, point, op, call): results never depend on the
///    thread count.
///  - gather(cat, P, dir, angle, samples, ...) hit-body [else miss-body]:
///    `samples` rays per point in the cone of half-angle `angle` about dir
///    ("distribution" "uniform" (default, Specular rays) or "cosine"
///    (Diffuse)); the bodies run once per sample, the hit body for the
///    points whose ray s hit, the else body for the others, with the output
///    variables set from ray s. Category "environment": Diffuse rays whose
///    "environment:color" is the "environmentmap" lookup; the hit body runs
///    for blocked rays, the else body for open ones.
///  - trace(P, dir): the hit's Ci (0 on a miss), Specular; environment(
///    "raytrace", dir) likewise from the surface P; "samples" with
///    "samplecone" / "blur" (full apex angle) average rays in a cone.
///  - occlusion(P, N, samples) / indirectdiffuse(P, N, samples): Diffuse
///    rays, cosine distributed in "coneangle" (default PI/2) about N,
///    adaptive sampling on request ("adaptive" 1), environment maps for the open
///    directions.
///  - shadow("raytrace", P) and transmission(Psrc, Pdst): transmit() with
///    Transmission rays (colour transmittance). shadow() of any other
///    non-empty name reads a depth map (shadow_map_lookup, engine_texture.cpp).

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include "engine_internal.h"
#include "sss/light/ray_tracer.h"
#include "sss/shading/texture_services.h"
#include "sss/util/hash.h"
#include "sss/util/math.h"

namespace sss::detail {

namespace {

constexpr double kGolden = 0.6180339887498949;
constexpr float kHalfPi = 1.5707963f;
/// ray:length of a ray that hit nothing within an infinite maxdist.
constexpr float kMissLength = 1e30f;

bool finite3(const glm::vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

/// An orthonormal basis about the unit vector w (Duff et al. 2017).
struct Basis {
    glm::vec3 t1{1, 0, 0}, t2{0, 1, 0}, w{0, 0, 1};
};
Basis basis_about(const glm::vec3& w) {
    Basis b;
    b.w = w;
    const float sign = std::copysign(1.0f, w.z);
    const float a = -1.0f / (sign + w.z);
    const float bb = w.x * w.y * a;
    b.t1 = glm::vec3(1.0f + sign * w.x * w.x * a, sign * bb, -sign * w.x);
    b.t2 = glm::vec3(bb, sign + w.y * w.y * a, -w.y);
    return b;
}

/// Stratum k of n directions in the cone of half-angle `angle` about b.w:
/// equal-measure rings (stratum k at (k + jitter) / n), golden-angle turns
/// from a per-point rotation. Cosine: density proportional to cos(theta)
/// (the cone clamped to the hemisphere); otherwise uniform over the solid
/// angle. `h` is the point's hash.
glm::vec3 cone_direction(const Basis& b, uint64_t h, int k, int n, double angle,
                         bool cosine) {
    const double u = (k + unit_double(splitmix64(h + 1 + static_cast<uint64_t>(k)))) / n;
    double turn = unit_double(h) + k * kGolden;
    turn -= std::floor(turn);
    const double phi = 2.0 * kPi * turn;
    double r, z;
    if (cosine) {
        const double smax = std::sin(std::clamp(angle, 0.0, kPi / 2));
        const double r2 = u * smax * smax;
        r = std::sqrt(r2);
        z = std::sqrt(std::max(0.0, 1.0 - r2));
    } else {
        const double cos_max = std::cos(std::clamp(angle, 0.0, kPi));
        z = 1.0 - (1.0 - cos_max) * u;
        r = std::sqrt(std::max(0.0, 1.0 - z * z));
    }
    return glm::normalize(float(r * std::cos(phi)) * b.t1 +
                          float(r * std::sin(phi)) * b.t2 + float(z) * b.w);
}

/// Angle between neighbouring rays of n in a cone of half-angle `angle`.
float ray_spread(double angle, int n) {
    const double solid = 2.0 * kPi * (1.0 - std::cos(std::clamp(angle, 0.0, kPi)));
    return static_cast<float>(std::sqrt(solid / std::max(n, 1)));
}

/// The token-value options of a ray-tracing call (uniform: the first running
/// point's values).
struct RayParams {
    int samples = 1;      ///< trace/environment/shadow/transmission "samples"
    float cone = 0.0f;    ///< "samplecone" / "blur": full apex angle
    float bias = -1.0f;   ///< < 0: ShadingBatch::ray_offset
    float maxdist = 0.0f; ///< <= 0: infinite
    float coneangle = kHalfPi;
    float samplebase = 0.0f;
    float adaptive = 0.0f; // off: the early stop misses small occluders
    std::string label;
    std::string distribution;
    std::string envmap;
    HitSides hitsides = HitSides::Both;
    int out_envcolor = -1, out_envdir = -1, out_occlusion = -1; ///< argument index
};

/// "hitsides" "front" | "back" | "both" (the default).
void set_hitsides(Frame& f, const BoundOp& b, const std::string& v, RayParams& o) {
    if (v == "both")
        o.hitsides = HitSides::Both;
    else if (v == "front")
        o.hitsides = HitSides::Front;
    else if (v == "back")
        o.hitsides = HitSides::Back;
    else
        f.warn_once(b, "hitsides \"" + v + "\" is not front, back or both; both is used");
}

RayParams ray_params(Frame& f, const BoundOp& b, int first) {
    RayParams o;
    const std::size_t i0 = f.first_active();
    // PRMan ignores the options it does not know; so do we, loudly.
    const auto ignored = [&](const std::string& name) {
        f.warn_once(b, b.op->name + " option \"" + name + "\" is not supported; ignored");
    };
    for_options(f, b, first, [&](const std::string& name, int k) {
        const Symbol& sym = f.program->symbols[b.op->args[k]];
        if (sym.type.type == ShadingType::String && !sym.type.is_array()) {
            const std::string& v = f.str(b, k, i0);
            if (name == "label")
                o.label = v;
            else if (name == "distribution")
                o.distribution = v;
            else if (name == "environmentmap")
                o.envmap = v;
            else if (name == "hitsides")
                set_hitsides(f, b, v, o);
            else
                ignored(name);
            return;
        }
        if (name == "environmentcolor" && b.op->writes >> k & 1u) {
            o.out_envcolor = k;
            return;
        }
        if (name == "environmentdir" && b.op->writes >> k & 1u) {
            o.out_envdir = k;
            return;
        }
        if (name == "occlusion" && b.op->writes >> k & 1u) {
            o.out_occlusion = k;
            return;
        }
        if (f.slot(b, k).nf != 1) return ignored(name);
        const float v = *f.ptr(b, k, i0);
        const bool finite = std::isfinite(v); // a non-finite value keeps the default
        if (name == "samples") {
            if (finite) o.samples = std::clamp(static_cast<int>(v), 1, 4096);
        } else if (name == "samplecone" || name == "blur") {
            if (finite) o.cone = std::clamp(v, 0.0f, 6.2831853f);
        } else if (name == "bias") {
            if (finite) o.bias = v;
        } else if (name == "maxdist") {
            if (finite) o.maxdist = v;
        } else if (name == "coneangle") {
            if (finite) o.coneangle = std::clamp(v, 0.0f, kHalfPi);
        } else if (name == "samplebase") {
            if (finite) o.samplebase = std::max(0.0f, v);
        } else if (name == "adaptive") {
            if (finite) o.adaptive = v;
        } else {
            ignored(name);
        }
    });
    return o;
}

/// What every ray-tracing op needs of its frame.
struct RayEnv {
    Frame& f;
    const ShadingBatch* batch;
    glm::dmat4 to_world, to_current;
    float offset;
    uint64_t seed;
    int op;
    uint32_t call;

    RayEnv(Frame& fr, const BoundOp& b, const RayParams& o)
        : f(fr), batch(fr.ctx->batch), to_world(fr.ctx->camera_to_world),
          to_current(fr.ctx->world_to_camera),
          offset(o.bias >= 0.0f ? o.bias : (batch ? batch->ray_offset : 0.0f)),
          seed(batch ? batch->seed : 0), op(b.index), call(fr.calls[b.index]++) {}

    int depth() const { return (batch ? batch->ray.depth : 0) + 1; }
    /// The time point i's rays are traced at (motion blur), 0 by default.
    float time(std::size_t i) const {
        return batch && batch->ray_time.size() > i ? batch->ray_time[i] : 0.0f;
    }
    uint64_t hash(std::size_t i) const { return point_hash(seed, i, op, call); }
    /// Seed of the query's hit shaders.
    uint64_t query_seed() const {
        return splitmix64(point_hash(seed, ~std::size_t(0), op, call));
    }
    float tfar(float maxdist) const {
        return maxdist > 0.0f ? maxdist : std::numeric_limits<float>::infinity();
    }

    /// The surface normal at point i (world space, unit), or 0.
    glm::vec3 normal(std::size_t i) const {
        glm::vec3 n(0.0f);
        if (batch && batch->N.size() > i)
            n = batch->N[i];
        else if (batch && batch->Ng.size() > i)
            n = batch->Ng[i];
        n = xform_normal(to_world, n);
        const float l = glm::length(n);
        return l > 0.0f ? n / l : glm::vec3(0.0f);
    }

    /// Radius of point i's micropolygon (world units, camera space lengths):
    /// sqrt(area / pi) of ShadingBatch::dicing_area or |dPdu x dPdv| du dv.
    float micro_radius(std::size_t i) const {
        if (!batch) return 0.0f;
        float area = 0.0f;
        if (batch->dicing_area.size() > i) {
            area = batch->dicing_area[i];
        } else if (batch->dPdu.size() > i && batch->dPdv.size() > i &&
                   batch->du.size() > i && batch->dv.size() > i) {
            area = glm::length(glm::cross(batch->dPdu[i], batch->dPdv[i])) *
                   std::abs(batch->du[i] * batch->dv[i]);
        }
        const float r = std::sqrt(std::max(0.0f, area) / static_cast<float>(kPi));
        return std::isfinite(r) ? r : 0.0f;
    }

    /// A point of the disk of `radius` about the origin in the plane of b
    /// (samplebase jitter of ray k of point hash h).
    static glm::vec3 disk(const Basis& b, uint64_t h, int k, float radius) {
        if (!(radius > 0.0f)) return glm::vec3(0.0f);
        const uint64_t hk = splitmix64(h ^ (0xA24BAED4963EE407ull + 2 * k));
        const double r = radius * std::sqrt(unit_double(hk));
        const double phi = 2.0 * kPi * unit_double(splitmix64(hk));
        return float(r * std::cos(phi)) * b.t1 + float(r * std::sin(phi)) * b.t2;
    }

    /// Calls services.trace and checks what it returned.
    void trace(RayQuery& q) const {
        const std::size_t count = q.rays.size();
        q.hit.clear();
        q.length.clear();
        q.values.clear();
        if (count == 0) {
            q.values.resize(q.outputs.size());
            return;
        }
        f.ctx->services.trace(q);
        f.ctx->rays += count;
        q.hit.resize(count, 0);
        q.length.resize(count, std::numeric_limits<float>::infinity());
        q.values.resize(q.outputs.size());
        for (std::size_t k = 0; k < q.outputs.size(); ++k) {
            q.values[k].resize(count * q.output_floats[k], 0.0f);
            for (float& v : q.values[k])
                if (!std::isfinite(v)) v = 0.0f;
        }
    }
};

/// Environment lookups (colour, world directions) of map `file`, each
/// filtered over the ray's footprint: a cone `spread` radians wide (the
/// angle between neighbouring rays of the point).
void environment_colors(Frame& f, const BoundOp& b, const std::string& file,
                        const std::vector<glm::vec3>& dirs, std::vector<glm::vec3>& out,
                        float spread) {
    out.assign(dirs.size(), glm::vec3(0.0f));
    if (file.empty() || dirs.empty()) return;
    TextureServices* lib = f.ctx->services.textures();
    std::vector<float> values(dirs.size() * 3, 0.0f);
    std::vector<uint8_t> all(dirs.size(), 1);
    std::string error;
    TextureOptions o;
    // Two directions across the footprint, perpendicular to each ray.
    std::vector<glm::vec3> du(dirs.size()), dv(dirs.size());
    for (std::size_t r = 0; r < dirs.size(); ++r) {
        const glm::vec3 d = dirs[r];
        const glm::vec3 a =
            std::abs(d.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
        glm::vec3 t1 = glm::cross(d, a);
        const float l = glm::length(t1);
        t1 = l > 0.0f ? t1 / l : glm::vec3(0.0f);
        du[r] = t1 * spread;
        dv[r] = glm::cross(d, t1) * spread;
    }
    const bool ok = lib && lib->environment(file, 0, 3, o, dirs.size(), dirs.data(),
                                            spread > 0.0f ? du.data() : nullptr,
                                            spread > 0.0f ? dv.data() : nullptr,
                                            all.data(), values.data(), &error);
    if (!ok)
        f.fail(b,
               "environment \"" + file + "\": " + (lib ? error : "no texture services"));
    for (std::size_t r = 0; r < dirs.size(); ++r) {
        const glm::vec3 c = ld3(&values[r * 3]);
        out[r] = finite3(c) ? c : glm::vec3(0.0f);
    }
}

bool close_rel(const glm::vec3& a, const glm::vec3& b) {
    const glm::vec3 d = glm::abs(a - b);
    const float scale = std::max({std::abs(a.x), std::abs(a.y), std::abs(a.z),
                                  std::abs(b.x), std::abs(b.y), std::abs(b.z)});
    return std::max({d.x, d.y, d.z}) <= 1e-3f * scale;
}

} // namespace

// --- gather ------------------------------------------------------------------------

namespace {

enum GatherOutKind { O_Surface, O_Length, O_Direction, O_Origin, O_EnvColor, O_EnvDir };

/// An output variable of a gather.
struct GatherOut {
    GatherOutKind kind;
    int k; ///< argument index of the variable
    int q; ///< index in the query's outputs (O_Surface)
};

/// A gather's options and outputs, from its token-value pairs.
struct GatherArgs {
    RayParams o;
    std::vector<GatherOut> outs;
    std::vector<std::string> qnames; ///< the query's outputs ("surface:" names)
    std::vector<int> qfloats;        ///< the floats of each of them
};

/// Reads the token-value pairs (from argument 5) at point i0.
GatherArgs read_gather_args(Frame& f, const BoundOp& b, std::size_t i0) {
    const Op& op = *b.op;
    GatherArgs g;
    RayParams& o = g.o;
    o.bias = -1.0f;
    const int nargs = static_cast<int>(op.args.size());
    for (int k = 5; k + 1 < nargs; k += 2) {
        const std::string& name = f.str(b, k, i0);
        const int v = k + 1;
        if ((op.writes >> v) & 1u) {
            const auto colon = name.find(':');
            const std::string group = name.substr(0, colon), key = name.substr(colon + 1);
            if (group == "surface") {
                g.outs.push_back({O_Surface, v, static_cast<int>(g.qnames.size())});
                g.qnames.push_back(key);
                g.qfloats.push_back(f.slot(b, v).nf);
            } else if (name == "ray:length") {
                g.outs.push_back({O_Length, v, -1});
            } else if (name == "ray:direction") {
                g.outs.push_back({O_Direction, v, -1});
            } else if (name == "ray:origin") {
                g.outs.push_back({O_Origin, v, -1});
            } else if (name == "environment:color") {
                g.outs.push_back({O_EnvColor, v, -1});
            } else if (name == "environment:direction") {
                g.outs.push_back({O_EnvDir, v, -1});
            } else {
                f.warn_once(b,
                            "gather output \"" + name + "\" is not supported; ignored");
            }
            continue;
        }
        const Symbol& sym = f.program->symbols[op.args[v]];
        const bool is_str = sym.type.type == ShadingType::String && !sym.type.is_array();
        const float x = is_str || f.slot(b, v).nf != 1 ? 0.0f : *f.ptr(b, v, i0);
        if (name == "distribution" && is_str)
            o.distribution = f.str(b, v, i0);
        else if (name == "label" && is_str)
            o.label = f.str(b, v, i0);
        else if (name == "environmentmap" && is_str)
            o.envmap = f.str(b, v, i0);
        else if (name == "hitsides" && is_str)
            set_hitsides(f, b, f.str(b, v, i0), o);
        else if (name == "bias" && !is_str)
            o.bias = x;
        else if (name == "maxdist" && !is_str)
            o.maxdist = x;
        else if (name == "samplebase" && !is_str)
            o.samplebase = std::max(0.0f, x);
        else if (name == "subset")
            f.warn_once(b, "gather \"subset\" is not supported; every object is traced");
        else
            f.warn_once(b, "unknown gather option \"" + name + "\"; ignored");
    }
    if (!std::isfinite(o.bias)) o.bias = -1.0f;
    if (!std::isfinite(o.maxdist)) o.maxdist = 0.0f;
    if (!std::isfinite(o.samplebase)) o.samplebase = 0.0f;
    return g;
}

/// A query of `kind` from the batch's points: the call's label and hitsides,
/// the ray depth, the shooter (its own triangles close by are skipped).
RayQuery start_query(Frame& f, const RayParams& o, const RayEnv& re, RayKind kind) {
    RayQuery q;
    q.kind = kind;
    q.label = o.label;
    q.hitsides = o.hitsides;
    q.depth = re.depth();
    q.origin = f.ctx->batch ? f.ctx->batch->primitive : nullptr;
    q.self_distance = f.ctx->batch ? f.ctx->batch->self_distance : 0.0f;
    return q;
}

/// One query for every running point (`entry`) and sample: point i's rays
/// start at first[i].
RayQuery gather_query(Frame& f, const BoundOp& b, const GatherArgs& g, RayEnv& re,
                      const std::vector<uint8_t>& entry, int samples, bool env,
                      bool cosine, std::vector<std::size_t>& first) {
    const std::size_t n = f.n;
    const RayParams& o = g.o;
    RayQuery q =
        start_query(f, o, re, env || cosine ? RayKind::Diffuse : RayKind::Specular);
    q.seed = re.query_seed();
    if (!env) {
        q.outputs = g.qnames;
        q.output_floats = g.qfloats;
    }
    const float tfar = re.tfar(o.maxdist);
    float spread = 0.0f;
    for (std::size_t i = 0; i < n; ++i) {
        if (!entry[i]) continue;
        first[i] = q.rays.size();
        const glm::vec3 Pw = xform_point(re.to_world, ld3(f.ptr(b, 1, i)));
        glm::vec3 w = xform_vector(re.to_world, ld3(f.ptr(b, 2, i)));
        const float wl = glm::length(w);
        w = wl > 0.0f && std::isfinite(wl) ? w / wl : re.normal(i);
        if (glm::length(w) == 0.0f) w = glm::vec3(0, 0, 1);
        double angle = *f.ptr(b, 3, i);
        if (!std::isfinite(angle)) angle = 0.0;
        spread = std::max(spread, ray_spread(angle, samples));
        const Basis B = basis_about(w);
        const uint64_t h = re.hash(i);
        const float jitter =
            o.samplebase > 0.0f ? o.samplebase * re.micro_radius(i) : 0.0f;
        for (int s = 0; s < samples; ++s) {
            const glm::vec3 d = cone_direction(B, h, s, samples, angle, cosine);
            const glm::vec3 origin = Pw + RayEnv::disk(B, h, s, jitter) + d * re.offset;
            q.rays.push_back(ShadowRay{origin, d, 0.0f, tfar, re.time(i)});
        }
    }
    q.spread = spread;
    return q;
}

/// Writes the outputs of sample s into the variables of the points of `base`.
void write_gather_outputs(Frame& f, const BoundOp& b, const GatherArgs& g,
                          const RayEnv& re, const RayQuery& q,
                          const std::vector<std::size_t>& first,
                          const std::vector<uint8_t>& base, int s, bool env,
                          const std::vector<glm::vec3>& envc) {
    const std::size_t n = f.n;
    for (const GatherOut& out : g.outs) {
        Slot& sl = f.slot(b, out.k);
        for (std::size_t i = 0; i < n; ++i) {
            if (!base[i]) continue;
            const std::size_t r = first[i] + s;
            const ShadowRay& ray = q.rays[r];
            float* dst = sl.at(i);
            switch (out.kind) {
            case O_Surface:
                // Hits only: a miss leaves the variable as it was.
                if (!env && q.hit[r]) {
                    const int nf = q.output_floats[out.q];
                    std::memcpy(dst, &q.values[out.q][r * nf], sizeof(float) * nf);
                }
                break;
            case O_Length:
                *dst = q.hit[r] ? q.length[r]
                                : (g.o.maxdist > 0.0f ? g.o.maxdist : kMissLength);
                if (!std::isfinite(*dst)) *dst = kMissLength;
                break;
            case O_Direction:
            case O_EnvDir:
                st3(dst, xform_vector(re.to_current, ray.direction));
                break;
            case O_Origin:
                st3(dst, xform_point(re.to_current, ray.origin));
                break;
            case O_EnvColor:
                st3(dst, env && !envc.empty() ? envc[r] : glm::vec3(0.0f));
                break;
            }
        }
    }
}

} // namespace

void run_gather(Frame& f, const BoundOp& b, int hit_end, int miss_end) {
    const std::size_t n = f.n;
    const std::size_t i0 = f.first_active();
    if (i0 >= n) return;
    const std::string cat = f.str(b, 0, i0);
    const int samples = std::clamp(static_cast<int>(*f.ptr(b, 4, i0)), 0, 4096);
    const bool env = cat == "environment";
    if (!env && !cat.empty() && cat != "illuminance")
        f.warn_once(b, "gather category \"" + cat +
                           "\" is not supported; traced as \"illuminance\"");

    const GatherArgs g = read_gather_args(f, b, i0);
    const RayParams& o = g.o;
    const bool cosine = o.distribution == "cosine";
    if (!o.distribution.empty() && !cosine && o.distribution != "uniform")
        f.warn_once(b, "gather distribution \"" + o.distribution +
                           "\" is not supported; uniform");
    RayEnv re(f, b, o);

    std::vector<uint8_t>& entry = f.push_mask();
    entry = f.mask;
    if (samples == 0) {
        f.pop_mask();
        return;
    }

    std::vector<std::size_t> first(n, 0);
    RayQuery q = gather_query(f, b, g, re, entry, samples, env, cosine, first);
    re.trace(q);

    // Environment lookups of every ray (category "environment").
    std::vector<glm::vec3> envc;
    bool need_env = false;
    for (const GatherOut& out : g.outs) need_env = need_env || out.kind == O_EnvColor;
    if (env && need_env) {
        std::vector<glm::vec3> dirs(q.rays.size());
        for (std::size_t r = 0; r < dirs.size(); ++r) dirs[r] = q.rays[r].direction;
        environment_colors(f, b, o.envmap, dirs, envc, q.spread);
    }

    std::vector<uint8_t>& base = f.push_mask();
    for (int s = 0; s < samples; ++s) {
        std::size_t cnt = 0;
        for (std::size_t i = 0; i < n; ++i) {
            base[i] = entry[i] && f.stop[i] == 0;
            cnt += base[i];
        }
        if (cnt == 0) break;
        write_gather_outputs(f, b, g, re, q, first, base, s, env, envc);
        // Hits, then misses.
        for (int part = 0; part < 2; ++part) {
            const int begin = part == 0 ? b.index + 1 : hit_end;
            const int end = part == 0 ? hit_end : miss_end;
            std::size_t on = 0;
            for (std::size_t i = 0; i < n; ++i) {
                const bool run = base[i] && f.stop[i] == 0 &&
                                 (q.hit[first[i] + s] != 0) == (part == 0);
                f.mask[i] = run;
                on += run;
            }
            f.active = on;
            if (on > 0 && end > begin) f.run(begin, end);
        }
    }
    f.restore_mask(entry);
    f.pop_mask();
    f.pop_mask();
}

namespace {

// --- trace and environment("raytrace") -----------------------------------------------

/// Mean hit Ci of `o.samples` Specular rays per running point from P along
/// dir (camera space; P null: the surface's P), into out (per point).
void specular_rays(Frame& f, const BoundOp& b, const RayParams& o, const Slot* P,
                   const Slot& dir, std::vector<glm::vec3>& out) {
    const std::size_t n = f.n;
    RayEnv re(f, b, o);
    out.assign(n, glm::vec3(0.0f));
    const int* g = f.bound->globals;
    const Slot* Pg = g[G_P] >= 0 ? &f.slots[g[G_P]] : nullptr;
    const int samples = o.cone > 0.0f ? o.samples : 1;
    RayQuery q = start_query(f, o, re, RayKind::Specular);
    q.seed = re.query_seed();
    q.outputs = {"Ci"};
    q.output_floats = {3};
    q.spread = samples > 1 ? ray_spread(0.5 * o.cone, samples) : 0.0f;
    const float tfar = re.tfar(o.maxdist);
    std::vector<std::size_t> first(n + 1, 0), count(n, 0);
    f.each(true, [&](std::size_t i) {
        glm::vec3 Pc;
        if (P)
            Pc = ld3(P->at(i));
        else if (Pg)
            Pc = ld3(Pg->at(i));
        else
            Pc = re.batch && re.batch->P.size() > i ? re.batch->P[i] : glm::vec3(0.0f);
        const glm::vec3 Pw = xform_point(re.to_world, Pc);
        glm::vec3 w = xform_vector(re.to_world, ld3(dir.at(i)));
        const float wl = glm::length(w);
        first[i] = q.rays.size();
        if (!(wl > 0.0f) || !std::isfinite(wl)) return;
        w /= wl;
        const Basis B = basis_about(w);
        const uint64_t h = re.hash(i);
        for (int s = 0; s < samples; ++s) {
            const glm::vec3 d =
                samples > 1 ? cone_direction(B, h, s, samples, 0.5 * o.cone, false) : w;
            q.rays.push_back(ShadowRay{Pw + d * re.offset, d, 0.0f, tfar, re.time(i)});
        }
        count[i] = samples;
    });
    re.trace(q);
    f.each(true, [&](std::size_t i) {
        glm::vec3 sum(0.0f);
        for (std::size_t r = first[i]; r < first[i] + count[i]; ++r)
            if (q.hit[r]) sum += ld3(&q.values[0][r * 3]);
        out[i] = count[i] > 0 ? sum / static_cast<float>(count[i]) : glm::vec3(0.0f);
    });
}

/// trace(P, dir, options)
void op_trace(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    const RayParams o = ray_params(f, b, 3);
    std::vector<glm::vec3> out;
    specular_rays(f, b, o, &f.slot(b, 1), f.slot(b, 2), out);
    f.each(d.varying, [&](std::size_t i) { st3(d.at(i), out[i]); });
}

bool bind_trace(const BindInfo& in, BoundOp& b, std::string&) {
    const int n = in.nargs();
    if (n < 3 || (n - 3) % 2 != 0 || !in.is_color(0) || !in.is_ptype(1) ||
        !in.is_ptype(2))
        return false;
    for (int k = 3; k < n; k += 2)
        if (!in.is_string(k)) return false;
    b.fn = op_trace;
    return true;
}

// --- occlusion and indirectdiffuse ---------------------------------------------------

/// occlusion(P, N, samples, options) (float result) and indirectdiffuse(P,
/// N, samples, options) (colour result).
template <bool Indirect>
void op_hemisphere(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    const std::size_t n = f.n;
    const RayParams o = ray_params(f, b, 4);
    const bool cosine = Indirect || o.distribution != "uniform";
    if (!Indirect && !o.distribution.empty() && o.distribution != "uniform" &&
        o.distribution != "cosine")
        f.warn_once(b, "occlusion distribution \"" + o.distribution +
                           "\" is not supported; cosine");
    RayEnv re(f, b, o);
    const bool adaptive = o.adaptive != 0.0f;
    const float tfar = re.tfar(o.maxdist);
    const bool want_env = !o.envmap.empty() && (Indirect || o.out_envcolor >= 0);

    struct PointState {
        int samples = 0;
        bool valid = false;
        bool done = false;
        glm::vec3 Pw{0.0f};
        Basis B;
        uint64_t h = 0;
        float jitter = 0.0f;
        int traced = 0, blocked = 0;
        glm::vec3 hit_sum{0.0f}, env_sum{0.0f}, open_dir{0.0f};
    };
    std::vector<PointState> ps(n);
    int max_samples = 1;
    f.each(true, [&](std::size_t i) {
        PointState& p = ps[i];
        const float sv = *f.ptr(b, 3, i);
        p.samples = std::isfinite(sv) ? std::clamp(static_cast<int>(sv), 1, 4096) : 1;
        max_samples = std::max(max_samples, p.samples);
        p.Pw = xform_point(re.to_world, ld3(f.ptr(b, 1, i)));
        glm::vec3 w = xform_normal(re.to_world, ld3(f.ptr(b, 2, i)));
        const float wl = glm::length(w);
        if (!(wl > 0.0f) || !std::isfinite(wl)) return;
        p.valid = true;
        p.B = basis_about(w / wl);
        p.h = re.hash(i);
        p.jitter = o.samplebase > 0.0f ? o.samplebase * re.micro_radius(i) : 0.0f;
    });

    // Pass 0: every 4th stratum of adaptive points with >= 16 samples (and
    // every stratum of the others); pass 1: the rest where still needed.
    for (int pass = 0; pass < 2; ++pass) {
        RayQuery q = start_query(f, o, re, RayKind::Diffuse);
        q.seed = splitmix64(re.query_seed() + pass);
        q.spread = ray_spread(o.coneangle, max_samples);
        if (Indirect) {
            q.outputs = {"Ci"};
            q.output_floats = {3};
        } else {
            q.need_length = false; // occlusion: hit or not
        }
        std::vector<std::size_t> owner;
        f.each(true, [&](std::size_t i) {
            PointState& p = ps[i];
            if (!p.valid || p.done) return;
            const bool split = adaptive && p.samples >= 16;
            for (int k = 0; k < p.samples; ++k) {
                const bool first_pass = !split || k % 4 == 0;
                if (first_pass != (pass == 0)) continue;
                const glm::vec3 dir =
                    cone_direction(p.B, p.h, k, p.samples, o.coneangle, cosine);
                const glm::vec3 origin =
                    p.Pw + RayEnv::disk(p.B, p.h, k, p.jitter) + p.B.w * re.offset;
                q.rays.push_back(ShadowRay{origin, dir, 0.0f, tfar, re.time(i)});
                owner.push_back(i);
            }
        });
        if (q.rays.empty()) break;
        re.trace(q);
        std::vector<glm::vec3> dirs, envc;
        std::vector<std::size_t> open_rays;
        if (want_env) {
            for (std::size_t r = 0; r < q.rays.size(); ++r)
                if (!q.hit[r]) {
                    open_rays.push_back(r);
                    dirs.push_back(q.rays[r].direction);
                }
            environment_colors(f, b, o.envmap, dirs, envc, q.spread);
        }
        std::vector<glm::vec3> env_of(q.rays.size(), glm::vec3(0.0f));
        for (std::size_t j = 0; j < open_rays.size(); ++j) env_of[open_rays[j]] = envc[j];
        // Per point: accumulate; after pass 0, decide whether it is done.
        std::vector<int> all_hit(n, 1), all_miss(n, 1), uniform_vals(n, 1);
        std::vector<glm::vec3> ref(n, glm::vec3(0.0f));
        std::vector<int> seen(n, 0);
        for (std::size_t r = 0; r < q.rays.size(); ++r) {
            const std::size_t i = owner[r];
            PointState& p = ps[i];
            ++p.traced;
            glm::vec3 value;
            if (q.hit[r]) {
                ++p.blocked;
                all_miss[i] = 0;
                value = Indirect ? ld3(&q.values[0][r * 3]) : glm::vec3(1.0f);
                p.hit_sum += Indirect ? value : glm::vec3(0.0f);
            } else {
                all_hit[i] = 0;
                value = env_of[r];
                p.env_sum += value;
                p.open_dir += q.rays[r].direction;
            }
            if (seen[i]++ == 0)
                ref[i] = value;
            else if (!close_rel(ref[i], value))
                uniform_vals[i] = 0;
        }
        if (pass == 0)
            for (std::size_t i = 0; i < n; ++i)
                if (seen[i]) {
                    PointState& p = ps[i];
                    const bool split = adaptive && p.samples >= 16;
                    p.done = !split || ((all_hit[i] || all_miss[i]) && uniform_vals[i]);
                }
    }

    // Results.
    Slot* ec = o.out_envcolor >= 0 ? &f.slot(b, o.out_envcolor) : nullptr;
    Slot* ed = o.out_envdir >= 0 ? &f.slot(b, o.out_envdir) : nullptr;
    Slot* oc = o.out_occlusion >= 0 ? &f.slot(b, o.out_occlusion) : nullptr;
    f.each(true, [&](std::size_t i) {
        const PointState& p = ps[i];
        const float inv = p.traced > 0 ? 1.0f / static_cast<float>(p.traced) : 0.0f;
        const float occl = static_cast<float>(p.blocked) * inv;
        const glm::vec3 envc = p.env_sum * inv;
        glm::vec3 dir(0.0f);
        const float dl = glm::length(p.open_dir);
        if (dl > 0.0f) dir = glm::normalize(xform_vector(re.to_current, p.open_dir / dl));
        if (Indirect) {
            if (d.varying || i == f.first_active())
                st3(d.at(i), (p.hit_sum + p.env_sum) * inv);
        } else if (d.varying || i == f.first_active()) {
            *d.at(i) = occl;
        }
        if (ec && ec->nf == 3 && (ec->varying || i == f.first_active()))
            st3(ec->at(i), envc);
        if (ed && ed->nf == 3 && (ed->varying || i == f.first_active()))
            st3(ed->at(i), dir);
        if (oc && oc->nf == 1 && (oc->varying || i == f.first_active()))
            *oc->at(i) = occl;
    });
}

bool bind_hemisphere(const BindInfo& in, BoundOp& b, std::string& why) {
    const int n = in.nargs();
    const bool indirect = in.op.name == "indirectdiffuse";
    if (n < 4 || (n - 4) % 2 != 0 || !(indirect ? in.is_color(0) : in.is_float(0)) ||
        !in.is_ptype(1) || !in.is_ptype(2) || !in.is_float(3))
        return false;
    for (int k = 4; k < n; k += 2) {
        if (!in.is_string(k)) return false;
        if (in.writes(k + 1)) {
            const Symbol& name = in.sym(k);
            const std::string t = name.strings.empty() ? "" : name.strings[0];
            const bool ok = (t == "environmentcolor" && in.is_color(k + 1)) ||
                            (t == "environmentdir" && in.is_ptype(k + 1)) ||
                            (t == "occlusion" && in.is_float(k + 1));
            if (!ok) {
                why = "output \"" + t + "\" of the wrong type or not an output";
                return false;
            }
        }
    }
    b.fn = indirect ? op_hemisphere<true> : op_hemisphere<false>;
    return true;
}

// --- ray-traced shadows ----------------------------------------------------------------

/// Transmission rays for one frame (shadow "raytrace", transmission()).
struct Tracer {
    RayEnv re;

    Tracer(Frame& fr, const BoundOp& b, const RayParams& o) : re(fr, b, o) {}

    /// The single transmission ray for point i (world space); false when
    /// there is no direction (then the point is unshadowed).
    bool single_ray(std::size_t i, const glm::vec3& from_c, const glm::vec3& to_or_dir_c,
                    bool infinite, ShadowRay& out) const {
        const glm::vec3 from = xform_point(re.to_world, from_c);
        glm::vec3 dir = infinite ? xform_vector(re.to_world, to_or_dir_c)
                                 : xform_point(re.to_world, to_or_dir_c) - from;
        const float dl = glm::length(dir);
        if (!(dl > 0.0f) || !std::isfinite(dl)) return false;
        dir /= dl;
        glm::vec3 nrm = re.normal(i);
        if (glm::dot(nrm, dir) < 0.0f) nrm = -nrm;
        const glm::vec3 origin = from + nrm * re.offset;
        float len = std::numeric_limits<float>::infinity();
        if (!infinite) {
            dir = xform_point(re.to_world, to_or_dir_c) - origin;
            len = glm::length(dir);
            if (!(len > 0.0f)) return false;
            dir /= len;
        }
        out = ShadowRay{origin, dir, 0.0f, infinite ? len : len * (1.0f - 1e-4f),
                        re.time(i)};
        return true;
    }

    /// Appends the rays of point i to `out` (none: unshadowed).
    void rays(std::size_t i, const glm::vec3& from_c, const glm::vec3& to_or_dir_c,
              bool infinite, int samples, float cone, std::vector<ShadowRay>& out) const {
        ShadowRay centre;
        if (!single_ray(i, from_c, to_or_dir_c, infinite, centre)) return;
        if (samples <= 1 || cone <= 0.0f) {
            out.push_back(centre);
            return;
        }
        // Stratified directions in the cone: equal-area rings, golden-angle turns.
        const Basis B = basis_about(centre.direction);
        const uint64_t h = re.hash(i);
        for (int k = 0; k < samples; ++k) {
            const glm::vec3 d = cone_direction(B, h, k, samples, 0.5 * cone, false);
            out.push_back(ShadowRay{centre.origin, d, 0.0f, centre.tfar, centre.time});
        }
    }

    /// Mean transmittance of each point's rays ([first[i], first[i+1])).
    void transmit(const std::vector<ShadowRay>& list, std::vector<glm::vec3>& out) const {
        out.assign(list.size(), glm::vec3(1.0f));
        if (list.empty()) return;
        re.f.ctx->services.transmit(list.data(), list.size(), out.data(), re.depth());
        re.f.ctx->rays += list.size();
        for (glm::vec3& c : out)
            c = finite3(c) ? glm::clamp(c, 0.0f, 1.0f) : glm::vec3(1.0f);
    }
};

/// shadow(name, channel, P, options): 1 - transmittance (per channel for a
/// colour, the channels' mean for a float).
void op_shadow(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    const std::string& name = f.str(b, 1, f.first_active());
    const int nc = d.nf;
    if (name.empty()) {
        // shadow("") is 0, quietly (as texture("")): library lights call it
        // with an empty default map name.
        f.each(d.varying, [&](std::size_t i) { std::fill(d.at(i), d.at(i) + nc, 0.0f); });
        return;
    }
    if (name != "raytrace") {
        shadow_map_lookup(f, b);
        return;
    }
    // The area form traces from its first point.
    const RayParams o = ray_params(f, b, 3 + (b.ia == 4 ? 4 : 1));
    Tracer t(f, b, o);
    const int* g = f.bound->globals;
    const Slot* Ls = g[G_L] >= 0 ? &f.slots[g[G_L]] : nullptr;
    // Every point's rays in one stream.
    std::vector<ShadowRay> list;
    std::vector<std::size_t> first(f.n + 1, 0), last(f.n, 0);
    std::vector<std::size_t> points;
    f.each(d.varying, [&](std::size_t i) {
        const glm::vec3 p = ld3(f.ptr(b, 3, i));
        first[i] = list.size();
        if (f.is_light) {
            const glm::vec3 L = Ls ? ld3(Ls->at(i)) : f.light_L[i];
            if (f.solar)
                t.rays(i, p, -L, true, o.samples, o.cone, list);
            else
                t.rays(i, p, p - L, false, o.samples, o.cone, list);
        } else if (f.current_light >= 0) {
            // Towards the light of the illuminance iteration: L (or the
            // light's own L reversed when the shader never names L).
            const LightState& ls = f.ctx->light_states[f.current_light];
            const glm::vec3 L = Ls ? ld3(Ls->at(i)) : -ls.L[i];
            t.rays(i, p, p + L, false, o.samples, o.cone, list);
        }
        last[i] = list.size();
        points.push_back(i);
    });
    std::vector<glm::vec3> through;
    t.transmit(list, through);
    for (std::size_t i : points) {
        glm::vec3 sum(0.0f);
        const std::size_t count = last[i] - first[i];
        for (std::size_t k = first[i]; k < last[i]; ++k) sum += through[k];
        const glm::vec3 shadow = count > 0
                                     ? glm::vec3(1.0f) - sum / static_cast<float>(count)
                                     : glm::vec3(0.0f);
        if (nc == 3)
            st3(d.at(i), shadow);
        else
            std::fill(d.at(i), d.at(i) + nc, (shadow.x + shadow.y + shadow.z) / 3.0f);
    }
}

bool bind_shadow(const BindInfo& in, BoundOp& b, std::string&) {
    const int n = in.nargs();
    if (n < 4 || !(in.is_float(0) || in.is_color(0)) || !in.is_string(1) ||
        !in.is_float(2) || !in.is_ptype(3))
        return false;
    // shadow(map, P1, P2, P3, P4): the area form (depth maps).
    b.ia = n >= 7 && in.is_ptype(4) && in.is_ptype(5) && in.is_ptype(6) ? 4 : 1;
    if ((n - 3 - b.ia) % 2 != 0) return false;
    b.fn = op_shadow;
    return true;
}

/// transmission(Psrc, Pdst, options): the mean colour transmittance.
void op_transmission(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    const RayParams o = ray_params(f, b, 3);
    Tracer t(f, b, o);
    std::vector<ShadowRay> list;
    std::vector<std::size_t> first(f.n, 0), last(f.n, 0);
    f.each(d.varying, [&](std::size_t i) {
        first[i] = list.size();
        t.rays(i, ld3(f.ptr(b, 1, i)), ld3(f.ptr(b, 2, i)), false, o.samples, o.cone,
               list);
        last[i] = list.size();
    });
    std::vector<glm::vec3> through;
    t.transmit(list, through);
    f.each(d.varying, [&](std::size_t i) {
        glm::vec3 sum(0.0f);
        for (std::size_t k = first[i]; k < last[i]; ++k) sum += through[k];
        const std::size_t count = last[i] - first[i];
        st3(d.at(i), count > 0 ? sum / static_cast<float>(count) : glm::vec3(1.0f));
    });
}

bool bind_transmission(const BindInfo& in, BoundOp& b, std::string&) {
    const int n = in.nargs();
    if (n < 3 || (n - 3) % 2 != 0 || !in.is_color(0) || !in.is_ptype(1) ||
        !in.is_ptype(2))
        return false;
    b.fn = op_transmission;
    return true;
}

} // namespace

/// environment("raytrace"[ch], dir, options) (engine_texture.cpp routes it
/// here): Specular rays from the surface P along dir, the hit's Ci.
void environment_raytrace(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    const RayParams o = ray_params(f, b, 4);
    const int channel =
        std::clamp(static_cast<int>(*f.ptr(b, 2, f.first_active())), 0, 2);
    std::vector<glm::vec3> out;
    specular_rays(f, b, o, nullptr, f.slot(b, 3), out);
    f.each(d.varying, [&](std::size_t i) {
        if (d.nf == 3)
            st3(d.at(i), out[i]);
        else
            *d.at(i) = out[i][channel];
    });
}

void register_raytrace(BinderTable& t) {
    t["shadow"] = bind_shadow;
    t["transmission"] = bind_transmission;
    t["occlusion"] = bind_hemisphere;
    t["indirectdiffuse"] = bind_hemisphere;
    t["trace"] = bind_trace;
}

} // namespace sss::detail
