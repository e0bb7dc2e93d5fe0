#pragma once
/// \file point_cloud_io.h
/// Reading and writing point clouds: Pixar .ptc (versions 0-2, plain or gzip)
/// and binary little-endian .ply. The format is chosen by file extension.

#include <array>
#include <string>

#include "sss/cloud/point_cloud.h"

namespace sss {

/// Options for writing point clouds.
struct PointCloudWriteOptions {
    int ptc_version = 0;   ///< 0, 1 or 2 (.ptc only); 0 is what Partio writes
    bool compress = false; ///< gzip the .ptc stream (Partio and PRMan read it)
};

/// Reads a .ptc (any other extension) or .ply file. Validates everything and
/// throws FormatError (bad magic, version, truncation, size mismatch, NaN/Inf)
/// or IoError naming the file.
PointCloud read_point_cloud(const std::string& path);

/// Writes by extension (.ply, else .ptc) atomically: a temporary file in the
/// target folder is renamed over the target only when complete.
void write_point_cloud(const PointCloud& cloud, const std::string& path,
                       const PointCloudWriteOptions& options = {});

/// Format-specific entry points (used by the above and by tests).
PointCloud read_ptc(const std::string& path);
void write_ptc(const PointCloud& cloud, const std::string& path,
               const PointCloudWriteOptions& options = {});
PointCloud read_ply(const std::string& path);
void write_ply(const PointCloud& cloud, const std::string& path);

/// Per-channel statistics, as printed by ptinfo.
struct ChannelStats {
    std::string name;
    ChannelType type = ChannelType::Float;
    std::vector<double> min, mean, max; ///< one entry per component
};
/// Computes min/mean/max per component of every channel (and of radius).
/// The first entry is the pseudo-channel "radius" (type Float), then the
/// channels in order. Sums are accumulated in double; all zero when empty.
std::vector<ChannelStats> channel_stats(const PointCloud& cloud);

/// Text helpers shared by the info tools (ptinfo, brickinfo): a number with
/// "%.6g", a 4x4 matrix as "a b c d | e f g h | ..." (stored order), and
/// whether a stored matrix is the identity.
std::string short_float(double v);
std::string matrix_text(const std::array<float, 16>& m);
bool is_identity(const std::array<float, 16>& m);

/// The report ptinfo prints for a cloud read from path: file format and
/// version, compression, point count, bbox, header matrices and image format
/// when not the defaults, each channel as "<type> <name>", and with stats the
/// per-component min/mean/max of every channel and of the radius.
std::string describe_point_cloud(const std::string& path, const PointCloud& cloud,
                                 bool stats = true);

} // namespace sss
