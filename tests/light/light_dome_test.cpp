// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file light_dome_test.cpp
/// Tests of the median-cut light dome (sss/light/light_dome.h): energy
/// conservation, light counts, a single bright pixel found, a constant map
/// balanced over the sphere, the lat-long direction formulas, the RIB text
/// and the procedural sky.
///
/// Suite names start with "LightDome".

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "sss/light/light_dome.h"
#include "sss/util/error.h"

namespace {

using namespace sss;
constexpr double kPi = std::numbers::pi;

LatLongImage constant_map(int h, float v) {
    LatLongImage img(2 * h, h);
    std::fill(img.rgb.begin(), img.rgb.end(), v);
    return img;
}

glm::dvec3 sum_colors(const std::vector<DomeLight>& lights) {
    glm::dvec3 s(0.0);
    for (const DomeLight& l : lights) s += l.color;
    return s;
}

TEST(LightDome, PixelSolidAnglesCoverTheSphere) {
    for (int h : {1, 3, 64}) {
        double sum = 0.0;
        for (int y = 0; y < h; ++y) sum += latlong_pixel_solid_angle(y, 2 * h, h) * 2 * h;
        EXPECT_NEAR(sum, 4.0 * kPi, 1e-12) << h;
    }
    const glm::dvec3 e = latlong_integral(constant_map(16, 2.0f));
    EXPECT_NEAR(e.x, 8.0 * kPi, 1e-9);
    EXPECT_NEAR(e.z, 8.0 * kPi, 1e-9);
}

TEST(LightDome, DirectionsFollowTheOiioConvention) {
    // Top +y, bottom -y, centre +z, s = 0.25 +x, s = 0.75 -x, edges -z.
    auto near = [](const glm::dvec3& a, const glm::dvec3& b) {
        return glm::length(a - b) < 1e-12;
    };
    EXPECT_TRUE(near(latlong_direction(0.5, 0.5), {0, 0, 1}));
    EXPECT_TRUE(near(latlong_direction(0.25, 0.5), {1, 0, 0}));
    EXPECT_TRUE(near(latlong_direction(0.75, 0.5), {-1, 0, 0}));
    EXPECT_TRUE(near(latlong_direction(0.0, 0.5), {0, 0, -1}));
    EXPECT_TRUE(near(latlong_direction(0.3, 0.0), {0, 1, 0}));
    EXPECT_TRUE(near(latlong_direction(0.7, 1.0), {0, -1, 0}));
    // Round trips.
    for (double s : {0.01, 0.2, 0.5, 0.77, 0.99})
        for (double t : {0.05, 0.3, 0.5, 0.8, 0.97}) {
            double s2, t2;
            latlong_coordinates(latlong_direction(s, t) * 3.0, s2, t2);
            EXPECT_NEAR(s2, s, 1e-12);
            EXPECT_NEAR(t2, t, 1e-12);
        }
}

TEST(LightDome, EnergyIsConservedAndCountsAreExact) {
    // A varied map: a gradient, a colour and a bright spot.
    LatLongImage img(64, 32);
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 64; ++x) {
            float* p = img.pixel(x, y);
            p[0] = 0.1f + 0.02f * x;
            p[1] = 0.5f + 0.03f * y;
            p[2] = (x == 40 && y == 9) ? 500.0f : 0.2f;
        }
    const glm::dvec3 integral = latlong_integral(img);
    for (int n : {1, 2, 8, 64, 256, 4096}) {
        const std::vector<DomeLight> lights = median_cut(img, n);
        ASSERT_EQ(static_cast<int>(lights.size()), n);
        const glm::dvec3 s = sum_colors(lights);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(s[c] / integral[c], 1.0, 1e-4) << n;
        for (const DomeLight& l : lights) {
            EXPECT_NEAR(glm::length(l.direction), 1.0, 1e-9);
            EXPECT_TRUE(std::isfinite(l.color.x) && l.color.x >= 0.0);
        }
    }
}

TEST(LightDome, TheStrongestLightIsTheBrightPixel) {
    LatLongImage img = constant_map(32, 0.01f);
    const int bx = 45, by = 10;
    float* p = img.pixel(bx, by);
    p[0] = p[1] = p[2] = 1000.0f;
    const glm::dvec3 pixel_dir = latlong_direction((bx + 0.5) / 64, (by + 0.5) / 32);
    for (int n : {4, 16, 64}) {
        const std::vector<DomeLight> lights = median_cut(img, n);
        std::size_t best = 0;
        for (std::size_t i = 1; i < lights.size(); ++i)
            if (lights[i].color.y > lights[best].color.y) best = i;
        const DomeLight& l = lights[best];
        EXPECT_TRUE(bx >= l.x0 && bx < l.x1 && by >= l.y0 && by < l.y1) << n;
        // Its direction is within the bright pixel's own extent (~5.6 degrees).
        EXPECT_GT(glm::dot(l.direction, pixel_dir), std::cos(3.0 * kPi / 180.0)) << n;
        // The cut balances energies, so the pixel may be shared by several
        // lights (halves of it): together they carry nearly all the energy.
        double on_pixel = 0.0;
        for (const DomeLight& k : lights)
            if (bx >= k.x0 && bx < k.x1 && by >= k.y0 && by < k.y1) on_pixel += k.color.y;
        EXPECT_GT(on_pixel / sum_colors(lights).y, 0.9) << n;
    }
}

