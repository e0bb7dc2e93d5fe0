// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file shadow_maps_test.cpp
/// Depth maps and cube-face environments through the job's TextureLibrary:
/// RSL's shadow() on a hand-made depth map (both forms, bias, a missing
/// map), MakeShadow (textureinfo of the result, up-to-date maps kept, a
/// missing zfile), and MakeCubeFaceEnvironment (six flat faces looked up
/// along the six axes, and the faces' orientation).
///
/// Suite names start with "ShadowMaps" and "CubeFaceEnvironment".

#include <gtest/gtest.h>

#include <array>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imageio.h>

#include "shading/engine_test_util.h"
#include "sss/binding/texture_library.h"
#include "sss/light/shadow_map.h"
#include "sss/util/error.h"
#include "test_util.h"

namespace {

using namespace sss;
using namespace sss::test;

/// An engine whose services look textures up in a job's TextureLibrary.
struct TexturedEngine : Engine {
    TextureLibrary library;
    TexturedEngine() { services.texture_services = &library; }
};

/// A zfile: n x n depths over the map, depth(x, y), with the matrices
/// (column-vector; stored row-vector, as render writes them).
std::string write_zfile(const std::string& path, int n, float (*depth)(int, int),
                        const Matrix4& world_to_camera, const Matrix4& world_to_screen) {
    OIIO::ImageSpec spec(n, n, 1, OIIO::TypeDesc::FLOAT);
    spec.channelnames = {"Z"};
    const glm::mat4 c(world_to_camera), s(world_to_screen);
    spec.attribute("worldtocamera", OIIO::TypeMatrix, glm::value_ptr(c));
    spec.attribute("worldtoscreen", OIIO::TypeMatrix, glm::value_ptr(s));
    std::vector<float> z;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) z.push_back(depth(x, y));
    auto out = OIIO::ImageOutput::create("openexr");
    EXPECT_TRUE(out && out->open(path, spec));
    EXPECT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, z.data()));
    out->close();
    return path;
}

/// The left half of the map (world x < 0) holds a surface at depth 0.5.
float left_half(int x, int) {
    return x < 4 ? 0.5f : 1e30f;
}

Param text_param(const std::string& name, const std::string& v) {
    return string_param(name, v);
}

TEST(ShadowMaps, ShadowLooksUpTheDepthMap) {
    TempDir dir;
    // Camera = world; the map covers x, y in [-1, 1] (orthographic).
    const std::string map =
        write_zfile(dir.file("half.z"), 8, left_half, Matrix4(1.0), Matrix4(1.0));
    TexturedEngine e;
    ShadingBatch b = plane_grid(4, 2); // P = (u - 0.5, v - 0.5, 1)
    ShaderInstance inst = e.instance(R"(
surface t(string map = ""; float bias = 0;
          output varying float r = 0; output varying float g = 0;
          output varying float area = 0;) {
    r = shadow(map, P, "bias", bias);
    color c = shadow(map[0], P, "bias", bias, "samples", 4);
    g = comp(c, 1);
    area = shadow(map, point(-0.25, 0, 1), point(0.25, 0, 1), point(-0.25, 0.1, 1),
                  point(0.25, 0.1, 1), "samples", 64, "bias", 0);
}
)",
                                     [&] {
                                         ParamList p;
                                         p.set(text_param("map", map));
                                         return p;
                                     }());
    e.context.execute(inst, b);
    TypeSpec ty;
    std::vector<float> r, g, area;
    ASSERT_TRUE(e.context.output("r", ty, r));
    ASSERT_TRUE(e.context.output("g", ty, g));
    ASSERT_TRUE(e.context.output("area", ty, area));
    for (std::size_t i = 0; i < b.size; ++i) {
        const float want = b.P[i].x < 0.0f ? 1.0f : 0.0f; // behind the left half
        EXPECT_EQ(r[i], want) << i;
        EXPECT_EQ(g[i], want) << i;
        // The quad straddles the edge: half of it is shadowed.
        EXPECT_NEAR(area[i], 0.5f, 0.07f) << i;
    }
    EXPECT_TRUE(e.services.warnings.empty());

    // A bias past the gap (1 - 0.5) lights everything; so does the scene's.
    ShaderInstance biased(
        inst.program_ptr(),
        [&] {
            ParamList p;
            p.set(text_param("map", map));
            p.set(float_param("bias", 0.6));
            return p;
        }(),
        Matrix4(1.0), "test.rib:2");
    e.context.execute(biased, b);
    ASSERT_TRUE(e.context.output("r", ty, r));
    for (std::size_t i = 0; i < b.size; ++i) EXPECT_EQ(r[i], 0.0f) << i;
    ShaderInstance plain = e.instance(R"(
surface t(string map = ""; output varying float r = 0;) { r = shadow(map, P); }
)",
                                      [&] {
                                          ParamList p;
                                          p.set(text_param("map", map));
                                          return p;
                                      }());
    e.context.execute(plain, b); // the default bias (0.225) is below the gap
    ASSERT_TRUE(e.context.output("r", ty, r));
    EXPECT_EQ(r[0], 1.0f);
    e.services.scene_.options.groups["shadow"].set(float_param("bias", 0.7));
    e.context.execute(plain, b);
    ASSERT_TRUE(e.context.output("r", ty, r));
    EXPECT_EQ(r[0], 0.0f);

    // A named map that is missing stops the shader with an error naming it.
    ShaderInstance missing(
        plain.program_ptr(),
        [&] {
            ParamList p;
            p.set(text_param("map", dir.file("nosuch.shd")));
            return p;
        }(),
        Matrix4(1.0), "test.rib:3");
    try {
        e.context.execute(missing, b);
        FAIL() << "no error for a missing shadow map";
    } catch (const ShaderRuntimeError& err) {
        EXPECT_NE(std::string(err.what()).find("nosuch.shd"), std::string::npos)
            << err.what();
    }
}

