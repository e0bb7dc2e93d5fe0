// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file scene_shaders.h
/// Module binding: a scene's shaders bound for a job (this file), secondary
/// rays through a diced scene with the hits shaded by their own shaders
/// (scene_rays.h) and displacement shaders on the dicer's grids
/// (displacement.h): what ptbake and render share above the engine.
/// May use: shading, rsl, dice, light, brick, image, cloud, scene and util.
///
/// The shaders of a scene bound for one job (ptbake or render): every
/// distinct Surface, Displacement, Atmosphere, Interior and Exterior call,
/// every light source and the Imager as a ShaderInstance, loaded
/// along the scene's shader search path (shader_library.h). Frame patterns
/// ("%04d", "####", "$F4") in string parameters are expanded with the job's frame,
/// so `"string filename" ["orbit_ssd.%04d.bkm"]` reads the frame's file.

#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "sss/rsl/shader_library.h"
#include "sss/scene/scene.h"
#include "sss/shading/engine.h"
#include "sss/util/job_files.h"

namespace sss {

struct SceneShaders {
    std::unique_ptr<ShaderLibrary> library;
    /// Distinct surface instances (one per Surface call).
    std::vector<std::unique_ptr<ShaderInstance>> surfaces;
    /// Per primitive: its surface shader (defaultsurface without a Surface).
    std::vector<const ShaderInstance*> surface_of;
    /// Distinct displacement instances (one per Displacement call).
    std::vector<std::unique_ptr<ShaderInstance>> displacements;
    /// Per primitive: its displacement shader, or null without a Displacement.
    /// Without one, a class surface shader (RSL 2.0) with a displacement
    /// method is its own (run with execute_as(ShaderKind::Displacement)).
    std::vector<const ShaderInstance*> displacement_of;
    /// Distinct volume instances (one per Atmosphere, Interior or Exterior
    /// call), and per primitive its Atmosphere (bound only for images: see
    /// bind_scene_shaders), Interior and Exterior shader, or null.
    std::vector<std::unique_ptr<ShaderInstance>> volumes;
    std::vector<const ShaderInstance*> atmosphere_of, interior_of, exterior_of;
    /// Whether some primitive has an Interior or Exterior shader (traced rays
    /// run them).
    bool any_interior_exterior = false;
    /// The scene's Imager shader (bound only for images), or null.
    std::unique_ptr<ShaderInstance> imager;
    /// Per scene light (Scene::lights order).
    std::vector<std::unique_ptr<ShaderInstance>> lights;
    /// Per primitive: the lights that are on for it, in Scene::lights order.
    std::vector<std::vector<const ShaderInstance*>> lights_of;
    /// Distinct co-shader instances (one per `Shader "name" "handle"` call,
    /// RSL 2.0), each with its handle (ShaderInstance::handle).
    std::vector<std::unique_ptr<ShaderInstance>> coshaders;
    /// Per primitive: the co-shaders in effect for it (its shaders'
    /// getshader() and getshaders() find them).
    std::vector<std::vector<const ShaderInstance*>> coshaders_of;
    /// Parameters the shaders do not declare, and similar notes.
    std::vector<std::string> warnings;

    /// Whether any bound program (surface, displacement, light, volume or
    /// imager) calls `op`.
    bool uses(std::string_view op) const;
};

/// The scene's shader search path, folders in search order
/// (resolve_shader_search_path() of search_path(scene, "shader")).
std::vector<std::string> shader_search_path(const Scene& scene);

/// Whether `program` has an op named `op`.
bool program_uses(const Program& program, std::string_view op);

/// A warning for a scene without light sources whose surface shaders read
/// lights (ambient, diffuse, specular, phong, illuminance...): what they take
/// from lights is black, so the image or bake is black where they shade.
/// nullopt when the scene has lights or no shader reads them.
std::optional<std::string> unlit_scene_warning(const Scene& scene,
                                               const SceneShaders& shaders);

/// Whether `program` reads the surface's parametrisation: one of the globals
/// u, v, s, t, du, dv, dPdu, dPdv, or a texture lookup (by s and t when it
/// gives no coordinates). Other shaders are diced without it (less work).
bool program_reads_parametric(const Program& program);

/// Whether `program` differentiates values over the batch (Du, Dv, Deriv,
/// calculatenormal, area other than area(P, "dicing"), filterstep, filtered
/// texture and environment lookups): then a renderer shades ray hits with
/// their neighbours (BatchLayout::Triplets) and a baker whole grids.
bool program_uses_derivatives(const Program& program);

/// Carries out the scene's Make requests (MakeTexture,
/// MakeLatLongEnvironment, MakeShadow, MakeCubeFaceEnvironment: through
/// TextureLibrary) that run before the frame (`after_frame` false; as
/// bind_scene_shaders does first) or after it (true: once the frame's images
/// are written, as RenderJob::run does), in RIB order. A texture newer than
/// its inputs is kept. Throws IoError / ValueError naming the request's RIB
/// line (a missing picture or zfile, an unknown filter or wrap mode).
void run_make_requests(const Scene& scene, bool after_frame);

/// Loads and binds the scene's shaders (surface, displacement, light, and the
/// Interior and Exterior volume shaders that traced rays run). With `image`
/// (render's image), also the Imager and the Atmosphere shaders, which only
/// an image runs (ptbake writes no image and shades no camera rays: it
/// neither loads nor needs them). Throws ShaderNotFoundError (a shader the
/// search path does not have, naming the call and the path),
/// ShaderCompileError, ValueError (parameters of the wrong type).
SceneShaders bind_scene_shaders(const Scene& scene, std::optional<int> frame,
                                bool image = false);

/// String parameter values of the bound shaders that name existing files, or
/// files by their extension (.bkm .ptc .ply .tx .tex .exr .png .tif .tiff
/// .jpg .hdr): the textures, brick maps and point clouds the shaders read,
/// then the shader files (.slo, .sl) loaded, each once: the inputs of
/// `-newer 1`. A bake shader's output "filename"
/// is among them too; callers drop their own outputs.
std::vector<std::string> shader_input_files(const SceneShaders& shaders);

/// Records in `files` what the bound shaders read that is known before they
/// run: each shader file loaded, and each string parameter that names an
/// existing regular file (a texture, brick map or point cloud), except the
/// "filename" of a shader that calls bake3d, which names an output. Files a
/// shader opens while it runs are checked as they open (JobFiles::opened).
/// Throws OutputConflictError when one of them is an output of the job.
void record_shader_inputs(JobFiles& files, const SceneShaders& shaders);

} // namespace sss
