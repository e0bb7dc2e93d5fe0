// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file srgb.h
/// The sRGB transfer curve, shared by the pictures (brickinfo, ptview) and the
/// display colours of .ply clouds.

#include <cmath>

namespace sss {

/// The sRGB transfer curve (IEC 61966-2-1): linear [0, 1] -> encoded [0, 1].
inline double srgb_encode(double linear) {
    return linear <= 0.0031308 ? 12.92 * linear
                               : 1.055 * std::pow(linear, 1.0 / 2.4) - 0.055;
}

} // namespace sss
