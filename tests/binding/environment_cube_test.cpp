// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file environment_cube_test.cpp
/// environment() on OpenEXR cube-face maps (six N x N faces stacked +X, -X,
/// +Y, -Y, +Z, -Z in an N x 6N image, the "envmap" attribute = cube), which
/// the texture plugin looks up itself: the faces along the axes, the
/// per-face orientation checked against OpenEXR's own Imf::CubeMap
/// functions, agreement with a lat-long map of the same environment, the
/// footprint (a wide one averages and stays on its face), and malformed
/// cube maps as errors.
///
/// Suite names start with "RslEnvironment".

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <OpenEXR/ImfEnvmap.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfStandardAttributes.h>
#include <OpenImageIO/imageio.h>
#include <glm/geometric.hpp>

#include "shading/engine_test_util.h"
#include "sss/binding/texture_library.h"
#include "sss/light/light_dome.h"
#include "test_util.h"

namespace {

using namespace sss;
using namespace sss::test;
using sss::TextureLibrary;
using sss::TextureOptions;

/// Colour of pixel (x, y) of face `face` (y = 0 the face's top row).
using FacePixel = std::function<glm::vec3(int face, int x, int y)>;

/// Writes a float RGB OpenEXR of w x h pixels, pixel (x, y) = f(y / w, x, y
/// % w), tagged as OIIO's "CubeFace Environment" (OIIO writes that as
/// OpenEXR's envmap = cube).
std::string write_cube(const TempDir& dir, const std::string& name, int w, int h,
                       const FacePixel& f) {
    const std::string path = dir.file(name);
    std::vector<float> px(static_cast<std::size_t>(w) * h * 3);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const glm::vec3 c = f(y / w, x, y % w);
            for (int k = 0; k < 3; ++k)
                px[(static_cast<std::size_t>(y) * w + x) * 3 + k] = c[k];
        }
    OIIO::ImageSpec spec(w, h, 3, OIIO::TypeDesc::FLOAT);
    spec.attribute("textureformat", "CubeFace Environment");
    auto out = OIIO::ImageOutput::create(path);
    EXPECT_TRUE(out && out->open(path, spec) &&
                out->write_image(OIIO::TypeDesc::FLOAT, px.data()) && out->close())
        << path;
    return path;
}

/// `file` made a tiled, MIP-mapped texture by maketx (TIFF for .tx, else
/// OpenEXR), the cube tag restored with --attrib (maketx writes "Plain
/// Texture" otherwise); "" when maketx is missing.
std::string maketx_cube(const std::string& file, const std::string& out) {
    if (!std::filesystem::exists("/usr/bin/maketx")) return "";
    const std::string cmd =
        "/usr/bin/maketx -d float --filter box --attrib textureformat "
        "'CubeFace Environment' -o '" +
        out + "' '" + file + "' >/dev/null 2>&1";
    EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
    return out;
}

/// environment(map, dir) through the shading engine, point lookups.
std::vector<glm::vec3> engine_lookup(const std::string& map,
                                     const std::vector<glm::vec3>& dirs) {
    TextureLibrary textures;
    return environment_lookups(textures, map, dirs);
}

/// TextureLibrary::environment for each direction with the derivatives
/// (null: point lookups).
std::vector<glm::vec3> lib_lookup(TextureLibrary& lib, const std::string& map,
                                  const std::vector<glm::vec3>& dirs,
                                  const std::vector<glm::vec3>* du = nullptr,
                                  const std::vector<glm::vec3>* dv = nullptr) {
    std::vector<glm::vec3> out(dirs.size(), glm::vec3(-1.0f));
    std::string error;
    EXPECT_TRUE(lib.environment(map, 0, 3, TextureOptions{}, dirs.size(), dirs.data(),
                                du ? du->data() : nullptr, dv ? dv->data() : nullptr,
                                nullptr, &out[0].x, &error))
        << error;
    return out;
}

/// Random unit directions (fixed seed).
std::vector<glm::vec3> random_directions(int count, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f), phi(0.0f, 6.2831853f);
    std::vector<glm::vec3> dirs;
    while (static_cast<int>(dirs.size()) < count) {
        const float z = u(rng), a = phi(rng), r = std::sqrt(1.0f - z * z);
        dirs.emplace_back(r * std::cos(a), r * std::sin(a), z);
    }
    return dirs;
}

