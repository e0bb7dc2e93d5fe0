// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file engine_textures_test.cpp
/// The shading engine's texture calls (texture, environment, texture3d)
/// answered by the job's TextureLibrary, as ptbake and render run them:
/// the corpus's texture shaders, 2-D lookups, and texture3d on clouds and
/// brick maps (hits, misses, unreadable files).
///
/// Suite names start with "RslCorpus" and "RslEngineTextures".

#include <gtest/gtest.h>

#include <fstream>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include <OpenImageIO/imagebuf.h>

#include "shading/corpus_harness.h"
#include "shading/engine_test_util.h"
#include "sss/binding/texture_library.h"
#include "sss/brick/brickmap.h"
#include "sss/cloud/point_cloud.h"
#include "sss/cloud/point_cloud_io.h"
#include "test_util.h"

namespace {

using namespace sss;
using namespace sss::test;

/// An engine whose services look textures up in a job's TextureLibrary.
struct TexturedEngine : Engine {
    TextureLibrary library;
    TexturedEngine() { services.texture_services = &library; }
};

/// Writes a float image of `channels` channels with value(x, y, c).
template <class F>
std::string write_image(const std::string& path, int w, int h, int channels, F value) {
    OIIO::ImageBuf buf(OIIO::ImageSpec(w, h, channels, OIIO::TypeDesc::FLOAT));
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            float v[4];
            for (int c = 0; c < channels; ++c) v[c] = value(x, y, c);
            buf.setpixel(x, y, v, channels);
        }
    EXPECT_TRUE(buf.write(path)) << buf.geterror();
    return path;
}

TEST(RslCorpus, Textures) {
    TempDir dir;
    const std::string map =
        write_image(dir.file("map.exr"), 4, 2, 3, [](int x, int y, int c) {
            return c == 0 ? (x + 0.5f) / 4 : c == 1 ? (y + 0.5f) / 2 : 0.25f + 0.1f * x;
        });
    const std::string env = write_image(dir.file("env.exr"), 8, 4, 3,
                                        [](int, int, int c) { return 0.2f * (c + 1); });
    TexturedEngine e;
    ParamList params;
    params.set(string_param("map", map));
    params.set(string_param("env", env));
    run_corpus("textures.sl", plane_grid(4, 2), params, &e);
    EXPECT_TRUE(e.services.warnings.empty()) << e.services.warnings[0];
}

