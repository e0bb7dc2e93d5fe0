// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file camera_sampling.cpp
/// Pixel filters (RISpec 3.2 appendix E) and thin-lens samples.

#include "sss/render/camera_sampling.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "sss/util/error.h"
#include "sss/util/hash.h"
#include "sss/util/math.h"

namespace sss {

PixelFilter::PixelFilter(const PixelFilterSpec& spec) {
    const std::string& n = spec.name;
    if (n == "box")
        m_kind = Kind::Box;
    else if (n == "triangle")
        m_kind = Kind::Triangle;
    else if (n == "catmull-rom" || n == "catmullrom")
        m_kind = Kind::CatmullRom;
    else if (n == "gaussian")
        m_kind = Kind::Gaussian;
    else if (n == "sinc")
        m_kind = Kind::Sinc;
    else
        throw ValueError("unknown pixel filter \"" + n +
                         "\" (box, triangle, catmull-rom, gaussian or sinc)");
    if (!(spec.xwidth > 0.0 && spec.xwidth <= 16.0) ||
        !(spec.ywidth > 0.0 && spec.ywidth <= 16.0))
        throw ValueError("pixel filter widths must lie in (0, 16] pixels");
    m_rx = 0.5 * spec.xwidth;
    m_ry = 0.5 * spec.ywidth;
}

double PixelFilter::axis(double d, double r) const {
    if (!(std::abs(d) < r)) return 0.0;
    switch (m_kind) {
    case Kind::Box:
        return 1.0;
    case Kind::Triangle:
        return 1.0 - std::abs(d) / r;
    case Kind::Gaussian: {
        // RISpec: x *= 2 / xwidth, exp(-2 x^2); for width 2 the scale is 1
        // exactly (the renderer's weights before PixelFilter existed).
        const double x = d / r;
        return std::exp(-2.0 * x * x);
    }
    case Kind::Sinc:
        // RISpec's sin(x) / x (x in pixels), cut off at the half width.
        return std::abs(d) < 0.001 ? 1.0 : std::sin(d) / d;
    case Kind::CatmullRom: // not separable: only the support
        return 1.0;
    }
    return 0.0;
}

double PixelFilter::weight(double dx, double dy) const {
    if (!(std::abs(dx) < m_rx) || !(std::abs(dy) < m_ry)) return 0.0;
    if (separable()) return axis(dx, m_rx) * axis(dy, m_ry);
    // RISpec's catmull-rom: radial, in pixels, zero from r = 2 on.
    const double r2 = dx * dx + dy * dy;
    const double r = std::sqrt(r2);
    if (r >= 2.0) return 0.0;
    return r < 1.0 ? 3.0 * r * r2 - 5.0 * r2 + 2.0 : -r * r2 + 5.0 * r2 - 8.0 * r + 4.0;
}

int PixelFilter::reach_x() const {
    return std::max(0, static_cast<int>(std::ceil(m_rx - 0.5)));
}
int PixelFilter::reach_y() const {
    return std::max(0, static_cast<int>(std::ceil(m_ry - 0.5)));
}

glm::dvec2 concentric_disk(double u, double v) {
    const double a = 2.0 * u - 1.0, b = 2.0 * v - 1.0;
    if (a == 0.0 && b == 0.0) return {0.0, 0.0};
    double r, phi;
    if (std::abs(a) > std::abs(b)) {
        r = a;
        phi = (kPi / 4.0) * (b / a);
    } else {
        r = b;
        phi = kPi / 2.0 - (kPi / 4.0) * (a / b);
    }
    return {r * std::cos(phi), r * std::sin(phi)};
}

std::vector<glm::dvec2> lens_square_samples(uint64_t pixel_key, int nx, int ny) {
    const int n = nx * ny;
    std::vector<int> cell(static_cast<std::size_t>(n));
    std::iota(cell.begin(), cell.end(), 0);
    // A stream of its own: the pixel position uses splitmix64(pixel_key + k * inc).
    uint64_t h = detail::splitmix64(pixel_key ^ 0x6C656E7344454653ull); // "lensDEFS"
    for (int k = n - 1; k > 0; --k) {                                   // Fisher-Yates
        h = detail::splitmix64(h);
        const int j = static_cast<int>(detail::unit_double(h) * (k + 1));
        std::swap(cell[std::size_t(k)], cell[std::size_t(std::min(j, k))]);
    }
    std::vector<glm::dvec2> out(static_cast<std::size_t>(n));
    for (int s = 0; s < n; ++s) {
        const int c = cell[std::size_t(s)];
        h = detail::splitmix64(h);
        const double ju = detail::unit_double(h);
        h = detail::splitmix64(h);
        const double jv = detail::unit_double(h);
        out[std::size_t(s)] = {((c % nx) + ju) / nx, ((c / nx) + jv) / ny};
    }
    return out;
}

std::vector<double> time_samples(uint64_t pixel_key, int n) {
    std::vector<double> out(static_cast<std::size_t>(std::max(n, 0)));
    uint64_t h = detail::splitmix64(pixel_key ^ 0x74696D6544454653ull); // "timeDEFS"
    for (int s = 0; s < n; ++s) {
        h = detail::splitmix64(h);
        out[std::size_t(s)] = (s + detail::unit_double(h)) / n;
    }
    for (int k = n - 1; k > 0; --k) { // Fisher-Yates
        h = detail::splitmix64(h);
        const int j = static_cast<int>(detail::unit_double(h) * (k + 1));
        std::swap(out[std::size_t(k)], out[std::size_t(std::min(j, k))]);
    }
    return out;
}

} // namespace sss
