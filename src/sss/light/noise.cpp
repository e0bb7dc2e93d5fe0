/// \file noise.cpp
/// noise3(): Ken Perlin's "improved noise" (SIGGRAPH 2002): quintic fade
/// curve, gradients from the 12 directions to the edge midpoints of a cube,
/// and a 256-entry permutation. Our permutation is not Perlin's published
/// table but a fixed shuffle from a seeded generator, so the pattern is the
/// same on every platform and run.

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
    return noise_permutation();
}

/// Gradients: the 12 cube-edge directions, 4 of them repeated to make 16 so
/// that a hash selects one with a mask (Perlin 2002).
constexpr int kGradients[16][3] = {{1, 1, 0}, {-1, 1, 0}, {1, -1, 0}, {-1, -1, 0},
                                   {1, 0, 1}, {-1, 0, 1}, {1, 0, -1}, {-1, 0, -1},
                                   {0, 1, 1}, {0, -1, 1}, {0, 1, -1}, {0, -1, -1},
                                   {1, 1, 0}, {0, -1, 1}, {-1, 1, 0}, {0, -1, -1}};

double grad_dot(int hash, double x, double y, double z) {
    const int* g = kGradients[hash & 15];
    return g[0] * x + g[1] * y + g[2] * z;
}

/// 6t^5 - 15t^4 + 10t^3: zero first and second derivatives at 0 and 1.
double fade(double t) {
    return t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
}

double lerp(double t, double a, double b) {
    return a + t * (b - a);
}

/// The lattice cell of x, reduced mod 256, and the offset inside it.
/// Reducing in double keeps huge coordinates from overflowing an int.
int cell(double x, double* frac) {
    const double f = std::floor(x);
    *frac = x - f;
    const double wrapped = f - 256.0 * std::floor(f / 256.0);
    return static_cast<int>(wrapped) & 255;
}

/// Signed improved noise, roughly in [-1, 1]; 0 on every lattice point.
double perlin(double x, double y, double z) {
    const PermutationTable& p = permutation();
    double fx, fy, fz;
    const int X = cell(x, &fx), Y = cell(y, &fy), Z = cell(z, &fz);
    const double u = fade(fx), v = fade(fy), w = fade(fz);

    const int a = p[X] + Y, aa = p[a] + Z, ab = p[a + 1] + Z;
    const int b = p[X + 1] + Y, ba = p[b] + Z, bb = p[b + 1] + Z;

    const double x1 = fx - 1.0, y1 = fy - 1.0, z1 = fz - 1.0;
    const double near_z =
        lerp(v, lerp(u, grad_dot(p[aa], fx, fy, fz), grad_dot(p[ba], x1, fy, fz)),
             lerp(u, grad_dot(p[ab], fx, y1, fz), grad_dot(p[bb], x1, y1, fz)));
    const double far_z =
        lerp(v, lerp(u, grad_dot(p[aa + 1], fx, fy, z1), grad_dot(p[ba + 1], x1, fy, z1)),
             lerp(u, grad_dot(p[ab + 1], fx, y1, z1), grad_dot(p[bb + 1], x1, y1, z1)));
    return lerp(w, near_z, far_z);
}

} // namespace

const std::array<uint8_t, 512>& noise_permutation() {
    static const PermutationTable table = make_permutation();
    return table;
}

double noise3(const glm::dvec3& p) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
        throw ValueError("noise: the point is not finite");
    // RenderMan's noise() is centred on 0.5; improved noise can slightly
    // exceed [-1, 1], hence the clamp.
    const double n = 0.5 + 0.5 * perlin(p.x, p.y, p.z);
    return n < 0.0 ? 0.0 : (n > 1.0 ? 1.0 : n);
}

} // namespace sss
