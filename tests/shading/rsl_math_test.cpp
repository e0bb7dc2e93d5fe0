// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file rsl_math_test.cpp
/// The pure built-in functions of RSL (src/sss/shading/rsl_math.h): noise
/// family, colour spaces, splines, format() and match().

#include <atomic>
#include <cmath>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "../../src/sss/shading/rsl_math.h"
#include "sss/light/lights.h"
#include "sss/util/error.h"

namespace sss::detail {
namespace {

// --- noise -------------------------------------------------------------------

/// Every scalar noise flavour at a random point of `dim` dimensions.
float noise_at(int dim, const float* x) {
    switch (dim) {
    case 1:
        return rsl_noise(x[0]);
    case 2:
        return rsl_noise(x[0], x[1]);
    case 3:
        return rsl_noise(glm::vec3(x[0], x[1], x[2]));
    default:
        return rsl_noise(glm::vec3(x[0], x[1], x[2]), x[3]);
    }
}

TEST(RslNoise, RangeMeanAndLatticeInEveryDimension) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> coord(-300.0f, 300.0f);
    for (int dim = 1; dim <= 4; ++dim) {
        double sum = 0.0, lo = 1.0, hi = 0.0;
        const int n = 20000;
        for (int i = 0; i < n; ++i) {
            float x[4];
            for (float& c : x) c = coord(rng);
            const float v = noise_at(dim, x);
            ASSERT_GE(v, 0.0f);
            ASSERT_LE(v, 1.0f);
            sum += v;
            lo = std::min<double>(lo, v);
            hi = std::max<double>(hi, v);
            // Integer lattice points: exactly 0.5.
            float lattice[4];
            for (int d = 0; d < 4; ++d) lattice[d] = std::floor(x[d]);
            ASSERT_EQ(noise_at(dim, lattice), 0.5f) << "dim " << dim;
        }
        EXPECT_NEAR(sum / n, 0.5, 0.02) << "dim " << dim;
        // Not degenerate: a real spread around 0.5.
        EXPECT_LT(lo, 0.25) << "dim " << dim;
        EXPECT_GT(hi, 0.75) << "dim " << dim;
    }
}

TEST(RslNoise, Continuous) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> coord(-50.0f, 50.0f);
    const float eps = 1e-3f;
    for (int dim = 1; dim <= 4; ++dim)
        for (int i = 0; i < 5000; ++i) {
            float x[4], y[4];
            for (int d = 0; d < 4; ++d) {
                x[d] = coord(rng);
                y[d] = x[d] + eps;
            }
            // The gradients are at most 2 per axis: |dn| <= ~4 * eps per axis.
            ASSERT_LT(std::fabs(noise_at(dim, x) - noise_at(dim, y)), 0.01f)
                << "dim " << dim;
        }
}

TEST(RslNoise, ThreeDimensionalEqualsLightNoise3) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> coord(-1000.0f, 1000.0f);
    for (int i = 0; i < 20000; ++i) {
        const glm::vec3 p(coord(rng), coord(rng), coord(rng));
        ASSERT_EQ(rsl_noise(p), static_cast<float>(noise3(glm::dvec3(p))))
            << p.x << " " << p.y << " " << p.z;
        const glm::vec3 q = p * 0.01f; // small coordinates too
        ASSERT_EQ(rsl_noise(q), static_cast<float>(noise3(glm::dvec3(q))));
    }
}

TEST(RslNoise, NotFiniteGivesHalf) {
    EXPECT_EQ(rsl_noise(NAN), 0.5f);
    EXPECT_EQ(rsl_noise(glm::vec3(1.5f, INFINITY, 0.2f)), 0.5f);
    EXPECT_EQ(rsl_pnoise(NAN, 4.0f), 0.5f);
    // Huge coordinates and periods stay defined (and in range).
    for (float big : {3.0e38f, -3.0e38f, 1.0e20f, -7.5e9f})
        for (float period : {3.0f, 7.0f, 1.0e12f, 3.0e38f, -2.0f}) {
            const float v =
                rsl_pnoise(glm::vec3(big, 0.5f, -big), big, glm::vec3(period), period);
            EXPECT_GE(v, 0.0f);
            EXPECT_LE(v, 1.0f);
            EXPECT_GE(rsl_noise(glm::vec3(big, big, 0.5f)), 0.0f);
            EXPECT_GE(rsl_cellnoise(big, big), 0.0f);
        }
    EXPECT_GE(rsl_cellnoise(NAN), 0.0f);
}

