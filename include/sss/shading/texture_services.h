// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file texture_services.h
/// Module shading: what the engine asks of textures. RSL's texture(),
/// environment(), textureinfo() and texture3d() reach files only through
/// the TextureServices a renderer hands out (ShadingServices::textures(),
/// engine.h), as OSL's runtime reaches its texture system through its
/// renderer services. The job's implementation, opened files and
/// OpenImageIO included, is binding's TextureLibrary.

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <glm/vec3.hpp>

namespace sss {

/// Filtering options of texture/environment/shadow calls (RSL token-value lists).
struct TextureOptions {
    float sblur = 0, tblur = 0;   // "blur" sets both; in texture units (1 = whole map)
    float swidth = 1, twidth = 1; // "width" sets both; multiplies the filter footprint;
                                  // 0 = no filtering
    int samples = 1;
    // "box": bilinear within a MIP level (a point lookup at a pixel centre
    // is that pixel); "none"/"nearest": the closest texel of one level; any
    // other ("gaussian", "triangle"...): OIIO's smart bicubic.
    std::string filter = "box";
    float fill = 0; // value of channels past the file's last
    int lerp = 2;   // mip levels: 0 one level, 1 trilinear, 2 (auto) anisotropic
    // shadow(): depth offset in the map camera's units; < 0: the scene's
    // (Option "shadow" "bias", else PRMan's default, sss/light/shadow_map.h).
    float bias = -1;
};

/// Sets option `name` from a token-value pair (numbers: count floats; text
/// for strings). False for an unknown name (the engine warns once).
bool set_texture_option(TextureOptions& options, std::string_view name,
                        const float* numbers, int count, const std::string* text);

/// Texture lookups for shaders. Every function may be called from many
/// threads at once; `mask` may be null (every point), and points whose mask
/// byte is 0 are left alone.
class TextureServices {
public:
    virtual ~TextureServices() = default;

