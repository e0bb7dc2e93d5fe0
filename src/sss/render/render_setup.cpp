// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file render_setup.cpp
/// The phases of render_image before the tiles (render.cpp): the camera, the
/// shaders and the AOVs, the surfaces to dice, the dicing with its memory
/// estimate, and the ray tracers.

#include "render_internal.h"

namespace sss::render_detail {

/// Whether a PixelFilter's weights can sum to about zero over a pixel's
/// samples: catmull-rom (negative from r = 1 on), sinc wider than 2 pi, and
/// any filter narrower than a pixel (it can miss every sample of a pixel).
/// The gaussian 2 x 2 and every other filter at least 1 pixel wide without
/// negative lobes give each sample in a pixel a positive weight for it.
bool needs_nearest_fallback(const PixelFilterSpec& spec) {
    if (spec.xwidth < 1.0 || spec.ywidth < 1.0) return true;
    if (spec.name == "catmull-rom" || spec.name == "catmullrom") return true;
    return spec.name == "sinc" && std::max(spec.xwidth, spec.ywidth) > 2.0 * kPi;
}

/// The camera with the image size overrides, the pixel samples, the camera
/// rays and the pixel size per unit of depth; ValueError (UsageError for a
/// half-given override) on values that cannot render.
void setup_depth(Renderer& job, const Scene& scene) {
    for (const DisplaySpec& d : scene.options.displays)
        job.opaque_depth = job.opaque_depth || display_is_depth_map(d);
    const auto limits = scene.options.groups.find("limits");
    if (limits == scene.options.groups.end()) return;
    const Param* t = limits->second.find("zthreshold");
    if (!t || t->numbers.empty()) return;
    for (int c = 0; c < 3; ++c) {
        const double v =
            t->numbers[std::min<std::size_t>(std::size_t(c), t->numbers.size() - 1)];
        if (std::isfinite(v)) job.zthreshold[c] = v;
    }
}

void setup_camera(Renderer& job, const Scene& scene, const RenderJobOptions& options) {
    job.scene = &scene;
    job.camera = scene.options.camera;
    if (options.xres > 0 || options.yres > 0) {
        if (!(options.xres > 0 && options.yres > 0))
            throw UsageError("image size overrides need both x and y resolutions");
        job.camera.xres = options.xres;
        job.camera.yres = options.yres;
    }
    if (job.camera.xres <= 0 || job.camera.yres <= 0)
        throw ValueError("image size " + std::to_string(job.camera.xres) + " x " +
                         std::to_string(job.camera.yres) + " has no pixels");
    job.nx = scene.options.pixel_samples[0];
    job.ny = scene.options.pixel_samples[1];
    if (options.pixel_samples > 0) job.nx = job.ny = options.pixel_samples;
    if (job.nx < 1 || job.ny < 1 || job.nx > 1024 || job.ny > 1024)
        throw ValueError("pixel samples must lie in [1, 1024]");
    // Motion blur: the camera rays start from the camera at the shutter's
    // open time; a moving camera moves them to each sample's time.
    Camera& cam = job.camera;
    job.motion_blur = cam.motion_blur();
    job.shutter_open = cam.shutter_open;
    job.shutter_close = cam.shutter_close;
    if (!cam.motion_times.empty()) {
        cam.world_to_camera =
            matrix_at(cam.motion_times, cam.motion_world_to_camera, cam.shutter_open);
        if (job.motion_blur) {
            job.camera_times = cam.motion_times;
            job.world_to_camera_keys = cam.motion_world_to_camera;
        }
    }
    job.rays.emplace(job.camera);
    // Shading at the ShadingRate: a lattice point is shaded once for every
    // sample that hits it, which holds while the surfaces and the camera
    // stand still over the shutter (with motion blur each sample is shaded
    // at its own time).
    job.shading_cache = !options.pixel_shading && !job.motion_blur;
    job.world_to_ndc = job.camera.world_to_ndc();
    job.smooth_shading.assign(scene.primitives.size(), 0);
    for (std::size_t i = 0; i < scene.primitives.size(); ++i)
        job.smooth_shading[i] =
            attributes_of(scene.primitives[i]).shading_interpolation == "smooth";
    const PixelFilterSpec& filter = scene.options.pixel_filter;
    job.filter.emplace(filter);
    job.reach_x = job.filter->reach_x();
    job.reach_y = job.filter->reach_y();
    if (job.reach_x > kMaxReach || job.reach_y > kMaxReach)
        throw ValueError("PixelFilter widths must be at most 16 pixels");
    job.nearest_fallback = needs_nearest_fallback(filter);
    // pixel_size_at is linear in the depth beyond hither (perspective).
    const double d = job.camera.perspective ? std::max(1.0, job.camera.near_clip) : 1.0;
    job.pixel_per_depth =
        job.camera.pixel_size_at(d) / (job.camera.perspective ? d : 1.0);
    const glm::dmat3 linear(job.camera.world_to_camera);
    job.normal_to_camera = glm::transpose(glm::inverse(linear));
    const glm::dmat3 to_world = glm::inverse(linear);
    job.camera_x = glm::normalize(to_world * glm::dvec3(1, 0, 0));
    job.camera_y = glm::normalize(to_world * glm::dvec3(0, 1, 0));
}

std::vector<double> dice_times(const Camera& camera, const Primitive& prim) {
    if (!prim.motion) return {};
    const double open = camera.shutter_open, close = camera.shutter_close;
    if (!camera.motion_blur()) return {open};
    std::vector<double> inside;
    for (double t : prim.motion->times())
        if (t > open && t < close) inside.push_back(t);
    // Even steps through every motion sample inside the shutter, when there
    // are such steps; else four per interval.
    int segments = static_cast<int>(inside.size()) + 1;
    for (double t : inside) {
        const double f = (t - open) / (close - open) * segments;
        if (std::abs(f - std::round(f)) > 1e-6) {
            segments = std::min(32, 4 * segments);
            break;
        }
    }
    std::vector<double> out(static_cast<std::size_t>(segments) + 1);
    for (int k = 0; k <= segments; ++k)
        out[std::size_t(k)] =
            k == segments ? close : open + (close - open) * k / segments;
    return out;
}

void move_camera_ray(const Renderer& job, double time, ShadowRay& ray) {
    ray.time = static_cast<float>(time);
    if (job.camera_times.empty()) return;
    const double t = job.shutter_open + (job.shutter_close - job.shutter_open) * time;
    const glm::dmat4 to_world =
        glm::inverse(matrix_at(job.camera_times, job.world_to_camera_keys, t));
    const glm::dmat4 move = to_world * job.camera.world_to_camera;
    const glm::dvec3 o = glm::dvec3(move * glm::dvec4(glm::dvec3(ray.origin), 1.0));
    const glm::dvec3 d = glm::dvec3(move * glm::dvec4(glm::dvec3(ray.direction), 0.0));
    const double len = glm::length(d);
    if (!(len > 0.0) || !std::isfinite(len)) return;
    ray.origin = glm::vec3(o);
    ray.direction = glm::vec3(d / len);
    // Distances along the ray scale with the direction (a camera that grows).
    ray.tnear = static_cast<float>(ray.tnear * len);
    if (std::isfinite(ray.tfar)) ray.tfar = static_cast<float>(ray.tfar * len);
}

namespace {

/// The built-in layers: the output variables of the standard shaders, under
/// the layer names a Display asks for them by ("diffuse" is `_diffuse`).
struct StandardAov {
    const char* variable;
    const char* layer;
    int floats;
    float fallback;
};
constexpr StandardAov kStandardAovs[] = {{"_ambient", "ambient", 3, 0.0f},
                                         {"_diffuse", "diffuse", 3, 0.0f},
                                         {"_specular", "specular", 3, 0.0f},
                                         {"_sss", "sss", 3, 0.0f},
                                         {"_occlusion", "occlusion", 1, 1.0f}};

/// A name a Display mode or a DisplayChannel asks for (its last word: the
/// type of an inline declaration is the shader's business).
struct AovRequest {
    std::string name;
    std::string by;   ///< "display '+x.tif' (scene.rib:9)", or "" for DisplayChannel
    std::string mode; ///< the Display's mode
};

std::vector<AovRequest> requested_outputs(const Scene& scene) {
    std::vector<AovRequest> names;
    const auto add = [&](std::string item, const std::string& by,
                         const std::string& mode) {
        const auto b = item.find_first_not_of(" \t");
        if (b == std::string::npos) return;
        item = item.substr(b, item.find_last_not_of(" \t") - b + 1);
        const auto space = item.find_last_of(" \t");
        if (space != std::string::npos) item = item.substr(space + 1);
        for (AovRequest& r : names)
            if (r.name == item) {
                if (r.by.empty()) r.by = by, r.mode = mode;
                return;
            }
        names.push_back({item, by, mode});
    };
    for (const DisplaySpec& d : scene.options.displays) {
        if (display_writes_nothing(d)) continue;
        const std::string by = "display '" + std::string(d.additional ? "+" : "") +
                               d.name + "'" +
                               (d.where.empty() ? "" : " (" + d.where + ")");
        std::size_t start = 0;
        while (true) {
            const std::size_t comma = d.mode.find(',', start);
            add(d.mode.substr(start, comma == std::string::npos ? std::string::npos
                                                                : comma - start),
                by, d.mode);
            if (comma == std::string::npos) break;
            start = comma + 1;
        }
    }
    for (const auto& [name, type] : scene.options.display_channels) add(name, "", "");
    return names;
}

/// The output variable `name` of the first surface shader that declares it
/// with a type an image can hold (float or a 3-component type); null if none.
const Symbol* shader_output(const SceneShaders& shaders, const std::string& name) {
    for (const auto& shader : shaders.surfaces) {
        const Program& program = shader->program();
        const int index = program.find(name);
        if (index < 0) continue;
        const Symbol& symbol = program.symbols[static_cast<std::size_t>(index)];
        if (symbol.kind != SymbolKind::OutputParam || symbol.type.is_array() ||
            symbol.type.type == ShadingType::String)
            continue;
        const int floats = shading_type_floats(symbol.type.type);
        if (floats == 1 || floats == 3) return &symbol;
    }
    return nullptr;
}

} // namespace

std::vector<Aov> plan_aovs(const Scene& scene, const SceneShaders& shaders) {
    std::vector<Aov> aovs;
    std::string layers;
    for (const StandardAov& s : kStandardAovs)
        layers += std::string(layers.empty() ? "" : ", ") + s.layer;
    for (const AovRequest& request : requested_outputs(scene)) {
        const std::string& name = request.name;
        std::string lower = name;
        for (char& c : lower) c = char(std::tolower(static_cast<unsigned char>(c)));
        static const char* const reserved[] = {"rgba", "rgb",   "a",  "z",
                                               "rgbz", "rgbaz", "ci", "oi"};
        if (std::find(std::begin(reserved), std::end(reserved), lower) !=
            std::end(reserved))
            continue;
        Aov a;
        a.variable = name;
        a.layer = name;
        // The user's own output variable first: its name and its declared type.
        if (const Symbol* symbol = shader_output(shaders, name)) {
            a.floats = shading_type_floats(symbol->type.type);
            aovs.push_back(a);
            continue;
        }
        const StandardAov* standard = nullptr;
        for (const StandardAov& s : kStandardAovs)
            if (name == s.layer) standard = &s;
        if (standard) {
            a.variable = standard->variable;
            a.floats = standard->floats;
            a.as_rgb = standard->floats == 1;
            a.fallback = standard->fallback;
            aovs.push_back(a);
            continue;
        }
        // A DisplayChannel alone only declares a channel (for bake3d, say).
        if (request.by.empty()) continue;
        throw ValueError(request.by + ": mode '" + request.mode + "' names '" + name +
                         "', which no surface shader of the scene outputs (as an output "
                         "parameter) and which is not a built-in layer (" +
                         layers + ")");
    }
    int offset = 4;
    for (Aov& a : aovs) {
        a.offset = offset;
        offset += a.as_rgb ? 3 : a.floats;
    }
    return aovs;
}

/// Shaders, lights, AOVs and shading resources (textures, brick maps and
/// point clouds are opened on first use); true when some light or shader
/// traces shadow or occlusion rays.
bool resolve_shading(Renderer& job, const Scene& scene, std::optional<int> frame,
                     RenderReport& report) {
    if (JobFiles* files = JobFiles::current()) record_shader_inputs(*files, job.shaders);
    for (const std::string& w : job.shaders.warnings) report.warnings.push_back(w);
    job.resources = std::make_unique<ShadingResources>();
    job.textures = std::make_unique<TextureLibrary>();
    job.textures->set_search_path(search_path(scene, "texture"));
    job.services = std::make_unique<RenderServices>(scene, frame, *job.textures);
    job.aovs = plan_aovs(scene, job.shaders);
    job.derivatives.resize(scene.primitives.size());
    job.parametric.resize(scene.primitives.size());
    for (std::size_t i = 0; i < scene.primitives.size(); ++i) {
        const Program& program = job.shaders.surface_of[i]->program();
        job.derivatives[i] = program_uses_derivatives(program);
        job.parametric[i] = program_reads_parametric(program);
    }
    job.values = 4;
    for (const Aov& a : job.aovs) job.values += a.as_rgb ? 3 : a.floats;
    bool any_shadows = false;
    for (const char* op :
         {"shadow", "transmission", "occlusion", "trace", "indirectdiffuse", "gather"})
        any_shadows = any_shadows || job.shaders.uses(op);
    for (const auto& s : job.shaders.surfaces)
        job.any_rays = job.any_rays || program_traces_rays(s->program());
    for (const auto* list : {&job.shaders.lights, &job.shaders.volumes})
        for (const auto& s : *list)
            job.any_rays = job.any_rays || program_traces_rays(s->program());
    if (job.shaders.imager)
        job.any_rays = job.any_rays || program_traces_rays(job.shaders.imager->program());
    return any_shadows || job.any_rays;
}

/// What is diced: everything the camera sees, and everything that casts
/// shadows when some light or shader traces them. Returns those primitives;
/// *separate_shadows tells whether shadows see other surfaces than the camera.
std::vector<std::size_t> plan_surfaces(Renderer& job, bool any_shadows,
                                       bool* separate_shadows) {
    const Scene& scene = *job.scene;
    const std::size_t count = scene.primitives.size();
    job.surfaces.resize(count);
    std::vector<std::size_t> to_dice;
    *separate_shadows = false;
    for (std::size_t i = 0; i < count; ++i) {
        Surface& s = job.surfaces[i];
        s.camera = visible_to(scene.primitives[i], "camera");
        s.shadows = any_shadows && visible_to(scene.primitives[i], "transmission");
        s.secondary = job.any_rays && (visible_to(scene.primitives[i], "diffuse") ||
                                       visible_to(scene.primitives[i], "specular"));
        if (s.camera || s.shadows || s.secondary) to_dice.push_back(i);
        if (s.camera != s.shadows && any_shadows) *separate_shadows = true;
    }
    return to_dice;
}

// Memory beyond the diced surfaces (DiceEstimate::surface_bytes), measured
// with the peak resident size of the teapot scene at 600 x 450 to 4800 x
// 3600 pixels (docs/render.md, "Memory").
/// Per estimated triangle in one Embree tracer (vertex and index copies,
/// BVH with spatial splits, the builder's peak).
constexpr double kTracedTriangleBytes = 80.0;
/// Per pixel and value of a pixel (RGBA, the AOVs, filter weights): the
/// filter sums, the image and its copy for the output file.
constexpr double kPixelValueBytes = 12.0;

/// Estimates the dicing before it allocates anything: Limit::
/// PrimitiveMicropolygons and Limit::SceneMicropolygons (LimitError), then
/// the memory the diced surfaces, their colours and the ray tracers holding
/// them need (OutOfMemoryError naming what reduces it).
void check_dicing(const Renderer& job, const std::vector<DiceRequest>& requests,
                  bool separate_shadows) {
    const Scene& scene = *job.scene;
    const std::string name = scene.path.empty() ? std::string("the scene") : scene.path;
    const std::vector<DiceEstimate> estimates = estimate_dicing(scene, requests, name);
    double triangles = 0.0, bytes = 0.0;
    for (std::size_t k = 0; k < requests.size(); ++k) {
        const std::size_t i = requests[k].primitive;
        const Surface& s = job.surfaces[i];
        const DiceEstimate& e = estimates[k];
        const bool colors = scene.primitives[i].params.has("Cs");
        triangles += e.triangles;
        bytes += e.surface_bytes(colors, requests[k].control.grids);
        if (colors) bytes += 12.0 * e.triangles;
        const int tracers = (s.camera ? 1 : 0) + (separate_shadows && s.shadows ? 1 : 0) +
                            (job.any_rays && (s.shadows || s.secondary) ? 1 : 0);
        bytes += tracers * kTracedTriangleBytes * e.triangles;
    }
    const double pixels = static_cast<double>(job.camera.xres) * job.camera.yres;
    bytes += pixels * kPixelValueBytes * (job.values + 2);
    char what[160];
    std::snprintf(what, sizeof what,
                  "rendering %s (about %.3g triangles, %d x %d pixels)", name.c_str(),
                  triangles, job.camera.xres, job.camera.yres);
    check_memory(static_cast<uint64_t>(std::min(bytes, 1.8e19)), what,
                 "render a smaller image (-res) or raise ShadingRate above 16 (render "
                 "dices triangles of max(4, sqrt(ShadingRate)) pixels)");
}

/// Dices the primitives `to_dice` into triangles of about kEdgePixels, with
/// unit vertex normals and per-triangle colours.
void dice_surfaces(Renderer& job, const std::vector<std::size_t>& to_dice,
                   bool separate_shadows, RenderReport& report) {
    const Scene& scene = *job.scene;
    // Displacement shaders run while dicing, before the ray tracers are
    // built: camera and shadow rays see the displaced surfaces.
    Displacer displacer(scene, job.shaders, *job.resources, *job.services);
    // Edges of kEdgePixels whatever the ShadingRate: coarser than its
    // micropolygons through the coarsening, finer through a camera with
    // proportionally more pixels over the same screen window.
    std::vector<Camera> dice_cameras(to_dice.size()); // live through dice_all
    std::vector<DiceRequest> requests(to_dice.size());
    for (std::size_t k = 0; k < to_dice.size(); ++k) {
        const Primitive& prim = scene.primitives[to_dice[k]];
        const double rate = attributes_of(prim).shading_rate;
        const double edge = std::sqrt(std::max(rate, 1e-12)); // pixels
        Camera& dice_camera = dice_cameras[k];
        dice_camera = job.camera;
        DiceControl control;
        control.camera = &dice_camera;
        if (edge <= kEdgePixels) {
            control.coarsening = kEdgePixels / edge;
        } else {
            dice_camera.screen_window = job.camera.resolved_screen_window();
            dice_camera.xres = static_cast<int>(
                std::min(1e9, std::round(job.camera.xres * edge / kEdgePixels)));
        }
        control.displace = displacer.hook(to_dice[k]);
        control.grids = job.parametric[to_dice[k]] != 0;
        control.depth_maps = [textures = job.textures.get()](const std::string& name) {
            return textures->depth_grid(name);
        };
        requests[k] = {to_dice[k], control, dice_times(job.camera, prim)};
    }
    ScopedStage stage("dicing " +
                      (scene.path.empty() ? std::string("the scene") : scene.path));
    check_dicing(job, requests, separate_shadows);
    std::vector<DicedSurface> diced =
        dice_all(scene, requests, [&](std::size_t i, DicedSurface& d) {
            const auto unit = [](std::vector<glm::vec3>& normals) {
                for (glm::vec3& n : normals) {
                    const float len = glm::length(n);
                    if (len > 0.0f && std::isfinite(len)) n /= len;
                }
            };
            unit(d.vertex_normals);
            for (std::vector<glm::vec3>& step : d.step_normals) unit(step);
            // Hits use the vertices' (u, v, s, t) only: free the centres'.
            for (auto* a : {&d.u, &d.v, &d.du, &d.dv, &d.s, &d.t})
                std::vector<float>().swap(*a);
            std::vector<glm::vec3>().swap(d.dPdu);
            std::vector<glm::vec3>().swap(d.dPdv);
            std::vector<DicedGrid>().swap(d.grids);
            job.surfaces[i].triangle_colors = triangle_colors(d);
        });
    for (std::size_t i : to_dice) job.surfaces[i].diced = std::move(diced[i]);
    for (const std::string& w : displacer.warnings()) report.warnings.push_back(w);
}

/// The ray tracers: one when the camera and shadows see the same surfaces,
/// else one each; and the scene extent.
void build_tracers(Renderer& job, const std::vector<std::size_t>& to_dice,
                   bool any_shadows, bool separate_shadows, RenderReport& report) {
    job.camera_tracer = std::make_unique<RayTracer>();
    if (separate_shadows) job.shadow_tracer = std::make_unique<RayTracer>();
    for (std::size_t i : to_dice) {
        const Surface& s = job.surfaces[i];
        if (s.diced.triangles.empty()) continue;
        report.triangles += s.diced.triangles.size() / 3;
        const auto* steps = s.diced.moving() ? &s.diced.step_vertices : nullptr;
        if (s.camera) {
            job.camera_tracer->add_mesh(s.diced.vertices, s.diced.triangles, steps);
            job.camera_primitive.push_back(static_cast<uint32_t>(i));
        }
        if (separate_shadows && s.shadows)
            job.shadow_tracer->add_mesh(s.diced.vertices, s.diced.triangles, steps);
    }
    job.camera_tracer->commit();
    if (job.shadow_tracer) job.shadow_tracer->commit();
    if (any_shadows)
        job.occluders =
            separate_shadows ? job.shadow_tracer.get() : job.camera_tracer.get();
    job.extent = std::max(job.camera_tracer->scene_extent(),
                          job.shadow_tracer ? job.shadow_tracer->scene_extent() : 0.0f);
}

} // namespace sss::render_detail