TEST(RslNoise, VectorComponentsDiffer) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> coord(-20.0f, 20.0f);
    int same = 0;
    double corr = 0.0;
    const int n = 5000;
    for (int i = 0; i < n; ++i) {
        const glm::vec3 p(coord(rng), coord(rng), coord(rng));
        const float t = coord(rng);
        for (const glm::vec3 v :
             {rsl_vnoise(p.x), rsl_vnoise(p.x, p.y), rsl_vnoise(p), rsl_vnoise(p, t)}) {
            for (int c = 0; c < 3; ++c) {
                ASSERT_GE(v[c], 0.0f);
                ASSERT_LE(v[c], 1.0f);
            }
            same += v.x == v.y || v.y == v.z;
            corr += (v.x - 0.5) * (v.y - 0.5);
        }
        // Lattice points stay at 0.5 in every component.
        EXPECT_EQ(rsl_vnoise(glm::floor(p)), glm::vec3(0.5f));
    }
    EXPECT_LT(same, n / 100);
    EXPECT_LT(std::fabs(corr / (4 * n)), 0.003);
}

TEST(RslNoise, PeriodicNoiseRepeatsExactly) {
    std::mt19937 rng(9);
    // Multiples of 1/1024: adding a period is exact in float, so the noise
    // must repeat bit for bit.
    std::uniform_int_distribution<int> grid(-10240, 10240);
    auto coord = [&] { return static_cast<float>(grid(rng)) / 1024.0f; };
    for (int i = 0; i < 3000; ++i) {
        const glm::vec3 p(coord(), coord(), coord());
        const float t = coord();
        // Periods are rounded: 3.2 -> 3, 5.7 -> 6, 2 -> 2, 4.4 -> 4.
        const glm::vec3 per(3.2f, 5.7f, 2.0f);
        const glm::vec3 shift(3.0f * 2, 6.0f * -1, 2.0f * 3);
        ASSERT_EQ(rsl_pnoise(p.x, per.x), rsl_pnoise(p.x + shift.x, per.x));
        ASSERT_EQ(rsl_pnoise(p.x, p.y, per.x, per.y),
                  rsl_pnoise(p.x + shift.x, p.y + shift.y, per.x, per.y));
        ASSERT_EQ(rsl_pnoise(p, per), rsl_pnoise(p + shift, per));
        ASSERT_EQ(rsl_pnoise(p, t, per, 4.4f),
                  rsl_pnoise(p + shift, t - 8.0f, per, 4.4f));
        const glm::vec3 a = rsl_vpnoise(p, t, per, 4.4f);
        const glm::vec3 b = rsl_vpnoise(p + shift, t + 4.0f, per, 4.4f);
        ASSERT_EQ(a, b);
        ASSERT_EQ(rsl_vpnoise(p.x, 7.0f), rsl_vpnoise(p.x - 7.0f, 7.0f));
        ASSERT_EQ(rsl_vpnoise(p.x, p.y, 7.0f, 1.0f),
                  rsl_vpnoise(p.x - 7.0f, p.y + 1.0f, 7.0f, 1.0f));
        ASSERT_EQ(rsl_vpnoise(p, per), rsl_vpnoise(p + shift, per));
    }
    // A period below 1 (0 here) means not periodic: plain noise.
    EXPECT_EQ(rsl_pnoise(glm::vec3(0.3f, 1.7f, 2.2f), glm::vec3(0.0f)),
              rsl_noise(glm::vec3(0.3f, 1.7f, 2.2f)));
    EXPECT_EQ(rsl_pnoise(0.3f, 0.4f), rsl_noise(0.3f));
    // Exact at representable shifts: x and x + period hit the same lattice
    // cell offsets when both are exact in float.
    EXPECT_EQ(rsl_pnoise(glm::vec3(0.25f, 0.5f, 0.75f), glm::vec3(4.0f)),
              rsl_pnoise(glm::vec3(4.25f, -3.5f, 8.75f), glm::vec3(4.0f)));
}

