#pragma once
// Internal to the texture library (texture_library.cpp,
// texture3d_library.cpp): the files it has opened, each once.

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include <OpenImageIO/texture.h>

#include "sss/brick/brickmap.h"
#include "sss/cloud/point_cloud.h"
#include "sss/cloud/point_cloud_lookup.h"
#include "texture_library.h"

namespace sss::detail {

/// A 2-D texture or environment map as opened by the texture system.
struct TextureFile {
    std::once_flag once;
    OIIO::TextureSystem::TextureHandle* handle = nullptr; ///< null: unreadable
    std::string error;                                    ///< "file: reason"
    int nchannels = 0;
    int width = 0, height = 0;
    std::string format; ///< OIIO "textureformat" ("" for plain images)
};

/// A 3-D texture: a brick map, or a point cloud (.ptc, .ply) with its lookup.
struct Texture3dFile {
    std::once_flag once;
    std::string error; ///< "file: reason" when it could not be opened
    std::unique_ptr<BrickMap> map;
    std::unique_ptr<PointCloud> cloud; ///< outlives `lookup` (its contract)
    std::unique_ptr<PointCloudLookup> lookup;
    struct Channel {
        std::string name;
        int offset = 0; ///< first float in a lookup's result
        int floats = 0;
    };
    std::vector<Channel> channels; ///< every channel of the file
    int data_size = 0;             ///< floats of a lookup's result

    // Point clouds: where there is data. The nearest-point lookup always
    // finds something, so "found" also needs a point within `reach` of the
    // query: occupied cells of edge `cell` (hash of the cell coordinates).
    float cell = 0.0f;
    glm::vec3 origin{0.0f};
    glm::vec3 lo{0.0f}, hi{0.0f}; ///< bounding box of the points
    std::unordered_set<uint64_t> occupied;

    const Channel* find(const std::string& name) const {
        for (const Channel& c : channels)
            if (c.name == name) return &c;
        return nullptr;
    }
    /// Whether some point may lie within max(cell, radius) of p (clouds).
    bool near_data(const glm::vec3& p, float radius) const;
    void index_cloud();
};

struct TextureLibrary::Impl {
    Impl();
    ~Impl();
    /// The texture system, created on first use (jobs without 2-D textures
    /// never load OpenImageIO's texture machinery).
    OIIO::TextureSystem* system();
    static OIIO::TextureSystem* make_texture_system();
    OIIO::TextureSystem* ts = nullptr;
    std::once_flag ts_once;
    std::mutex mutex; ///< guards the two maps (not the files' contents)
    std::unordered_map<std::string, std::shared_ptr<TextureFile>> files;
    std::unordered_map<std::string, std::shared_ptr<Texture3dFile>> files3d;

    /// The entry of a file, opened on first use by whichever thread asks first.
    std::shared_ptr<TextureFile> open(const std::string& file);
    std::shared_ptr<Texture3dFile> open3d(const std::string& file);
};

} // namespace sss::detail
