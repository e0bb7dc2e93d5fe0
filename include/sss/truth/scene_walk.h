// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file scene_walk.h
/// The random walk in a scene's own geometry (mesh_walk.h), lit by a baked
/// point cloud: what `ssprofile -scene` runs, so that ptfilter's result on a
/// real shape (thin parts, small objects, absorbing bones) can be held
/// against the light on that shape.

#include <cstdint>
#include <string>
#include <vector>

#include "sss/cloud/point_cloud.h"
#include "sss/diffusion/material.h"
#include "sss/truth/mesh_walk.h"

namespace sss {

struct SceneWalkOptions {
    /// The RIB whose objects bound the medium (a ReadArchive of an .obj
    /// file brings in a mesh). Every object is part of the medium except
    /// the blockers.
    std::string scene;
    /// Names (`Attribute "identifier" "name"`) of the objects that absorb
    /// whatever reaches them (bones). A name no object has is an error.
    std::vector<std::string> blockers;
    /// The medium, with ptfilter's units: coefficients in 1/mm, scene
    /// length = mm x unitlength. Albedo and dmfp mean the medium the classic
    /// dipole infers from them; `fromfile` is refused.
    MaterialSpec material;
    /// Edge length of the triangles the objects are diced into (scene
    /// units); 0: 1/500 of the scene's bounding-box diagonal.
    double spacing = 0.0;
    uint64_t photons = 1'000'000; ///< per channel
    uint64_t seed = 1;
    int batches = 64;
    std::string area_channel = "_area";           ///< else pi radius^2
    std::string radiance_channel = "_radiance_t"; ///< transmitted irradiance
    bool normal_incidence = false;                ///< as MeshWalkOptions
    bool scattered_only = false;                  ///< as MeshWalkOptions
};

struct SceneWalkReport {
    MeshWalkResult walk; ///< totals and per-point exitance
    std::size_t medium_triangles = 0, blocker_triangles = 0;
    double spacing = 0.0; ///< the dicing edge length used
    std::vector<std::string> warnings;
};

/// Walks the light of `baked` (positions, normals, areas and the radiance
/// channel) through the scene's objects. Returns the cloud's points with
/// `color _ssdiffusion` (the walk's exitance, ptfilter's channel and scale)
/// and `color _ssdiffusion_error` (its standard error). Throws IoError,
/// RibError, ValueError (a missing channel, an unknown blocker, a negative
/// irradiance: blockers baked with negative light are ptfilter's fake, here
/// bones are geometry).
PointCloud walk_scene(const SceneWalkOptions& options, const PointCloud& baked,
                      SceneWalkReport* report = nullptr);

/// A result against the walk's, per channel: the flux-weighted L1 error
/// sum |a_i - t_i| A_i / sum t_i A_i and the ratio of the totals
/// sum a_i A_i / sum t_i A_i, over the points with area. `noise` is the L1
/// error a perfect result would score against the walk's noise,
/// sqrt(2 / pi) sum s_i A_i / sum t_i A_i from the walk's standard errors s_i
/// (`_ssdiffusion_error`; 0 when the truth has none).
struct CloudComparison {
    glm::dvec3 l1{0.0}, total_ratio{0.0}, noise{0.0};
};
CloudComparison compare_with_truth(const PointCloud& result, const PointCloud& truth,
                                   const std::vector<float>& areas);

/// The areas of a cloud's points: `area_channel` if it has one, else pi r^2.
std::vector<float> cloud_areas(const PointCloud& cloud, const std::string& area_channel);

/// The area-weighted mean `_ssdiffusion` of the points with area inside the
/// box [lo, hi] (e.g. the middle of a slab's lit face).
struct RegionMean {
    std::size_t points = 0;
    glm::dvec3 mean{0.0};
};
RegionMean region_mean(const PointCloud& cloud, const std::vector<float>& areas,
                       const glm::dvec3& lo, const glm::dvec3& hi);

} // namespace sss
