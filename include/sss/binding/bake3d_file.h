// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file bake3d_file.h
/// Module binding: the file side of RSL's bake3d: the records shaders hand to
/// ShadingServices::bake3d (engine.h), merged per file into point clouds and
/// written as .ptc (or .ply) files, for ptbake and render.

#include <span>
#include <string>
#include <utility>
#include <vector>

#include "sss/cloud/point_cloud.h"
#include "sss/cloud/point_cloud_io.h"
#include "sss/shading/engine.h"

namespace sss {

/// Declared channel types: name -> RenderMan type ("color _radiance_t" in a
/// DisplayChannel gives {"_radiance_t", "color"}; Scene::display_channels).
using ChannelDeclarations = std::vector<std::pair<std::string, std::string>>;

/// Merges bake3d records (of one file) into a point cloud, points in the
/// records' order (collect them in a deterministic order for reproducible
/// files). A channel's type is its declaration in `declared`, else by size:
/// 1 float, 3 color, 16 matrix. Channels absent from some records are 0
/// there. Throws ValueError for a record whose sizes disagree (P, N, radius,
/// values), a channel whose size differs from its declared type or between
/// records, or a bad channel name.
PointCloud bake3d_point_cloud(std::span<const Bake3dRecord> records,
                              const ChannelDeclarations& declared = {});

/// The point clouds of bake3d records, one per file in the order of the
/// files' first records: each file's records merged (bake3d_point_cloud)
/// with a float `_area` channel first (the records' own "_area" values, else
/// Bake3dRecord::area), and, given a camera, its world-to-eye and
/// world-to-NDC matrices and image format. Throws ValueError naming the file.
std::vector<std::pair<std::string, PointCloud>>
bake3d_clouds(std::span<const Bake3dRecord> records,
              const ChannelDeclarations& declared = {}, const Camera* camera = nullptr);

/// bake3d_clouds, each cloud written atomically (write_point_cloud: .ptc or
/// .ply by extension). Every name is checked before any file is written: a
/// known extension, a writable folder, and (with a current JobFiles) not a
/// file the job reads or writes otherwise. Returns the files written, in the
/// order of their first record. Throws ValueError naming the file,
/// OutputConflictError and IoError.
std::vector<std::string> write_bake3d_files(std::span<const Bake3dRecord> records,
                                            const ChannelDeclarations& declared = {},
                                            const PointCloudWriteOptions& options = {},
                                            const Camera* camera = nullptr);

} // namespace sss
