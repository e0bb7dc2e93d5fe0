// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
// Internal: the Newell teapot of `Geometry "teapot"` (teapot.cpp), diced by
// dice_patch.cpp as 32 bicubic Bezier patches.

#include <array>

#include <glm/vec3.hpp>

namespace sss::detail {

/// One bicubic patch: 16 control points in RenderMan order (u varies
/// fastest: point [4 * row_v + column_u]).
using BicubicControlPoints = std::array<glm::dvec3, 16>;

/// The 32 Bezier patches of the classic Newell teapot (rim, body, handle,
/// spout, lid, bottom) in its original units: z up, resting on z = 0, spout
/// towards +x. Oriented so that dPdu x dPdv points out of the teapot.
const std::array<BicubicControlPoints, 32>& teapot_patches();

} // namespace sss::detail
