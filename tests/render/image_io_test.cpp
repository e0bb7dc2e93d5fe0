// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file image_io_test.cpp
/// Image output: Display resolution (types, extensions, modes, AOV layers,
/// pixel types), OpenEXR round trips with layers and metadata, PNG/TIFF quantised
/// as PRMan does (linear, "quantize" and "dither", Exposure) with straight alpha,
/// atomic writes that leave nothing behind on
/// errors, and reading images back.

#include <gtest/gtest.h>

#include "test_util.h"

#include <cmath>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <OpenImageIO/imageio.h>
#include <glm/gtc/matrix_transform.hpp>

#include "sss/render/image_io.h"
#include "sss/scene/scene.h"
#include "sss/util/error.h"

namespace fs = std::filesystem;
using sss::DisplaySpec;
using sss::DisplayTarget;
using sss::Image;
using sss::ImageMetadata;

namespace {

using Names = std::vector<std::string>;

/// A 5 x 3 image with the beauty, Z and two AOV layers; every value distinct
/// and exactly representable in half (multiples of 1/64 below 8).
Image test_image() {
    Image img(5, 3,
              {"R", "G", "B", "A", "Z", "diffuse.R", "diffuse.G", "diffuse.B",
               "specular.R", "specular.G", "specular.B"});
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x)
            for (int c = 0; c < img.channel_count(); ++c)
                img.pixel(x, y)[c] = float((y * img.width + x) * 11 + c) / 64.0f;
    return img;
}

DisplaySpec display(const std::string& name, const std::string& type,
                    const std::string& mode, bool additional = false) {
    DisplaySpec d;
    d.name = name;
    d.type = type;
    d.mode = mode;
    d.additional = additional;
    return d;
}

void set_string(DisplaySpec& d, const std::string& name, const std::string& value) {
    sss::Param p;
    p.name = name;
    p.type = sss::ParamType::String;
    p.storage = sss::ParamClass::Uniform;
    p.strings = {value};
    d.params.set(p);
}

void set_numbers(DisplaySpec& d, const std::string& name, std::vector<double> values) {
    sss::Param p;
    p.name = name;
    p.type = sss::ParamType::Float;
    p.storage = sss::ParamClass::Uniform;
    p.array_size = static_cast<int>(values.size());
    p.numbers = std::move(values);
    d.params.set(p);
}

ImageMetadata test_metadata() {
    ImageMetadata m;
    m.software = "render (sss) 0.1.0";
    m.command_line = "render -frame 3 scene.rib";
    m.render_seconds = 12.5;
    m.world_to_camera = glm::translate(sss::Matrix4(1.0), glm::dvec3(1.0, 2.0, 3.0));
    m.world_to_ndc = glm::scale(sss::Matrix4(1.0), glm::dvec3(2.0, 4.0, 8.0));
    m.extra = {{"sss:scene", "scenes/teapot.rib"}};
    return m;
}

std::string format_of(const std::string& path) {
    auto in = OIIO::ImageInput::open(path);
    EXPECT_TRUE(in) << path;
    return in ? in->format_name() : "";
}

OIIO::TypeDesc pixel_type_of(const std::string& path, int channel) {
    auto in = OIIO::ImageInput::open(path);
    EXPECT_TRUE(in) << path;
    return in ? in->spec().channelformat(channel) : OIIO::TypeDesc();
}

