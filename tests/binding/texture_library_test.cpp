// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file texture_library_test.cpp
/// The shading module's texture library: RSL texture options, 2-D lookups
/// through OpenImageIO (pixel centres, channels, fill, grey as colour, blur,
/// wrap modes, MIP-mapped .tx files, the four-point form), missing files,
/// textureinfo, lat-long environment maps, and texture3d on brick maps and
/// point clouds.

#include <gtest/gtest.h>

#include "test_util.h"

#include <array>
#include <cmath>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

#include "sss/binding/bake3d_file.h"
#include "sss/binding/texture_library.h"
#include "sss/brick/brickmap.h"
#include "sss/cloud/point_cloud.h"
#include "sss/cloud/point_cloud_io.h"
#include "sss/util/error.h"

using sss::TextureLibrary;
using sss::TextureOptions;
using sss::test::TempDir;

namespace {

constexpr int kWidth = 64, kHeight = 32;
constexpr float kPi = 3.14159265358979f;

/// The test image's channel c at pixel (x, y) (y = 0 the top row): distinct
/// gradients per channel.
float pixel(int x, int y, int c) {
    switch (c) {
    case 0:
        return (x + 0.5f) / kWidth;
    case 1:
        return (y + 0.5f) / kHeight;
    default:
        return 0.25f + 0.01f * float((x + 3 * y) % 17);
    }
}

/// Writes a float image of `channels` channels with pixel() values.
std::string write_gradient(const TempDir& dir, const std::string& name, int channels) {
    OIIO::ImageSpec spec(kWidth, kHeight, channels, OIIO::TypeDesc::FLOAT);
    OIIO::ImageBuf buf(spec);
    for (int y = 0; y < kHeight; ++y)
        for (int x = 0; x < kWidth; ++x) {
            float v[4];
            for (int c = 0; c < channels; ++c) v[c] = pixel(x, y, c);
            buf.setpixel(x, y, v, channels);
        }
    const std::string path = dir.file(name);
    EXPECT_TRUE(buf.write(path)) << buf.geterror();
    return path;
}

/// A 1-channel checkerboard of `cell`-pixel squares, 0 and 1.
OIIO::ImageBuf checkerboard(int size, int cell) {
    OIIO::ImageBuf buf(OIIO::ImageSpec(size, size, 1, OIIO::TypeDesc::FLOAT));
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const float v = float(((x / cell) + (y / cell)) % 2);
            buf.setpixel(x, y, &v, 1);
        }
    return buf;
}

/// A MIP-mapped texture made as maketx makes them.
std::string make_tx(const TempDir& dir, const std::string& name,
                    const OIIO::ImageBuf& src, const std::string& wrap = "black") {
    OIIO::ImageSpec config;
    config.attribute("wrapmodes", wrap);
    const std::string path = dir.file(name);
    EXPECT_TRUE(OIIO::ImageBufAlgo::make_texture(OIIO::ImageBufAlgo::MakeTxTexture, src,
                                                 path, config))
        << OIIO::geterror();
    return path;
}

/// One point lookup (no filtering) of nchannels channels from `channel`.
std::vector<float> lookup(TextureLibrary& lib, const std::string& file, int channel,
                          int nchannels, float s, float t,
                          const TextureOptions& options = {}) {
    std::vector<float> out(nchannels, -1.0f);
    std::string error;
    EXPECT_TRUE(lib.texture(file, channel, nchannels, options, 1, &s, &t, nullptr,
                            nullptr, nullptr, nullptr, nullptr, out.data(), &error))
        << error;
    return out;
}

/// A lookup filtered over a square footprint of side `width` (texture units).
float filtered(TextureLibrary& lib, const std::string& file, float s, float t,
               float width, const TextureOptions& options = {}) {
    float out = -1.0f, zero = 0.0f;
    std::string error;
    EXPECT_TRUE(lib.texture(file, 0, 1, options, 1, &s, &t, &width, &zero, &zero, &width,
                            nullptr, &out, &error))
        << error;
    return out;
}

} // namespace

// ---------------------------------------------------------------------------
// 2-D textures

