// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file lights.h
/// The light module owns lights, noise and the ray tracer that shadows use.
/// May use: scene and util (Embree privately).
///
/// RenderMan's standard light shaders resolved to world space, and the
/// irradiance they give at a surface point: ambient() + diffuse(N), the sum
/// over lights of Cl * max(0, N.L), with ray-traced shadows when a light asks
/// for them.

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "sss/light/ray_tracer.h"
#include "sss/light/shadow_map.h"
#include "sss/scene/scene.h"

namespace sss {

/// A light in world space.
struct Light {
    enum class Kind { Ambient, Distant, Point, Spot };
    Kind kind = Kind::Point;
    glm::dvec3 color{1.0}; ///< intensity * lightcolor
    glm::dvec3 from{0.0};  ///< world position (point, spot)
    glm::dvec3 direction{
        0, 0, 1}; ///< unit direction the light travels (distant, spot): to - from
    double cone_angle = 0.0;        ///< radians (spot)
    double cone_delta = 0.0;        ///< radians (spot)
    double beam_distribution = 2.0; ///< spot
    bool shadows = false;           ///< ray-traced shadows
    int samples = 1;                ///< shadow rays per shading point
    /// Soft shadows: radius of the spherical (point/spot) emitter in world
    /// units, or the angular radius in radians of a distant light's disk.
    double size = 0.0;
    std::string name;     ///< shader name, for messages
    int scene_index = -1; ///< index in Scene::lights
    /// Depth-map shadows: the map a "shadowname" other than "raytrace"
    /// names, or shadowpoint's six (sfpx sfnx sfpy sfny sfpz sfnz; null
    /// where the name is empty); empty without maps. Each point is looked up
    /// in one (shadowpoint: the map of the world axis nearest to the
    /// direction from the light to the point) with `shadow_lookup`.
    std::vector<std::shared_ptr<const ShadowMap>> shadow_maps;
    ShadowLookup shadow_lookup;
};

/// Reads the depth map a light names (a zfile or shadow map): the caller's
/// (binding's TextureLibrary::shadow_map); throws when it cannot.
using ShadowMapLoader =
    std::function<std::shared_ptr<const ShadowMap>(const std::string&)>;

/// Resolves every light of the scene (parameter defaults as RenderMan's
/// standard shaders; "from"/"to" in the light's shader space). Unknown light
/// shaders give a warning string in `warnings` and an entry with color 0.
/// Shadow maps (a "shadowname" other than "raytrace", shadowpoint's sfpx...)
/// are read with `maps`; without one a light that names a map is a
/// ValueError.
std::vector<Light> resolve_lights(const Scene& scene, std::vector<std::string>* warnings,
                                  const ShadowMapLoader& maps = nullptr);

/// Irradiance at world point p with unit normal n from the lights listed in
/// `active` (indices into `lights`): ambient lights add their colour, the
/// others Cl * max(0, n.L), times the fraction of unoccluded shadow rays when
/// the light has shadows and `tracer` is given, or by the lit fraction of its
/// depth maps (Light::shadow_maps, no tracer needed). `seed` picks the sample
/// pattern (deterministic; pass the point index). `ray_offset` is the origin
/// offset along n used for shadow rays (world units).
glm::dvec3 irradiance(const std::vector<Light>& lights, const std::vector<int>& active,
                      const glm::dvec3& p, const glm::dvec3& n, const RayTracer* tracer,
                      uint64_t seed, double ray_offset);

/// Batched form used by the baker: irradiance for `count` points (arrays of
/// positions, normals) into `out`; same values as the scalar form, but
/// shadow rays are traced in packets. Point i uses the seed seed_base + i, so
/// out[i] == irradiance(..., p[i], n[i], tracer, seed_base + i, ray_offset)
/// exactly. Not internally parallel.
void irradiance_batch(const std::vector<Light>& lights, const std::vector<int>& active,
                      const glm::vec3* p, const glm::vec3* n, std::size_t count,
                      const RayTracer* tracer, uint64_t seed_base, double ray_offset,
                      glm::dvec3* out);

/// One light as a shader's illuminance loop sees it at a shaded point.
struct LightSample {
    /// Cl: the light arriving at the point (intensity, colour, falloff, spot
    /// cone and beam, times the unoccluded fraction of its shadow rays), without
    /// the N.L cosine.
    glm::dvec3 color{0.0};
    /// L: unit vector from the point towards the light's centre (zero for
    /// ambient lights).
    glm::dvec3 direction{0.0};
    bool ambient = false; ///< an ambient light: no direction, added whatever the normal
    int light = -1;       ///< index in the lights vector
};

/// The lights of `active` one by one, for shaders that need Cl and L per light
/// (specular()): `out` is cleared and gets, in `active` order, every ambient
/// light and every other light that reaches the front of the surface (n.L > 0,
/// inside a spot's cone, colour not 0), as RenderMan's illuminance(P, n, PI/2)
/// loop sees them. Shadow rays, seeds and ray offsets are those of
/// irradiance(), so irradiance(...) equals the sum of the ambient colours plus
/// the sum of color * dot(n, direction) over the others (up to rounding).
void light_samples(const std::vector<Light>& lights, const std::vector<int>& active,
                   const glm::dvec3& p, const glm::dvec3& n, const RayTracer* tracer,
                   uint64_t seed, double ray_offset, std::vector<LightSample>& out);

/// Improved Perlin gradient noise in [0, 1] (RenderMan's noise() range), deterministic.
double noise3(const glm::dvec3& p);

/// Signed improved gradient noise (Perlin 2002) in `dims` = 1..4 dimensions at
/// x[0..dims), roughly in [-1, 1] and 0 on every lattice point. periods[d]
/// (rounded integers) makes it repeat every periods[d] cells along d; null or
/// < 1: every 256 cells (the permutation's own period). `component` 0..2
/// shifts the lattice to decorrelate the components of vector noise. RSL's
/// noise family (the shading module) and noise3() are this function.
double gradient_noise(int dims, const double* x, const double* periods, int component);

} // namespace sss
