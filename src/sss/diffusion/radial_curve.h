// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file radial_curve.h
/// A profile known by its values: f(rho) = rho R(rho) with rho = r sigma_t'
/// (lengths in transport mean free paths), sampled on a logarithmic grid and
/// interpolated by a natural cubic spline of ln f in ln rho. The profiles that
/// are not closed forms (photon beam diffusion, the Monte-Carlo table) are
/// curves: they are universal in rho for a given (alpha', eta), so one curve
/// serves every length scale.

#include <functional>
#include <vector>

namespace sss {

class RadialCurve {
public:
    /// Samples f at `per_decade` points per decade from rho_min to rho_max
    /// (f > 0 there). Below rho_min f is taken as constant (R ~ 1/rho, the
    /// single-scattering peak); past rho_max it decays exponentially at the
    /// rate of the last interval.
    RadialCurve(double rho_min, double rho_max, int per_decade,
                const std::function<double(double)>& f);

    /// f(rho) = rho R(rho).
    double value(double rho) const;
    /// \int_0^rho f(t) dt, so that the flux within radius rho is 2 pi times it.
    double integral(double rho) const;
    /// integral(infinity).
    double total() const { return m_total; }
    double rho_max() const { return m_rho_max; }
    /// The far tail's decay rate (per transport mean free path).
    double tail_rate() const { return m_tail_rate; }

private:
    double m_x0 = 0, m_h = 0; // knots at x = ln rho = m_x0 + k m_h
    double m_rho_min = 0, m_rho_max = 0;
    std::vector<double> m_g;   // ln f at the knots
    std::vector<double> m_m;   // spline second derivatives
    std::vector<double> m_cum; // integral at the knots
    double m_tail_rate = 0, m_total = 0;

    double ln_value(double x, std::size_t k) const;
    double integral_within(std::size_t k, double x) const;
};

} // namespace sss
