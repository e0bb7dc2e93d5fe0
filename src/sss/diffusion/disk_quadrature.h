// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file disk_quadrature.h
/// Close sources as disks: when a source is integrated over its disk rather
/// than taken as a point, the quadrature rule over a disk and the disk's
/// tangent frame. Shared by the hierarchical kernels and the exact sum.

#include <cmath>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "sss/util/math.h"

namespace sss::diffusion_detail {

// A source disk is integrated (rather than taken as a point) when its radius
// exceeds kNearKappa times the distance softened by the profile's core length.
// 0.1 keeps a uniformly lit plane within 1 % of albedo x E from well-sampled
// down to spacings of 9 z_r (measured; docs/ptfilter.md).
constexpr double kNearKappa2 = 0.1;

// The sampled profiles (pbd, mc: 1/r at the source, no core length) would
// send every close pair to the quadrature (twice the classic's time at 1M
// points). A disk whose radius^2 is at most this fraction of its squared
// distance is taken instead as its mean to second order,
// F + rho^2/2 (F' + |w_t|^2 F'') (w_t: the offset within the disk's plane):
// 1.3x the classic's time, 0.26 % RMS from the exact sum (0.15 % at 0.25,
// but 1.5x the time; docs/ptfilter.md).
constexpr float kTaylorDisk2 = 0.5f;

// The exact sum takes a source disk of a sampled profile as a point
// only when its radius^2 is below this fraction of its squared distance.
constexpr double kExactDisk2 = 1e-3;

// Quadrature over a disk: 4 Gauss-Legendre nodes in t = (rho'/rho)^2 (uniform
// in area) times 8 angles.
constexpr int kQuadRadial = 4, kQuadAngular = 8;
struct DiskRule {
    double radius[kQuadRadial]; // sqrt(t)
    double weight[kQuadRadial]; // sums to 1 (angular average folded in below)
    double cs[kQuadAngular], sn[kQuadAngular];
    DiskRule() {
        const double x[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563,
                             0.8611363115940526};
        const double w[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461,
                             0.3478548451374538};
        for (int i = 0; i < kQuadRadial; ++i) {
            radius[i] = std::sqrt(0.5 * (x[i] + 1.0));
            weight[i] = 0.5 * w[i] / kQuadAngular;
        }
        for (int k = 0; k < kQuadAngular; ++k) {
            double a = 2.0 * kPi * (k + 0.5) / kQuadAngular;
            cs[k] = std::cos(a);
            sn[k] = std::sin(a);
        }
    }
};
inline const DiskRule& disk_rule() {
    static const DiskRule rule;
    return rule;
}

// Orthonormal tangent frame of a source disk; for a zero normal, the disk
// faces the receiver.
inline void disk_frame(glm::dvec3 n, glm::dvec3 to_receiver, glm::dvec3& u,
                       glm::dvec3& v) {
    double len = glm::length(n);
    if (len < 1e-12) {
        n = to_receiver;
        len = glm::length(n);
        if (len < 1e-300) n = {0, 0, 1}, len = 1;
    }
    n /= len;
    glm::dvec3 a = std::abs(n.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
    u = glm::normalize(glm::cross(n, a));
    v = glm::cross(n, u);
}

// Calls f(offset, weight) for each quadrature point of a disk of radius rho.
template <class F>
void for_disk_points(double rho, const glm::dvec3& u, const glm::dvec3& v, F&& f) {
    const DiskRule& rule = disk_rule();
    for (int i = 0; i < kQuadRadial; ++i)
        for (int k = 0; k < kQuadAngular; ++k)
            f(rho * rule.radius[i] * (rule.cs[k] * u + rule.sn[k] * v), rule.weight[i]);
}

} // namespace sss::diffusion_detail