TEST(RslEnvironmentCube, TheFileIsAnOpenExrCubeMap) {
    TempDir dir;
    const std::string file =
        write_cube(dir, "tag.exr", 4, 24, [](int, int, int) { return glm::vec3(1.0f); });
    Imf::InputFile in(file.c_str());
    ASSERT_TRUE(Imf::hasEnvmap(in.header()));
    EXPECT_EQ(Imf::envmap(in.header()), Imf::ENVMAP_CUBE);
}

TEST(RslEnvironmentCube, EachAxisSeesItsFace) {
    TempDir dir;
    const glm::vec3 colours[6] = {{1, 0, 0},   {0, 1, 0},    {0, 0, 1},
                                  {10, 20, 0}, {0.5f, 3, 7}, {100, 0.25f, 1}};
    const std::string file =
        write_cube(dir, "const.exr", 8, 48, [&](int f, int, int) { return colours[f]; });
    // Along the axes, and towards the corners of each face: each face's own
    // colour exactly (HDR values unchanged, nothing from the faces next to
    // it in the image).
    std::vector<glm::vec3> dirs;
    std::vector<int> face;
    for (int f = 0; f < 6; ++f) {
        glm::vec3 axis(0.0f);
        axis[f / 2] = f % 2 ? -1.0f : 1.0f;
        const int a = (f / 2 + 1) % 3, b = (f / 2 + 2) % 3;
        for (glm::vec2 o :
             {glm::vec2(0, 0), glm::vec2(0.99f, 0.99f), glm::vec2(-0.99f, 0.99f),
              glm::vec2(0.99f, -0.99f), glm::vec2(-0.99f, -0.99f)}) {
            glm::vec3 d = axis;
            d[a] = o.x;
            d[b] = o.y;
            dirs.push_back(d);
            face.push_back(f);
        }
    }
    const std::vector<glm::vec3> got = engine_lookup(file, dirs);
    for (std::size_t i = 0; i < dirs.size(); ++i)
        for (int k = 0; k < 3; ++k)
            EXPECT_NEAR(got[i][k], colours[face[i]][k], 1e-5f * colours[face[i]][k])
                << "direction " << i << " face " << face[i];
}

TEST(RslEnvironmentCube, OrientationIsOpenExrs) {
    TempDir dir;
    constexpr int n = 17;
    // R, G: the pixel's column and row in its face, B: the face. Bilinear
    // lookups reproduce the ramps exactly, so each lookup tells the pixel
    // position it read.
    const std::string file =
        write_cube(dir, "ramp.exr", n, 6 * n, [](int f, int x, int y) {
            return glm::vec3(float(x), float(y), float(f));
        });
    TextureLibrary lib;
    // Worked out by hand from ImfEnvmap.h's diagram: on +X the image's
    // right is +z and its bottom -y; on +Z right is -x; on +Y the bottom
    // is -z; on -Y it is +z. Pixel centres 0 and n - 1 are the cube's edges.
    const std::vector<glm::vec3> dirs = {
        {1, 0.5f, 0}, {0.5f, 0, 1}, {0.5f, 1, 0.5f}, {0.5f, -1, 0.5f}, {-1, 0, 0.5f}};
    const glm::vec3 want[] = {{8, 4, 0}, {4, 8, 4}, {12, 4, 2}, {12, 12, 3}, {4, 8, 1}};
    std::vector<std::string> maps = {file};
    // The same map tiled and MIP-mapped by maketx: as TIFF (OIIO's
    // coordinates from the image's edges) and as OpenEXR (from the border
    // pixels' centres, "oiio:sampleborder").
    for (const std::string& out : {dir.file("ramp.tx"), dir.file("ramp_tx.exr")})
        if (const std::string tx = maketx_cube(file, out); !tx.empty())
            maps.push_back(tx);
    for (const std::string& map : maps) {
        const std::vector<glm::vec3> got = lib_lookup(lib, map, dirs);
        for (std::size_t i = 0; i < dirs.size(); ++i)
            for (int k = 0; k < 3; ++k)
                EXPECT_NEAR(got[i][k], want[i][k], 1e-4f) << map << " " << i;
    }

    // Random directions against OpenEXR's faceAndPixelPosition.
    const Imath::Box2i dw(Imath::V2i(0, 0), Imath::V2i(n - 1, 6 * n - 1));
    std::vector<glm::vec3> rand;
    for (const glm::vec3& d : random_directions(400, 7)) {
        // Not within a hair of the cube's edges, where the face is a tie.
        glm::vec3 m = glm::abs(d);
        std::sort(&m.x, &m.x + 3);
        if (m.z - m.y > 0.01f) rand.push_back(d);
    }
    int checked = 0;
    for (const std::string& map : maps) {
        const std::vector<glm::vec3> got_rand = lib_lookup(lib, map, rand);
        for (std::size_t i = 0; i < rand.size(); ++i) {
            Imf::CubeMapFace face;
            Imath::V2f pif;
            Imf::CubeMap::faceAndPixelPosition(
                Imath::V3f(rand[i].x, rand[i].y, rand[i].z), dw, face, pif);
            const Imath::V2f pos = Imf::CubeMap::pixelPosition(face, dw, pif);
            const glm::vec3 w(pos.x, pos.y - float(int(face) * n), float(int(face)));
            for (int k = 0; k < 3; ++k)
                EXPECT_NEAR(got_rand[i][k], w[k], 2e-3f)
                    << map << " direction " << rand[i].x << "," << rand[i].y << ","
                    << rand[i].z;
            ++checked;
        }
    }
    EXPECT_GT(checked, 350 * static_cast<int>(maps.size()));
}

