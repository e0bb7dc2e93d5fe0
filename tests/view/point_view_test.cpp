// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// Unit tests for the view module: where a disc lands and how large it is,
// the z-buffer, false colour, contact sheets, thread-count independence and
// channel errors.

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "sss/cloud/synthetic.h"
#include "sss/util/error.h"
#include "sss/util/threads.h"
#include "sss/view/point_view.h"

namespace {

/// A pinhole at the origin looking down +z (RenderMan eye space): raster
/// x = W/2 + f x/z, y = H/2 - f y/z.
sss::ViewCamera pinhole(int width, int height, double f) {
    sss::ViewCamera cam;
    cam.width = width;
    cam.height = height;
    glm::dmat4 proj(0.0);
    proj[0][0] = f;
    proj[2][0] = 0.5 * width;
    proj[1][1] = -f;
    proj[2][1] = 0.5 * height;
    proj[2][2] = 1.0;
    proj[2][3] = 1.0;
    cam.world_to_raster = proj;
    cam.min_w = 1e-6;
    return cam;
}

/// A cloud of discs with a float channel "v".
sss::PointCloud discs(const std::vector<glm::vec3>& p, const std::vector<glm::vec3>& n,
                      const std::vector<float>& r, const std::vector<float>& v) {
    sss::PointCloud c;
    c.add_channel("v", sss::ChannelType::Float);
    c.resize(p.size());
    for (std::size_t i = 0; i < p.size(); ++i) {
        c.positions[i] = p[i];
        c.normals[i] = n[i];
        c.radii[i] = r[i];
        c.channels[0].data[i] = v[i];
    }
    return c;
}

struct Coverage {
    std::size_t pixels = 0;
    double cx = 0.0, cy = 0.0; ///< centroid of the covered pixel centres
    int x0 = 1 << 30, x1 = -1, y0 = 1 << 30, y1 = -1;
};

Coverage coverage(const sss::ViewTile& t) {
    Coverage c;
    for (int y = 0; y < t.height; ++y)
        for (int x = 0; x < t.width; ++x)
            if (t.covered(std::size_t(y) * t.width + x)) {
                ++c.pixels;
                c.cx += x + 0.5;
                c.cy += y + 0.5;
                c.x0 = std::min(c.x0, x);
                c.x1 = std::max(c.x1, x);
                c.y0 = std::min(c.y0, y);
                c.y1 = std::max(c.y1, y);
            }
    if (c.pixels) {
        c.cx /= double(c.pixels);
        c.cy /= double(c.pixels);
    }
    return c;
}

TEST(PointView, SingleDiscLandsAtItsProjectionWithItsProjectedRadius) {
    // Radius 2 at distance 10 with f = 100: 20 pixels. Centre x = 3 -> 30 px
    // right of the middle, y = -1 -> 10 px below it.
    const sss::PointCloud c = discs({{3, -1, 10}}, {{0, 0, -1}}, {2}, {1});
    const sss::ViewTile t =
        sss::render_view_tile(c, {"v", false}, pinhole(201, 151, 100.0), 1.0f, "disc");
    const Coverage cov = coverage(t);
    EXPECT_NEAR(cov.cx, 100.5 + 30.0, 0.05);
    EXPECT_NEAR(cov.cy, 75.5 + 10.0, 0.05);
    // A disc of radius 20 widened by the half-pixel minimum: r^2 = 400.5.
    // (The disc is off-axis, so its image is very slightly elliptical.)
    EXPECT_NEAR(double(cov.pixels), M_PI * 400.5, 0.02 * M_PI * 400.5);
    EXPECT_NEAR(cov.x1 - cov.x0 + 1, 40, 1);
    EXPECT_NEAR(cov.y1 - cov.y0 + 1, 40, 1);
    EXPECT_EQ(t.points_drawn, 1u);
    EXPECT_EQ(t.value[std::size_t(85) * 201 + 130].x, 1.0f);
}

TEST(PointView, PointsBehindTheEyeAreNotDrawn) {
    // An orthographic camera (w = 1 everywhere): raster x = 10 + x, y = 10 - y.
    sss::ViewCamera cam;
    cam.width = cam.height = 21;
    cam.world_to_raster[1][1] = -1.0;
    cam.world_to_raster[3][0] = cam.world_to_raster[3][1] = 10.0;
    const sss::PointCloud c =
        discs({{0, 0, -1}, {5, 0, 1}}, {{0, 0, -1}, {0, 0, -1}}, {2, 2}, {1, 2});
    const sss::ViewTile t = sss::render_view_tile(c, {"v", false}, cam, 1.0f, "ortho");
    EXPECT_EQ(t.points_drawn, 1u);
    EXPECT_FALSE(t.covered(10 * 21 + 10));
    EXPECT_EQ(t.value[10 * 21 + 15].x, 2.0f);
}

TEST(PointView, TiltedDiscIsAnEllipse) {
    // Tilted 60 degrees about x: the vertical axis shrinks to cos 60 = 1/2.
    const double a = 60.0 * M_PI / 180.0;
    const sss::PointCloud c =
        discs({{0, 0, 10}}, {{0, std::sin(a), -std::cos(a)}}, {2}, {1});
    const Coverage cov = coverage(
        sss::render_view_tile(c, {"v", false}, pinhole(101, 101, 100.0), 1.0f, "d"));
    EXPECT_NEAR(cov.x1 - cov.x0 + 1, 40, 1.5);
    EXPECT_NEAR(cov.y1 - cov.y0 + 1, 20, 1.5);
}

TEST(PointView, SphereWithoutNormalIsARoundDisc) {
    const sss::PointCloud c = discs({{0, 0, 10}}, {{0, 0, 0}}, {1}, {1});
    const Coverage cov = coverage(
        sss::render_view_tile(c, {"v", false}, pinhole(101, 101, 100.0), 1.0f, "s"));
    EXPECT_NEAR(double(cov.pixels), M_PI * 100.5, 0.03 * M_PI * 100.5);
}

TEST(PointView, NearerDiscWinsWhateverTheOrder) {
    for (int order = 0; order < 2; ++order) {
        std::vector<glm::vec3> p = {{0, 0, 20}, {0, 0, 10}};
        std::vector<float> v = {2.0f, 1.0f};
        if (order) {
            std::swap(p[0], p[1]);
            std::swap(v[0], v[1]);
        }
        // Same screen size: radius proportional to distance.
        const std::vector<float> r = {p[0].z / 5.0f, p[1].z / 5.0f};
        const sss::PointCloud c = discs(p, {{0, 0, -1}, {0, 0, -1}}, r, v);
        const sss::ViewTile t =
            sss::render_view_tile(c, {"v", false}, pinhole(101, 101, 100.0), 1.0f, "two");
        for (std::size_t k = 0; k < t.point.size(); ++k) {
            if (t.covered(k)) {
                ASSERT_EQ(t.value[k].x, 1.0f) << "order " << order;
            }
        }
        EXPECT_GT(coverage(t).pixels, 1000u);
    }
}

TEST(PointView, TiltedDiscBehindAnotherShowsOnlyWhereItIsNearer) {
    // A disc facing the camera at z = 10 and a steep one through z = 10 that
    // leans: it is nearer only on one half.
    const double a = 45.0 * M_PI / 180.0;
    const sss::PointCloud c =
        discs({{0, 0, 10}, {0, 0, 10.0001f}},
              {{0, 0, -1}, {0, std::sin(a), -std::cos(a)}}, {2, 2}, {1, 2});
    const sss::ViewTile t =
        sss::render_view_tile(c, {"v", false}, pinhole(101, 101, 100.0), 1.0f, "tilt");
    // Its plane is z = 10 + y: below the middle (eye y < 0, the image's lower
    // half) it is nearer than the facing disc, above it farther.
    EXPECT_EQ(t.value[std::size_t(50 - 8) * 101 + 50].x, 1.0f);
    EXPECT_EQ(t.value[std::size_t(50 + 8) * 101 + 50].x, 2.0f);
}

TEST(PointView, FalseColourOfNegativeValues) {
    using sss::ViewValueKind;
    const glm::vec3 neg =
        sss::displayed_value(glm::vec3(-0.5f), ViewValueKind::Grey, 1.0, true);
    EXPECT_FLOAT_EQ(neg.x, 1.0f * sss::kNegativeHue[0]);
    EXPECT_FLOAT_EQ(neg.y, 1.0f * sss::kNegativeHue[1]);
    EXPECT_FLOAT_EQ(neg.z, 1.0f * sss::kNegativeHue[2]);
    EXPECT_GT(neg.z, 2.0f * neg.x); // blue
    // Without false colour the value is only exposed.
    EXPECT_FLOAT_EQ(
        sss::displayed_value(glm::vec3(-0.5f), ViewValueKind::Grey, 1.0, false).x, -1.0f);
    // Positive colours keep their hue; a negative component alone is cut to 0.
    const glm::vec3 pos =
        sss::displayed_value({0.5f, -0.1f, 0.25f}, ViewValueKind::Colour, 1.0, true);
    EXPECT_FLOAT_EQ(pos.x, 1.0f);
    EXPECT_FLOAT_EQ(pos.y, 0.0f);
    EXPECT_FLOAT_EQ(pos.z, 0.5f);
    // Huge values and exposures stay finite (also with false colour).
    for (bool fc : {false, true}) {
        const glm::vec3 big =
            sss::displayed_value({3e38f, -3e38f, 1.0f}, ViewValueKind::Colour, 256.0, fc);
        EXPECT_TRUE(std::isfinite(big.x) && std::isfinite(big.y) && std::isfinite(big.z));
    }
    // Normals are mapped, never exposed.
    const glm::vec3 up =
        sss::displayed_value({0, 1, 0}, ViewValueKind::Direction, 5.0, true);
    EXPECT_FLOAT_EQ(up.x, 0.5f);
    EXPECT_FLOAT_EQ(up.y, 1.0f);
}

TEST(PointView, ContactSheetLayout) {
    sss::ContactSheetLayout l = sss::contact_sheet_layout(2, 100, 50, 0, 2);
    EXPECT_EQ(l.columns, 2);
    EXPECT_EQ(l.rows, 1);
    EXPECT_EQ(l.width, 202);
    EXPECT_EQ(l.height, 50);
    EXPECT_EQ(l.tile_x(1), 102);
    EXPECT_EQ(l.tile_y(1), 0);
    l = sss::contact_sheet_layout(5, 100, 50, 0, 2);
    EXPECT_EQ(l.columns, 3);
    EXPECT_EQ(l.rows, 2);
    EXPECT_EQ(l.width, 304);
    EXPECT_EQ(l.height, 102);
    EXPECT_EQ(l.tile_x(4), 102);
    EXPECT_EQ(l.tile_y(4), 52);
    l = sss::contact_sheet_layout(3, 10, 10, 1, 0);
    EXPECT_EQ(l.width, 10);
    EXPECT_EQ(l.height, 30);
    EXPECT_THROW(sss::contact_sheet_layout(2, 40000, 10, 0, 0), sss::ValueError);
}

TEST(PointView, ContactSheetPlacesTilesWithOneExposure) {
    // Two clouds, values 2 and 4: auto exposure maps the 99.5th percentile
    // (4) to 1, the same for both tiles.
    const sss::PointCloud a = discs({{0, 0, 10}}, {{0, 0, -1}}, {5}, {2});
    const sss::PointCloud b = discs({{0, 0, 10}}, {{0, 0, -1}}, {5}, {4});
    sss::PointViewOptions opt;
    opt.background = glm::vec3(0.0f);
    const sss::PointViewImage img =
        sss::render_point_view({{&a, "a"}, {&b, "b"}}, pinhole(21, 21, 10.0), opt);
    EXPECT_EQ(img.width, 44);
    EXPECT_EQ(img.height, 21);
    EXPECT_TRUE(img.auto_exposure);
    EXPECT_DOUBLE_EQ(img.exposure, -2.0);
    EXPECT_FLOAT_EQ(img.rgb[10 * 44 + 10].x, 0.5f);      // a's centre
    EXPECT_FLOAT_EQ(img.rgb[10 * 44 + 23 + 10].x, 1.0f); // b's centre
    EXPECT_FLOAT_EQ(img.rgb[0].x, 0.0f);                 // background
    EXPECT_FLOAT_EQ(img.rgb[10 * 44 + 21].x, 0.2f);      // the gap
    ASSERT_EQ(img.tiles.size(), 2u);
    EXPECT_EQ(img.tiles[1].cloud, 1u);
    // One exposure per tile: each centre shows as 1.
    opt.exposure_per_tile = true;
    const sss::PointViewImage each =
        sss::render_point_view({{&a, "a"}, {&b, "b"}}, pinhole(21, 21, 10.0), opt);
    EXPECT_DOUBLE_EQ(each.tiles[0].exposure, -1.0);
    EXPECT_DOUBLE_EQ(each.tiles[1].exposure, -2.0);
    EXPECT_FLOAT_EQ(each.rgb[10 * 44 + 10].x, 1.0f);
    EXPECT_FLOAT_EQ(each.rgb[10 * 44 + 23 + 10].x, 1.0f);
    // A given exposure wins over both.
    opt.exposure = 0.0;
    const sss::PointViewImage fixed =
        sss::render_point_view({{&a, "a"}, {&b, "b"}}, pinhole(21, 21, 10.0), opt);
    EXPECT_FALSE(fixed.auto_exposure);
    EXPECT_FLOAT_EQ(fixed.rgb[10 * 44 + 10].x, 2.0f);
}

TEST(PointView, SameImageAtAnyThreadCount) {
    sss::SyntheticParams sp;
    sp.shape = sss::SyntheticShape::Box;
    sp.count = 200000;
    sp.jitter = 0.5;
    sss::PointCloud cloud = sss::make_synthetic_cloud(sp);
    // Duplicated points: equal depths, the lower index must win every time.
    const std::size_t n = cloud.size();
    sss::PointCloud twice = cloud;
    twice.append(cloud);
    for (std::size_t i = n; i < twice.size(); ++i)
        for (int c = 0; c < 3; ++c)
            twice.find_channel("_radiance_t")->data[3 * i + c] = -1.0f;
    const sss::ViewCamera cam =
        sss::orbit_camera(twice.bounds(), 30, 20, 1, 30, 256, 256);
    std::vector<uint32_t> first;
    std::vector<glm::vec3> first_value;
    for (int threads : {1, 2, 4}) {
        const sss::ThreadLimit limit(threads);
        const sss::ViewTile t =
            sss::render_view_tile(twice, {"_radiance_t", false}, cam, 1.0f, "box");
        if (first.empty()) {
            first = t.point;
            first_value = t.value;
            for (uint32_t p : first) ASSERT_TRUE(p == sss::ViewTile::kNoPoint || p < n);
        } else {
            EXPECT_EQ(t.point, first) << threads << " threads";
            EXPECT_TRUE(t.value == first_value) << threads << " threads";
        }
    }
}

TEST(PointView, MissingChannelNamesTheChannelsTheCloudHas) {
    sss::SyntheticParams sp;
    sp.count = 100;
    const sss::PointCloud c = sss::make_synthetic_cloud(sp);
    try {
        sss::render_view_tile(c, {"_ssdiffusion", false}, pinhole(8, 8, 4.0), 1.0f,
                              "bake.ptc");
        FAIL() << "no error";
    } catch (const sss::ValueError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("bake.ptc"), std::string::npos) << what;
        EXPECT_NE(what.find("_ssdiffusion"), std::string::npos) << what;
        EXPECT_NE(what.find("_area, _radiance_t"), std::string::npos) << what;
    }
    // In a contact sheet a channel only some clouds have is fine; one no
    // cloud has is an error.
    const std::vector<sss::LabelledCloud> clouds = {{&c, "a.ptc"}};
    EXPECT_EQ(sss::view_tiles(clouds, {{"_area", false}, {"N", false}}).size(), 2u);
    EXPECT_THROW(sss::view_tiles(clouds, {{"_area", false}, {"nope", false}}),
                 sss::ValueError);
}

