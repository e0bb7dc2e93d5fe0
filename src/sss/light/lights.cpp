// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file lights.cpp
/// Light shaders resolved to world space, and the irradiance they give.
///
/// Supported light shaders (RenderMan's standard shaders; parameters in the
/// light's shader space, i.e. the CTM at the LightSource call):
///
///   ambientlight  "intensity" 1  "lightcolor" [1 1 1]
///       Adds Cl = intensity * lightcolor whatever the normal.
///   distantlight  "intensity" 1  "lightcolor" [1 1 1]  "from" [0 0 0]  "to" [0 0 1]
///       Light travels along to - from; Cl = intensity * lightcolor, no falloff.
///   pointlight    "intensity" 1  "lightcolor" [1 1 1]  "from" [0 0 0]
///       Cl = intensity * lightcolor / d^2 (d: distance to "from").
///   spotlight     "intensity" 1  "lightcolor" [1 1 1]  "from" [0 0 0]  "to" [0 0 1]
///                 "coneangle" radians(30)  "conedeltaangle" radians(5)
///                 "beamdistribution" 2
///       Cl = intensity * lightcolor * cosangle^beamdistribution / d^2
///            * smoothstep(cos(coneangle), cos(coneangle - conedeltaangle), cosangle)
///       with cosangle the cosine between the axis (to - from) and the
///       direction from "from" to the shaded point. The beam term is 0 where
///       cosangle < 0 (only reachable with a cone wider than 90 degrees).
///
/// Every light but ambientlight contributes Cl * max(0, N.L) (L: unit vector
/// towards the light's centre). A point light exactly at the shaded point
/// contributes nothing. "from" and "to" must differ for distant and spot
/// lights, and every number must be finite: otherwise ValueError.
///
/// Shadows:
///   - `"string shadowname" "raytrace"` on distantlight, pointlight or
///     spotlight turns ray-traced shadows on.
///   - distantlight_rts, pointlight_rts and spotlight_rts (as in the
///     RenderMan application notes) take the same parameters as their
///     standard shader and always cast ray-traced shadows.
///   - Any other non-empty shadowname is a depth map (a zfile or shadow
///     map, read by resolve_lights' loader), and so are the maps of PRMan's
///     shadowspot, shadowdistant ("shadowname") and shadowpoint ("sfpx"
///     "sfnx" "sfpy" "sfny" "sfpz" "sfnz": the map of the world axis nearest
///     to the direction from the light to the point; an empty name: none),
///     which take the parameters of spotlight, distantlight and pointlight.
///     The shadow term is 1 - shadow_fraction() (shadow_map.h) at the point,
///     one texel's footprint, with "samples" (default 1; the shadow* lights
///     16), "blur" (0), "width" (1) and "bias" (< 0, the default: the
///     scene's, scene_shadow_bias()); no rays are traced.
///   - For ray-traced shadows "blur" and "bias" are not read; the baker
///     chooses the ray origin offset.
///
/// Soft shadows. Lights with shadows also read:
///   "float samples"  (default 1, whole number in [1, 1024]): shadow rays per
///                    shaded point;
///   "float radius"   (point and spot, default 0): the light is a sphere of
///                    this radius in shader space, scaled to world space by
///                    the cube root of |det| of the transform's 3x3 part
///                    (exact for uniform scales);
///   "float angle"    (distant, degrees, default 0, below 180): the light is
///                    a disk of this angular diameter seen from everywhere.
/// With samples > 1 and a non-zero size, the shadow term is the fraction of
/// `samples` rays that reach their sample point on the emitter: points on the
/// disk of the sphere's radius facing the shaded point (point, spot), or
/// directions uniform in solid angle in the cone of half the angular diameter
/// (distant). The samples are stratified (equal-area rings, golden-angle
/// spiral), jittered and rotated by a hash of the point's seed and the light's
/// index, so they are deterministic and independent of threads. Otherwise one
/// ray goes to the centre (a hard shadow). Cl and N.L always come from the
/// centre: the size only softens shadows; the falloff stays the point light's.
///
/// Shadow rays start at p + n * ray_offset (n faces the light, since lights
/// with N.L <= 0 are skipped without a ray) with tnear 0, and end just short
/// of the sample point (1e-4 relative) or at infinity for distant lights.
///
/// light_samples() is the same evaluation light by light (Cl and L apart, for
/// specular()), with the same shadow rays.
///
/// Unknown shader names (including area light shaders) warn
/// "file:line: unknown light shader 'x', ignored" and resolve to an
/// ambient light of colour 0.

