// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file ray_tracer.h
/// Ray tracing over the diced scene with Embree 3: occlusion (shadow) queries
/// for ptbake and render, closest hits for render.

#include <cstdint>
#include <memory>
#include <vector>

#include <glm/vec3.hpp>

namespace sss {

/// One shadow ray: origin, unit direction, the [tnear, tfar] interval and
/// the time it is traced at (motion blur: 0 = shutter open, 1 = close).
struct ShadowRay {
    glm::vec3 origin;
    glm::vec3 direction;
    float tnear = 0.0f;
    float tfar = 0.0f;
    float time = 0.0f;
};

/// A closest hit.
struct RayHit {
    bool hit = false;
    float t = 0.0f;
    uint32_t mesh = 0;                ///< index of the mesh, in add_mesh order
    uint32_t triangle = 0;            ///< triangle index within the mesh
    float u = 0.0f, v = 0.0f;         ///< barycentrics of vertices 1 and 2
    glm::vec3 geometric_normal{0.0f}; ///< unnormalised, as Embree returns it
};

/// Triangle meshes in an Embree scene. Build with add_mesh() then commit();
/// queries are thread-safe after commit(). Results never depend on the
/// thread count (every query is independent).
class RayTracer {
public:
    RayTracer();
    ~RayTracer();
    RayTracer(const RayTracer&) = delete;
    RayTracer& operator=(const RayTracer&) = delete;

    /// Adds a mesh (3 indices per triangle) and returns its index. Data are
    /// copied. A moving mesh gives its vertices at later times in `steps`
    /// (each as many as `vertices`): the times spread evenly over [0, 1],
    /// linear in between, and a ray sees the mesh as it is at its time.
    uint32_t add_mesh(const std::vector<glm::vec3>& vertices,
                      const std::vector<uint32_t>& triangles,
                      const std::vector<std::vector<glm::vec3>>* steps = nullptr);
    /// Builds the acceleration structure.
    void commit();

    // Queries never hand Embree a ray it cannot trace: a ray whose origin or
    // direction is not finite or has a coordinate beyond Embree's range
    // (1.844e18), whose direction is zero, whose tnear is negative or not
    // finite or whose tfar is NaN hits nothing and is counted in
    // invalid_rays() (docs/render.md, "Rays"). tnear > tfar hits nothing.

    /// True if anything is hit in (tnear, tfar).
    bool occluded(const ShadowRay& ray) const;
    /// Batch form: hit[i] = occluded(rays[i]); uses Embree packets/streams.
    void occluded(const ShadowRay* rays, std::size_t count, uint8_t* hit) const;
    /// Closest hit in (tnear, tfar).
    RayHit intersect(const ShadowRay& ray) const;

    /// Rays refused as invalid (answered as misses) so far, over all threads.
    uint64_t invalid_rays() const;

    /// Diagonal of the scene's bounding box (for ray offsets), 0 when empty.
    float scene_extent() const;

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

} // namespace sss