TEST(RslTexture, PointLookupsAtPixelCentresReturnThePixels) {
    TempDir dir;
    const std::string file = write_gradient(dir, "grad.exr", 3);
    TextureLibrary lib;
    for (int y : {0, 1, 15, 31})
        for (int x : {0, 7, 40, 63}) {
            const float s = (x + 0.5f) / kWidth, t = (y + 0.5f) / kHeight;
            const std::vector<float> c = lookup(lib, file, 0, 3, s, t);
            for (int k = 0; k < 3; ++k)
                EXPECT_NEAR(c[k], pixel(x, y, k), 1e-5f) << x << "," << y << " ch " << k;
        }
    // t = 0 is the top row of the image (RenderMan and OIIO alike).
    EXPECT_NEAR(lookup(lib, file, 1, 1, 0.5f, 0.5f / kHeight)[0], pixel(0, 0, 1), 1e-5f);

    // width 0 turns the derivatives off: the same values.
    TextureOptions sharp;
    sharp.swidth = sharp.twidth = 0.0f;
    const float s = 10.5f / kWidth, t = 20.5f / kHeight, d = 0.3f;
    float out[3];
    ASSERT_TRUE(
        lib.texture(file, 0, 3, sharp, 1, &s, &t, &d, &d, &d, &d, nullptr, out, nullptr));
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(out[k], pixel(10, 20, k), 1e-5f);
}

TEST(RslTexture, ChannelOffsetFillAndGreyAsColour) {
    TempDir dir;
    const std::string rgb = write_gradient(dir, "rgb.tif", 3);
    const std::string grey = write_gradient(dir, "grey.tif", 1);
    TextureLibrary lib;
    const float s = 5.5f / kWidth, t = 9.5f / kHeight;
    // file[1] as float: the second channel.
    EXPECT_NEAR(lookup(lib, rgb, 1, 1, s, t)[0], pixel(5, 9, 1), 1e-5f);
    // file[2] as colour: the third channel, then the fill value.
    TextureOptions fill;
    fill.fill = 0.75f;
    std::vector<float> c = lookup(lib, rgb, 2, 3, s, t, fill);
    EXPECT_NEAR(c[0], pixel(5, 9, 2), 1e-5f);
    EXPECT_EQ(c[1], 0.75f);
    EXPECT_EQ(c[2], 0.75f);
    // Past every channel: all fill (default 0).
    c = lookup(lib, rgb, 5, 3, s, t);
    EXPECT_EQ(c, (std::vector<float>{0.0f, 0.0f, 0.0f}));
    // A grey map read as colour replicates the grey.
    c = lookup(lib, grey, 0, 3, s, t, fill);
    EXPECT_NEAR(c[0], pixel(5, 9, 0), 1e-5f);
    EXPECT_EQ(c[1], c[0]);
    EXPECT_EQ(c[2], c[0]);
    // ... but its channel 1 does not exist.
    EXPECT_EQ(lookup(lib, grey, 1, 1, s, t, fill)[0], 0.75f);
}

TEST(RslTexture, MaskedPointsAreLeftAlone) {
    TempDir dir;
    const std::string file = write_gradient(dir, "grad.exr", 3);
    TextureLibrary lib;
    const float s[3] = {0.1f, 0.5f, 0.9f}, t[3] = {0.5f, 0.5f, 0.5f};
    const uint8_t mask[3] = {1, 0, 1};
    float out[3] = {-1.0f, -1.0f, -1.0f};
    ASSERT_TRUE(lib.texture(file, 0, 1, {}, 3, s, t, nullptr, nullptr, nullptr, nullptr,
                            mask, out, nullptr));
    EXPECT_NEAR(out[0], 0.1f, 1e-3f);
    EXPECT_EQ(out[1], -1.0f);
    EXPECT_NEAR(out[2], 0.9f, 1e-3f);
}

