// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file scene_rays.h
/// The scene as secondary rays see it (issue 14): the diced surfaces in
/// Embree, one ray tracer per kind of ray (`Attribute "visibility"`
/// "diffuse", "specular", "transmission"; identical sets share one), and the
/// shading of ray hits with the hit object's own surface shader and lights,
/// recursively (a hit shader may trace rays too, up to the depth limits).
/// ptbake and render both implement ShadingServices::trace() and
/// transmit() with it.
///
/// Rules (docs/shading.md, "Ray tracing"):
///  - Depth: rays of depth d are traced when d <= `Option "trace"
///    "maxdepth"` (default 10) and, for diffuse rays, d <= the shooting
///    primitive's `Attribute "trace" "maxdiffusedepth"` (default 1), for
///    specular rays d <= "maxspeculardepth" (default 2); deeper rays miss.
///    Transmission rays are always traced.
///  - What a ray hits: the nearest surface visible to its kind, skipping
///    back faces of one-sided (`Sides 1`) surfaces and fully transparent
///    ones (Os = 0).
///  - Hits are shaded (when the query asks for values) by the primitive's
///    surface shader with its lights, as a Points batch at depth d: P, N, Ng
///    on the diced surface, I from the ray's origin, Cs/Os, u v s t when the
///    shader reads them, dPdu/dPdv the ray footprint (length * spread) on
///    the tangent plane. `Attribute "shade" "diffusehitmode" /
///    "specularhitmode"` "primitive" skip the shader (Ci = Cs, Oi = Os).
///    bake3d calls of hit shaders are dropped (they would bake points from
///    ray hits).
///  - Volumes: a query that asks for Ci or Oi gets them through the
///    Interior shader of the object whose back face a ray hit (the ray
///    travelled inside it), else through the Exterior shader of the object
///    that shot the ray (RayQuery::origin), run on the segment to the hit (P
///    the hit, I the segment). Misses and transmission rays run none.
///  - Transmission: the product of (1 - Os) of every surface along the ray
///    (`"shade" "transmissionhitmode"` "primitive", the default) or of
///    (1 - Oi) of the hit shader ("shader").
///  - Results never depend on the thread count: hit batches are formed in
///    ray order per primitive and seeded from the query's seed.

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "sss/binding/scene_shaders.h"
#include "sss/binding/texture_library.h"
#include "sss/dice/dice.h"
#include "sss/light/ray_tracer.h"
#include "sss/scene/scene.h"
#include "sss/shading/engine.h"
#include "sss/util/messages.h"

namespace sss {

/// One primitive as rays see it.
struct RaySurface {
    const DicedSurface* diced = nullptr; ///< null or no triangles: not traced
    /// Cs per triangle (triangle_colors), or empty for the attributes' Color.
    const std::vector<glm::vec3>* triangle_colors = nullptr;
};

/// Whether `program` traces rays that need the scene (trace, gather,
/// indirectdiffuse, occlusion, or environment/shadow with "raytrace").
bool program_traces_rays(const Program& program);
/// Whether `program` traces rays whose hits matter beyond blocking light:
/// trace, gather, indirectdiffuse, occlusion or environment("raytrace")
/// (shadow("raytrace") and transmission() only need occluders).
bool program_shades_hits(const Program& program);

/// `Attribute "trace" "bias"` of `prim` (world units: how far rays leaving
/// it start off its surface) when given, finite and >= 0.
std::optional<float> trace_bias(const Primitive& prim);

class SceneRays;

/// The services of a tool's run (ptbake, render): the scene, the frame,
/// shader printf output on stdout one message at a time, shader run-time
/// warnings kept for the job's report (take_warnings()), the job's
/// TextureLibrary (one per job, shared by every SceneServices of the job, so
/// that each file is opened once), and the ray-tracing
/// shadeops through a SceneRays once one is set (before that,
/// ShadingServices' defaults).
class SceneServices : public ShadingServices {
public:
    /// `textures` must outlive the services.
    SceneServices(const Scene& scene, std::optional<int> frame, TextureLibrary& textures)
        : m_scene(scene), m_frame(frame), m_textures(textures) {}
    const Scene& scene() const override { return m_scene; }
    std::optional<int> frame() const override { return m_frame; }
    void message(const std::string& text) override;
    /// Kept (the engine gives each text once per job) for the job's report,
    /// which the tool prints as "<tool> WARNING: ..." on stderr.
    void warning(const std::string& text) override;
    /// The warnings kept so far; the list is emptied.
    Warnings take_warnings();
    TextureServices* textures() override { return &m_textures; }
    void trace(RayQuery& query) override;
    void transmit(const ShadowRay* rays, std::size_t count, glm::vec3* out,
                  int depth) override;
    void set_scene_rays(const SceneRays* rays) { m_rays = rays; }
    const SceneRays* scene_rays() const { return m_rays; }

private:
    const Scene& m_scene;
    std::optional<int> m_frame;
    const SceneRays* m_rays = nullptr;
    std::mutex m_mutex;
    Warnings m_warnings; ///< guarded by m_mutex
    TextureLibrary& m_textures;
};

/// The one warning ptbake and render give about the rays their ray tracers
/// refused (RayTracer::invalid_rays, `count` > 0): "N rays with a NaN,
/// infinite or out-of-range origin or direction were not traced (misses)
/// ...". Such rays come from a shader's arithmetic (a NaN direction) or a
/// light beyond the coordinate range (docs/render.md, "Rays").
std::string invalid_rays_warning(uint64_t count);

/// Secondary rays over a diced scene; thread-safe after construction.
class SceneRays {
public:
    /// `surfaces` by primitive index (scene.primitives order). `outer`
    /// receives printf output and warnings of hit shaders. Everything
    /// given must outlive the SceneRays.
    SceneRays(const Scene& scene, const SceneShaders& shaders,
              const ShadingResources& resources, ShadingServices& outer,
              std::vector<RaySurface> surfaces);
    ~SceneRays();
    SceneRays(const SceneRays&) = delete;
    SceneRays& operator=(const SceneRays&) = delete;

    /// ShadingServices::trace: traces and shades (see the file comment).
    void trace(RayQuery& query) const;
    /// ShadingServices::transmit.
    void transmit(const ShadowRay* rays, std::size_t count, glm::vec3* out,
                  int depth) const;
    /// The transmission tracer (binary occlusion), null when nothing casts
    /// shadows.
    const RayTracer* occluders() const;
    /// Diagonal of the traced scene's bounds.
    float extent() const;
    /// Rays traced so far (all kinds, hits shaded or not).
    uint64_t rays_traced() const;
    /// Points of hit shaders whose results were NaN or infinite (written as 0).
    uint64_t nonfinite_points() const;
    /// Rays the tracers refused as invalid (RayTracer::invalid_rays: a
    /// non-finite or out-of-range origin or direction), answered as misses.
    uint64_t invalid_rays() const;
    /// Triangles in the tracers (each distinct set counted once).
    std::size_t triangles() const;

    struct Impl;

private:
    std::unique_ptr<Impl> m_impl;
};

} // namespace sss