    /// texture(file[channel], s, t): nchannels (1 for float, 3 for color)
    /// floats per point into out (count*nchannels), for the points whose mask
    /// byte is non-zero (mask may be null: every point). The filter footprint
    /// is given by the derivatives of s,t along the grid's two directions
    /// (ds/du*du etc., i.e. differences to the neighbour points); null
    /// derivative arrays = point sampling. Channels past the file's last get
    /// options.fill; a 1-channel file read as colour replicates it (RenderMan
    /// behaviour). Wrap modes come from the file ("wrapmodes", as maketx
    /// writes them), black where it says none. t = 0 is the image's top row.
    /// Non-finite s or t give 0. Returns false (and sets *error to "file:
    /// reason") when the file cannot be read; the engine reports that once
    /// and leaves the result 0.
    virtual bool texture(const std::string& file, int channel, int nchannels,
                         const TextureOptions& options, std::size_t count, const float* s,
                         const float* t, const float* ds_du, const float* dt_du,
                         const float* ds_dv, const float* dt_dv, const uint8_t* mask,
                         float* out, std::string* error) = 0;
    /// The 4-point form: the quad (s1,t1)...(s4,t4) per point is the filter
    /// region (st[0..7] = s1,t1,s2,t2,s3,t3,s4,t4, each count floats). The
    /// corners are in a bilinear patch's order: 1 at (0,0), 2 at (1,0), 3 at
    /// (0,1), 4 at (1,1); the lookup is at their mean, its footprint spanned
    /// by the mean edges along each direction.
    virtual bool texture_quad(const std::string& file, int channel, int nchannels,
                              const TextureOptions& options, std::size_t count,
                              const float* const st[8], const uint8_t* mask, float* out,
                              std::string* error) = 0;
    /// environment(file[channel], dir): world-space directions, footprint
    /// from the direction's differences (may be null). Lat-long maps follow
    /// OpenImageIO's convention, +y up: s = 0.5 + atan2(-x, z) / 2pi (+z at
    /// the centre, +x at s = 0.25, -x at 0.75, -z at the left and right
    /// edges), t = 0.5 - asin(y) / pi (t = 0, the top row, looks along +y),
    /// for every lat-long map (OIIO's "oiio:updirection" hint is not stored
    /// in files). Plain images are read as lat-long maps. (RISpec 3.2's
    /// MakeLatLongEnvironment describes a z-up map with +x at s = 0: such a
    /// map gives at direction d what ours gives at (d.y, d.z, -d.x).) Cube
    /// maps (OIIO "textureformat" = "CubeFace Environment": OpenEXR's envmap
    /// = cube, or maketx with that attribute) are looked up by the plugin
    /// itself in OpenEXR's layout (ImfEnvmap.h): six N x N faces stacked +X,
    /// -X, +Y, -Y, +Z, -Z in an N x 6N image, each seen from the cube's
    /// centre (+X: right +z, down -y; -X: right -z, down -y; +Y: right +x,
    /// down -z; -Y: right +x, down +z; +Z: right -x, down -y; -Z: right +x,
    /// down -y), pixel centres 0 and N-1 on the cube's edges; the footprint
    /// is projected onto the face, capped at half a face and kept inside it
    /// (docs/lighting.md). A cube-tagged file of another layout fails with
    /// "file: cube-face environment map of W x H...; expected ...". A zero or
    /// non-finite direction gives 0.
    virtual bool environment(const std::string& file, int channel, int nchannels,
                             const TextureOptions& options, std::size_t count,
                             const glm::vec3* dir, const glm::vec3* ddir_du,
                             const glm::vec3* ddir_dv, const uint8_t* mask, float* out,
                             std::string* error) = 0;
    /// shadow(file, P) on a depth map (a shadow map or zfile: docs/scene.md):
    /// per point the fraction in shadow, 0 = lit, percentage-closer filtered
    /// (sss/light/shadow_map.h: shadow_fraction) over the footprint of the
    /// world-space differences dP_du, dP_dv (may be null: one texel) times
    /// options.swidth/twidth, plus options.sblur/tblur, with options.samples
    /// comparisons, options.bias (>= 0; the caller resolves the scene's
    /// default) and options.filter ("gaussian" weights; others box).
    /// Points behind the map's camera or outside the map are lit. Returns
    /// false with *error ("file: reason") when the file cannot be read as a
    /// depth map. The default implementation has no maps.
    virtual bool shadow(const std::string& file, const TextureOptions& options,
                        std::size_t count, const glm::vec3* P, const glm::vec3* dP_du,
                        const glm::vec3* dP_dv, const uint8_t* mask, float* out,
                        std::string* error) {
        (void)options, (void)count, (void)P, (void)dP_du, (void)dP_dv, (void)mask,
            (void)out;
        if (error) *error = file + ": these texture services read no shadow maps";
        return false;
    }
    /// textureinfo(file, key, out): "resolution" (2 floats), "channels" (1),
    /// "type" ("texture", "environment", "shadow"),
    /// "viewingmatrix"/"projectionmatrix" (16, when the file has them: OIIO
    /// worldtocamera/worldtoscreen). Returns false for an unknown key, a
    /// missing file, or a value type mismatch (expected_floats: how many
    /// floats the caller's variable holds; 0 for a string).
    virtual bool texture_info(const std::string& file, const std::string& key,
                              int expected_floats, float* numbers, std::string* text) = 0;
    /// texture3d(file, P, N, "channel", out...): world-space P, N, filter
    /// radius per point (0: the nearest points). For each requested channel
    /// name, its floats per point go to channel_floats (1 float, 3
    /// colour/point/vector/normal, 16 matrix); out gets, per point, all
    /// requested channels' floats in order (stride: the sum of
    /// channel_floats). found[i] = 1 where the lookup found data (RSL rule:
    /// where not found the engine leaves the shader's variables unchanged).
    ///
    /// Files: .ptc and .ply are point clouds, anything else a brick map
    /// (.bkm), as the renderer reads `_ssdiffusion`. Brick maps blend their
    /// two levels nearest to the radius (BrickMap::lookup). Point clouds
    /// average the nearest points whatever the radius (PointCloudLookup with
    /// radius 0: a fixed radius may hold no point), normal-aware; a point is
    /// found there only when some cloud point lies within about max(4
    /// median point radii, radius) of it, so that lookups far from the data
    /// miss as on brick maps. N zero or null: no normal.
    ///
    /// Returns false with *error when the file cannot be opened or has none
    /// of the channels. Channels missing individually get channel_floats 0
    /// (no floats in out) and are named in *error ("file: no channel
    /// \"x\" (it has: a, b)"), while the call returns true for the others:
    /// the engine warns once and leaves those variables alone. found is
    /// zeroed first (every point, masked ones included).
    virtual bool texture3d(const std::string& file, std::span<const std::string> channels,
                           std::size_t count, const glm::vec3* P, const glm::vec3* N,
                           const float* radius, const uint8_t* mask,
                           std::vector<int>& channel_floats, float* out, uint8_t* found,
                           std::string* error) = 0;
};

} // namespace sss