TEST(RslTexture, MipMappedTxLookupsAndBlur) {
    TempDir dir;
    const std::string file = make_tx(dir, "check.tx", checkerboard(64, 4));
    TextureLibrary lib;
    // Point lookups at pixel centres: the checkerboard itself.
    EXPECT_NEAR(lookup(lib, file, 0, 1, 0.5f / 64, 0.5f / 64)[0], 0.0f, 1e-5f);
    EXPECT_NEAR(lookup(lib, file, 0, 1, 4.5f / 64, 0.5f / 64)[0], 1.0f, 1e-5f);
    EXPECT_NEAR(lookup(lib, file, 0, 1, 4.5f / 64, 4.5f / 64)[0], 0.0f, 1e-5f);

    // A blurred lookup averages the squares: the mean, 0.5.
    TextureOptions blur;
    blur.sblur = blur.tblur = 0.5f;
    EXPECT_NEAR(lookup(lib, file, 0, 1, 0.5f, 0.5f, blur)[0], 0.5f, 0.05f);
    // So does a footprint of many squares (the derivatives)...
    EXPECT_NEAR(filtered(lib, file, 0.5f, 0.5f, 0.25f), 0.5f, 0.05f);
    // ... unless width 0 turns the filtering off.
    TextureOptions sharp;
    sharp.swidth = sharp.twidth = 0.0f;
    EXPECT_NEAR(filtered(lib, file, 4.5f / 64, 0.5f / 64, 0.25f, sharp), 1.0f, 1e-5f);
    // The other filters and lerp settings filter too.
    for (const char* filter : {"gaussian", "box"})
        for (int lerp : {0, 1, 2}) {
            TextureOptions o;
            o.filter = filter;
            o.lerp = lerp;
            EXPECT_NEAR(filtered(lib, file, 0.5f, 0.5f, 0.25f, o), 0.5f, 0.06f)
                << filter << " lerp " << lerp;
        }
    // A plain (scanline, single-level) image is MIP-mapped on the fly.
    const std::string plain = dir.file("check.exr");
    ASSERT_TRUE(checkerboard(64, 4).write(plain));
    EXPECT_NEAR(filtered(lib, plain, 0.5f, 0.5f, 0.25f), 0.5f, 0.05f);
    EXPECT_NEAR(lookup(lib, plain, 0, 1, 0.5f, 0.5f, blur)[0], 0.5f, 0.05f);
    // "none": the nearest texel, even between texels.
    TextureOptions nearest;
    nearest.filter = "none";
    EXPECT_EQ(lookup(lib, file, 0, 1, 4.9f / 64, 0.5f / 64, nearest)[0], 1.0f);
    EXPECT_EQ(lookup(lib, file, 0, 1, 3.9f / 64, 0.5f / 64, nearest)[0], 0.0f);
}

TEST(RslTexture, FourPointFormFiltersTheQuad) {
    TempDir dir;
    const std::string file = make_tx(dir, "check.tx", checkerboard(64, 4));
    TextureLibrary lib;
    // A small quad inside one white square, and a large one over many squares.
    const float small[8] = {4.2f / 64, 0.2f / 64, 4.8f / 64, 0.2f / 64,
                            4.2f / 64, 0.8f / 64, 4.8f / 64, 0.8f / 64};
    const float large[8] = {0.25f, 0.25f, 0.75f, 0.25f, 0.25f, 0.75f, 0.75f, 0.75f};
    for (const float* q : {small, large}) {
        const float* st[8];
        for (int k = 0; k < 8; ++k) st[k] = q + k;
        float out = -1.0f;
        std::string error;
        ASSERT_TRUE(lib.texture_quad(file, 0, 1, {}, 1, st, nullptr, &out, &error))
            << error;
        EXPECT_NEAR(out, q == small ? 1.0f : 0.5f, q == small ? 0.02f : 0.05f);
    }
}

TEST(RslTexture, WrapModesComeFromTheFile) {
    TempDir dir;
    OIIO::ImageBuf grad(OIIO::ImageSpec(kWidth, kHeight, 1, OIIO::TypeDesc::FLOAT));
    for (int y = 0; y < kHeight; ++y)
        for (int x = 0; x < kWidth; ++x) {
            const float v = pixel(x, y, 0);
            grad.setpixel(x, y, &v, 1);
        }
    const std::string black = make_tx(dir, "black.tx", grad, "black");
    const std::string periodic = make_tx(dir, "periodic.tx", grad, "periodic");
    const std::string clamp = make_tx(dir, "clamp.tx", grad, "clamp");
    const std::string plain = dir.file("plain.exr");
    ASSERT_TRUE(grad.write(plain));
    TextureLibrary lib;
    const float t = 0.5f;
    const float s_in = 8.5f / kWidth, s_out = 1.0f + s_in;
    EXPECT_NEAR(lookup(lib, black, 0, 1, s_out, t)[0], 0.0f, 1e-5f);
    EXPECT_NEAR(lookup(lib, periodic, 0, 1, s_out, t)[0], pixel(8, 0, 0), 1e-5f);
    EXPECT_NEAR(lookup(lib, periodic, 0, 1, s_in - 1.0f, t)[0], pixel(8, 0, 0), 1e-5f);
    EXPECT_NEAR(lookup(lib, clamp, 0, 1, s_out, t)[0], pixel(kWidth - 1, 0, 0), 1e-5f);
    EXPECT_NEAR(lookup(lib, clamp, 0, 1, -0.5f, t)[0], pixel(0, 0, 0), 1e-5f);
    // A plain image says nothing: periodic, so that filters reaching across
    // the s = 0 seam of a sphere read the map's other edge, not black.
    EXPECT_NEAR(lookup(lib, plain, 0, 1, s_out, t)[0], pixel(8, 0, 0), 1e-5f);
    EXPECT_NEAR(lookup(lib, plain, 0, 1, s_in, t)[0], pixel(8, 0, 0), 1e-5f);
}