/// A smooth environment: colour as a function of the unit direction.
glm::vec3 sky(const glm::vec3& d) {
    return {1.0f + 0.5f * d.x + 0.25f * d.y * d.z, 1.0f + 0.5f * d.y,
            1.0f + 0.5f * d.z + 0.3f * d.x * d.x};
}

TEST(RslEnvironmentCube, AgreesWithTheLatLongMapOfTheSameSky) {
    TempDir dir;
    // The lat-long map: pixel centres' directions by light_dome.h.
    constexpr int lw = 256, lh = 128;
    std::vector<float> ll(lw * lh * 3);
    for (int y = 0; y < lh; ++y)
        for (int x = 0; x < lw; ++x) {
            const glm::vec3 c =
                sky(glm::vec3(latlong_direction((x + 0.5) / lw, (y + 0.5) / lh)));
            for (int k = 0; k < 3; ++k) ll[(y * lw + x) * 3 + k] = c[k];
        }
    const std::string latlong = dir.file("sky_latlong.exr");
    {
        OIIO::ImageSpec spec(lw, lh, 3, OIIO::TypeDesc::FLOAT);
        auto out = OIIO::ImageOutput::create(latlong);
        ASSERT_TRUE(out && out->open(latlong, spec) &&
                    out->write_image(OIIO::TypeDesc::FLOAT, ll.data()) && out->close());
    }
    // The cube map: pixel centres' directions by OpenEXR's CubeMap::direction
    // (image pixel -> position in face by inverting its pixelPosition, a
    // flip or transposition per face).
    constexpr int n = 32;
    const Imath::Box2i dw(Imath::V2i(0, 0), Imath::V2i(n - 1, 6 * n - 1));
    const std::string cube =
        write_cube(dir, "sky_cube.exr", n, 6 * n, [&](int f, int x, int y) {
            const auto face = Imf::CubeMapFace(f);
            const Imath::V2f p0 = Imf::CubeMap::pixelPosition(face, dw, Imath::V2f(0, 0));
            const Imath::V2f ex =
                Imf::CubeMap::pixelPosition(face, dw, Imath::V2f(1, 0)) - p0;
            const Imath::V2f ey =
                Imf::CubeMap::pixelPosition(face, dw, Imath::V2f(0, 1)) - p0;
            const Imath::V2f r = Imath::V2f(float(x), float(f * n + y)) - p0;
            const Imath::V2f pif(r.dot(ex), r.dot(ey)); // ex, ey: signed unit axes
            const Imath::V3f d = Imf::CubeMap::direction(face, dw, pif).normalized();
            return sky(glm::vec3(d.x, d.y, d.z));
        });
    TextureLibrary lib;
    const std::vector<glm::vec3> dirs = random_directions(300, 11);
    const std::vector<glm::vec3> from_cube = lib_lookup(lib, cube, dirs);
    const std::vector<glm::vec3> from_latlong = lib_lookup(lib, latlong, dirs);
    float worst = 0.0f;
    for (std::size_t i = 0; i < dirs.size(); ++i) {
        const glm::vec3 exact = sky(glm::normalize(dirs[i]));
        for (int k = 0; k < 3; ++k) {
            EXPECT_NEAR(from_cube[i][k], exact[k], 2e-3f) << i << " channel " << k;
            EXPECT_NEAR(from_cube[i][k], from_latlong[i][k], 5e-3f)
                << i << " channel " << k;
            worst = std::max(worst, std::abs(from_cube[i][k] - exact[k]));
        }
    }
    // And the lookups are the sky's, not a mirror image of it: along +x
    // red is 1.5, along -x 0.5.
    const std::vector<glm::vec3> axes = lib_lookup(lib, cube, {{1, 0, 0}, {-1, 0, 0}});
    EXPECT_NEAR(axes[0].x, 1.5f, 1e-3f);
    EXPECT_NEAR(axes[1].x, 0.5f, 1e-3f);
    RecordProperty("worst_cube_error", std::to_string(worst));
}