/// Names of the files in a folder, hidden temporaries included.
Names folder_files(const fs::path& dir) {
    Names names;
    for (const auto& entry : fs::directory_iterator(dir))
        names.push_back(entry.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

std::string file_text(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

std::vector<double> numbers_of(const std::string& text) {
    std::vector<double> out;
    std::string s = text;
    for (char& c : s)
        if (c == ',') c = ' ';
    std::istringstream in(s);
    double v;
    while (in >> v) out.push_back(v);
    return out;
}

} // namespace

// ---------------------------------------------------------------------------
// Image
// ---------------------------------------------------------------------------

TEST(ImageIoImage, ConstructorSizesAndZeroFills) {
    Image img(4, 3, {"R", "G", "B", "A", "diffuse.R"});
    EXPECT_EQ(img.width, 4);
    EXPECT_EQ(img.height, 3);
    EXPECT_EQ(img.channel_count(), 5);
    ASSERT_EQ(img.pixels.size(), 4u * 3u * 5u);
    for (float v : img.pixels) EXPECT_EQ(v, 0.0f);
    EXPECT_EQ(img.channel_index("R"), 0);
    EXPECT_EQ(img.channel_index("diffuse.R"), 4);
    EXPECT_EQ(img.channel_index("diffuse"), -1);
    EXPECT_EQ(img.channel_index("r"), -1);
    img.pixel(3, 2)[1] = 7.0f;
    EXPECT_EQ(img.pixels[(2 * 4 + 3) * 5 + 1], 7.0f);
}

TEST(ImageIoImage, RejectsBadSizesAndNames) {
    EXPECT_THROW(Image(-1, 3, {"R"}), sss::ValueError);
    EXPECT_THROW(Image(2, 3, {"R", "R"}), sss::ValueError);
    EXPECT_THROW(Image(2, 3, {"R", ""}), sss::ValueError);
    EXPECT_NO_THROW(Image(0, 0, {"R"}));
}

// ---------------------------------------------------------------------------
// resolve_display
// ---------------------------------------------------------------------------

TEST(ImageIoResolve, FormatFromTypeAndExtension) {
    Image img = test_image();
    struct Case {
        std::string name, type, path, format;
    };
    const std::vector<Case> cases = {
        {"a.exr", "openexr", "a.exr", "openexr"},
        {"a.png", "openexr", "a.png", "openexr"}, // the type wins over the name
        {"a", "exr", "a", "openexr"},
        {"a.tif", "tiff", "a.tif", "tiff"},
        {"a.exr", "png", "a.exr", "png"},
        {"a.jpg", "jpeg", "a.jpg", "jpeg"},
        {"a.exr", "file", "a.exr", "openexr"},
        {"a.tiff", "file", "a.tiff", "tiff"},
        {"a.TIF", "file", "a.TIF", "tiff"},
        {"a.png", "file", "a.png", "png"},
        {"a.jpeg", "file", "a.jpeg", "jpeg"},
        {"a.png", "mydriver", "a.png", "png"},
        {"view", "it", "view.exr", "openexr"},
        {"view", "framebuffer", "view.exr", "openexr"},
        {"view.png", "it", "view.png", "png"},
        {"view.tif", "framebuffer", "view.tif", "tiff"},
        {"shot.0042", "it", "shot.0042.exr", "openexr"},
        {"x.OpenEXR", "OpenEXR", "x.OpenEXR", "openexr"},
    };
    for (const auto& c : cases) {
        DisplayTarget t = sss::resolve_display(display(c.name, c.type, "rgb"), img, true);
        EXPECT_EQ(t.path, c.path) << c.name << " " << c.type;
        EXPECT_EQ(t.format, c.format) << c.name << " " << c.type;
    }
}

TEST(ImageIoResolve, FileTypeNeedsAnImageExtension) {
    // "file" and unknown drivers take the format from the name: a name that
    // does not say one is an error naming the Display and its line (it used
    // to write OpenEXR under any name).
    Image img = test_image();
    for (const auto& [name, type] :
         std::vector<std::pair<std::string, std::string>>{{"a", "file"},
                                                          {"a.xyz", "file"},
                                                          {"shot.0042", "file"},
                                                          {"a", "mydriver"}}) {
        sss::DisplaySpec d = display(name, type, "rgb");
        d.where = "scene.rib:4";
        try {
            sss::resolve_display(d, img, true);
            ADD_FAILURE() << name << " " << type << ": expected ValueError";
        } catch (const sss::ValueError& e) {
            const std::string what = e.what();
            EXPECT_EQ(what.rfind("Display \"" + name + "\" (scene.rib:4): '" + name +
                                     "' is not an image file name",
                                 0),
                      0u)
                << what;
            EXPECT_NE(what.find("(known: .exr, .tif, .tiff, .png, .jpg, .jpeg)"),
                      std::string::npos)
                << what;
        }
        EXPECT_THROW(sss::display_format(d), sss::ValueError);
    }
}

TEST(ImageIoResolve, StandardModes) {
    Image img = test_image();
    auto own = [&](const std::string& mode) {
        return sss::resolve_display(display("x.tif", "tiff", mode, true), img, false);
    };
    EXPECT_EQ(own("rgba").channels, (Names{"R", "G", "B", "A"}));
    EXPECT_EQ(own("rgba").names, (Names{"R", "G", "B", "A"}));
    EXPECT_EQ(own("rgb").channels, (Names{"R", "G", "B"}));
    EXPECT_EQ(own("a").channels, (Names{"A"}));
    EXPECT_EQ(own("RGBA").channels, (Names{"R", "G", "B", "A"}));
    EXPECT_EQ(own("Ci,a").channels, (Names{"R", "G", "B", "A"}));
    EXPECT_EQ(own("rgba,a").channels, (Names{"R", "G", "B", "A"}));

    auto z = sss::resolve_display(display("z.exr", "openexr", "z", true), img, false);
    EXPECT_EQ(z.channels, (Names{"Z"}));
    EXPECT_EQ(z.names, (Names{"Z"}));
    auto rgbaz =
        sss::resolve_display(display("z.exr", "openexr", "rgbaz", true), img, false);
    EXPECT_EQ(rgbaz.channels, (Names{"R", "G", "B", "A", "Z"}));
}

TEST(ImageIoResolve, PrimaryExrCarriesEveryAovLayer) {
    Image img = test_image();
    DisplayTarget t =
        sss::resolve_display(display("beauty.exr", "openexr", "rgba"), img, true);
    const Names expected = {"R",          "G",         "B",         "A",
                            "diffuse.R",  "diffuse.G", "diffuse.B", "specular.R",
                            "specular.G", "specular.B"};
    EXPECT_EQ(t.channels, expected);
    EXPECT_EQ(t.names, expected);
    EXPECT_TRUE(t.half);
    EXPECT_EQ(t.compression, "zip");

    // An AOV in the primary's own mode keeps its layer name, and is not repeated.
    DisplayTarget d =
        sss::resolve_display(display("d.exr", "openexr", "diffuse,a"), img, true);
    EXPECT_EQ(d.names, (Names{"diffuse.R", "diffuse.G", "diffuse.B", "A", "specular.R",
                              "specular.G", "specular.B"}));

    // The same display as '+' (or primary non-EXR) holds only its mode.
    DisplayTarget extra =
        sss::resolve_display(display("beauty.exr", "openexr", "rgba", true), img, false);
    EXPECT_EQ(extra.channels, (Names{"R", "G", "B", "A"}));
    DisplayTarget png =
        sss::resolve_display(display("beauty.png", "png", "rgba"), img, true);
    EXPECT_EQ(png.channels, (Names{"R", "G", "B", "A"}));
}

TEST(ImageIoResolve, AovDisplayOfItsOwn) {
    Image img = test_image();
    for (std::string mode : {"diffuse", "color diffuse", " varying color diffuse "}) {
        DisplayTarget t = sss::resolve_display(
            display("diffuse.exr", "openexr", mode, true), img, false);
        EXPECT_EQ(t.channels, (Names{"diffuse.R", "diffuse.G", "diffuse.B"})) << mode;
        EXPECT_EQ(t.names, (Names{"R", "G", "B"})) << mode;
    }
    // With alpha the short names stay unique.
    DisplayTarget da =
        sss::resolve_display(display("d.png", "png", "diffuse,a", true), img, false);
    EXPECT_EQ(da.names, (Names{"R", "G", "B", "A"}));
    // Two layers would collide as R G B: they keep their layer names.
    DisplayTarget two = sss::resolve_display(
        display("ds.exr", "openexr", "diffuse,specular", true), img, false);
    EXPECT_EQ(two.names, two.channels);
    EXPECT_EQ(two.names, (Names{"diffuse.R", "diffuse.G", "diffuse.B", "specular.R",
                                "specular.G", "specular.B"}));
    // A plain (un-layered) channel is found by its name.
    DisplayTarget zc =
        sss::resolve_display(display("z.exr", "openexr", "float Z", true), img, false);
    EXPECT_EQ(zc.channels, (Names{"Z"}));
}

TEST(ImageIoResolve, ModeErrorsNameTheDisplay) {
    Image img = test_image();
    Image no_alpha(2, 2, {"R", "G", "B"});
    auto message = [](const auto& f) -> std::string {
        try {
            f();
        } catch (const sss::ValueError& e) {
            return e.what();
        }
        return "no ValueError";
    };
    std::string m = message([&] {
        sss::resolve_display(display("out/occ.exr", "openexr", "occlusion", true), img,
                             false);
    });
    EXPECT_NE(m.find("+out/occ.exr"), std::string::npos) << m;
    EXPECT_NE(m.find("occlusion"), std::string::npos) << m;
    EXPECT_NE(m.find("diffuse"), std::string::npos) << m; // lists what there is

    m = message([&] {
        sss::resolve_display(display("b.exr", "openexr", "rgba"), no_alpha, true);
    });
    EXPECT_NE(m.find("'b.exr'"), std::string::npos) << m;
    EXPECT_NE(m.find("channel A"), std::string::npos) << m;

    m = message(
        [&] { sss::resolve_display(display("b.exr", "openexr", "z"), no_alpha, true); });
    EXPECT_NE(m.find("channel Z"), std::string::npos) << m;

    EXPECT_THROW(sss::resolve_display(display("b.exr", "openexr", ""), img, true),
                 sss::ValueError);
    EXPECT_THROW(sss::resolve_display(display("b.exr", "openexr", "Ci,,a"), img, true),
                 sss::ValueError);
    // The prefix must be a whole layer name.
    EXPECT_THROW(sss::resolve_display(display("b.exr", "openexr", "diff"), img, true),
                 sss::ValueError);
    // What 8-bit formats cannot hold.
    EXPECT_THROW(sss::resolve_display(display("z.png", "png", "z"), img, true),
                 sss::ValueError);
    EXPECT_THROW(sss::resolve_display(display("d.png", "png", "rgba,diffuse"), img, true),
                 sss::ValueError);
}

TEST(ImageIoResolve, PixelTypeAndCompression) {
    Image img = test_image();
    DisplaySpec d = display("b.exr", "openexr", "rgba");
    EXPECT_TRUE(sss::resolve_display(d, img, true).half);
    set_string(d, "type", "float");
    EXPECT_FALSE(sss::resolve_display(d, img, true).half);
    set_string(d, "type", "half");
    EXPECT_TRUE(sss::resolve_display(d, img, true).half);
    set_string(d, "type", "uint16");
    EXPECT_THROW(sss::resolve_display(d, img, true), sss::ValueError);
    set_string(d, "type", "float");
    set_string(d, "compression", "piz");
    EXPECT_EQ(sss::resolve_display(d, img, true).compression, "piz");
    set_string(d, "compression", "lzw");
    EXPECT_THROW(sss::resolve_display(d, img, true), sss::ValueError);

    DisplaySpec p = display("b.png", "png", "rgba");
    set_string(p, "type", "float");
    EXPECT_THROW(sss::resolve_display(p, img, true), sss::ValueError);
    set_string(p, "type", "uint8");
    EXPECT_NO_THROW(sss::resolve_display(p, img, true));
}

TEST(ImageIoResolve, JpegDropsAlpha) {
    Image img = test_image();
    DisplayTarget t = sss::resolve_display(display("b.jpg", "file", "rgba"), img, true);
    EXPECT_EQ(t.format, "jpeg");
    EXPECT_EQ(t.names, (Names{"R", "G", "B"}));
}

// ---------------------------------------------------------------------------
// OpenEXR
// ---------------------------------------------------------------------------

TEST(ImageIoExr, DepthMapDisplays) {
    // Display "zfile" / "shadow": OpenEXR whatever the name, float Z only,
    // no surface (Z 0 in the image) = kNoSurfaceDepth, and the matrices.
    sss::test::TempDir dir("image_io");
    Image img = test_image();
    img.pixel(0, 0)[img.channel_index("Z")] = 0.0f; // no hit
    ImageMetadata meta = test_metadata();
    meta.world_to_screen = glm::scale(sss::Matrix4(1.0), glm::dvec3(0.5, 0.25, 1.0));
    const std::string zfile = dir.file("key.z"), shd = dir.file("key.shd");
    DisplayTarget z = sss::resolve_display(display(zfile, "zfile", "z"), img, true);
    EXPECT_EQ(z.channels, (Names{"Z"}));
    EXPECT_TRUE(z.depth_map);
    EXPECT_FALSE(z.shadow_map);
    sss::write_display(img, z, meta);
    DisplayTarget s = sss::resolve_display(display(shd, "Shadow", "z", true), img, false);
    EXPECT_TRUE(s.shadow_map);
    sss::write_display(img, s, meta);
    for (const std::string& path : {zfile, shd}) {
        EXPECT_EQ(format_of(path), "openexr") << path;
        EXPECT_EQ(pixel_type_of(path, 0), OIIO::TypeDesc::FLOAT) << path;
        const Image back = sss::read_image(path);
        ASSERT_EQ(back.channels, (Names{"Z"})) << path;
        EXPECT_EQ(back.pixel(0, 0)[0], 1e30f) << path;
        EXPECT_EQ(back.pixel(1, 0)[0], img.pixel(1, 0)[img.channel_index("Z")]) << path;
        auto in = OIIO::ImageInput::open(path);
        ASSERT_TRUE(in);
        float m[16] = {};
        ASSERT_TRUE(in->spec().getattribute("worldtoscreen", OIIO::TypeMatrix, m))
            << path;
        EXPECT_EQ(m[0], 0.5f);
        EXPECT_EQ(m[5], 0.25f);
        ASSERT_TRUE(in->spec().getattribute("worldtocamera", OIIO::TypeMatrix, m))
            << path;
        EXPECT_EQ(m[12], 1.0f); // row-vector layout: the translation in the last row
        EXPECT_EQ(m[14], 3.0f);
        EXPECT_EQ(in->spec().get_string_attribute("sss:textureformat"),
                  path == shd ? "Shadow" : "")
            << path;
    }
    // Depth maps hold depth only.
    EXPECT_THROW(sss::resolve_display(display(zfile, "zfile", "rgba"), img, true),
                 sss::ValueError);
}

TEST(ImageIoExr, RoundTripBeautyAndLayers) {
    sss::test::TempDir dir("image_io");
    Image img = test_image();
    const std::string path = dir.file("beauty.exr");
    DisplayTarget t = sss::resolve_display(display(path, "openexr", "rgba"), img, true);
    sss::write_display(img, t, test_metadata());

    EXPECT_EQ(format_of(path), "openexr");
    EXPECT_EQ(pixel_type_of(path, 0), OIIO::TypeDesc::HALF);
    Image back = sss::read_image(path);
    EXPECT_EQ(back.width, 5);
    EXPECT_EQ(back.height, 3);
    // OpenImageIO lists the beauty first, then the layers in name order.
    EXPECT_EQ(back.channels,
              (Names{"R", "G", "B", "A", "diffuse.R", "diffuse.G", "diffuse.B",
                     "specular.R", "specular.G", "specular.B"}));
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x)
            for (const auto& c : back.channels) {
                float want = img.pixel(x, y)[img.channel_index(c)];
                float got = back.pixel(x, y)[back.channel_index(c)];
                // Half keeps 11 significant bits.
                EXPECT_NEAR(got, want, std::abs(want) * 1e-3f + 1e-6f)
                    << c << " at " << x << "," << y;
            }
    // Only the file itself is left in the folder.
    EXPECT_EQ(folder_files(dir.path()), (Names{"beauty.exr"}));
}

TEST(ImageIoExr, FloatPixelType) {
    sss::test::TempDir dir("image_io");
    Image img = test_image();
    img.pixel(1, 1)[0] = 1.0f / 3.0f; // not representable in half
    DisplaySpec d = display(dir.file("f.exr"), "openexr", "rgba");
    set_string(d, "type", "float");
    DisplayTarget t = sss::resolve_display(d, img, true);
    sss::write_display(img, t, test_metadata());
    for (int c = 0; c < 10; ++c)
        EXPECT_EQ(pixel_type_of(t.path, c), OIIO::TypeDesc::FLOAT) << c;
    Image back = sss::read_image(t.path);
    EXPECT_EQ(back.pixel(1, 1)[0], 1.0f / 3.0f);

    // Half: the same value is rounded.
    DisplayTarget h =
        sss::resolve_display(display(dir.file("h.exr"), "openexr", "rgba"), img, true);
    sss::write_display(img, h, test_metadata());
    Image hb = sss::read_image(h.path);
    EXPECT_NE(hb.pixel(1, 1)[0], 1.0f / 3.0f);
    EXPECT_NEAR(hb.pixel(1, 1)[0], 1.0f / 3.0f, 2e-4f);
}

TEST(ImageIoExr, DepthStaysFloatAndHalfOverflowIsClamped) {
    sss::test::TempDir dir("image_io");
    Image img = test_image();
    img.pixel(0, 0)[img.channel_index("Z")] = 123456.789f;
    img.pixel(0, 0)[0] = 1e6f;
    img.pixel(1, 0)[0] = -1e6f;
    DisplayTarget t =
        sss::resolve_display(display(dir.file("z.exr"), "openexr", "rgbaz"), img, true);
    sss::write_display(img, t, test_metadata());
    Image back = sss::read_image(t.path);
    int z = back.channel_index("Z");
    ASSERT_GE(z, 0);
    EXPECT_EQ(pixel_type_of(t.path, z), OIIO::TypeDesc::FLOAT);
    EXPECT_EQ(pixel_type_of(t.path, back.channel_index("R")), OIIO::TypeDesc::HALF);
    EXPECT_EQ(back.pixel(0, 0)[z], 123456.789f);
    EXPECT_EQ(back.pixel(0, 0)[back.channel_index("R")], 65504.0f);
    EXPECT_EQ(back.pixel(1, 0)[back.channel_index("R")], -65504.0f);
}

TEST(ImageIoExr, Metadata) {
    sss::test::TempDir dir("image_io");
    Image img = test_image();
    ImageMetadata meta = test_metadata();
    DisplayTarget t =
        sss::resolve_display(display(dir.file("m.exr"), "openexr", "rgba"), img, true);
    sss::write_display(img, t, meta);

    EXPECT_EQ(sss::read_image_attribute(t.path, "Software"), "render (sss) 0.1.0");
    EXPECT_EQ(sss::read_image_attribute(t.path, "sss:commandLine"),
              "render -frame 3 scene.rib");
    EXPECT_EQ(sss::read_image_attribute(t.path, "sss:scene"), "scenes/teapot.rib");
    EXPECT_EQ(numbers_of(sss::read_image_attribute(t.path, "renderTimeSeconds")),
              std::vector<double>{12.5});
    EXPECT_EQ(sss::read_image_attribute(t.path, "compression"), "zip");
    EXPECT_EQ(sss::read_image_attribute(t.path, "no:suchAttribute"), "");

    std::string date = sss::read_image_attribute(t.path, "capDate");
    EXPECT_TRUE(
        std::regex_match(date, std::regex(R"(\d{4}:\d{2}:\d{2} \d{2}:\d{2}:\d{2})")))
        << date;
    EXPECT_EQ(numbers_of(sss::read_image_attribute(t.path, "utcOffset")).size(), 1u);

    // Row-vector layout: the translation (1, 2, 3) is the last row.
    EXPECT_EQ(numbers_of(sss::read_image_attribute(t.path, "worldToCamera")),
              (std::vector<double>{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 1, 2, 3, 1}));
    EXPECT_EQ(numbers_of(sss::read_image_attribute(t.path, "worldToNDC")),
              (std::vector<double>{2, 0, 0, 0, 0, 4, 0, 0, 0, 0, 8, 0, 0, 0, 0, 1}));

    // The attribute types are OpenEXR's standard ones.
    auto in = OIIO::ImageInput::open(t.path);
    ASSERT_TRUE(in);
    const OIIO::ParamValue* w2c = in->spec().find_attribute("worldToCamera");
    ASSERT_TRUE(w2c);
    EXPECT_EQ(w2c->type(), OIIO::TypeMatrix44);
    const OIIO::ParamValue* rt = in->spec().find_attribute("renderTimeSeconds");
    ASSERT_TRUE(rt);
    EXPECT_EQ(rt->type(), OIIO::TypeFloat);
}

TEST(ImageIoExr, SourceDateEpochFixesTheDate) {
    sss::test::TempDir dir("image_io");
    Image img = test_image();
    DisplayTarget t =
        sss::resolve_display(display(dir.file("d.exr"), "openexr", "rgb"), img, true);
    ::setenv("SOURCE_DATE_EPOCH", "1700000000", 1);
    sss::write_display(img, t, test_metadata());
    ::setenv("SOURCE_DATE_EPOCH", "yesterday", 1);
    EXPECT_THROW(sss::write_display(img, t, test_metadata()), sss::ValueError);
    ::unsetenv("SOURCE_DATE_EPOCH");
    EXPECT_EQ(sss::read_image_attribute(t.path, "capDate"), "2023:11:14 22:13:20");
    EXPECT_EQ(numbers_of(sss::read_image_attribute(t.path, "utcOffset")),
              std::vector<double>{0.0});
}

TEST(ImageIoExr, CapDateIsLocalTimeWithUtcOffset) {
    sss::test::TempDir dir("image_io");
    Image img = test_image();
    DisplayTarget t =
        sss::resolve_display(display(dir.file("d.exr"), "openexr", "rgb"), img, true);
    const char* old_tz = std::getenv("TZ");
    std::string saved = old_tz ? old_tz : "";
    // POSIX TZ "XYZ-2": local time is two hours ahead of UTC.
    ::setenv("TZ", "XYZ-2", 1);
    std::time_t before = std::time(nullptr);
    sss::write_display(img, t, test_metadata());
    if (old_tz)
        ::setenv("TZ", saved.c_str(), 1);
    else
        ::unsetenv("TZ");
    ::tzset();
    // UTC = local + utcOffset.
    EXPECT_EQ(numbers_of(sss::read_image_attribute(t.path, "utcOffset")),
              std::vector<double>{-7200.0});
    std::tm tm{};
    std::string date = sss::read_image_attribute(t.path, "capDate");
    ASSERT_TRUE(strptime(date.c_str(), "%Y:%m:%d %H:%M:%S", &tm)) << date;
    // Read as UTC, the local stamp is two hours later than the true time.
    double ahead = double(timegm(&tm) - before);
    EXPECT_GE(ahead, 7200.0 - 1.0);
    EXPECT_LE(ahead, 7200.0 + 5.0);
}

TEST(ImageIoExr, AovDisplayWritesItsOwnFile) {
    sss::test::TempDir dir("image_io");
    Image img = test_image();
    DisplayTarget t = sss::resolve_display(
        display(dir.file("diffuse.exr"), "openexr", "color diffuse", true), img, false);
    sss::write_display(img, t, test_metadata());
    Image back = sss::read_image(t.path);
    ASSERT_EQ(back.channels, (Names{"R", "G", "B"}));
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x)
            for (int c = 0; c < 3; ++c)
                EXPECT_EQ(
                    back.pixel(x, y)[c],
                    img.pixel(x, y)[img.channel_index("diffuse." + back.channels[c])]);
}

