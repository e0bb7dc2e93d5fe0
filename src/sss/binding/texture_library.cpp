// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// The texture library: 2-D textures and
// environment maps forwarded to the OpenImageIO plugin (texture2d_backend.h,
// plugin/texture2d_oiio.cpp), loaded on first use. The 3-D side (texture3d)
// is in texture3d_library.cpp.

#include "sss/binding/texture_library.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>

#include <cstdlib>
#include <dlfcn.h>

#include "sss/image/image_check.h"
#include "sss/scene/scene.h"
#include "sss/util/install_layout.h"
#include "sss/util/job_files.h"
#include "texture2d_backend.h"
#include "texture_library_impl.h"

namespace sss {

using detail::kTexture2dEntry;
using detail::kTexture2dPlugin;
using detail::MakeTexture2dBackend;
using detail::Texture2dBackend;

namespace {

/// False (with *error) when `file` is an output of the running job: a file
/// the job writes is never read (docs/cli-conventions.md).
bool readable_by_job(const std::string& file, const char* use, std::string* error) {
    std::string conflict = JobFiles::opened(file, use);
    if (conflict.empty()) return true;
    if (error) *error = std::move(conflict);
    return false;
}

} // namespace

// ---------------------------------------------------------------------------
// TextureLibrary

TextureLibrary::Impl::Impl() = default;

TextureLibrary::Impl::~Impl() = default;

Texture2dBackend* TextureLibrary::Impl::textures(std::string* error) {
    std::call_once(plugin_once, [this] {
        // SSS_PLUGIN_DIR, else the plugin folder beside the running tool
        // (the install's <libdir>/sss or the build tree's lib/).
        std::string dir;
        if (const char* env = std::getenv("SSS_PLUGIN_DIR"); env && *env)
            dir = env;
        else
            dir = data_folder(DataFolder::Plugins);
        const std::string path = (std::filesystem::path(dir) / kTexture2dPlugin).string();
        // Never closed: the backend's code must outlive it, up to exit.
        void* lib = ::dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
        if (!lib) {
            const char* why = ::dlerror();
            plugin_error =
                "2-D textures need " + path + " (" + (why ? why : "not found") + ")";
            return;
        }
        auto make = reinterpret_cast<MakeTexture2dBackend>(::dlsym(lib, kTexture2dEntry));
        if (!make) {
            plugin_error = path + " has no " + kTexture2dEntry;
            return;
        }
        backend.reset(make());
        loaded.store(backend.get(), std::memory_order_release);
    });
    if (!backend && error) *error = plugin_error;
    return backend.get();
}

std::string TextureLibrary::Impl::resolve(const std::string& file, bool* missing) {
    *missing = false;
    if (search_path.empty() || file.empty() || std::filesystem::path(file).is_absolute())
        return file;
    {
        std::lock_guard lock(mutex);
        if (auto it = found.find(file); it != found.end()) return it->second;
    }
    // Not remembered when missing: a file the job writes later is found then.
    const std::optional<std::string> where = find_on_search_path(search_path, file);
    if (!where) {
        *missing = true;
        return file;
    }
    std::lock_guard lock(mutex);
    found.emplace(file, *where);
    return *where;
}

bool TextureLibrary::Impl::image_ok(const std::string& file, std::string* error) {
    std::shared_ptr<detail::CheckedImage> entry;
    {
        std::lock_guard lock(mutex);
        auto& slot = checked[file];
        if (!slot) slot = std::make_shared<detail::CheckedImage>();
        entry = slot;
    }
    std::call_once(entry->once, [&] {
        std::error_code ec;
        if (!std::filesystem::is_regular_file(file, ec)) return; // the plugin says why
        try {
            // PNG files whole without OpenImageIO; other headers through the
            // plugin, which this process loads for the lookup anyway.
            if (check_png_file(file)) return;
            ImageHeader header;
            if (Texture2dBackend* backend = textures(nullptr);
                backend && backend->image_header(file, header))
                check_image_header(file, header);
        } catch (const Error& e) {
            entry->error = e.what();
        } catch (const std::bad_alloc&) {
            entry->error = file + ": out of memory while checking the image";
        }
    });
    if (entry->error.empty()) return true;
    if (error) *error = entry->error;
    return false;
}

std::string TextureLibrary::Impl::path_note() const {
    return " (not found along the texture search path \"" +
           search_path_text(search_path) + "\", relative to the working folder)";
}

TextureLibrary::TextureLibrary() : m_impl(std::make_unique<Impl>()) {}

void TextureLibrary::set_search_path(std::vector<std::string> path) {
    m_impl->search_path = std::move(path);
}

TextureLibrary::~TextureLibrary() = default;

bool TextureLibrary::texture(const std::string& name, int channel, int nchannels,
                             const TextureOptions& options, std::size_t count,
                             const float* s, const float* t, const float* ds_du,
                             const float* dt_du, const float* ds_dv, const float* dt_dv,
                             const uint8_t* mask, float* out, std::string* error) {
    bool missing = false;
    const std::string file = m_impl->resolve(name, &missing);
    if (!readable_by_job(file, "a texture lookup", error)) return false;
    if (!m_impl->image_ok(file, error)) return false;
    Texture2dBackend* b = m_impl->textures(error);
    const bool ok = b && b->texture(file, channel, nchannels, options, count, s, t, ds_du,
                                    dt_du, ds_dv, dt_dv, mask, out, error);
    if (!ok && missing && error) *error += m_impl->path_note();
    return ok;
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

bool TextureLibrary::environment(const std::string& name, int channel, int nchannels,
                                 const TextureOptions& options, std::size_t count,
                                 const glm::vec3* dir, const glm::vec3* ddir_du,
                                 const glm::vec3* ddir_dv, const uint8_t* mask,
                                 float* out, std::string* error) {
    bool missing = false;
    const std::string file = m_impl->resolve(name, &missing);
    if (!readable_by_job(file, "an environment lookup", error)) return false;
    if (!m_impl->image_ok(file, error)) return false;
    Texture2dBackend* b = m_impl->textures(error);
    const bool ok = b && b->environment(file, channel, nchannels, options, count, dir,
                                        ddir_du, ddir_dv, mask, out, error);
    if (!ok && missing && error) *error += m_impl->path_note();
    return ok;
}

bool TextureLibrary::texture_info(const std::string& name, const std::string& key,
                                  int expected_floats, float* numbers,
                                  std::string* text) {
    bool missing = false;
    const std::string file = m_impl->resolve(name, &missing);
    if (!readable_by_job(file, "a textureinfo lookup", nullptr)) return false;
    if (!m_impl->image_ok(file, nullptr)) return false;
    Texture2dBackend* b = m_impl->textures(nullptr);
    return b && b->texture_info(file, key, expected_floats, numbers, text);
}

} // namespace sss
