// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file rsl_math.cpp
/// RSL's colour spaces and spline() (rsl_math.h).

#include <algorithm>
#include <cctype>
#include <cmath>

#include <glm/mat3x3.hpp>

#include "rsl_math.h"

namespace sss::detail {

namespace {

/// Space names compare without case ("XYZ", "xyz", "HSV"...).
bool same_name(std::string_view a, std::string_view b) {
    return a.size() == b.size() &&
           std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
               return std::tolower(static_cast<unsigned char>(x)) ==
                      std::tolower(static_cast<unsigned char>(y));
           });
}

/// Linear RGB (Rec.709 primaries, D65 white) to CIE XYZ (IEC 61966-2-1).
/// glm matrices are column-major: each line below is a column.
const glm::dmat3 kRgbToXyz(0.4124564, 0.2126729, 0.0193339, //
                           0.3575761, 0.7151522, 0.1191920, //
                           0.1804375, 0.0721750, 0.9503041);
/// NTSC YIQ (FCC coefficients).
const glm::dmat3 kRgbToYiq(0.299, 0.596, 0.211,   //
                           0.587, -0.274, -0.523, //
                           0.114, -0.322, 0.312);

glm::vec3 apply(const glm::dmat3& m, const glm::vec3& v) {
    return glm::vec3(m * glm::dvec3(v));
}

/// Inverses computed once in double, so that round trips are exact to float.
const glm::dmat3& xyz_to_rgb() {
    static const glm::dmat3 m = glm::inverse(kRgbToXyz);
    return m;
}
const glm::dmat3& yiq_to_rgb() {
    static const glm::dmat3 m = glm::inverse(kRgbToYiq);
    return m;
}

/// Hue in [0, 1) of an rgb colour whose largest and smallest components are
/// `hi` and `lo` (hi > lo); 0 red, 1/3 green, 2/3 blue.
float hue(const glm::vec3& c, float hi, float lo) {
    const float d = hi - lo;
    float h;
    if (c.r == hi)
        h = (c.g - c.b) / d;
    else if (c.g == hi)
        h = 2.0f + (c.b - c.r) / d;
    else
        h = 4.0f + (c.r - c.g) / d;
    h /= 6.0f;
    return h < 0.0f ? h + 1.0f : h;
}

glm::vec3 rgb_to_hsv(const glm::vec3& c) {
    const float hi = std::max({c.r, c.g, c.b}), lo = std::min({c.r, c.g, c.b});
    const float s = hi > 0.0f ? (hi - lo) / hi : 0.0f;
    return {hi > lo ? hue(c, hi, lo) : 0.0f, s, hi};
}

/// Hue (any real: wrapped) to the fully saturated rgb of that hue, from
/// which hsv and hsl scale.
glm::vec3 hue_rgb(float h) {
    h = (h - std::floor(h)) * 6.0f;
    auto channel = [h](float centre) {
        // Distance to the channel's peak on the 6-sector circle.
        float d = std::fabs(h - centre);
        d = std::min(d, 6.0f - d);
        return std::clamp(2.0f - d, 0.0f, 1.0f);
    };
    return {channel(0.0f), channel(2.0f), channel(4.0f)};
}

glm::vec3 hsv_to_rgb(const glm::vec3& c) {
    const glm::vec3 pure = hue_rgb(c.x);
    // v * (1 - s * (1 - pure)): grey of value v at s = 0.
    return c.z * (glm::vec3(1.0f) - c.y * (glm::vec3(1.0f) - pure));
}

glm::vec3 rgb_to_hsl(const glm::vec3& c) {
    const float hi = std::max({c.r, c.g, c.b}), lo = std::min({c.r, c.g, c.b});
    const float l = 0.5f * (hi + lo);
    if (!(hi > lo)) return {0.0f, 0.0f, l};
    const float d = hi - lo;
    const float s = l <= 0.5f ? d / (hi + lo) : d / (2.0f - hi - lo);
    return {hue(c, hi, lo), s, l};
}

glm::vec3 hsl_to_rgb(const glm::vec3& c) {
    const glm::vec3 pure = hue_rgb(c.x);
    const float l = c.z, s = c.y;
    const float chroma = (1.0f - std::fabs(2.0f * l - 1.0f)) * s;
    return glm::vec3(l - 0.5f * chroma) + chroma * pure;
}

/// Spline bases as 4x4 matrices M (value = [t^3 t^2 t 1] M [v0 v1 v2 v3]),
/// with the step between segments (RenderMan's RiBasis convention).
struct Basis {
    float m[4][4];
    int step;
};

