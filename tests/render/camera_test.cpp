// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file camera_test.cpp
/// Tests of the renderer's camera features (docs/render.md): the pixel
/// filters against their RISpec formulas and on rendered images (a constant
/// image stays constant, an edge gives the filtered coverage), the thin-lens
/// samples, and DepthOfField's circle of confusion measured on a rendered
/// image against the thin-lens formula.
///
/// Suite names start with "Render".

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <string>
#include <vector>

#include "sss/render/camera_sampling.h"
#include "sss/render/render.h"
#include "sss/scene/rib.h"
#include "sss/util/error.h"
#include "sss/util/threads.h"

namespace {

using sss::PixelFilter;
using sss::PixelFilterSpec;

PixelFilter filter(const std::string& name, double xw, double yw) {
    return PixelFilter(PixelFilterSpec{name, xw, yw});
}

sss::Image render_rib(const std::string& rib) {
    return sss::render_image(sss::parse_rib(rib, "camera.rib"), sss::RenderJobOptions{},
                             nullptr);
}

float value(const sss::Image& img, int x, int y, const std::string& channel) {
    return img.pixel(x, y)[img.channel_index(channel)];
}

} // namespace

// ---------------------------------------------------------------------------
// Filters: RISpec 3.2 appendix E
// ---------------------------------------------------------------------------

TEST(RenderFilter, WeightsFollowTheirFormulas) {
    // gaussian: x *= 2 / xwidth, exp(-2 (x^2 + y^2)).
    const PixelFilter g = filter("gaussian", 2, 2);
    EXPECT_DOUBLE_EQ(g.weight(0.3, -0.4), std::exp(-2.0 * (0.09 + 0.16)));
    EXPECT_DOUBLE_EQ(g.weight(0.0, 0.0), 1.0);
    EXPECT_EQ(g.weight(1.0, 0.0), 0.0); // the support is open
    const PixelFilter g42 = filter("gaussian", 4, 2);
    EXPECT_DOUBLE_EQ(g42.weight(1.0, 0.5), std::exp(-2.0 * (0.25 + 0.25)));
    EXPECT_EQ(g42.weight(2.1, 0.0), 0.0);
    EXPECT_EQ(g42.weight(0.0, 1.01), 0.0);
    // box
    const PixelFilter b = filter("box", 1, 1);
    EXPECT_EQ(b.weight(0.49, -0.49), 1.0);
    EXPECT_EQ(b.weight(0.51, 0.0), 0.0);
    // triangle (the RISpec text's brackets corrected): (1 - |x| / (xw/2)) (1 - |y| /
    // (yw/2))
    const PixelFilter t = filter("triangle", 2, 4);
    EXPECT_DOUBLE_EQ(t.weight(0.5, 1.0), 0.5 * 0.5);
    EXPECT_DOUBLE_EQ(t.weight(-0.25, 0.0), 0.75);
    EXPECT_EQ(t.weight(1.0, 0.0), 0.0);
    // catmull-rom: radial, in pixels, negative for 1 < r < 2.
    const PixelFilter c = filter("catmull-rom", 4, 4);
    EXPECT_FALSE(c.separable());
    EXPECT_DOUBLE_EQ(c.weight(0.3, 0.4), 3 * 0.125 - 5 * 0.25 + 2);   // r = 0.5
    EXPECT_DOUBLE_EQ(c.weight(1.5, 0.0), -3.375 + 5 * 2.25 - 12 + 4); // -0.125
    EXPECT_NEAR(c.weight(0.0, 1.0), 0.0, 1e-15);
    EXPECT_EQ(c.weight(1.5, 1.5), 0.0); // r > 2
    EXPECT_DOUBLE_EQ(filter("catmullrom", 2, 2).weight(0.6, 0.8), 0.0 + 3 - 5 + 2);
    // sinc: sin(x)/x sin(y)/y, x in pixels, cut off at the half width.
    const PixelFilter s = filter("sinc", 8, 8);
    EXPECT_DOUBLE_EQ(s.weight(1.0, 2.0), std::sin(1.0) * std::sin(2.0) / 2.0);
    EXPECT_DOUBLE_EQ(s.weight(3.5, 0.0), std::sin(3.5) / 3.5); // negative lobe
    EXPECT_EQ(s.weight(4.0, 0.0), 0.0);
}