TEST(PointView, ChannelSpecs) {
    EXPECT_EQ(sss::parse_view_channel("_radiance_t").name, "_radiance_t");
    EXPECT_FALSE(sss::parse_view_channel("_radiance_t").luminance);
    const sss::ViewChannel lum = sss::parse_view_channel("_radiance_t:lum");
    EXPECT_EQ(lum.name, "_radiance_t");
    EXPECT_TRUE(lum.luminance);
    EXPECT_THROW(sss::parse_view_channel("x:red"), sss::ValueError);
    EXPECT_THROW(sss::parse_view_channel(":lum"), sss::ValueError);
}

TEST(PointView, OrbitCameraLooksAtTheCentre) {
    sss::Bounds3 b;
    b.lo = {-1, 2, -3};
    b.hi = {3, 4, 1};
    for (double az : {0.0, 45.0, 200.0})
        for (double el : {-30.0, 0.0, 60.0, 90.0}) {
            const sss::ViewCamera cam = sss::orbit_camera(b, az, el, 2, 40, 64, 48);
            const glm::dvec4 h = cam.world_to_raster * glm::dvec4(1, 3, -1, 1);
            ASSERT_GT(h.w, 0.0);
            EXPECT_NEAR(h.x / h.w, 32.0, 1e-9) << az << " " << el;
            EXPECT_NEAR(h.y / h.w, 24.0, 1e-9) << az << " " << el;
            // Every corner is in the frame.
            for (int k = 0; k < 8; ++k) {
                const glm::dvec4 c =
                    cam.world_to_raster *
                    glm::dvec4((k & 1) ? 3 : -1, (k & 2) ? 4 : 2, (k & 4) ? 1 : -3, 1);
                EXPECT_GE(c.x / c.w, 0.0);
                EXPECT_LE(c.x / c.w, 64.0);
                EXPECT_GE(c.y / c.w, 0.0);
                EXPECT_LE(c.y / c.w, 48.0);
            }
        }
    // Up z, azimuth 0, elevation 0: the viewer is on -y, +x to its right,
    // +z up.
    const sss::ViewCamera cam = sss::orbit_camera(b, 0, 0, 2, 40, 64, 48);
    const glm::dvec4 right = cam.world_to_raster * glm::dvec4(2, 3, -1, 1);
    const glm::dvec4 top = cam.world_to_raster * glm::dvec4(1, 3, 0, 1);
    EXPECT_GT(right.x / right.w, 32.0);
    EXPECT_LT(top.y / top.w, 24.0);
    EXPECT_LT((cam.world_to_eye * glm::dvec4(1, 2, -1, 1)).z,
              (cam.world_to_eye * glm::dvec4(1, 4, -1, 1)).z);
}