TEST(RslNoise, CellNoiseConstantPerCellAndUniform) {
    std::mt19937 rng(13);
    std::uniform_real_distribution<float> frac(0.0f, 0.999f);
    std::vector<int> histogram(10, 0);
    const int cells = 20000;
    for (int i = 0; i < cells; ++i) {
        const float cx = static_cast<float>(i % 200) - 100.0f;
        const float cy = static_cast<float>(i / 200) - 50.0f;
        const glm::vec3 c(cx, cy, 3.0f);
        const float v = rsl_cellnoise(c);
        ASSERT_GE(v, 0.0f);
        ASSERT_LT(v, 1.0f);
        ++histogram[static_cast<int>(v * 10.0f)];
        const glm::vec3 inside = c + glm::vec3(frac(rng), frac(rng), frac(rng));
        ASSERT_EQ(rsl_cellnoise(inside), v);
        ASSERT_EQ(rsl_cellnoise(cx + frac(rng)), rsl_cellnoise(cx));
        ASSERT_EQ(rsl_cellnoise(cx + 0.5f, cy + frac(rng)), rsl_cellnoise(cx, cy));
        ASSERT_EQ(rsl_cellnoise(inside, 2.5f), rsl_cellnoise(c, 2.0f));
        ASSERT_EQ(rsl_vcellnoise(inside), rsl_vcellnoise(c));
        const glm::vec3 vc = rsl_vcellnoise(c, 1.0f);
        ASSERT_NE(vc.x, vc.y);
        ASSERT_EQ(rsl_vcellnoise(cx + 0.5f), rsl_vcellnoise(cx));
        ASSERT_EQ(rsl_vcellnoise(cx + 0.5f, cy), rsl_vcellnoise(cx, cy + 0.5f));
    }
    for (int count : histogram) {
        EXPECT_GT(count, cells / 10 * 0.9);
        EXPECT_LT(count, cells / 10 * 1.1);
    }
    // Negative coordinates use the floor: -0.5 is in cell -1, not 0.
    EXPECT_EQ(rsl_cellnoise(-0.5f), rsl_cellnoise(-1.0f));
    EXPECT_NE(rsl_cellnoise(-0.5f), rsl_cellnoise(0.0f));
}

// --- colour spaces -----------------------------------------------------------

void expect_vec_near(const glm::vec3& a, const glm::vec3& b, float tol) {
    EXPECT_NEAR(a.x, b.x, tol);
    EXPECT_NEAR(a.y, b.y, tol);
    EXPECT_NEAR(a.z, b.z, tol);
}

