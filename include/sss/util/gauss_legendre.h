// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file gauss_legendre.h
/// Gauss-Legendre quadrature rules, shared by the stages that integrate
/// smooth functions (reference areas of quadrics, slab transport).

#include <cmath>
#include <cstddef>
#include <vector>

#include "sss/util/math.h"

namespace sss {

/// n-point Gauss-Legendre nodes and weights on [-1, 1] (Newton on P_n).
struct GaussRule {
    std::vector<double> x;
    std::vector<double> w;
    explicit GaussRule(int n) : x(std::size_t(n)), w(std::size_t(n)) {
        for (int i = 0; i < (n + 1) / 2; ++i) {
            double z = std::cos(kPi * (i + 0.75) / (n + 0.5));
            double dp = 1.0;
            for (int iter = 0; iter < 100; ++iter) {
                double p0 = 1.0;
                double p1 = z;
                for (int k = 2; k <= n; ++k) {
                    const double p2 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p0) / k;
                    p0 = p1;
                    p1 = p2;
                }
                dp = n * (z * p1 - p0) / (z * z - 1.0);
                const double step = p1 / dp;
                z -= step;
                if (std::abs(step) < 1e-16) break;
            }
            x[std::size_t(i)] = -z;
            x[std::size_t(n - 1 - i)] = z;
            w[std::size_t(i)] = w[std::size_t(n - 1 - i)] =
                2.0 / ((1.0 - z * z) * dp * dp);
        }
    }
    /// The integral of f over [a, b].
    template <class F>
    double integrate(const F& f, double a, double b) const {
        const double half = 0.5 * (b - a);
        const double mid = 0.5 * (a + b);
        double sum = 0.0;
        for (std::size_t k = 0; k < x.size(); ++k) sum += w[k] * f(mid + half * x[k]);
        return sum * half;
    }
};

} // namespace sss
