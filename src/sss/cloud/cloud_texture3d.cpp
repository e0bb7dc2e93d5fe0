// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file cloud_texture3d.cpp
/// CloudTexture3d: texture3d on a point cloud as the renderer reads it. The
/// nearest-point average always finds something, so whether a query is near
/// the data is decided apart: a hash of the occupied cells of a grid whose
/// cell is the reach.

#include "sss/cloud/cloud_texture3d.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_set>

#include <glm/common.hpp>

namespace sss {

namespace {

/// Cells per axis are kept below 2^20 so that a cell's three coordinates
/// pack into one 64-bit key.
constexpr int kCellBits = 21;
constexpr float kMaxCells = float(1 << (kCellBits - 1));
/// A query is near the data within this many median point radii (about two
/// point spacings of a bake: points are as far apart as their diameter).
constexpr float kReachInRadii = 4.0f;
/// Neighbour cells searched each way; farther reaches use the bounding box.
constexpr int kMaxCellRange = 2;

uint64_t cell_key(int64_t x, int64_t y, int64_t z) {
    const uint64_t mask = (uint64_t(1) << kCellBits) - 1;
    return (uint64_t(x) & mask) | ((uint64_t(y) & mask) << kCellBits) |
           ((uint64_t(z) & mask) << (2 * kCellBits));
}

bool finite(const glm::vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

std::vector<std::string> channel_names(const PointCloud& cloud) {
    std::vector<std::string> names;
    for (const sss::Channel& c : cloud.channels) names.push_back(c.name);
    return names;
}

} // namespace

struct CloudTexture3d::Impl {
    PointCloud cloud;
    std::vector<Channel> channels;
    int data_size = 0;
    std::unique_ptr<PointCloudLookup> lookup; ///< over `cloud`, every channel
    float cell = 0.0f;
    glm::vec3 origin{0.0f};
    glm::vec3 lo{0.0f}, hi{0.0f}; ///< bounding box of the points
    std::unordered_set<uint64_t> occupied;

    void index();
    /// Whether p is farther than max(cell, radius) outside the points' box
    /// (then no point is near it).
    bool outside_box(const glm::vec3& p, float radius) const;
    /// Whether some point may lie within max(cell, radius) of p.
    bool near_data(const glm::vec3& p, float radius) const;
};

void CloudTexture3d::Impl::index() {
    if (cloud.size() == 0) return;
    const Bounds3 b = cloud.bounds();
    lo = b.lo;
    hi = b.hi;
    const float extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
    std::vector<float> radii;
    radii.reserve(cloud.radii.size());
    for (float r : cloud.radii)
        if (r > 0.0f && std::isfinite(r)) radii.push_back(r);
    float reach = 0.0f;
    if (!radii.empty()) {
        auto mid = radii.begin() + radii.size() / 2;
        std::nth_element(radii.begin(), mid, radii.end());
        reach = kReachInRadii * *mid;
    } else {
        // No radii: about two mean spacings of points spread over the box.
        reach = 2.0f * extent / std::cbrt(float(cloud.size()));
    }
    cell = std::max({reach, extent / kMaxCells, 1e-6f});
    origin = lo;
    for (const glm::vec3& p : cloud.positions) {
        const glm::vec3 g = (p - origin) / cell;
        occupied.insert(cell_key(int64_t(g.x), int64_t(g.y), int64_t(g.z)));
    }
}

bool CloudTexture3d::Impl::outside_box(const glm::vec3& p, float radius) const {
    const float reach = std::max(cell, std::isfinite(radius) ? radius : 0.0f);
    for (int a = 0; a < 3; ++a)
        if (p[a] < lo[a] - reach || p[a] > hi[a] + reach) return true;
    return false;
}

bool CloudTexture3d::Impl::near_data(const glm::vec3& p, float radius) const {
    if (occupied.empty() || outside_box(p, radius)) return false;
    const float reach = std::max(cell, std::isfinite(radius) ? radius : 0.0f);
    const int range = static_cast<int>(std::ceil(reach / cell));
    if (range > kMaxCellRange) return true; // a large filter: the box suffices
    const glm::vec3 g = glm::floor((p - origin) / cell);
    const int64_t cx = int64_t(g.x), cy = int64_t(g.y), cz = int64_t(g.z);
    for (int64_t z = cz - range; z <= cz + range; ++z)
        for (int64_t y = cy - range; y <= cy + range; ++y)
            for (int64_t x = cx - range; x <= cx + range; ++x) {
                if (x < 0 || y < 0 || z < 0) continue;
                if (occupied.count(cell_key(x, y, z))) return true;
            }
    return false;
}

CloudTexture3d::CloudTexture3d(PointCloud cloud) : m_impl(std::make_unique<Impl>()) {
    Impl& d = *m_impl;
    d.cloud = std::move(cloud);
    for (const sss::Channel& c : d.cloud.channels) {
        d.channels.push_back({c.name, c.type, d.data_size, c.components()});
        d.data_size += c.components();
    }
    d.lookup = std::make_unique<PointCloudLookup>(d.cloud, channel_names(d.cloud));
    d.index();
}

CloudTexture3d::~CloudTexture3d() = default;

const PointCloud& CloudTexture3d::cloud() const {
    return m_impl->cloud;
}

const std::vector<CloudTexture3d::Channel>& CloudTexture3d::channels() const {
    return m_impl->channels;
}

const CloudTexture3d::Channel* CloudTexture3d::find(const std::string& name) const {
    for (const Channel& c : m_impl->channels)
        if (c.name == name) return &c;
    return nullptr;
}

int CloudTexture3d::data_size() const {
    return m_impl->data_size;
}

bool CloudTexture3d::lookup(const glm::vec3& p, const glm::vec3& n, float radius,
                            std::span<const PointCloudLookup::Range> ranges,
                            float* out) const {
    const Impl& d = *m_impl;
    if (!finite(p)) return false;
    const glm::vec3 normal = finite(n) ? n : glm::vec3(0.0f);
    const float r = radius > 0.0f && std::isfinite(radius) ? radius : 0.0f;
    // Always the nearest points (a fixed radius may hold none); found only
    // near the data. A point within half a cell is near (its cell is a
    // neighbour of p's), which spares the cell test almost always.
    if (d.outside_box(p, r)) return false;
    float nearest = 0.0f;
    if (!d.lookup->lookup(p, normal, 0.0f, ranges, out, &nearest)) return false;
    return nearest <= 0.5f * d.cell || d.near_data(p, r);
}

} // namespace sss
