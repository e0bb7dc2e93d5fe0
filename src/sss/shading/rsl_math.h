// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
// Internal to the shading module: the pure functions behind RSL built-ins
// that the engine calls per point (noise family, colour spaces, splines,
// string formatting and matching). No state besides caches; every function
// is thread-safe.

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include <glm/vec3.hpp>

#include "sss/rsl/program.h"

namespace sss::detail {

// --- Noise (rsl_noise.cpp) -------------------------------------------------

/// RenderMan noise: smooth, in [0,1], exactly 0.5 at integer lattice points,
/// clustered around 0.5 (shading.md 5.1): improved Perlin gradient noise n
/// scaled as 0.5*(1+n). The 3-D form equals sss::noise3 (module light)
/// exactly, so existing bakes keep their patterns.
float rsl_noise(float x);
float rsl_noise(float x, float y);
float rsl_noise(const glm::vec3& p);
float rsl_noise(const glm::vec3& p, float t);
/// Vector-valued noise: three decorrelated components (a different offset
/// per component), same range.
glm::vec3 rsl_vnoise(float x);
glm::vec3 rsl_vnoise(float x, float y);
glm::vec3 rsl_vnoise(const glm::vec3& p);
glm::vec3 rsl_vnoise(const glm::vec3& p, float t);
/// Periodic noise: periods are rounded to integers; a period < 1 means not
/// periodic in that dimension.
float rsl_pnoise(float x, float px);
float rsl_pnoise(float x, float y, float px, float py);
float rsl_pnoise(const glm::vec3& p, const glm::vec3& period);
float rsl_pnoise(const glm::vec3& p, float t, const glm::vec3& period, float pt);
glm::vec3 rsl_vpnoise(float x, float px);
glm::vec3 rsl_vpnoise(float x, float y, float px, float py);
glm::vec3 rsl_vpnoise(const glm::vec3& p, const glm::vec3& period);
glm::vec3 rsl_vpnoise(const glm::vec3& p, float t, const glm::vec3& period, float pt);
/// Cell noise: uniform in [0,1), constant on each integer cell (floor of the
/// coordinates), hashed deterministically.
float rsl_cellnoise(float x);
float rsl_cellnoise(float x, float y);
float rsl_cellnoise(const glm::vec3& p);
float rsl_cellnoise(const glm::vec3& p, float t);
glm::vec3 rsl_vcellnoise(float x);
glm::vec3 rsl_vcellnoise(float x, float y);
glm::vec3 rsl_vcellnoise(const glm::vec3& p);
glm::vec3 rsl_vcellnoise(const glm::vec3& p, float t);

// --- Colour spaces (rsl_math.cpp) -----------------------------------------

/// Colour spaces of RSL: "rgb", "hsv", "hsl", "xyz"/"XYZ" (CIE XYZ, Rec.709
/// primaries, D65), "yiq"/"YIQ"; false for an unknown name.
bool rsl_color_to_rgb(std::string_view space, const glm::vec3& c, glm::vec3& rgb);
bool rsl_rgb_to_color(std::string_view space, const glm::vec3& rgb, glm::vec3& c);

// --- Splines (rsl_math.cpp) ------------------------------------------------

/// spline(basis, t, v0..vn-1): bases "catmull-rom" (default, also
/// "catmullrom"), "b-spline" ("bspline"), "bezier", "hermite", "power",
/// "linear" (piecewise linear through the interior knots, like PRMan).
/// `values`: `count` values of `components` floats each, consecutive. t is
/// clamped to [0,1]. Returns false for an unknown basis or too few values
/// (catmull-rom, b-spline: >= 4; bezier: 4+3k; hermite: 4+2k; power: 4k;
/// linear: >= 4, the first and last being unused like catmull-rom's). An
/// empty basis name is catmull-rom.
bool rsl_spline(std::string_view basis, float t, const float* values, int count,
                int components, float* out);

// --- Strings (rsl_string.cpp) ----------------------------------------------

/// One argument of format()/printf(): `numbers` holds
/// shading_type_floats(type) floats; `string` is set for ShadingType::String.
struct RslFormatArg {
    ShadingType type = ShadingType::Float;
    const float* numbers = nullptr;
    const std::string* string = nullptr;
};
/// format()/printf(): %f %e %g (with flags, width, precision), %d / %i
/// (the float rounded toward zero, printed as an integer), %s, %c (color
/// "r g b"), %p (point/vector/normal "x y z"), %m (matrix, 16 numbers
/// row by row); the components of %c %p %m are printed as %f with the
/// conversion's flags, width and precision each (%.3p: "1.000 2.000 3.000");
/// %% is a percent sign. Too few or too many arguments, a wrong type for a
/// conversion, an unknown conversion or a width/precision over 4 digits ->
/// sss::ValueError naming the pattern and the argument.
std::string rsl_format(std::string_view pattern, std::span<const RslFormatArg> args);

/// Bounds of match()'s patterns, checked before regcomp (glibc's compiled
/// size grows with the repetitions multiplied out: `((a{1,100}){1,100}){1,100}`
/// takes gigabytes; its matching time with the size times the subject).
constexpr std::size_t kMaxRegexLength = 4096; ///< bytes of one pattern
constexpr uint64_t kMaxRegexSize = 2000;      ///< elements, repetitions multiplied out
constexpr int kMaxRegexNesting = 64;          ///< nested groups
constexpr uint64_t kMaxRegexWork = uint64_t(1) << 24; ///< size x subject bytes

/// match(pattern, subject): true if the POSIX extended regular expression
/// matches anywhere in subject. Compiled patterns are cached (thread-safe).
/// Throws sss::ValueError naming the pattern for an invalid one (regcomp's
/// reason), one over the bounds above, a back-reference (`\1`: glibc
/// matches them by backtracking, in exponential time), and a subject too
/// long for the pattern's size (kMaxRegexWork).
bool rsl_match(std::string_view pattern, std::string_view subject);

} // namespace sss::detail