TEST(RslTexture, MissingOrBrokenFilesFailCleanly) {
    TempDir dir;
    const std::string missing = dir.file("nothere.tx");
    const std::string broken = dir.file("broken.tif");
    sss::test::write_bytes(broken, sss::test::Bytes{'I', 'I', 42, 0, 1, 2, 3});
    testing::internal::CaptureStderr();
    auto lib_owner = std::make_unique<TextureLibrary>();
    TextureLibrary& lib = *lib_owner;
    for (const std::string& file : {missing, broken, missing}) {
        const float s = 0.5f, t = 0.5f;
        float out[3] = {0, 0, 0};
        std::string error;
        EXPECT_FALSE(lib.texture(file, 0, 3, {}, 1, &s, &t, nullptr, nullptr, nullptr,
                                 nullptr, nullptr, out, &error));
        EXPECT_EQ(error.rfind(file + ": ", 0), 0u) << error;
        const glm::vec3 dir(0, 0, 1);
        error.clear();
        EXPECT_FALSE(lib.environment(file, 0, 3, {}, 1, &dir, nullptr, nullptr, nullptr,
                                     out, &error));
        EXPECT_EQ(error.rfind(file + ": ", 0), 0u) << error;
        float res[2];
        EXPECT_FALSE(lib.texture_info(file, "resolution", 2, res, nullptr));
    }
    lib_owner.reset(); // nothing left to print at destruction either
    EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
}

TEST(RslTexture, TextureInfo) {
    TempDir dir;
    const std::string file = write_gradient(dir, "grad.exr", 3);
    OIIO::ImageBuf grey(OIIO::ImageSpec(16, 8, 1, OIIO::TypeDesc::FLOAT));
    const float m[16] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16};
    grey.specmod().attribute("worldtocamera", OIIO::TypeMatrix, m);
    const std::string tx = make_tx(dir, "grey.tx", grey);
    TextureLibrary lib;
    float numbers[16] = {};
    std::string text;
    ASSERT_TRUE(lib.texture_info(file, "resolution", 2, numbers, &text));
    EXPECT_EQ(numbers[0], float(kWidth));
    EXPECT_EQ(numbers[1], float(kHeight));
    ASSERT_TRUE(lib.texture_info(file, "channels", 1, numbers, &text));
    EXPECT_EQ(numbers[0], 3.0f);
    ASSERT_TRUE(lib.texture_info(file, "type", 0, numbers, &text));
    EXPECT_EQ(text, "texture");
    ASSERT_TRUE(lib.texture_info(tx, "resolution", 2, numbers, &text));
    EXPECT_EQ(numbers[0], 16.0f);
    EXPECT_EQ(numbers[1], 8.0f);
    ASSERT_TRUE(lib.texture_info(tx, "channels", 1, numbers, &text));
    EXPECT_EQ(numbers[0], 1.0f);
    ASSERT_TRUE(lib.texture_info(tx, "viewingmatrix", 16, numbers, &text));
    for (int k = 0; k < 16; ++k) EXPECT_EQ(numbers[k], m[k]);
    // Absent matrices, wrong sizes and unknown keys: false.
    EXPECT_FALSE(lib.texture_info(tx, "projectionmatrix", 16, numbers, &text));
    EXPECT_FALSE(lib.texture_info(file, "viewingmatrix", 16, numbers, &text));
    EXPECT_FALSE(lib.texture_info(file, "resolution", 3, numbers, &text));
    EXPECT_FALSE(lib.texture_info(file, "resolution", 0, numbers, &text));
    EXPECT_FALSE(lib.texture_info(file, "type", 1, numbers, &text));
    EXPECT_FALSE(lib.texture_info(file, "type", 0, numbers, nullptr));
    EXPECT_FALSE(lib.texture_info(file, "colour", 1, numbers, &text));
}

