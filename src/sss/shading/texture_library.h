#pragma once
// Internal to the shading module: the texture library the engine calls for
// RSL's texture, environment, textureinfo, texture3d (and the file side of
// bake3d). 2-D and environment maps go through one OpenImageIO
// TextureSystem; 3-D textures (brick maps, point clouds) reuse the lookups
// of the brick and cloud modules with the renderer's semantics (brick maps
// blend levels by radius, point clouds use the nearest points).

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <glm/vec3.hpp>

namespace sss::detail {

/// Filtering options of texture/environment/shadow calls (RSL token-value lists).
struct TextureOptions {
    float sblur = 0, tblur = 0;   // "blur" sets both; in texture units (1 = whole map)
    float swidth = 1, twidth = 1; // "width" sets both; multiplies the filter footprint;
                                  // 0 = no filtering
    int samples = 1;
    std::string filter = "box"; // "box", "gaussian", "none" (nearest)
    float fill = 0;             // value of channels past the file's last
    int lerp = 2;               // mip interpolation hint
};

/// Sets option `name` from a token-value pair (numbers: count floats; text
/// for strings). False for an unknown name (the engine warns once).
bool set_texture_option(TextureOptions& options, std::string_view name,
                        const float* numbers, int count, const std::string* text);

/// 2-D textures through one OpenImageIO TextureSystem (MIP-mapped .tx/.tex
/// made by maketx, and any image OIIO reads, MIP-mapped on the fly),
/// environment maps (lat-long, and cube maps OIIO supports) and 3-D textures
/// (brick maps, point clouds), opened once per file. Thread-safe; one per
/// job (owned by ShadingResources).
class TextureLibrary {
public:
    TextureLibrary();
    ~TextureLibrary();
    TextureLibrary(const TextureLibrary&) = delete;
    TextureLibrary& operator=(const TextureLibrary&) = delete;

    /// texture(file[channel], s, t): nchannels (1 for float, 3 for color)
    /// floats per point into out (count*nchannels), for the points whose mask
    /// byte is non-zero (mask may be null: every point). The filter footprint
    /// is given by the derivatives of s,t along the grid's two directions
    /// (ds/du*du etc., i.e. differences to the neighbour points); null
    /// derivative arrays = point sampling. Channels past the file's last get
    /// options.fill; a 1-channel file read as colour replicates it (RenderMan
    /// behaviour). Returns false (and sets *error to "file: reason") when the
    /// file cannot be read; the engine reports that once and leaves the
    /// result 0.
    bool texture(const std::string& file, int channel, int nchannels,
                 const TextureOptions& options, std::size_t count, const float* s,
                 const float* t, const float* ds_du, const float* dt_du,
                 const float* ds_dv, const float* dt_dv, const uint8_t* mask, float* out,
                 std::string* error);
    /// The 4-point form: the quad (s1,t1)...(s4,t4) per point is the filter
    /// region (st[0..7] = s1,t1,s2,t2,s3,t3,s4,t4, each count floats).
    bool texture_quad(const std::string& file, int channel, int nchannels,
                      const TextureOptions& options, std::size_t count,
                      const float* const st[8], const uint8_t* mask, float* out,
                      std::string* error);
    /// environment(file[channel], dir): world-space directions, footprint
    /// from the direction's differences (may be null).
    bool environment(const std::string& file, int channel, int nchannels,
                     const TextureOptions& options, std::size_t count,
                     const glm::vec3* dir, const glm::vec3* ddir_du,
                     const glm::vec3* ddir_dv, const uint8_t* mask, float* out,
                     std::string* error);
    /// textureinfo(file, key, out): "resolution" (2 floats), "channels" (1),
    /// "type" ("texture", "environment", "shadow"),
    /// "viewingmatrix"/"projectionmatrix" (16, when the file has them: OIIO
    /// worldtocamera/worldtoscreen). Returns false for an unknown key, a
    /// missing file, or a value type mismatch (expected_floats: how many
    /// floats the caller's variable holds; 0 for a string).
    bool texture_info(const std::string& file, const std::string& key,
                      int expected_floats, float* numbers, std::string* text);
    /// texture3d(file, P, N, "channel", out...): world-space P, N, filter
    /// radius per point (0: the nearest points). For each requested channel
    /// name, its floats per point go to channel_floats (1 float, 3
    /// colour/point/vector/normal, 16 matrix); out gets, per point, all
    /// requested channels' floats in order (stride: the sum of
    /// channel_floats). found[i] = 1 where the lookup found data (RSL rule:
    /// where not found the engine leaves the shader's variables unchanged).
    ///
    /// Returns false with *error when the file cannot be opened or has none
    /// of the channels. Channels missing individually get channel_floats 0
    /// (no floats in out) and are named in *error ("file: no channel
    /// \"x\""), while the call returns true for the others.
    bool texture3d(const std::string& file, std::span<const std::string> channels,
                   std::size_t count, const glm::vec3* P, const glm::vec3* N,
                   const float* radius, const uint8_t* mask,
                   std::vector<int>& channel_floats, float* out, uint8_t* found,
                   std::string* error);

    /// Forgets what is known of `file` (2-D and 3-D), so that the next call
    /// opens it again: for a file written during the job (bake3d, then
    /// texture3d). Unreadable files are otherwise remembered as such.
    void invalidate(const std::string& file);

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

} // namespace sss::detail