TEST(ShadowMaps, MakeShadowAndTextureinfo) {
    TempDir dir;
    const Matrix4 to_camera = glm::translate(Matrix4(1.0), glm::dvec3(1, 2, 3));
    const std::string zfile =
        write_zfile(dir.file("s.z"), 8, left_half, to_camera, Matrix4(1.0));
    TextureLibrary library;
    const std::string tex = dir.file("s.tex");
    EXPECT_TRUE(library.make_shadow(zfile, tex, "test.rib:3: MakeShadow"));
    // Up to date: kept.
    EXPECT_FALSE(library.make_shadow(zfile, tex, "test.rib:3: MakeShadow"));
    std::string type;
    ASSERT_TRUE(library.texture_info(tex, "type", 0, nullptr, &type));
    EXPECT_EQ(type, "shadow");
    float res[2] = {0, 0};
    ASSERT_TRUE(library.texture_info(tex, "resolution", 2, res, nullptr));
    EXPECT_EQ(res[0], 8.0f);
    EXPECT_EQ(res[1], 8.0f);
    // RenderMan's row-vector layout: the translation in the last row.
    float m[16] = {};
    ASSERT_TRUE(library.texture_info(tex, "viewingmatrix", 16, m, nullptr));
    EXPECT_EQ(m[12], 1.0f);
    EXPECT_EQ(m[13], 2.0f);
    EXPECT_EQ(m[14], 3.0f);
    ASSERT_TRUE(library.texture_info(tex, "projectionmatrix", 16, m, nullptr));
    EXPECT_EQ(m[0], 1.0f);
    // The map holds the zfile's depths.
    std::string error;
    auto map = library.shadow_map(tex, &error);
    ASSERT_TRUE(map) << error;
    EXPECT_EQ(map->width, 8);
    EXPECT_EQ(map->at(0, 0), 0.5f);
    EXPECT_EQ(map->at(7, 7), 1e30f);
    EXPECT_EQ(map->world_to_camera, to_camera);

    // A missing zfile is an error naming the RIB line.
    try {
        library.make_shadow(dir.file("none.z"), dir.file("none.tex"),
                            "test.rib:9: MakeShadow");
        FAIL() << "no error for a missing zfile";
    } catch (const IoError& err) {
        EXPECT_NE(std::string(err.what()).find("test.rib:9"), std::string::npos)
            << err.what();
    }
    // A picture without depth is not a zfile.
    OIIO::ImageBuf rgb(OIIO::ImageSpec(2, 2, 3, OIIO::TypeDesc::FLOAT));
    ASSERT_TRUE(rgb.write(dir.file("rgb.exr")));
    EXPECT_THROW(library.make_shadow(dir.file("rgb.exr"), dir.file("rgb.tex"), "x"),
                 IoError);
}

