// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// The texture library's 3-D side: texture3d on brick maps and point clouds,
// as RenderMan looks them up: brick maps blend their levels by the filter
// radius, point clouds average their nearest points (sss::CloudTexture3d).

#include "sss/binding/texture_library.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <filesystem>

#include "sss/cloud/point_cloud_io.h"
#include "sss/util/error.h"
#include "sss/util/job_files.h"
#include "texture2d_backend.h"
#include "texture_library_impl.h"

namespace sss::detail {

namespace {

bool ends_with_nocase(const std::string& s, const std::string& suffix) {
    if (s.size() < suffix.size()) return false;
    return std::equal(suffix.rbegin(), suffix.rend(), s.rbegin(), [](char a, char b) {
        return std::tolower(static_cast<unsigned char>(a)) ==
               std::tolower(static_cast<unsigned char>(b));
    });
}

} // namespace

} // namespace sss::detail

namespace sss {

using namespace detail;

std::shared_ptr<Texture3dFile> TextureLibrary::Impl::open3d(const std::string& file) {
    std::shared_ptr<Texture3dFile> entry;
    {
        std::lock_guard lock(mutex);
        auto& slot = files3d[file];
        if (!slot) slot = std::make_shared<Texture3dFile>();
        entry = slot;
    }
    std::call_once(entry->once, [&] {
        Texture3dFile& f = *entry;
        try {
            std::error_code ec;
            if (!std::filesystem::is_regular_file(file, ec)) {
                if (std::filesystem::exists(file, ec))
                    throw IoError(file, "not a regular file");
                throw IoError(file, "cannot open: No such file or directory", ENOENT);
            }
            if (ends_with_nocase(file, ".ptc") || ends_with_nocase(file, ".ply")) {
                f.cloud = std::make_unique<CloudTexture3d>(read_point_cloud(file));
                for (const CloudTexture3d::Channel& c : f.cloud->channels())
                    f.channels.push_back({c.name, c.offset, c.floats});
                f.data_size = f.cloud->data_size();
            } else {
                f.map = std::make_unique<BrickMap>(file);
                for (const auto& [name, type] : f.map->info().channels)
                    f.channels.push_back(
                        {name, f.map->channel_offset(name), channel_type_size(type)});
                f.data_size = f.map->info().data_size;
            }
        } catch (const Error& e) {
            const std::string what = e.what();
            // Library messages already start with the file name.
            f.error = what.rfind(file, 0) == 0 ? what : file + ": " + what;
            f.map.reset();
            f.cloud.reset();
        }
    });
    return entry;
}

bool TextureLibrary::texture3d(const std::string& name,
                               std::span<const std::string> channels, std::size_t count,
                               const glm::vec3* P, const glm::vec3* N,
                               const float* radius, const uint8_t* mask,
                               std::vector<int>& channel_floats, float* out,
                               uint8_t* found, std::string* error) {
    bool not_found = false;
    const std::string file = m_impl->resolve(name, &not_found);
    channel_floats.assign(channels.size(), 0);
    if (found) std::fill(found, found + count, uint8_t(0));
    // A file this job writes is never read (docs/cli-conventions.md).
    if (std::string conflict = JobFiles::opened(file, "a texture3d lookup");
        !conflict.empty()) {
        if (error) *error = conflict;
        return false;
    }
    const std::shared_ptr<Texture3dFile> f = m_impl->open3d(file);
    if (!f->error.empty()) {
        if (error) *error = f->error + (not_found ? m_impl->path_note() : std::string());
        return false;
    }

    // Where each requested channel's floats come from.
    std::vector<const Texture3dFile::Channel*> sources(channels.size(), nullptr);
    std::string missing;
    int stride = 0;
    for (std::size_t k = 0; k < channels.size(); ++k) {
        sources[k] = f->find(channels[k]);
        if (sources[k]) {
            channel_floats[k] = sources[k]->floats;
            stride += sources[k]->floats;
        } else {
            missing += (missing.empty() ? "" : ", ") + ("\"" + channels[k] + "\"");
        }
    }
    if (!missing.empty() && error) {
        std::string names;
        for (const Texture3dFile::Channel& c : f->channels)
            names += (names.empty() ? "" : ", ") + c.name;
        *error = file + ": no channel " + missing +
                 " (it has: " + (names.empty() ? "none" : names) + ")";
    }
    if (stride == 0) return false;

    // Point clouds average only the channels asked for, straight into the
    // call's buffer; brick maps fill all their floats, then the channels are
    // copied out. Scratch space per thread: no allocation per call.
    thread_local std::vector<float> t_buf;
    thread_local std::vector<PointCloudLookup::Range> t_ranges;
    t_buf.resize(std::size_t(std::max({f->data_size, stride, 1})));
    float* const buf = t_buf.data();
    t_ranges.clear();
    for (const Texture3dFile::Channel* c : sources)
        if (c) t_ranges.push_back({c->offset, c->floats});
    for (std::size_t i = 0; i < count; ++i) {
        if (mask && !mask[i]) continue;
        const glm::vec3 p = P[i];
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
        glm::vec3 n = N ? N[i] : glm::vec3(0.0f);
        if (!std::isfinite(n.x) || !std::isfinite(n.y) || !std::isfinite(n.z))
            n = glm::vec3(0.0f);
        float r = radius ? radius[i] : 0.0f;
        if (!(r > 0.0f) || !std::isfinite(r)) r = 0.0f;
        float* dst = out + i * std::size_t(stride);
        if (f->map) {
            if (!f->map->lookup(p, n, r, buf)) continue;
            for (const Texture3dFile::Channel* c : sources) {
                if (!c) continue;
                std::copy_n(buf + c->offset, c->floats, dst);
                dst += c->floats;
            }
        } else {
            // Point clouds average only the channels asked for.
            if (!f->cloud->lookup(p, n, r, t_ranges, buf)) continue;
            std::copy_n(buf, stride, dst);
        }
        if (found) found[i] = 1;
    }
    return true;
}

void TextureLibrary::invalidate(const std::string& file) {
    {
        std::lock_guard lock(m_impl->mutex);
        // Calls in flight keep their entries (shared_ptr) until they finish.
        m_impl->files3d.erase(file);
        m_impl->shadow_maps.erase(file);
        m_impl->checked.erase(file);
    }
    // The 2-D side only when the plugin is loaded: nothing else cached it.
    if (Texture2dBackend* b = m_impl->loaded.load(std::memory_order_acquire))
        b->invalidate(file);
}

} // namespace sss