TEST(ImageIoExr, ItAndFramebufferWriteAFile) {
    sss::test::TempDir dir("image_io");
    Image img = test_image();
    for (std::string type : {"it", "framebuffer"}) {
        DisplayTarget t =
            sss::resolve_display(display(dir.file(type), type, "rgba"), img, true);
        sss::write_display(img, t, test_metadata());
        EXPECT_EQ(t.path, dir.file(type + ".exr"));
        EXPECT_EQ(format_of(t.path), "openexr");
        EXPECT_EQ(sss::read_image(t.path).channel_count(), 10);
    }
    EXPECT_EQ(folder_files(dir.path()), (Names{"framebuffer.exr", "it.exr"}));
}

// ---------------------------------------------------------------------------
// 8-bit formats
// ---------------------------------------------------------------------------

TEST(ImageIo8Bit, PngIsLinearTimes255WithStraightAlpha) {
    sss::test::TempDir dir("image_io");
    Image img(4, 1, {"R", "G", "B", "A"});
    auto set = [&](int x, float r, float g, float b, float a) {
        float* p = img.pixel(x, 0);
        p[0] = r, p[1] = g, p[2] = b, p[3] = a;
    };
    set(0, 0.5f, 0.0f, 1.0f, 1.0f);    // opaque: round(0.5 * 255) = 128
    set(1, 0.25f, 0.1f, 0.5f, 0.5f);   // premultiplied half coverage
    set(2, 0.0f, 0.0f, 0.0f, 0.0f);    // empty
    set(3, 3.0f, -1.0f, 0.002f, 1.0f); // clamped; 0.002 * 255 = 0.51
    // No dither: the values are exactly round(255 v) (PRMan's quantize
    // 0 255 0 255, no sRGB curve).
    DisplaySpec spec = display(dir.file("b.png"), "png", "rgba");
    set_numbers(spec, "dither", {0.0});
    DisplayTarget t = sss::resolve_display(spec, img, true);
    EXPECT_EQ(t.bits, 8);
    sss::write_display(img, t, test_metadata());

    EXPECT_EQ(format_of(t.path), "png");
    EXPECT_EQ(pixel_type_of(t.path, 0), OIIO::TypeDesc::UINT8);
    Image back = sss::read_image(t.path);
    ASSERT_EQ(back.channels, (Names{"R", "G", "B", "A"}));
    auto byte = [&](int x, int c) {
        return int(std::lround(back.pixel(x, 0)[c] * 255.0f));
    };
    EXPECT_EQ(byte(0, 0), 128);
    EXPECT_EQ(byte(0, 1), 0);
    EXPECT_EQ(byte(0, 2), 255);
    EXPECT_EQ(byte(0, 3), 255);
    // (0.25, 0.1, 0.5) / 0.5 = (0.5, 0.2, 1.0)
    EXPECT_EQ(byte(1, 0), 128);
    EXPECT_EQ(byte(1, 1), 51);
    EXPECT_EQ(byte(1, 2), 255);
    EXPECT_EQ(byte(1, 3), 128);
    for (int c = 0; c < 4; ++c) EXPECT_EQ(byte(2, c), 0);
    EXPECT_EQ(byte(3, 0), 255);
    EXPECT_EQ(byte(3, 1), 0);
    EXPECT_EQ(byte(3, 2), 1);
    EXPECT_EQ(byte(3, 3), 255);

    EXPECT_EQ(sss::read_image_attribute(t.path, "Software"), "render (sss) 0.1.0");
    EXPECT_EQ(sss::read_image_attribute(t.path, "ImageDescription"),
              "render -frame 3 scene.rib");
    EXPECT_EQ(sss::read_image_attribute(t.path, "sss:commandLine"),
              "render -frame 3 scene.rib");
}