TEST(RslCorpus, Bake3dAndTexture3d) {
    TempDir dir;
    // A 1 x 1 square on world z = 0, normals -z (towards the camera below).
    PointCloud cloud;
    const int n = 32;
    cloud.resize(std::size_t(n) * n);
    // Every channel first: adding one may move the others.
    cloud.add_channel("v", ChannelType::Float);
    cloud.add_channel("c", ChannelType::Color);
    cloud.add_channel("x", ChannelType::Float);
    Channel& v = *cloud.find_channel("v");
    Channel& c = *cloud.find_channel("c");
    Channel& x = *cloud.find_channel("x");
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const std::size_t k = std::size_t(j) * n + i;
            cloud.positions[k] = {(i + 0.5f) / n - 0.5f, (j + 0.5f) / n - 0.5f, 0.0f};
            cloud.normals[k] = {0.0f, 0.0f, -1.0f};
            cloud.radii[k] = 0.5f / n;
            v.data[k] = 0.25f;
            c.data[3 * k] = 0.1f;
            c.data[3 * k + 1] = 0.2f;
            c.data[3 * k + 2] = 0.3f;
            x.data[k] = cloud.positions[k].x;
        }
    const std::string ptc = dir.file("square.ptc"), bkm = dir.file("square.bkm");
    write_point_cloud(cloud, ptc);
    build_brick_map({cloud}, BrickMapBuildOptions{}, bkm);

    TexturedEngine e;
    e.services.scene_.options.camera.world_to_camera =
        glm::translate(Matrix4(1.0), glm::dvec3(0, 0, 1));
    ShadingBatch b = plane_grid(6, 6);
    b.Cs.assign(b.size, glm::vec3(0.5f, 0.25f, 1.0f));
    ParamList params;
    params.set(string_param("cloud", ptc));
    params.set(string_param("bkm", bkm));
    params.set(string_param("out", "baked.ptc"));
    run_corpus("bake3d_texture3d.sl", b, params, &e);
    // What bake3d sent: world-space points on z = 0, the channels per point.
    ASSERT_EQ(e.services.bakes.size(), 1u);
    const Bake3dRecord& rec = e.services.bakes[0];
    EXPECT_EQ(rec.file, "baked.ptc");
    EXPECT_EQ(rec.channels, (std::vector<std::string>{"a", "col"}));
    EXPECT_EQ(rec.channel_floats, (std::vector<int>{1, 3}));
    ASSERT_EQ(rec.P.size(), b.size);
    ASSERT_EQ(rec.values.size(), 4 * b.size);
    for (std::size_t i = 0; i < b.size; ++i) {
        EXPECT_NEAR(rec.P[i].x, b.P[i].x, 1e-6);
        EXPECT_NEAR(rec.P[i].z, 0.0f, 1e-6);
        EXPECT_NEAR(rec.N[i].z, -1.0f, 1e-6);
        EXPECT_EQ(rec.radius[i], 0.05f);
        EXPECT_NEAR(rec.values[4 * i], b.u[i], 1e-6);
        EXPECT_NEAR(rec.values[4 * i + 1], 0.5f, 1e-6);
        EXPECT_NEAR(rec.values[4 * i + 3], 1.0f, 1e-6);
    }
}

TEST(RslEngineTextures, Bake3dRecordsAndTexture3dMisses) {
    // A cloud whose only point is far from the plane: every lookup misses.
    sss::test::TempDir dir;
    const std::string cloud_file = dir.file("far.ptc");
    {
        PointCloud cloud;
        cloud.resize(1);
        cloud.add_channel("a", ChannelType::Float);
        cloud.positions[0] = glm::vec3(100.0f, 100.0f, 100.0f);
        cloud.normals[0] = glm::vec3(0.0f, 0.0f, 1.0f);
        cloud.radii[0] = 0.01f;
        cloud.find_channel("a")->data[0] = 3.0f;
        write_point_cloud(cloud, cloud_file, {});
    }
    TexturedEngine e;
    e.services.scene_.options.camera.world_to_camera =
        glm::translate(Matrix4(1.0), glm::dvec3(0, 0, 2));
    ShadingBatch b = plane_grid(4, 2);
    b.Cs.assign(b.size, glm::vec3(0.5f, 0.25f, 1.0f));
    ShaderInstance inst = e.instance(R"(
surface t(string cloud = "";
          output varying float r = 0; output varying float x = 7; output varying float y = 0;) {
    if (u > 0.5)
        y = bake3d("out.ptc", "a, col", P, N, "a", u, "col", Cs, "radius", 0.25, "interpolate", 1);
    r = texture3d(cloud, P, N, "a", x);
}
)");
    ParamList params;
    Param file;
    file.name = "cloud";
    file.type = ParamType::String;
    file.strings = {cloud_file};
    params.set(file);
    ShaderInstance with_cloud(inst.program_ptr(), params, Matrix4(1.0), "test.rib:1");
    e.context.execute(with_cloud, b);
    ASSERT_EQ(e.services.bakes.size(), 1u);
    const Bake3dRecord& rec = e.services.bakes[0];
    EXPECT_EQ(rec.file, "out.ptc");
    ASSERT_EQ(rec.channels, (std::vector<std::string>{"a", "col"}));
    EXPECT_EQ(rec.channel_floats, (std::vector<int>{1, 3}));
    ASSERT_EQ(rec.P.size(), 4u);
    ASSERT_EQ(rec.values.size(), 16u);
    EXPECT_EQ(rec.radius[0], 0.25f);
    EXPECT_NEAR(rec.P[0].z, -1.0f, 1e-6); // camera z 1 -> world -1
    EXPECT_NEAR(rec.values[0], 0.625f, 1e-6);
    EXPECT_NEAR(rec.values[1], 0.5f, 1e-6);
    TypeSpec ty;
    std::vector<float> r, x, y;
    e.context.output("r", ty, r);
    e.context.output("x", ty, x);
    e.context.output("y", ty, y);
    for (std::size_t i = 0; i < b.size; ++i) {
        EXPECT_EQ(r[i], 0.0f);
        EXPECT_EQ(x[i], 7.0f);
        EXPECT_EQ(y[i], b.u[i] > 0.5f ? 1.0f : 0.0f);
    }

    // A file that cannot be read stops the shader with an error naming it.
    try {
        e.context.execute(inst, b);
        FAIL() << "no error for a cloud named \"\"";
    } catch (const ShaderRuntimeError& err) {
        EXPECT_NE(std::string(err.what()).find("texture3d"), std::string::npos)
            << err.what();
    }
}

