// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file brickmap.h
/// Module brick: brick maps (build, .bkm format, cached lookups, brickinfo
/// reports and pictures).
/// May use: image, cloud and util.
///
/// Brick maps: sparse octrees of 8^3-sample bricks built from point clouds
/// (brickmake), stored in our own documented .bkm format (docs/bkm-format.md),
/// read with bricks loaded on demand through a bounded cache, and looked up
/// with texture3d semantics.
///
/// Structure: 7 octrees over one cubic bounding box. Tree 0 holds points
/// without normals (or everything with ignore_normals); trees 1..6 hold points
/// whose normal is near +x, -x, +y, -y, +z, -z, so the two sides of a thin
/// surface never blend. A node at depth d covers a cube of edge side / 2^d;
/// its brick holds 8 x 8 x 8 samples at the cube's corners and 6 interior
/// steps (sample i at min + i * edge / 7), so neighbouring bricks share
/// their faces and trilinear interpolation never leaves a brick. Samples
/// carry a presence flag (sparse data).

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "sss/cloud/point_cloud.h"

namespace sss {

class Progress; // sss/util/progress.h

/// brickmake's options (PRMan names).
struct BrickMapBuildOptions {
    double max_error = 0.002;    ///< -maxerror: absolute, in the channel's units
    int max_depth = 15;          ///< -maxdepth
    double radius_scale = 1.0;   ///< -radiusscale
    bool ignore_normals = false; ///< -ignorenormals 1: one tree, normals ignored
    bool omit_geometry = false;  ///< -omitgeometry 1: no occupancy data (see docs)
    /// Channels to store; empty = every float and color channel of the input.
    std::vector<std::string> channels;
    Progress* progress = nullptr;
    /// Free text stored in the file: tool version and command line.
    std::string provenance;
};

/// Bricks and samples at one depth (all trees).
struct BrickMapLevel {
    int depth = 0;
    std::size_t bricks = 0;
    std::size_t samples = 0; ///< samples with data
    /// Occupancy-only nodes (presence mask, no data: the geometry that
    /// -omitgeometry 1 leaves out).
    std::size_t occupancy_nodes = 0;
};

/// Everything in a .bkm header, for brickinfo and tests.
struct BrickMapInfo {
    uint32_t version = 0;
    std::vector<std::pair<std::string, ChannelType>> channels; ///< float or color
    int data_size = 0;                                         ///< floats per sample
    glm::dvec3 bbox_min{0.0};                                  ///< of the input points
    glm::dvec3 bbox_max{0.0};
    glm::dvec3 cube_min{0.0}; ///< the root cube (all trees)
    double cube_side = 0.0;
    int max_depth = 0;      ///< as built (-maxdepth)
    double max_error = 0.0; ///< as built
    bool ignore_normals = false;
    bool omit_geometry = false;
    std::array<float, 16> world_to_eye{};
    std::array<float, 16> world_to_ndc{};
    std::array<float, 3> format{};
    std::string provenance;
    std::vector<BrickMapLevel> levels; ///< depth 0 .. deepest
    std::size_t trees_used = 0;        ///< trees with at least one brick
    std::size_t total_bricks = 0;
    std::size_t total_samples = 0;
    std::size_t occupancy_nodes = 0; ///< all trees, all depths
    uint64_t file_size = 0;
};

/// What the build did.
struct BrickMapBuildReport {
    std::size_t points = 0;
    std::size_t bricks_before_pruning = 0;
    std::size_t bricks_written = 0;
    uint64_t file_size = 0;
    double seconds = 0.0;
};

/// Builds a brick map from clouds (merged; channels matched by name and
/// type) and writes it atomically to path. Throws ValueError (no points, no
/// usable channel, a named channel missing or not float/color, radius <= 0,
/// bad options) and IoError. Output does not depend on the thread count.
BrickMapBuildReport build_brick_map(const std::vector<PointCloud>& clouds,
                                    const BrickMapBuildOptions& options,
                                    const std::string& path);

/// Whether a BrickMap compares the file's CRC-32 checksums
/// (docs/bkm-format.md, "Integrity").
enum class BrickMapChecksums {
    Verify, ///< every tool: a mismatch is a FormatError
    /// Fuzz target and tests only: mutated files get past the checksums to
    /// the structural checks (which still all run).
    Ignore
};

/// A brick map file opened for lookups. Bricks are read from the file on
/// demand and kept in a bounded cache, so maps larger than memory work.
/// Thread-safe: any number of threads may call lookup() at once.
class BrickMap {
public:
    /// Opens and validates the header and node tables, checksum included
    /// (FormatError on a corrupt, truncated or wrong-version file; IoError
    /// if unreadable; LimitError beyond Limit::Bricks; OutOfMemoryError when
    /// the node tables would not fit in memory). cache_bytes bounds the
    /// memory held by cached bricks. Each brick is checked (checksum,
    /// presence mask, finite values) when it is first read, before any
    /// lookup uses it.
    explicit BrickMap(const std::string& path, std::size_t cache_bytes = 256u << 20,
                      BrickMapChecksums checksums = BrickMapChecksums::Verify);
    ~BrickMap();
    BrickMap(const BrickMap&) = delete;
    BrickMap& operator=(const BrickMap&) = delete;