/// A flat n x n picture of colour c (left half `c`, right half `right`).
std::string write_face(const std::string& path, glm::vec3 c, glm::vec3 right,
                       bool split_rows = false) {
    const int n = 4;
    OIIO::ImageBuf buf(OIIO::ImageSpec(n, n, 3, OIIO::TypeDesc::FLOAT));
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const bool second = split_rows ? y >= n / 2 : x >= n / 2;
            const glm::vec3 v = second ? right : c;
            buf.setpixel(x, y, &v.x, 3);
        }
    EXPECT_TRUE(buf.write(path)) << buf.geterror();
    return path;
}

TEST(CubeFaceEnvironment, SixFacesAlongTheSixAxes) {
    TempDir dir;
    const std::array<glm::vec3, 6> colour = {glm::vec3(1, 0, 0), glm::vec3(0, 1, 0),
                                             glm::vec3(0, 0, 1), glm::vec3(1, 1, 0),
                                             glm::vec3(0, 1, 1), glm::vec3(1, 0, 1)};
    const char* names[6] = {"px", "nx", "py", "ny", "pz", "nz"};
    std::array<std::string, 6> faces;
    for (int f = 0; f < 6; ++f)
        faces[f] =
            write_face(dir.file(std::string(names[f]) + ".exr"), colour[f], colour[f]);
    TextureLibrary library;
    const std::string env = dir.file("cube.env");
    EXPECT_TRUE(library.make_cube_environment(faces, env, 90.0, "box", "test.rib:4"));
    EXPECT_FALSE(library.make_cube_environment(faces, env, 90.0, "box", "test.rib:4"));
    const std::vector<glm::vec3> dirs = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                         {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};
    std::vector<float> out(18, -1.0f);
    std::string error;
    ASSERT_TRUE(library.environment(env, 0, 3, TextureOptions{}, 6, dirs.data(), nullptr,
                                    nullptr, nullptr, out.data(), &error))
        << error;
    for (int f = 0; f < 6; ++f)
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(out[f * 3 + c], colour[f][c], 1e-4) << names[f] << " " << c;
    std::string type;
    ASSERT_TRUE(library.texture_info(env, "type", 0, nullptr, &type));
    EXPECT_EQ(type, "environment");
    // Faces of different sizes, an unknown filter: errors naming the request.
    EXPECT_THROW(library.make_cube_environment(faces, dir.file("bad.env"), 90.0,
                                               "nosuchfilter", "test.rib:5"),
                 IoError);
}

TEST(CubeFaceEnvironment, RenderManFaceOrientation) {
    // RenderMan's views from the cube's centre, left-handed: +x seen with +y
    // up has -z to its right; +y seen with +x to the right has -z up.
    TempDir dir;
    const glm::vec3 a(1, 0, 0), b(0, 0, 1), grey(0.5f);
    std::array<std::string, 6> faces;
    for (int f = 0; f < 6; ++f)
        faces[f] = write_face(dir.file("f" + std::to_string(f) + ".exr"), grey, grey);
    faces[0] = write_face(dir.file("px.exr"), a, b);       // left a, right b
    faces[2] = write_face(dir.file("py.exr"), a, b, true); // top a, bottom b
    faces[4] = write_face(dir.file("pz.exr"), a, b);       // left a, right b
    TextureLibrary library;
    const std::string env = dir.file("cube.env");
    library.make_cube_environment(faces, env, 90.0, "gaussian", "test.rib:4");
    const std::vector<glm::vec3> dirs = {{1, 0, 0.5f}, {1, 0, -0.5f}, {0, 1, -0.5f},
                                         {0, 1, 0.5f}, {-0.5f, 0, 1}, {0.5f, 0, 1}};
    std::vector<float> out(18, -1.0f);
    std::string error;
    ASSERT_TRUE(library.environment(env, 0, 3, TextureOptions{}, 6, dirs.data(), nullptr,
                                    nullptr, nullptr, out.data(), &error))
        << error;
    const glm::vec3 want[6] = {a, b, a, b, a, b};
    for (int k = 0; k < 6; ++k)
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(out[k * 3 + c], want[k][c], 1e-4) << k;
}

} // namespace