TEST(RenderFilter, ReachGrowsWithTheWidthAndBadFiltersAreErrors) {
    EXPECT_EQ(filter("gaussian", 2, 2).reach_x(), 1);
    EXPECT_EQ(filter("box", 1, 1).reach_x(), 0);
    EXPECT_EQ(filter("catmull-rom", 4, 3).reach_x(), 2);
    EXPECT_EQ(filter("catmull-rom", 4, 3).reach_y(), 1);
    EXPECT_EQ(filter("sinc", 16, 16).reach_y(), 8);
    EXPECT_THROW(filter("mitchell", 2, 2), sss::ValueError);
    EXPECT_THROW(filter("box", 0, 1), sss::ValueError);
    EXPECT_THROW(filter("box", 1, 16.5), sss::ValueError);
}

namespace {

/// Format 64 x 64, orthographic, screen [-1, 1]^2 (a pixel is 1/32 unit),
/// a white "constant" polygon covering x > edge (screen units).
std::string edge_rib(const std::string& filter_line, double edge, int samples = 16) {
    const std::string e = std::to_string(edge);
    return "Format 64 64 1\nPixelSamples " + std::to_string(samples) + " " +
           std::to_string(samples) + "\n" + filter_line +
           "Projection \"orthographic\"\nScreenWindow -1 1 -1 1\nTranslate 0 0 5\n"
           "WorldBegin\nSurface \"constant\"\nColor [1 1 1]\nPolygon \"P\" [" +
           e + " -4 0  " + e + " 4 0  8 4 0  8 -4 0]\nWorldEnd\n";
}

} // namespace

TEST(RenderFilter, ConstantImageStaysConstantForEveryFilter) {
    for (const char* line :
         {"", "PixelFilter \"box\" 1 1\n", "PixelFilter \"triangle\" 3 3\n",
          "PixelFilter \"catmull-rom\" 4 4\n", "PixelFilter \"gaussian\" 3 5\n",
          "PixelFilter \"sinc\" 8 8\n", "PixelFilter \"sinc\" 16 16\n",
          // Narrower than a pixel: most pixels have no sample within 0.1
          // pixel of their centre and take their nearest sample instead.
          "PixelFilter \"box\" 0.2 0.2\n"}) {
        std::string rib = "Format 40 24 1\nPixelSamples 2 2\n" + std::string(line) +
                          "Projection \"perspective\" \"fov\" 40\nTranslate 0 0 5\n"
                          "WorldBegin\nSurface \"constant\"\nColor [0.3 0.6 0.9]\n"
                          "Polygon \"P\" [-20 -20 0  -20 20 0  20 20 0  20 -20 0]\n"
                          "WorldEnd\n";
        const sss::Image img = render_rib(rib);
        for (int y = 0; y < img.height; ++y)
            for (int x = 0; x < img.width; ++x) {
                ASSERT_NEAR(value(img, x, y, "R"), 0.3f, 2e-5f) << line << x << " " << y;
                ASSERT_NEAR(value(img, x, y, "B"), 0.9f, 2e-5f) << line << x << " " << y;
                ASSERT_NEAR(value(img, x, y, "A"), 1.0f, 2e-5f) << line << x << " " << y;
            }
    }
}

