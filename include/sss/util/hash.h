// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
// Small deterministic hashes shared by the library (sample patterns, noise
// permutations, jitter, temporary file names).

#include <cstddef>
#include <cstdint>
#include <cstring>

namespace sss::detail {

/// The increment of the SplitMix64 sequence (2^64 / golden ratio).
inline constexpr uint64_t kSplitMixIncrement = 0x9E3779B97F4A7C15ull;

/// SplitMix64 (Steele, Lea and Flood 2014): a well-mixed 64-bit hash of x;
/// splitmix64(s), splitmix64(s + kSplitMixIncrement), ... is the SplitMix64
/// random sequence.
inline uint64_t splitmix64(uint64_t x) {
    uint64_t z = x + kSplitMixIncrement;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/// A 64-bit hash of `size` bytes, continuing from `seed`: 8 bytes at a time
/// through SplitMix64's mixer (fast, not cryptographic: it tells apart
/// inputs that differ by accident, as the fingerprints of a split job's parts).
inline uint64_t hash_bytes(const void* bytes, std::size_t size, uint64_t seed = 0) {
    const unsigned char* p = static_cast<const unsigned char*>(bytes);
    uint64_t h = splitmix64(seed ^ size);
    std::size_t i = 0;
    for (; i + 8 <= size; i += 8) {
        uint64_t w;
        std::memcpy(&w, p + i, 8);
        h = splitmix64(h ^ w);
    }
    uint64_t tail = 0;
    std::memcpy(&tail, p + i, size - i);
    return splitmix64(h ^ tail ^ (uint64_t(size - i) << 56));
}

/// A 64-bit hash mapped to a double in [0, 1) (its top 53 bits).
inline double unit_double(uint64_t h) {
    return static_cast<double>(h >> 11) * 0x1.0p-53;
}

} // namespace sss::detail
