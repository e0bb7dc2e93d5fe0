// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file render.cpp
/// The final renderer (docs/render.md): every primitive is diced into
/// triangles with vertex normals and ray traced with Embree; camera samples
/// are stratified and jittered per pixel by a hash, shaded by the scene's RSL
/// shaders (sss/shading) in batches of hits, composited front to back through
/// semi-transparent surfaces and reconstructed with the PixelFilter (RenderMan's
/// gaussian 2 x 2 by default). DepthOfField moves the rays' origins onto a
/// thin lens.
/// The image holds the beauty, Z and the AOVs; render_scene writes the Displays.
/// render_image runs its phases in order (camera, lights and shaders,
/// surfaces, dicing, ray tracers, tiles, pixels), each a function: the ones
/// before the tiles are in render_setup.cpp (render_internal.h).
///
/// Determinism: a sample's position and every random decision in it depend
/// only on (pixel, sample index, surface layer), tiles splat their samples
/// into private buffers, and the buffers are added up in tile order, so the
/// image is the same for every thread count.

#include "render_internal.h"

namespace sss {

using namespace render_detail;

namespace {

/// Image channel names, in order: beauty, Z, then each AOV (a colour as
/// layer.R/G/B, a float as one channel, occlusion as occlusion.R/G/B).
std::vector<std::string> image_channels(const std::vector<Aov>& aovs) {
    std::vector<std::string> names = {"R", "G", "B", "A", "Z"};
    for (const Aov& aov : aovs) {
        if (aov.floats == 3 || aov.as_rgb) {
            for (const char* c : {"R", "G", "B"}) names.push_back(aov.layer + "." + c);
        } else {
            names.push_back(aov.layer);
        }
    }
    return names;
}

/// The image cut into kTile x kTile tiles, in row order.
struct TileGrid {
    int width = 0, height = 0;
    int tiles_x = 0, tiles_y = 0;

