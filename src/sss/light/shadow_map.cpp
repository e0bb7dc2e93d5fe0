// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file shadow_map.cpp
/// Depth-map shadow lookups (shadow_map.h): the point projected with the
/// map's matrices, then percentage-closer filtering (Reeves, Salesin and
/// Cook 1987): the fraction of depth comparisons over the filter region
/// that find a nearer surface.

#include "sss/light/shadow_map.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include <glm/vec4.hpp>

#include "sss/util/hash.h"

namespace sss {

namespace {

bool finite3(const glm::dvec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

/// A point's place on the map: texture coordinates (s right, t down, both
/// in [0, 1] over the map); false behind the map's camera.
bool map_coordinates(const ShadowMap& map, const glm::dvec3& p, double& s, double& t) {
    const glm::dvec4 h = map.world_to_screen * glm::dvec4(p, 1.0);
    if (!(h.w > 0.0)) return false;
    s = 0.5 * (h.x / h.w + 1.0);
    t = 0.5 * (1.0 - h.y / h.w);
    return std::isfinite(s) && std::isfinite(t);
}

/// Whether the texel under (s, t) holds a surface nearer than `depth`.
bool occluded(const ShadowMap& map, double s, double t, double depth) {
    const double x = std::floor(s * map.width), y = std::floor(t * map.height);
    if (!(x >= 0.0 && y >= 0.0 && x < map.width && y < map.height)) return false;
    return depth > map.at(static_cast<int>(x), static_cast<int>(y));
}

/// A hash of a point's coordinates (the jitter's seed).
uint64_t point_hash(const glm::dvec3& p, uint64_t seed) {
    const double xyz[3] = {p.x, p.y, p.z};
    return detail::hash_bytes(xyz, sizeof xyz, seed ^ 0x736861646f77ull);
}

} // namespace

float shadow_fraction(const ShadowMap& map, const glm::dvec3& p, const glm::dvec3& dp_du,
                      const glm::dvec3& dp_dv, const ShadowLookup& lookup,
                      uint64_t seed) {
    if (map.width <= 0 || map.height <= 0 || !finite3(p)) return 0.0f;
    const glm::dvec4 pc = map.world_to_camera * glm::dvec4(p, 1.0);
    const double z = pc.z / pc.w;
    if (!(z > 0.0) || !std::isfinite(z)) return 0.0f; // behind the map's camera
    double s, t;
    if (!map_coordinates(map, p, s, t)) return 0.0f;
    const double depth =
        z - std::max(0.0f, std::isfinite(lookup.bias) ? lookup.bias : 0.0f);

    // The footprint: how far the neighbour points land on the map.
    double ext_s = 0.0, ext_t = 0.0;
    for (const glm::dvec3& d : {dp_du, dp_dv}) {
        double sd, td;
        if (finite3(d) && map_coordinates(map, p + d, sd, td)) {
            ext_s = std::max(ext_s, std::abs(sd - s));
            ext_t = std::max(ext_t, std::abs(td - t));
        }
    }
    const auto clean = [](float x) {
        return std::isfinite(x) ? std::max(x, 0.0f) : 0.0f;
    };
    const double texel_s = 1.0 / map.width, texel_t = 1.0 / map.height;
    // Full widths of the region: footprint times width, plus blur, at least a texel.
    const double ws = std::min(
        std::max(ext_s * clean(lookup.swidth) + clean(lookup.sblur), texel_s), 2.0);
    const double wt = std::min(
        std::max(ext_t * clean(lookup.twidth) + clean(lookup.tblur), texel_t), 2.0);
    // Wholly outside the map: lit.
    if (s + 0.5 * ws < 0.0 || s - 0.5 * ws > 1.0 || t + 0.5 * wt < 0.0 ||
        t - 0.5 * wt > 1.0)
        return 0.0f;

    const int n = std::clamp(lookup.samples, 1, 4096);
    if (n == 1) return occluded(map, s, t, depth) ? 1.0f : 0.0f;
    // Stratified: a gx x gy grid of cells, one jittered sample per cell.
    const int gx = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(n))));
    const int gy = (n + gx - 1) / gx;
    const uint64_t h = point_hash(p, seed);
    double sum = 0.0, weights = 0.0;
    for (int k = 0; k < n; ++k) {
        const uint64_t r =
            detail::splitmix64(h + uint64_t(k) * detail::kSplitMixIncrement);
        const double u = ((k % gx) + detail::unit_double(r)) / gx - 0.5;
        const double v =
            ((k / gx) + detail::unit_double(detail::splitmix64(r))) / gy - 0.5;
        const double w = lookup.gaussian ? std::exp(-8.0 * (u * u + v * v)) : 1.0;
        weights += w;
        if (occluded(map, s + u * ws, t + v * wt, depth)) sum += w;
    }
    const double f = weights > 0.0 ? sum / weights : 0.0;
    return static_cast<float>(std::clamp(f, 0.0, 1.0));
}

float scene_shadow_bias(const Scene& scene) {
    const auto it = scene.options.groups.find("shadow");
    if (it == scene.options.groups.end()) return kDefaultShadowBias;
    const ParamList& p = it->second;
    const auto number = [&](const char* name) -> std::optional<double> {
        const Param* q = p.find(name);
        if (!q || q->numbers.empty() || !std::isfinite(q->numbers[0]))
            return std::nullopt;
        return q->numbers[0];
    };
    if (auto b = number("bias")) return static_cast<float>(*b);
    const auto b0 = number("bias0"), b1 = number("bias1");
    if (b0 && b1) return static_cast<float>(0.5 * (*b0 + *b1));
    if (b0) return static_cast<float>(*b0);
    if (b1) return static_cast<float>(*b1);
    return kDefaultShadowBias;
}

} // namespace sss
