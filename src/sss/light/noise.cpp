// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file noise.cpp
/// Improved gradient noise (Ken Perlin, SIGGRAPH 2002) in 1 to 4 dimensions:
/// quintic fade curve, gradients to the edge midpoints of a cube (3-D; the
/// other dimensions extend the construction: 1-D gradients are slopes in
/// [-2, 2], 2-D ones the 8 directions to a square's edges and corners, 4-D
/// ones the 32 directions to a hypercube's edge midpoints), and a 256-entry
/// permutation. Our permutation is not Perlin's published table but a fixed
/// shuffle from a seeded generator, so the pattern is the same on every
/// platform and run. noise3() (the baker's) and RSL's noise family (the
/// shading module) are both this one function.

#include <array>
#include <cmath>
#include <cstdint>

#include <glm/vec3.hpp>

#include "sss/light/lights.h"
#include "sss/util/error.h"
#include "sss/util/hash.h"

namespace sss {

namespace {

/// The permutation, stored twice so that p[p[x] + y] needs no wrapping.
using PermutationTable = std::array<uint8_t, 512>;

PermutationTable make_permutation() {
    std::array<uint8_t, 256> p{};
    for (int i = 0; i < 256; ++i) p[i] = static_cast<uint8_t>(i);
    // Fisher-Yates with our own generator: std::shuffle's result is
    // implementation-defined, and the pattern must not change with the library.
    uint64_t state = 0x73737320'6e6f6973ull; // "sss nois"
    for (int i = 255; i > 0; --i) {
        // Multiply-shift maps 32 random bits onto [0, i]; the tiny bias is harmless here.
        const uint64_t r = detail::splitmix64(state) >> 32;
        state += detail::kSplitMixIncrement;
        const int j = static_cast<int>((r * static_cast<uint64_t>(i + 1)) >> 32);
        std::swap(p[i], p[j]);
    }
    PermutationTable table{};
    for (int i = 0; i < 512; ++i) table[i] = p[i & 255];
    return table;
}

const PermutationTable& permutation() {
    static const PermutationTable table = make_permutation();
    return table;
}

/// 3-D gradients: the 12 cube-edge directions, 4 repeated to make 16 (Perlin
/// 2002).
constexpr int kGradients3[16][3] = {{1, 1, 0}, {-1, 1, 0}, {1, -1, 0}, {-1, -1, 0},
                                    {1, 0, 1}, {-1, 0, 1}, {1, 0, -1}, {-1, 0, -1},
                                    {0, 1, 1}, {0, -1, 1}, {0, 1, -1}, {0, -1, -1},
                                    {1, 1, 0}, {0, -1, 1}, {-1, 1, 0}, {0, -1, -1}};

constexpr int kGradients2[8][2] = {{1, 1}, {-1, 1}, {1, -1}, {-1, -1},
                                   {1, 0}, {-1, 0}, {0, 1},  {0, -1}};

/// 4-D: the 32 vectors with one zero and three +-1 components.
constexpr std::array<std::array<int, 4>, 32> make_gradients4() {
    std::array<std::array<int, 4>, 32> g{};
    int n = 0;
    for (int zero = 0; zero < 4; ++zero)
        for (int signs = 0; signs < 8; ++signs) {
            int bit = 0;
            for (int d = 0; d < 4; ++d)
                g[n][d] = d == zero ? 0 : ((signs >> bit++) & 1 ? -1 : 1);
            ++n;
        }
    return g;
}
constexpr auto kGradients4 = make_gradients4();

template <int D>
double grad_dot(int hash, const double* x) {
    if constexpr (D == 1) {
        // Slopes +-0.25 .. +-2 so that the 1-D noise reaches +-1 at most.
        const double g = 0.25 * ((hash & 7) + 1);
        return (hash & 8 ? -g : g) * x[0];
    } else if constexpr (D == 2) {
        const int* g = kGradients2[hash & 7];
        return g[0] * x[0] + g[1] * x[1];
    } else if constexpr (D == 3) {
        const int* g = kGradients3[hash & 15];
        return g[0] * x[0] + g[1] * x[1] + g[2] * x[2];
    } else {
        const auto& g = kGradients4[hash & 31];
        return g[0] * x[0] + g[1] * x[1] + g[2] * x[2] + g[3] * x[3];
    }
}

/// 6t^5 - 15t^4 + 10t^3: zero first and second derivatives at 0 and 1.
double fade(double t) {
    return t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
}

double lerp(double t, double a, double b) {
    return a + t * (b - a);
}

/// The lattice cells either side of x along one axis, as permutation indices
/// in [0, 255], and the offset of x inside its cell. `period` < 1: the
/// lattice repeats every 256 cells (the permutation's own period), as in
/// Perlin's; otherwise every `period` cells. `shift` decorrelates the
/// components of vector noise (an integer lattice shift keeps the value 0.5
/// on lattice points and keeps the period).
struct Axis {
    int i0 = 0, i1 = 0;
    double frac = 0.0;
};

Axis axis(double x, double period, int shift) {
    Axis a;
    const double f = std::floor(x);
    a.frac = x - f;
    // Reducing in double keeps huge coordinates from overflowing an int.
    // 256 divides exactly (the classic formula); other periods
    // use fmod, which is exact where f - n*floor(f/n) may round out of
    // [0, n) for huge f.
    const double n = period >= 1.0 ? period : 256.0;
    double wrapped;
    if (n == 256.0) {
        wrapped = f - n * std::floor(f / n);
    } else {
        wrapped = std::fmod(f, n);
        if (wrapped < 0.0) wrapped += n;
    }
    const auto c0 = static_cast<int64_t>(wrapped);
    const auto p = static_cast<int64_t>(n);
    const int64_t c1 = c0 + 1 == p ? 0 : c0 + 1;
    a.i0 = static_cast<int>((c0 + shift) & 255);
    a.i1 = static_cast<int>((c1 + shift) & 255);
    return a;
}

/// Signed gradient noise, roughly in [-1, 1], 0 on every lattice point.
/// periods[d] < 1: not periodic along d.
template <int D>
double gradient_noise(const double* x, const double* periods, int component) {
    // Per-component lattice shifts (arbitrary, distinct mod 256).
    static constexpr int kShift[3][4] = {
        {0, 0, 0, 0}, {97, 13, 181, 59}, {211, 149, 37, 113}};
    const PermutationTable& p = permutation();
    Axis ax[D];
    double u[D];
    for (int d = 0; d < D; ++d) {
        ax[d] = axis(x[d], periods ? periods[d] : 0.0, kShift[component][d]);
        u[d] = fade(ax[d].frac);
    }
    constexpr int kCorners = 1 << D;
    double v[kCorners];
    for (int c = 0; c < kCorners; ++c) {
        int h = 0;
        double offset[D];
        for (int d = 0; d < D; ++d) {
            const bool upper = (c >> d) & 1;
            h = p[h + (upper ? ax[d].i1 : ax[d].i0)];
            offset[d] = upper ? ax[d].frac - 1.0 : ax[d].frac;
        }
        v[c] = grad_dot<D>(h, offset);
    }
    // Interpolate x first, then y, z, w: Perlin's order.
    for (int d = 0, n = kCorners; d < D; ++d, n /= 2)
        for (int c = 0; c < n / 2; ++c) v[c] = lerp(u[d], v[2 * c], v[2 * c + 1]);
    return v[0];
}

} // namespace

double gradient_noise(int dims, const double* x, const double* periods, int component) {
    switch (dims) {
    case 1:
        return gradient_noise<1>(x, periods, component);
    case 2:
        return gradient_noise<2>(x, periods, component);
    case 3:
        return gradient_noise<3>(x, periods, component);
    case 4:
        return gradient_noise<4>(x, periods, component);
    }
    throw ValueError("gradient_noise: " + std::to_string(dims) + " dimensions (1 to 4)");
}

double noise3(const glm::dvec3& p) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
        throw ValueError("noise: the point is not finite");
    // RenderMan's noise() is centred on 0.5; improved noise can slightly
    // exceed [-1, 1], hence the clamp.
    const double x[3] = {p.x, p.y, p.z};
    const double n = 0.5 + 0.5 * gradient_noise(3, x, nullptr, 0);
    return n < 0.0 ? 0.0 : (n > 1.0 ? 1.0 : n);
}

} // namespace sss
