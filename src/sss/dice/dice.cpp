/// \file dice.cpp
/// The dispatcher: dice_primitive hands each primitive to the dicer of its
/// family (dice_quadric.cpp, dice_patch.cpp, dice_polygon.cpp,
/// dice_subdiv.cpp), and dice_all dices many of them in parallel for the
/// baker and the renderer.

#include "sss/dice/dice.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <tbb/parallel_for.h>

#include "dice_common.h"
#include "sss/util/error.h"
#include "sss/util/hash.h"

namespace sss {

DicedSurface dice_primitive(const Primitive& prim, const DiceControl& control) {
    switch (prim.kind) {
    case PrimitiveKind::Polygon:
    case PrimitiveKind::GeneralPolygon:
    case PrimitiveKind::PointsPolygons:
    case PrimitiveKind::PointsGeneralPolygons:
        return detail::dice_polygons(prim, control);
    case PrimitiveKind::SubdivisionMesh:
        return detail::dice_subdivision(prim, control);
    case PrimitiveKind::Sphere:
    case PrimitiveKind::Cylinder:
    case PrimitiveKind::Cone:
    case PrimitiveKind::Disk:
    case PrimitiveKind::Torus:
    case PrimitiveKind::Hyperboloid:
    case PrimitiveKind::Paraboloid:
        return detail::dice_quadric(prim, control);
    case PrimitiveKind::Patch:
        return detail::dice_patch(prim, control);
    case PrimitiveKind::PatchMesh:
        return detail::dice_patch_mesh(prim, control);
    case PrimitiveKind::Teapot:
        return detail::dice_teapot(prim, control);
    }
    throw ValueError(prim.source + ": unknown primitive kind");
}

std::vector<DicedSurface> dice_all(const Scene& scene,
                                   std::span<const DiceRequest> requests,
                                   const DiceFinish& finish) {
    std::vector<DicedSurface> diced(scene.primitives.size());
    // One message per request, so that the first failure in request order is
    // reported whichever thread met it first.
    std::vector<std::string> errors(requests.size());
    tbb::parallel_for(std::size_t(0), requests.size(), [&](std::size_t k) {
        try {
            const DiceRequest& request = requests[k];
            DicedSurface& surface = diced[request.primitive];
            surface =
                dice_primitive(scene.primitives[request.primitive], request.control);
            if (finish) finish(request.primitive, surface);
        } catch (const std::exception& e) {
            errors[k] = e.what();
        }
    });
    for (const std::string& e : errors)
        if (!e.empty()) throw ValueError(e);
    return diced;
}

std::vector<glm::vec3> triangle_colors(const DicedSurface& d) {
    std::vector<glm::vec3> colors;
    if (d.colors.empty() || d.triangles.empty()) return colors;
    float cell = 0.0f;
    for (float r : d.radii) cell = std::max(cell, r);
    if (!(cell > 0.0f)) cell = 1.0f;
    const auto key = [&](const glm::vec3& p, int dx, int dy, int dz) {
        const int64_t x = static_cast<int64_t>(std::floor(p.x / cell)) + dx;
        const int64_t y = static_cast<int64_t>(std::floor(p.y / cell)) + dy;
        const int64_t z = static_cast<int64_t>(std::floor(p.z / cell)) + dz;
        return detail::splitmix64(static_cast<uint64_t>(x) * 0x9E3779B1u ^
                                  static_cast<uint64_t>(y) * 0x85EBCA77u ^
                                  static_cast<uint64_t>(z) * 0xC2B2AE3Du);
    };
    // Open hashing into sorted (key, index) pairs.
    std::vector<std::pair<uint64_t, uint32_t>> grid(d.size());
    for (std::size_t i = 0; i < d.size(); ++i)
        grid[i] = {key(d.centers[i], 0, 0, 0), static_cast<uint32_t>(i)};
    std::sort(grid.begin(), grid.end());
    const std::size_t triangles = d.triangles.size() / 3;
    colors.resize(triangles);
    for (std::size_t t = 0; t < triangles; ++t) {
        const glm::vec3 c =
            (d.vertices[d.triangles[3 * t]] + d.vertices[d.triangles[3 * t + 1]] +
             d.vertices[d.triangles[3 * t + 2]]) /
            3.0f;
        float best = std::numeric_limits<float>::infinity();
        uint32_t best_i = 0;
        for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const uint64_t k = key(c, dx, dy, dz);
                    auto it = std::lower_bound(grid.begin(), grid.end(),
                                               std::make_pair(k, uint32_t{0}));
                    for (; it != grid.end() && it->first == k; ++it) {
                        const glm::vec3 e = d.centers[it->second] - c;
                        const float dist = glm::dot(e, e);
                        if (dist < best || (dist == best && it->second < best_i)) {
                            best = dist;
                            best_i = it->second;
                        }
                    }
                }
        if (!std::isfinite(best)) {
            // Nothing in the neighbouring cells (a sliver far from any centre).
            for (std::size_t i = 0; i < d.size(); ++i) {
                const glm::vec3 e = d.centers[i] - c;
                const float dist = glm::dot(e, e);
                if (dist < best) {
                    best = dist;
                    best_i = static_cast<uint32_t>(i);
                }
            }
        }
        colors[t] = d.colors[best_i];
    }
    return colors;
}

} // namespace sss
