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

/// Throws ValueError unless the cloud can be written: consistent array sizes,
/// finite values, non-negative radii, unique one-word channel names, finite
/// header matrices. Called before any file is created.
void check_writable(const PointCloud& cloud);

/// Lower-case extension test ("x.PLY" has extension ".ply").
bool has_extension(const std::string& path, const std::string& ext);

/// "%.9g" formatting: enough digits to round-trip a float.
std::string format_float(double v);

} // namespace sss::detail
