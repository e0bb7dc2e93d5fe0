// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
// Internal to the 2-D texture plugin: depth maps (zfiles, shadow maps) and
// cube-face environments, through OpenImageIO (texture2d_makers.cpp).

#include <array>
#include <string>

#include "../texture2d_backend.h"

namespace sss::detail {

/// Whether OpenImageIO knows the resampling filter `name`.
bool known_filter(const std::string& name);

bool read_depth_map_file(const std::string& file, DepthMapData& out, std::string* error);

bool make_shadow_file(const std::string& input, const std::string& output,
                      std::string* error);

bool make_cube_environment_file(const std::array<std::string, 6>& faces,
                                const std::string& output, double fov,
                                const std::string& filter, std::string* error);

} // namespace sss::detail
