// The 2-D texture plugin (texture2d_backend.h): texture(), environment()
// and textureinfo() through one OpenImageIO TextureSystem per job. Built as
// libsss_texture2d.so and loaded by TextureLibrary on first use.

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <memory>
#include <mutex>
#include <unordered_map>

#include <OpenImageIO/texture.h>

#include "texture2d_backend.h"

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

namespace {

/// A 2-D texture or environment map as opened by the texture system.
struct TextureFile {
    std::once_flag once;
    OIIO::TextureSystem::TextureHandle* handle = nullptr; ///< null: unreadable
    std::string error;                                    ///< "file: reason"
    int nchannels = 0;
    int width = 0, height = 0;
    std::string format; ///< OIIO "textureformat" ("" for plain images)
};

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

private:
    std::shared_ptr<TextureFile> open(const std::string& file);
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
            entry->error =
                file + ": " +
                (std::filesystem::exists(file, ec) ? "not a regular file"
                                                   : "no such file or directory");
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

} // namespace

} // namespace sss::detail

extern "C" __attribute__((visibility("default"))) sss::detail::Texture2dBackend*
sss_make_texture2d_backend() {
    return new sss::detail::OiioTextures();
}
