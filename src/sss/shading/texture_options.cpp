// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// The token-value options of RSL's texture calls (texture, environment,
// shadow: texture_services.h), texture3d and bake3d (texture_options.h).

#include "texture_options.h"

#include <algorithm>
#include <cmath>

#include "sss/shading/texture_services.h"

namespace sss {

bool set_texture_option(TextureOptions& options, std::string_view name,
                        const float* numbers, int count, const std::string* text) {
    const bool number = numbers && count >= 1;
    const float x = number ? numbers[0] : 0.0f;
    if (name == "blur") {
        if (number) options.sblur = options.tblur = x;
    } else if (name == "sblur") {
        if (number) options.sblur = x;
    } else if (name == "tblur") {
        if (number) options.tblur = x;
    } else if (name == "width") {
        if (number) options.swidth = options.twidth = x;
    } else if (name == "swidth") {
        if (number) options.swidth = x;
    } else if (name == "twidth") {
        if (number) options.twidth = x;
    } else if (name == "samples") {
        if (number) options.samples = std::max(1, static_cast<int>(std::lround(x)));
    } else if (name == "filter") {
        if (text) options.filter = *text;
    } else if (name == "fill") {
        if (number) options.fill = x;
    } else if (name == "bias") {
        if (number) options.bias = x;
    } else if (name == "lerp") {
        if (number) options.lerp = std::clamp(static_cast<int>(std::lround(x)), 0, 2);
    } else {
        return false;
    }
    return true;
}

namespace detail {

bool set_texture3d_option(Texture3dOptions& options, std::string_view name,
                          const float* numbers, int count, const std::string* text) {
    const bool number = numbers && count >= 1;
    const float x = number ? numbers[0] : 0.0f;
    if (name == "coordsystem") {
        if (text) options.coordsystem = *text;
    } else if (name == "filterradius" || name == "radius") {
        if (number) options.filterradius = x;
    } else if (name == "filterscale" || name == "radiusscale") {
        if (number) options.filterscale = x;
    } else if (name == "maxdepth") {
        if (number) options.maxdepth = static_cast<int>(std::lround(x));
    } else if (name != "interpolate") {
        return false;
    }
    return true;
}

bool set_bake3d_option(Bake3dOptions& options, std::string_view name,
                       const float* numbers, int count, const std::string* text) {
    const bool number = numbers && count >= 1;
    const float x = number ? numbers[0] : 0.0f;
    if (name == "radius") {
        if (number) options.radius = x;
    } else if (name == "radiusscale") {
        if (number) options.radiusscale = x;
    } else if (name == "coordsystem") {
        if (text) options.coordsystem = *text;
    } else if (name == "interpolate") {
        if (number) options.interpolate = x != 0.0f;
    } else {
        return false;
    }
    return true;
}

} // namespace detail

} // namespace sss
