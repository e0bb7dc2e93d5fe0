// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file vdb.h
/// Module vdb: OpenVDB files (.vdb): a brick map's channels written as grids
/// that Houdini, Blender and other volume tools read (brickmake out.vdb), and
/// .vdb files described (brickinfo) and read back.
/// May use: brick, image, cloud, util (and OpenVDB, privately).
///
/// The grids of a written file (docs/brickmake.md, "OpenVDB output"): per
/// channel of the map, a `float` grid (float channels) or a `vec3s` grid
/// (color channels) named after the channel, on the lattice of the map's
/// surface depth (brick_map_surface_depth), then one grid per coarser depth,
/// `<channel>_level1` (one depth coarser) ... `<channel>_level<D>` (the
/// root); each holds the map's data of its depth (brick_map_voxels). Each
/// grid's transform puts voxel (i, j, k) at the world point of that lattice
/// point (voxel centres on the brick samples; voxel size = sample spacing).

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>

#include "sss/brick/brickmap.h"

namespace sss {

/// One grid of a .vdb file, as written or read.
struct VdbGridInfo {
    std::string name;
    std::string value_type;   ///< OpenVDB's name: "float", "vec3s", ...
    std::string grid_class;   ///< "unknown", "level set", "fog volume", "staggered"
    std::size_t voxels = 0;   ///< active voxels
    bool linear = true;       ///< a linear transform without shear or rotation
    glm::dvec3 voxel_size{0}; ///< world size of a voxel along x, y, z
    glm::dvec3 origin{0};     ///< world point of voxel (0, 0, 0)'s centre
    std::array<int32_t, 3> index_min{}; ///< bounding box of the active voxels
    std::array<int32_t, 3> index_max{}; ///< (both 0 when there are none)
    /// The grid's metadata as text, by name (OpenVDB's statistics left out).
    std::vector<std::pair<std::string, std::string>> metadata;
};

/// What write_brick_map_vdb wrote.
struct VdbWriteReport {
    int surface_depth = 0; ///< the depth of the main grids
    std::vector<VdbGridInfo> grids;
    uint64_t file_size = 0;
};

/// Writes every channel of the map as OpenVDB grids (see the file comment)
/// to path, atomically. The file's metadata holds "creator" (sss and its
/// version) and the brick map's provenance ("sss_provenance"). Throws
/// IoError when the file cannot be written.
VdbWriteReport write_brick_map_vdb(const BrickMap& map, const std::string& path);

/// What brickmake does for a .vdb output.
struct VdbMakeReport {
    BrickMapBuildReport build; ///< the brick map (its file_size: the .bkm's)
    VdbWriteReport vdb;
};

/// brickmake in.ptc ... out.vdb: builds the brick map from the clouds as
/// make_brick_map_from_files does, into a temporary file beside the output
/// that is removed afterwards, and writes its grids to output (atomically).
/// Throws as make_brick_map_from_files and write_brick_map_vdb.
VdbMakeReport make_vdb_from_files(const std::vector<std::string>& inputs,
                                  const BrickMapBuildOptions& options,
                                  const std::string& output);

/// A grid read from a .vdb file: float and vec3s grids with their voxels.
struct VdbGrid {
    VdbGridInfo info;
    int components = 1; ///< 1 (float) or 3 (vec3s)
    /// Active voxels in index order (x, then y, then z) and their values.
    std::vector<std::array<int32_t, 3>> coords;
    std::vector<float> values;
};

/// Reads the float and vec3s grids of a .vdb file (grids of other types are
/// left out). IoError when it cannot be opened, FormatError when it is not
/// an OpenVDB file or cannot be read.
std::vector<VdbGrid> read_vdb_grids(const std::string& path);

/// brickinfo's report of a .vdb file: the file's metadata and, per grid, its
/// name, value type, class, active voxels, voxel size, the world box of its
/// active voxels and its metadata. Reads only the grids' descriptions.
std::string describe_vdb_file(const std::string& path);

/// Why the file at path is not a readable OpenVDB file, or "" when it opens
/// (brickmake -newer 1 rebuilds such an output).
std::string vdb_file_problem(const std::string& path);

/// Whether path names a .vdb file (by its extension, any case).
bool is_vdb_path(const std::string& path);

} // namespace sss
