// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file rsl_noise.cpp
/// RSL's noise(), pnoise() and cellnoise() in 1 to 4 dimensions (rsl_math.h).
///
/// noise is the light module's improved gradient noise (sss::gradient_noise,
/// Ken Perlin's, SIGGRAPH 2002) scaled to 0.5*(1+n): the 3-D form is exactly
/// sss::noise3, the baker's, so existing bakes keep their patterns.

#include <array>
#include <cmath>
#include <cstdint>
#include <initializer_list>

#include "rsl_math.h"
#include "sss/light/lights.h"
#include "sss/util/hash.h"

namespace sss::detail {

namespace {

/// 0.5*(1+n) clamped to [0,1] (improved noise can slightly exceed [-1,1]).
/// A non-finite coordinate gives 0.5: a shader's NaN must not stop the
/// render, and the lattice arithmetic is undefined on it.
template <int D>
float noise01(const double* x, const double* periods, int component) {
    for (int d = 0; d < D; ++d)
        if (!std::isfinite(x[d])) return 0.5f;
    // 4-D gradient noise spreads wider (about 1.1x the 3-D one's standard
    // deviation, and past +-1 now and then): 0.9 matches the 3-D spread.
    constexpr double kScale = D == 4 ? 0.9 : 1.0;
    const double n = 0.5 + 0.5 * kScale * gradient_noise(D, x, periods, component);
    return static_cast<float>(n < 0.0 ? 0.0 : (n > 1.0 ? 1.0 : n));
}

template <int D>
glm::vec3 vnoise01(const double* x, const double* periods) {
    return {noise01<D>(x, periods, 0), noise01<D>(x, periods, 1),
            noise01<D>(x, periods, 2)};
}

/// pnoise periods: rounded to integers; < 1 means not periodic.
/// Periods of 2^30 and more (beyond float's integers anyway) are treated as
/// not periodic, which keeps the cell arithmetic in range.
double period_of(float p) {
    const double r = std::isfinite(p) ? std::round(static_cast<double>(p)) : 0.0;
    return r < 0x1.0p30 ? r : 0.0;
}

/// The integer cell of x; non-finite coordinates fall in cell 0, huge ones
/// saturate.
int64_t cell_index(float x) {
    if (!std::isfinite(x)) return 0;
    const double f = std::floor(static_cast<double>(x));
    if (f >= 9.0e18) return INT64_MAX;
    if (f <= -9.0e18) return INT64_MIN;
    return static_cast<int64_t>(f);
}

/// A uniform float in [0, 1) hashed from the cells and a component seed.
float cell_hash(std::initializer_list<float> coords, uint64_t component) {
    uint64_t h = splitmix64(0x63656c6c'6e6f6973ull + component); // "cellnois"
    for (float x : coords) h = splitmix64(h ^ static_cast<uint64_t>(cell_index(x)));
    // The top 24 bits: exactly representable, so the float stays below 1.
    return static_cast<float>(h >> 40) * 0x1.0p-24f;
}

glm::vec3 vcell_hash(std::initializer_list<float> coords) {
    return {cell_hash(coords, 0), cell_hash(coords, 1), cell_hash(coords, 2)};
}

} // namespace

float rsl_noise(float x) {
    const double c[1] = {x};
    return noise01<1>(c, nullptr, 0);
}
float rsl_noise(float x, float y) {
    const double c[2] = {x, y};
    return noise01<2>(c, nullptr, 0);
}
float rsl_noise(const glm::vec3& p) {
    const double c[3] = {p.x, p.y, p.z};
    return noise01<3>(c, nullptr, 0);
}
float rsl_noise(const glm::vec3& p, float t) {
    const double c[4] = {p.x, p.y, p.z, t};
    return noise01<4>(c, nullptr, 0);
}

glm::vec3 rsl_vnoise(float x) {
    const double c[1] = {x};
    return vnoise01<1>(c, nullptr);
}
glm::vec3 rsl_vnoise(float x, float y) {
    const double c[2] = {x, y};
    return vnoise01<2>(c, nullptr);
}
glm::vec3 rsl_vnoise(const glm::vec3& p) {
    const double c[3] = {p.x, p.y, p.z};
    return vnoise01<3>(c, nullptr);
}
glm::vec3 rsl_vnoise(const glm::vec3& p, float t) {
    const double c[4] = {p.x, p.y, p.z, t};
    return vnoise01<4>(c, nullptr);
}

float rsl_pnoise(float x, float px) {
    const double c[1] = {x}, per[1] = {period_of(px)};
    return noise01<1>(c, per, 0);
}
float rsl_pnoise(float x, float y, float px, float py) {
    const double c[2] = {x, y}, per[2] = {period_of(px), period_of(py)};
    return noise01<2>(c, per, 0);
}
float rsl_pnoise(const glm::vec3& p, const glm::vec3& period) {
    const double c[3] = {p.x, p.y, p.z};
    const double per[3] = {period_of(period.x), period_of(period.y), period_of(period.z)};
    return noise01<3>(c, per, 0);
}
float rsl_pnoise(const glm::vec3& p, float t, const glm::vec3& period, float pt) {
    const double c[4] = {p.x, p.y, p.z, t};
    const double per[4] = {period_of(period.x), period_of(period.y), period_of(period.z),
                           period_of(pt)};
    return noise01<4>(c, per, 0);
}

glm::vec3 rsl_vpnoise(float x, float px) {
    const double c[1] = {x}, per[1] = {period_of(px)};
    return vnoise01<1>(c, per);
}
glm::vec3 rsl_vpnoise(float x, float y, float px, float py) {
    const double c[2] = {x, y}, per[2] = {period_of(px), period_of(py)};
    return vnoise01<2>(c, per);
}
glm::vec3 rsl_vpnoise(const glm::vec3& p, const glm::vec3& period) {
    const double c[3] = {p.x, p.y, p.z};
    const double per[3] = {period_of(period.x), period_of(period.y), period_of(period.z)};
    return vnoise01<3>(c, per);
}
glm::vec3 rsl_vpnoise(const glm::vec3& p, float t, const glm::vec3& period, float pt) {
    const double c[4] = {p.x, p.y, p.z, t};
    const double per[4] = {period_of(period.x), period_of(period.y), period_of(period.z),
                           period_of(pt)};
    return vnoise01<4>(c, per);
}

// Each dimension count hashes its own number of coordinates, so
// cellnoise(x) and cellnoise(x, 0) are independent.
float rsl_cellnoise(float x) {
    return cell_hash({x}, 0);
}
float rsl_cellnoise(float x, float y) {
    return cell_hash({x, y}, 0);
}
float rsl_cellnoise(const glm::vec3& p) {
    return cell_hash({p.x, p.y, p.z}, 0);
}
float rsl_cellnoise(const glm::vec3& p, float t) {
    return cell_hash({p.x, p.y, p.z, t}, 0);
}
glm::vec3 rsl_vcellnoise(float x) {
    return vcell_hash({x});
}
glm::vec3 rsl_vcellnoise(float x, float y) {
    return vcell_hash({x, y});
}
glm::vec3 rsl_vcellnoise(const glm::vec3& p) {
    return vcell_hash({p.x, p.y, p.z});
}
glm::vec3 rsl_vcellnoise(const glm::vec3& p, float t) {
    return vcell_hash({p.x, p.y, p.z, t});
}

} // namespace sss::detail