TEST(RslEnvironmentCube, AWideFootprintAveragesWithinItsFace) {
    TempDir dir;
    constexpr int n = 16;
    // +X: a checkerboard of 0 and 2; -X (below it in the image) 100; the
    // others 50.
    const std::string file =
        write_cube(dir, "checker.exr", n, 6 * n, [](int f, int x, int y) {
            if (f == 0) return glm::vec3(float(((x + y) % 2) * 2));
            return glm::vec3(f == 1 ? 100.0f : 50.0f);
        });
    TextureLibrary lib;
    // (1, 1/3, -1/3) is the centre of +X's pixel (5, 5): 0.
    const glm::vec3 centre(1.0f, 1.0f / 3.0f, -1.0f / 3.0f);
    const glm::vec3 near_bottom(1.0f, -0.97f,
                                0.2f); // by the -y edge (next to -X in the image)
    const glm::vec3 near_top(1.0f, 0.97f, -0.2f); // by the image's top edge
    const std::vector<glm::vec3> dirs = {centre, centre, near_bottom, near_top, centre};
    const glm::vec3 zero(0.0f);
    // Point lookup; then a cone of about 4 pixels, then one wider than the face.
    const std::vector<glm::vec3> du = {
        zero, {0, 0.5f, 0}, {0, 0.5f, 0}, {0, 0.5f, 0}, {0, 4.0f, 0}};
    const std::vector<glm::vec3> dv = {
        zero, {0, 0, 0.5f}, {0, 0, 0.5f}, {0, 0, 0.5f}, {0, 0, 4.0f}};
    const std::vector<glm::vec3> got = lib_lookup(lib, file, dirs, &du, &dv);
    EXPECT_NEAR(got[0].x, 0.0f, 1e-5f);
    EXPECT_NEAR(got[1].x, 1.0f, 0.2f); // the checker's mean
    EXPECT_NEAR(got[2].x, 1.0f, 0.2f); // the same, nothing of -X's 100
    EXPECT_NEAR(got[3].x, 1.0f, 0.2f);
    EXPECT_NEAR(got[4].x, 1.0f, 0.1f);
    for (const glm::vec3& c : got) EXPECT_TRUE(std::isfinite(c.x) && std::isfinite(c.y));

    // Nothing of the faces next to it in the image: +X constant 1, -X 100.
    const std::string flat = write_cube(dir, "flat.exr", n, 6 * n, [](int f, int, int) {
        return glm::vec3(f == 0 ? 1.0f : (f == 1 ? 100.0f : 50.0f));
    });
    std::vector<std::string> flats = {flat};
    for (const std::string& out : {dir.file("flat.tx"), dir.file("flat_tx.exr")})
        if (const std::string tx = maketx_cube(flat, out); !tx.empty())
            flats.push_back(tx);
    for (const std::string& map : flats)
        for (float w : {0.0f, 0.1f, 0.25f, 0.5f, 1.0f, 4.0f, 100.0f}) {
            const std::vector<glm::vec3> wide_du(dirs.size(), glm::vec3(0, w, 0));
            const std::vector<glm::vec3> wide_dv(dirs.size(), glm::vec3(0, 0, w));
            const std::vector<glm::vec3> f =
                lib_lookup(lib, map, dirs, &wide_du, &wide_dv);
            for (std::size_t i = 0; i < dirs.size(); ++i)
                EXPECT_NEAR(f[i].x, 1.0f, 1e-4f)
                    << map << " width " << w << " direction " << i;
            // Blur, up to wider than the cube.
            TextureOptions blur_only;
            blur_only.sblur = blur_only.tblur = w;
            std::vector<glm::vec3> b(dirs.size(), glm::vec3(-1.0f));
            ASSERT_TRUE(lib.environment(map, 0, 3, blur_only, dirs.size(), dirs.data(),
                                        nullptr, nullptr, nullptr, &b[0].x, nullptr));
            for (std::size_t i = 0; i < dirs.size(); ++i)
                EXPECT_NEAR(b[i].x, 1.0f, 1e-4f)
                    << map << " blur " << w << " direction " << i;
        }

    // "blur" widens too (face units, both ways).
    TextureOptions blurred;
    blurred.sblur = blurred.tblur = 0.5f;
    glm::vec3 out(-1.0f);
    std::string error;
    ASSERT_TRUE(lib.environment(file, 0, 3, blurred, 1, &centre, nullptr, nullptr,
                                nullptr, &out.x, &error))
        << error;
    EXPECT_NEAR(out.x, 1.0f, 0.2f);

    // The same values from several threads.
    const std::vector<glm::vec3> many = random_directions(2000, 3);
    std::vector<glm::vec3> many_du(many.size(), glm::vec3(0.05f, 0.0f, 0.0f));
    const std::vector<glm::vec3> serial = lib_lookup(lib, file, many, &many_du, &many_du);
    std::vector<glm::vec3> parallel(many.size());
    std::vector<std::thread> threads;
    for (int k = 0; k < 4; ++k)
        threads.emplace_back([&, k] {
            for (std::size_t i = k; i < many.size(); i += 4)
                lib.environment(file, 0, 3, TextureOptions{}, 1, &many[i], &many_du[i],
                                &many_du[i], nullptr, &parallel[i].x, nullptr);
        });
    for (std::thread& t : threads) t.join();
    for (std::size_t i = 0; i < many.size(); ++i) ASSERT_EQ(parallel[i], serial[i]) << i;
}

