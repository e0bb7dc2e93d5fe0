// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
// Voxel grids of the volume a cloud of oriented surface points encloses, for
// the volume diffusion (volume.cpp): classification of voxels as medium,
// outside or blocker, and trilinear reads of a field stored on the medium
// voxels.

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "sss/diffusion/volume.h"

namespace sss::volume_detail {

enum Label : int8_t { kOutside = 0, kMedium = 1, kBlocker = 2 };

/// A regular grid of cubic voxels; voxel (x, y, z) is centred at
/// origin + h (x, y, z).
struct VoxelGrid {
    glm::dvec3 origin{0.0};
    double h = 1.0;
    glm::ivec3 dim{0};
    std::vector<int8_t> label; ///< Label per voxel

    std::size_t count() const { return std::size_t(dim.x) * dim.y * dim.z; }
    std::size_t voxel(int x, int y, int z) const {
        return (std::size_t(z) * std::size_t(dim.y) + std::size_t(y)) *
                   std::size_t(dim.x) +
               std::size_t(x);
    }
    glm::dvec3 centre(int x, int y, int z) const {
        return origin + h * glm::dvec3(x, y, z);
    }
    /// The voxel containing p, clamped to the grid.
    glm::ivec3 cell_of(const glm::dvec3& p) const;
    int8_t label_at(const glm::dvec3& p) const;
};

/// A grid of edge h over [lo, hi] with `pad` voxels around.
VoxelGrid make_grid(const glm::dvec3& lo, const glm::dvec3& hi, double h, int pad);

/// Per voxel, 1 where it lies inside the closed surface the samples stand
/// for: the side of the nearest sample's tangent plane near the surface
/// (Hoppe et al. 1992), flood-filled from there into the rest of the grid;
/// the grid's border counts as outside.
std::vector<int8_t> inside_voxels(const VoxelGrid& grid, const SurfaceSamples& samples);

/// The depth of the medium below each sample of `surface`: the distance
/// along its inward normal to the first sample disk the ray leaves the
/// medium through (a surface sample facing along the ray) or enters a
/// blocker through, at most `limit`. Disks are taken a little wider than
/// their area, so that rays do not slip between samples; the grid indexes
/// them.
std::vector<double> ray_thickness(const VoxelGrid& grid, const SurfaceSamples& surface,
                                  const std::vector<SurfaceSamples>& blockers,
                                  double limit);

/// Per query point, the straight distance to the nearest of `sources`, to
/// about the grid's resolution (a brushfire from the sources' voxels: each
/// voxel takes the nearest source of its neighbours'); infinity without
/// sources.
std::vector<double> nearest_source_distance(const VoxelGrid& grid,
                                            const std::vector<glm::dvec3>& sources,
                                            const std::vector<glm::vec3>& queries);

/// The grid's medium voxels as unknowns of the diffusion system.
struct Unknowns {
    std::vector<int32_t> index;   ///< per voxel: its unknown, or -1
    std::vector<uint32_t> voxels; ///< per unknown: its voxel
    /// Per unknown, its six neighbours: an unknown (>= 0), kNone (outside:
    /// no flux crosses) or kBlack (a blocker voxel).
    std::vector<std::array<int32_t, 6>> neighbours;
    static constexpr int32_t kNone = -1, kBlack = -2;
};
Unknowns number_unknowns(const VoxelGrid& grid);

/// Trilinear weights of the medium voxels around p, renormalised over those
/// that are unknowns; false when none is.
struct Stencil {
    int32_t unknown[8];
    double weight[8];
    int n = 0;
};
bool medium_stencil(const VoxelGrid& grid, const Unknowns& u, const glm::dvec3& p,
                    Stencil& out);

} // namespace sss::volume_detail
