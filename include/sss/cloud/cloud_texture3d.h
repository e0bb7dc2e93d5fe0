// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file cloud_texture3d.h
/// texture3d on a point cloud, as the renderer looks a .ptc or .ply file up
/// when a shader names a cloud instead of a brick map (render's texture3d,
/// and the Python module's PointCloudLookup).

#include <memory>
#include <span>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "sss/cloud/point_cloud.h"
#include "sss/cloud/point_cloud_lookup.h"

namespace sss {

/// A cloud's texture3d lookups: PointCloudLookup's average of the nearest
/// points (always the k nearest: a fixed radius may hold none), reported as
/// found only near the data, within max(reach, filter radius) of a point,
/// where the reach is four median point radii (about two point spacings of a
/// bake; without radii, two mean spacings over the bounding box). Far from
/// the points a lookup is a miss, as in a brick map. Thread-safe.
class CloudTexture3d {
public:
    /// A channel's place in a lookup of every channel (lookup_all()).
    struct Channel {
        std::string name;
        ChannelType type = ChannelType::Float;
        int offset = 0; ///< its first float
        int floats = 0; ///< its components
    };

    /// Indexes every channel of the cloud (which it keeps).
    explicit CloudTexture3d(PointCloud cloud);
    ~CloudTexture3d();
    CloudTexture3d(const CloudTexture3d&) = delete;
    CloudTexture3d& operator=(const CloudTexture3d&) = delete;

    const PointCloud& cloud() const;
    /// Every channel, in the cloud's order.
    const std::vector<Channel>& channels() const;
    /// The channel called name, or null.
    const Channel* find(const std::string& name) const;
    /// Floats of a lookup of every channel.
    int data_size() const;

    /// texture3d at p with surface normal n: the ranges' floats of the
    /// average, one range after another in out. False (out untouched or
    /// partly written) when p is not near the data. A non-finite p is a miss,
    /// a non-finite n no normal (every side), a radius that is not a
    /// positive finite number 0.
    bool lookup(const glm::vec3& p, const glm::vec3& n, float radius,
                std::span<const PointCloudLookup::Range> ranges, float* out) const;

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

} // namespace sss