TEST(RslEnvironmentCube, AMalformedCubeMapIsAnError) {
    TempDir dir;
    auto grey = [](int, int, int) { return glm::vec3(0.5f); };
    const std::string five = write_cube(dir, "five.exr", 8, 40, grey);
    const std::string three_by_two = write_cube(dir, "three_by_two.exr", 24, 16, grey);
    TextureLibrary lib;
    const glm::vec3 d(0, 0, 1);
    for (const std::string& file : {five, three_by_two}) {
        glm::vec3 out(-1.0f);
        std::string error;
        EXPECT_FALSE(lib.environment(file, 0, 3, TextureOptions{}, 1, &d, nullptr,
                                     nullptr, nullptr, &out.x, &error));
        EXPECT_NE(error.find(file + ": cube-face environment map of "), std::string::npos)
            << error;
        EXPECT_NE(error.find("N x 6N"), std::string::npos) << error;
        // Still readable as a plain texture.
        const float s = 0.5f, t = 0.5f;
        EXPECT_TRUE(lib.texture(file, 0, 3, TextureOptions{}, 1, &s, &t, nullptr, nullptr,
                                nullptr, nullptr, nullptr, &out.x, &error))
            << error;
        EXPECT_NEAR(out.x, 0.5f, 1e-5f);
    }
    glm::vec3 out;
    std::string error;
    lib.environment(three_by_two, 0, 3, TextureOptions{}, 1, &d, nullptr, nullptr,
                    nullptr, &out.x, &error);
    EXPECT_NE(error.find("24 x 16 (a 3 x 2 arrangement"), std::string::npos) << error;
}

} // namespace