TEST(ImageIo8Bit, TiffAndAovPng) {
    sss::test::TempDir dir("image_io");
    Image img = test_image();
    DisplayTarget t =
        sss::resolve_display(display(dir.file("b.tif"), "tiff", "rgba"), img, true);
    sss::write_display(img, t, test_metadata());
    EXPECT_EQ(format_of(t.path), "tiff");
    EXPECT_EQ(pixel_type_of(t.path, 0), OIIO::TypeDesc::UINT8);
    Image back = sss::read_image(t.path);
    ASSERT_EQ(back.channels, (Names{"R", "G", "B", "A"}));
    // Pixel (1, 0): R = 11/64 over A = 14/64; the default dither (0.5)
    // moves a value by at most one step.
    double straight = (11.0 / 64.0) / (14.0 / 64.0);
    EXPECT_LE(std::abs(std::lround(back.pixel(1, 0)[0] * 255.0) - straight * 255.0), 1.0);
    EXPECT_LE(std::abs(std::lround(back.pixel(1, 0)[3] * 255.0) - 14.0 / 64.0 * 255.0),
              1.0);
    EXPECT_EQ(sss::read_image_attribute(t.path, "Software"), "render (sss) 0.1.0");

    // An AOV in a PNG of its own: R G B from diffuse.*, no alpha so no division.
    DisplayTarget d = sss::resolve_display(
        display(dir.file("d.png"), "file", "diffuse", true), img, false);
    sss::write_display(img, d, test_metadata());
    Image db = sss::read_image(d.path);
    ASSERT_EQ(db.channels, (Names{"R", "G", "B"}));
    double lin = img.pixel(0, 0)[img.channel_index("diffuse.G")]; // 6/64
    EXPECT_LE(std::abs(std::lround(db.pixel(0, 0)[1] * 255.0) - lin * 255.0), 1.0);
}

