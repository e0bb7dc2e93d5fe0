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
#include <string>
#include <utility>
#include <vector>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec4.hpp>
#include <tbb/parallel_for.h>

#include "sss/dice/dice.h"
#include "sss/light/lights.h"
#include "sss/light/ray_tracer.h"
#include "sss/util/error.h"
#include "sss/util/frame_pattern.h"
#include "sss/util/progress.h"

namespace sss {
namespace {

enum class BakeShader { RadianceT, SssParams, Constant };

// Surfaces that only cast shadows are diced this many times coarser (edge
// length) than baked ones: 1/64 of the triangles, and the chord error of a
// curved occluder stays a small fraction of its size.
constexpr double kOccluderCoarsening = 8.0;

std::optional<BakeShader> bake_shader_kind(const std::string& name) {
    if (name == "bake_radiance_t") return BakeShader::RadianceT;
    if (name == "bake_sss_params") return BakeShader::SssParams;
    if (name == "bake_constant") return BakeShader::Constant;
    return std::nullopt;
}

// Channels a bake shader can write, besides _area.
std::vector<std::string> produced_channels(BakeShader kind) {
    switch (kind) {
    case BakeShader::RadianceT:
        return {"_radiance_t"};
    case BakeShader::SssParams:
        return {"_radiance_t", "_albedo", "_diffusemeanfreepath"};
    case BakeShader::Constant:
        return {"_radiance_t"};
    }
    return {};
}

std::vector<std::string> split_channel_list(const std::string& text) {
    std::vector<std::string> out;
    std::string cur;
    for (char c : text) {
        if (c == ',' || c == ' ' || c == '\t') {
            if (!cur.empty()) out.push_back(cur);
            cur.clear();
        } else {
            cur += c;
        }
    }
    if (!cur.empty()) out.push_back(cur);
    return out;
}

// What one baked primitive writes.
struct BakeJob {
    std::size_t prim = 0;
    BakeShader kind = BakeShader::RadianceT;
    std::string file;
    std::vector<std::string> channels; // without _area
    // Material parameters (bake_sss_params).
    glm::dvec3 albedo{0.0}, albedo2{0.0}, dmfp{0.0}, dmfp2{0.0};
    double noise_freq = 0.0;
    double kdt = 1.0;
};

// The DisplayChannel declaration of a channel, if any, must agree with what
// the bake shaders produce (colours; _area is a float).
void check_declared_type(const Scene& scene, const std::string& channel,
                         ChannelType produced, const std::string& where) {
    for (const auto& [name, type] : scene.options.display_channels) {
        if (name != channel) continue;
        std::string last = type;
        auto sp = last.find_last_of(" \t");
        if (sp != std::string::npos) last = last.substr(sp + 1);
        auto t = parse_channel_type(last);
        if (!t ||
            (*t != produced && !(produced == ChannelType::Color &&
                                 (*t == ChannelType::Point || *t == ChannelType::Vector ||
                                  *t == ChannelType::Normal))))
            throw ValueError(where + ": DisplayChannel declares " + channel + " as '" +
                             type + "' but the bake shader writes a " +
                             channel_type_name(produced));
    }
}

/// The file a baked primitive goes to: -o, else its shader's "filename".
std::string bake_file(const Primitive& prim, const BakeOptions& options,
                      std::optional<int> frame) {
    if (!options.output.empty()) return options.output;
    const ShaderRef& sh = *prim.attributes->surface;
    const std::string where = prim.source + ": " + sh.name;
    std::string name = sh.params.get_string("filename", "");
    if (name.empty()) throw MissingBakeFileError(where + " has no \"filename\"");
    return expand_frame_pattern(name, frame, where + " filename");
}

BakeJob make_job(const Scene& scene, std::size_t index, BakeShader kind,
                 const BakeOptions& options, std::optional<int> frame) {
    const Primitive& prim = scene.primitives[index];
    const ShaderRef& sh = *prim.attributes->surface;
    const std::string where = prim.source + ": " + sh.name;
    BakeJob job;
    job.prim = index;
    job.kind = kind;

    job.file = bake_file(prim, options, frame);

    const std::vector<std::string> produced = produced_channels(kind);
    std::string list = sh.params.get_string("displaychannels", "");
    std::vector<std::string> wanted = split_channel_list(list);
    if (wanted.empty()) wanted = produced;
    for (const std::string& c : wanted) {
        if (c == "_area") continue; // always written
        bool ok = kind == BakeShader::Constant ||
                  std::find(produced.begin(), produced.end(), c) != produced.end();
        if (!ok) {
            std::string names;
            for (const std::string& p : produced) names += p + ", ";
            throw ValueError(where + " cannot bake channel '" + c + "' (it bakes " +
                             names + "_area)");
        }
        if (std::find(job.channels.begin(), job.channels.end(), c) == job.channels.end())
            job.channels.push_back(c);
        check_declared_type(scene, c, ChannelType::Color, where);
    }
    check_declared_type(scene, "_area", ChannelType::Float, where);

    job.kdt = sh.params.get_float("Kdt", 1.0);
    if (!std::isfinite(job.kdt)) throw ValueError(where + ": Kdt is not finite");
    if (kind == BakeShader::SssParams) {
        MaterialSpec preset;
        preset.preset = sh.params.get_string("material", "marble");
        if (!find_material(preset.preset))
            throw ValueError(where + ": unknown material '" + preset.preset +
                             "' (known: " + material_names() + ")");
        glm::dvec3 a, d;
        preset.resolve_albedo_dmfp(a, d);
        job.albedo = sh.params.get_vec3("albedo", a);
        job.dmfp = sh.params.get_vec3("dmfp", d);
        job.albedo2 = sh.params.get_vec3("albedo2", job.albedo);
        job.dmfp2 = sh.params.get_vec3("dmfp2", job.dmfp);
        job.noise_freq = sh.params.get_float("noisefreq", 0.0);
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
        if (!(job.noise_freq >= 0.0 && std::isfinite(job.noise_freq)))
            throw ValueError(where + ": noisefreq must be >= 0");
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

void store_matrix(const Matrix4& m, std::array<float, 16>& out) {
    const double* p = glm::value_ptr(m);
    for (int i = 0; i < 16; ++i) out[i] = static_cast<float>(p[i]);
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

/// The scene's lights; their warnings and the shadow-casting ones counted
/// in the report.
std::vector<Light> bake_lights(const Scene& scene, BakeReport& report) {
    std::vector<std::string> light_warnings;
    std::vector<Light> lights = resolve_lights(scene, &light_warnings);
    for (const std::string& w : light_warnings) report.warnings.push_back(w);
    for (const Light& l : lights)
        if (l.shadows) ++report.shadow_lights;
    return lights;
}

/// What the bake does with each primitive.
struct BakePlan {
    std::vector<BakeJob> jobs;
    std::vector<int> job_of;    ///< per primitive: its job, or -1 when not baked
    std::vector<char> occluder; ///< per primitive: casts shadows
    /// Per job: the mean free path its points should respect, if known.
    std::vector<std::optional<double>> job_mfp;
};

/// Which primitives are baked (a job each, in primitive order) and which
/// only cast shadows; ValueError when nothing is baked.
BakePlan plan_jobs(const Scene& scene, const BakeOptions& options,
                   std::optional<int> frame, bool any_shadows, BakeReport& report) {
    BakePlan plan;
    plan.job_of.assign(scene.primitives.size(), -1);
    plan.occluder.assign(scene.primitives.size(), 0);
    for (std::size_t i = 0; i < scene.primitives.size(); ++i) {
        const Primitive& prim = scene.primitives[i];
        const auto& surf = prim.attributes->surface;
        std::optional<BakeShader> kind;
        if (surf) {
            kind = bake_shader_kind(surf->name);
            if (!kind && surf->name.rfind("bake", 0) == 0)
                report.warnings.push_back(
                    prim.source + ": unknown bake shader '" + surf->name +
                    "' (known: bake_radiance_t, bake_sss_params, "
                    "bake_constant); the object only casts shadows");
        }
        plan.occluder[i] = any_shadows && prim.attributes->visible_to("transmission");
        if (kind) {
            plan.job_of[i] = static_cast<int>(plan.jobs.size());
            plan.jobs.push_back(make_job(scene, i, *kind, options, frame));
        }
    }
    report.baked_primitives = plan.jobs.size();
    if (plan.jobs.empty())
        throw ValueError(
            scene.path +
            ": nothing to bake (no primitive has a bake shader: Surface "
            "\"bake_radiance_t\", \"bake_sss_params\" or \"bake_constant\")");
    return plan;
}

/// The mean free path each job's points should respect: the -material's,
/// else a bake_sss_params object's own (the smallest over its range).
/// SpacingMaterialError when the spacing from the mean free path leaves a job
/// without one.
void job_mean_free_paths(const Scene& scene, const BakeOptions& options,
                         std::optional<double> material_mfp, BakePlan& plan) {
    const std::vector<BakeJob>& jobs = plan.jobs;
    plan.job_mfp.assign(jobs.size(), material_mfp);
    for (std::size_t j = 0; j < jobs.size(); ++j) {
        const BakeJob& job = jobs[j];
        if (job.kind != BakeShader::SssParams) continue;
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

/// Dices what is baked or casts shadows; the rest is not needed.
std::vector<DicedSurface> dice_scene(const Scene& scene, const BakeOptions& options,
                                     const BakePlan& plan, double spacing) {
    DiceControl control;
    control.spacing = spacing;
    control.camera = &scene.options.camera;
    // Shadow-only surfaces need their shape, not micropolygon density.
    DiceControl occluder_control = control;
    occluder_control.coarsening = kOccluderCoarsening;
    std::vector<DiceRequest> requests;
    for (std::size_t i = 0; i < scene.primitives.size(); ++i) {
        const int job = plan.job_of[i];
        if (job < 0 && !plan.occluder[i]) continue;
        DiceRequest request{i, control};
        if (job < 0) {
            request.control = occluder_control;
        } else if (options.spacing_from_material && !options.material) {
            request.control.spacing = *plan.job_mfp[job] * options.mfp_fraction;
        }
        requests.push_back(request);
    }
    return dice_all(scene, requests);
}

/// Reports the micropolygon spacing, and warns about objects without area
/// and points farther apart than their mean free path.
void check_spacing(const Scene& scene, const BakePlan& plan,
                   const std::vector<DicedSurface>& diced, BakeReport& report) {
    report.min_spacing = std::numeric_limits<double>::infinity();
    report.max_spacing = 0.0;
    for (std::size_t j = 0; j < plan.jobs.size(); ++j) {
        const BakeJob& job = plan.jobs[j];
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

/// The irradiance at every micropolygon of every job (none for
/// bake_constant). Seeds are global point indices, so the result does not
/// depend on how the work is split between threads.
std::vector<std::vector<glm::dvec3>>
light_points(const Scene& scene, const BakeOptions& options,
             const std::vector<Light>& lights, const std::vector<BakeJob>& jobs,
             const std::vector<DicedSurface>& diced, const RayTracer* tracer) {
    const double extent = tracer ? tracer->scene_extent() : 0.0;
    std::size_t total_points = 0;
    std::vector<std::size_t> first_point(jobs.size());
    for (std::size_t j = 0; j < jobs.size(); ++j) {
        first_point[j] = total_points;
        total_points += diced[jobs[j].prim].size();
    }
    std::vector<std::vector<glm::dvec3>> irr(jobs.size());
    constexpr std::size_t kChunk = 256;
    struct Chunk {
        std::size_t job, begin, end;
    };
    std::vector<Chunk> chunks;
    for (std::size_t j = 0; j < jobs.size(); ++j) {
        const std::size_t n = diced[jobs[j].prim].size();
        if (jobs[j].kind == BakeShader::Constant) continue;
        irr[j].resize(n);
        for (std::size_t b = 0; b < n; b += kChunk)
            chunks.push_back({j, b, std::min(n, b + kChunk)});
    }
    std::atomic<std::size_t> done{0};
    tbb::parallel_for(std::size_t(0), chunks.size(), [&](std::size_t c) {
        const Chunk& ch = chunks[c];
        const BakeJob& job = jobs[ch.job];
        const DicedSurface& d = diced[job.prim];
        const double offset =
            shadow_ray_offset(d, ch.begin, ch.end, static_cast<double>(extent));
        irradiance_batch(lights, scene.primitives[job.prim].attributes->lights_on,
                         d.centers.data() + ch.begin, d.normals.data() + ch.begin,
                         ch.end - ch.begin, tracer, first_point[ch.job] + ch.begin,
                         offset, irr[ch.job].data() + ch.begin);
        if (options.progress)
            options.progress->update(done += ch.end - ch.begin, total_points);
    });
    return irr;
}

/// The output files, in first-use order, and the channels each gets.
struct OutputFiles {
    std::vector<std::string> paths;
    std::map<std::string, std::size_t> index; ///< path -> position in paths
    std::vector<std::vector<std::string>> channels;
};

/// Lists the files the jobs bake into, each with the union of its jobs'
/// channels (warning when they differ), and starts their reports.
OutputFiles plan_files(const Scene& scene, const std::vector<BakeJob>& jobs,
                       BakeReport& report) {
    OutputFiles files;
    for (const BakeJob& job : jobs) {
        auto [it, inserted] = files.index.emplace(job.file, files.paths.size());
        if (inserted) {
            files.paths.push_back(job.file);
            files.channels.push_back(job.channels);
            BakeFileReport fr;
            fr.path = job.file;
            report.files.push_back(fr);
        } else if (files.channels[it->second] != job.channels) {
            report.warnings.push_back(scene.primitives[job.prim].source +
                                      ": bakes other channels than the "
                                      "first object baked into " +
                                      job.file + "; missing channels are filled with 0");
            std::vector<std::string>& have = files.channels[it->second];
            for (const std::string& c : job.channels)
                if (std::find(have.begin(), have.end(), c) == have.end())
                    have.push_back(c);
        }
    }
    return files;
}

/// An empty cloud of `points` points with _area and the given colour
/// channels, and the camera's matrices and format.
PointCloud make_cloud(const Camera& cam, std::size_t points,
                      const std::vector<std::string>& channels) {
    PointCloud cloud;
    cloud.resize(points);
    cloud.add_channel("_area", ChannelType::Float);
    for (const std::string& c : channels) cloud.add_channel(c, ChannelType::Color);
    store_matrix(cam.world_to_camera, cloud.world_to_eye);
    store_matrix(cam.world_to_ndc(), cloud.world_to_ndc);
    cloud.format = {float(cam.xres), float(cam.yres), float(cam.pixel_aspect)};
    return cloud;
}

/// Writes one job's micropolygons into `cloud` from point `base` on: their
/// geometry, _area and the job's channels.
void write_job(const Primitive& prim, const BakeJob& job, const DicedSurface& d,
               const std::vector<glm::dvec3>& irr, std::size_t base, PointCloud& cloud,
               BakeFileReport& file_report) {
    file_report.points += d.size();
    file_report.objects.push_back(prim.source);
    Channel* area = cloud.find_channel("_area");
    const Matrix4 to_shader = glm::inverse(prim.attributes->surface->shader_to_world);
    for (std::size_t i = 0; i < d.size(); ++i) {
        cloud.positions[base + i] = d.centers[i];
        cloud.normals[base + i] = d.normals[i];
        cloud.radii[base + i] = d.radii[i];
        area->data[base + i] = d.areas[i];
        file_report.area += d.areas[i];
    }
    for (const std::string& name : job.channels) {
        Channel* ch = cloud.find_channel(name);
        for (std::size_t i = 0; i < d.size(); ++i) {
            glm::dvec3 v(0.0);
            if (job.kind == BakeShader::Constant) {
                v = d.colors.empty() ? prim.attributes->color : glm::dvec3(d.colors[i]);
            } else if (name == "_radiance_t") {
                v = job.kdt * irr[i];
            } else {
                double t = 0.0;
                if (job.noise_freq > 0.0) {
                    glm::dvec3 ps =
                        glm::dvec3(to_shader * glm::dvec4(glm::dvec3(d.centers[i]), 1.0));
                    t = noise3(ps * job.noise_freq);
                }
                v = name == "_albedo" ? glm::mix(job.albedo, job.albedo2, t)
                                      : glm::mix(job.dmfp, job.dmfp2, t);
            }
            for (int k = 0; k < 3; ++k) {
                float x = static_cast<float>(v[k]);
                if (!std::isfinite(x))
                    throw ValueError(prim.source + ": " + name +
                                     " is not finite at micropolygon " +
                                     std::to_string(i));
                ch->data[(base + i) * 3 + k] = x;
            }
        }
    }
}

/// The point clouds by output file, in first-use order: every job's points
/// in primitive order.
std::vector<std::pair<std::string, PointCloud>>
gather_clouds(const Scene& scene, const std::vector<BakeJob>& jobs,
              const std::vector<DicedSurface>& diced,
              const std::vector<std::vector<glm::dvec3>>& irr, BakeReport& report) {
    const OutputFiles out = plan_files(scene, jobs, report);
    std::vector<std::pair<std::string, PointCloud>> files;
    for (std::size_t f = 0; f < out.paths.size(); ++f) {
        std::size_t n = 0;
        for (const BakeJob& job : jobs)
            if (out.index.at(job.file) == f) n += diced[job.prim].size();
        files.emplace_back(out.paths[f],
                           make_cloud(scene.options.camera, n, out.channels[f]));
    }
    std::vector<std::size_t> fill(files.size(), 0);
    for (std::size_t j = 0; j < jobs.size(); ++j) {
        const BakeJob& job = jobs[j];
        const std::size_t f = out.index.at(job.file);
        const DicedSurface& d = diced[job.prim];
        write_job(scene.primitives[job.prim], job, d, irr[j], fill[f], files[f].second,
                  report.files[f]);
        fill[f] += d.size();
    }
    for (std::size_t f = 0; f < files.size(); ++f) {
        for (const Channel& c : files[f].second.channels)
            report.files[f].channels.push_back(std::string(channel_type_name(c.type)) +
                                               " " + c.name);
    }
    return files;
}

} // namespace

double material_mean_free_path(const MaterialSpec& material) {
    material.validate();
    return mfp_mm(material, nullptr, nullptr) * material.unitlength;
}

std::vector<std::pair<std::string, PointCloud>>
bake_clouds(const Scene& scene, const BakeOptions& options, BakeReport* report_out) {
    BakeReport local;
    BakeReport& report = report_out ? *report_out : local;
    Stopwatch watch;
    const std::optional<int> frame = options.frame ? options.frame : scene.options.frame;

    const BakeSpacing spacing = resolve_spacing(options);
    const std::vector<Light> lights = bake_lights(scene, report);
    const bool any_shadows = std::any_of(lights.begin(), lights.end(),
                                         [](const Light& l) { return l.shadows; });
    BakePlan plan = plan_jobs(scene, options, frame, any_shadows, report);
    job_mean_free_paths(scene, options, spacing.material_mfp, plan);

    const std::vector<DicedSurface> diced =
        dice_scene(scene, options, plan, spacing.spacing);
    report.dice_seconds = watch.seconds();

    check_spacing(scene, plan, diced, report);
    const std::unique_ptr<RayTracer> tracer =
        build_occluders(scene, plan, diced, any_shadows, report);
    report.trace_build_seconds = watch.seconds() - report.dice_seconds;

    const std::vector<std::vector<glm::dvec3>> irr =
        light_points(scene, options, lights, plan.jobs, diced, tracer.get());
    report.light_seconds =
        watch.seconds() - report.dice_seconds - report.trace_build_seconds;

    return gather_clouds(scene, plan.jobs, diced, irr, report);
}

std::vector<std::string> bake_output_files(const Scene& scene,
                                           const BakeOptions& options) {
    const std::optional<int> frame = options.frame ? options.frame : scene.options.frame;
    std::vector<std::string> files;
    for (const Primitive& prim : scene.primitives) {
        const auto& surf = prim.attributes->surface;
        if (!surf || !bake_shader_kind(surf->name)) continue;
        std::string file = bake_file(prim, options, frame);
        if (std::find(files.begin(), files.end(), file) == files.end())
            files.push_back(std::move(file));
    }
    return files;
}

BakeReport bake_scene(const Scene& scene, const BakeOptions& options) {
    BakeReport report;
    Stopwatch watch;
    auto files = bake_clouds(scene, options, &report);
    const double before = watch.seconds();
    for (auto& [path, cloud] : files) write_point_cloud(cloud, path, options.write);
    report.write_seconds = watch.seconds() - before;
    if (options.progress) options.progress->finish();
    return report;
}

MissingBakeFileError::MissingBakeFileError(const std::string& what) : ValueError(what) {}

SpacingMaterialError::SpacingMaterialError(std::string source)
    : UsageError(source +
                 ": the spacing from the mean free path needs a material for objects "
                 "baked without bake_sss_params"),
      m_source(std::move(source)) {}

} // namespace sss
