// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file shadow_library.cpp
/// TextureLibrary's depth maps: zfiles and shadow maps read once through the
/// OpenImageIO plugin (texture2d_backend.h), and RSL's shadow() on them
/// through the light module's percentage-closer filter (shadow_map.h).

#include <glm/gtc/type_ptr.hpp>

#include "sss/binding/texture_library.h"
#include "sss/dice/dice.h"
#include "sss/light/shadow_map.h"
#include "sss/util/job_files.h"
#include "texture2d_backend.h"
#include "texture_library_impl.h"

namespace sss {

namespace {

static_assert(kNoSurfaceDepth == DepthGrid::kNoDepth,
              "the dicer's depth maps mark texels without a surface as shadow maps do");

/// The matrix stored row-vector row by row: glm's column-major order of the
/// column-vector matrix.
Matrix4 stored_matrix(const std::array<float, 16>& m) {
    return Matrix4(glm::make_mat4(m.data()));
}

} // namespace

std::shared_ptr<const ShadowMap> TextureLibrary::shadow_map(const std::string& name,
                                                            std::string* error) {
    bool missing = false;
    const std::string file = m_impl->resolve(name, &missing);
    if (std::string conflict = JobFiles::opened(file, "a shadow lookup");
        !conflict.empty()) {
        if (error) *error = std::move(conflict);
        return nullptr;
    }
    std::shared_ptr<detail::ShadowMapFile> entry;
    {
        std::lock_guard lock(m_impl->mutex);
        auto& slot = m_impl->shadow_maps[file];
        if (!slot) slot = std::make_shared<detail::ShadowMapFile>();
        entry = slot;
    }
    std::call_once(entry->once, [&] {
        if (!m_impl->image_ok(file, &entry->error)) return;
        detail::Texture2dBackend* b = m_impl->textures(&entry->error);
        detail::DepthMapData data;
        if (!b || !b->read_depth_map(file, data, &entry->error)) {
            if (missing) entry->error += m_impl->path_note();
            return;
        }
        auto map = std::make_shared<ShadowMap>();
        map->width = data.width;
        map->height = data.height;
        map->depth = std::move(data.z);
        map->world_to_camera = stored_matrix(data.world_to_camera);
        map->world_to_screen = stored_matrix(data.world_to_screen);
        entry->map = std::move(map);
    });
    if (!entry->map && error) *error = entry->error;
    return entry->map;
}

std::shared_ptr<const DepthGrid> TextureLibrary::depth_grid(const std::string& file) {
    std::string error;
    const std::shared_ptr<const ShadowMap> map = shadow_map(file, &error);
    if (!map) throw IoError(file, "not a depth map the dicer can read (" + error + ")");
    std::lock_guard lock(m_impl->mutex);
    std::shared_ptr<const DepthGrid>& slot = m_impl->depth_grids[map.get()];
    if (!slot) {
        auto grid = std::make_shared<DepthGrid>();
        grid->width = map->width;
        grid->height = map->height;
        grid->depth = map->depth;
        grid->world_to_camera = map->world_to_camera;
        grid->world_to_screen = map->world_to_screen;
        slot = std::move(grid);
    }
    return slot;
}

bool TextureLibrary::shadow(const std::string& file, const TextureOptions& options,
                            std::size_t count, const glm::vec3* P, const glm::vec3* dP_du,
                            const glm::vec3* dP_dv, const uint8_t* mask, float* out,
                            std::string* error) {
    const std::shared_ptr<const ShadowMap> map = shadow_map(file, error);
    if (!map) return false;
    ShadowLookup lookup;
    lookup.bias = options.bias >= 0.0f ? options.bias : kDefaultShadowBias;
    lookup.sblur = options.sblur;
    lookup.tblur = options.tblur;
    lookup.swidth = options.swidth;
    lookup.twidth = options.twidth;
    lookup.samples = options.samples;
    lookup.gaussian = options.filter == "gaussian";
    const glm::dvec3 zero(0.0);
    for (std::size_t i = 0; i < count; ++i) {
        if (mask && !mask[i]) continue;
        out[i] =
            shadow_fraction(*map, glm::dvec3(P[i]), dP_du ? glm::dvec3(dP_du[i]) : zero,
                            dP_dv ? glm::dvec3(dP_dv[i]) : zero, lookup);
    }
    return true;
}

} // namespace sss
