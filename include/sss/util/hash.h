#pragma once
// Small deterministic hashes shared by the library (sample patterns, noise
// permutations, jitter, temporary file names).

#include <cstdint>

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

/// A 64-bit hash mapped to a double in [0, 1) (its top 53 bits).
inline double unit_double(uint64_t h) {
    return static_cast<double>(h >> 11) * 0x1.0p-53;
}

} // namespace sss::detail