TEST(RslColor, KnownValues) {
    glm::vec3 c;
    ASSERT_TRUE(rsl_rgb_to_color("hsv", {1, 0, 0}, c));
    expect_vec_near(c, {0, 1, 1}, 1e-6f);
    ASSERT_TRUE(rsl_rgb_to_color("hsv", {0, 0.5f, 0}, c));
    expect_vec_near(c, {1.0f / 3, 1, 0.5f}, 1e-6f);
    ASSERT_TRUE(rsl_rgb_to_color("hsl", {0, 0, 1}, c));
    expect_vec_near(c, {2.0f / 3, 1, 0.5f}, 1e-6f);
    ASSERT_TRUE(rsl_rgb_to_color("hsl", {0.5f, 0.5f, 0.5f}, c));
    expect_vec_near(c, {0, 0, 0.5f}, 1e-6f);
    ASSERT_TRUE(rsl_rgb_to_color("XYZ", {1, 1, 1}, c));
    expect_vec_near(c, {0.95047f, 1.0f, 1.08883f}, 1e-4f);
    ASSERT_TRUE(rsl_rgb_to_color("yiq", {1, 1, 1}, c));
    expect_vec_near(c, {1, 0, 0}, 1e-6f);
    ASSERT_TRUE(rsl_rgb_to_color("rgb", {0.1f, 0.2f, 0.3f}, c));
    EXPECT_EQ(c, glm::vec3(0.1f, 0.2f, 0.3f));

    glm::vec3 rgb;
    ASSERT_TRUE(rsl_color_to_rgb("hsv", {0, 1, 1}, rgb));
    expect_vec_near(rgb, {1, 0, 0}, 1e-6f);
    ASSERT_TRUE(rsl_color_to_rgb("hsv", {1.0f / 6, 1, 1}, rgb)); // yellow
    expect_vec_near(rgb, {1, 1, 0}, 1e-6f);
    ASSERT_TRUE(rsl_color_to_rgb("hsv", {1.5f, 1, 1}, rgb)); // hue wraps: cyan
    expect_vec_near(rgb, {0, 1, 1}, 1e-6f);
    ASSERT_TRUE(rsl_color_to_rgb("hsl", {0, 1, 0.5f}, rgb));
    expect_vec_near(rgb, {1, 0, 0}, 1e-6f);
    ASSERT_TRUE(rsl_color_to_rgb("hsl", {0.25f, 0, 0.3f}, rgb)); // grey
    expect_vec_near(rgb, {0.3f, 0.3f, 0.3f}, 1e-6f);
    ASSERT_TRUE(rsl_color_to_rgb("xyz", {0.95047f, 1.0f, 1.08883f}, rgb));
    expect_vec_near(rgb, {1, 1, 1}, 1e-4f);

    EXPECT_FALSE(rsl_color_to_rgb("cmyk", {0, 0, 0}, rgb));
    EXPECT_FALSE(rsl_rgb_to_color("", {0, 0, 0}, c));
}

TEST(RslColor, RoundTrips) {
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (const char* space : {"rgb", "hsv", "hsl", "xyz", "XYZ", "yiq", "YIQ"})
        for (int i = 0; i < 2000; ++i) {
            const glm::vec3 rgb(u(rng), u(rng), u(rng));
            glm::vec3 c, back;
            ASSERT_TRUE(rsl_rgb_to_color(space, rgb, c));
            ASSERT_TRUE(rsl_color_to_rgb(space, c, back));
            for (int k = 0; k < 3; ++k) ASSERT_NEAR(back[k], rgb[k], 2e-5f) << space;
        }
}

// --- splines -----------------------------------------------------------------

float spline1(std::string_view basis, float t, const std::vector<float>& v) {
    float out = NAN;
    EXPECT_TRUE(rsl_spline(basis, t, v.data(), static_cast<int>(v.size()), 1, &out))
        << basis;
    return out;
}

TEST(RslSpline, CatmullRomPassesThroughInteriorKnots) {
    const std::vector<float> v = {5, 1, 4, -2, 7, 0};
    // Interior knots v1..v4 at t = 0, 1/3, 2/3, 1.
    for (const char* basis : {"catmull-rom", "catmullrom", ""}) {
        EXPECT_NEAR(spline1(basis, 0.0f, v), 1.0f, 1e-6f);
        EXPECT_NEAR(spline1(basis, 1.0f / 3, v), 4.0f, 1e-5f);
        EXPECT_NEAR(spline1(basis, 2.0f / 3, v), -2.0f, 1e-5f);
        EXPECT_NEAR(spline1(basis, 1.0f, v), 7.0f, 1e-6f);
    }
    // Clamped t.
    EXPECT_NEAR(spline1("catmull-rom", -3.0f, v), 1.0f, 1e-6f);
    EXPECT_NEAR(spline1("catmull-rom", 9.0f, v), 7.0f, 1e-6f);
    // A straight line stays straight.
    EXPECT_NEAR(spline1("catmull-rom", 0.3f, {0, 1, 2, 3}), 1.3f, 1e-6f);
}

