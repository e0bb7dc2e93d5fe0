// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file bake.h
/// The bake module owns ptbake's job: baking lit micropolygons into point
/// clouds.
/// May use: binding, shading, rsl, dice, light, diffusion, brick, image, cloud, scene
/// and util.
///
/// The ptbake job as one library call, as PRMan bakes: every primitive whose
/// surface shader (RSL, found along the shader search path) calls bake3d is
/// diced into micropolygons; the shader runs over their centres (what
/// bake3d's "interpolate" mode bakes) with the scene's light shaders, and
/// what bake3d writes becomes the point clouds (the shader picks the files
/// and channels). Every other primitive only casts shadows. The pipeline's
/// bake shaders are RSL sources in shaders/: bake_radiance_t (_radiance_t =
/// Kdt x (ambient + diffuse)), bake_sss_params (also _albedo and
/// _diffusemeanfreepath from a material preset or colours, optionally
/// blended with noise) and bake_constant (the colour Cs: blockers).
/// `float _area` is always written (a shader's own "_area" value, else the
/// micropolygon's area).

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "sss/cloud/point_cloud_io.h"
#include "sss/diffusion/material.h"
#include "sss/scene/scene.h"
#include "sss/util/error.h"
#include "sss/util/messages.h"

namespace sss {

class Progress; // sss/util/progress.h

/// Everything ptbake can be told.
struct BakeOptions {
    /// > 0: micropolygon edge length in scene units (-spacing LEN). 0: ShadingRate.
    double spacing = 0.0;
    /// Pick the spacing from the material (-spacing mfp): its smallest mean
    /// free path 1/sigma_t' in scene units, times mfp_fraction. Without
    /// `material`, each object whose shader has albedo and dmfp parameters
    /// (bake_sss_params) uses their range (other objects then have no
    /// material: UsageError).
    bool spacing_from_material = false;
    double mfp_fraction = 1.0;
    /// The material the bake is for (-material ...): enables the spacing
    /// check (a warning when points are farther apart than its mean free path).
    std::optional<MaterialSpec> material;
    /// Scene length of one mm: the bake's one scene scale, for the material's
    /// mean free path and bake_sss_params' dmfp (mm). A given `material` must
    /// have the same unitlength (ValueError otherwise).
    double unitlength = 1.0;
    std::optional<int> frame; ///< -frame N, for frame patterns in file names
    /// run() ends with the Make requests that follow the frame
    /// (run_make_requests); render's bake pass leaves them to the render.
    bool after_frame_makes = true;
    std::string output; ///< -o: every bake goes to this one file
    PointCloudWriteOptions write;
    Progress* progress = nullptr;
};

/// One file written.
struct BakeFileReport {
    std::string path;
    std::size_t points = 0;
    double area = 0.0; ///< sum of _area
    std::vector<std::string> channels;
    std::vector<std::string> objects; ///< source locations of the baked primitives
};

/// What happened, for -progress reports and tests.
struct BakeReport {
    std::vector<BakeFileReport> files;
    /// Non-fatal problems, counted by kind (a few of each kind kept).
    Warnings warnings;
    std::size_t baked_primitives = 0;
    std::size_t occluder_primitives = 0;
    std::size_t occluder_triangles = 0;
    std::size_t shadow_lights = 0;
    /// Before dicing: the micropolygons estimated (DiceEstimate) and the
    /// memory the bake was estimated to need for them.
    double estimated_micropolygons = 0.0;
    double estimated_bytes = 0.0;
    double min_spacing = 0.0; ///< smallest and largest micropolygon edge used
    double max_spacing = 0.0;
    double dice_seconds = 0.0;
    double trace_build_seconds = 0.0;
    double light_seconds = 0.0;
    double write_seconds = 0.0;
};

/// A baked primitive whose shader names no "filename" while no single
/// output file (BakeOptions::output) is given.
class MissingBakeFileError : public ValueError {
public:
    explicit MissingBakeFileError(const std::string& what);
};

/// spacing_from_material without a material, for an object that does not
/// carry its own (bake_sss_params). A UsageError; source() is the object's
/// "file.rib:12".
class SpacingMaterialError : public UsageError {
public:
    explicit SpacingMaterialError(std::string source);
    const std::string& source() const { return m_source; }

private:
    std::string m_source;
};

/// Smallest mean free path 1/sigma_t' over the colour channels of a
/// material, in scene units (mm x unitlength, see material.h).
double material_mean_free_path(const MaterialSpec& material);

struct SceneShaders;

/// One ptbake job, planned once: the frame resolved (the options', else the
/// scene's), and the scene's shaders loaded and bound (each shader file read
/// once, parameters matched to symbols once). Every phase of the job, the
/// -newer test's file lists included, uses that plan. Construction throws as
/// binding does (ShaderNotFoundError, ShaderCompileError, ValueError). The
/// scene and the options must outlive the job.
class BakeJob {
public:
    BakeJob(const Scene& scene, const BakeOptions& options);
    /// The same job with the scene's shaders already bound for the job's
    /// frame (a render job's: each shader is loaded and compiled once).
    BakeJob(const Scene& scene, const BakeOptions& options,
            std::shared_ptr<const SceneShaders> shaders);
    ~BakeJob();
    BakeJob(const BakeJob&) = delete;
    BakeJob& operator=(const BakeJob&) = delete;

    /// The files run() would write, in first-use order, without baking (for
    /// -newer 1). Throws MissingBakeFileError for a bake shader without a
    /// "filename" when options.output is empty.
    std::vector<std::string> output_files() const;
    /// The files the bake reads (for -newer 1): the scene's sources, then the
    /// files its shaders read and the shaders themselves
    /// (shader_input_files()), without the bake's own outputs.
    std::vector<std::string> input_files() const;
    /// Bakes without writing: the clouds by output path, in first-use order.
    std::vector<std::pair<std::string, PointCloud>> clouds(BakeReport* report) const;
    /// Bakes the scene and writes its point clouds (atomically). Throws
    /// ValueError / UsageError / IoError with the primitive's source location.
    BakeReport run() const;

private:
    /// The bake shaders' files with how each is named, for messages.
    std::vector<std::pair<std::string, std::string>> named_outputs() const;

    const Scene& m_scene;
    const BakeOptions& m_options;
    std::optional<int> m_frame;
    std::shared_ptr<const SceneShaders> m_shaders;
};

/// BakeJob(scene, options).run().
BakeReport bake_scene(const Scene& scene, const BakeOptions& options);

/// BakeJob(scene, options).output_files().
std::vector<std::string> bake_output_files(const Scene& scene,
                                           const BakeOptions& options);

/// BakeJob(scene, options).input_files().
std::vector<std::string> bake_input_files(const Scene& scene, const BakeOptions& options);

/// BakeJob(scene, options).clouds(report).
std::vector<std::pair<std::string, PointCloud>>
bake_clouds(const Scene& scene, const BakeOptions& options, BakeReport* report);

} // namespace sss
