// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
// Internal to the shading module: the token-value options of texture3d and
// bake3d calls, as the engine reads them (texture_options.cpp; the 2-D
// texture options are public, texture_services.h).

#include <string>
#include <string_view>

namespace sss::detail {

/// Options of texture3d calls (formats.md 3.5). The engine turns them into
/// the per-point world-space P, N and filter radius texture3d() takes.
struct Texture3dOptions {
    std::string coordsystem = "world"; // space of the file's data
    float filterradius =
        -1; // < 0: not given (the shading point's own radius); 0: the finest data
    float filterscale = 1; // multiplies filterradius
    int maxdepth = -1;     // brick maps: accepted, not used (-1: all)
};

/// Sets a texture3d option ("coordsystem", "filterradius", "filterscale",
/// "maxdepth"; Pixie's "radius" and "radiusscale" as the first two, its
/// "interpolate" accepted and ignored). False for an unknown name.
bool set_texture3d_option(Texture3dOptions& options, std::string_view name,
                          const float* numbers, int count, const std::string* text);

/// Options of bake3d calls (formats.md 3.5).
struct Bake3dOptions {
    float radius = -1;                 // < 0: not given (the micropolygon's size)
    float radiusscale = 1;             // multiplies the radius
    std::string coordsystem = "world"; // space the points are written in
    bool interpolate = false;          // bake micropolygon centres
};

/// Sets a bake3d option ("radius", "radiusscale", "coordsystem",
/// "interpolate"). False for an unknown name.
bool set_bake3d_option(Bake3dOptions& options, std::string_view name,
                       const float* numbers, int count, const std::string* text);

} // namespace sss::detail
