// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// The 2-D texture plugin (texture2d_backend.h): texture(), environment()
// and textureinfo() through one OpenImageIO TextureSystem per job. Built as
// libsss_texture2d.so and loaded by TextureLibrary on first use.
//
// Environment maps: lat-long maps go to OIIO's environment(); cube-face maps
// (which OIIO's environment() does not read) are looked up here, face by
// face, with OIIO's texture() on the whole image (see CubeFace below).

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <memory>
#include <mutex>
#include <sstream>
#include <unordered_map>

#include <OpenImageIO/filter.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/texture.h>

#include <glm/geometric.hpp>

#include "texture2d_backend.h"
#include "texture2d_makers.h"

namespace sss::detail {

namespace {

/// Cache bound of the texture system: tiles beyond it are evicted, so maps
/// larger than memory work, and a job does not hold gigabytes for textures.
constexpr float kCacheMegabytes = 256.0f;

float finite_or_zero(float x) {
    return std::isfinite(x) ? x : 0.0f;
}

/// Bounds of the filter's options and footprints before OpenImageIO sees
/// them: its filters assert on footprints whose squares overflow (a "width"
/// of 1e38). A blur of 1 already averages the whole map, a footprint of 4
/// (texture units) reaches the coarsest level, and a width beyond 1000 only
/// multiplies derivatives to such footprints.
constexpr float kMaxBlur = 1.0f;
constexpr float kMaxWidth = 1000.0f;
constexpr float kMaxFootprint = 4.0f;

float clamp_option(float x, float hi) {
    return std::clamp(finite_or_zero(x), 0.0f, hi);
}

/// A footprint axis (ds, dt along x or y) times the widths, finite and at
/// most kMaxFootprint long: scaled as a whole (clamping each component
/// would turn a wide ellipse into a line, on which OpenImageIO's blur
/// asserts).
void footprint_axis(float ds, float dt, float swidth, float twidth, float& s, float& t) {
    s = finite_or_zero(ds * swidth);
    t = finite_or_zero(dt * twidth);
    const float len = std::hypot(s, t);
    if (!std::isfinite(len)) {
        s = t = 0.0f;
    } else if (len > kMaxFootprint) {
        s *= kMaxFootprint / len;
        t *= kMaxFootprint / len;
    }
}

/// Gives a footprint that is a line (its axes parallel, or one of them zero)
/// a width of a thousandth of its length: OpenImageIO's blur asserts on an
/// ellipse without area. Only with blur; a point (both axes zero) is fine.
void widen_line(float& dsdx, float& dtdx, float& dsdy, float& dtdy) {
    const float lx = std::hypot(dsdx, dtdx), ly = std::hypot(dsdy, dtdy);
    const float major = std::max(lx, ly);
    if (!(major > 0.0f)) return;
    if (std::abs(dsdx * dtdy - dtdx * dsdy) > 1e-3f * major * major) return;
    // The minor axis: perpendicular to the major one.
    const float ms = lx >= ly ? dsdx : dsdy, mt = lx >= ly ? dtdx : dtdy;
    const float ps = -mt * 1e-3f, pt = ms * 1e-3f;
    if (lx >= ly) {
        dsdy = ps;
        dtdy = pt;
    } else {
        dsdx = ps;
        dtdx = pt;
    }
}

/// A direction's derivative, finite and at most kMaxFootprint times as long
/// as the direction.
glm::vec3 direction_footprint(glm::vec3 d, const glm::vec3& dir) {
    for (int a = 0; a < 3; ++a) d[a] = finite_or_zero(d[a]);
    const float len = glm::length(d), most = kMaxFootprint * glm::length(dir);
    return std::isfinite(len) && len > most && len > 0.0f ? d * (most / len) : d;
}

/// RSL options -> OIIO's. The wrap modes stay WrapDefault: OIIO then takes
/// them from the file's "wrapmodes" metadata (maketx writes it); the caller
/// makes a file that says nothing periodic (TextureFile::periodic).
OIIO::TextureOpt oiio_options(const TextureOptions& options, int channel) {
    OIIO::TextureOpt opt;
    opt.firstchannel = std::max(channel, 0);
    opt.sblur = clamp_option(options.sblur, kMaxBlur);
    opt.tblur = clamp_option(options.tblur, kMaxBlur);
    opt.swidth = clamp_option(options.swidth, kMaxWidth);
    opt.twidth = clamp_option(options.twidth, kMaxWidth);
    opt.fill = finite_or_zero(options.fill);
    opt.samples = std::clamp(options.samples, 1, 1024);
    // Bilinear within a level: a point lookup at a pixel's centre returns
    // that pixel (OIIO's bicubic is a B-spline, which blurs even there).
    opt.interpmode = OIIO::TextureOpt::InterpBilinear;
    switch (options.lerp) {
    case 0:
        opt.mipmode = OIIO::TextureOpt::MipModeOneLevel;
        break;
    case 1:
        opt.mipmode = OIIO::TextureOpt::MipModeTrilinear;
        break;
    default:
        opt.mipmode = OIIO::TextureOpt::MipModeDefault;
        break; // anisotropic
    }
    if (options.filter == "none" || options.filter == "nearest") {
        opt.interpmode = OIIO::TextureOpt::InterpClosest;
        opt.mipmode = OIIO::TextureOpt::MipModeOneLevel;
    } else if (options.filter != "box") {
        // gaussian, triangle, catmull-rom, sinc...: the smoother of OIIO's
        // kernels (bicubic when magnifying).
        opt.interpmode = OIIO::TextureOpt::InterpSmartBicubic;
    }
    return opt;
}

/// "file: reason" from OIIO's message: its first line, without OIIO's own
/// "Could not open file:" and repetitions of the file name.
std::string file_error(const std::string& file, std::string reason) {
    reason = reason.substr(0, reason.find('\n'));
    for (const std::string& prefix : {std::string("Could not open file: "), file + ": "})
        if (reason.rfind(prefix, 0) == 0) reason.erase(0, prefix.size());
    while (!reason.empty() && reason.back() == ' ') reason.pop_back();
    if (reason.empty()) reason = "cannot be read as a texture";
    return file + ": " + reason;
}

/// How environment() reads a file, decided once when it is opened.
enum class EnvLayout {
    LatLong,      ///< OIIO's environment() (lat-long; plain images are read as such)
    CubeOneBySix, ///< OpenEXR's cube-face map, looked up by cube_lookup()
    Invalid,      ///< tagged as a cube map with a layout we do not read
};

/// A direction's place on an OpenEXR cube-face map (ImfEnvmap.h): the face
/// (0..5: +X, -X, +Y, -Y, +Z, -Z, stacked top to bottom in an N x 6N image)
/// and the face coordinates a (image left to right) and b (top to bottom) in
/// [-1, 1]. Each face is seen from the cube's centre, +y up on the four side
/// faces; on +Y the image's bottom edge is towards -z, on -Y towards +z:
///
///     face  a (right)  b (down)
///     +X      +z        -y
///     -X      -z        -y
///     +Y      +x        -z
///     -Y      +x        +z
///     +Z      -x        -y
///     -Z      +x        -y
///
/// a = +-1 and b = +-1 are the centres of the face's border pixels (OpenEXR
/// maps pixel centres 0..N-1 to the cube's edges; OIIO reads such files with
/// "oiio:sampleborder" = 1).
struct CubeFace {
    int face = 0;
    int major = 0; ///< axis of the face's normal
    int a_axis = 0, b_axis = 0;
    float a_sign = 1, b_sign = 1;
};

CubeFace cube_face(const glm::vec3& d) {
    const glm::vec3 m(std::abs(d.x), std::abs(d.y), std::abs(d.z));
    const int major = m.x >= m.y && m.x >= m.z ? 0 : (m.y >= m.z ? 1 : 2);
    // {a axis, a sign, b axis, b sign} per face, from the table above.
    static constexpr int kAxes[6][4] = {{2, 1, 1, -1}, {2, -1, 1, -1}, {0, 1, 2, -1},
                                        {0, 1, 2, 1},  {0, -1, 1, -1}, {0, 1, 1, -1}};
    CubeFace f;
    f.major = major;
    f.face = 2 * major + (d[major] < 0.0f ? 1 : 0);
    f.a_axis = kAxes[f.face][0];
    f.a_sign = static_cast<float>(kAxes[f.face][1]);
    f.b_axis = kAxes[f.face][2];
    f.b_sign = static_cast<float>(kAxes[f.face][3]);
    return f;
}

/// The face coordinate sign * d[axis] / |d[major]| and its derivative along
/// dd (the quotient rule), for a direction d on face f.
void face_coordinate(const CubeFace& f, int axis, float sign, const glm::vec3& d,
                     const glm::vec3& dd, float& x, float& dx) {
    const float q = std::abs(d[f.major]);
    const float dq = d[f.major] < 0.0f ? -dd[f.major] : dd[f.major];
    x = sign * d[axis] / q;
    dx = sign * (dd[axis] * q - d[axis] * dq) / (q * q);
}

} // namespace

namespace {

/// A 2-D texture or environment map as opened by the texture system.
struct TextureFile {
    std::once_flag once;
    OIIO::TextureSystem::TextureHandle* handle = nullptr; ///< null: unreadable
    std::string error;                                    ///< "file: reason"
    int nchannels = 0;
    int width = 0, height = 0;
    std::string format; ///< OIIO "textureformat" ("" for plain images)
    /// "oiio:sampleborder": s = 0 and 1 are the border pixels' centres.
    bool sample_border = false;
    /// The file names no wrap modes (a plain image, not made by maketx):
    /// looked up periodic in s and t, so that filters reaching across s = 0
    /// or 1 (the seam of a sphere, a torus, a cylinder) find the other edge
    /// of the map, not black.
    bool periodic = false;
    EnvLayout env = EnvLayout::LatLong;
    std::string env_error; ///< "file: reason" when env is Invalid
};

/// The environment layout of an opened file. OIIO reads OpenEXR's "envmap"
/// attribute as "textureformat": "CubeFace Environment" for a cube map (and
/// writes it back the same way); maketx tags its cube maps so too.
void decide_env_layout(TextureFile& tex, const std::string& file,
                       const OIIO::ImageSpec& spec) {
    if (tex.format != "CubeFace Environment") return; // lat-long (OIIO)
    const int n = spec.width;
    const bool one_by_six = n > 0 && spec.height == 6 * n;
    // The display window: the whole image, or (as OIIO writes cube maps to
    // OpenEXR) the first face.
    const bool whole = spec.x == spec.full_x && spec.y == spec.full_y &&
                       spec.full_width == spec.width &&
                       (spec.full_height == spec.height || spec.full_height == n);
    if (one_by_six && whole) {
        tex.env = EnvLayout::CubeOneBySix;
        return;
    }
    tex.env = EnvLayout::Invalid;
    const std::string expected =
        "expected OpenEXR's layout: six N x N faces stacked top to bottom (+X, -X, +Y, "
        "-Y, +Z, -Z), an N x 6N image whose display window is the whole image or the "
        "first face";
    std::string got = std::to_string(spec.width) + " x " + std::to_string(spec.height);
    if (one_by_six)
        got += " with data window " + std::to_string(spec.width) + " x " +
               std::to_string(spec.height) + " at (" + std::to_string(spec.x) + ", " +
               std::to_string(spec.y) + ") and display window " +
               std::to_string(spec.full_width) + " x " +
               std::to_string(spec.full_height) + " at (" + std::to_string(spec.full_x) +
               ", " + std::to_string(spec.full_y) + ")";
    else if (spec.width * 2 == spec.height * 3)
        got += " (a 3 x 2 arrangement of faces: not read, its face order is not "
               "documented)";
    tex.env_error = file + ": cube-face environment map of " + got + "; " + expected;
}

class OiioTextures final : public Texture2dBackend {
public:
    OiioTextures();
    ~OiioTextures() override;
    bool texture(const std::string& file, int channel, int nchannels,
                 const TextureOptions& options, std::size_t count, const float* s,
                 const float* t, const float* ds_du, const float* dt_du,
                 const float* ds_dv, const float* dt_dv, const uint8_t* mask, float* out,
                 std::string* error) override;
    bool environment(const std::string& file, int channel, int nchannels,
                     const TextureOptions& options, std::size_t count,
                     const glm::vec3* dir, const glm::vec3* ddir_du,
                     const glm::vec3* ddir_dv, const uint8_t* mask, float* out,
                     std::string* error) override;
    bool texture_info(const std::string& file, const std::string& key,
                      int expected_floats, float* numbers, std::string* text) override;
    void invalidate(const std::string& file) override;
    bool make_texture(const std::string& input, const std::string& output, bool latlong,
                      const std::string& wrapmodes, const std::string& filter,
                      std::string* error) override;
    bool image_header(const std::string& file, ImageHeader& out) override {
        // Only the header: OpenImageIO's readers allocate nothing more on open.
        std::unique_ptr<OIIO::ImageInput> in = OIIO::ImageInput::open(file);
        if (!in) {
            (void)OIIO::geterror(); // the lookup that follows says why
            return false;
        }
        const OIIO::ImageSpec& spec = in->spec();
        out.width = spec.width;
        out.height = spec.height;
        out.channels = spec.nchannels;
        out.tile_width = spec.tile_width;
        out.tile_height = spec.tile_height;
        return true;
    }
    bool read_depth_map(const std::string& file, DepthMapData& out,
                        std::string* error) override {
        return read_depth_map_file(file, out, error);
    }
    bool make_shadow(const std::string& input, const std::string& output,
                     std::string* error) override {
        return make_shadow_file(input, output, error);
    }
    bool make_cube_environment(const std::array<std::string, 6>& faces,
                               const std::string& output, double fov,
                               const std::string& filter, std::string* error) override {
        return make_cube_environment_file(faces, output, fov, filter, error);
    }

private:
    std::shared_ptr<TextureFile> open(const std::string& file);
    bool cube_lookup(const TextureFile& tex, OIIO::TextureSystem::Perthread* pt,
                     OIIO::TextureOpt& options, const glm::vec3& dir,
                     const glm::vec3& ddir_du, const glm::vec3& ddir_dv, int nchannels,
                     float* out);
    OIIO::TextureSystem* ts = nullptr;
    std::mutex mutex; ///< guards `files` (not the files' contents)
    std::unordered_map<std::string, std::shared_ptr<TextureFile>> files;
};

OiioTextures::OiioTextures() {
    // A private texture system (not OIIO's process-wide shared one): one per
    // job, freed with it. It adds no threads of its own; lookups run on the
    // callers' threads.
    ts = OIIO::TextureSystem::create(false);
    ts->attribute("max_memory_MB", kCacheMegabytes);
    // Scanline images (PNG, JPEG, untiled TIFF/EXR): MIP-mapped on the fly,
    // read in tiles, so blurred lookups filter and large files stay cheap.
    ts->attribute("automip", 1);
    ts->attribute("autotile", 64);
    ts->attribute("accept_untiled", 1);
    ts->attribute("accept_unmipped", 1);
    // Lat-long maps without an up direction of their own: +y up.
    ts->attribute("latlong_up", "y");
    // The library replicates grey itself (texture()), only for channel 0.
    ts->attribute("gray_to_rgb", 0);
}

OiioTextures::~OiioTextures() {
    // Leave no pending error behind (OIIO prints those at exit).
    (void)ts->geterror(true);
    OIIO::TextureSystem::destroy(ts);
}

std::shared_ptr<TextureFile> OiioTextures::open(const std::string& file) {
    std::shared_ptr<TextureFile> entry;
    {
        std::lock_guard lock(mutex);
        auto& slot = files[file];
        if (!slot) slot = std::make_shared<TextureFile>();
        entry = slot;
    }
    std::call_once(entry->once, [&] {
        // A missing file is told apart here: OIIO's words for it are long.
        std::error_code ec;
        if (!std::filesystem::is_regular_file(file, ec)) {
            entry->error = file + ": " +
                           (std::filesystem::exists(file, ec)
                                ? "not a regular file"
                                : "cannot open: No such file or directory");
            return;
        }
        OIIO::TextureSystem::Perthread* pt = ts->get_perthread_info();
        entry->handle = ts->get_texture_handle(OIIO::ustring(file), pt);
        OIIO::ImageSpec spec;
        if (!entry->handle || !ts->get_imagespec(entry->handle, pt, 0, spec) ||
            !ts->good(entry->handle)) {
            entry->error = file_error(file, ts->geterror(true));
            entry->handle = nullptr;
            return;
        }
        entry->nchannels = spec.nchannels;
        entry->width = spec.full_width > 0 ? spec.full_width : spec.width;
        entry->height = spec.full_height > 0 ? spec.full_height : spec.height;
        entry->format = spec.get_string_attribute("textureformat");
        // OpenEXR keeps no "textureformat" but its cube and lat-long tags:
        // our shadow maps say theirs in an attribute of their own.
        if (entry->format.empty())
            entry->format = spec.get_string_attribute("sss:textureformat");
        entry->sample_border = spec.get_int_attribute("oiio:sampleborder") != 0;
        entry->periodic = spec.get_string_attribute("wrapmodes").empty();
        decide_env_layout(*entry, file, spec);
    });
    return entry;
}

bool OiioTextures::texture(const std::string& file, int channel, int nchannels,
                           const TextureOptions& options, std::size_t count,
                           const float* s, const float* t, const float* ds_du,
                           const float* dt_du, const float* ds_dv, const float* dt_dv,
                           const uint8_t* mask, float* out, std::string* error) {
    const std::shared_ptr<TextureFile> tex = open(file);
    if (!tex->handle) {
        if (error) *error = tex->error;
        return false;
    }
    OIIO::TextureSystem::Perthread* pt = ts->get_perthread_info();
    OIIO::TextureOpt opt = oiio_options(options, channel);
    if (tex->periodic) opt.swrap = opt.twrap = OIIO::TextureOpt::WrapPeriodic;
    // A grey map read as colour gives grey (RenderMan); other channels past
    // the file's last get the fill value, here: OpenImageIO asserts when it
    // is asked for channels a tile does not hold.
    const bool replicate = tex->nchannels == 1 && channel == 0 && nchannels == 3;
    const int read = replicate ? 1 : std::clamp(tex->nchannels - channel, 0, nchannels);
    // The widths applied here, so that each footprint is bounded.
    const float sw = opt.swidth, tw = opt.twidth;
    opt.swidth = opt.twidth = 1.0f;
    const bool blur = opt.sblur > 0.0f || opt.tblur > 0.0f;
    bool ok = true;
    for (std::size_t i = 0; i < count; ++i) {
        if (mask && !mask[i]) continue;
        float* result = out + i * std::size_t(nchannels);
        const float si = s[i], ti = t[i];
        if (!std::isfinite(si) || !std::isfinite(ti)) {
            std::fill(result, result + nchannels, 0.0f);
            continue;
        }
        if (!replicate) std::fill(result + read, result + nchannels, opt.fill);
        if (read == 0) continue;
        float dsdx, dtdx, dsdy, dtdy;
        footprint_axis(ds_du ? ds_du[i] : 0.0f, dt_du ? dt_du[i] : 0.0f, sw, tw, dsdx,
                       dtdx);
        footprint_axis(ds_dv ? ds_dv[i] : 0.0f, dt_dv ? dt_dv[i] : 0.0f, sw, tw, dsdy,
                       dtdy);
        if (blur) widen_line(dsdx, dtdx, dsdy, dtdy);
        ok &= ts->texture(tex->handle, pt, opt, si, ti, dsdx, dtdx, dsdy, dtdy, read,
                          result);
        if (replicate) result[1] = result[2] = result[0];
    }
    if (!ok) {
        // A file that opened but fails to read (truncated tiles...).
        if (error) *error = file_error(file, ts->geterror(true));
        return false;
    }
    return true;
}

bool OiioTextures::environment(const std::string& file, int channel, int nchannels,
                               const TextureOptions& options, std::size_t count,
                               const glm::vec3* dir, const glm::vec3* ddir_du,
                               const glm::vec3* ddir_dv, const uint8_t* mask, float* out,
                               std::string* error) {
    const std::shared_ptr<TextureFile> tex = open(file);
    if (!tex->handle) {
        if (error) *error = tex->error;
        return false;
    }
    if (tex->env == EnvLayout::Invalid) {
        if (error) *error = tex->env_error;
        return false;
    }
    const bool cube = tex->env == EnvLayout::CubeOneBySix;
    OIIO::TextureSystem::Perthread* pt = ts->get_perthread_info();
    OIIO::TextureOpt opt = oiio_options(options, channel);
    if (cube) {
        // Blur in face units both ways (t spans the display window: six
        // faces or one), at most half a face (see cube_lookup); and the
        // image's own edge pixels at its top and bottom, not black, when a
        // coarse level's filter reaches past them.
        opt.sblur = std::min(opt.sblur, 0.5f);
        opt.tblur = std::min(opt.tblur, 0.5f) / 6.0f;
        opt.swrap = opt.twrap = OIIO::TextureOpt::WrapClamp;
    }
    const bool replicate = tex->nchannels == 1 && channel == 0 && nchannels == 3;
    const int read = replicate ? 1 : std::clamp(tex->nchannels - channel, 0, nchannels);
    const glm::vec3 zero(0.0f);
    bool ok = true;
    for (std::size_t i = 0; i < count; ++i) {
        if (mask && !mask[i]) continue;
        float* result = out + i * std::size_t(nchannels);
        const glm::vec3 r = dir[i];
        if (!std::isfinite(r.x) || !std::isfinite(r.y) || !std::isfinite(r.z) ||
            r == zero) {
            std::fill(result, result + nchannels, 0.0f);
            continue;
        }
        if (!replicate) std::fill(result + read, result + nchannels, opt.fill);
        if (read == 0) continue;
        const glm::vec3 dx = ddir_du ? direction_footprint(ddir_du[i], r) : zero;
        const glm::vec3 dy = ddir_dv ? direction_footprint(ddir_dv[i], r) : zero;
        if (cube)
            ok &= cube_lookup(*tex, pt, opt, r, dx, dy, read, result);
        else
            ok &= ts->environment(tex->handle, pt, opt, r, dx, dy, read, result);
        if (replicate) result[1] = result[2] = result[0];
    }
    if (!ok) {
        if (error) *error = file_error(file, ts->geterror(true));
        return false;
    }
    return true;
}

/// One lookup on an OpenEXR cube-face map (CubeFace): the direction's face
/// and position on it, as texture coordinates of the whole N x 6N image, and
/// the footprint of the direction's derivatives projected onto that face
/// (so a wider ray cone blurs). The position is moved inwards, to at least
/// half a texel of the coarsest MIP level the filter may use (1.5 texels for
/// the bicubic filters) from the face's edges, so the filter does not reach
/// into the faces above and below in the image, which are not the cube's
/// neighbours: near an edge a wide footprint sees its own face only. The
/// footprint (and blur) is capped at half a face, the widest a lookup can be
/// without reading the MIP levels coarser than one texel per face.
bool OiioTextures::cube_lookup(const TextureFile& tex, OIIO::TextureSystem::Perthread* pt,
                               OIIO::TextureOpt& opt, const glm::vec3& dir,
                               const glm::vec3& ddir_du, const glm::vec3& ddir_dv,
                               int nchannels, float* out) {
    const CubeFace f = cube_face(dir);
    float a, b, da_du, db_du, da_dv, db_dv;
    face_coordinate(f, f.a_axis, f.a_sign, dir, ddir_du, a, da_du);
    face_coordinate(f, f.b_axis, f.b_sign, dir, ddir_du, b, db_du);
    face_coordinate(f, f.a_axis, f.a_sign, dir, ddir_dv, a, da_dv);
    face_coordinate(f, f.b_axis, f.b_sign, dir, ddir_dv, b, db_dv);
    const float n = static_cast<float>(tex.width);
    // Face coordinates -> face pixels: [-1, 1] spans the border pixels' centres.
    const float pixels = 0.5f * (n - 1.0f);
    // The footprint in face pixels, at most half a face: OIIO's coarser MIP
    // levels (once a face is one texel, the 1 x 6 level) mix faces.
    const float scale = std::max(opt.swidth, opt.twidth);
    const float cone =
        std::max(std::hypot(da_du, db_du), std::hypot(da_dv, db_dv)) * pixels * scale;
    const float limit = 0.5f * n;
    const float shrink = std::isfinite(cone) && cone > limit ? limit / cone : 1.0f;
    // Blur in faces (environment() set tblur in data-window units, 6 faces).
    const float blur = std::max(opt.sblur, 6.0f * opt.tblur);
    const float footprint = std::max(cone * shrink, blur * n);
    const float texel = std::isfinite(footprint) && footprint > 1.0f
                            ? std::exp2(std::ceil(std::log2(footprint)))
                            : 1.0f;
    const bool bicubic = opt.interpmode == OIIO::TextureOpt::InterpBicubic ||
                         opt.interpmode == OIIO::TextureOpt::InterpSmartBicubic;
    const float inset = std::min((bicubic ? 1.5f : 0.5f) * texel, 0.5f * n);
    // Pixel-centre coordinates in the face (0 and n - 1: the border pixels'
    // centres), moved inwards.
    auto place = [&](float x) {
        const float p = (std::clamp(x, -1.0f, 1.0f) + 1.0f) * pixels;
        return std::clamp(p, inset - 0.5f, n - 0.5f - inset);
    };
    const float x = place(a), y = static_cast<float>(f.face) * n + place(b);
    // OIIO's texture coordinates are relative to the display window (the
    // whole image, or the first face): s = 0 and 1 are its edges. For files
    // with "oiio:sampleborder" (OIIO reads OpenEXR's envmaps so) the pixel
    // centre coordinate is s (w - 1) wd / w (w the data window's width, wd
    // the display window's; measured: OIIO 2.4).
    const float wd = static_cast<float>(tex.width), hd = static_cast<float>(tex.height);
    const float h = 6.0f * n;
    float s, t, ds, dt;
    if (tex.sample_border) {
        const float sx = n > 1.0f ? n / (wd * (n - 1.0f)) : 0.0f;
        const float sy = h / (hd * (h - 1.0f));
        s = x * sx;
        t = y * sy;
        ds = shrink * pixels * sx;
        dt = shrink * pixels * sy;
    } else {
        s = (x + 0.5f) / wd;
        t = (y + 0.5f) / hd;
        ds = shrink * pixels / wd;
        dt = shrink * pixels / hd;
    }
    auto finite = [](float x) { return finite_or_zero(x); };
    return ts->texture(tex.handle, pt, opt, s, t, finite(da_du * ds), finite(db_du * dt),
                       finite(da_dv * ds), finite(db_dv * dt), nchannels, out);
}

bool OiioTextures::texture_info(const std::string& file, const std::string& key,
                                int expected_floats, float* numbers, std::string* text) {
    const std::shared_ptr<TextureFile> tex = open(file);
    if (!tex->handle) return false;
    if (key == "resolution") {
        if (expected_floats != 2) return false;
        numbers[0] = static_cast<float>(tex->width);
        numbers[1] = static_cast<float>(tex->height);
        return true;
    }
    if (key == "channels") {
        if (expected_floats != 1) return false;
        numbers[0] = static_cast<float>(tex->nchannels);
        return true;
    }
    if (key == "type") {
        if (expected_floats != 0 || !text) return false;
        // OIIO's "textureformat" (maketx): "Plain Texture", "LatLong
        // Environment", "CubeFace Environment", "Shadow", "CubeFace
        // Shadow"...; images without one are plain textures.
        const std::string& f = tex->format;
        if (f.find("Environment") != std::string::npos)
            *text = "environment";
        else if (f.find("Shadow") != std::string::npos)
            *text = "shadow";
        else
            *text = "texture";
        return true;
    }
    if (key == "viewingmatrix" || key == "projectionmatrix") {
        if (expected_floats != 16) return false;
        const char* name = key == "viewingmatrix" ? "worldtocamera" : "worldtoscreen";
        float m[16];
        if (!ts->get_texture_info(tex->handle, ts->get_perthread_info(), 0,
                                  OIIO::ustring(name), OIIO::TypeMatrix, m)) {
            (void)ts->geterror(true); // "no such attribute" is not an error here
            return false;
        }
        std::memcpy(numbers, m, sizeof m);
        return true;
    }
    return false;
}

void OiioTextures::invalidate(const std::string& file) {
    {
        std::lock_guard lock(mutex);
        // Calls in flight keep their entries (shared_ptr) until they finish.
        files.erase(file);
    }
    ts->invalidate(OIIO::ustring(file), true);
}

bool OiioTextures::make_texture(const std::string& input, const std::string& output,
                                bool latlong, const std::string& wrapmodes,
                                const std::string& filter, std::string* error) {
    if (!known_filter(filter)) {
        *error = "unknown filter \"" + filter + "\"";
        return false;
    }
    OIIO::ImageSpec config;
    config.attribute("wrapmodes", wrapmodes);
    config.attribute("maketx:filtername", filter);
    config.attribute("maketx:fileformatname", "tiff");
    std::ostringstream log;
    const auto mode =
        latlong ? OIIO::ImageBufAlgo::MakeTxEnvLatl : OIIO::ImageBufAlgo::MakeTxTexture;
    if (OIIO::ImageBufAlgo::make_texture(mode, input, output, config, &log)) return true;
    *error = OIIO::geterror();
    if (error->empty()) *error = log.str();
    return false;
}

} // namespace

} // namespace sss::detail

extern "C" __attribute__((visibility("default"))) sss::detail::Texture2dBackend*
sss_make_texture2d_backend() {
    return new sss::detail::OiioTextures();
}
