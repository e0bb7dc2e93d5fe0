// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file radial_curve.cpp
/// The sampled profile curve: spline construction and its integral.

#include "radial_curve.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sss/util/error.h"

namespace sss {

namespace {

// Gauss-Legendre nodes and weights on [0, 1], 6 points: the integral of one
// spline interval of e^{g(x) + x} to far below the spline's own error.
constexpr double kGlX[6] = {0.033765242898423975, 0.16939530676686776,
                            0.38069040695840156,  0.6193095930415985,
                            0.8306046932331322,   0.966234757101576};
constexpr double kGlW[6] = {0.08566224618958517, 0.18038078652406933,
                            0.23395696728634552, 0.23395696728634552,
                            0.18038078652406933, 0.08566224618958517};

} // namespace

RadialCurve::RadialCurve(double rho_min, double rho_max, int per_decade,
                         const std::function<double(double)>& f) {
    if (!(rho_min > 0.0 && rho_max > rho_min && per_decade > 0))
        throw ValueError("radial curve: bad range");
    m_rho_min = rho_min;
    m_x0 = std::log(rho_min);
    const double span = std::log(rho_max) - m_x0;
    const std::size_t n = std::max<std::size_t>(
        4, std::size_t(std::ceil(span / std::log(10.0) * per_decade)) + 1);
    m_h = span / double(n - 1);
    m_rho_max = std::exp(m_x0 + m_h * double(n - 1));
    m_g.resize(n);
    for (std::size_t k = 0; k < n; ++k) {
        const double v = f(std::exp(m_x0 + m_h * double(k)));
        // A curve is positive; a value that underflows ends the useful range
        // (the floor keeps ln finite, its contribution is nil).
        m_g[k] = std::log(std::max(v, 1e-300));
        if (!std::isfinite(m_g[k])) throw ValueError("radial curve: non-finite value");
    }
    // Natural cubic spline on the uniform grid (tridiagonal solve).
    m_m.assign(n, 0.0);
    std::vector<double> c(n, 0.0), d(n, 0.0);
    for (std::size_t k = 1; k + 1 < n; ++k) {
        const double rhs = 6.0 * (m_g[k + 1] - 2.0 * m_g[k] + m_g[k - 1]) / (m_h * m_h);
        const double denom = 4.0 - c[k - 1];
        c[k] = 1.0 / denom;
        d[k] = (rhs - d[k - 1]) / denom;
    }
    for (std::size_t k = n - 1; k-- > 1;) m_m[k] = d[k] - c[k] * m_m[k + 1];
    // Tail rate from the last interval's slope of ln f against rho.
    const double slope =
        (m_g[n - 1] - m_g[n - 2]) / m_h + m_h * (m_m[n - 2] + 2.0 * m_m[n - 1]) / 6.0;
    m_tail_rate = std::max(-slope / m_rho_max, 1e-9);
    // Cumulative integrals: below rho_min f is flat.
    m_cum.assign(n, 0.0);
    m_cum[0] = std::exp(m_g[0]) * m_rho_min;
    for (std::size_t k = 0; k + 1 < n; ++k)
        m_cum[k + 1] = m_cum[k] + integral_within(k, m_x0 + m_h * double(k + 1));
    m_total = m_cum[n - 1] + std::exp(m_g[n - 1]) / m_tail_rate;
}

double RadialCurve::ln_value(double x, std::size_t k) const {
    const double a = (m_x0 + m_h * double(k + 1) - x) / m_h, b = 1.0 - a;
    return a * m_g[k] + b * m_g[k + 1] +
           ((a * a * a - a) * m_m[k] + (b * b * b - b) * m_m[k + 1]) * m_h * m_h / 6.0;
}

double RadialCurve::integral_within(std::size_t k, double x) const {
    // \int f d rho = \int e^{g(x) + x} dx from knot k to x.
    const double x0 = m_x0 + m_h * double(k), w = x - x0;
    double sum = 0.0;
    for (int i = 0; i < 6; ++i) {
        const double xi = x0 + w * kGlX[i];
        sum += kGlW[i] * std::exp(ln_value(xi, k) + xi);
    }
    return sum * w;
}

double RadialCurve::value(double rho) const {
    if (!(rho > m_rho_min)) return std::exp(m_g.front());
    const std::size_t n = m_g.size();
    if (rho >= m_rho_max) return std::exp(m_g[n - 1] - m_tail_rate * (rho - m_rho_max));
    const double x = std::log(rho);
    const std::size_t k = std::min(n - 2, std::size_t((x - m_x0) / m_h));
    return std::exp(ln_value(x, k));
}

double RadialCurve::integral(double rho) const {
    if (!(rho > 0.0)) return 0.0;
    if (rho <= m_rho_min) return std::exp(m_g.front()) * rho;
    const std::size_t n = m_g.size();
    if (rho >= m_rho_max) {
        if (std::isinf(rho)) return m_total;
        return m_cum[n - 1] + std::exp(m_g[n - 1]) *
                                  -std::expm1(-m_tail_rate * (rho - m_rho_max)) /
                                  m_tail_rate;
    }
    const double x = std::log(rho);
    const std::size_t k = std::min(n - 2, std::size_t((x - m_x0) / m_h));
    return m_cum[k] + integral_within(k, x);
}

} // namespace sss