TEST(ImageIo8Bit, AlphaOnlyPngAndJpeg) {
    sss::test::TempDir dir("image_io");
    Image img = test_image();
    DisplayTarget a =
        sss::resolve_display(display(dir.file("a.png"), "png", "a", true), img, false);
    sss::write_display(img, a, test_metadata());
    Image ab = sss::read_image(a.path);
    ASSERT_EQ(ab.channel_count(), 1);
    // Alpha is written linear: pixel (2, 1) has A = (7 * 11 + 3) / 64 > 1 -> 255,
    // pixel (0, 0) has A = 3/64 (give or take the dither's one step).
    EXPECT_LE(std::abs(std::lround(ab.pixel(0, 0)[0] * 255.0) - 3.0 / 64.0 * 255.0), 1.0);
    EXPECT_EQ(std::lround(ab.pixel(2, 1)[0] * 255.0), 255);

    DisplayTarget j =
        sss::resolve_display(display(dir.file("b.jpg"), "it", "rgba"), img, true);
    EXPECT_EQ(j.path, dir.file("b.jpg"));
    sss::write_display(img, j, test_metadata());
    EXPECT_EQ(format_of(j.path), "jpeg");
    EXPECT_EQ(sss::read_image(j.path).channel_count(), 3);
}

// ---------------------------------------------------------------------------
// Failures leave nothing behind
// ---------------------------------------------------------------------------

