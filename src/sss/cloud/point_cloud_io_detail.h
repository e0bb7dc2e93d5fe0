#pragma once
/// \file point_cloud_io_detail.h
/// Internal helpers shared by the .ptc and .ply readers and writers: the
/// checks every writer makes and small formatting helpers. Not installed.
/// The byte streams they read and write through are in sss/util/byte_io.h.

#include <bit>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "sss/cloud/point_cloud.h"
#include "sss/util/byte_io.h"

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

/// Throws ValueError unless the cloud can be written: consistent array sizes,
/// finite values, non-negative radii, unique one-word channel names, finite
/// header matrices. Called before any file is created.
void check_writable(const PointCloud& cloud);

/// Lower-case extension test ("x.PLY" has extension ".ply").
bool has_extension(const std::string& path, const std::string& ext);

/// "%.9g" formatting: enough digits to round-trip a float.
std::string format_float(double v);

} // namespace sss::detail
