// The texture library: 2-D textures and environment maps through one
// OpenImageIO TextureSystem (texture, environment, textureinfo). The 3-D
// side (texture3d) is in texture3d_library.cpp.

#include "texture_library.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>

#include <OpenImageIO/texture.h>

#include "texture_library_impl.h"

namespace sss::detail {

namespace {

/// Cache bound of the texture system: tiles beyond it are evicted, so maps
/// larger than memory work, and a job does not hold gigabytes for textures.
constexpr float kCacheMegabytes = 256.0f;

float finite_or_zero(float x) {
    return std::isfinite(x) ? x : 0.0f;
}

/// RSL options -> OIIO's. The wrap modes stay WrapDefault: OIIO then takes
/// them from the file's "wrapmodes" metadata (maketx writes it), and black
/// where the file says nothing, as RenderMan does.
OIIO::TextureOpt oiio_options(const TextureOptions& options, int channel) {
    OIIO::TextureOpt opt;
    opt.firstchannel = std::max(channel, 0);
    opt.sblur = std::max(finite_or_zero(options.sblur), 0.0f);
    opt.tblur = std::max(finite_or_zero(options.tblur), 0.0f);
    opt.swidth = std::max(finite_or_zero(options.swidth), 0.0f);
    opt.twidth = std::max(finite_or_zero(options.twidth), 0.0f);
    opt.fill = options.fill;
    opt.samples = std::max(options.samples, 1);
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

} // namespace

bool set_texture_option(TextureOptions& options, std::string_view name,
                        const float* numbers, int count, const std::string* text) {
    const bool number = numbers && count >= 1;
    const float x = number ? numbers[0] : 0.0f;
    if (name == "blur") {
        if (number) options.sblur = options.tblur = x;
    } else if (name == "sblur") {
        if (number) options.sblur = x;
    } else if (name == "tblur") {
        if (number) options.tblur = x;
    } else if (name == "width") {
        if (number) options.swidth = options.twidth = x;
    } else if (name == "swidth") {
        if (number) options.swidth = x;
    } else if (name == "twidth") {
        if (number) options.twidth = x;
    } else if (name == "samples") {
        if (number) options.samples = std::max(1, static_cast<int>(std::lround(x)));
    } else if (name == "filter") {
        if (text) options.filter = *text;
    } else if (name == "fill") {
        if (number) options.fill = x;
    } else if (name == "lerp") {
        if (number) options.lerp = std::clamp(static_cast<int>(std::lround(x)), 0, 2);
    } else {
        return false;
    }
    return true;
}

bool set_texture3d_option(Texture3dOptions& options, std::string_view name,
                          const float* numbers, int count, const std::string* text) {
    const bool number = numbers && count >= 1;
    const float x = number ? numbers[0] : 0.0f;
    if (name == "coordsystem") {
        if (text) options.coordsystem = *text;
    } else if (name == "filterradius" || name == "radius") {
        if (number) options.filterradius = x;
    } else if (name == "filterscale" || name == "radiusscale") {
        if (number) options.filterscale = x;
    } else if (name == "maxdepth") {
        if (number) options.maxdepth = static_cast<int>(std::lround(x));
    } else if (name != "interpolate") {
        return false;
    }
    return true;
}

bool set_bake3d_option(Bake3dOptions& options, std::string_view name,
                       const float* numbers, int count, const std::string* text) {
    const bool number = numbers && count >= 1;
    const float x = number ? numbers[0] : 0.0f;
    if (name == "radius") {
        if (number) options.radius = x;
    } else if (name == "radiusscale") {
        if (number) options.radiusscale = x;
    } else if (name == "coordsystem") {
        if (text) options.coordsystem = *text;
    } else if (name == "interpolate") {
        if (number) options.interpolate = x != 0.0f;
    } else {
        return false;
    }
    return true;
}

// ---------------------------------------------------------------------------
// TextureLibrary

TextureLibrary::Impl::Impl() = default;

OIIO::TextureSystem* TextureLibrary::Impl::system() {
    std::call_once(ts_once, [this] { ts = make_texture_system(); });
    return ts;
}

OIIO::TextureSystem* TextureLibrary::Impl::make_texture_system() {
    // A private texture system (not OIIO's process-wide shared one): one per
    // job, freed with it. It adds no threads of its own; lookups run on the
    // callers' threads.
    OIIO::TextureSystem* ts = OIIO::TextureSystem::create(false);
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
    return ts;
}

TextureLibrary::Impl::~Impl() {
    if (!ts) return;
    // Leave no pending error behind (OIIO prints those at exit).
    (void)ts->geterror(true);
    OIIO::TextureSystem::destroy(ts);
}

std::shared_ptr<TextureFile> TextureLibrary::Impl::open(const std::string& file) {
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
            entry->error =
                file + ": " +
                (std::filesystem::exists(file, ec) ? "not a regular file"
                                                   : "no such file or directory");
            return;
        }
        OIIO::TextureSystem* ts = system();
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
    });
    return entry;
}

TextureLibrary::TextureLibrary() : m_impl(std::make_unique<Impl>()) {}

TextureLibrary::~TextureLibrary() = default;

