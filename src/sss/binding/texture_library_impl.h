// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
// Internal to binding's texture library (texture_library.cpp,
// texture3d_library.cpp): the files it has opened, each once.

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

#include "sss/binding/texture_library.h"
#include "sss/brick/brickmap.h"
#include "sss/cloud/cloud_texture3d.h"
#include "sss/cloud/point_cloud.h"
#include "sss/cloud/point_cloud_lookup.h"
#include "sss/dice/dice.h"
#include "sss/light/shadow_map.h"

namespace sss {

namespace detail {

/// A 3-D texture: a brick map, or a point cloud (.ptc, .ply) with its lookup.
struct Texture3dFile {
    std::once_flag once;
    std::string error; ///< "file: reason" when it could not be opened
    std::unique_ptr<BrickMap> map;
    std::unique_ptr<CloudTexture3d> cloud;
    struct Channel {
        std::string name;
        int offset = 0; ///< first float in a lookup's result
        int floats = 0;
    };
    std::vector<Channel> channels; ///< every channel of the file
    int data_size = 0;             ///< floats of a lookup's result

    const Channel* find(const std::string& name) const {
        for (const Channel& c : channels)
            if (c.name == name) return &c;
        return nullptr;
    }
};

class Texture2dBackend; // texture2d_backend.h

/// A 2-D image file's check (check_image_file), made once before the plugin
/// opens it.
struct CheckedImage {
    std::once_flag once;
    std::string error; ///< "file: reason" when it is refused
};

/// A depth map (zfile or shadow map), read once.
struct ShadowMapFile {
    std::once_flag once;
    std::string error; ///< "file: reason" when it could not be read
    std::shared_ptr<const ShadowMap> map;
};

} // namespace detail

struct TextureLibrary::Impl {
    Impl();
    ~Impl();
    /// The 2-D texture plugin, loaded on first use; null (with *error set)
    /// when it cannot be loaded.
    detail::Texture2dBackend* textures(std::string* error);
    std::once_flag plugin_once;
    std::unique_ptr<detail::Texture2dBackend> backend;
    /// The backend once loaded (for invalidate(), which must not load it).
    std::atomic<detail::Texture2dBackend*> loaded{nullptr};
    std::string plugin_error;
    std::mutex mutex; ///< guards files3d (not the files' contents)
    std::unordered_map<std::string, std::shared_ptr<detail::Texture3dFile>> files3d;
    /// Depth maps by resolved name; guarded by mutex.
    std::unordered_map<std::string, std::shared_ptr<detail::ShadowMapFile>> shadow_maps;
    /// The dicer's copies of depth maps, by map; guarded by mutex.
    std::unordered_map<const ShadowMap*, std::shared_ptr<const DepthGrid>> depth_grids;

    std::shared_ptr<detail::Texture3dFile> open3d(const std::string& file);
    /// 2-D image files by resolved name, checked once; guarded by mutex.
    std::unordered_map<std::string, std::shared_ptr<detail::CheckedImage>> checked;
    /// Whether `file` passed check_image_file() (false with *error: the
    /// reason, the file named): a texture, environment or depth map is
    /// checked before OpenImageIO reads it. A missing file passes (the
    /// plugin names it).
    bool image_ok(const std::string& file, std::string* error);

    std::vector<std::string> search_path;
    std::unordered_map<std::string, std::string> found; ///< by name; guarded by mutex
    /// `file` along search_path (the name itself when the path is empty, the
    /// name is absolute or found nowhere: *missing then tells the caller to
    /// name the path in its error).
    std::string resolve(const std::string& file, bool* missing);
    /// " (not found along the texture search path \"a:b\")".
    std::string path_note() const;
};

} // namespace sss
