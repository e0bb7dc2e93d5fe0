// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file environment_test.cpp
/// environment() on lat-long maps made by maketx --envlatl: lookups along
/// pixel-centre directions return those pixels, and the orientation agrees
/// with sss/light/light_dome.h (the envdome tool's median cut): the
/// strongest dome light of a map with one bright spot points where
/// environment() sees the spot.
///
/// Suite names start with "RslEnvironment".

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "shading/engine_test_util.h"
#include "sss/binding/texture_library.h"
#include "sss/light/light_dome.h"
#include "sss/render/image_io.h"
#include "test_util.h"

namespace {

using namespace sss;
using namespace sss::test;

/// Writes `img` as a float OpenEXR and converts it with maketx --envlatl;
/// returns the .tx path ("" when maketx is missing).
std::string make_envlatl(const LatLongImage& img, const TempDir& dir,
                         const std::string& name) {
    Image out(img.width, img.height, {"R", "G", "B"});
    out.pixels = img.rgb;
    DisplayTarget target;
    target.path = dir.file(name + ".exr");
    target.format = "openexr";
    target.channels = {"R", "G", "B"};
    target.names = {"R", "G", "B"};
    target.half = false;
    write_display(out, target, ImageMetadata{});
    if (!std::filesystem::exists("/usr/bin/maketx")) return "";
    const std::string tx = dir.file(name + ".tx");
    const std::string cmd = "/usr/bin/maketx --envlatl -d float --filter box -o '" + tx +
                            "' '" + target.path + "' >/dev/null 2>&1";
    EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
    return tx;
}

/// environment(map, dir) for each direction (world = camera space here).
std::vector<glm::vec3> lookup(const std::string& map,
                              const std::vector<glm::dvec3>& dirs) {
    TextureLibrary textures;
    return environment_lookups(textures, map,
                               std::vector<glm::vec3>(dirs.begin(), dirs.end()));
}

TEST(RslEnvironment, LatLongLookupsReturnThePixels) {
    TempDir dir;
    // Every pixel its own colour.
    LatLongImage img(32, 16);
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 32; ++x) {
            float* p = img.pixel(x, y);
            p[0] = 1.0f + x;
            p[1] = 1.0f + y;
            p[2] = 1.0f + ((x * 7 + y * 3) % 11);
        }
    const std::string tx = make_envlatl(img, dir, "known");
    if (tx.empty()) GTEST_SKIP() << "maketx not installed";
    std::vector<glm::dvec3> dirs;
    // Not the pole rows (0 and 15): there OIIO's filter widens along s.
    std::vector<std::pair<int, int>> pixels = {{0, 1},  {31, 14}, {8, 8},   {16, 7},
                                               {24, 3}, {5, 12},  {19, 10}, {27, 13}};
    for (auto [x, y] : pixels)
        dirs.push_back(latlong_direction((x + 0.5) / 32, (y + 0.5) / 16));
    const std::vector<glm::vec3> got = lookup(tx, dirs);
    for (std::size_t i = 0; i < pixels.size(); ++i) {
        const float* want = img.pixel(pixels[i].first, pixels[i].second);
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(got[i][c], want[c], 0.02f * want[c])
                << "pixel " << pixels[i].first << "," << pixels[i].second << " channel "
                << c;
    }
}

TEST(RslEnvironment, TheBrightestDomeLightPointsAtTheSpot) {
    TempDir dir;
    for (auto [bx, by] : {std::pair{10, 5}, std::pair{50, 20}, std::pair{33, 12}}) {
        LatLongImage img(64, 32);
        std::fill(img.rgb.begin(), img.rgb.end(), 0.01f);
        float* p = img.pixel(bx, by);
        p[0] = p[1] = p[2] = 100.0f;
        const std::string tx = make_envlatl(img, dir, "spot" + std::to_string(bx));
        if (tx.empty()) GTEST_SKIP() << "maketx not installed";
        const std::vector<DomeLight> lights = median_cut(img, 16);
        std::size_t best = 0;
        for (std::size_t i = 1; i < lights.size(); ++i)
            if (lights[i].color.y > lights[best].color.y) best = i;
        const glm::dvec3 d = lights[best].direction;
        // environment() sees the spot along the light's direction and not
        // along the other axes' directions.
        const std::vector<glm::vec3> got =
            lookup(tx, {d, -d, glm::dvec3(d.z, d.x, d.y), glm::dvec3(-d.x, d.y, d.z)});
        EXPECT_GT(got[0].y, 50.0f) << bx << "," << by;
        EXPECT_LT(got[1].y, 0.1f);
        EXPECT_LT(got[2].y, 0.1f);
        if (std::abs(d.x) > 0.2) {
            EXPECT_LT(got[3].y, 0.1f);
        } // mirrored in x: elsewhere
    }
}

} // namespace