constexpr Basis kCatmullRom{{{-0.5f, 1.5f, -1.5f, 0.5f},
                             {1.0f, -2.5f, 2.0f, -0.5f},
                             {-0.5f, 0.0f, 0.5f, 0.0f},
                             {0.0f, 1.0f, 0.0f, 0.0f}},
                            1};
constexpr Basis kBSpline{{{-1.0f / 6, 3.0f / 6, -3.0f / 6, 1.0f / 6},
                          {3.0f / 6, -6.0f / 6, 3.0f / 6, 0.0f},
                          {-3.0f / 6, 0.0f, 3.0f / 6, 0.0f},
                          {1.0f / 6, 4.0f / 6, 1.0f / 6, 0.0f}},
                         1};
constexpr Basis kBezier{{{-1.0f, 3.0f, -3.0f, 1.0f},
                         {3.0f, -6.0f, 3.0f, 0.0f},
                         {-3.0f, 3.0f, 0.0f, 0.0f},
                         {1, 0, 0, 0}},
                        3};
// Geometry (P0, T0, P1, T1): points and tangents alternate.
constexpr Basis kHermite{
    {{2.0f, 1.0f, -2.0f, 1.0f}, {-3.0f, -2.0f, 3.0f, -1.0f}, {0, 1, 0, 0}, {1, 0, 0, 0}},
    2};
constexpr Basis kPower{{{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}, 4};

/// The segment containing t in [0, 1] out of `segments`, and t's position
/// in it.
int segment(float t, int segments, float* local) {
    const float x = t * static_cast<float>(segments);
    const int s = std::min(static_cast<int>(x), segments - 1);
    *local = x - static_cast<float>(s);
    return s;
}

} // namespace

bool rsl_color_to_rgb(std::string_view space, const glm::vec3& c, glm::vec3& rgb) {
    if (same_name(space, "rgb"))
        rgb = c;
    else if (same_name(space, "hsv"))
        rgb = hsv_to_rgb(c);
    else if (same_name(space, "hsl"))
        rgb = hsl_to_rgb(c);
    else if (same_name(space, "xyz"))
        rgb = apply(xyz_to_rgb(), c);
    else if (same_name(space, "yiq"))
        rgb = apply(yiq_to_rgb(), c);
    else
        return false;
    return true;
}

bool rsl_rgb_to_color(std::string_view space, const glm::vec3& rgb, glm::vec3& c) {
    if (same_name(space, "rgb"))
        c = rgb;
    else if (same_name(space, "hsv"))
        c = rgb_to_hsv(rgb);
    else if (same_name(space, "hsl"))
        c = rgb_to_hsl(rgb);
    else if (same_name(space, "xyz"))
        c = apply(kRgbToXyz, rgb);
    else if (same_name(space, "yiq"))
        c = apply(kRgbToYiq, rgb);
    else
        return false;
    return true;
}

bool rsl_spline(std::string_view basis, float t, const float* values, int count,
                int components, float* out) {
    if (!values || !out || components < 1 || count < 2) return false;
    // NaN goes to 0 (the clamp would keep it, and the segment index with it).
    t = std::isnan(t) ? 0.0f : std::clamp(t, 0.0f, 1.0f);
    auto value = [&](int i, int c) { return values[i * components + c]; };

    if (same_name(basis, "linear")) {
        // Through the interior knots v1 .. v(n-2), like catmull-rom.
        if (count < 4) return false;
        float u;
        const int s = segment(t, count - 3, &u);
        for (int c = 0; c < components; ++c)
            out[c] = value(s + 1, c) + u * (value(s + 2, c) - value(s + 1, c));
        return true;
    }

    const Basis* b = nullptr;
    if (basis.empty() || same_name(basis, "catmull-rom") ||
        same_name(basis, "catmullrom"))
        b = &kCatmullRom;
    else if (same_name(basis, "b-spline") || same_name(basis, "bspline"))
        b = &kBSpline;
    else if (same_name(basis, "bezier"))
        b = &kBezier;
    else if (same_name(basis, "hermite"))
        b = &kHermite;
    else if (same_name(basis, "power"))
        b = &kPower;
    else
        return false;
    if (count < 4 || (count - 4) % b->step != 0) return false;

    float u;
    const int s = segment(t, (count - 4) / b->step + 1, &u);
    const float powers[4] = {u * u * u, u * u, u, 1.0f};
    float w[4]; // the weight of each of the segment's 4 values
    for (int j = 0; j < 4; ++j) {
        w[j] = 0.0f;
        for (int i = 0; i < 4; ++i) w[j] += powers[i] * b->m[i][j];
    }
    const int first = s * b->step;
    for (int c = 0; c < components; ++c) {
        float sum = 0.0f;
        for (int j = 0; j < 4; ++j) sum += w[j] * value(first + j, c);
        out[c] = sum;
    }
    return true;
}

} // namespace sss::detail
