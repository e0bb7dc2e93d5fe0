// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file texture_library.h
/// Module binding: the job's TextureServices (shading/texture_services.h),
/// over OpenImageIO (a plugin loaded on the first 2-D lookup), brick maps
/// and point clouds.

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "sss/shading/texture_services.h"

namespace sss {

struct ShadowMap; // sss/light/shadow_map.h
struct DepthGrid; // sss/dice/dice.h

/// 2-D textures through one OpenImageIO TextureSystem (MIP-mapped .tx/.tex
/// made by maketx, and any image OIIO reads, MIP-mapped on the fly),
/// environment maps (lat-long through OIIO, OpenEXR cube-face maps looked
/// up face by face with OIIO's texture()) and 3-D textures
/// (brick maps, point clouds), opened once per file. Thread-safe; one per
/// job (SceneServices owns it). The contracts of the lookups are
/// TextureServices'.
class TextureLibrary final : public TextureServices {
public:
    TextureLibrary();
    ~TextureLibrary() override;
    TextureLibrary(const TextureLibrary&) = delete;
    TextureLibrary& operator=(const TextureLibrary&) = delete;

    bool texture(const std::string& file, int channel, int nchannels,
                 const TextureOptions& options, std::size_t count, const float* s,
                 const float* t, const float* ds_du, const float* dt_du,
                 const float* ds_dv, const float* dt_dv, const uint8_t* mask, float* out,
                 std::string* error) override;
    bool texture_quad(const std::string& file, int channel, int nchannels,
                      const TextureOptions& options, std::size_t count,
                      const float* const st[8], const uint8_t* mask, float* out,
                      std::string* error) override;
    bool environment(const std::string& file, int channel, int nchannels,
                     const TextureOptions& options, std::size_t count,
                     const glm::vec3* dir, const glm::vec3* ddir_du,
                     const glm::vec3* ddir_dv, const uint8_t* mask, float* out,
                     std::string* error) override;
    bool texture_info(const std::string& file, const std::string& key,
                      int expected_floats, float* numbers, std::string* text) override;
    bool shadow(const std::string& file, const TextureOptions& options, std::size_t count,
                const glm::vec3* P, const glm::vec3* dP_du, const glm::vec3* dP_dv,
                const uint8_t* mask, float* out, std::string* error) override;
    bool texture3d(const std::string& file, std::span<const std::string> channels,
                   std::size_t count, const glm::vec3* P, const glm::vec3* N,
                   const float* radius, const uint8_t* mask,
                   std::vector<int>& channel_floats, float* out, uint8_t* found,
                   std::string* error) override;

    /// The folders a relative file name is looked for in, in order (the
    /// scene's search_path(scene, "texture"); "." is the working folder, "@"
    /// entries are skipped). Empty (the default): names are used as given.
    /// A file found nowhere is an error that names the path. Set before the
    /// first lookup.
    void set_search_path(std::vector<std::string> path);

    /// Forgets what is known of `file` (2-D and 3-D), so that the next call
    /// opens it again: for a file written during the job (bake3d, then
    /// texture3d). Unreadable files are otherwise remembered as such.
    void invalidate(const std::string& file);

    /// A texture to make (RenderMan's MakeTexture, MakeLatLongEnvironment).
    struct Make {
        std::string input;  ///< the picture (any format OpenImageIO reads)
        std::string output; ///< the texture, written atomically
        bool latlong = false;
        std::string swrap = "black", twrap = "black"; ///< periodic, clamp, black, mirror
        std::string filter = "box"; ///< OpenImageIO's filter names; "catmullrom" too
    };
    /// Makes a tiled, MIP-mapped texture with OpenImageIO's texture maker
    /// (the plugin), unless the texture is already newer than its picture
    /// (returns false then). IoError / ValueError naming `where` when the
    /// picture cannot be read, a wrap mode or filter is unknown, or the
    /// texture cannot be written.
    bool make_texture(const Make& m, const std::string& where);

    /// The depth map `file` (a zfile or shadow map: docs/scene.md), read
    /// once along the search path and shared; null with *error ("file:
    /// reason") when it cannot be read as one. Thread-safe.
    std::shared_ptr<const ShadowMap> shadow_map(const std::string& file,
                                                std::string* error);

    /// The same depth map as the dicer reads it (a Blobby's repelling ground
    /// plane: DiceControl::depth_maps), made once per map; IoError naming
    /// `file` when it cannot be read as one. Thread-safe.
    std::shared_ptr<const DepthGrid> depth_grid(const std::string& file);

    /// MakeShadow: the zfile `input` as a shadow map in `output` (OpenEXR,
    /// atomically), unless `output` is already newer than `input` (returns
    /// false then). IoError naming `where` when the zfile is missing or not
    /// a depth map, or the map cannot be written.
    bool make_shadow(const std::string& input, const std::string& output,
                     const std::string& where);

    /// MakeCubeFaceEnvironment: the six pictures (+x, -x, +y, -y, +z, -z
    /// views of `fov` degrees, RenderMan's orientation) as an OpenEXR
    /// cube-face environment map in `output` (atomically), unless it is
    /// newer than every picture (returns false then). IoError / ValueError
    /// naming `where` (a missing picture, faces of different sizes, an
    /// unknown filter).
    bool make_cube_environment(const std::array<std::string, 6>& faces,
                               const std::string& output, double fov,
                               const std::string& filter, const std::string& where);

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

} // namespace sss