TEST(RslSpline, LinearIsExact) {
    const std::vector<float> v = {99, 0, 10, 30, -99};
    EXPECT_FLOAT_EQ(spline1("linear", 0.0f, v), 0.0f);
    EXPECT_FLOAT_EQ(spline1("linear", 0.25f, v), 5.0f);
    EXPECT_FLOAT_EQ(spline1("linear", 0.5f, v), 10.0f);
    EXPECT_FLOAT_EQ(spline1("linear", 0.75f, v), 20.0f);
    EXPECT_FLOAT_EQ(spline1("linear", 1.0f, v), 30.0f);
}

TEST(RslSpline, BezierHermiteBSplinePower) {
    // Bezier: endpoints of each segment are knots 0, 3, 6.
    const std::vector<float> bz = {1, 5, -3, 2, 8, 8, 4};
    EXPECT_FLOAT_EQ(spline1("bezier", 0.0f, bz), 1.0f);
    EXPECT_FLOAT_EQ(spline1("bezier", 0.5f, bz), 2.0f);
    EXPECT_FLOAT_EQ(spline1("bezier", 1.0f, bz), 4.0f);
    // One segment at t = 0.5: (1 + 3*5 + 3*(-3) + 2) / 8.
    EXPECT_FLOAT_EQ(spline1("bezier", 0.5f, {1, 5, -3, 2}), 9.0f / 8);
    // Hermite (P0, T0, P1, T1): endpoints and midpoint (P0+P1)/2 + (T0-T1)/8.
    EXPECT_FLOAT_EQ(spline1("hermite", 0.0f, {2, 1, 6, 3}), 2.0f);
    EXPECT_FLOAT_EQ(spline1("hermite", 1.0f, {2, 1, 6, 3}), 6.0f);
    EXPECT_FLOAT_EQ(spline1("hermite", 0.5f, {2, 1, 6, 3}), 4.0f - 0.25f);
    // B-spline of constant knots is that constant; at t=0: (v0 + 4 v1 + v2) / 6.
    EXPECT_FLOAT_EQ(spline1("b-spline", 0.4f, {3, 3, 3, 3, 3}), 3.0f);
    EXPECT_FLOAT_EQ(spline1("bspline", 0.0f, {6, 0, 12, 1}), 3.0f);
    // Power: v0 t^3 + v1 t^2 + v2 t + v3.
    EXPECT_FLOAT_EQ(spline1("power", 0.5f, {8, 4, 2, 1}), 1 + 1 + 1 + 1);
}

TEST(RslSpline, ComponentsAndRefusals) {
    // Three colours: red, green, blue, white, black; catmull-rom at t=0 is v1.
    const float colors[] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1, 0, 0, 0};
    float out[3];
    ASSERT_TRUE(rsl_spline("catmull-rom", 0.0f, colors, 5, 3, out));
    EXPECT_FLOAT_EQ(out[0], 0.0f);
    EXPECT_FLOAT_EQ(out[1], 1.0f);
    EXPECT_FLOAT_EQ(out[2], 0.0f);
    ASSERT_TRUE(rsl_spline("linear", 0.5f, colors, 5, 3, out));
    EXPECT_FLOAT_EQ(out[0], 0.0f);
    EXPECT_FLOAT_EQ(out[1], 0.0f);
    EXPECT_FLOAT_EQ(out[2], 1.0f);

    const float v[7] = {0, 1, 2, 3, 4, 5, 6};
    float f;
    EXPECT_FALSE(rsl_spline("catmull-rom", 0.5f, v, 3, 1, &f));
    EXPECT_FALSE(rsl_spline("bezier", 0.5f, v, 5, 1, &f));
    EXPECT_TRUE(rsl_spline("bezier", 0.5f, v, 7, 1, &f));
    EXPECT_FALSE(rsl_spline("hermite", 0.5f, v, 5, 1, &f));
    EXPECT_TRUE(rsl_spline("hermite", 0.5f, v, 6, 1, &f));
    EXPECT_FALSE(rsl_spline("power", 0.5f, v, 6, 1, &f));
    EXPECT_FALSE(rsl_spline("linear", 0.5f, v, 3, 1, &f));
    EXPECT_FALSE(rsl_spline("cardinal", 0.5f, v, 7, 1, &f));
    EXPECT_FALSE(rsl_spline("linear", 0.5f, v, 7, 0, &f));
}