TEST(RslEnvironment, LatLongConvention) {
    // Channel 0 = s, channel 1 = t of the pixel centre. Convention (OIIO's,
    // +y up): t = 0 (top) looks along +y; s = 0.5 along +z, s = 0.25 along
    // +x, s = 0.75 along -x, s = 0 and 1 along -z.
    TempDir dir;
    const int w = 128, h = 64;
    OIIO::ImageBuf buf(OIIO::ImageSpec(w, h, 2, OIIO::TypeDesc::FLOAT));
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const float v[2] = {(x + 0.5f) / w, (y + 0.5f) / h};
            buf.setpixel(x, y, v, 2);
        }
    const std::string plain = dir.file("env.exr");
    ASSERT_TRUE(buf.write(plain));
    const std::string tx = dir.file("env.tx");
    ASSERT_TRUE(OIIO::ImageBufAlgo::make_texture(OIIO::ImageBufAlgo::MakeTxEnvLatl, buf,
                                                 tx, OIIO::ImageSpec()))
        << OIIO::geterror();
    TextureLibrary lib;
    std::string text;
    ASSERT_TRUE(lib.texture_info(tx, "type", 0, nullptr, &text));
    EXPECT_EQ(text, "environment");

    struct Case {
        glm::vec3 dir;
        float s, t;
    };
    const float up45 = std::sin(kPi / 4);
    const Case cases[] = {{{0, 0, 1}, 0.5f, 0.5f},   {{1, 0, 0}, 0.25f, 0.5f},
                          {{-1, 0, 0}, 0.75f, 0.5f}, {{0, up45, up45}, 0.5f, 0.25f},
                          {{0, -1, 1}, 0.5f, 0.75f}, {{-up45, 0, up45}, 0.625f, 0.5f}};
    for (const std::string& file : {plain, tx})
        for (const Case& c : cases) {
            float out[2] = {-1, -1};
            std::string error;
            ASSERT_TRUE(lib.environment(file, 0, 2, {}, 1, &c.dir, nullptr, nullptr,
                                        nullptr, out, &error))
                << error;
            EXPECT_NEAR(out[0], c.s, 0.01f)
                << file << " " << c.dir.x << "," << c.dir.y << "," << c.dir.z;
            EXPECT_NEAR(out[1], c.t, 0.01f)
                << file << " " << c.dir.x << "," << c.dir.y << "," << c.dir.z;
        }
    // RISpec 3.2's z-up maps (longitude 0 = +x at s = 0): at direction d,
    // what ours gives at (d.y, d.z, -d.x).
    for (const glm::vec3 d : {glm::vec3(1, 0.5f, 0.2f), glm::vec3(-0.3f, 1, -0.4f),
                              glm::vec3(0.2f, -1, 0.6f), glm::vec3(-1, -0.1f, -0.5f)}) {
        const glm::vec3 u = d / std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
        float s = std::atan2(u.y, u.x) / (2 * kPi);
        if (s < 0) s += 1;
        const float t = 0.5f - std::asin(u.z) / kPi;
        const glm::vec3 ours(u.y, u.z, -u.x);
        float st[2];
        ASSERT_TRUE(lib.environment(tx, 0, 2, {}, 1, &ours, nullptr, nullptr, nullptr, st,
                                    nullptr));
        EXPECT_NEAR(st[0], s, 0.01f) << d.x << "," << d.y << "," << d.z;
        EXPECT_NEAR(st[1], t, 0.01f) << d.x << "," << d.y << "," << d.z;
    }
    // Straight up: the top row (t near 0), whatever s.
    const glm::vec3 up(0, 1, 0);
    float out[2];
    ASSERT_TRUE(
        lib.environment(tx, 0, 2, {}, 1, &up, nullptr, nullptr, nullptr, out, nullptr));
    EXPECT_LT(out[1], 0.02f);
    // Channel offset and grey-as-colour work as for texture().
    ASSERT_TRUE(lib.environment(tx, 1, 1, {}, 1, &cases[3].dir, nullptr, nullptr, nullptr,
                                out, nullptr));
    EXPECT_NEAR(out[0], 0.25f, 0.01f);
}

