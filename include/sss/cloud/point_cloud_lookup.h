// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file point_cloud_lookup.h
/// texture3d-style lookups directly in a point cloud (the renderer's fallback
/// when a shader names a cloud instead of a brick map, and the reference the
/// brick-map tests compare against).

#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>

#include "sss/cloud/point_cloud.h"

namespace sss {

/// The same lookup directly on a point cloud: a normal-aware average of the
/// nearest points (those whose normal agrees with n, within about 60 degrees;
/// all of them when n is zero), weighted by distance within the filter
/// radius or, when 0, over the k = 8 nearest (a tent reaching zero at the
/// 9th). The neighbours are exact (ties broken by point order), so results
/// do not depend on the order of lookups, the thread or the thread count;
/// consecutive lookups near each other on one thread are faster.
class PointCloudLookup {
public:
    /// Some of a lookup's floats: `floats` of them from `offset` on.
    struct Range {
        int offset = 0;
        int floats = 0;
    };

    /// Indexes the cloud's positions (the cloud must outlive this object).
    /// channels: the channels to return, in order (empty: every float and
    /// color channel).
    PointCloudLookup(const PointCloud& cloud, std::vector<std::string> channels = {});
    ~PointCloudLookup();
    PointCloudLookup(const PointCloudLookup&) = delete;
    PointCloudLookup& operator=(const PointCloudLookup&) = delete;

    /// Floats per lookup (sum of the channels' components).
    int data_size() const;
    const std::vector<std::pair<std::string, ChannelType>>& channels() const;
    /// Fills out; false when no point qualifies. Thread-safe.
    bool lookup(const glm::vec3& p, const glm::vec3& n, float filter_radius,
                float* out) const;
    /// The same with only the ranges' floats, one range after another in out
    /// (each value identical to lookup's). *nearest, when given, gets the
    /// distance from p to the nearest point averaged (infinity on a miss).
    bool lookup(const glm::vec3& p, const glm::vec3& n, float filter_radius,
                std::span<const Range> ranges, float* out,
                float* nearest = nullptr) const;

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

} // namespace sss