TEST(RenderFilter, EdgeGivesTheFilteredCoverage) {
    // The edge at raster x = 32.3: 0.3 of the way into pixel column 32.
    const double edge = -1.0 + 32.3 / 32.0;
    // box 1 x 1: each pixel is the coverage of its own samples (16 strata in x).
    const sss::Image box = render_rib(edge_rib("PixelFilter \"box\" 1 1\n", edge));
    for (int y = 10; y < 54; y += 7) {
        EXPECT_EQ(value(box, 31, y, "A"), 0.0f);
        EXPECT_NEAR(value(box, 32, y, "A"), 0.7f, 0.02f);
        EXPECT_EQ(value(box, 33, y, "A"), 1.0f);
    }
    // triangle 2 x 2: coverage weighted by (1 - |d|): pixel 32 (centre 32.5,
    // edge at d = -0.2) sees 1 - 0.8^2 / 2 = 0.68; pixel 31 (edge at d = 0.8)
    // 0.2^2 / 2 = 0.02; pixel 33 everything.
    const sss::Image tri = render_rib(edge_rib("PixelFilter \"triangle\" 2 2\n", edge));
    for (int y = 10; y < 54; y += 7) {
        EXPECT_NEAR(value(tri, 31, y, "A"), 0.02f, 0.006f);
        EXPECT_NEAR(value(tri, 32, y, "A"), 0.68f, 0.01f);
        EXPECT_NEAR(value(tri, 33, y, "A"), 1.0f, 1e-6f);
        EXPECT_EQ(value(tri, 30, y, "A"), 0.0f);
    }
    // catmull-rom 4 x 4 overshoots beside the edge (negative lobes are not clamped).
    const sss::Image cr = render_rib(edge_rib("PixelFilter \"catmull-rom\" 4 4\n", edge));
    // Pixel 33 loses the negative lobe over the uncovered side, pixel 31
    // keeps only it from the covered side; pixel 34 is beyond r = 2.
    EXPECT_GT(value(cr, 33, 32, "A"), 1.03f);
    EXPECT_LT(value(cr, 31, 32, "A"), -0.05f);
    EXPECT_NEAR(value(cr, 32, 32, "A"), 0.78f, 0.03f);
    EXPECT_NEAR(value(cr, 34, 32, "A"), 1.0f, 1e-6f);
    EXPECT_NEAR(value(cr, 5, 32, "A"), 0.0f, 1e-6f);
    EXPECT_NEAR(value(cr, 60, 32, "A"), 1.0f, 1e-6f);
}

TEST(RenderFilter, WideFiltersAreThreadIndependent) {
    const sss::Scene scene =
        sss::parse_rib(edge_rib("PixelFilter \"sinc\" 9 9\n", 0.1, 3), "camera.rib");
    sss::Image one, two;
    {
        sss::ThreadLimit limit(1);
        one = sss::render_image(scene, {}, nullptr);
    }
    {
        sss::ThreadLimit limit(2);
        two = sss::render_image(scene, {}, nullptr);
    }
    EXPECT_EQ(one.pixels, two.pixels);
}

// ---------------------------------------------------------------------------
// The thin lens
// ---------------------------------------------------------------------------

TEST(RenderLens, SamplesAreStratifiedInsideTheLensAndDeterministic) {
    for (auto [nx, ny] : {std::pair{4, 3}, std::pair{1, 1}, std::pair{8, 8}}) {
        const auto uv = sss::lens_square_samples(12345, nx, ny);
        ASSERT_EQ(uv.size(), std::size_t(nx * ny));
        std::set<int> cells;
        for (const auto& p : uv) {
            ASSERT_GE(p.x, 0.0);
            ASSERT_LT(p.x, 1.0);
            ASSERT_GE(p.y, 0.0);
            ASSERT_LT(p.y, 1.0);
            cells.insert(int(p.y * ny) * nx + int(p.x * nx));
            const glm::dvec2 d = sss::concentric_disk(p.x, p.y);
            EXPECT_LE(d.x * d.x + d.y * d.y, 1.0 + 1e-12);
        }
        EXPECT_EQ(cells.size(), std::size_t(nx * ny)) << "one sample per stratum";
        EXPECT_EQ(sss::lens_square_samples(12345, nx, ny), uv);
    }
    // A different pixel, a different shuffle and jitter.
    EXPECT_NE(sss::lens_square_samples(1, 4, 4), sss::lens_square_samples(2, 4, 4));
    // The concentric map: centre, edges, and uniform area (mean r^2 = 1/2).
    EXPECT_EQ(sss::concentric_disk(0.5, 0.5), glm::dvec2(0.0));
    EXPECT_NEAR(sss::concentric_disk(1.0, 0.5).x, 1.0, 1e-12);
    EXPECT_NEAR(sss::concentric_disk(0.5, 1.0).y, 1.0, 1e-12);
    double r2 = 0.0;
    const int n = 200;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const glm::dvec2 d = sss::concentric_disk((i + 0.5) / n, (j + 0.5) / n);
            r2 += d.x * d.x + d.y * d.y;
        }
    EXPECT_NEAR(r2 / (n * n), 0.5, 1e-3);
}

