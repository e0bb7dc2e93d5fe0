// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file random.h
/// The random numbers of the walks: a fast generator seeded per batch, and
/// uniform directions.

#include <cmath>
#include <cstdint>

#include <glm/vec3.hpp>

#include "sss/util/hash.h"

namespace sss {

/// Uniform doubles in [0, 1): xoshiro256** (Blackman and Vigna), seeded per
/// batch through splitmix64; faster than the Mersenne twister, and a walk
/// draws three to five numbers per collision.
class Uniform {
public:
    explicit Uniform(uint64_t seed) {
        for (uint64_t& w : m_s) w = seed = detail::splitmix64(seed);
    }
    double operator()() { return double(next() >> 11) * 0x1.0p-53; }

private:
    uint64_t m_s[4];
    static uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
    uint64_t next() {
        const uint64_t result = rotl(m_s[1] * 5, 7) * 9, t = m_s[1] << 17;
        m_s[2] ^= m_s[0];
        m_s[3] ^= m_s[1];
        m_s[1] ^= m_s[2];
        m_s[0] ^= m_s[3];
        m_s[2] ^= t;
        m_s[3] = rotl(m_s[3], 45);
        return result;
    }
};

/// The seed of batch `batch` of a walk seeded with `seed`.
inline uint64_t batch_seed(uint64_t seed, uint64_t batch) {
    return detail::splitmix64(seed ^ detail::splitmix64(batch + 1));
}

/// A direction uniform on the unit sphere. Marsaglia (1972): a point in the
/// unit disk maps to the sphere without trigonometric functions.
inline glm::dvec3 uniform_direction(Uniform& u) {
    for (;;) {
        const double a = 2.0 * u() - 1.0, b = 2.0 * u() - 1.0, s = a * a + b * b;
        if (s >= 1.0) continue;
        const double f = 2.0 * std::sqrt(1.0 - s);
        return {a * f, b * f, 1.0 - 2.0 * s};
    }
}

} // namespace sss