#include "sss/light/lights.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>
#include <glm/vec4.hpp>

#include "sss/util/error.h"
#include "sss/util/hash.h"
#include "sss/util/math.h"

namespace sss {

namespace {

constexpr int kMaxSamples = 1024;
/// Shadow rays stop this fraction short of the light so that geometry at
/// the light itself (a bulb, a light on a wall) does not shadow everything.
constexpr double kShadowEndFraction = 1.0 - 1e-4;
/// Points per block in irradiance_batch: bounds the scratch memory.
constexpr std::size_t kBatchBlock = 256;

// ---------------------------------------------------------------------------
// Resolving light shaders

bool finite3(const glm::dvec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

/// Shader-space point to world space (projective transforms are divided out).
glm::dvec3 to_world(const Matrix4& m, const glm::dvec3& p) {
    const glm::dvec4 q = m * glm::dvec4(p, 1.0);
    if (q.w != 0.0 && q.w != 1.0) return glm::dvec3(q) / q.w;
    return glm::dvec3(q);
}

/// Length scale of a transform: cube root of its 3x3 part's |determinant|.
double length_scale(const Matrix4& m) {
    return std::cbrt(std::abs(glm::determinant(glm::dmat3(m))));
}

glm::dvec3 vec3_param(const ParamList& params, const char* name,
                      const glm::dvec3& fallback) {
    const glm::dvec3 v = params.get_vec3(name, fallback);
    if (!finite3(v)) throw ValueError(std::string("\"") + name + "\" is not finite");
    return v;
}

double float_param(const ParamList& params, const char* name, double fallback) {
    const double v = params.get_float(name, fallback);
    if (!std::isfinite(v))
        throw ValueError(std::string("\"") + name + "\" is not finite");
    return v;
}

/// The unit direction from "from" to "to", both in world space.
glm::dvec3 axis_of(const ShaderRef& shader, const glm::dvec3& from) {
    const glm::dvec3 to = to_world(shader.shader_to_world,
                                   vec3_param(shader.params, "to", glm::dvec3(0, 0, 1)));
    const glm::dvec3 d = to - from;
    const double len = glm::length(d);
    if (!(len > 0.0) || !std::isfinite(len))
        throw ValueError("\"from\" and \"to\" give no direction");
    return d / len;
}

/// Fills `light` from the shader call; throws ValueError (without location)
/// on bad values. Returns false for an unknown shader.
bool resolve_one(const ShaderRef& shader, const ShadowMapLoader& loader, float scene_bias,
                 Light& light) {
    std::string base = shader.name;
    const bool rts = base.size() > 4 && base.ends_with("_rts");
    if (rts) base.resize(base.size() - 4);
    // PRMan's shadow-map lights: the standard ones with maps.
    const bool mapped = !rts && (base == "shadowspot" || base == "shadowdistant" ||
                                 base == "shadowpoint");
    if (mapped)
        base = base == "shadowspot"      ? "spotlight"
               : base == "shadowdistant" ? "distantlight"
                                         : "pointlight";

    if (base == "ambientlight" && !rts) {
        light.kind = Light::Kind::Ambient;
    } else if (base == "distantlight") {
        light.kind = Light::Kind::Distant;
    } else if (base == "pointlight") {
        light.kind = Light::Kind::Point;
    } else if (base == "spotlight") {
        light.kind = Light::Kind::Spot;
    } else {
        return false;
    }

    const ParamList& params = shader.params;
    const Matrix4& m = shader.shader_to_world;
    light.color = float_param(params, "intensity", 1.0) *
                  vec3_param(params, "lightcolor", glm::dvec3(1.0));
    if (light.kind == Light::Kind::Ambient) return true;

    light.from = to_world(m, vec3_param(params, "from", glm::dvec3(0.0)));
    if (!finite3(light.from)) throw ValueError("\"from\" is not finite in world space");
    if (light.kind == Light::Kind::Distant || light.kind == Light::Kind::Spot)
        light.direction = axis_of(shader, light.from);
    if (light.kind == Light::Kind::Spot) {
        light.cone_angle = float_param(params, "coneangle", 30.0 * kPi / 180.0);
        light.cone_delta = float_param(params, "conedeltaangle", 5.0 * kPi / 180.0);
        light.beam_distribution = float_param(params, "beamdistribution", 2.0);
    }

    std::vector<std::string> maps;
    if (rts) {
        light.shadows = true;
    } else if (mapped && light.kind == Light::Kind::Point) {
        for (const char* name : {"sfpx", "sfnx", "sfpy", "sfny", "sfpz", "sfnz"})
            maps.push_back(params.get_string(name, ""));
    } else {
        const std::string map = params.get_string("shadowname", "");
        if (map == "raytrace")
            light.shadows = true;
        else if (!map.empty())
            maps.push_back(map);
    }
    const auto named = std::find_if(maps.begin(), maps.end(),
                                    [](const std::string& m) { return !m.empty(); });
    if (named != maps.end()) {
        if (!loader) throw ValueError("shadow map \"" + *named + "\" but no map reader");
        for (const std::string& map : maps)
            light.shadow_maps.push_back(map.empty() ? nullptr : loader(map));
        ShadowLookup& look = light.shadow_lookup;
        look.samples = params.get_int("samples", mapped ? 16 : 1);
        look.sblur = look.tblur = static_cast<float>(float_param(params, "blur", 0.0));
        look.swidth = look.twidth = static_cast<float>(float_param(params, "width", 1.0));
        const double bias = float_param(params, "bias", -1.0);
        look.bias = bias >= 0.0 ? static_cast<float>(bias) : scene_bias;
    }

    const int samples = params.get_int("samples", mapped ? 16 : 1);
    if (samples < 1 || samples > kMaxSamples)
        throw ValueError("\"samples\" must be in [1, " + std::to_string(kMaxSamples) +
                         "], got " + std::to_string(samples));
    light.samples = samples;
    if (light.kind == Light::Kind::Distant) {
        const double angle = float_param(params, "angle", 0.0);
        if (angle < 0.0 || angle >= 180.0)
            throw ValueError("\"angle\" must be in [0, 180) degrees, got " +
                             std::to_string(angle));
        light.size = 0.5 * angle * kPi / 180.0;
    } else {
        const double radius = float_param(params, "radius", 0.0);
        if (radius < 0.0)
            throw ValueError("\"radius\" must not be negative, got " +
                             std::to_string(radius));
        light.size = radius * length_scale(m);
        if (!std::isfinite(light.size))
            throw ValueError("\"radius\" is not finite in world space");
    }
    return true;
}

// ---------------------------------------------------------------------------
// Irradiance

/// A light prepared for evaluation: per-light constants computed once.
struct PreparedLight {
    const Light* light = nullptr;
    int index = 0;            ///< in the lights vector: part of the sample hash
    glm::dvec3 axis{0, 0, 1}; ///< unit direction of travel (distant, spot)
    double cos_outer = 0.0;   ///< spot: cos(coneangle)
    double cos_inner = 0.0;   ///< spot: cos(coneangle - conedeltaangle)
    bool traced = false;      ///< shadows on and a tracer given
    int rays = 1;             ///< shadow rays per point when traced
    bool dark = false;        ///< colour 0: contributes nothing, traces nothing
};

PreparedLight prepare(const std::vector<Light>& lights, int index,
                      const RayTracer* tracer) {
    if (index < 0 || static_cast<std::size_t>(index) >= lights.size())
        throw ValueError("irradiance: light index " + std::to_string(index) +
                         " out of range (" + std::to_string(lights.size()) + " lights)");
    const Light& l = lights[index];
    PreparedLight pl;
    pl.light = &l;
    pl.index = index;
    pl.dark = l.color == glm::dvec3(0.0);
    if (l.kind == Light::Kind::Distant || l.kind == Light::Kind::Spot) {
        const double len = glm::length(l.direction);
        if (!(len > 0.0) || !std::isfinite(len))
            throw ValueError("irradiance: light '" + l.name + "' has no direction");
        pl.axis = l.direction / len;
    }
    if (l.kind == Light::Kind::Spot) {
        pl.cos_outer = std::cos(l.cone_angle);
        pl.cos_inner = std::cos(l.cone_angle - l.cone_delta);
    }
    pl.traced = l.shadows && tracer != nullptr && l.kind != Light::Kind::Ambient;
    pl.rays = (l.samples > 1 && l.size > 0.0) ? l.samples : 1;
    return pl;
}

/// RenderMan's smoothstep: 0 below e0, 1 from e1 up, Hermite in between.
double smoothstep(double e0, double e1, double x) {
    if (x < e0) return 0.0;
    if (x >= e1) return 1.0;
    const double t = (x - e0) / (e1 - e0);
    return t * t * (3.0 - 2.0 * t);
}

/// Where a non-ambient light is, seen from a shaded point.
struct Incidence {
    glm::dvec3 value{0.0};    ///< Cl * n.L, before shadowing
    glm::dvec3 color{0.0};    ///< Cl, before shadowing (for light_samples)
    glm::dvec3 to_light{0.0}; ///< unit, towards the light's centre
};

// incidence(), shadow_rays() and accumulate() are the arithmetic shared by
// irradiance() and irradiance_batch(). They are kept out of line so that both
// run the very same machine code: inlined, the compiler may contract a*b+c
// into FMAs differently in each caller, and the results would differ in the
// last bit.

/// Unshadowed contribution of a non-ambient light; false when it gives
/// nothing (behind the surface, outside the cone, colour 0...).
[[gnu::noinline]] bool incidence(const PreparedLight& pl, const glm::dvec3& p,
                                 const glm::dvec3& n, Incidence* out) {
    const Light& l = *pl.light;
    if (pl.dark) return false;
    if (l.kind == Light::Kind::Distant) {
        out->to_light = -pl.axis;
        const double cosine = glm::dot(n, out->to_light);
        if (!(cosine > 0.0)) return false;
        out->color = l.color;
        out->value = l.color * cosine;
        return true;
    }
    const glm::dvec3 d = l.from - p;
    const double d2 = glm::dot(d, d);
    if (!(d2 > 0.0) || !std::isfinite(d2)) return false;
    out->to_light = d / std::sqrt(d2);
    const double cosine = glm::dot(n, out->to_light);
    if (!(cosine > 0.0)) return false;
    glm::dvec3 cl = l.color / d2;
    if (l.kind == Light::Kind::Spot) {
        const double cosangle = -glm::dot(out->to_light, pl.axis);
        const double cone = smoothstep(pl.cos_outer, pl.cos_inner, cosangle);
        if (cone == 0.0) return false;
        cl *= std::pow(std::max(cosangle, 0.0), l.beam_distribution) * cone;
    }
    out->color = cl;
    out->value = cl * cosine;
    return true;
}

/// Orthonormal vectors perpendicular to unit w (Duff et al. 2017).
void basis_around(const glm::dvec3& w, glm::dvec3* t1, glm::dvec3* t2) {
    const double sign = std::copysign(1.0, w.z);
    const double a = -1.0 / (sign + w.z);
    const double b = w.x * w.y * a;
    *t1 = glm::dvec3(1.0 + sign * w.x * w.x * a, sign * b, -sign * w.x);
    *t2 = glm::dvec3(b, sign + w.y * w.y * a, -w.y);
}

ShadowRay ray_to(const glm::dvec3& origin, const glm::dvec3& target) {
    const glm::dvec3 d = target - origin;
    const double len = glm::length(d);
    ShadowRay r;
    r.origin = glm::vec3(origin);
    r.direction = len > 0.0 ? glm::vec3(d / len) : glm::vec3(0, 0, 1);
    r.tnear = 0.0f;
    r.tfar = static_cast<float>(len * kShadowEndFraction);
    return r;
}

/// Writes the pl.rays shadow rays of one point into `out`.
[[gnu::noinline]] void shadow_rays(const PreparedLight& pl, const glm::dvec3& p,
                                   const glm::dvec3& n, const Incidence& inc,
                                   uint64_t seed, double ray_offset, ShadowRay* out) {
    const Light& l = *pl.light;
    const glm::dvec3 origin = p + n * ray_offset;
    const bool distant = l.kind == Light::Kind::Distant;
    if (pl.rays == 1) {
        if (distant) {
            out->origin = glm::vec3(origin);
            out->direction = glm::vec3(inc.to_light);
            out->tnear = 0.0f;
            out->tfar = std::numeric_limits<float>::infinity();
        } else {
            *out = ray_to(origin, l.from);
        }
        return;
    }

    glm::dvec3 t1, t2;
    basis_around(inc.to_light, &t1, &t2);
    const uint64_t h = detail::splitmix64(
        seed ^ detail::splitmix64(0x6c69676874ull + static_cast<uint64_t>(pl.index)));
    const double rotation = detail::unit_double(h);
    const double cos_max = std::cos(l.size); // distant: cone half-angle
    for (int k = 0; k < pl.rays; ++k) {
        // Stratified in area: sample k lies in the k-th of `rays` equal rings.
        const double radial =
            (k +
             detail::unit_double(detail::splitmix64(h + 1 + static_cast<uint64_t>(k)))) /
            pl.rays;
        double turn = rotation + k * 0.6180339887498949; // golden-ratio spiral
        turn -= std::floor(turn);
        const double phi = 2.0 * kPi * turn;
        const glm::dvec3 around = std::cos(phi) * t1 + std::sin(phi) * t2;
        if (distant) {
            const double cos_t = 1.0 - radial * (1.0 - cos_max);
            const double sin_t = std::sqrt(std::max(0.0, 1.0 - cos_t * cos_t));
            out[k].origin = glm::vec3(origin);
            out[k].direction =
                glm::vec3(glm::normalize(sin_t * around + cos_t * inc.to_light));
            out[k].tnear = 0.0f;
            out[k].tfar = std::numeric_limits<float>::infinity();
        } else {
            out[k] = ray_to(origin, l.from + (l.size * std::sqrt(radial)) * around);
        }
    }
}

/// sum += value * fraction.
[[gnu::noinline]] void accumulate(glm::dvec3& sum, const glm::dvec3& value,
                                  double fraction) {
    sum += value * fraction;
}

/// The unshadowed fraction of a light's depth maps at p (1 without maps):
/// shadowpoint's map of the world axis nearest to the direction from the
/// light to p, as its RSL shader chooses.
double map_visibility(const Light& l, const glm::dvec3& p) {
    if (l.shadow_maps.empty()) return 1.0;
    std::size_t k = 0;
    if (l.shadow_maps.size() == 6) {
        const glm::dvec3 d = p - l.from;
        const glm::dvec3 a = glm::abs(d);
        const int axis = a.x >= a.y && a.x >= a.z ? 0 : (a.y >= a.z ? 1 : 2);
        k = std::size_t(2 * axis + (d[axis] > 0.0 ? 0 : 1));
    }
    const ShadowMap* map = l.shadow_maps[k].get();
    if (!map) return 1.0;
    return 1.0 -
           shadow_fraction(*map, p, glm::dvec3(0.0), glm::dvec3(0.0), l.shadow_lookup);
}

double visible_fraction(const uint8_t* hit, int count) {
    int visible = 0;
    for (int k = 0; k < count; ++k) visible += hit[k] ? 0 : 1;
    return static_cast<double>(visible) / static_cast<double>(count);
}

} // namespace

std::vector<Light> resolve_lights(const Scene& scene, std::vector<std::string>* warnings,
                                  const ShadowMapLoader& maps) {
    const float scene_bias = scene_shadow_bias(scene);
    std::vector<Light> lights;
    lights.reserve(scene.lights.size());
    for (std::size_t i = 0; i < scene.lights.size(); ++i) {
        const ShaderRef& shader = scene.lights[i].shader;
        const std::string where = shader.source.empty() ? "" : shader.source + ": ";
        Light light;
        light.name = shader.name;
        light.scene_index = static_cast<int>(i);
        bool known = false;
        try {
            known = resolve_one(shader, maps, scene_bias, light);
        } catch (const ValueError& e) {
            throw ValueError(where + "light shader '" + shader.name + "': " + e.what());
        }
        if (!known) {
            if (warnings)
                warnings->push_back(where + "unknown light shader '" + shader.name +
                                    "', ignored");
            light = Light{};
            light.kind = Light::Kind::Ambient;
            light.color = glm::dvec3(0.0);
            light.name = shader.name;
            light.scene_index = static_cast<int>(i);
        }
        lights.push_back(std::move(light));
    }
    return lights;
}

glm::dvec3 irradiance(const std::vector<Light>& lights, const std::vector<int>& active,
                      const glm::dvec3& p, const glm::dvec3& n, const RayTracer* tracer,
                      uint64_t seed, double ray_offset) {
    glm::dvec3 e(0.0);
    std::vector<ShadowRay> rays;
    std::vector<uint8_t> hits;
    for (int index : active) {
        const PreparedLight pl = prepare(lights, index, tracer);
        if (pl.light->kind == Light::Kind::Ambient) {
            e += pl.light->color;
            continue;
        }
        Incidence inc;
        if (!incidence(pl, p, n, &inc)) continue;
        double fraction = 1.0;
        if (pl.traced) {
            rays.resize(pl.rays);
            hits.resize(pl.rays);
            shadow_rays(pl, p, n, inc, seed, ray_offset, rays.data());
            // The batch call, as irradiance_batch uses: same rays, same answers.
            tracer->occluded(rays.data(), rays.size(), hits.data());
            fraction = visible_fraction(hits.data(), pl.rays);
        } else {
            fraction = map_visibility(*pl.light, p);
        }
        accumulate(e, inc.value, fraction);
    }
    return e;
}

void light_samples(const std::vector<Light>& lights, const std::vector<int>& active,
                   const glm::dvec3& p, const glm::dvec3& n, const RayTracer* tracer,
                   uint64_t seed, double ray_offset, std::vector<LightSample>& out) {
    out.clear();
    // Up to 16 shadow rays on the stack (a small array: it is constructed on
    // every call); soft lights with more use the heap.
    constexpr int kStackRays = 16;
    ShadowRay stack_rays[kStackRays];
    uint8_t stack_hits[kStackRays];
    std::vector<ShadowRay> heap_rays;
    std::vector<uint8_t> heap_hits;
    for (int index : active) {
        const PreparedLight pl = prepare(lights, index, tracer);
        LightSample sample;
        sample.light = index;
        if (pl.light->kind == Light::Kind::Ambient) {
            sample.ambient = true;
            sample.color = pl.light->color;
            out.push_back(sample);
            continue;
        }
        Incidence inc;
        if (!incidence(pl, p, n, &inc)) continue;
        double fraction = 1.0;
        if (pl.traced) {
            ShadowRay* rays = stack_rays;
            uint8_t* hits = stack_hits;
            if (pl.rays > kStackRays) {
                heap_rays.resize(pl.rays);
                heap_hits.resize(pl.rays);
                rays = heap_rays.data();
                hits = heap_hits.data();
            }
            shadow_rays(pl, p, n, inc, seed, ray_offset, rays);
            // One ray: rtcOccluded1 is cheaper than a stream of one, and gives
            // the same answer (ray_tracer.cpp).
            if (pl.rays == 1)
                hits[0] = tracer->occluded(rays[0]) ? 1 : 0;
            else
                tracer->occluded(rays, static_cast<std::size_t>(pl.rays), hits);
            fraction = visible_fraction(hits, pl.rays);
        } else {
            fraction = map_visibility(*pl.light, p);
        }
        sample.color = inc.color * fraction;
        sample.direction = inc.to_light;
        out.push_back(sample);
    }
}

void irradiance_batch(const std::vector<Light>& lights, const std::vector<int>& active,
                      const glm::vec3* p, const glm::vec3* n, std::size_t count,
                      const RayTracer* tracer, uint64_t seed_base, double ray_offset,
                      glm::dvec3* out) {
    std::vector<PreparedLight> prepared;
    prepared.reserve(active.size());
    for (int index : active) prepared.push_back(prepare(lights, index, tracer));

    // Per block: for each light in order, the unshadowed terms of every
    // point, then all their shadow rays in one call (consecutive points, same
    // light: coherent rays), then the sums. Each point adds its lights in the
    // same order and with the same arithmetic as irradiance().
    std::vector<Incidence> inc(kBatchBlock);
    std::vector<uint8_t> lit(kBatchBlock);
    std::vector<std::size_t> first_ray(kBatchBlock);
    std::vector<ShadowRay> rays;
    std::vector<uint8_t> hits;
    for (std::size_t begin = 0; begin < count; begin += kBatchBlock) {
        const std::size_t m = std::min(kBatchBlock, count - begin);
        for (std::size_t i = 0; i < m; ++i) out[begin + i] = glm::dvec3(0.0);
        for (const PreparedLight& pl : prepared) {
            if (pl.light->kind == Light::Kind::Ambient) {
                for (std::size_t i = 0; i < m; ++i) out[begin + i] += pl.light->color;
                continue;
            }
            rays.clear();
            for (std::size_t i = 0; i < m; ++i) {
                const glm::dvec3 pi(p[begin + i]), ni(n[begin + i]);
                lit[i] = incidence(pl, pi, ni, &inc[i]) ? 1 : 0;
                if (!lit[i] || !pl.traced) continue;
                first_ray[i] = rays.size();
                rays.resize(rays.size() + pl.rays);
                shadow_rays(pl, pi, ni, inc[i], seed_base + begin + i, ray_offset,
                            rays.data() + first_ray[i]);
            }
            if (pl.traced && !rays.empty()) {
                hits.resize(rays.size());
                tracer->occluded(rays.data(), rays.size(), hits.data());
            }
            for (std::size_t i = 0; i < m; ++i) {
                if (!lit[i]) continue;
                const double fraction =
                    pl.traced ? visible_fraction(hits.data() + first_ray[i], pl.rays)
                              : map_visibility(*pl.light, glm::dvec3(p[begin + i]));
                accumulate(out[begin + i], inc[i].value, fraction);
            }
        }
    }
}

} // namespace sss
