// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file point_cloud_io_detail.h
/// Internal helpers shared by the .ptc and .ply readers and writers: the
/// checks every writer makes and small formatting helpers. Not installed.
/// The byte streams they read and write through are in sss/util/byte_io.h.

#include <bit>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "sss/cloud/point_cloud.h"
#include "sss/cloud/point_cloud_io.h"
#include "sss/util/byte_io.h"

namespace sss {
class AtomicOutput;
} // namespace sss

namespace sss::detail {

/// Most channels a cloud may have: what a .ptc header can declare (nvars), so
/// that every cloud a reader returns can be written as .ptc again.
constexpr int kMaxChannels = 4096;

/// Reserves a cloud's per-point arrays as points arrive, never ahead of the
/// data when the header's count cannot be checked: a gzip stream may inflate
/// to 1000x its size, so a small file can claim billions of points. With
/// `verified` (a plain file whose size was checked against the count) it
/// reserves the whole count at once; otherwise it starts small and doubles,
/// capped at the count, as room_for() is asked for more. Each reservation
/// above a few MB is first checked against the memory the process may use
/// (check_memory), so a cloud larger than that is an OutOfMemoryError naming
/// the file instead of a std::bad_alloc. The channels must be in place.
class CloudReserve {
public:
    CloudReserve(PointCloud& cloud, const std::string& path, uint64_t claimed,
                 bool verified);
    /// Makes room for `more` points after the cloud's current size.
    void room_for(std::size_t more) {
        if (m_cloud.size() + more > m_capacity) grow(m_cloud.size() + more);
    }

private:
    void grow(uint64_t needed);
    void reserve(uint64_t capacity);

    PointCloud& m_cloud;
    const std::string& m_path;
    uint64_t m_claimed;
    uint64_t m_point_bytes; ///< memory per point: position, normal, radius, channels
    uint64_t m_capacity = 0;
};

/// A .ptc file read a chunk of points at a time: the header on construction
/// (every check read_ptc makes), the records on demand.
class PtcReader {
public:
    explicit PtcReader(const std::string& path);
    ~PtcReader();
    /// Channels (without data), matrices, format, version, compression.
    const PointCloud& header() const { return m_header; }
    /// Points the header claims.
    uint64_t size() const { return m_npoints; }
    /// Whether size() was checked against the size of a plain file.
    bool verified() const { return m_verified; }
    /// Appends the next (up to) `max` points to `cloud`, whose channels are
    /// the header's; returns how many. With `reserve`, asks it for room before
    /// each batch is appended. Throws FormatError as read_ptc does. The stream
    /// is finished (gzip trailer checked) with the last point.
    std::size_t read_into(PointCloud& cloud, std::size_t max, CloudReserve* reserve);

private:
    /// Appends the k records in m_buf to `cloud` (in parallel); throws for
    /// the first bad one.
    void decode_records(PointCloud& cloud, std::size_t k);

    std::unique_ptr<ByteSource> m_in;
    PointCloud m_header;
    uint64_t m_npoints = 0;
    uint64_t m_done = 0;
    std::size_t m_record = 0;
    bool m_verified = false;
    bool m_finished = false;
    std::vector<unsigned char> m_buf;
};

/// A .ptc file written a chunk of points at a time, atomically: the header
/// (with the bounds and largest radius of all the points, which the caller
/// knows ahead) on construction, the records by write(), the rename by commit().
class PtcWriter {
public:
    PtcWriter(const std::string& path, const PointCloud& header, uint64_t count,
              const Bounds3& bounds, float max_radius,
              const PointCloudWriteOptions& options);
    ~PtcWriter();
    /// Writes the chunk's records (its channels must be the header's).
    void write(const PointCloud& chunk);
    /// Throws ValueError unless exactly `count` points were written.
    void commit();

private:
    std::unique_ptr<AtomicOutput> m_out;
    std::unique_ptr<ByteSink> m_sink;
    uint64_t m_count = 0;
    uint64_t m_written = 0;
    std::size_t m_record = 0;
    int m_data_size = 0;
    std::vector<unsigned char> m_rec;
};

/// Throws ValueError unless the cloud can be written: consistent array sizes,
/// finite values, non-negative radii, unique one-word channel names, finite
/// header matrices. Called before any file is created.
void check_writable(const PointCloud& cloud);

/// The channel names part of check_writable: each one check_channel_name's,
/// none repeated.
void check_channel_names(const PointCloud& cloud);

/// Lower-case extension test ("x.PLY" has extension ".ply").
bool has_extension(const std::string& path, const std::string& ext);

/// "%.9g" formatting: enough digits to round-trip a float.
std::string format_float(double v);

} // namespace sss::detail