TEST(PointView, FileCameraProjectsThroughWorldToNdc) {
    // world2ndc: x_ndc = 0.5 + x / 20, y_ndc = 0.5 - y / 20 (orthographic), a
    // 2:1 frame in a 100 x 100 image: the frame is 100 x 50, 25 pixels down.
    sss::PointCloud c = discs({{5, 0, 0}}, {{0, 0, 1}}, {1}, {1});
    c.world_to_ndc = {0.05f, 0, 0, 0, 0, -0.05f, 0, 0, 0, 0, 1, 0, 0.5f, 0.5f, 0, 1};
    c.format = {200, 100, 1};
    ASSERT_TRUE(sss::has_file_camera(c));
    EXPECT_DOUBLE_EQ(sss::file_camera_aspect(c), 2.0);
    const sss::ViewCamera cam = sss::file_camera(c, 100, 100, "f");
    const glm::dvec4 h = cam.world_to_raster * glm::dvec4(5, 0, 0, 1);
    EXPECT_NEAR(h.x / h.w, 75.0, 1e-4); // the matrix is stored in floats
    EXPECT_NEAR(h.y / h.w, 50.0, 1e-4);
    sss::PointCloud none = c;
    none.world_to_ndc = sss::PointCloud().world_to_ndc;
    EXPECT_FALSE(sss::has_file_camera(none));
    EXPECT_THROW(sss::file_camera(none, 10, 10, "none"), sss::ValueError);
}

} // namespace