TEST(RslTexture, ConcurrentLookups) {
    TempDir dir;
    const std::string file = make_tx(dir, "check.tx", checkerboard(64, 4));
    TextureLibrary lib;
    std::vector<std::thread> threads;
    std::vector<int> bad(4, 0);
    for (int k = 0; k < 4; ++k)
        threads.emplace_back([&, k] {
            std::vector<float> s(256), t(256), out(256);
            for (int i = 0; i < 256; ++i) {
                s[i] = ((i % 64) + 0.5f) / 64;
                t[i] = ((i / 64 + 4 * k) + 0.5f) / 64;
            }
            for (int round = 0; round < 20; ++round) {
                if (!lib.texture(file, 0, 1, {}, 256, s.data(), t.data(), nullptr,
                                 nullptr, nullptr, nullptr, nullptr, out.data(), nullptr))
                    ++bad[k];
                for (int i = 0; i < 256; ++i) {
                    const int x = i % 64, y = i / 64 + 4 * k;
                    if (out[i] != float(((x / 4) + (y / 4)) % 2)) ++bad[k];
                }
            }
        });
    for (std::thread& th : threads) th.join();
    EXPECT_EQ(bad, std::vector<int>(4, 0));
}

// ---------------------------------------------------------------------------
// 3-D textures

namespace {

/// A 1 x 1 square of points in z = 0, normals +z, radius `spacing`/2, with
/// a float channel "v" = 0.25 and a colour "c" = (0.1, 0.2, 0.3).
sss::PointCloud square_cloud(int n = 24) {
    sss::PointCloud cloud;
    cloud.resize(std::size_t(n) * n);
    sss::Channel& v = cloud.add_channel("v", sss::ChannelType::Float);
    for (std::size_t i = 0; i < cloud.size(); ++i) v.data[i] = 0.25f;
    sss::Channel& c = cloud.add_channel("c", sss::ChannelType::Color);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        c.data[3 * i] = 0.1f;
        c.data[3 * i + 1] = 0.2f;
        c.data[3 * i + 2] = 0.3f;
    }
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const std::size_t k = std::size_t(j) * n + i;
            cloud.positions[k] = {(i + 0.5f) / n - 0.5f, (j + 0.5f) / n - 0.5f, 0.0f};
            cloud.normals[k] = {0.0f, 0.0f, 1.0f};
            cloud.radii[k] = 0.5f / n;
        }
    return cloud;
}

void check_3d_file(const std::string& file) {
    TextureLibrary lib;
    const std::vector<std::string> channels = {"c", "v"};
    const glm::vec3 P[3] = {{0.1f, -0.2f, 0.0f}, {0.0f, 0.0f, 5.0f}, {0.3f, 0.3f, 0.0f}};
    const glm::vec3 N[3] = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
    const float radius[3] = {0.0f, 0.0f, 0.05f};
    std::vector<int> floats;
    std::vector<float> out(3 * 4, -1.0f);
    uint8_t found[3] = {9, 9, 9};
    std::string error;
    ASSERT_TRUE(lib.texture3d(file, channels, 3, P, N, radius, nullptr, floats,
                              out.data(), found, &error))
        << error;
    EXPECT_EQ(floats, (std::vector<int>{3, 1}));
    EXPECT_EQ(error, "");
    for (int i : {0, 2}) {
        EXPECT_EQ(found[i], 1) << i;
        EXPECT_NEAR(out[4 * i + 0], 0.1f, 1e-3f);
        EXPECT_NEAR(out[4 * i + 1], 0.2f, 1e-3f);
        EXPECT_NEAR(out[4 * i + 2], 0.3f, 1e-3f);
        EXPECT_NEAR(out[4 * i + 3], 0.25f, 1e-3f);
    }
    // Far from the data: not found, the output untouched.
    EXPECT_EQ(found[1], 0);
    for (int k = 4; k < 8; ++k) EXPECT_EQ(out[k], -1.0f);

    // A missing channel: 0 floats, named in the error; the others still read.
    const std::vector<std::string> some = {"nope", "v"};
    float one[1] = {-1.0f};
    ASSERT_TRUE(
        lib.texture3d(file, some, 1, P, N, radius, nullptr, floats, one, found, &error));
    EXPECT_EQ(floats, (std::vector<int>{0, 1}));
    EXPECT_NE(error.find("nope"), std::string::npos) << error;
    EXPECT_EQ(error.rfind(file + ": ", 0), 0u) << error;
    EXPECT_EQ(found[0], 1);
    EXPECT_NEAR(one[0], 0.25f, 1e-3f);
    // None of the channels: false.
    const std::vector<std::string> none = {"nope"};
    error.clear();
    EXPECT_FALSE(
        lib.texture3d(file, none, 1, P, N, radius, nullptr, floats, one, found, &error));
    EXPECT_NE(error.find("nope"), std::string::npos) << error;
    EXPECT_EQ(found[0], 0);
    // Masked points are not looked up.
    const uint8_t mask[1] = {0};
    one[0] = -1.0f;
    found[0] = 9;
    ASSERT_TRUE(
        lib.texture3d(file, some, 1, P, N, radius, mask, floats, one, found, &error));
    EXPECT_EQ(found[0], 0);
    EXPECT_EQ(one[0], -1.0f);
}

} // namespace

