#pragma once
/// \file point_cloud_lookup.h
/// texture3d-style lookups directly in a point cloud (the renderer's fallback
/// when a shader names a cloud instead of a brick map, and the reference the
/// brick-map tests compare against).

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>

#include "sss/cloud/point_cloud.h"

namespace sss {

/// The same lookup directly on a point cloud, for checks: a normal-aware
/// average of the nearest points (those whose normal agrees with n, within
/// about 60 degrees; all of them when n is zero), weighted by distance within
/// the filter radius or, when 0, over the k nearest.
class PointCloudLookup {
public:
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

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

} // namespace sss