namespace {

/// Per-axis second moment (pixels^2) of a channel around its centroid.
double spread(const sss::Image& img, const std::string& channel) {
    double w = 0, sx = 0, sy = 0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            const double v = value(img, x, y, channel);
            w += v;
            sx += v * (x + 0.5);
            sy += v * (y + 0.5);
        }
    const double cx = sx / w, cy = sy / w;
    double m = 0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            const double v = value(img, x, y, channel);
            m += v * ((x + 0.5 - cx) * (x + 0.5 - cx) + (y + 0.5 - cy) * (y + 0.5 - cy));
        }
    return 0.5 * m / w;
}

/// A white ball of radius `radius` at camera depth `depth` on the axis, 64 x
/// 64 pixels, fov 30 (screen window [-1, 1]^2), 16 x 16 samples. (Balls under
/// about 3 pixels across vanish: the dicer gives them no triangles.)
sss::Image ball(double depth, const std::string& dof, double radius = 0.1) {
    const std::string r = std::to_string(radius);
    return render_rib("Format 64 64 1\nPixelSamples 16 16\n" + dof +
                      "Projection \"perspective\" \"fov\" 30\nWorldBegin\n"
                      "Surface \"constant\"\nTranslate 0 0 " +
                      std::to_string(depth) + "\nSphere " + r + " -" + r + " " + r +
                      " 360\nWorldEnd\n");
}

} // namespace

TEST(RenderLens, BlurDiscMatchesTheThinLensCircleOfConfusion) {
    // fstop 1, focallength 1, focaldistance D = 6; the ball at d = 3.
    // RISpec's circle of confusion on the film, C = (f/n) f |d - D| / (d (D - f))
    // = 0.2, lies on the film at the image distance v = f D / (D - f) = 1.2: it
    // subtends C / v = (f/n) |d - D| / (d D) = 1/6 on the plane z = 1, which
    // is 1/6 / tan(15 deg) screen units, 32 pixels per screen unit.
    const double f = 1.0, n = 1.0, D = 6.0, d = 3.0;
    const double C = (f / n) * f * std::abs(d - D) / (d * (D - f));
    const double v = f * D / (D - f);
    const double expected = C / v / std::tan(15.0 * M_PI / 180.0) * 32.0; // 19.9 px
    const std::string dof = "DepthOfField 1 1 6\n";
    const double sharp = spread(ball(d, ""), "A");
    const double blurred = spread(ball(d, dof), "A");
    // A uniform disc of diameter w has a per-axis second moment w^2 / 16; the
    // blur convolves the sharp image with it, so the moments add.
    const double measured = 4.0 * std::sqrt(blurred - sharp);
    EXPECT_NEAR(measured, expected, 0.04 * expected) << "sharp " << sharp;
    // At the focal distance the ball stays sharp.
    const double at_focus_pinhole = spread(ball(D, ""), "A");
    const double at_focus_lens = spread(ball(D, dof), "A");
    EXPECT_NEAR(at_focus_lens, at_focus_pinhole, 0.05 * at_focus_pinhole);
    // Beyond the focal plane: d = 12, (f/n)|d - D|/(d D) = 1/12.
    const double far_expected = (1.0 / 12.0) / std::tan(15.0 * M_PI / 180.0) * 32.0;
    const double far =
        4.0 * std::sqrt(spread(ball(12, dof, 0.2), "A") - spread(ball(12, "", 0.2), "A"));
    EXPECT_NEAR(far, far_expected, 0.05 * far_expected);
}

TEST(RenderLens, DepthIsTheCameraZAndRendersAreThreadIndependent) {
    const sss::Scene scene = sss::parse_rib(
        "Format 32 32 1\nPixelSamples 3 3\nDepthOfField 2 1 4\n"
        "Projection \"perspective\" \"fov\" 30\nWorldBegin\nSurface \"constant\"\n"
        "Polygon \"P\" [-9 -9 7  -9 9 7  9 9 7  9 -9 7]\nWorldEnd\n",
        "camera.rib");
    sss::Image one, two;
    {
        sss::ThreadLimit limit(1);
        one = sss::render_image(scene, {}, nullptr);
    }
    {
        sss::ThreadLimit limit(2);
        two = sss::render_image(scene, {}, nullptr);
    }
    EXPECT_EQ(one.pixels, two.pixels);
    // Rays from the lens still report the hit's camera-space z.
    EXPECT_NEAR(value(one, 16, 16, "Z"), 7.0f, 1e-4f);
    EXPECT_NEAR(value(one, 0, 0, "Z"), 7.0f, 1e-4f);
}