// --- format ------------------------------------------------------------------

std::string fmt(std::string_view pattern, std::initializer_list<RslFormatArg> args) {
    return rsl_format(pattern, std::span<const RslFormatArg>(args.begin(), args.size()));
}

TEST(RslFormat, EveryConversion) {
    const float pi = 3.14159265f, big = 12345.678f, neg = -2.7f;
    const float triple[3] = {1.0f, 0.5f, 0.25f};
    float matrix[16] = {};
    for (int i = 0; i < 16; ++i) matrix[i] = i % 5 == 0 ? 1.0f : 0.0f;
    const std::string name = "skin";
    const RslFormatArg f{ShadingType::Float, &pi};
    EXPECT_EQ(fmt("x=%f", {f}), "x=3.141593");
    EXPECT_EQ(fmt("%.2f|%8.3f|%-7.1f|", {f, f, f}), "3.14|   3.142|3.1    |");
    EXPECT_EQ(fmt("%e %.2E", {f, f}), "3.141593e+00 3.14E+00");
    EXPECT_EQ(fmt("%g", {{ShadingType::Float, &big}}), "12345.7");
    EXPECT_EQ(fmt("%d %i %5d", {{ShadingType::Float, &neg}, f, f}), "-2 3     3");
    EXPECT_EQ(fmt("[%s] [%6s]", {{ShadingType::String, nullptr, &name},
                                 {ShadingType::String, nullptr, &name}}),
              "[skin] [  skin]");
    EXPECT_EQ(fmt("%c", {{ShadingType::Color, triple}}), "1.000000 0.500000 0.250000");
    EXPECT_EQ(fmt("%.2p", {{ShadingType::Point, triple}}), "1.00 0.50 0.25");
    EXPECT_EQ(
        fmt("%.1p;%.0p", {{ShadingType::Normal, triple}, {ShadingType::Vector, triple}}),
        "1.0 0.5 0.2;1 0 0");
    EXPECT_EQ(fmt("%.0m", {{ShadingType::Matrix, matrix}}),
              "1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1");
    EXPECT_EQ(fmt("100%% done\n", {}), "100% done\n");
    EXPECT_EQ(fmt("", {}), "");
}

TEST(RslFormat, ErrorsAreClear) {
    const float x = 1.0f;
    const float triple[3] = {1, 2, 3};
    const RslFormatArg f{ShadingType::Float, &x};
    const RslFormatArg p{ShadingType::Point, triple};
    auto message = [](auto&& call) -> std::string {
        try {
            call();
        } catch (const ValueError& e) {
            return e.what();
        }
        return "no error";
    };
    EXPECT_NE(message([&] { fmt("%f %f", {f}); }).find("too few arguments"),
              std::string::npos);
    EXPECT_NE(message([&] {
                  fmt("%f", {f, f});
              }).find("too many arguments"),
              std::string::npos);
    const std::string wrong = message([&] { fmt("%f", {p}); });
    EXPECT_NE(wrong.find("'%f' needs a float"), std::string::npos) << wrong;
    EXPECT_NE(wrong.find("point"), std::string::npos) << wrong;
    EXPECT_NE(message([&] { fmt("%c", {p}); }).find("needs a color"), std::string::npos);
    EXPECT_NE(message([&] {
                  fmt("%p", {{ShadingType::Color, triple}});
              }).find("needs a point"),
              std::string::npos);
    EXPECT_NE(message([&] { fmt("%s", {f}); }).find("needs a string"), std::string::npos);
    EXPECT_NE(message([&] { fmt("%q", {f}); }).find("unknown conversion '%q'"),
              std::string::npos);
    EXPECT_NE(message([&] { fmt("50%", {}); }).find("incomplete"), std::string::npos);
    EXPECT_NE(message([&] { fmt("%99999f", {f}); }).find("too large"), std::string::npos);
}