    const BrickMapInfo& info() const;
    /// Index of a channel, or -1.
    int channel_index(const std::string& name) const;
    /// Offset of a channel's first float within a sample's data, or -1.
    int channel_offset(const std::string& name) const;

    /// texture3d: the value of every channel (data_size floats into out) at
    /// world point p, for a surface with normal n (zero: the no-normal tree),
    /// filtered at radius filter_radius (0: the finest level there).
    /// Trilinear within a level over the samples that have data, a blend
    /// between the two levels nearest to the filter radius, and fallback to
    /// coarser data where finer is missing. Returns false (out zeroed) when no
    /// level has data around p.
    bool lookup(const glm::vec3& p, const glm::vec3& n, float filter_radius,
                float* out) const;
    /// lookup() of the data of one depth: trilinear over that depth's samples
    /// at p, falling back to coarser depths where it has none (pruned bricks),
    /// never reading finer ones. The voxels of a depth (brickmap_voxels.h).
    bool lookup_depth(const glm::vec3& p, const glm::vec3& n, int depth,
                      float* out) const;

    /// Reads one brick for inspection (brickinfo pictures, tests): the
    /// samples of node (tree, depth, ix, iy, iz); false if there is no such
    /// brick (occupancy-only nodes have none). data gets 512 * data_size
    /// floats (absent samples 0), present 512 flags (index i + 8 j + 64 k).
    /// Reads the file directly (the lookup cache is not used).
    bool read_brick(int tree, int depth, uint32_t ix, uint32_t iy, uint32_t iz,
                    std::vector<float>& data, std::vector<uint8_t>& present) const;
    /// Node coordinates (ix, iy, iz) of every brick of a tree at a depth.
    std::vector<std::array<uint32_t, 3>> bricks_at(int tree, int depth) const;
    /// Node coordinates of every node of a tree at a depth, data bricks and
    /// occupancy-only nodes alike: where the map has geometry at that depth.
    std::vector<std::array<uint32_t, 3>> nodes_at(int tree, int depth) const;
    /// The presence flags (which samples have geometry in them) of any node,
    /// data brick or occupancy-only; false if the file has no such node.
    bool read_occupancy(int tree, int depth, uint32_t ix, uint32_t iy, uint32_t iz,
                        std::vector<uint8_t>& present) const;

    /// Reads every brick, data and occupancy-only, from the file and checks
    /// it (checksum, presence mask against its record, finite values): what
    /// brickinfo does before it reports. FormatError naming the first bad
    /// brick; returns the number of bricks checked. Does not use the cache.
    std::size_t verify() const;

    /// Cache statistics: bricks read from disk so far, bytes currently cached.
    std::size_t bricks_loaded() const;
    std::size_t cached_bytes() const;

private:
    bool lookup(const glm::vec3& p, const glm::vec3& n, float filter_radius,
                int max_depth, float* out) const;

    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

} // namespace sss