TEST(RslTexture3d, PointCloud) {
    TempDir dir;
    const std::string file = dir.file("square.ptc");
    sss::write_point_cloud(square_cloud(), file);
    check_3d_file(file);
}

TEST(RslTexture3d, BrickMap) {
    TempDir dir;
    const std::string file = dir.file("square.bkm");
    sss::build_brick_map({square_cloud()}, sss::BrickMapBuildOptions{}, file);
    check_3d_file(file);
}

TEST(RslTexture3d, NormalsSelectTheSide) {
    TempDir dir;
    const std::string file = dir.file("square.ptc");
    sss::write_point_cloud(square_cloud(), file);
    TextureLibrary lib;
    const std::vector<std::string> channels = {"v"};
    const glm::vec3 P(0.0f, 0.0f, 0.0f), down(0, 0, -1);
    std::vector<int> floats;
    float out = -1.0f;
    uint8_t found = 9;
    ASSERT_TRUE(lib.texture3d(file, channels, 1, &P, &down, nullptr, nullptr, floats,
                              &out, &found, nullptr));
    EXPECT_EQ(found, 0); // every point faces +z
    // No normal: every point qualifies.
    ASSERT_TRUE(lib.texture3d(file, channels, 1, &P, nullptr, nullptr, nullptr, floats,
                              &out, &found, nullptr));
    EXPECT_EQ(found, 1);
    EXPECT_NEAR(out, 0.25f, 1e-4f);
}

TEST(RslTexture3d, MissingAndCorruptFiles) {
    TempDir dir;
    const std::string bad = dir.file("bad.ptc");
    sss::test::write_bytes(bad, sss::test::Bytes{'p', 't', 'c', 0});
    TextureLibrary lib;
    const std::vector<std::string> channels = {"v"};
    const glm::vec3 P(0.0f);
    std::vector<int> floats;
    float out = -1.0f;
    uint8_t found = 9;
    for (const std::string& file : {dir.file("none.bkm"), dir.file("none.ptc"), bad}) {
        std::string error;
        EXPECT_FALSE(lib.texture3d(file, channels, 1, &P, nullptr, nullptr, nullptr,
                                   floats, &out, &found, &error));
        EXPECT_EQ(error.rfind(file + ": ", 0), 0u) << error;
        EXPECT_EQ(found, 0);
        EXPECT_EQ(out, -1.0f);
    }
    // Written later: invalidate() makes the library look again.
    const std::string later = dir.file("none.ptc");
    sss::write_point_cloud(square_cloud(), later);
    EXPECT_FALSE(lib.texture3d(later, channels, 1, &P, nullptr, nullptr, nullptr, floats,
                               &out, &found, nullptr));
    lib.invalidate(later);
    EXPECT_TRUE(lib.texture3d(later, channels, 1, &P, nullptr, nullptr, nullptr, floats,
                              &out, &found, nullptr));
    EXPECT_EQ(found, 1);
}

// ---------------------------------------------------------------------------
// bake3d files