TEST(LightDome, AConstantMapIsBalancedOverTheSphere) {
    const LatLongImage img = constant_map(64, 1.0f);
    for (int n : {8, 64, 256}) {
        const std::vector<DomeLight> lights = median_cut(img, n);
        glm::dvec3 moment(0.0);
        double total = 0.0;
        for (const DomeLight& l : lights) {
            moment += l.color.x * l.direction;
            total += l.color.x;
            // Equal energies: each light has 1/n of 4 pi (within a pixel row).
            EXPECT_NEAR(l.color.x / (4.0 * kPi / n), 1.0, 0.25) << n;
        }
        EXPECT_NEAR(total, 4.0 * kPi, 1e-9);
        EXPECT_LT(glm::length(moment) / total, 0.01) << n;
        // Spread: lights in both hemispheres of every axis.
        for (int a = 0; a < 3; ++a) {
            int pos = 0, neg = 0;
            for (const DomeLight& l : lights) (l.direction[a] > 0 ? pos : neg) += 1;
            EXPECT_GE(pos, n / 4) << a;
            EXPECT_GE(neg, n / 4) << a;
        }
        // The dome's diffuse response (sum of c max(0, N.d) / pi) to a
        // constant radiance of 1 is 1 for any N.
        for (const glm::dvec3 N :
             {glm::dvec3(0, 1, 0), glm::dvec3(0.6, 0, 0.8), glm::dvec3(0, -1, 0)}) {
            double d = 0.0;
            for (const DomeLight& l : lights)
                d += l.color.x * std::max(0.0, glm::dot(N, l.direction)) / kPi;
            EXPECT_NEAR(d, 1.0, n >= 64 ? 0.03 : 0.2) << n;
        }
    }
}

TEST(LightDome, SinglePixelRegionsSplitInHalves) {
    LatLongImage img = constant_map(1, 1.0f); // 2 x 1 pixels
    const std::vector<DomeLight> lights = median_cut(img, 8);
    ASSERT_EQ(lights.size(), 8u);
    EXPECT_NEAR(sum_colors(lights).x, 4.0 * kPi, 1e-9);
    for (const DomeLight& l : lights) EXPECT_NEAR(l.color.x, 4.0 * kPi / 8, 1e-9);
}

TEST(LightDome, BadInputsThrow) {
    const LatLongImage img = constant_map(4, 1.0f);
    EXPECT_THROW(median_cut(img, 3), ValueError);
    EXPECT_THROW(median_cut(img, 0), ValueError);
    EXPECT_THROW(LatLongImage(10, 4), ValueError);
    LatLongImage bad = img;
    bad.pixel(3, 2)[1] = std::nanf("");
    try {
        median_cut(bad, 4);
        FAIL() << "no error for a NaN pixel";
    } catch (const ValueError& e) {
        EXPECT_NE(std::string(e.what()).find("(3, 2)"), std::string::npos) << e.what();
    }
    bad.pixel(3, 2)[1] = -1.0f;
    EXPECT_THROW(median_cut(bad, 4), ValueError);
}

