// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file camera_sampling.h
/// The renderer's camera sampling (docs/render.md): the pixel
/// reconstruction filters of RISpec 3.2 appendix E and the stratified
/// samples of a thin lens (DepthOfField).

#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec2.hpp>

#include "sss/scene/scene.h"

namespace sss {

/// A PixelFilter: its weight at an offset (pixels) from a pixel's centre,
/// zero outside the xwidth/2 by ywidth/2 support.
class PixelFilter {
public:
    /// Throws ValueError for an unknown name or widths outside (0, 16].
    explicit PixelFilter(const PixelFilterSpec& spec);

    /// Whether the weight is wx(dx) * wy(dy) (box, triangle, gaussian,
    /// sinc); catmull-rom is radial.
    bool separable() const { return m_kind != Kind::CatmullRom; }
    /// Separable filters: the weight along x (y) at offset d, 0 beyond the
    /// half width; catmull-rom: 1 inside the half width (its support).
    double weight_x(double d) const { return axis(d, m_rx); }
    double weight_y(double d) const { return axis(d, m_ry); }
    /// The weight at offset (dx, dy): weight_x * weight_y, or the radial
    /// catmull-rom inside the support.
    double weight(double dx, double dy) const;
    /// Half widths: how far (pixels) from a pixel's centre samples count.
    double radius_x() const { return m_rx; }
    double radius_y() const { return m_ry; }
    /// Pixels a sample reaches on each side of its own: ceil(radius - 0.5).
    int reach_x() const;
    int reach_y() const;

private:
    enum class Kind { Box, Triangle, CatmullRom, Gaussian, Sinc };
    double axis(double d, double r) const;
    Kind m_kind = Kind::Gaussian;
    double m_rx = 1.0, m_ry = 1.0;
};

/// Shirley and Chiu's concentric map of the unit square onto the unit disk
/// (area preserving, keeps strata compact).
glm::dvec2 concentric_disk(double u, double v);

/// The lens positions in the unit square of the nx * ny samples of one
/// pixel, in sample order (j * nx + i): one per cell of an nx x ny grid,
/// the cells assigned to samples by a permutation and jittered, both from
/// `pixel_key` only (a different shuffle per pixel, none per thread).
std::vector<glm::dvec2> lens_square_samples(uint64_t pixel_key, int nx, int ny);

/// Motion blur: n times in [0, 1) for a pixel's n samples, one per stratum
/// of width 1/n, jittered, in an order shuffled by the pixel's key (a stream
/// of their own, apart from the pixel and lens positions).
std::vector<double> time_samples(uint64_t pixel_key, int n);

} // namespace sss
