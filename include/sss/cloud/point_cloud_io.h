// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file point_cloud_io.h
/// Reading and writing point clouds: Pixar .ptc (versions 0-2, plain or gzip)
/// and binary little-endian .ply. The format is chosen by file extension.

#include <array>
#include <cstdint>
#include <memory>
#include <string>

#include "sss/cloud/point_cloud.h"

namespace sss {

/// Options for writing point clouds.
struct PointCloudWriteOptions {
    int ptc_version = 0;   ///< 0, 1 or 2 (.ptc only); 0 is what Partio writes
    bool compress = false; ///< gzip the .ptc stream (Partio and PRMan read it)
};

/// Longest line "<type> <name>" declaring a channel in a .ptc header, newline
/// left out: what the .ptc reader accepts, so also what the writers write.
constexpr std::size_t kMaxChannelSpecLine = 4095;

/// Throws ValueError unless `name` can name a channel of type `type` in a
/// written cloud, one the readers read back: not empty, no whitespace or
/// control bytes (NUL included), its spec line at most kMaxChannelSpecLine
/// bytes (a color channel's name at most 4089). The name is quoted and cut in
/// the message, so the cause stays in it.
void check_channel_name(const std::string& name, ChannelType type);

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

/// The channel a .ply file shows as its vertex colours (uchar red, green,
/// blue, which MeshLab and CloudCompare display): `_ssdiffusion` when it is
/// a color channel, else the first color channel; nullptr when there is none
/// (or when the cloud has channels of its own named red, green or blue).
/// The channels are written as floats as well, so the file reads back exactly.
const Channel* ply_display_channel(const PointCloud& cloud);
/// One colour byte of a .ply display colour: the value clamped to [0, 1],
/// sRGB-encoded (viewers send the bytes to the screen as they are) and
/// rounded to the nearest of 0..255.
uint8_t ply_display_byte(float value);

/// Reads a point cloud a chunk of points at a time, so that a job that needs
/// only some of its channels, or reads it twice, never holds it whole. A .ptc
/// file is streamed; a .ply file is read whole when opened and handed out in
/// chunks. The checks and errors are read_point_cloud()'s.
class PointCloudReader {
public:
    /// Opens the file and reads its header (throws as read_point_cloud).
    explicit PointCloudReader(const std::string& path);
    ~PointCloudReader();
    PointCloudReader(const PointCloudReader&) = delete;
    PointCloudReader& operator=(const PointCloudReader&) = delete;

    /// The cloud without its points: channels (no data), header matrices,
    /// image format, file version and compression.
    const PointCloud& header() const;
    /// The number of points the file holds (its header's count).
    uint64_t size() const;
    /// Whether size() was checked against the file's length (a plain .ptc
    /// file, or a .ply file read whole), so that memory can be reserved for
    /// it: a gzip stream may claim far more points than it holds.
    bool size_verified() const;
    /// Replaces chunk's points with the next (up to) `max` points, its
    /// channels with the header's; returns how many (0: all were read).
    std::size_t read(PointCloud& chunk, std::size_t max);

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

/// Writes a point cloud a chunk of points at a time, atomically (the target
/// is replaced on commit() only). The .ptc header holds the bounding box and
/// largest radius of all the points, so the caller gives them ahead. A .ply
/// target is gathered in memory and written on commit().
class PointCloudWriter {
public:
    /// `header`: the channels (names and types; data ignored), matrices and
    /// image format of the output. Throws ValueError for options or channels
    /// the format cannot hold, IoError when the target cannot be written.
    PointCloudWriter(const std::string& path, const PointCloud& header, uint64_t count,
                     const Bounds3& bounds, float max_radius,
                     const PointCloudWriteOptions& options = {});
    ~PointCloudWriter();
    PointCloudWriter(const PointCloudWriter&) = delete;
    PointCloudWriter& operator=(const PointCloudWriter&) = delete;

    /// Appends the chunk's points (channels as the header's, in that order).
    /// Throws ValueError as write_point_cloud does for values it cannot write.
    void write(const PointCloud& chunk);
    /// Puts the file in place; ValueError unless `count` points were written.
    void commit();

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

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