TEST(ImageIoErrors, NonFiniteValuesWriteNothing) {
    sss::test::TempDir dir("image_io");
    Image img = test_image();
    const std::string path = dir.file("b.exr");
    {
        std::ofstream old(path);
        old << "previous frame";
    }
    DisplayTarget t = sss::resolve_display(display(path, "openexr", "rgba"), img, true);
    for (float bad : {std::nanf(""), INFINITY, -INFINITY}) {
        Image broken = img;
        broken.pixel(3, 2)[broken.channel_index("specular.G")] = bad;
        try {
            sss::write_display(broken, t, test_metadata());
            ADD_FAILURE() << "no ValueError for " << bad;
        } catch (const sss::ValueError& e) {
            std::string m = e.what();
            EXPECT_NE(m.find("specular.G"), std::string::npos) << m;
            EXPECT_NE(m.find("(3, 2)"), std::string::npos) << m;
            EXPECT_NE(m.find(path), std::string::npos) << m;
        }
    }
    // A NaN in a channel that is not written does not matter.
    Image other = img;
    other.pixel(0, 0)[other.channel_index("Z")] = std::nanf("");
    DisplayTarget png =
        sss::resolve_display(display(dir.file("c.png"), "png", "rgb"), img, true);
    EXPECT_NO_THROW(sss::write_display(other, png, test_metadata()));

    EXPECT_EQ(file_text(path), "previous frame");
    EXPECT_EQ(folder_files(dir.path()), (Names{"b.exr", "c.png"}));
}

