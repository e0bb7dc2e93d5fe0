// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file cloud_part.h
/// Parts of a point cloud computed on different machines (ptfilter -part K/N)
/// and their join: the `.ptpart` file (layout in docs/file-formats.md), a
/// fingerprint that ties the parts of one job together, and the merge.

#include <cstdint>
#include <string>
#include <vector>

#include "sss/cloud/point_cloud.h"
#include "sss/cloud/point_cloud_io.h"

namespace sss {

/// The extension of part files.
inline constexpr const char* kCloudPartExtension = ".ptpart";

/// What a part file says about itself (its header).
struct CloudPartInfo {
    uint32_t part = 1;        ///< K, 1-based
    uint32_t parts = 1;       ///< N
    uint64_t fingerprint = 0; ///< the same in every part of one job
    uint64_t total = 0;       ///< points of the whole cloud
    uint64_t first = 0;       ///< points held by parts 1 .. K-1
    uint64_t count = 0;       ///< points in this part
    /// How the joined cloud is written (the options of the job that made it).
    PointCloudWriteOptions write_options;
};

/// One part: its header and its points. indices[k] is the index of points'
/// point k in the whole cloud. The points carry the whole cloud's header
/// (matrices, format) and all its channels.
struct CloudPart {
    CloudPartInfo info;
    std::vector<uint64_t> indices;
    PointCloud points;
};

/// Writes a part atomically (temporary + rename). Throws IoError, or
/// ValueError for an inconsistent part (sizes, part numbers, indices).
void write_cloud_part(const CloudPart& part, const std::string& path);

/// Reads and checks a part's header only (both checksums' header part):
/// FormatError for anything but a complete, intact part file header, and for
/// a file whose size is not the size the header implies (truncated).
CloudPartInfo read_cloud_part_info(const std::string& path);

/// Reads a whole part, checksums verified. Throws FormatError / IoError.
CloudPart read_cloud_part(const std::string& path);

/// Joins parts given in any order into the whole cloud and says how to write
/// it (`write_options`). Every header is checked before any data is read:
/// one fingerprint and one N for all, each part 1..N exactly once, ranges
/// that tile the whole cloud, the same channels; then each part is read (one
/// at a time) and its points put at their indices, each index exactly once.
/// Throws ValueError naming the files for a missing, repeated or foreign
/// part, FormatError for a damaged one.
PointCloud merge_cloud_parts(const std::vector<std::string>& paths,
                             PointCloudWriteOptions& write_options);

/// A 64-bit fingerprint of a cloud's content (points, channels with names
/// and types, header matrices and format), continuing from `seed`.
uint64_t cloud_fingerprint(const PointCloud& cloud, uint64_t seed = 0);

} // namespace sss
