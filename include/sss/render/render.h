// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file render.h
/// The render module owns the final image: ray tracing, shading and image
/// output.
/// May use: bake, binding, shading, rsl, dice, light, diffusion, brick, image, cloud,
/// scene and util (OpenEXR and OpenImageIO privately).
///
/// The final renderer: ray tracing (Embree) over the shared scene layer,
/// the scene's RSL shaders run over batches of hits (the shading module;
/// `read_ssdiffusion` looks `_ssdiffusion` up with texture3d), AOVs, and
/// RenderMan Display outputs.

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "sss/render/image_io.h"
#include "sss/scene/scene.h"
#include "sss/util/messages.h"

namespace sss {

class Progress; // sss/util/progress.h

/// Everything `render` can be told besides the scene.
struct RenderJobOptions {
    std::optional<int>
        frame;          ///< -frame N: frame patterns in Display names and shader files
    std::string output; ///< -o IMAGE: replaces the primary Display's file name
    /// How messages name `output` (the command line passes "option -o").
    std::string output_label = "output image";
    Progress* progress = nullptr;
    std::string command_line; ///< stored in image metadata
    /// Overrides for quick tests: 0 = use the scene's Format / PixelSamples.
    int xres = 0, yres = 0;
    int pixel_samples = 0;
    /// Shade every camera sample on its own (-pixelshading 1) instead of at
    /// the ShadingRate (docs/render.md, "Shading rate").
    bool pixel_shading = false;
};

/// What happened.
struct RenderReport {
    std::vector<std::string> files; ///< images written
    /// Point clouds the shaders' bake3d calls wrote: a bake RIB rendered
    /// bakes as ptbake does (BakeJob: every baked primitive diced and
    /// shaded whole, one point per micropolygon), not the camera's hits.
    std::vector<std::string> baked_files;
    std::vector<std::size_t> baked_points; ///< per baked file
    std::vector<double> baked_areas;       ///< per baked file: the sum of _area
    /// Non-fatal problems, counted by kind (a few of each kind kept).
    Warnings warnings;
    std::size_t triangles = 0;
    std::size_t camera_rays = 0;
    std::size_t shadow_rays = 0;
    /// Rays traced through the scene for the shaders' ray-tracing shadeops
    /// (trace, gather, occlusion, indirectdiffuse, transmission with
    /// opacity), the hit shaders' own rays included.
    std::size_t secondary_rays = 0;
    /// Points the surface shaders ran at (at the ShadingRate: the lattice
    /// points the samples hit; with pixel shading: every hit).
    std::size_t shading_points = 0;
    double bake_seconds = 0.0;   ///< a bake RIB's bake pass
    double setup_seconds = 0.0;  ///< dicing, Embree build, maps opened
    double render_seconds = 0.0; ///< pixels
    double write_seconds = 0.0;
};

/// The files a render job reads and writes, without rendering (for -newer 1).
struct RenderFiles {
    std::vector<std::string> inputs;  ///< scene.sources, then the diffusion files
    std::vector<std::string> outputs; ///< every Display's file
};

struct SceneShaders;
struct BakeOptions; // sss/bake/bake.h
class BakeJob;

/// One render job, planned once: the frame resolved (the options', else the
/// scene's), and the scene's shaders loaded and bound (each shader file read
/// once, parameters matched to symbols once); the -newer test's file lists
/// and the render itself use that plan. Construction throws as binding does
/// (ShaderNotFoundError, ShaderCompileError, ValueError). The scene and the
/// options must outlive the job.
///
/// A scene whose surface shaders call bake3d (a bake RIB) is baked as PRMan
/// bakes it, by the same job as ptbake's (BakeJob): every such primitive is
/// diced and shaded whole, view-independent, one point per micropolygon, so
/// that `render bake.rib` and `ptbake bake.rib` write the same clouds. The
/// image is rendered as usual; its own shading bakes nothing.
class RenderJob {
public:
    RenderJob(const Scene& scene, const RenderJobOptions& options);
    ~RenderJob();
    RenderJob(const RenderJob&) = delete;
    RenderJob& operator=(const RenderJob&) = delete;

    /// The files the job reads and writes (render_files()), the bake's clouds
    /// among the outputs.
    RenderFiles files() const;
    /// Whether the job bakes point clouds (some surface shader calls bake3d).
    bool bakes() const { return m_bake != nullptr; }
    /// The image (render_image()).
    Image image(RenderReport* report) const;
    /// Renders and writes every Display (render_scene()), then carries out
    /// the Make requests that follow the frame (a zfile it wrote made into
    /// a shadow map: run_make_requests).
    RenderReport run() const;

private:
    RenderReport render_frame() const;
    const Scene& m_scene;
    const RenderJobOptions& m_options;
    std::optional<int> m_frame;
    std::shared_ptr<const SceneShaders> m_shaders; ///< shared with m_bake
    std::unique_ptr<BakeOptions> m_bake_options;
    std::unique_ptr<BakeJob> m_bake; ///< a bake RIB's bake pass, else null
};

/// Renders the scene into an image with the beauty (R, G, B, A) and the AOV
/// layers (at least ambient, diffuse, specular, sss as layer.R/G/B and
/// occlusion.R/G/B... see docs/render.md). Deterministic: the same image for
/// any thread count.
Image render_image(const Scene& scene, const RenderJobOptions& options,
                   RenderReport* report);

/// RenderJob(scene, options).files().
RenderFiles render_files(const Scene& scene, const RenderJobOptions& options);

/// render_image, then writes every Display of the scene (the primary one
/// replaced by options.output when given; no Display: "<scene>.exr").
RenderReport render_scene(const Scene& scene, const RenderJobOptions& options);

} // namespace sss
