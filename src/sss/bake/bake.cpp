// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file bake.cpp
/// The ptbake job (bake.h): bake_clouds runs its phases in order (spacing,
/// lights, jobs, dicing, spacing checks, occluders, lighting, point clouds),
/// each a function below; bake_scene writes the clouds.

#include "sss/bake/bake.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec4.hpp>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "sss/binding/bake3d_file.h"
#include "sss/binding/displacement.h"
#include "sss/binding/scene_rays.h"
#include "sss/binding/scene_shaders.h"
#include "sss/dice/dice.h"
#include "sss/light/ray_tracer.h"
#include "sss/shading/engine.h"
#include "sss/util/atomic_output.h"
#include "sss/util/error.h"
#include "sss/util/frame_pattern.h"
#include "sss/util/job_files.h"
#include "sss/util/limits.h"
#include "sss/util/progress.h"

namespace sss {
namespace {

// Surfaces that only cast shadows are diced this many times coarser (edge
// length) than baked ones: 1/64 of the triangles, and the chord error of a
// curved occluder stays a small fraction of its size.
constexpr double kOccluderCoarsening = 8.0;
// Surfaces that secondary rays shade (trace, gather, occlusion,
// indirectdiffuse in a bake shader) are seen at their hit points: diced only
// twice as coarse, so that chords stay within a fraction of a percent of a
// curved surface (occlusion and bounced light depend on the true shape).
constexpr double kRayCoarsening = 2.0;
/// Shading points per batch: the unit of parallel work.
constexpr std::size_t kChunk = 256;

// What one baked primitive is: its shader, and the file its shader names.
struct BakedPrimitive {
    std::size_t prim = 0;
    const ShaderInstance* shader = nullptr;
    std::string file; ///< the shader's "filename" (or -o); "" when unknown
    // The material range of a bake_sss_params-style shader (albedo, dmfp mm).
    bool has_material = false;
    glm::dvec3 albedo{0.0}, albedo2{0.0}, dmfp{0.0}, dmfp2{0.0};
};

/// A colour parameter of a bound shader: the RIB's value, else the
/// shader's constant default, else `fallback`.
glm::dvec3 color_parameter(const ShaderInstance& shader, const std::string& name,
                           const glm::dvec3& fallback) {
    for (const ShaderArgument& a : shader.arguments())
        if (a.name == name && !a.numbers.empty()) {
            if (a.numbers.size() >= 3) return {a.numbers[0], a.numbers[1], a.numbers[2]};
            return glm::dvec3(a.numbers[0]);
        }
    const int index = shader.program().find(name);
    if (index >= 0) {
        const Symbol& s = shader.program().symbols[static_cast<std::size_t>(index)];
        if (s.numbers.size() >= 3) return {s.numbers[0], s.numbers[1], s.numbers[2]};
        if (s.numbers.size() == 1) return glm::dvec3(s.numbers[0]);
    }
    return fallback;
}

/// The file a baked primitive goes to: -o, else its shader's "filename"
/// ("" when the shader has no such parameter: then only bake3d knows).
std::string bake_file(const Primitive& prim, const ShaderInstance& shader,
                      const BakeOptions& options) {
    if (!options.output.empty()) return options.output;
    const std::optional<std::string> name = shader.string_parameter("filename");
    if (name && name->empty())
        throw MissingBakeFileError(prim.source + ": " + shader.program().name +
                                   " has no \"filename\"");
    return name ? *name : std::string();
}

BakedPrimitive make_job(const Scene& scene, std::size_t index,
                        const ShaderInstance& shader, const BakeOptions& options) {
    const Primitive& prim = scene.primitives[index];
    const std::string where = prim.source + ": " + shader.program().name;
    BakedPrimitive job;
    job.prim = index;
    job.shader = &shader;
    job.file = bake_file(prim, shader, options);

    // A shader with a material (bake_sss_params and shaders like it): the
    // range its points take, for the spacing checks.
    const Program& program = shader.program();
    if (program.find("dmfp") >= 0 && program.find("albedo") >= 0) {
        MaterialSpec preset;
        preset.preset = shader.string_parameter("material").value_or("marble");
        glm::dvec3 a(0.0), d(0.0);
        if (find_material(preset.preset)) preset.resolve_albedo_dmfp(a, d);
        const auto given = [&](const char* name, const glm::dvec3& fallback) {
            const glm::dvec3 v = color_parameter(shader, name, glm::dvec3(-1.0));
            return v == glm::dvec3(-1.0) ? fallback : v;
        };
        job.albedo = given("albedo", a);
        job.dmfp = given("dmfp", d);
        job.albedo2 = given("albedo2", job.albedo);
        job.dmfp2 = given("dmfp2", job.dmfp);
        job.has_material = true;
        for (int i = 0; i < 3; ++i) {
            for (double v : {job.albedo[i], job.albedo2[i]})
                if (!(v >= 0.0 && v <= 1.0))
                    throw ValueError(where + ": impossible albedo " + std::to_string(v) +
                                     " (must be in [0, 1])");
            for (double v : {job.dmfp[i], job.dmfp2[i]})
                if (!(v > 0.0 && std::isfinite(v)))
                    throw ValueError(where + ": impossible dmfp " + std::to_string(v) +
                                     " (must be > 0, in mm)");
        }
    }
    return job;
}

double mfp_mm(const MaterialSpec& m, const glm::dvec3* albedo, const glm::dvec3* dmfp) {
    double best = std::numeric_limits<double>::infinity();
    for (int i = 0; i < 3; ++i) {
        double st = 0.0;
        if (albedo && dmfp) {
            ChannelCoefficients c = coefficients_from_albedo_dmfp(
                std::min((*albedo)[i], 0.999999), (*dmfp)[i], m.resolved_ior());
            st = c.sigma_s_prime + c.sigma_a;
        } else if (m.uses_albedo_form()) {
            glm::dvec3 a, d;
            m.resolve_albedo_dmfp(a, d);
            ChannelCoefficients c = coefficients_from_albedo_dmfp(
                std::min(a[i], 0.999999), d[i], m.resolved_ior());
            st = c.sigma_s_prime + c.sigma_a;
        } else {
            glm::dvec3 ss, sa;
            m.resolve_coefficients(ss, sa);
            st = ss[i] + sa[i];
        }
        if (st > 0.0) best = std::min(best, 1.0 / st);
    }
    return best;
}

// How far off the surface shadow rays start, for points [begin, end) of a
// diced surface. The traced triangles are chords of curved surfaces, up to a
// sagitta r^2 kappa / 2 away from the micropolygon centres (r: micropolygon
// radius, kappa: curvature), so rays start a little beyond that: kappa is
// estimated from the normal change between neighbouring points of the chunk.
// Flat surfaces get only a rounding-sized offset, so shadows stay where they
// are; at creases and corners the estimate is capped at half a radius.
double shadow_ray_offset(const DicedSurface& d, std::size_t begin, std::size_t end,
                         double extent) {
    double rmax = 0.0, kappa = 0.0;
    for (std::size_t i = begin; i < end; ++i) {
        rmax = std::max(rmax, double(d.radii[i]));
        if (i + 1 < end) {
            const double dist = glm::length(glm::dvec3(d.centers[i + 1] - d.centers[i]));
            const double limit = 3.0 * std::max(d.radii[i], d.radii[i + 1]);
            if (dist > 0.0 && dist < limit)
                kappa = std::max(
                    kappa,
                    glm::length(glm::dvec3(d.normals[i + 1] - d.normals[i])) / dist);
        }
    }
    return 1e-5 * extent + std::min(0.5 * rmax, kappa * rmax * rmax);
}

// ---------------------------------------------------------------------------
// The phases of bake_clouds

/// The dicing spacing (0: ShadingRate) and the given material's mean free path.
struct BakeSpacing {
    double spacing = 0.0;
    std::optional<double> material_mfp;
};

/// The bake's one scene scale is options.unitlength; a material given for the
/// bake must use the same one.
void check_units(const BakeOptions& options) {
    check_unitlength(options.unitlength);
    if (options.material && options.material->unitlength != options.unitlength)
        throw ValueError(
            "the material's unitlength " + std::to_string(options.material->unitlength) +
            " differs from the bake's " + std::to_string(options.unitlength));
}

/// Resolves the spacing (a length, or from the material's mean free path)
/// and checks it and the unitlength.
BakeSpacing resolve_spacing(const BakeOptions& options) {
    BakeSpacing out;
    out.spacing = options.spacing;
    if (options.material) {
        out.material_mfp = material_mean_free_path(*options.material);
        if (options.spacing_from_material)
            out.spacing = *out.material_mfp * options.mfp_fraction;
    }
    if (!(out.spacing >= 0.0) || !std::isfinite(out.spacing))
        throw ValueError("impossible spacing " + std::to_string(out.spacing));
    check_units(options);
    return out;
}

/// What the bake does with each primitive.
struct BakePlan {
    std::vector<BakedPrimitive> jobs;
    std::vector<int> job_of;    ///< per primitive: its job, or -1 when not baked
    std::vector<char> occluder; ///< per primitive: casts shadows
    /// Per job: the mean free path its points should respect, if known.
    std::vector<std::optional<double>> job_mfp;
};

/// Which primitives are baked (those whose surface shader calls bake3d, a
/// job each, in primitive order) and which only cast shadows; ValueError
/// when nothing is baked.
BakePlan plan_jobs(const Scene& scene, const SceneShaders& shaders,
                   const BakeOptions& options, bool any_shadows, bool any_hits,
                   BakeReport& report) {
    BakePlan plan;
    plan.job_of.assign(scene.primitives.size(), -1);
    plan.occluder.assign(scene.primitives.size(), 0);
    for (std::size_t i = 0; i < scene.primitives.size(); ++i) {
        const Primitive& prim = scene.primitives[i];
        const ShaderInstance& shader = *shaders.surface_of[i];
        const Attributes& attr = *prim.attributes;
        plan.occluder[i] =
            (any_shadows && attr.visible_to("transmission")) ||
            (any_hits && (attr.visible_to("diffuse") || attr.visible_to("specular")));
        if (program_uses(shader.program(), "bake3d")) {
            plan.job_of[i] = static_cast<int>(plan.jobs.size());
            plan.jobs.push_back(make_job(scene, i, shader, options));
        }
    }
    report.baked_primitives = plan.jobs.size();
    if (plan.jobs.empty())
        throw ValueError(scene.path +
                         ": nothing to bake (no primitive's surface shader calls bake3d, "
                         "e.g. Surface \"bake_radiance_t\", \"bake_sss_params\" or "
                         "\"bake_constant\")");
    return plan;
}

/// The mean free path each job's points should respect: the -material's,
/// else the object's own material range (bake_sss_params). A
/// SpacingMaterialError when the spacing from the mean free path leaves a
/// job without one.
void job_mean_free_paths(const Scene& scene, const BakeOptions& options,
                         std::optional<double> material_mfp, BakePlan& plan) {
    const std::vector<BakedPrimitive>& jobs = plan.jobs;
    plan.job_mfp.assign(jobs.size(), material_mfp);
    for (std::size_t j = 0; j < jobs.size(); ++j) {
        const BakedPrimitive& job = jobs[j];
        if (!job.has_material) continue;
        MaterialSpec m = options.material ? *options.material : MaterialSpec{};
        const double unit = options.unitlength;
        const double a = mfp_mm(m, &job.albedo, &job.dmfp) * unit;
        const double b = mfp_mm(m, &job.albedo2, &job.dmfp2) * unit;
        plan.job_mfp[j] = std::min(plan.job_mfp[j].value_or(a), std::min(a, b));
    }
    if (options.spacing_from_material && !options.material)
        for (std::size_t j = 0; j < jobs.size(); ++j)
            if (!plan.job_mfp[j])
                throw SpacingMaterialError(scene.primitives[jobs[j].prim].source);
}

/// What is diced: what is baked or casts shadows (the rest is not needed),
/// and how finely.
std::vector<DiceRequest> dice_requests(const Scene& scene, const BakeOptions& options,
                                       const SceneShaders& shaders, const BakePlan& plan,
                                       double spacing, bool any_hits,
                                       Displacer& displacer, TextureLibrary& textures) {
    DiceControl control;
    control.spacing = spacing;
    control.camera = &scene.options.camera;
    control.depth_maps = [&textures](const std::string& name) {
        return textures.depth_grid(name);
    };
    // Shadow-only surfaces need their shape, not micropolygon density.
    DiceControl occluder_control = control;
    occluder_control.coarsening = any_hits ? kRayCoarsening : kOccluderCoarsening;
    std::vector<DiceRequest> requests;
    for (std::size_t i = 0; i < scene.primitives.size(); ++i) {
        const int job = plan.job_of[i];
        if (job < 0 && !plan.occluder[i]) continue;
        DiceRequest request{i, control, {}};
        // A moving primitive is baked as it is when the shutter opens.
        if (scene.primitives[i].motion)
            request.times = {scene.options.camera.shutter_open};
        // Shaders that differentiate or read u, v, s, t are shaded grid by
        // grid with the parametrisation; the others need neither.
        if (job >= 0) {
            const Program& program =
                plan.jobs[static_cast<std::size_t>(job)].shader->program();
            request.control.grids =
                program_uses_derivatives(program) || program_reads_parametric(program);
        }
        if (job < 0) {
            request.control = occluder_control;
            // Ray hits interpolate (u, v, s, t) over the triangles for hit
            // shaders that read them.
            request.control.grids =
                any_hits && program_reads_parametric(shaders.surface_of[i]->program());
        } else if (options.spacing_from_material && !options.material) {
            request.control.spacing = *plan.job_mfp[job] * options.mfp_fraction;
        }
        request.control.displace = displacer.hook(i);
        if (job >= 0 && request.control.displace) request.control.grids = true;
        requests.push_back(request);
    }
    return requests;
}

// Memory per unit of dicing, beyond the diced surfaces themselves
// (DiceEstimate::surface_bytes), measured on the teapot and polygon scenes
// of docs/ptbake.md ("Memory") with their peak resident size.
/// Per baked point: its bake3d record (P, N, radius, area, channels) and
/// its point in the cloud written, with the vectors' spare capacity.
constexpr double kBakedPointBytes = 140.0;
/// Per occluder triangle in Embree (vertex and index copies, BVH with
/// spatial splits), per vertex included.
constexpr double kTracedTriangleBytes = 80.0;

/// Estimates the dicing before it allocates anything: Limit::
/// PrimitiveMicropolygons and Limit::SceneMicropolygons (LimitError), then
/// the memory the diced surfaces, the occluders and the baked points need
/// (OutOfMemoryError naming the option that reduces it).
void check_dicing(const Scene& scene, const BakeOptions& options, const BakePlan& plan,
                  const std::vector<DiceRequest>& requests, BakeReport& report) {
    const std::string name = scene.path.empty() ? std::string("the scene") : scene.path;
    const std::vector<DiceEstimate> estimates = estimate_dicing(scene, requests, name);
    double micropolygons = 0.0, bytes = 0.0;
    for (std::size_t k = 0; k < requests.size(); ++k) {
        const std::size_t i = requests[k].primitive;
        const DiceEstimate& e = estimates[k];
        micropolygons += e.micropolygons;
        bytes += e.surface_bytes(scene.primitives[i].params.has("Cs"),
                                 requests[k].control.grids);
        if (plan.job_of[i] >= 0) bytes += kBakedPointBytes * e.micropolygons;
        if (plan.occluder[i]) bytes += kTracedTriangleBytes * e.triangles;
    }
    report.estimated_micropolygons = micropolygons;
    report.estimated_bytes = bytes;
    char what[160];
    std::snprintf(what, sizeof what, "baking %s (about %.3g micropolygons)", name.c_str(),
                  micropolygons);
    const char* remedy = options.spacing_from_material ? "raise -mfpfraction"
                         : options.spacing > 0.0
                             ? "raise -spacing"
                             : "raise ShadingRate or give a larger -spacing";
    check_memory(static_cast<uint64_t>(std::min(bytes, 1.8e19)), what, remedy);
}

/// Reports the micropolygon spacing, and warns about objects without area
/// and points farther apart than their mean free path.
void check_spacing(const Scene& scene, const BakePlan& plan,
                   const std::vector<DicedSurface>& diced, BakeReport& report) {
    report.min_spacing = std::numeric_limits<double>::infinity();
    report.max_spacing = 0.0;
    for (std::size_t j = 0; j < plan.jobs.size(); ++j) {
        const BakedPrimitive& job = plan.jobs[j];
        const DicedSurface& d = diced[job.prim];
        double lo = std::numeric_limits<double>::infinity(), hi = 0.0;
        for (float a : d.areas) {
            lo = std::min(lo, double(a));
            hi = std::max(hi, double(a));
        }
        if (d.areas.empty()) {
            report.warnings.push_back(scene.primitives[job.prim].source +
                                      ": the object has no area; nothing baked from it");
            continue;
        }
        report.min_spacing = std::min(report.min_spacing, std::sqrt(lo));
        report.max_spacing = std::max(report.max_spacing, std::sqrt(hi));
        const std::optional<double> mfp = plan.job_mfp[j];
        // sqrt(area) is the edge of a square micropolygon: the point spacing.
        if (mfp && std::sqrt(hi) > *mfp * 1.0001) {
            char buf[256];
            std::snprintf(buf, sizeof buf,
                          ": points up to %.4g apart, coarser than the material's mean "
                          "free path %.4g (dice at a spacing of %.4g or a smaller "
                          "ShadingRate)",
                          std::sqrt(hi), *mfp, *mfp);
            report.warnings.push_back(scene.primitives[job.prim].source + buf);
        }
    }
    if (!std::isfinite(report.min_spacing)) report.min_spacing = 0.0;
}

/// The ray tracer of the occluders, for ray-traced shadows (none without
/// shadow-casting lights).
std::unique_ptr<RayTracer> build_occluders(const Scene& scene, const BakePlan& plan,
                                           const std::vector<DicedSurface>& diced,
                                           bool any_shadows, BakeReport& report) {
    if (!any_shadows) return nullptr;
    auto tracer = std::make_unique<RayTracer>();
    for (std::size_t i = 0; i < scene.primitives.size(); ++i) {
        if (!plan.occluder[i] || diced[i].triangles.empty()) continue;
        tracer->add_mesh(diced[i].vertices, diced[i].triangles);
        report.occluder_triangles += diced[i].triangles.size() / 3;
        if (plan.job_of[i] < 0) ++report.occluder_primitives;
    }
    tracer->commit();
    return tracer;
}

/// The parametric globals of a batch of micropolygons begin.. of a diced
/// surface: u, v, du, dv, s, t, and dPdu, dPdv in camera space.
void fill_parametric(const DicedSurface& d, std::size_t begin,
                     const glm::dmat3& world_to_camera, ShadingBatch& batch) {
    const std::size_t n = batch.size;
    const auto range = [&](const std::vector<float>& from, std::vector<float>& to) {
        to.assign(from.begin() + static_cast<std::ptrdiff_t>(begin),
                  from.begin() + static_cast<std::ptrdiff_t>(begin + n));
    };
    range(d.u, batch.u);
    range(d.v, batch.v);
    range(d.du, batch.du);
    range(d.dv, batch.dv);
    range(d.s, batch.s);
    range(d.t, batch.t);
    batch.dPdu.resize(n);
    batch.dPdv.resize(n);
    for (std::size_t k = 0; k < n; ++k) {
        batch.dPdu[k] = glm::vec3(world_to_camera * glm::dvec3(d.dPdu[begin + k]));
        batch.dPdv[k] = glm::vec3(world_to_camera * glm::dvec3(d.dPdv[begin + k]));
    }
}

/// What bake3d calls hand over while a chunk is shaded: collected per chunk
/// (through a thread-local sink), so the clouds come out in point order for
/// any number of threads.
class BakeServices final : public SceneServices {
public:
    BakeServices(const Scene& scene, const RayTracer* occluders, std::optional<int> frame,
                 TextureLibrary& textures, const std::string& output)
        : SceneServices(scene, frame, textures), m_occluders(occluders),
          m_output(output) {}
    const RayTracer* occluders() const override {
        return scene_rays() ? scene_rays()->occluders() : m_occluders;
    }
    void bake3d(Bake3dRecord&& record) override {
        if (!m_output.empty()) record.file = m_output;
        if (s_sink) s_sink->push_back(std::move(record));
    }
    /// Where this thread's bake3d records go (null: dropped).
    static void set_sink(std::vector<Bake3dRecord>* sink) { s_sink = sink; }

private:
    const RayTracer* m_occluders;
    std::string m_output;
    static thread_local std::vector<Bake3dRecord>* s_sink;
};
thread_local std::vector<Bake3dRecord>* BakeServices::s_sink = nullptr;

/// Runs every job's surface shader over its micropolygons (a Grid batch per
/// diced grid, a Points batch per chunk of kChunk other points; micropolygon
/// centres as bake3d's "interpolate" mode bakes them) and returns the bake3d records of
/// each chunk in order. Point seeds are global point indices, so the result does not
/// depend on how the work is split between threads.
std::vector<std::vector<Bake3dRecord>> shade_points(
    const Scene& scene, const BakeOptions& options, const SceneShaders& shaders,
    const std::vector<BakedPrimitive>& jobs, const std::vector<DicedSurface>& diced,
    const RayTracer* tracer, const SceneRays* scene_rays, std::optional<int> frame,
    const ShadingResources& resources, TextureLibrary& textures, BakeReport& report) {
    std::size_t total_points = 0;
    std::vector<std::size_t> first_point(jobs.size());
    struct Chunk {
        std::size_t job, begin, end;
        const DicedGrid* grid; ///< null: unrelated points
    };
    std::vector<Chunk> chunks;
    if (options.progress) options.progress->set_unit("points");
    for (std::size_t j = 0; j < jobs.size(); ++j) {
        first_point[j] = total_points;
        const DicedSurface& d = diced[jobs[j].prim];
        const std::size_t n = d.size();
        total_points += n;
        // A shader that differentiates gets each grid as one batch (exact
        // derivatives), the points between grids in chunks; any other shader
        // gets chunks of kChunk points (fewer, larger batches run faster).
        std::size_t at = 0;
        const auto points_up_to = [&](std::size_t end) {
            for (std::size_t b = at; b < end; b += kChunk)
                chunks.push_back({j, b, std::min(end, b + kChunk), nullptr});
        };
        if (program_uses_derivatives(jobs[j].shader->program()))
            for (const DicedGrid& g : d.grids) {
                points_up_to(g.first);
                chunks.push_back({j, g.first, g.first + g.size(), &g});
                at = g.first + g.size();
            }
        points_up_to(n);
    }
    BakeServices services(scene, tracer, frame, textures, options.output);
    services.set_scene_rays(scene_rays);
    const double extent = tracer       ? tracer->scene_extent()
                          : scene_rays ? scene_rays->extent()
                                       : 0.0;
    const Camera& camera = scene.options.camera;
    const glm::dmat4& to_camera = camera.world_to_camera;
    const glm::dmat3 normal_to_camera =
        glm::transpose(glm::inverse(glm::dmat3(camera.world_to_camera)));
    std::vector<std::vector<Bake3dRecord>> records(chunks.size());
    std::atomic<std::size_t> done{0};
    std::atomic<uint64_t> nonfinite{0};
    tbb::enumerable_thread_specific<std::unique_ptr<ShadingContext>> contexts(
        [&] { return std::make_unique<ShadingContext>(resources, services); });
    tbb::parallel_for(std::size_t(0), chunks.size(), [&](std::size_t c) {
        ShadingContext& context = *contexts.local();
        const Chunk& ch = chunks[c];
        const BakedPrimitive& job = jobs[ch.job];
        const Primitive& prim = scene.primitives[job.prim];
        const Attributes& attr = attributes_of(prim);
        const DicedSurface& d = diced[job.prim];
        const std::size_t n = ch.end - ch.begin;
        ShadingBatch batch;
        batch.size = n;
        batch.layout = BatchLayout::Points;
        if (ch.grid) {
            // A grid one micropolygon wide has no differences across it: as
            // unrelated points, Du(P) and Dv(P) are dPdu and dPdv instead of 0.
            if (ch.grid->nu > 1 && ch.grid->nv > 1) {
                batch.layout = BatchLayout::Grid;
                batch.nu = ch.grid->nu;
                batch.nv = ch.grid->nv;
            }
        }
        if (d.has_parametric())
            fill_parametric(d, ch.begin, glm::dmat3(to_camera), batch);
        batch.primitive = &prim;
        batch.P.resize(n);
        batch.N.resize(n);
        batch.I.resize(n);
        batch.Cs.resize(n);
        batch.Os.assign(n, glm::vec3(attr.opacity));
        batch.dicing_area.resize(n);
        batch.radius.resize(n);
        batch.seed = first_point[ch.job] + ch.begin;
        batch.ray_offset = trace_bias(prim).value_or(
            static_cast<float>(shadow_ray_offset(d, ch.begin, ch.end, extent)));
        for (std::size_t k = 0; k < n; ++k) {
            const std::size_t i = ch.begin + k;
            const glm::dvec3 pc =
                glm::dvec3(to_camera * glm::dvec4(glm::dvec3(d.centers[i]), 1.0));
            batch.P[k] = glm::vec3(pc);
            batch.I[k] = camera.perspective ? glm::vec3(pc) : glm::vec3(0.0f, 0.0f, 1.0f);
            batch.N[k] =
                glm::vec3(glm::normalize(normal_to_camera * glm::dvec3(d.normals[i])));
            batch.Cs[k] = d.colors.empty() ? glm::vec3(attr.color) : d.colors[i];
            batch.dicing_area[k] = d.areas[i];
            batch.radius[k] = d.radii[i];
        }
        batch.Ng = batch.N;
        BakeServices::set_sink(&records[c]);
        const auto& lights = shaders.lights_of[job.prim];
        const auto& coshaders = shaders.coshaders_of[job.prim];
        try {
            context.execute(*job.shader, batch, LightList(lights.data(), lights.size()),
                            CoshaderList(coshaders.data(), coshaders.size()));
        } catch (...) {
            BakeServices::set_sink(nullptr);
            throw;
        }
        BakeServices::set_sink(nullptr);
        nonfinite += context.nonfinite_points();
        if (options.progress) options.progress->update(done += n, total_points);
    });
    if (nonfinite.load() > 0)
        report.warnings.push_back(std::to_string(nonfinite.load()) +
                                  " shading points gave NaN or infinite values, "
                                  "written as 0");
    report.warnings.append(services.take_warnings());
    return records;
}

/// The point clouds by output file, in first-use order, from the bake3d
/// records in chunk order (bake3d_clouds: `_area` always, the camera's
/// matrices), with the report's per-file figures.
std::vector<std::pair<std::string, PointCloud>>
gather_clouds(const Scene& scene, const std::vector<BakedPrimitive>& jobs,
              std::vector<std::vector<Bake3dRecord>>& records, BakeReport& report) {
    std::vector<Bake3dRecord> all;
    std::map<std::string, std::vector<std::string>> first_channels;
    std::set<std::string> mixed;
    for (auto& chunk : records)
        for (Bake3dRecord& r : chunk) {
            if (r.file.empty())
                throw MissingBakeFileError(
                    scene.path + ": bake3d was called without a file name (give "
                                 "the shader a \"filename\" or ptbake -o)");
            auto [it, added] = first_channels.try_emplace(r.file, r.channels);
            if (!added && it->second != r.channels) mixed.insert(r.file);
            all.push_back(std::move(r));
        }
    records.clear();
    std::vector<std::pair<std::string, PointCloud>> out =
        bake3d_clouds(all, scene.options.display_channels, &scene.options.camera);
    for (const auto& [path, cloud] : out) {
        BakeFileReport fr;
        fr.path = path;
        fr.points = cloud.size();
        if (const Channel* area = cloud.find_channel("_area"))
            for (float a : area->data) fr.area += a;
        for (const Channel& c : cloud.channels)
            fr.channels.push_back(std::string(channel_type_name(c.type)) + " " + c.name);
        for (const BakedPrimitive& job : jobs)
            if (job.file == path) fr.objects.push_back(scene.primitives[job.prim].source);
        if (mixed.count(path))
            report.warnings.push_back(path +
                                      ": objects bake different channels into this file; "
                                      "missing channels are filled with 0");
        report.files.push_back(std::move(fr));
    }
    for (const BakedPrimitive& job : jobs)
        if (!job.file.empty() && !first_channels.count(job.file))
            report.warnings.push_back(scene.primitives[job.prim].source +
                                      ": the shader baked no point into " + job.file);
    return out;
}

} // namespace

double material_mean_free_path(const MaterialSpec& material) {
    material.validate();
    return mfp_mm(material, nullptr, nullptr) * material.unitlength;
}

BakeJob::BakeJob(const Scene& scene, const BakeOptions& options)
    : m_scene(scene), m_options(options), m_frame(job_frame(scene, options.frame)),
      m_shaders(
          std::make_shared<const SceneShaders>(bind_scene_shaders(scene, m_frame))) {}

BakeJob::BakeJob(const Scene& scene, const BakeOptions& options,
                 std::shared_ptr<const SceneShaders> shaders)
    : m_scene(scene), m_options(options), m_frame(job_frame(scene, options.frame)),
      m_shaders(std::move(shaders)) {}

BakeJob::~BakeJob() = default;

std::vector<std::pair<std::string, PointCloud>>
BakeJob::clouds(BakeReport* report_out) const {
    BakeReport local;
    BakeReport& report = report_out ? *report_out : local;
    Stopwatch watch;
    const Scene& scene = m_scene;
    const BakeOptions& options = m_options;
    const std::optional<int> frame = m_frame;
    const SceneShaders& shaders = *m_shaders;

    // Camera space is the shaders' current space and the bake3d files'
    // reference: it must exist (no camera rays are traced).
    check_camera(scene.options.camera, false);
    const BakeSpacing spacing = resolve_spacing(options);
    if (JobFiles* files = JobFiles::current()) record_shader_inputs(*files, shaders);
    for (const std::string& w : shaders.warnings) report.warnings.push_back(w);
    if (auto w = unlit_scene_warning(scene, shaders)) report.warnings.push_back(*w);
    bool any_shadows = false;
    for (const char* op : {"shadow", "transmission"})
        any_shadows = any_shadows || shaders.uses(op);
    // Shaders that trace rays through the scene (ray-traced global
    // illumination bakes): the scene's surfaces, shaded where rays hit.
    bool any_rays = false, any_hits = false;
    for (const auto* list : {&shaders.surfaces, &shaders.lights})
        for (const auto& s : *list) {
            any_rays = any_rays || program_traces_rays(s->program());
            any_hits = any_hits || program_shades_hits(s->program());
        }
    for (const auto& light : shaders.lights)
        if (program_uses(light->program(), "shadow") ||
            program_uses(light->program(), "transmission"))
            ++report.shadow_lights;
    BakePlan plan = plan_jobs(scene, shaders, options, any_shadows, any_hits, report);
    job_mean_free_paths(scene, options, spacing.material_mfp, plan);

    // Displacement shaders run while dicing, before the occluders are built:
    // shadows see the displaced surfaces.
    ShadingResources resources;
    TextureLibrary textures; // every phase's lookups: each file opened once
    textures.set_search_path(search_path(scene, "texture"));
    BakeServices dice_services(scene, nullptr, frame, textures, options.output);
    Displacer displacer(scene, shaders, resources, dice_services);
    const std::string name = scene.path.empty() ? std::string("the scene") : scene.path;
    const std::vector<DiceRequest> requests = dice_requests(
        scene, options, shaders, plan, spacing.spacing, any_hits, displacer, textures);
    std::optional<ScopedStage> stage(std::in_place, "dicing " + name);
    check_dicing(scene, options, plan, requests, report);
    const std::vector<DicedSurface> diced = dice_all(scene, requests);
    for (const std::string& w : displacer.warnings()) report.warnings.push_back(w);
    report.warnings.append(dice_services.take_warnings());
    report.dice_seconds = watch.seconds();

    check_spacing(scene, plan, diced, report);
    stage.emplace("building the ray tracer for " + name);
    const std::unique_ptr<RayTracer> tracer =
        build_occluders(scene, plan, diced, any_shadows && !any_rays, report);
    std::unique_ptr<SceneRays> scene_rays;
    std::vector<std::vector<glm::vec3>> colors(scene.primitives.size());
    if (any_rays) {
        std::vector<RaySurface> surfaces(scene.primitives.size());
        for (std::size_t i = 0; i < scene.primitives.size(); ++i) {
            if (!plan.occluder[i] && plan.job_of[i] < 0) continue;
            colors[i] = triangle_colors(diced[i]);
            surfaces[i] = {&diced[i], &colors[i]};
            if (plan.job_of[i] < 0 && !diced[i].triangles.empty())
                ++report.occluder_primitives;
        }
        scene_rays = std::make_unique<SceneRays>(scene, shaders, resources, dice_services,
                                                 std::move(surfaces));
        report.occluder_triangles = scene_rays->triangles();
    }
    report.trace_build_seconds = watch.seconds() - report.dice_seconds;

    stage.emplace("baking " + name);
    std::vector<std::vector<Bake3dRecord>> records =
        shade_points(scene, options, shaders, plan.jobs, diced, tracer.get(),
                     scene_rays.get(), frame, resources, textures, report);
    const uint64_t invalid = (tracer ? tracer->invalid_rays() : 0) +
                             (scene_rays ? scene_rays->invalid_rays() : 0);
    if (invalid > 0) report.warnings.push_back(invalid_rays_warning(invalid));
    report.light_seconds =
        watch.seconds() - report.dice_seconds - report.trace_build_seconds;

    report.warnings.append(dice_services.take_warnings()); // the rays' hit shaders
    return gather_clouds(scene, plan.jobs, records, report);
}

/// The files the bake shaders name (output_files()) with how each is
/// named, for messages: "option -o \"x.ptc\"", "bake file \"a.ptc\"
/// (parameter \"filename\" of scene.rib:12: Surface \"bake_radiance_t\")".
std::vector<std::pair<std::string, std::string>> BakeJob::named_outputs() const {
    const Scene& scene = m_scene;
    const BakeOptions& options = m_options;
    const SceneShaders& shaders = *m_shaders;
    std::vector<std::pair<std::string, std::string>> files;
    for (std::size_t i = 0; i < scene.primitives.size(); ++i) {
        const ShaderInstance& shader = *shaders.surface_of[i];
        if (!program_uses(shader.program(), "bake3d")) continue;
        std::string file = bake_file(scene.primitives[i], shader, options);
        if (file.empty() || std::any_of(files.begin(), files.end(),
                                        [&](const auto& f) { return f.first == file; }))
            continue;
        std::string use = !options.output.empty()
                              ? "option -o \"" + file + "\""
                              : "bake file \"" + file + "\" (parameter \"filename\" of " +
                                    (shader.where().empty() ? scene.primitives[i].source
                                                            : shader.where()) +
                                    ")";
        files.emplace_back(std::move(file), std::move(use));
    }
    return files;
}

namespace {

/// Checks an output cloud's name before anything is baked: a .ptc or .ply
/// name, a writable folder, not a file of the job's (`files`).
void check_bake_output(JobFiles& files, const std::string& file, const std::string& use) {
    files.output(file, use);
    if (!has_extension_in(file, point_cloud_extensions()) && !writes_into_existing(file))
        throw ValueError(
            use + ": " +
            unknown_extension_text(file, "a point cloud file", point_cloud_extensions()));
    check_output_target(file);
}

} // namespace

std::vector<std::string> BakeJob::output_files() const {
    std::vector<std::string> files;
    for (auto& [file, use] : named_outputs()) files.push_back(std::move(file));
    return files;
}

std::vector<std::string> BakeJob::input_files() const {
    const std::vector<std::string> outputs = output_files();
    std::vector<std::string> files = m_scene.sources;
    for (const std::string& f : shader_input_files(*m_shaders))
        if (std::find(files.begin(), files.end(), f) == files.end() &&
            std::find(outputs.begin(), outputs.end(), f) == outputs.end())
            files.push_back(f);
    return files;
}

BakeReport BakeJob::run() const {
    const Scene& scene = m_scene;
    const BakeOptions& options = m_options;
    BakeReport report;
    Stopwatch watch;
    // Before any work: every cloud the shaders name is a .ptc or .ply in a
    // folder that exists, and none is a file the scene reads (the shaders'
    // files and lookups are checked in bake_clouds).
    JobFilesScope scope;
    JobFiles& job = scope.files();
    for (std::size_t i = 0; i < scene.sources.size(); ++i)
        job.input(scene.sources[i], i < scene.source_uses.size()
                                        ? scene.source_uses[i]
                                        : "\"" + scene.sources[i] + "\"");
    std::vector<std::string> named;
    for (const auto& [file, use] : named_outputs()) {
        check_bake_output(job, file, use);
        named.push_back(file);
    }
    auto files = clouds(&report);
    // Files only the bake3d calls named (computed at run time).
    for (const auto& [path, cloud] : files)
        if (std::find(named.begin(), named.end(), path) == named.end())
            check_bake_output(job, path, "bake3d file \"" + path + "\"");
    const double before = watch.seconds();
    // Every cloud is written as a temporary first and all are put in place
    // together at the end, or none.
    {
        OutputSet outputs;
        for (auto& [path, cloud] : files) {
            ScopedStage stage("writing " + path);
            write_point_cloud(cloud, path, options.write);
        }
        outputs.commit();
    }
    report.write_seconds = watch.seconds() - before;
    if (options.progress) options.progress->finish();
    // Once the clouds are in place (the set is gone: the textures are put in
    // place by themselves).
    if (options.after_frame_makes) run_make_requests(scene, true);
    return report;
}

BakeReport bake_scene(const Scene& scene, const BakeOptions& options) {
    return BakeJob(scene, options).run();
}

std::vector<std::string> bake_output_files(const Scene& scene,
                                           const BakeOptions& options) {
    return BakeJob(scene, options).output_files();
}

std::vector<std::string> bake_input_files(const Scene& scene,
                                          const BakeOptions& options) {
    return BakeJob(scene, options).input_files();
}

std::vector<std::pair<std::string, PointCloud>>
bake_clouds(const Scene& scene, const BakeOptions& options, BakeReport* report) {
    return BakeJob(scene, options).clouds(report);
}

MissingBakeFileError::MissingBakeFileError(const std::string& what) : ValueError(what) {}

SpacingMaterialError::SpacingMaterialError(std::string source)
    : UsageError(source +
                 ": the spacing from the mean free path needs a material for objects "
                 "baked without bake_sss_params"),
      m_source(std::move(source)) {}

} // namespace sss