bool TextureLibrary::texture(const std::string& file, int channel, int nchannels,
                             const TextureOptions& options, std::size_t count,
                             const float* s, const float* t, const float* ds_du,
                             const float* dt_du, const float* ds_dv, const float* dt_dv,
                             const uint8_t* mask, float* out, std::string* error) {
    const std::shared_ptr<TextureFile> tex = m_impl->open(file);
    if (!tex->handle) {
        if (error) *error = tex->error;
        return false;
    }
    OIIO::TextureSystem* ts = m_impl->system();
    OIIO::TextureSystem::Perthread* pt = ts->get_perthread_info();
    OIIO::TextureOpt opt = oiio_options(options, channel);
    // A grey map read as colour gives grey (RenderMan); other channels past
    // the file's last get the fill value (OIIO).
    const bool replicate = tex->nchannels == 1 && channel == 0 && nchannels == 3;
    const int read = replicate ? 1 : nchannels;
    bool ok = true;
    for (std::size_t i = 0; i < count; ++i) {
        if (mask && !mask[i]) continue;
        float* result = out + i * std::size_t(nchannels);
        const float si = s[i], ti = t[i];
        if (!std::isfinite(si) || !std::isfinite(ti)) {
            std::fill(result, result + nchannels, 0.0f);
            continue;
        }
        const float dsdx = ds_du ? finite_or_zero(ds_du[i]) : 0.0f;
        const float dtdx = dt_du ? finite_or_zero(dt_du[i]) : 0.0f;
        const float dsdy = ds_dv ? finite_or_zero(ds_dv[i]) : 0.0f;
        const float dtdy = dt_dv ? finite_or_zero(dt_dv[i]) : 0.0f;
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

bool TextureLibrary::texture_quad(const std::string& file, int channel, int nchannels,
                                  const TextureOptions& options, std::size_t count,
                                  const float* const st[8], const uint8_t* mask,
                                  float* out, std::string* error) {
    // The quad's corners are in the order of a bilinear patch's: (s1,t1) at
    // (0,0), (s2,t2) at (1,0), (s3,t3) at (0,1), (s4,t4) at (1,1) (Aqsis'
    // reading of RISpec): the lookup is at the centre, its footprint spanned
    // by the mean edges along each direction.
    std::vector<float> buf(6 * count);
    float* s = buf.data();
    float* t = s + count;
    float* ds_du = t + count;
    float* dt_du = ds_du + count;
    float* ds_dv = dt_du + count;
    float* dt_dv = ds_dv + count;
    for (std::size_t i = 0; i < count; ++i) {
        const float s1 = st[0][i], t1 = st[1][i], s2 = st[2][i], t2 = st[3][i];
        const float s3 = st[4][i], t3 = st[5][i], s4 = st[6][i], t4 = st[7][i];
        s[i] = 0.25f * (s1 + s2 + s3 + s4);
        t[i] = 0.25f * (t1 + t2 + t3 + t4);
        ds_du[i] = 0.5f * ((s2 - s1) + (s4 - s3));
        dt_du[i] = 0.5f * ((t2 - t1) + (t4 - t3));
        ds_dv[i] = 0.5f * ((s3 - s1) + (s4 - s2));
        dt_dv[i] = 0.5f * ((t3 - t1) + (t4 - t2));
    }
    return texture(file, channel, nchannels, options, count, s, t, ds_du, dt_du, ds_dv,
                   dt_dv, mask, out, error);
}

bool TextureLibrary::environment(const std::string& file, int channel, int nchannels,
                                 const TextureOptions& options, std::size_t count,
                                 const glm::vec3* dir, const glm::vec3* ddir_du,
                                 const glm::vec3* ddir_dv, const uint8_t* mask,
                                 float* out, std::string* error) {
    const std::shared_ptr<TextureFile> tex = m_impl->open(file);
    if (!tex->handle) {
        if (error) *error = tex->error;
        return false;
    }
    OIIO::TextureSystem* ts = m_impl->system();
    OIIO::TextureSystem::Perthread* pt = ts->get_perthread_info();
    OIIO::TextureOpt opt = oiio_options(options, channel);
    const bool replicate = tex->nchannels == 1 && channel == 0 && nchannels == 3;
    const int read = replicate ? 1 : nchannels;
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
        glm::vec3 dx = ddir_du ? ddir_du[i] : zero;
        glm::vec3 dy = ddir_dv ? ddir_dv[i] : zero;
        for (int a = 0; a < 3; ++a) {
            dx[a] = finite_or_zero(dx[a]);
            dy[a] = finite_or_zero(dy[a]);
        }
        ok &= ts->environment(tex->handle, pt, opt, r, dx, dy, read, result);
        if (replicate) result[1] = result[2] = result[0];
    }
    if (!ok) {
        if (error) *error = file_error(file, ts->geterror(true));
        return false;
    }
    return true;
}

bool TextureLibrary::texture_info(const std::string& file, const std::string& key,
                                  int expected_floats, float* numbers,
                                  std::string* text) {
    const std::shared_ptr<TextureFile> tex = m_impl->open(file);
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
        OIIO::TextureSystem* ts = m_impl->system();
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

} // namespace sss::detail
