// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file beam_diffusion.cpp
/// Photon beam diffusion and the cache of sampled curves.

#include "beam_diffusion.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>
#include <tuple>

#include "fresnel.h"
#include "sss/util/math.h"

namespace sss::diffusion_detail {

namespace {

// Gauss-Legendre on [0, 1], 6 points.
constexpr double kX[6] = {0.033765242898423975, 0.16939530676686776, 0.38069040695840156,
                          0.6193095930415985,   0.8306046932331322,  0.966234757101576};
constexpr double kW[6] = {0.08566224618958517, 0.18038078652406933, 0.23395696728634552,
                          0.23395696728634552, 0.18038078652406933, 0.08566224618958517};

// \int_{lo}^{60 + lo} g(z) dz in panels that double in width from `first`,
// so that a peak at z ~ rho (small rho) and the e^-z decay are both resolved.
template <class G>
double along_beam(double lo, double first, G&& g) {
    double sum = 0.0, a = lo, w = first;
    const double end = lo + 60.0;
    while (a < end) {
        const double b = std::min(end, a + w);
        for (int i = 0; i < 6; ++i) sum += kW[i] * (b - a) * g(a + (b - a) * kX[i]);
        a = b;
        w *= 2.0;
    }
    return sum;
}

} // namespace

double grosjean_sigma_tr(double alpha) {
    const double sa = 1.0 - alpha;
    const double d = (2.0 * sa + alpha) / 3.0;
    return std::sqrt(sa / d);
}

double beam_multiple(double alpha, double eta, double rho) {
    const double sa = 1.0 - alpha;
    const double D = (2.0 * sa + alpha) / 3.0;
    const double s = std::sqrt(sa / D);
    const FresnelMoments fm = fresnel_moments(eta);
    const double a = (1.0 + fm.three_c2) / (1.0 - fm.two_c1);
    const double c_phi = 0.25 * (1.0 - fm.two_c1), c_e = 0.5 * (1.0 - fm.three_c2);
    const double r2 = rho * rho;
    const double inv4pi = 1.0 / (4.0 * kPi);
    const auto at_depth = [&](double zr) {
        const double zv = -zr - 4.0 * a * D;
        const double dr = std::sqrt(r2 + zr * zr), dv = std::sqrt(r2 + zv * zv);
        const double er = std::exp(-s * dr), ev = std::exp(-s * dv);
        const double phi = inv4pi / D * (er / dr - ev / dv);
        const double e = inv4pi * (zr * (1.0 + s * dr) * er / (dr * dr * dr) -
                                   zv * (1.0 + s * dv) * ev / (dv * dv * dv));
        // d'Eon's correction: sources close to the exit point see less of the
        // diffusion they would feed.
        const double kappa = -std::expm1(-2.0 * (dr + zr));
        return std::exp(-zr) * kappa * (c_phi * phi + c_e * e);
    };
    return alpha * alpha *
           along_beam(0.0, std::min(1.0, std::max(rho, 1e-6)) / 8.0, at_depth);
}

double beam_single(double alpha, double eta, double rho) {
    // First collision at depth t (density e^-t), isotropic scattering towards
    // the exit point at distance d, the exit's Fresnel transmission; past
    // the critical angle nothing leaves.
    const double t_crit = eta > 1.0 ? rho * std::sqrt(eta * eta - 1.0) : 0.0;
    const double r2 = rho * rho;
    const auto at_depth = [&](double t) {
        const double d = std::sqrt(r2 + t * t);
        const double mu = t / d;
        return std::exp(-t - d) * mu / (d * d) * (1.0 - fresnel_internal(mu, eta));
    };
    const double first = std::min(1.0, std::max(std::max(rho, t_crit), 1e-6)) / 8.0;
    return alpha / (4.0 * kPi) * along_beam(t_crit, first, at_depth);
}

double beam_curve_value(double alpha, double eta, double rho) {
    return rho * (beam_multiple(alpha, eta, rho) + beam_single(alpha, eta, rho));
}

std::shared_ptr<const RadialCurve> cached_curve(int family, CurveMaker make, double alpha,
                                                double eta) {
    static std::mutex mutex;
    static std::map<std::tuple<int, double, double>, std::shared_ptr<const RadialCurve>>
        cache;
    const auto key = std::make_tuple(family, alpha, eta);
    {
        std::lock_guard<std::mutex> lock(mutex);
        auto it = cache.find(key);
        if (it != cache.end()) return it->second;
    }
    // Out to where the diffusion tail has lost e^-30 (capped: alpha -> 1
    // spreads the light without bound).
    const double s = grosjean_sigma_tr(alpha);
    const double rho_max = std::clamp(30.0 / std::max(s, 1e-12), 40.0, 1e5);
    auto curve = std::make_shared<const RadialCurve>(
        1e-4, rho_max, 24, [&](double rho) { return make(alpha, eta, rho); });
    std::lock_guard<std::mutex> lock(mutex);
    // Per-point materials make one curve per distinct albedo: bounded.
    if (cache.size() > 8192) cache.clear();
    return cache.emplace(key, std::move(curve)).first->second;
}

} // namespace sss::diffusion_detail