TEST(ImageIoErrors, MissingFolderIsAnIoError) {
    sss::test::TempDir dir("image_io");
    Image img = test_image();
    const std::string path = dir.file("no/such/folder/b.exr");
    DisplayTarget t = sss::resolve_display(display(path, "openexr", "rgba"), img, true);
    try {
        sss::write_display(img, t, test_metadata());
        ADD_FAILURE() << "no IoError";
    } catch (const sss::IoError& e) {
        EXPECT_EQ(e.path(), path);
    }
    EXPECT_FALSE(fs::exists(dir.path() / "no"));
    EXPECT_TRUE(folder_files(dir.path()).empty());
}

TEST(ImageIoErrors, FailedWritesLeaveTheTargetUntouched) {
    sss::test::TempDir dir("image_io");
    Image img = test_image();
    const std::string path = dir.file("b.png");
    {
        std::ofstream old(path);
        old << "previous frame";
    }
    // A mode error: nothing is resolved, nothing written.
    EXPECT_THROW(sss::resolve_display(display(path, "png", "rgba,nosuchaov"), img, true),
                 sss::ValueError);
    // Channels the image lacks, in a hand-made target: caught before writing.
    DisplayTarget missing{path, "png", {"R", "G", "X"}, {"R", "G", "B"}};
    EXPECT_THROW(sss::write_display(img, missing, test_metadata()), sss::ValueError);
    // A failure inside the writer, once the temporary exists: PNG cannot hold
    // five channels (resolve_display would have refused this target).
    DisplayTarget five{path, "png", {"R", "G", "B", "A", "Z"}, {"R", "G", "B", "A", "Z"}};
    EXPECT_THROW(sss::write_display(img, five, test_metadata()), sss::IoError);
    // An unknown format.
    DisplayTarget unknown{path, "nosuchformat", {"R"}, {"R"}};
    EXPECT_THROW(sss::write_display(img, unknown, test_metadata()), sss::IoError);

    EXPECT_EQ(file_text(path), "previous frame");
    EXPECT_EQ(folder_files(dir.path()), (Names{"b.png"}));
}

TEST(ImageIoRead, Errors) {
    sss::test::TempDir dir("image_io");
    EXPECT_THROW(sss::read_image(dir.file("none.exr")), sss::IoError);
    EXPECT_THROW(sss::read_image_attribute(dir.file("none.exr"), "Software"),
                 sss::IoError);
    {
        std::ofstream junk(dir.file("junk.exr"));
        junk << "not an image";
    }
    EXPECT_THROW(sss::read_image(dir.file("junk.exr")), sss::FormatError);
}

// ---------------------------------------------------------------------------
// Exposure and quantize (PRMan's Display "quantize" / "dither")
// ---------------------------------------------------------------------------

TEST(ImageIoQuantize, DitherStaysWithinOneStepAndIsReproducible) {
    sss::test::TempDir dir("image_io");
    Image img(32, 8, {"R", "G", "B"});
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x)
            for (int c = 0; c < 3; ++c) img.pixel(x, y)[c] = (x + 32 * y + c) / 300.0f;
    DisplaySpec spec = display(dir.file("d.png"), "png", "rgb");
    set_numbers(spec, "dither", {0.5});
    DisplayTarget t = sss::resolve_display(spec, img, true);
    sss::write_display(img, t, test_metadata());
    Image back = sss::read_image(t.path);
    int moved = 0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x)
            for (int c = 0; c < 3; ++c) {
                const double exact = 255.0 * img.pixel(x, y)[c];
                const long got = std::lround(back.pixel(x, y)[c] * 255.0f);
                EXPECT_LE(std::abs(got - exact), 1.0) << x << " " << y << " " << c;
                moved += got != std::lround(exact);
            }
    // Amplitude 0.5 moves a value whose fraction is within r/2 of .5.
    EXPECT_GT(moved, 20);
    // The noise is a hash of (pixel, channel): a second file is identical
    // (so is one written by any other thread count). Both files are written
    // at one pinned capture time: the DateTime attribute has a resolution of
    // a second, and two writes that straddled one differed there.
    ::setenv("SOURCE_DATE_EPOCH", "1700000000", 1);
    sss::write_display(img, t, test_metadata());
    const auto pinned = sss::test::read_bytes(t.path);
    sss::write_display(img, t, test_metadata());
    EXPECT_EQ(sss::test::read_bytes(t.path), pinned);
    ::unsetenv("SOURCE_DATE_EPOCH");
    for (int k = 0; k < 4; ++k) {
        const double r = sss::dither_noise(3, 5, k);
        EXPECT_GE(r, -1.0);
        EXPECT_LT(r, 1.0);
        EXPECT_EQ(r, sss::dither_noise(3, 5, k));
    }
    EXPECT_NE(sss::dither_noise(3, 5, 0), sss::dither_noise(3, 5, 1));
}

