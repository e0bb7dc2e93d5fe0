// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
// Internal to the binding module (TextureLibrary and its plugin): the OpenImageIO side of
// 2-D textures and environment maps, built as a plugin (libsss_texture2d.so, beside the
// tools: <build>/lib, or an install's <libdir>/sss) and loaded on the first texture
// lookup, so that tools and jobs that never look up a 2-D texture do not load OpenImageIO
// and the 260 libraries behind it (0.15 s at every process start).

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "sss/image/image_check.h"
#include "sss/shading/texture_services.h"

namespace sss::detail {

/// A depth map as the plugin reads it (a zfile or shadow map, docs/scene.md).
struct DepthMapData {
    int width = 0, height = 0;
    std::vector<float> z; ///< rows top to bottom
    /// The files' matrices as stored: row-vector (Imath) layout, row by row,
    /// which is glm's column-major order of the column-vector matrix.
    std::array<float, 16> world_to_camera{}, world_to_screen{};
};

/// What TextureLibrary forwards to the plugin: the 2-D calls of texture_library.h.
class Texture2dBackend {
public:
    virtual ~Texture2dBackend() = default;
    virtual bool texture(const std::string& file, int channel, int nchannels,
                         const TextureOptions& options, std::size_t count, const float* s,
                         const float* t, const float* ds_du, const float* dt_du,
                         const float* ds_dv, const float* dt_dv, const uint8_t* mask,
                         float* out, std::string* error) = 0;
    virtual bool environment(const std::string& file, int channel, int nchannels,
                             const TextureOptions& options, std::size_t count,
                             const glm::vec3* dir, const glm::vec3* ddir_du,
                             const glm::vec3* ddir_dv, const uint8_t* mask, float* out,
                             std::string* error) = 0;
    virtual bool texture_info(const std::string& file, const std::string& key,
                              int expected_floats, float* numbers, std::string* text) = 0;
    virtual void invalidate(const std::string& file) = 0;
    /// The header of an image file (first subimage, level 0) as OpenImageIO
    /// reads it, nothing more; false when it cannot read one.
    virtual bool image_header(const std::string& file, ImageHeader& out) = 0;
    /// Makes a tiled, MIP-mapped TIFF texture (`latlong`: a lat-long
    /// environment) of the picture `input` into `output`, with OpenImageIO's
    /// wrap modes ("periodic,clamp") and resampling filter; false with
    /// *error when the filter is unknown or the texture cannot be made.
    virtual bool make_texture(const std::string& input, const std::string& output,
                              bool latlong, const std::string& wrapmodes,
                              const std::string& filter, std::string* error) = 0;
    /// Reads a zfile or shadow map (its "Z" channel, or its only channel,
    /// and the worldtocamera and worldtoscreen matrices); false with *error
    /// ("file: reason") when it is not one.
    virtual bool read_depth_map(const std::string& file, DepthMapData& out,
                                std::string* error) = 0;
    /// MakeShadow: the zfile `input` as a shadow map in `output` (an
    /// OpenEXR file, written where told: the caller renames it).
    virtual bool make_shadow(const std::string& input, const std::string& output,
                             std::string* error) = 0;
    /// MakeCubeFaceEnvironment: the six pictures (+x, -x, +y, -y, +z, -z,
    /// RenderMan's orientation, `fov` degrees each) resampled into an
    /// OpenEXR cube-face map (N x 6N) in `output`; `filter` is checked as
    /// make_texture's.
    virtual bool make_cube_environment(const std::array<std::string, 6>& faces,
                                       const std::string& output, double fov,
                                       const std::string& filter, std::string* error) = 0;
};

/// The plugin's entry point (extern "C", looked up by name).
using MakeTexture2dBackend = Texture2dBackend* (*)();
constexpr const char* kTexture2dEntry = "sss_make_texture2d_backend";
constexpr const char* kTexture2dPlugin = "libsss_texture2d.so";

} // namespace sss::detail
