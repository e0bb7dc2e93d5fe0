// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#include "sss/diffusion/slab_transport.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "fresnel.h"
#include "sss/util/error.h"
#include "sss/util/gauss_legendre.h"

namespace sss {

using diffusion_detail::fresnel_internal;

namespace {

// The nodes and weights of `rule` mapped to [a, b], appended.
void gauss_legendre(const GaussRule& rule, double a, double b, std::vector<double>& x,
                    std::vector<double>& w) {
    for (std::size_t k = 0; k < rule.x.size(); ++k) {
        x.push_back(a + 0.5 * (b - a) * (rule.x[k] + 1.0));
        w.push_back(0.5 * (b - a) * rule.w[k]);
    }
}

// Solves a x = b in place (Gaussian elimination, partial pivoting); a is m x m
// row-major.
void solve_dense(std::vector<double>& a, std::vector<double>& b, std::size_t m) {
    for (std::size_t c = 0; c < m; ++c) {
        std::size_t p = c;
        for (std::size_t r = c + 1; r < m; ++r)
            if (std::abs(a[r * m + c]) > std::abs(a[p * m + c])) p = r;
        if (p != c) {
            for (std::size_t k = 0; k < m; ++k) std::swap(a[c * m + k], a[p * m + k]);
            std::swap(b[c], b[p]);
        }
        const double inv = 1.0 / a[c * m + c];
        for (std::size_t r = c + 1; r < m; ++r) {
            const double f = a[r * m + c] * inv;
            if (f == 0.0) continue;
            for (std::size_t k = c; k < m; ++k) a[r * m + k] -= f * a[c * m + k];
            b[r] -= f * b[c];
        }
    }
    for (std::size_t c = m; c-- > 0;) {
        double s = b[c];
        for (std::size_t k = c + 1; k < m; ++k) s -= a[c * m + k] * b[k];
        b[c] = s / a[c * m + c];
    }
}

// One direction cosine of the quadrature with what the slab does to it.
struct Direction {
    double mu = 0, weight = 0;
    double fresnel = 0; // reflectance of a face from inside
    double through = 0; // exp(-d / mu): one crossing of the slab
    double bounce = 0;  // 1 / (1 - R^2 exp(-2 d / mu)): every reflection summed
};

std::vector<Direction> directions(double eta, double d) {
    static const GaussRule rule(24);
    std::vector<double> x, w;
    const double mu_c = eta > 1.0 ? std::sqrt(1.0 - 1.0 / (eta * eta)) : 0.0;
    if (mu_c > 0.0) gauss_legendre(rule, 0.0, mu_c, x, w);
    gauss_legendre(rule, mu_c, 1.0, x, w);
    std::vector<Direction> dirs(x.size());
    for (std::size_t k = 0; k < x.size(); ++k) {
        Direction& q = dirs[k];
        q.mu = x[k];
        q.weight = w[k];
        q.fresnel = fresnel_internal(q.mu, eta);
        q.through = std::exp(-d / q.mu);
        q.bounce = 1.0 / (1.0 - q.fresnel * q.fresnel * q.through * q.through);
    }
    return dirs;
}

// The refracted cosines of the entering light and their shares of its flux:
// one straight beam, or cosine-weighted light outside times the Fresnel
// transmission.
std::vector<std::pair<double, double>> entering(double eta, bool diffuse) {
    if (!diffuse) return {{1.0, 1.0}};
    static const GaussRule rule(32);
    std::vector<double> x, w;
    gauss_legendre(rule, 0.0, 1.0, x, w);
    std::vector<std::pair<double, double>> in;
    double total = 0;
    for (std::size_t k = 0; k < x.size(); ++k) {
        const double sin_in = std::sqrt(1.0 - x[k] * x[k]) / eta;
        const double mu = std::sqrt(1.0 - sin_in * sin_in);
        const double share = w[k] * 2.0 * x[k] * (1.0 - fresnel_internal(mu, eta));
        in.emplace_back(mu, share);
        total += share;
    }
    for (auto& [mu, share] : in) share /= total;
    return in;
}

} // namespace

SlabLight slab_transport(double alpha, double eta, double thickness, bool diffuse) {
    if (!(alpha >= 0.0 && alpha < 1.0) || !(eta >= 1.0 && eta < 10.0) ||
        !(thickness > 0.0 && thickness < 1e4))
        throw ValueError("slab transport: albedo in [0, 1), ior >= 1 and a positive "
                         "thickness needed");
    const double d = thickness;
    const std::size_t m = std::size_t(std::clamp(std::ceil(d / 0.15), 8.0, 240.0));
    const double dz = d / double(m);
    const std::vector<Direction> dirs = directions(eta, d);
    const std::size_t nq = dirs.size();
    // top[i * nq + q] = integral over cell i of exp(-z / mu_q); the bottom
    // face's is the same cell counted from the other end.
    std::vector<double> top(m * nq);
    for (std::size_t q = 0; q < nq; ++q) {
        const double mu = dirs[q].mu, cell = -mu * std::expm1(-dz / mu);
        for (std::size_t i = 0; i < m; ++i)
            top[i * nq + q] = cell * std::exp(-double(i) * dz / mu);
    }
    const auto bottom = [&](std::size_t i, std::size_t q) {
        return top[(m - 1 - i) * nq + q];
    };
    // The kernel: collisions in cell i per emission in cell j, averaged over
    // cell i. The direct part depends on |i - j| only.
    std::vector<double> direct(m, 0.0);
    for (const Direction& q : dirs) {
        const double e = -std::expm1(-dz / q.mu);
        direct[0] += q.weight * (dz - q.mu * e);
        for (std::size_t k = 1; k < m; ++k)
            direct[k] +=
                0.5 * q.weight * q.mu * e * e * std::exp(-double(k - 1) * dz / q.mu);
    }
    std::vector<double> a(m * m);
    for (std::size_t i = 0; i < m; ++i)
        for (std::size_t j = 0; j < m; ++j) {
            double k = direct[i > j ? i - j : j - i];
            for (std::size_t q = 0; q < nq; ++q) {
                const Direction& r = dirs[q];
                const double c = 0.5 * r.weight * r.bounce / r.mu;
                const double ti = top[i * nq + q], tj = top[j * nq + q];
                const double bi = bottom(i, q), bj = bottom(j, q);
                k += c * r.fresnel *
                     (bi * bj + ti * tj + r.fresnel * r.through * (ti * bj + bi * tj));
            }
            a[i * m + j] = (i == j ? 1.0 : 0.0) - alpha * k / dz;
        }
    // First collisions of the entering light (cell averages), the straight
    // crossings reflected at the faces included.
    std::vector<double> f(m, 0.0);
    for (const auto& [mu, share] : entering(eta, diffuse)) {
        const double r = fresnel_internal(mu, eta), through = std::exp(-d / mu);
        const double cell = -mu * std::expm1(-dz / mu);
        const double scale = share / (mu * dz * (1.0 - r * r * through * through));
        for (std::size_t i = 0; i < m; ++i) {
            const double down = cell * std::exp(-double(i) * dz / mu);
            const double up = cell * std::exp(-double(m - 1 - i) * dz / mu);
            f[i] += scale * (down + r * through * up);
        }
    }
    solve_dense(a, f, m);
    SlabLight out;
    for (std::size_t i = 0; i < m; ++i) {
        double down = 0, up = 0;
        for (std::size_t q = 0; q < nq; ++q) {
            const Direction& r = dirs[q];
            const double c = 0.5 * r.weight * (1.0 - r.fresnel) * r.bounce;
            const double ti = top[i * nq + q], bi = bottom(i, q);
            down += c * (bi + r.fresnel * r.through * ti);
            up += c * (ti + r.fresnel * r.through * bi);
        }
        out.transmittance += alpha * f[i] * down;
        out.reflectance += alpha * f[i] * up;
    }
    return out;
}

double first_collision_share(double eta, double depth, bool diffuse) {
    if (!(eta >= 1.0 && eta < 10.0))
        throw ValueError("first collisions: ior >= 1 needed");
    if (!(depth > 0.0)) return 0.0;
    double share = 0;
    for (const auto& [mu, w] : entering(eta, diffuse))
        share -= w * std::expm1(-depth / mu);
    return share;
}

double diffuse_reflectance_ratio(double alpha, double eta) {
    const double a = std::min(alpha, 1.0 - 1e-9);
    return slab_transport(a, eta, 30.0, true).reflectance /
           slab_transport(a, eta, 30.0, false).reflectance;
}

} // namespace sss