    TileGrid(int w, int h)
        : width(w), height(h), tiles_x((w + kTile - 1) / kTile),
          tiles_y((h + kTile - 1) / kTile) {}
    std::size_t count() const { return std::size_t(tiles_x) * tiles_y; }
    int x0(std::size_t t) const { return static_cast<int>(t % tiles_x) * kTile; }
    int y0(std::size_t t) const { return static_cast<int>(t / tiles_x) * kTile; }
};

/// Floats per pixel of the filter sums: the values, the weight sum and,
/// for nearest_fallback filters, the sum of the weights' magnitudes.
int filter_slots(const Renderer& job) {
    return job.values + (job.nearest_fallback ? 2 : 1);
}

/// The camera samples of the pixels [x0, x1) x [y0, y1), pixel by pixel in
/// row order: stratified and jittered positions, lens positions (depth of
/// field) and times (motion blur) of their own strata.
std::vector<CameraSample> tile_samples(const Renderer& job, int x0, int y0, int x1,
                                       int y1) {
    const bool lens = job.camera.depth_of_field();
    std::vector<CameraSample> samples;
    samples.reserve(std::size_t(x1 - x0) * (y1 - y0) * job.nx * job.ny);
    for (int py = y0; py < y1; ++py) {
        for (int px = x0; px < x1; ++px) {
            const uint64_t pixel_key =
                detail::splitmix64((uint64_t(uint32_t(py)) << 32) | uint32_t(px));
            // Lens positions: strata of their own, paired with the pixel
            // strata by a per-pixel shuffle (no extra numbers without DOF).
            const std::vector<glm::dvec2> lens_uv =
                lens ? lens_square_samples(pixel_key, job.nx, job.ny)
                     : std::vector<glm::dvec2>();
            // Times over the shutter: strata of their own, shuffled per pixel.
            const std::vector<double> times =
                job.motion_blur ? time_samples(pixel_key, job.nx * job.ny)
                                : std::vector<double>();
            for (int j = 0; j < job.ny; ++j) {
                for (int i = 0; i < job.nx; ++i) {
                    CameraSample cs;
                    cs.key =
                        detail::splitmix64(pixel_key + uint64_t(j * job.nx + i) *
                                                           detail::kSplitMixIncrement);
                    cs.sx = px + (i + detail::unit_double(cs.key)) / job.nx;
                    cs.sy = py + (j + detail::unit_double(detail::splitmix64(cs.key))) /
                                     job.ny;
                    const glm::dvec2 uv =
                        lens ? lens_uv[std::size_t(j * job.nx + i)] : glm::dvec2(0.5);
                    cs.ray = job.rays->ray(cs.sx, cs.sy, concentric_disk(uv.x, uv.y),
                                           &cs.units);
                    if (job.motion_blur)
                        move_camera_ray(job, times[std::size_t(j * job.nx + i)], cs.ray);
                    samples.push_back(cs);
                }
            }
        }
    }
    return samples;
}

/// Renders every tile: its camera samples go through the scene layer by
/// layer (each pass traces every live sample's ray to its next surface and
/// shades the hits in batches per primitive), then each splats into the
/// tile's buffer, which is job.reach_x (job.reach_y) pixels wider than the
/// tile on each side (the filter's reach), of filter_slots floats per pixel.
/// The nearest depth of its pixels goes to `depth`; for nearest_fallback
/// filters, each pixel's sample nearest to its centre goes to `nearest`
/// (job.values floats per pixel).
std::vector<std::vector<float>> render_tiles(Renderer& job, const TileGrid& grid,
                                             const RenderJobOptions& options,
                                             std::vector<float>& depth,
                                             std::vector<float>& nearest) {
    const int width = grid.width, height = grid.height;
    const std::size_t tiles = grid.count();
    const int slots = filter_slots(job);
    const int span_x = kTile + 2 * job.reach_x, span_y = kTile + 2 * job.reach_y;
    const int rx = job.reach_x, ry = job.reach_y;
    const PixelFilter& filter = *job.filter;
    if (job.nearest_fallback)
        nearest.assign(std::size_t(width) * height * job.values, 0.0f);
    std::vector<std::vector<float>> tile_sums(tiles);
    std::atomic<std::size_t> tiles_done{0};
    if (options.progress) options.progress->set_unit("tiles");
    tbb::enumerable_thread_specific<std::unique_ptr<ShadingContext>> contexts(
        [&] { return std::make_unique<ShadingContext>(*job.resources, *job.services); });
    tbb::parallel_for(std::size_t(0), tiles, [&](std::size_t t) {
        ShadingContext& context = *contexts.local();
        const uint64_t rays_before = context.rays_traced();
        const int x0 = grid.x0(t);
        const int y0 = grid.y0(t);
        const int x1 = std::min(width, x0 + kTile), y1 = std::min(height, y0 + kTile);
        std::vector<float>& sums = tile_sums[t];
        sums.assign(std::size_t(span_x) * span_y * slots, 0.0f);
        uint64_t camera_count = 0, bad_count = 0;

        // The tile's samples, pixel by pixel in row order.
        std::vector<CameraSample> samples = tile_samples(job, x0, y0, x1, y1);
        std::vector<float> values(samples.size() * job.values, 0.0f);
        std::vector<SurfaceHit> hits;
        ShadingCache cache;
        while (true) {
            trace_pass(job, samples, hits, camera_count);
            if (hits.empty() &&
                std::none_of(samples.begin(), samples.end(),
                             [](const CameraSample& c) { return c.active; }))
                break;
            if (job.shading_cache) {
                shade_pass_cached(job, context, hits, samples, values, cache);
            } else {
                job.shading_points += hits.size();
                shade_pass(job, context, hits, samples, values);
            }
        }

        std::size_t pixel_best = 0; // nearest_fallback: the pixel's nearest sample
        for (std::size_t s = 0; s < samples.size(); ++s) {
            const CameraSample& cs = samples[s];
            float* v = &values[s * job.values];
            v[3] = static_cast<float>(1.0 - (cs.trans.x + cs.trans.y + cs.trans.z) / 3.0);
            // A sample that went wrong numerically is dropped (black,
            // transparent) rather than spreading NaN through the filter.
            bool bad = false;
            for (int c = 0; c < job.values; ++c)
                if (!std::isfinite(v[c])) bad = true;
            if (bad) {
                std::fill(v, v + job.values, 0.0f);
                ++bad_count;
            }
            const int px = static_cast<int>(std::floor(cs.sx));
            const int py = static_cast<int>(std::floor(cs.sy));
            float& z = depth[std::size_t(py) * width + px];
            z = std::min(z, cs.depth);
            if (job.nearest_fallback) {
                // The pixel's samples come together, in order: at its first
                // one, find the one nearest to the centre (ties: the earlier).
                const std::size_t per_pixel = std::size_t(job.nx) * job.ny;
                if (s % per_pixel == 0) {
                    pixel_best = s;
                    double best_d = std::numeric_limits<double>::infinity();
                    for (std::size_t o = s; o < s + per_pixel; ++o) {
                        const double dx = samples[o].sx - (px + 0.5);
                        const double dy = samples[o].sy - (py + 0.5);
                        if (dx * dx + dy * dy < best_d) {
                            best_d = dx * dx + dy * dy;
                            pixel_best = o;
                        }
                    }
                }
                if (pixel_best == s)
                    std::copy(v, v + job.values,
                              &nearest[(std::size_t(py) * width + px) * job.values]);
            }
            // Splat into the pixels whose filter reaches the sample: up to
            // reach_x (reach_y) pixels on each side of its own.
            double wx[2 * kMaxReach + 1], wy[2 * kMaxReach + 1];
            for (int k = 0; k <= 2 * rx; ++k) {
                const int qx = px - rx + k;
                wx[k] = qx >= 0 && qx < width ? filter.weight_x(cs.sx - (qx + 0.5)) : 0.0;
            }
            for (int k = 0; k <= 2 * ry; ++k) {
                const int qy = py - ry + k;
                wy[k] =
                    qy >= 0 && qy < height ? filter.weight_y(cs.sy - (qy + 0.5)) : 0.0;
            }
            for (int ky = 0; ky <= 2 * ry; ++ky) {
                if (wy[ky] == 0.0) continue;
                for (int kx = 0; kx <= 2 * rx; ++kx) {
                    if (wx[kx] == 0.0) continue;
                    // Radial filters (catmull-rom) have no product form.
                    const float w = static_cast<float>(
                        filter.separable() ? wx[kx] * wy[ky]
                                           : filter.weight(cs.sx - (px - rx + kx + 0.5),
                                                           cs.sy - (py - ry + ky + 0.5)));
                    if (w == 0.0f) continue;
                    // Buffer cell of pixel (px - rx + kx, py - ry + ky).
                    float* acc =
                        &sums[(std::size_t(py - y0 + ky) * span_x + (px - x0 + kx)) *
                              slots];
                    for (int c = 0; c < job.values; ++c) acc[c] += w * v[c];
                    acc[job.values] += w;
                    if (job.nearest_fallback) acc[job.values + 1] += std::abs(w);
                }
            }
        }
        job.shadow_rays += context.rays_traced() - rays_before;
        uint64_t met = 0;
        for (const CameraSample& cs : samples) met += cs.layers > 0 ? 1 : 0;
        job.surface_samples += met;
        job.camera_rays += camera_count;
        job.bad_samples += bad_count;
        if (options.progress) options.progress->update(++tiles_done, tiles);
    });
    return tile_sums;
}

/// Adds the tiles up in a fixed order, the same sums for any thread count,
/// freeing each tile's buffer once added.
std::vector<float> add_tiles(const Renderer& job, const TileGrid& grid,
                             std::vector<std::vector<float>>& tile_sums) {
    const int width = grid.width, height = grid.height;
    const int slots = filter_slots(job);
    const int span_x = kTile + 2 * job.reach_x, span_y = kTile + 2 * job.reach_y;
    std::vector<float> sums(std::size_t(width) * height * slots, 0.0f);
    for (std::size_t t = 0; t < grid.count(); ++t) {
        const int x0 = grid.x0(t);
        const int y0 = grid.y0(t);
        const std::vector<float>& tile = tile_sums[t];
        for (int ty = 0; ty < span_y; ++ty) {
            const int py = y0 - job.reach_y + ty;
            if (py < 0 || py >= height) continue;
            for (int tx = 0; tx < span_x; ++tx) {
                const int px = x0 - job.reach_x + tx;
                if (px < 0 || px >= width) continue;
                const float* src = &tile[(std::size_t(ty) * span_x + tx) * slots];
                float* dst = &sums[(std::size_t(py) * width + px) * slots];
                for (int c = 0; c < slots; ++c) dst[c] += src[c];
            }
        }
        std::vector<float>().swap(tile_sums[t]);
    }
    return sums;
}

/// The image: filtered sums divided by their weights, and the depth. With
/// nearest_fallback filters, a pixel whose weights sum to less than 1e-3 of their
/// magnitudes takes its nearest sample instead (no division by about 0).
Image resolve_pixels(const Renderer& job, const TileGrid& grid,
                     const std::vector<float>& sums, const std::vector<float>& depth,
                     const std::vector<float>& nearest) {
    const int width = grid.width, height = grid.height;
    const int slots = filter_slots(job);
    Image image(width, height, image_channels(job.aovs));
    for (int py = 0; py < height; ++py) {
        for (int px = 0; px < width; ++px) {
            const float* s = &sums[(std::size_t(py) * width + px) * slots];
            float* out = image.pixel(px, py);
            const float weight = s[job.values];
            float inv = weight > 0.0f ? 1.0f / weight : 0.0f;
            if (job.nearest_fallback && !(weight > 1e-3f * s[job.values + 1])) {
                s = &nearest[(std::size_t(py) * width + px) * job.values];
                inv = 1.0f;
            }
            for (int c = 0; c < 4; ++c) out[c] = s[c] * inv;
            const float z = depth[std::size_t(py) * width + px];
            out[4] = std::isfinite(z) ? z : 0.0f; // no hit: 0
            for (int c = 4; c < job.values; ++c) out[c + 1] = s[c] * inv;
        }
    }
    return image;
}

/// The image buffers fit in memory before any is allocated: per pixel the
/// depth, the nearest samples (some filters), the tiles' filter sums (wider
/// than the tiles by the filter's reach), their total, the image and its
/// copy in the writer. OutOfMemoryError says how much.
void check_image_memory(const Renderer& job, const Scene& scene) {
    const uint64_t pixels = uint64_t(job.camera.xres) * uint64_t(job.camera.yres);
    const double overlap = double(kTile + 2 * job.reach_x) * (kTile + 2 * job.reach_y) /
                           double(kTile * kTile);
    const double floats = 1.0 + (job.nearest_fallback ? job.values : 0) +
                          filter_slots(job) * (overlap + 1.0) + 2.0 * (job.values + 1);
    const uint64_t bytes = uint64_t(double(pixels) * floats * sizeof(float));
    check_memory(bytes,
                 (scene.path.empty() ? std::string("the image") : scene.path) + ": a " +
                     std::to_string(job.camera.xres) + " x " +
                     std::to_string(job.camera.yres) + " image of " +
                     std::to_string(job.values + 1) + " channels",
                 "lower the resolution (Format, or render -res)");
}

/// The ray counts, and warnings about samples that went wrong numerically.
void report_rays(const Renderer& job, RenderReport& report) {
    report.camera_rays = job.camera_rays.load();
    report.shadow_rays = job.shadow_rays.load();
    report.shading_points = job.shading_points.load();
    if (job.scene_rays) {
        report.secondary_rays = job.scene_rays->rays_traced();
    }
    if (job.bad_samples.load() > 0)
        report.warnings.push_back(std::to_string(job.bad_samples.load()) +
                                  " samples had non-finite values and were left black");
    const uint64_t nan_points =
        job.nan_points.load() + (job.scene_rays ? job.scene_rays->nonfinite_points() : 0);
    if (nan_points > 0)
        report.warnings.push_back(
            std::to_string(nan_points) +
            " shading points gave NaN or infinite values, written as 0");
    uint64_t invalid = job.camera_tracer ? job.camera_tracer->invalid_rays() : 0;
    if (job.shadow_tracer) invalid += job.shadow_tracer->invalid_rays();
    if (job.scene_rays) invalid += job.scene_rays->invalid_rays();
    if (invalid > 0) report.warnings.push_back(invalid_rays_warning(invalid));
}

/// PRMan bakes only the visible, front-facing micropolygons of a primitive
/// unless `Attribute "cull" "hidden" 0 "backfacing" 0`; the bake pass bakes
/// whole objects (as ptbake, and as the pipeline needs): said once, naming
/// the first such primitive.
std::optional<std::string> culled_bake_warning(const Scene& scene,
                                               const SceneShaders& shaders) {
    std::size_t count = 0;
    std::string first;
    for (std::size_t i = 0; i < scene.primitives.size(); ++i) {
        const ShaderInstance* s = shaders.surface_of[i];
        if (!s || !program_uses(s->program(), "bake3d")) continue;
        const Attributes& attr = attributes_of(scene.primitives[i]);
        bool culled = true;
        if (auto it = attr.groups.find("cull"); it != attr.groups.end()) {
            const auto off = [&](const char* name) {
                const Param* p = it->second.find(name);
                return p && !p->numbers.empty() && p->numbers[0] == 0.0;
            };
            culled = !(off("hidden") && off("backfacing"));
        }
        if (!culled) continue;
        if (count++ == 0) first = scene.primitives[i].source;
    }
    if (count == 0) return std::nullopt;
    return first + ": baked whole, hidden and back-facing parts included, as ptbake " +
           "bakes (" + std::to_string(count) +
           " baked primitive(s) without Attribute \"cull\" \"hidden\" 0 "
           "\"backfacing\" 0, with which PRMan would bake only what the camera sees)";
}

} // namespace

RenderJob::~RenderJob() = default;

Image RenderJob::image(RenderReport* report_out) const {
    RenderReport local;
    RenderReport& report = report_out ? *report_out : local;
    Stopwatch watch;
    const Scene& scene = m_scene;
    const RenderJobOptions& options = m_options;
    const std::optional<int> frame = m_frame;

    Renderer job(*m_shaders);
    if (scene.primitives.empty())
        report.warnings.push_back(
            (scene.path.empty() ? std::string("the scene") : scene.path) +
            ": no geometry in the world: the image is empty");
    const std::string name = scene.path.empty() ? std::string("the scene") : scene.path;
    setup_camera(job, scene, options);
    setup_depth(job, scene);
    const bool any_shadows = resolve_shading(job, scene, frame, report);
    if (auto w = unlit_scene_warning(scene, job.shaders)) report.warnings.push_back(*w);
    check_image_memory(job, scene);
    bool separate_shadows = false;
    const std::vector<std::size_t> to_dice =
        plan_surfaces(job, any_shadows, &separate_shadows);
    {
        ScopedStage stage("dicing " + name);
        dice_surfaces(job, to_dice, separate_shadows, report);
    }
    ScopedStage building("building the ray tracer for " + name);
    build_tracers(job, to_dice, any_shadows, separate_shadows, report);
    job.services->set_occluders(job.occluders);
    if (job.any_rays) {
        std::vector<RaySurface> surfaces(scene.primitives.size());
        for (std::size_t i : to_dice)
            if (job.surfaces[i].shadows || job.surfaces[i].secondary)
                surfaces[i] = {&job.surfaces[i].diced, &job.surfaces[i].triangle_colors};
        job.scene_rays = std::make_unique<SceneRays>(scene, job.shaders, *job.resources,
                                                     *job.services, std::move(surfaces));
        job.services->set_scene_rays(job.scene_rays.get());
    }
    report.setup_seconds = watch.seconds();

    ScopedStage rendering("rendering " + name);
    const TileGrid grid(job.camera.xres, job.camera.yres);
    std::vector<float> depth(std::size_t(grid.width) * grid.height,
                             std::numeric_limits<float>::infinity());
    std::vector<float> nearest;
    std::vector<std::vector<float>> tile_sums =
        render_tiles(job, grid, options, depth, nearest);
    Image image =
        resolve_pixels(job, grid, add_tiles(job, grid, tile_sums), depth, nearest);
    // RISpec's imaging pipeline: the pixel filter, the imager, then (when
    // the Displays are written) exposure and quantisation.
    run_imager(job, image);
    // A camera that sees nothing of a scene with geometry is a mistake more
    // often than a wish (a camera transform after WorldBegin, a sign).
    if (!scene.primitives.empty() && job.surface_samples.load() == 0)
        report.warnings.push_back(
            name + ": no camera ray hit a surface: the image is empty (is the camera "
                   "looking away from the scene, or is the scene smaller than a pixel? "
                   "See the camera transform, Projection and ScreenWindow)");

    report_rays(job, report);
    report.warnings.append(job.services->take_warnings());
    report.render_seconds = watch.seconds() - report.setup_seconds;
    return image;
}

namespace {

/// The Displays a job writes: the scene's, with -o in place of the primary
/// one's file name (or a default "<scene>.exr"), frame patterns expanded.
/// `primary` receives the index of the primary Display.
std::vector<DisplaySpec> job_displays(const Scene& scene, const RenderJobOptions& options,
                                      std::optional<int> frame, int& primary) {
    std::vector<DisplaySpec> displays = scene.options.displays;
    primary = -1;
    for (std::size_t i = 0; i < displays.size(); ++i)
        if (!displays[i].additional) {
            primary = static_cast<int>(i);
            break;
        }
    if (!options.output.empty()) {
        if (primary >= 0) {
            // -o names a file: its extension picks the format, whatever
            // the Display's type said.
            displays[primary].name = options.output;
            displays[primary].type = "file";
        } else {
            DisplaySpec d;
            d.name = options.output;
            d.type = "file";
            d.mode = "rgba";
            displays.insert(displays.begin(), d);
            primary = 0;
        }
    }
    if (displays.empty()) {
        DisplaySpec d;
        d.name =
            scene.path.empty()
                ? std::string("render.exr")
                : std::filesystem::path(scene.path).replace_extension(".exr").string();
        d.type = "openexr";
        d.mode = "rgba";
        displays.push_back(d);
        primary = 0;
    }
    // Names first: a bad pattern is a usage error before any rendering.
    for (std::size_t i = 0; i < displays.size(); ++i)
        displays[i].name =
            expand_frame_pattern(displays[i].name, frame,
                                 static_cast<int>(i) == primary && !options.output.empty()
                                     ? options.output_label
                                     : "Display");
    return displays;
}

} // namespace

RenderJob::RenderJob(const Scene& scene, const RenderJobOptions& options)
    : m_scene(scene), m_options(options), m_frame(job_frame(scene, options.frame)),
      m_shaders(std::make_shared<const SceneShaders>(
          bind_scene_shaders(scene, m_frame, true))) {
    bool bakes = false;
    for (const ShaderInstance* s : m_shaders->surface_of)
        bakes = bakes || (s && program_uses(s->program(), "bake3d"));
    if (!bakes) return;
    // The bake pass of a bake RIB: ptbake's job with ptbake's defaults
    // (ShadingRate micropolygons of the scene's own camera, not -res).
    m_bake_options = std::make_unique<BakeOptions>();
    m_bake_options->frame = m_frame;
    m_bake_options->after_frame_makes = false; // run() does them after the image
    // A pass that renders no image (only "null" Displays) reports the bake's
    // progress; otherwise the image's (one 0-100 % run per job).
    int primary = -1;
    bool image = false;
    for (const DisplaySpec& d : job_displays(scene, options, m_frame, primary))
        image = image || !display_writes_nothing(d);
    if (!image) m_bake_options->progress = options.progress;
    m_bake = std::make_unique<BakeJob>(scene, *m_bake_options, m_shaders);
}

RenderFiles RenderJob::files() const {
    RenderFiles files;
    files.inputs = m_scene.sources;
    for (const std::string& f : shader_input_files(*m_shaders))
        if (std::find(files.inputs.begin(), files.inputs.end(), f) == files.inputs.end())
            files.inputs.push_back(f);
    int primary = -1;
    if (m_bake) {
        files.outputs = m_bake->output_files();
        for (const std::string& f : m_bake->input_files())
            if (std::find(files.inputs.begin(), files.inputs.end(), f) ==
                files.inputs.end())
                files.inputs.push_back(f);
    }
    for (const DisplaySpec& d : job_displays(m_scene, m_options, m_frame, primary))
        if (!display_writes_nothing(d)) files.outputs.push_back(display_file(d));
    return files;
}

RenderReport RenderJob::run() const {
    RenderReport report = render_frame();
    // After the frame's files are in place: MakeShadow of its zfile.
    run_make_requests(m_scene, true);
    return report;
}

RenderReport RenderJob::render_frame() const {
    RenderReport report;
    Stopwatch watch;
    const Scene& scene = m_scene;
    const RenderJobOptions& options = m_options;
    const std::optional<int> frame = m_frame;

    int primary = -1;
    const std::vector<DisplaySpec> displays =
        job_displays(scene, options, frame, primary);

    // Before any work: every Display writes a known format into a folder
    // that exists, no two name one file, and none is a file the scene
    // reads (the shaders' files and lookups are checked in render_image).
    JobFilesScope scope;
    JobFiles& files = scope.files();
    for (std::size_t i = 0; i < scene.sources.size(); ++i)
        files.input(scene.sources[i], i < scene.source_uses.size()
                                          ? scene.source_uses[i]
                                          : "\"" + scene.sources[i] + "\"");
    std::vector<std::size_t> written; // the Displays that write a file
    for (std::size_t i = 0; i < displays.size(); ++i) {
        const DisplaySpec& d = displays[i];
        if (display_writes_nothing(d)) continue;
        written.push_back(i);
        const std::string path = display_file(d);
        std::string use;
        if (static_cast<int>(i) == primary && !options.output.empty())
            use = options.output_label + " " + sss::quoted(path);
        else if (d.where.empty())
            use = "the output image " + sss::quoted(path);
        else
            use = "Display " +
                  sss::quoted(std::string(d.additional ? "+" : "") + d.name) + " (" +
                  d.where + ")";
        files.output(path, use);
        display_format(d);
        check_output_target(path);
        if (display_is_window(d))
            report.warnings.push_back(
                "Display " + sss::quoted(d.name) + " " + sss::quoted(d.type) +
                (d.where.empty() ? "" : " (" + d.where + ")") +
                ": there is no framebuffer window here; the image is written to " +
                sss::quoted(path));
    }
    DisplayDefaults defaults;
    defaults.exposure_gain = scene.options.exposure_gain;
    defaults.exposure_gamma = scene.options.exposure_gamma;
    defaults.quantize = scene.options.quantize;
    {
        // Every mode against the channels the image will have (the AOVs the
        // shaders output), before anything is baked or rendered.
        const Image probe(1, 1, image_channels(plan_aovs(scene, *m_shaders)));
        const int xres = options.xres > 0 ? options.xres : scene.options.camera.xres;
        const int yres = options.yres > 0 ? options.yres : scene.options.camera.yres;
        for (std::size_t i : written)
            check_display_size(displays[i],
                               resolve_display(displays[i], probe,
                                               static_cast<int>(i) == primary, defaults),
                               xres, yres);
    }

    // Every file (the shaders' bakes, then the Displays) is written as a
    // temporary first; the set puts them all in place at the end, or none.
    OutputSet outputs;
    if (m_bake) {
        // The bake pass first (its clouds join this job's outputs), as
        // ptbake bakes: the image's own shading bakes nothing.
        const Stopwatch bake_watch;
        const BakeReport baked = m_bake->run();
        report.bake_seconds = bake_watch.seconds();
        report.warnings.append(baked.warnings);
        if (auto w = culled_bake_warning(scene, *m_shaders))
            report.warnings.push_back(*w);
        for (const BakeFileReport& f : baked.files) {
            report.baked_files.push_back(f.path);
            report.baked_points.push_back(f.points);
            report.baked_areas.push_back(f.area);
        }
    }
    if (written.empty()) {
        // Only "null" Displays (a bake pass): no image to render.
        outputs.commit();
        if (options.progress) options.progress->finish();
        return report;
    }
    Image image = this->image(&report);
    if (m_bake) {
        // The bake and the image report the same shaders' warnings: once.
        Warnings unique;
        std::set<std::string> seen;
        for (const std::string& w : report.warnings)
            if (seen.insert(w).second) unique.push_back(w);
        for (const Warnings::Omitted& o : report.warnings.omitted())
            unique.add_omitted(o.label, o.count);
        report.warnings = std::move(unique);
    }
    const Stopwatch write_watch;
    ImageMetadata meta;
    meta.software = std::string("render (sss) ") + version_string();
    meta.command_line = options.command_line;
    meta.render_seconds = watch.seconds();
    meta.world_to_camera = scene.options.camera.world_to_camera;
    Camera cam = scene.options.camera;
    cam.xres = image.width;
    cam.yres = image.height;
    meta.world_to_ndc = cam.world_to_ndc();
    // NDC (x right, y down, [0, 1]) to the depth maps' screen ([-1, 1], y up).
    Matrix4 ndc_to_screen(1.0);
    ndc_to_screen[0][0] = 2.0;
    ndc_to_screen[1][1] = -2.0;
    ndc_to_screen[3][0] = -1.0;
    ndc_to_screen[3][1] = 1.0;
    meta.world_to_screen = ndc_to_screen * meta.world_to_ndc;
    if (!scene.path.empty()) meta.extra.emplace_back("sss:scene", scene.path);
    const int nx = options.pixel_samples > 0 ? options.pixel_samples
                                             : scene.options.pixel_samples[0];
    const int ny = options.pixel_samples > 0 ? options.pixel_samples
                                             : scene.options.pixel_samples[1];
    meta.extra.emplace_back("sss:pixelSamples",
                            std::to_string(nx) + " " + std::to_string(ny));
    if (frame) meta.extra.emplace_back("sss:frame", std::to_string(*frame));
    meta.extra.emplace_back("sss:threads",
                            std::to_string(tbb::this_task_arena::max_concurrency()));
    // Resolve every Display (an unknown AOV, a mode the format cannot
    // hold) before the first is written.
    std::vector<DisplayTarget> targets;
    for (std::size_t i : written)
        targets.push_back(resolve_display(displays[i], image,
                                          static_cast<int>(i) == primary, defaults));
    for (const DisplayTarget& target : targets) {
        ScopedStage stage("writing " + target.path);
        write_display(image, target, meta);
        report.files.push_back(target.path);
    }
    outputs.commit();
    report.write_seconds = write_watch.seconds();
    if (options.progress) options.progress->finish();
    return report;
}

Image render_image(const Scene& scene, const RenderJobOptions& options,
                   RenderReport* report) {
    return RenderJob(scene, options).image(report);
}

RenderFiles render_files(const Scene& scene, const RenderJobOptions& options) {
    return RenderJob(scene, options).files();
}

RenderReport render_scene(const Scene& scene, const RenderJobOptions& options) {
    return RenderJob(scene, options).run();
}

} // namespace sss