TEST(RslBake3dFile, RecordsMergeIntoACloudThatTexture3dReads) {
    TempDir dir;
    const std::string file = dir.file("baked.ptc");
    const std::string other = dir.file("other.ptc");
    // Two records for `file` (the second without "_area", with a new
    // channel "_n" declared a normal), one for `other`.
    sss::Bake3dRecord a;
    a.file = file;
    a.channels = {"_radiance_t", "_area"};
    a.channel_floats = {3, 1};
    a.P = {{0, 0, 0}, {0.1f, 0, 0}};
    a.N = {{0, 0, 1}, {0, 0, 1}};
    a.radius = {0.05f, 0.05f};
    a.values = {1, 2, 3, 0.01f, 4, 5, 6, 0.02f};
    sss::Bake3dRecord b;
    b.file = file;
    b.channels = {"_n", "_radiance_t"};
    b.channel_floats = {3, 3};
    b.P = {{0.2f, 0, 0}};
    b.N = {{0, 0, 1}};
    b.radius = {0.05f};
    b.values = {0, 1, 0, 7, 8, 9};
    sss::Bake3dRecord c = a;
    c.file = other;
    const sss::ChannelDeclarations declared = {{"_n", "normal"}};

    const std::vector<sss::Bake3dRecord> records = {a, b, c};
    const sss::PointCloud cloud = sss::bake3d_point_cloud({records.data(), 2}, declared);
    ASSERT_EQ(cloud.size(), 3u);
    ASSERT_EQ(cloud.channels.size(), 3u);
    EXPECT_EQ(cloud.channels[0].name, "_radiance_t");
    EXPECT_EQ(cloud.channels[0].type, sss::ChannelType::Color);
    EXPECT_EQ(cloud.channels[1].type, sss::ChannelType::Float);
    EXPECT_EQ(cloud.channels[2].type, sss::ChannelType::Normal);
    EXPECT_EQ(cloud.channels[0].data, (std::vector<float>{1, 2, 3, 4, 5, 6, 7, 8, 9}));
    EXPECT_EQ(cloud.channels[1].data, (std::vector<float>{0.01f, 0.02f, 0.0f}));
    EXPECT_EQ(cloud.positions[2], glm::vec3(0.2f, 0, 0));
    EXPECT_EQ(cloud.radii[1], 0.05f);

    EXPECT_EQ(sss::write_bake3d_files(records, declared),
              (std::vector<std::string>{file, other}));
    EXPECT_EQ(sss::read_point_cloud(file).size(), 3u);
    EXPECT_EQ(sss::read_point_cloud(other).size(), 2u);

    // texture3d reads it back: at the third point, its colour.
    TextureLibrary lib;
    const std::vector<std::string> channels = {"_radiance_t"};
    const glm::vec3 P(0.2f, 0, 0), N(0, 0, 1);
    std::vector<int> floats;
    float out[3];
    uint8_t found = 0;
    ASSERT_TRUE(lib.texture3d(file, channels, 1, &P, &N, nullptr, nullptr, floats, out,
                              &found, nullptr));
    EXPECT_EQ(found, 1);
    EXPECT_GT(out[0], 4.0f); // the nearest points dominate
    EXPECT_LE(out[0], 7.0f);
}

TEST(RslBake3dFile, InconsistentRecordsAreRejected) {
    sss::Bake3dRecord r;
    r.file = "x.ptc";
    r.channels = {"v"};
    r.channel_floats = {1};
    r.P = {{0, 0, 0}};
    r.values = {1, 2}; // two floats for one point of one float
    EXPECT_THROW(sss::bake3d_point_cloud({&r, 1}), sss::ValueError);
    r.values = {1};
    EXPECT_NO_THROW(sss::bake3d_point_cloud({&r, 1}));
    EXPECT_THROW(sss::bake3d_point_cloud({&r, 1}, {{"v", "color"}}), sss::ValueError);
    sss::Bake3dRecord wide = r;
    wide.channel_floats = {3};
    wide.values = {1, 2, 3};
    const std::vector<sss::Bake3dRecord> both = {r, wide};
    EXPECT_THROW(sss::bake3d_point_cloud(both), sss::ValueError);
    try {
        sss::write_bake3d_files(both);
        FAIL() << "no error";
    } catch (const sss::ValueError& e) {
        EXPECT_EQ(std::string(e.what()).rfind("x.ptc: ", 0), 0u) << e.what();
    }
    r.channel_floats = {2};
    r.values = {1, 2};
    EXPECT_THROW(sss::bake3d_point_cloud({&r, 1}), sss::ValueError);
}
