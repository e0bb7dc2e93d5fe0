// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file brickmap_voxels.h
/// A brick map's samples as voxels on the lattice of one depth, for volume
/// formats (OpenVDB, docs/brickmake.md "OpenVDB output"). A brick of depth d
/// holds 8 x 8 x 8 samples whose spacing is cube_side / (7 * 2^d); bricks
/// share their faces, so the samples of one depth lie on one lattice:
/// lattice point (i, j, k) is the world point cube_min + spacing * (i, j, k).
/// Volumes know nothing of normals, so the seven octrees are merged: a
/// lattice point that several trees have gets the mean of their values.

#include <array>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

namespace sss {

class BrickMap;

/// Voxels of one depth: lattice coordinates and the map's channels there.
struct BrickMapVoxels {
    int depth = 0;
    double spacing = 0.0;   ///< world distance between lattice points
    glm::dvec3 origin{0.0}; ///< the world point of lattice point (0, 0, 0)
    /// Lattice coordinates, sorted (x, then y, then z), each once.
    std::vector<std::array<int32_t, 3>> coords;
    /// data_size floats per voxel (the map's channels in order).
    std::vector<float> values;
};

/// The depth whose lattice the main grid of a map uses: the deepest depth at
/// which at least 90 % of the map's geometry is still present (from depth to
/// depth, the share of the coarser depth's nodes that have a node below
/// them, multiplied down from the root). Deeper than that, only the parts
/// made of smaller points go on, and a grid there would be mostly holes.
int brick_map_surface_depth(const BrickMap& map);

/// The map's data of one depth at every lattice point of that depth where it
/// has geometry (a data brick's sample or an occupancy-only node's, in any
/// tree): BrickMap::lookup_depth there with the normal of each tree that has
/// the point (no normal for tree 0), averaged over those trees. At a sample
/// of a data brick that is the sample itself; where bricks were pruned, the
/// coarser data that lookups fall back to. Points where no lookup finds data
/// are left out. Parallel; the result does not depend on the thread count.
BrickMapVoxels brick_map_voxels(const BrickMap& map, int depth);

} // namespace sss
