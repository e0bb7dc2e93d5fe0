// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file fresnel.cpp
/// Fresnel reflectance inside the medium and its hemispherical moments.

#include "fresnel.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>

namespace sss::diffusion_detail {

// Fresnel reflectance for light inside a medium of relative index eta
// (inside/outside) meeting the boundary at cosine mu; total internal
// reflection beyond the critical angle.
double fresnel_internal(double mu, double eta) {
    double sin_i2 = std::max(0.0, 1.0 - mu * mu);
    double sin_t2 = eta * eta * sin_i2;
    if (sin_t2 >= 1.0) return 1.0;
    double cos_t = std::sqrt(1.0 - sin_t2);
    // Relative index for the inside -> outside interface is 1/eta.
    double n1 = eta, n2 = 1.0;
    double rs = (n1 * mu - n2 * cos_t) / (n1 * mu + n2 * cos_t);
    double rp = (n2 * mu - n1 * cos_t) / (n2 * mu + n1 * cos_t);
    return 0.5 * (rs * rs + rp * rp);
}

// Exact hemispherical Fresnel moments by composite Simpson integration
// (cached per ior: they are needed once per material).
FresnelMoments fresnel_moments(double eta) {
    static std::mutex mutex;
    static std::map<double, FresnelMoments> cache;
    std::lock_guard<std::mutex> lock(mutex);
    auto it = cache.find(eta);
    if (it != cache.end()) return it->second;
    // The integrand has a kink at the critical angle: integrate the two sides.
    double mu_c = eta > 1.0 ? std::sqrt(std::max(0.0, 1.0 - 1.0 / (eta * eta))) : 0.0;
    auto simpson = [&](double a, double b, int power) {
        const int n = 4000;
        double h = (b - a) / n, sum = 0.0;
        for (int i = 0; i <= n; ++i) {
            double mu = a + i * h;
            double w = (i == 0 || i == n) ? 1.0 : (i % 2 ? 4.0 : 2.0);
            sum += w * fresnel_internal(mu, eta) * std::pow(mu, power);
        }
        return sum * h / 3.0;
    };
    FresnelMoments m;
    m.two_c1 = 2.0 * (simpson(0.0, mu_c, 1) + simpson(mu_c, 1.0, 1));
    m.three_c2 = 3.0 * (simpson(0.0, mu_c, 2) + simpson(mu_c, 1.0, 2));
    cache.emplace(eta, m);
    return m;
}

} // namespace sss::diffusion_detail