TEST(ImageIoQuantize, ExposureGainAndGamma) {
    sss::test::TempDir dir("image_io");
    Image img(1, 1, {"R", "G", "B", "A", "Z", "diffuse.R", "occ"});
    float* p = img.pixel(0, 0);
    p[0] = 0.18f, p[1] = 0.02f, p[2] = 0.0f, p[3] = 1.0f, p[4] = 7.0f, p[5] = 0.08f,
    p[6] = 0.5f;
    sss::DisplayDefaults exposure;
    exposure.exposure_gain = 2.0;
    exposure.exposure_gamma = 2.0;
    // PNG, no dither: (2 v)^(1/2) * 255.
    DisplaySpec spec = display(dir.file("e.png"), "png", "rgba");
    set_numbers(spec, "dither", {0.0});
    DisplayTarget t = sss::resolve_display(spec, img, true, exposure);
    sss::write_display(img, t, test_metadata());
    Image back = sss::read_image(t.path);
    EXPECT_EQ(std::lround(back.pixel(0, 0)[0] * 255.0), 153); // sqrt(0.36) = 0.6
    EXPECT_EQ(std::lround(back.pixel(0, 0)[1] * 255.0), 51);  // sqrt(0.04) = 0.2
    EXPECT_EQ(std::lround(back.pixel(0, 0)[2] * 255.0), 0);
    EXPECT_EQ(std::lround(back.pixel(0, 0)[3] * 255.0), 255); // alpha untouched
    // EXR: colour and colour layers exposed; alpha, Z and float AOVs not.
    DisplaySpec e = display(dir.file("e.exr"), "openexr", "rgbaz");
    set_string(e, "type", "float");
    DisplayTarget te = sss::resolve_display(e, img, true, exposure);
    sss::write_display(img, te, test_metadata());
    Image eb = sss::read_image(te.path);
    auto value = [&](const std::string& c) {
        return eb.pixel(0, 0)[eb.channel_index(c)];
    };
    EXPECT_NEAR(value("R"), 0.6f, 1e-6f);
    EXPECT_NEAR(value("diffuse.R"), 0.4f, 1e-6f);
    EXPECT_EQ(value("A"), 1.0f);
    EXPECT_EQ(value("Z"), 7.0f);
    EXPECT_EQ(value("occ"), 0.5f);
}

TEST(ImageIoQuantize, SixteenBitsFloatTiffAndErrors) {
    sss::test::TempDir dir("image_io");
    Image img(2, 1, {"R", "G", "B"});
    for (int c = 0; c < 3; ++c) img.pixel(0, 0)[c] = 0.25f + 0.125f * c;
    for (int c = 0; c < 3; ++c) img.pixel(1, 0)[c] = 1.5f;
    DisplaySpec spec = display(dir.file("w.png"), "png", "rgb");
    set_numbers(spec, "quantize", {0, 65535, 0, 65535});
    set_numbers(spec, "dither", {0});
    DisplayTarget t = sss::resolve_display(spec, img, true);
    EXPECT_EQ(t.bits, 16);
    sss::write_display(img, t, test_metadata());
    EXPECT_EQ(pixel_type_of(t.path, 0), OIIO::TypeDesc::UINT16);
    Image back = sss::read_image(t.path);
    EXPECT_EQ(std::lround(back.pixel(0, 0)[0] * 65535.0), 16384); // round(16383.75)
    EXPECT_EQ(std::lround(back.pixel(1, 0)[0] * 65535.0), 65535); // clamped to max
    // zero, min and max: round(10 + 100 v) in [20, 60].
    DisplaySpec z = display(dir.file("z.png"), "png", "rgb");
    set_numbers(z, "quantize", {10, 100, 20, 60});
    set_numbers(z, "dither", {0});
    DisplayTarget tz = sss::resolve_display(z, img, true);
    sss::write_display(img, tz, test_metadata());
    Image zb = sss::read_image(tz.path);
    EXPECT_EQ(std::lround(zb.pixel(0, 0)[0] * 255.0), 35); // 10 + 25
    EXPECT_EQ(std::lround(zb.pixel(0, 0)[2] * 255.0), 60); // 10 + 50 = 60
    EXPECT_EQ(std::lround(zb.pixel(1, 0)[0] * 255.0), 60); // 160 -> max
    // one = 0: float pixels in a TIFF, unquantised.
    DisplaySpec f = display(dir.file("f.tif"), "tiff", "rgb");
    set_numbers(f, "quantize", {0, 0, 0, 0});
    DisplayTarget tf = sss::resolve_display(f, img, true);
    EXPECT_EQ(tf.bits, 32);
    sss::write_display(img, tf, test_metadata());
    EXPECT_EQ(pixel_type_of(tf.path, 0), OIIO::TypeDesc::FLOAT);
    EXPECT_EQ(sss::read_image(tf.path).pixel(0, 0)[1], 0.375f);
    // Defaults from the scene's Quantize, which a Display's parameters override.
    sss::DisplayDefaults scene;
    scene.quantize = sss::QuantizeSpec{0, 1023, 0, 1023, 0};
    EXPECT_EQ(
        sss::resolve_display(display("s.tif", "tiff", "rgb"), img, true, scene).bits, 16);
    EXPECT_EQ(
        sss::resolve_display(display("s.exr", "openexr", "rgb"), img, true, scene).half,
        true);
    // Errors: PNG cannot hold floats, JPEG 16 bits, bad parameter shapes.
    DisplaySpec fp = display("f.png", "png", "rgb");
    set_numbers(fp, "quantize", {0, 0, 0, 0});
    EXPECT_THROW(sss::resolve_display(fp, img, true), sss::ValueError);
    DisplaySpec j = display("j.jpg", "jpeg", "rgb");
    set_numbers(j, "quantize", {0, 65535, 0, 65535});
    EXPECT_THROW(sss::resolve_display(j, img, true), sss::ValueError);
    DisplaySpec bad = display("b.png", "png", "rgb");
    set_numbers(bad, "quantize", {0, 255, 0});
    EXPECT_THROW(sss::resolve_display(bad, img, true), sss::ValueError);
    DisplaySpec neg = display("b.png", "png", "rgb");
    set_numbers(neg, "dither", {-1});
    EXPECT_THROW(sss::resolve_display(neg, img, true), sss::ValueError);
}