// --- match -------------------------------------------------------------------

/// The ValueError's message of match(pattern, subject), or "no error".
std::string match_error(const std::string& pattern, const std::string& subject) {
    try {
        rsl_match(pattern, subject);
    } catch (const ValueError& e) {
        return e.what();
    }
    return "no error";
}

TEST(RslMatch, ExtendedRegularExpressions) {
    EXPECT_TRUE(rsl_match("skin", "my_skin_shader"));
    EXPECT_FALSE(rsl_match("^skin", "my_skin_shader"));
    EXPECT_TRUE(rsl_match("^(my|your)_[a-z]+_shader$", "my_skin_shader"));
    EXPECT_TRUE(rsl_match("a{2,3}", "baaad"));
    EXPECT_FALSE(rsl_match("a{4}", "baaad"));
    EXPECT_TRUE(rsl_match("", "anything"));
    EXPECT_TRUE(rsl_match("[[:alpha:]]+[]x]{2}(a|b)*$", "ab]x"));
    EXPECT_TRUE(rsl_match("(a{1,10}){1,100}", "xaay"));
}

TEST(RslMatch, InvalidPatternsAreErrors) {
    EXPECT_NE(match_error("(unclosed", "(unclosed")
                  .find("match(\"(unclosed\"): invalid regular expression"),
              std::string::npos);
    EXPECT_THROW(rsl_match("[z-a]", "a"), ValueError);
}

TEST(RslMatch, BoundsBeforeCompiling) {
    // Repetitions multiplied out: glibc would take gigabytes for this one.
    const std::string bomb = match_error("((a{1,100}){1,100}){1,100}", "a");
    EXPECT_NE(bomb.find("1020201 elements once its repetitions are multiplied out"),
              std::string::npos)
        << bomb;
    EXPECT_NE(bomb.find("the bound of 2000"), std::string::npos) << bomb;
    EXPECT_THROW(rsl_match("(a+)+(b+)+(c{1,50}){1,50}", "a"), ValueError);
    EXPECT_NE(match_error("(a*)*\\1b", "aaab").find("back-references"),
              std::string::npos);
    EXPECT_NE(match_error(std::string(100, '(') + "a" + std::string(100, ')'), "a")
                  .find("nest more than 64"),
              std::string::npos);
    EXPECT_THROW(rsl_match(std::string(5000, 'a'), "a"), ValueError);
    // Matching time: the size times the subject's length is bounded.
    EXPECT_TRUE(rsl_match("b", std::string(1 << 20, 'a') + "b"));
    EXPECT_THROW(rsl_match("(a|b){1,400}c", std::string(1 << 16, 'a')), ValueError);
    // Brackets and escapes count as one element.
    EXPECT_TRUE(rsl_match("[(]{3}\\(", "x(((("));
}

TEST(RslMatch, ThreadSafeCache) {
    std::vector<std::thread> threads;
    std::atomic<int> failures{0};
    for (int t = 0; t < 4; ++t)
        threads.emplace_back([t, &failures] {
            for (int i = 0; i < 2000; ++i) {
                // Many distinct patterns: the cache fills and is cleared meanwhile.
                // (Appended, not "^x" + ...: gcc 12 warns falsely on that form.)
                std::string subj = "x";
                subj += std::to_string((i * 7 + t) % 400);
                std::string pat = "^";
                pat += subj;
                pat += '$';
                if (!rsl_match(pat, subj) || rsl_match(pat, subj + "0")) ++failures;
            }
        });
    for (auto& th : threads) th.join();
    EXPECT_EQ(failures.load(), 0);
}

} // namespace
} // namespace sss::detail