TEST(RslEngineTextures, TextureLooksUpThePixels) {
    sss::test::TempDir dir;
    const std::string file = dir.file("two.ppm");
    {
        std::ofstream out(file);
        out << "P3\n2 1\n255\n255 0 0  0 0 255\n";
    }
    TexturedEngine e;
    ShadingBatch b = plane_grid(2, 1); // s = 0.25, 0.75
    ShaderInstance inst = e.instance(R"(
surface t(string map = "";) {
    Ci = color texture(map, "width", 0);
    Oi = float texture(map[2], s, t, "width", 0);
}
)",
                                     [&] {
                                         ParamList p;
                                         p.set(string_param("map", file));
                                         return p;
                                     }());
    e.context.execute(inst, b);
    EXPECT_NEAR(b.Ci[0].x, 1.0f, 1e-3);
    EXPECT_NEAR(b.Ci[0].z, 0.0f, 1e-3);
    EXPECT_NEAR(b.Ci[1].x, 0.0f, 1e-3);
    EXPECT_NEAR(b.Ci[1].z, 1.0f, 1e-3);
    EXPECT_NEAR(b.Oi[0].x, 0.0f, 1e-3); // blue channel
    EXPECT_NEAR(b.Oi[1].y, 1.0f, 1e-3);
    EXPECT_TRUE(e.services.warnings.empty());
}

TEST(RslEngineTextures, EmptyMapNamesGiveZeroQuietlyAMissingMapIsAnError) {
    // Library shaders call texture(), environment() and shadow() unguarded
    // with an empty default: 0, as in PRMan, and no warning.
    TexturedEngine e;
    ShadingBatch b = plane_grid(2, 1);
    const char* source = R"(
surface t(string map = ""; string env = ""; string shad = "";) {
    Ci = color texture(map) + color environment(env, I) + color (1 - shadow(shad, P));
    Oi = float texture(map[1], s, t) + float environment(env[2], N);
}
)";
    ShaderInstance inst = e.instance(source);
    e.context.execute(inst, b);
    for (std::size_t i = 0; i < b.size; ++i) {
        EXPECT_EQ(b.Ci[i], glm::vec3(1.0f)) << i;
        EXPECT_EQ(b.Oi[i], glm::vec3(0.0f)) << i;
    }
    EXPECT_TRUE(e.services.warnings.empty());
    // A named map that is missing stops the shader with an error naming it.
    ShaderInstance missing = e.instance(source, [&] {
        ParamList p;
        p.set(string_param("map", "no_such_map.tx"));
        return p;
    }());
    try {
        e.context.execute(missing, b);
        FAIL() << "no error for a missing map";
    } catch (const ShaderRuntimeError& err) {
        EXPECT_NE(std::string(err.what()).find("no_such_map.tx"), std::string::npos)
            << err.what();
    }
}

} // namespace