TEST(LightDome, RibHasOneDistantLightPerRegion) {
    LatLongImage img = constant_map(8, 0.0f);
    // All the energy straight up (+y): the top row.
    for (int x = 0; x < 16; ++x)
        img.pixel(x, 0)[0] = img.pixel(x, 0)[1] = img.pixel(x, 0)[2] = 1;
    std::vector<DomeLight> lights = median_cut(img, 1);
    ASSERT_EQ(lights.size(), 1u);
    EXPECT_GT(lights[0].direction.y, 0.999);
    DomeRibOptions o;
    o.probe = "sky.exr";
    o.intensity = 2.0;
    o.shadows = true;
    const std::string rib = dome_rib(lights, o);
    EXPECT_NE(rib.find("## probe: sky.exr"), std::string::npos) << rib;
    EXPECT_NE(rib.find("LightSource \"distantlight_rts\" \"envdome1\" \"intensity\" [2]"),
              std::string::npos)
        << rib;
    // The light travels downwards: "to" ~ (0, -1, 0); lightcolor = colour / pi.
    const std::size_t to = rib.find("\"to\" [");
    ASSERT_NE(to, std::string::npos);
    std::istringstream in(rib.substr(to + 6));
    double tx, ty, tz;
    in >> tx >> ty >> tz;
    EXPECT_LT(ty, -0.999);
    const std::size_t lc = rib.find("\"lightcolor\" [");
    std::istringstream cin(rib.substr(lc + 14));
    double r;
    cin >> r;
    EXPECT_NEAR(r, lights[0].color.x / kPi, 1e-6 * r);
    // Rotation by 90 degrees about +y takes +z to +x.
    LatLongImage front = constant_map(8, 0.0f);
    front.pixel(8, 4)[0] = front.pixel(8, 4)[1] = front.pixel(8, 4)[2] = 1; // near +z
    lights = median_cut(front, 1);
    EXPECT_GT(lights[0].direction.z, 0.9);
    o.rotate_degrees = 90.0;
    const std::string rot = dome_rib(lights, o);
    std::istringstream rin(rot.substr(rot.find("\"to\" [") + 6));
    rin >> tx >> ty >> tz;
    EXPECT_LT(tx, -0.9); // light from +x travels along -x
}

TEST(LightDome, SkyProbeHasASunAndADarkGround) {
    SkyOptions o;
    o.sun_elevation = 30.0;
    o.sun_azimuth = 90.0; // towards +x
    const LatLongImage sky = sky_probe(128, 64, o);
    const glm::dvec3 sun = sun_direction(o);
    EXPECT_NEAR(sun.x, std::cos(30.0 * kPi / 180.0), 1e-12);
    EXPECT_NEAR(sun.y, 0.5, 1e-12);
    double s, t;
    latlong_coordinates(sun, s, t);
    const float* at_sun = sky.pixel(static_cast<int>(s * 128), static_cast<int>(t * 64));
    EXPECT_GT(at_sun[0], 100.0f);
    EXPECT_LT(sky.pixel(10, 60)[2], 0.1f);         // ground
    EXPECT_GT(sky.pixel(10, 5)[2], 0.5f);          // sky
    EXPECT_EQ(sky.rgb, sky_probe(128, 64, o).rgb); // deterministic
    // The strongest dome light points at the sun.
    const std::vector<DomeLight> lights = median_cut(sky, 16);
    std::size_t best = 0;
    for (std::size_t i = 1; i < lights.size(); ++i)
        if (lights[i].color.x > lights[best].color.x) best = i;
    EXPECT_GT(glm::dot(lights[best].direction, sun), std::cos(5.0 * kPi / 180.0));
}

TEST(LightDome, DiffuseMatchesTheCosineWeightedIntegral) {
    // What envlight computes for a white diffuse surface, (1/pi) integral of
    // L max(0, N.w) dw, here by direct summation over the pixels, against the
    // dome's sum of (c / pi) max(0, N.d).
    SkyOptions o;
    o.sun_elevation = 35.0;
    o.sun_azimuth = 60.0;
    const LatLongImage sky = sky_probe(256, 128, o);
    std::vector<glm::dvec3> normals;
    for (int i = 0; i < 26; ++i) {
        const double z = 1.0 - (i + 0.5) / 13.0, phi = 2.399963 * i;
        const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
        normals.push_back({r * std::cos(phi), z, r * std::sin(phi)});
    }
    normals.push_back(sun_direction(o));
    for (int n : {64, 256}) {
        const std::vector<DomeLight> lights = median_cut(sky, n);
        double worst = 0.0;
        for (const glm::dvec3& N : normals) {
            double exact = 0.0;
            for (int y = 0; y < sky.height; ++y) {
                const double omega = latlong_pixel_solid_angle(y, sky.width, sky.height);
                for (int x = 0; x < sky.width; ++x) {
                    const glm::dvec3 w =
                        latlong_direction((x + 0.5) / sky.width, (y + 0.5) / sky.height);
                    exact += sky.pixel(x, y)[1] * omega * std::max(0.0, glm::dot(N, w));
                }
            }
            exact /= kPi;
            double dome = 0.0;
            for (const DomeLight& l : lights)
                dome += l.color.y * std::max(0.0, glm::dot(N, l.direction)) / kPi;
            worst = std::max(worst, std::abs(dome / exact - 1.0));
        }
        EXPECT_LT(worst, n == 64 ? 0.08 : 0.04) << n << " lights";
        std::printf("[          ] %d lights: worst relative error %.4f\n", n, worst);
    }
}

} // namespace
