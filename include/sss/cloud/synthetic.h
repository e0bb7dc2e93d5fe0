// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file synthetic.h
/// Synthetic lit point clouds with known geometry: for the demo, tests and
/// benchmarks, and for checking a pipeline without a renderer (ptsynth).

#include <cstddef>
#include <cstdint>

#include <glm/vec3.hpp>

#include "sss/cloud/point_cloud.h"

namespace sss {

/// Shapes ptsynth can make.
enum class SyntheticShape {
    Sphere, ///< sphere of radius `size` centred at the origin (Fibonacci lattice)
    Plane,  ///< square of side `size` in z = 0, normal +z (regular grid, optional jitter)
    Box     ///< box size x size x thickness centred at the origin (grids on all 6 faces)
};

/// Parameters of a synthetic cloud.
struct SyntheticParams {
    SyntheticShape shape = SyntheticShape::Sphere;
    std::size_t count = 100000; ///< approximate number of points
    double size = 50.0;         ///< sphere radius / plane or box side (scene units)
    double thickness = 5.0;     ///< box only
    double jitter = 0.0;        ///< plane/box: random offset, fraction of the spacing
    uint64_t seed = 1;          ///< jitter seed (output is deterministic)
    glm::dvec3 light_dir{0, 0,
                         1}; ///< direction towards a distant light (normalised inside)
    glm::dvec3 light_color{1, 1, 1};
    double ambient = 0.0; ///< constant irradiance added everywhere
};

/// Makes the cloud: P, N, radius (half diagonal of the point's square patch),
/// `float _area` (exact share of the surface area; areas add up to the surface
/// area) and `color _radiance_t` = light_color * max(0, N.L) + ambient.
PointCloud make_synthetic_cloud(const SyntheticParams& params);

} // namespace sss
