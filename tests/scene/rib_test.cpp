// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file rib_test.cpp
/// Tests of the scene layer basics (sss/scene.h) and the RIB reader (sss/rib.h).

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <string>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/matrix.hpp>
#include <glm/vec4.hpp>

#include "sss/scene/rib.h"
#include "sss/scene/scene.h"
#include "sss/util/error.h"

namespace fs = std::filesystem;

namespace {

sss::Scene parse(const std::string& text, const sss::RibReadOptions& options = {}) {
    return sss::parse_rib(text, "test.rib", options);
}

glm::dvec3 apply(const sss::Matrix4& m, const glm::dvec3& p) {
    glm::dvec4 r = m * glm::dvec4(p, 1.0);
    return glm::dvec3(r) / r.w;
}

void expect_near(const glm::dvec3& a, const glm::dvec3& b, double tol = 1e-12) {
    EXPECT_NEAR(a.x, b.x, tol);
    EXPECT_NEAR(a.y, b.y, tol);
    EXPECT_NEAR(a.z, b.z, tol);
}

/// Expects parse(text) to throw RibError whose message contains every `parts`;
/// returns the error's line.
int expect_rib_error(const std::string& text, std::initializer_list<std::string> parts,
                     const sss::RibReadOptions& options = {}) {
    try {
        parse(text, options);
        ADD_FAILURE() << "no RibError for:\n" << text;
    } catch (const sss::RibError& e) {
        std::string what = e.what();
        for (const auto& part : parts)
            EXPECT_NE(what.find(part), std::string::npos)
                << "message '" << what << "' lacks '" << part << "'";
        return e.line();
    }
    return -1;
}

bool has_warning(const sss::Scene& scene, const std::string& part) {
    for (const auto& w : scene.warnings)
        if (w.find(part) != std::string::npos) return true;
    return false;
}

/// A fresh empty folder, removed at the end of the test.
class TempFolder {
public:
    TempFolder() {
        std::random_device rd;
        m_path = fs::temp_directory_path() / ("sss_rib_test_" + std::to_string(rd()));
        fs::create_directories(m_path);
    }
    ~TempFolder() {
        std::error_code ec;
        fs::remove_all(m_path, ec);
    }
    const fs::path& path() const { return m_path; }
    fs::path write(const std::string& name, const std::string& text) const {
        fs::path p = m_path / name;
        fs::create_directories(p.parent_path());
        std::ofstream out(p, std::ios::binary);
        out << text;
        return p;
    }

private:
    fs::path m_path;
};

const std::string kWorld = "WorldBegin\n";

} // namespace

// --- scene.h --------------------------------------------------------------

TEST(SceneBasis, NamedBasesHaveRiSpecMatricesAndSteps) {
    auto bezier = sss::named_basis("bezier");
    ASSERT_TRUE(bezier);
    EXPECT_EQ(bezier->step, 3);
    const double b[16] = {-1, 3, -3, 1, 3, -6, 3, 0, -3, 3, 0, 0, 1, 0, 0, 0};
    for (int k = 0; k < 16; ++k) EXPECT_EQ(bezier->matrix[k / 4][k % 4], b[k]) << k;

    auto cr = sss::named_basis("catmull-rom");
    ASSERT_TRUE(cr);
    EXPECT_EQ(cr->step, 1);
    // Row 1 of the RI matrix is (2 -5 4 -1)/2; column 1 is (3 -5 0 2)/2.
    EXPECT_DOUBLE_EQ(cr->matrix[1][0], 1.0);
    EXPECT_DOUBLE_EQ(cr->matrix[1][3], -0.5);
    EXPECT_DOUBLE_EQ(cr->matrix[0][1], 1.5);
    EXPECT_DOUBLE_EQ(cr->matrix[3][1], 1.0);

    auto bs = sss::named_basis("bspline");
    ASSERT_TRUE(bs);
    EXPECT_EQ(bs->name, "b-spline");
    EXPECT_EQ(bs->step, 1);
    EXPECT_DOUBLE_EQ(bs->matrix[3][1], 4.0 / 6.0);
    EXPECT_EQ(sss::named_basis("hermite")->step, 2);
    EXPECT_EQ(sss::named_basis("power")->step, 4);
    EXPECT_EQ(sss::named_basis("power")->matrix, sss::Matrix4(1.0));
    EXPECT_EQ(sss::named_basis("catmullrom")->name, "catmull-rom");
    EXPECT_FALSE(sss::named_basis("nurbs"));

    // The spline bases reproduce constants: the weights (t^3 t^2 t 1) * B of
    // the four control points add up to 1 for every t.
    for (const char* name : {"bezier", "b-spline", "catmull-rom"}) {
        auto basis = *sss::named_basis(name);
        for (double t : {0.0, 0.3, 1.0}) {
            glm::dvec4 tv(t * t * t, t * t, t, 1.0);
            double total = 0.0;
            for (int j = 0; j < 4; ++j) {
                double wj = 0.0;
                for (int i = 0; i < 4; ++i) wj += tv[i] * basis.matrix[i][j];
                total += wj;
            }
            EXPECT_NEAR(total, 1.0, 1e-12) << name << " t=" << t;
        }
    }
}

TEST(SceneCamera, DefaultScreenWindowFollowsFrameAspect) {
    sss::Camera cam;
    cam.xres = 640;
    cam.yres = 480;
    auto sw = cam.resolved_screen_window();
    EXPECT_DOUBLE_EQ(sw[0], -4.0 / 3.0);
    EXPECT_DOUBLE_EQ(sw[1], 4.0 / 3.0);
    EXPECT_DOUBLE_EQ(sw[2], -1.0);
    EXPECT_DOUBLE_EQ(sw[3], 1.0);
    cam.xres = 300;
    cam.yres = 600;
    sw = cam.resolved_screen_window();
    EXPECT_DOUBLE_EQ(sw[0], -1.0);
    EXPECT_DOUBLE_EQ(sw[3], 2.0);
    cam.screen_window = std::array<double, 4>{-3, 1, -2, 2};
    EXPECT_EQ(cam.resolved_screen_window()[0], -3.0);
}

TEST(SceneCamera, PixelSizePerspectiveAndOrthographic) {
    sss::Camera cam;
    cam.xres = 640;
    cam.yres = 480;
    cam.perspective = true;
    cam.fov = 60.0;
    double width = 8.0 / 3.0;
    double t = std::tan(std::numbers::pi / 6.0);
    EXPECT_NEAR(cam.pixel_size_at(10.0), width * 10.0 * t / 640.0, 1e-15);
    EXPECT_NEAR(cam.pixel_size_at(2.0) * 5.0, cam.pixel_size_at(10.0), 1e-15);
    // Never below the near clipping plane.
    cam.near_clip = 0.5;
    EXPECT_NEAR(cam.pixel_size_at(0.0), width * 0.5 * t / 640.0, 1e-15);
    cam.perspective = false;
    EXPECT_NEAR(cam.pixel_size_at(10.0), width / 640.0, 1e-15);
    EXPECT_NEAR(cam.pixel_size_at(1000.0), width / 640.0, 1e-15);
}

TEST(SceneParamList, TypedGettersAndSet) {
    sss::ParamList list;
    sss::Param kd;
    kd.name = "Kd";
    kd.numbers = {0.5};
    list.set(kd);
    sss::Param color;
    color.name = "lightcolor";
    color.type = sss::ParamType::Color;
    color.numbers = {1, 0.5, 0.25};
    list.set(color);
    sss::Param name;
    name.name = "shadowname";
    name.type = sss::ParamType::String;
    name.strings = {"key.shd"};
    list.set(name);
    sss::Param n;
    n.name = "samples";
    n.type = sss::ParamType::Integer;
    n.numbers = {16};
    list.set(n);

    EXPECT_EQ(list.get_float("Kd", 1.0), 0.5);
    EXPECT_EQ(list.get_float("Ks", 0.7), 0.7);
    EXPECT_EQ(list.get_int("samples", 1), 16);
    EXPECT_EQ(list.get_string("shadowname", ""), "key.shd");
    EXPECT_EQ(list.get_vec3("lightcolor", glm::dvec3(0)), glm::dvec3(1, 0.5, 0.25));
    EXPECT_EQ(list.get_vec3("from", glm::dvec3(7)), glm::dvec3(7));
    EXPECT_THROW(list.get_float("shadowname", 0), sss::ValueError);
    EXPECT_THROW(list.get_string("Kd", ""), sss::ValueError);
    EXPECT_THROW(list.get_vec3("Kd", glm::dvec3(0)), sss::ValueError);
    EXPECT_THROW(list.get_float("lightcolor", 0), sss::ValueError);
    kd.numbers = {2.5};
    list.set(kd);
    EXPECT_EQ(list.items.size(), 4u);
    EXPECT_EQ(list.get_float("Kd", 0), 2.5);
    EXPECT_THROW(list.get_int("Kd", 0), sss::ValueError); // not a whole number
    EXPECT_EQ(color.element_size(), 3);
    EXPECT_EQ(color.element_count(), 1u);
    EXPECT_STREQ(sss::param_type_name(sss::ParamType::HPoint), "hpoint");
    EXPECT_EQ(sss::param_type_components(sss::ParamType::Matrix), 16);
    EXPECT_STREQ(sss::primitive_kind_name(sss::PrimitiveKind::PointsGeneralPolygons),
                 "PointsGeneralPolygons");
}

// --- options ----------------------------------------------------------------

TEST(RibOptions, EachOptionLandsInRenderOptions) {
    auto scene = parse(R"(##RenderMan RIB
version 3.04
Format 320 240 1.5
PixelSamples 4 3
ShadingRate 0.5
ShadingInterpolation "smooth"
Display "out.exr" "openexr" "rgba" "quantize" [0 0 0 0]
Display "+aux.tif" "tiff" "_radiance_t"
DisplayChannel "color _radiance_t"
DisplayChannel "varying float[2] uv"
Projection "perspective" "fov" [30]
ScreenWindow -1 1 -0.5 0.5
Clipping 0.1 500
Option "limits" "bucketsize" [32 32]
Option "user" "float myopt" 3
Option "limits" "integer othersetting" 1
Hider "hidden" "jitter" [1]
CropWindow 0 1 0 1
Exposure 1 2.2
Quantize "rgba" 255 0 255 0.5
PixelFilter "gaussian" 2 2
WorldBegin
Sphere 1 -1 1 360
WorldEnd
)");
    const auto& o = scene.options;
    EXPECT_EQ(o.camera.xres, 320);
    EXPECT_EQ(o.camera.yres, 240);
    EXPECT_EQ(o.camera.pixel_aspect, 1.5);
    EXPECT_EQ(o.pixel_samples[0], 4);
    EXPECT_EQ(o.pixel_samples[1], 3);
    ASSERT_EQ(o.displays.size(), 2u);
    EXPECT_EQ(o.displays[0].name, "out.exr");
    EXPECT_EQ(o.displays[0].type, "openexr");
    EXPECT_EQ(o.displays[0].mode, "rgba");
    EXPECT_FALSE(o.displays[0].additional);
    EXPECT_TRUE(o.displays[0].params.has("quantize"));
    EXPECT_EQ(o.displays[1].name, "aux.tif");
    EXPECT_TRUE(o.displays[1].additional);
    EXPECT_EQ(o.displays[1].mode, "_radiance_t");
    ASSERT_EQ(o.display_channels.size(), 2u);
    EXPECT_EQ(o.display_channels[0],
              std::make_pair(std::string("_radiance_t"), std::string("color")));
    EXPECT_EQ(o.display_channels[1].first, "uv");
    EXPECT_EQ(o.display_channels[1].second, "varying float[2]");
    EXPECT_TRUE(o.camera.perspective);
    EXPECT_EQ(o.camera.fov, 30.0);
    ASSERT_TRUE(o.camera.screen_window);
    EXPECT_EQ((*o.camera.screen_window)[3], 0.5);
    EXPECT_EQ(o.camera.near_clip, 0.1);
    EXPECT_EQ(o.camera.far_clip, 500.0);
    ASSERT_TRUE(o.groups.count("limits"));
    const sss::Param* bs = o.groups.at("limits").find("bucketsize");
    ASSERT_TRUE(bs);
    EXPECT_EQ(bs->type, sss::ParamType::Integer);
    EXPECT_EQ(bs->numbers, (std::vector<double>{32, 32}));
    EXPECT_TRUE(o.groups.at("limits").has("othersetting")); // merged per group
    EXPECT_EQ(o.groups.at("user").get_float("myopt", 0), 3.0);
    EXPECT_EQ(o.hider, "hidden");
    EXPECT_FALSE(o.frame);
    ASSERT_EQ(scene.primitives.size(), 1u);
    EXPECT_EQ(scene.primitives[0].attributes->shading_rate, 0.5);
    EXPECT_EQ(scene.primitives[0].attributes->shading_interpolation, "smooth");
    EXPECT_TRUE(scene.warnings.empty()) << scene.warnings.front();
}

TEST(RibOptions, PrimaryDisplayReplacesEarlierOnesAndDefaultsHold) {
    auto scene =
        parse("Display \"a\" \"file\" \"rgb\"\nDisplay \"b\" \"file\" \"rgb\"\n");
    ASSERT_EQ(scene.options.displays.size(), 1u);
    EXPECT_EQ(scene.options.displays[0].name, "b");
    EXPECT_FALSE(scene.options.camera.perspective);
    EXPECT_EQ(scene.options.camera.xres, 640);
    EXPECT_TRUE(scene.primitives.empty());
}

TEST(RibOptions, FrameAspectRatioSetsTheScreenWindow) {
    auto scene = parse("Format 400 400 1\nFrameAspectRatio 2\nWorldBegin\nWorldEnd\n");
    ASSERT_TRUE(scene.options.camera.screen_window);
    EXPECT_EQ((*scene.options.camera.screen_window)[1], 2.0);
    EXPECT_EQ((*scene.options.camera.screen_window)[2], -1.0);
}

TEST(RibOptions, BadOptionValuesAreErrors) {
    expect_rib_error("Projection \"fisheye\"\n", {"Projection", "fisheye"});
    expect_rib_error("Format 0 480 1\n", {"Format"});
    expect_rib_error("Clipping 1 0.5\n", {"Clipping"});
    expect_rib_error("Projection \"perspective\" \"fov\" 190\n", {"fov"});
    expect_rib_error("ShadingRate 0\n", {"ShadingRate"});
    expect_rib_error("ShadingInterpolation \"phong\"\n", {"phong"});
    expect_rib_error("Sides 3\n", {"Sides"});
}

TEST(RibOptions, OptionsInsideTheWorldOnlyWarn) {
    auto scene = parse("Format 100 100 1\nWorldBegin\nFormat 200 200 1\nWorldEnd\n");
    EXPECT_EQ(scene.options.camera.xres, 100);
    EXPECT_TRUE(has_warning(scene, "test.rib:3: Format inside WorldBegin"));
}

// --- transforms and camera --------------------------------------------------

TEST(RibTransform, LaterTransformsApplyFirst) {
    auto scene = parse("WorldBegin\nTranslate 1 0 0\nScale 2 2 2\nSphere 1 -1 1 360\n");
    ASSERT_EQ(scene.primitives.size(), 1u);
    expect_near(apply(scene.primitives[0].object_to_world, {1, 0, 0}), {3, 0, 0});
    EXPECT_EQ(scene.primitives[0].kind, sss::PrimitiveKind::Sphere);
    EXPECT_EQ(scene.primitives[0].args, (std::vector<double>{1, -1, 1, 360}));
    EXPECT_EQ(scene.primitives[0].source, "test.rib:4");
}

TEST(RibTransform, RotateMatchesGlmAboutNormalisedAxis) {
    auto scene = parse("WorldBegin\nRotate 90 0 0 5\nTranslate 1 0 0\nDisk 0 1 360\n");
    expect_near(apply(scene.primitives[0].object_to_world, {0, 0, 0}), {0, 1, 0});
    sss::Matrix4 want =
        glm::rotate(sss::Matrix4(1.0), glm::radians(90.0), glm::dvec3(0, 0, 1)) *
        glm::translate(sss::Matrix4(1.0), glm::dvec3(1, 0, 0));
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
            EXPECT_NEAR(scene.primitives[0].object_to_world[c][r], want[c][r], 1e-12);
}

TEST(RibTransform, TransformAndConcatTransformUseRibLayout) {
    // Row-vector RIB matrices: the translation is in the last row.
    auto scene = parse("WorldBegin\nTransform [1 0 0 0 0 1 0 0 0 0 1 0 5 0 0 1]\n"
                       "ConcatTransform [2 0 0 0 0 2 0 0 0 0 2 0 0 1 0 1]\n"
                       "Sphere 1 -1 1 360\nIdentity\nSphere 1 -1 1 360\n");
    ASSERT_EQ(scene.primitives.size(), 2u);
    expect_near(apply(scene.primitives[0].object_to_world, {1, 0, 0}), {7, 1, 0});
    EXPECT_EQ(scene.primitives[1].object_to_world, sss::Matrix4(1.0));
}

TEST(RibTransform, SkewTurnsTheFirstVectorTowardsTheSecond) {
    auto scene = parse("WorldBegin\nSkew 45 0 1 0 1 0 0\nSphere 1 -1 1 360\n");
    expect_near(apply(scene.primitives[0].object_to_world, {0, 1, 0}), {1, 1, 0});
    expect_near(apply(scene.primitives[0].object_to_world, {1, 0, 0}), {1, 0, 0});
    expect_rib_error("Skew 10 1 0 0 2 0 0\n", {"parallel"});
}

TEST(RibCamera, WorldBeginFixesWorldToCamera) {
    auto scene =
        parse("Projection \"perspective\" \"fov\" 45\nTranslate 0 0 5\nWorldBegin\n"
              "Sphere 1 -1 1 360\nWorldEnd\n");
    const auto& cam = scene.options.camera;
    EXPECT_TRUE(cam.perspective);
    EXPECT_EQ(cam.fov, 45.0);
    expect_near(apply(cam.world_to_camera, {0, 0, 0}), {0, 0, 5});
    // The CTM restarts from identity in world space.
    EXPECT_EQ(scene.primitives[0].object_to_world, sss::Matrix4(1.0));
}

TEST(RibCamera, ProjectionResetsTheTransform) {
    auto scene =
        parse("Translate 0 0 9\nProjection \"orthographic\"\nWorldBegin\nWorldEnd\n");
    expect_near(apply(scene.options.camera.world_to_camera, {0, 0, 0}), {0, 0, 0});
    EXPECT_FALSE(scene.options.camera.perspective);
}

// --- attributes -------------------------------------------------------------

TEST(RibAttributes, AttributeBlocksRestoreColorAndTransform) {
    auto scene = parse(R"(WorldBegin
Color 1 0 0
AttributeBegin
  Color [0 1 0]
  Opacity 0.5 0.5 0.5
  Translate 0 1 0
  Sphere 1 -1 1 360
AttributeEnd
Sphere 1 -1 1 360
TransformBegin
  Translate 0 0 1
  Color 0 0 1
  Sphere 1 -1 1 360
TransformEnd
Sphere 1 -1 1 360
WorldEnd
)");
    ASSERT_EQ(scene.primitives.size(), 4u);
    const auto& p = scene.primitives;
    EXPECT_EQ(p[0].attributes->color, glm::dvec3(0, 1, 0));
    EXPECT_EQ(p[0].attributes->opacity, glm::dvec3(0.5));
    expect_near(apply(p[0].object_to_world, {0, 0, 0}), {0, 1, 0});
    EXPECT_EQ(p[1].attributes->color, glm::dvec3(1, 0, 0));
    EXPECT_EQ(p[1].attributes->opacity, glm::dvec3(1));
    EXPECT_EQ(p[1].object_to_world, sss::Matrix4(1.0));
    expect_near(apply(p[2].object_to_world, {0, 0, 0}), {0, 0, 1});
    // TransformEnd restores the transform only: the colour stays blue.
    EXPECT_EQ(p[3].object_to_world, sss::Matrix4(1.0));
    EXPECT_EQ(p[3].attributes->color, glm::dvec3(0, 0, 1));
}

TEST(RibAttributes, UnchangedAttributesShareOneSnapshot) {
    auto scene =
        parse("WorldBegin\nColor 1 0 0\nSphere 1 -1 1 360\nTranslate 1 0 0\n"
              "Sphere 1 -1 1 360\nAttributeBegin\nSphere 1 -1 1 360\nColor 0 1 0\n"
              "Sphere 1 -1 1 360\nAttributeEnd\nSphere 1 -1 1 360\n");
    const auto& p = scene.primitives;
    ASSERT_EQ(p.size(), 5u);
    EXPECT_EQ(p[0].attributes, p[1].attributes);
    EXPECT_EQ(p[1].attributes, p[2].attributes);
    EXPECT_NE(p[2].attributes, p[3].attributes);
    EXPECT_EQ(p[0].attributes, p[4].attributes);
}

TEST(RibAttributes, AttributeGroupsSurfaceSidesAndIdentifier) {
    auto scene = parse(R"(WorldBegin
Translate 0 2 0
Surface "plastic" "Kd" 0.8 "color specularcolor" [1 1 1] "float[2] pair" [3 4]
Translate 5 0 0
Attribute "identifier" "name" "marble"
Attribute "dice" "integer binary" [1]
Attribute "dice" "rasterorient" 0
Sides 1
Sphere 1 -1 1 360
)");
    ASSERT_EQ(scene.primitives.size(), 1u);
    const auto& a = *scene.primitives[0].attributes;
    EXPECT_EQ(a.name(), "marble");
    EXPECT_EQ(a.sides, 1);
    ASSERT_TRUE(a.groups.count("dice"));
    EXPECT_EQ(a.groups.at("dice").get_int("binary", 0), 1);
    EXPECT_EQ(a.groups.at("dice").get_int("rasterorient", 1), 0);
    ASSERT_TRUE(a.surface);
    EXPECT_EQ(a.surface->name, "plastic");
    EXPECT_EQ(a.surface->params.get_float("Kd", 0), 0.8);
    EXPECT_EQ(a.surface->params.get_vec3("specularcolor", glm::dvec3(0)), glm::dvec3(1));
    const sss::Param* pair = a.surface->params.find("pair");
    ASSERT_TRUE(pair);
    EXPECT_EQ(pair->array_size, 2);
    EXPECT_EQ(pair->element_count(), 1u);
    EXPECT_EQ(a.surface->source, "test.rib:3");
    // The shader space is the CTM at the Surface call.
    expect_near(apply(a.surface->shader_to_world, {0, 0, 0}), {0, 2, 0});
}

TEST(RibAttributes, SurfaceBeforeWorldBeginIsPlacedInWorldSpace) {
    auto scene =
        parse("Translate 0 0 5\nTransformBegin\nTranslate 1 0 0\nSurface \"matte\"\n"
              "TransformEnd\nWorldBegin\nSphere 1 -1 1 360\nWorldEnd\n");
    const auto& surface = scene.primitives[0].attributes->surface;
    ASSERT_TRUE(surface);
    // Camera (1, 0, 5) is world (1, 0, 0).
    expect_near(apply(surface->shader_to_world, {0, 0, 0}), {1, 0, 0});
}

TEST(RibAttributes, DeclareAndInlineDeclarations) {
    auto scene = parse(R"(Declare "roughness2" "uniform float"
Declare "tint" "color"
Declare "uvs" "facevarying float[2]"
WorldBegin
Surface "mine" "roughness2" 0.1 "tint" [0.1 0.2 0.3] "constant string mapname" "a.tex"
PointsPolygons [3] [0 1 2] "P" [0 0 0 1 0 0 0 1 0] "uvs" [0 0 1 0 0 1] "vertex float foo" [1 2 3]
)");
    const auto& s = scene.primitives[0].attributes->surface;
    ASSERT_TRUE(s);
    const sss::Param* tint = s->params.find("tint");
    ASSERT_TRUE(tint);
    EXPECT_EQ(tint->type, sss::ParamType::Color);
    EXPECT_EQ(tint->storage, sss::ParamClass::Uniform);
    const sss::Param* map = s->params.find("mapname");
    ASSERT_TRUE(map);
    EXPECT_EQ(map->storage, sss::ParamClass::Constant);
    EXPECT_EQ(map->strings, std::vector<std::string>{"a.tex"});
    const auto& params = scene.primitives[0].params;
    const sss::Param* uvs = params.find("uvs");
    ASSERT_TRUE(uvs);
    EXPECT_EQ(uvs->storage, sss::ParamClass::FaceVarying);
    EXPECT_EQ(uvs->element_count(), 3u);
    EXPECT_EQ(params.find("foo")->storage, sss::ParamClass::Vertex);
    EXPECT_EQ(params.find("P")->storage, sss::ParamClass::Vertex);
}

TEST(RibAttributes, UndeclaredParametersWarnAndWrongCountsFail) {
    // A shader call keeps an undeclared parameter for the shader's own
    // declaration to type (as PRMan); a primitive's is skipped with a warning.
    auto scene = parse("WorldBegin\nSurface \"matte\" \"Kd\" 1 \"mystery\" [2 3]\n"
                       "Sphere 1 -1 1 360 \"enigma\" 4\n");
    const sss::Param* mystery =
        scene.primitives[0].attributes->surface->params.find("mystery");
    ASSERT_TRUE(mystery);
    EXPECT_FALSE(mystery->declared);
    EXPECT_EQ(mystery->type, sss::ParamType::Float);
    EXPECT_EQ(mystery->numbers, (std::vector<double>{2, 3}));
    EXPECT_TRUE(scene.primitives[0].attributes->surface->params.find("Kd")->declared);
    EXPECT_TRUE(has_warning(
        scene, "test.rib:3: Sphere: undeclared parameter \"enigma\", skipped"));
    EXPECT_FALSE(has_warning(
        scene, "test.rib:2: Surface: undeclared parameter \"mystery\", skipped"));

    expect_rib_error("WorldBegin\nLightSource \"pointlight\" 1 \"lightcolor\" [1 1]\n",
                     {"2: LightSource", "lightcolor"});
    expect_rib_error("Surface \"matte\" \"Kd\" \"high\"\n", {"Kd", "numbers"});
    expect_rib_error("Surface \"matte\" \"Kd\"\n", {"no value"});
    expect_rib_error("Surface \"matte\" \"uniform float\" 1\n",
                     {"bad declaration", "no name"});
    expect_rib_error("Surface \"matte\" \"integer n\" 1.5\n", {"integer"});
    expect_rib_error("Declare \"x\" \"quaternion\"\n", {"Declare", "quaternion"});
}

TEST(RibAttributes, OrientationAndReverseOrientation) {
    auto scene = parse(R"(WorldBegin
Sphere 1 -1 1 360
Orientation "inside"
Sphere 1 -1 1 360
ReverseOrientation
Sphere 1 -1 1 360
Orientation "rh"
Sphere 1 -1 1 360
Orientation "lh"
Sphere 1 -1 1 360
Scale -1 1 1
Orientation "rh"
Sphere 1 -1 1 360
ReverseOrientation
Sphere 1 -1 1 360
)");
    const auto& p = scene.primitives;
    ASSERT_EQ(p.size(), 7u);
    EXPECT_FALSE(p[0].attributes->orientation_inside);
    EXPECT_TRUE(p[1].attributes->orientation_inside);
    EXPECT_FALSE(p[2].attributes->orientation_inside);
    // World space under an identity camera is left-handed: "rh" differs.
    EXPECT_TRUE(p[3].attributes->orientation_inside);
    EXPECT_FALSE(p[4].attributes->orientation_inside);
    // A mirror makes the current space right-handed.
    EXPECT_FALSE(p[5].attributes->orientation_inside);
    EXPECT_TRUE(p[6].attributes->orientation_inside);
    expect_rib_error("Orientation \"up\"\n", {"Orientation"});
}

TEST(RibAttributes, OrientationHandednessIncludesTheCamera) {
    // A mirroring camera makes world space right-handed.
    auto scene =
        parse("Scale 1 1 -1\nWorldBegin\nOrientation \"rh\"\nSphere 1 -1 1 360\n");
    EXPECT_FALSE(scene.primitives[0].attributes->orientation_inside);
}

TEST(RibAttributes, BasisNamesAndMatrices) {
    auto scene =
        parse("WorldBegin\nBasis \"catmull-rom\" 1 [1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1] 4\n"
              "Sphere 1 -1 1 360\n");
    const auto& a = *scene.primitives[0].attributes;
    EXPECT_EQ(a.u_basis.name, "catmull-rom");
    EXPECT_EQ(a.u_basis.step, 1);
    EXPECT_EQ(a.v_basis.matrix, sss::Matrix4(1.0));
    EXPECT_EQ(a.v_basis.step, 4);
    EXPECT_EQ(sss::Attributes{}.u_basis.name, "bezier");
    expect_rib_error("Basis \"nurbs\" 1 \"bezier\" 3\n", {"nurbs"});
}

// --- lights -----------------------------------------------------------------

TEST(RibLights, LightSourceAndIlluminateBookkeeping) {
    auto scene = parse(R"(WorldBegin
LightSource "ambientlight" 1 "intensity" 0.1
Translate 0 3 0
LightSource "pointlight" "key" "intensity" 20 "from" [0 0 0]
Sphere 1 -1 1 360
AttributeBegin
  Illuminate 1 0
  AreaLightSource "arealight" 7
  Sphere 1 -1 1 360
AttributeEnd
Sphere 1 -1 1 360
Illuminate "key" 0
Sphere 1 -1 1 360
)");
    ASSERT_EQ(scene.lights.size(), 3u);
    EXPECT_EQ(scene.lights[0].shader.name, "ambientlight");
    EXPECT_EQ(scene.lights[0].handle, "1");
    EXPECT_EQ(scene.lights[1].handle, "key");
    EXPECT_FALSE(scene.lights[1].area);
    EXPECT_TRUE(scene.lights[2].area);
    EXPECT_EQ(scene.lights[1].shader.params.get_float("intensity", 0), 20.0);
    expect_near(apply(scene.lights[1].shader.shader_to_world, {0, 0, 0}), {0, 3, 0});
    const auto& p = scene.primitives;
    ASSERT_EQ(p.size(), 4u);
    EXPECT_EQ(p[0].attributes->lights_on, (std::vector<int>{0, 1}));
    EXPECT_EQ(p[1].attributes->lights_on, (std::vector<int>{1, 2}));
    EXPECT_EQ(p[2].attributes->lights_on, (std::vector<int>{0, 1})); // restored
    EXPECT_EQ(p[3].attributes->lights_on, (std::vector<int>{0}));
    expect_rib_error("WorldBegin\nIlluminate 4 1\n", {"2: Illuminate", "4"});
}

// --- warnings and errors ------------------------------------------------------

/// Options that read leniently.
sss::RibReadOptions lenient() {
    sss::RibReadOptions o;
    o.lenient = true;
    return o;
}

TEST(RibErrors, UnknownStatementIsAnErrorOrLenientlyWarnsOncePerName) {
    const std::string text = "Frobnicate 1 2 [3 4]\nWorldBegin\nFrobnicate \"x\"\n"
                             "Frobnicate\nWibble 3\nSphere 1 -1 1 360\nWorldEnd\n";
    expect_rib_error(text, {"test.rib:1: Frobnicate: unknown statement Frobnicate",
                            "reading leniently: skipped"});
    auto scene = parse(text, lenient());
    ASSERT_EQ(scene.warnings.size(), 2u);
    EXPECT_EQ(scene.warnings[0], "test.rib:1: unknown statement Frobnicate, skipped");
    EXPECT_EQ(scene.warnings[1], "test.rib:5: unknown statement Wibble, skipped");
    EXPECT_EQ(scene.primitives.size(), 1u);
}

TEST(RibErrors, ErrorsNameFileLineAndStatement) {
    const std::string text = "##RenderMan RIB\n# comment\nFormat 64 64 1\n\nWorldBegin\n"
                             "AttributeBegin\nSphere 1 -1 1\nAttributeEnd\n";
    try {
        parse(text);
        FAIL() << "no error";
    } catch (const sss::RibError& e) {
        EXPECT_EQ(e.line(), 7);
        EXPECT_EQ(e.statement(), "Sphere");
        EXPECT_EQ(e.path(), "test.rib");
        std::string what = e.what();
        EXPECT_NE(what.find(":7: Sphere"), std::string::npos) << what;
        EXPECT_NE(what.find("expected 4 numbers, got 3"), std::string::npos) << what;
    }
}

TEST(RibErrors, TokenizerErrors) {
    EXPECT_EQ(expect_rib_error("Surface \"abc\nWorldBegin\n", {"unterminated string"}),
              1);
    EXPECT_EQ(
        expect_rib_error("WorldBegin\nPolygon \"P\" [0 0 0 1 0 0\n", {"end of file"}), 2);
    expect_rib_error("WorldBegin\nPolygon \"P\" [0 0 0 1 0 0\nSphere 1 -1 1 360\n",
                     {"unterminated array"});
    expect_rib_error("Color 1 nan 0\n", {"finite"});
    expect_rib_error("Color 1 -nan 0\n", {"finite"});
    expect_rib_error("Color 1 1e999 0\n", {"range"});
    expect_rib_error("Color 1 1.2.3 0\n", {"malformed number"});
    expect_rib_error("Color 1 0 0]\n", {"']'"});
    expect_rib_error("Color [1 [0] 0]\n", {"nested"});
    expect_rib_error("Display [\"a\" 1] \"file\" \"rgb\"\n", {"mixes"});
    expect_rib_error(std::string("WorldBegin\n\x80\x01\x02", 14), {"binary RIB"});
    expect_rib_error(std::string("\x1f\x8b\x08", 3), {"gzip"});
    expect_rib_error("3 WorldBegin\n", {"statement name"});
    // A UTF-8 byte order mark is not binary.
    EXPECT_EQ(
        parse("\xef\xbb\xbfWorldBegin\nSphere 1 -1 1 360\nWorldEnd\n").primitives.size(),
        1u);
}

TEST(RibErrors, StructureErrors) {
    expect_rib_error("AttributeEnd\n", {"AttributeEnd"});
    expect_rib_error("WorldBegin\nTransformBegin\nAttributeEnd\n", {"TransformBegin"});
    expect_rib_error("Sphere 1 -1 1 360\n", {"outside WorldBegin"});
    expect_rib_error("WorldBegin\nWorldBegin\n", {"nested"});
    expect_rib_error("WorldBegin\nObjectInstance 5\n", {"ObjectInstance", "5"});
    expect_rib_error("Rotate 30 0 0 0\n", {"axis"});
    expect_rib_error("Translate 1 2\n", {"expected 3 numbers, got 2"});
    expect_rib_error("Translate 1 2 3 4\n", {"extra"});
    auto scene = parse("WorldBegin\nAttributeBegin\n");
    EXPECT_TRUE(has_warning(scene, "test.rib:2: AttributeBegin is never closed"));
}

TEST(RibTokenizer, StringsNumbersCommentsAndTightArrays) {
    auto scene =
        parse("Option \"user\" \"string s\" \"a\\\"b\\\\c\\n\\td\\101\"\n"
              "Option \"user\" \"float[6] n\"[+1 -.5 1e3 1.5E-2 .25 -2.]# comment\n"
              "Option\"user\"\"string[2] two\"[\"x\"\"y\"]\n");
    const auto& user = scene.options.groups.at("user");
    EXPECT_EQ(user.get_string("s", ""), "a\"b\\c\n\tdA");
    EXPECT_EQ(user.find("n")->numbers,
              (std::vector<double>{1, -0.5, 1000, 0.015, 0.25, -2}));
    EXPECT_EQ(user.find("two")->strings, (std::vector<std::string>{"x", "y"}));
    EXPECT_TRUE(scene.warnings.empty());
}

// --- frames -------------------------------------------------------------------

TEST(RibFrames, FrameBeginSelectsOneFrame) {
    const std::string text = R"(Option "user" "float shared" 1
FrameBegin 1
Format 100 100 1
WorldBegin
Sphere 1 -1 1 360
WorldEnd
FrameEnd
FrameBegin 2
Format 200 200 1
Frobnicate
WorldBegin
Sphere 2 -2 2 360
Disk 0 1 360
WorldEnd
FrameEnd
)";
    auto first = parse(text);
    EXPECT_EQ(first.options.frame, 1);
    EXPECT_EQ(first.options.camera.xres, 100);
    EXPECT_EQ(first.primitives.size(), 1u);
    EXPECT_TRUE(first.warnings.empty()); // the skipped frame says nothing
    EXPECT_TRUE(first.options.groups.count("user"));

    sss::RibReadOptions opt;
    opt.frame = 2;
    opt.lenient = true; // Frobnicate
    auto second = parse(text, opt);
    EXPECT_EQ(second.options.frame, 2);
    EXPECT_EQ(second.options.camera.xres, 200);
    ASSERT_EQ(second.primitives.size(), 2u);
    EXPECT_EQ(second.primitives[0].args[0], 2.0);
    EXPECT_TRUE(second.options.groups.count("user")); // outside frames: applies

    opt.frame = 3;
    expect_rib_error(text, {"frame 3 not found"}, opt);
}

TEST(RibFrames, MakeRequestsBelongToTheFramesAroundThem) {
    // A shadow pass: frame 1 renders the zfile, MakeShadow makes the map
    // frame 2 reads. Requests before FrameBegin n run before frame n, those
    // after its FrameEnd (up to the next FrameBegin) after it.
    const std::string text = R"(MakeTexture "a.png" "a.tx" "black" "black" "box" 1 1
FrameBegin 1
MakeTexture "b.png" "b.tx" "black" "black" "box" 1 1
Display "s.z" "zfile" "z"
WorldBegin
Sphere 1 -1 1 360
WorldEnd
MakeShadow "s.z" "in_frame.tex"
FrameEnd
MakeShadow "s.z" "s.tex"
FrameBegin 2
WorldBegin
Sphere 1 -1 1 360
WorldEnd
FrameEnd
MakeCubeFaceEnvironment "px.tif" "nx.tif" "py.tif" "ny.tif" "pz.tif" "nz.tif" "env.tex" 95 "gaussian" 2 2
)";
    const auto summary = [](const sss::Scene& scene) {
        std::string out;
        for (const sss::MakeRequest& m : scene.makes)
            out += m.output + (m.after_frame ? "(after) " : " ");
        return out;
    };
    const sss::Scene first = parse(text);
    EXPECT_EQ(summary(first), "a.tx b.tx in_frame.tex(after) s.tex(after) ");
    EXPECT_EQ(first.frame_numbers, (std::vector<int>{1, 2}));
    sss::RibReadOptions opt;
    opt.frame = 2;
    const sss::Scene second = parse(text, opt);
    EXPECT_EQ(summary(second), "s.tex env.tex(after) ");
    ASSERT_EQ(second.makes.size(), 2u);
    EXPECT_EQ(second.makes[0].kind, "MakeShadow");
    EXPECT_EQ(second.makes[0].input, "s.z"); // not there yet: kept as given
    EXPECT_EQ(second.makes[0].source, "test.rib:10");
    const sss::MakeRequest& cube = second.makes[1];
    EXPECT_EQ(cube.kind, "MakeCubeFaceEnvironment");
    EXPECT_EQ(cube.faces, (std::vector<std::string>{"px.tif", "nx.tif", "py.tif",
                                                    "ny.tif", "pz.tif", "nz.tif"}));
    EXPECT_EQ(cube.fov, 95.0);
    EXPECT_EQ(cube.filter, "gaussian");
    EXPECT_TRUE(second.warnings.empty());
    // Without frames, requests after WorldEnd run after the image.
    const sss::Scene flat = parse(R"(MakeTexture "a.png" "a.tx" "black" "black" "box" 1 1
WorldBegin
WorldEnd
MakeShadow "s.z" "s.tex"
)");
    EXPECT_EQ(summary(flat), "a.tx s.tex(after) ");
    expect_rib_error(
        R"(MakeCubeFaceEnvironment "a" "b" "c" "d" "e" "f" "g" 190 "box" 1 1)",
        {"field of view"});
}

// --- coordinate systems -------------------------------------------------------

TEST(RibCoordinateSystems, DefineAndUse) {
    auto scene = parse(R"(Translate 0 0 10
AttributeBegin
Translate 1 0 0
CoordinateSystem "rig"
AttributeEnd
WorldBegin
Translate 0 4 0
CoordinateSystem "lamp"
Identity
Translate 9 9 9
CoordSysTransform "lamp"
Sphere 1 -1 1 360
CoordSysTransform "rig"
Sphere 1 -1 1 360
CoordSysTransform "camera"
Sphere 1 -1 1 360
CoordSysTransform "world"
Sphere 1 -1 1 360
)");
    ASSERT_EQ(scene.primitives.size(), 4u);
    ASSERT_TRUE(scene.coordinate_systems.count("lamp"));
    ASSERT_TRUE(scene.coordinate_systems.count("rig"));
    expect_near(apply(scene.coordinate_systems.at("lamp"), {0, 0, 0}), {0, 4, 0});
    // "rig" was defined in camera space, at camera (1, 0, 10): world (1, 0, 0).
    expect_near(apply(scene.coordinate_systems.at("rig"), {0, 0, 0}), {1, 0, 0});
    expect_near(apply(scene.primitives[0].object_to_world, {0, 0, 0}), {0, 4, 0});
    expect_near(apply(scene.primitives[1].object_to_world, {0, 0, 0}), {1, 0, 0});
    expect_near(apply(scene.primitives[2].object_to_world, {0, 0, 0}), {0, 0, -10});
    EXPECT_EQ(scene.primitives[3].object_to_world, sss::Matrix4(1.0));
    expect_rib_error("WorldBegin\nCoordSysTransform \"nowhere\"\n", {"nowhere"});
    expect_rib_error("CoordSysTransform \"world\"\n", {"WorldBegin"});
}

// --- geometry -----------------------------------------------------------------

TEST(RibGeometry, MeshesAndTheirCounts) {
    auto scene = parse(R"(WorldBegin
Polygon "P" [0 0 0 1 0 0 1 1 0 0 1 0] "N" [0 0 1 0 0 1 0 0 1 0 0 1] "Cs" [1 0 0 1 0 0 1 0 0 1 0 0]
GeneralPolygon [4 3] "P" [0 0 0 4 0 0 4 4 0 0 4 0 1 1 0 2 1 0 1 2 0]
PointsPolygons [3 3] [0 1 2 0 2 3] "P" [0 0 0 1 0 0 1 1 0 0 1 0] "uniform color Cs" [1 0 0 0 1 0]
PointsGeneralPolygons [1 2] [3 4 3] [0 1 2 0 1 2 3 4 5 6] "P" [0 0 0 1 0 0 1 1 0 0 1 0 .2 .2 0 .4 .2 0 .2 .4 0]
SubdivisionMesh "catmull-clark" [4] [0 1 2 3] ["interpolateboundary" "crease"] [0 0 2 1] [0 1] [5] "P" [0 0 0 1 0 0 1 1 0 0 1 0]
SubdivisionMesh "catmull-clark" [3] [0 1 2] "P" [0 0 0 1 0 0 1 1 0] "facevarying float s" [0 1 1]
Patch "bilinear" "P" [0 0 0 1 0 0 0 1 0 1 1 0]
Patch "bicubic" "Pz" [0 0 0 0 0 1 1 0 0 1 1 0 0 0 0 0]
PatchMesh "bilinear" 3 "nonperiodic" 2 "nonperiodic" "P" [0 0 0 1 0 0 2 0 0 0 1 0 1 1 0 2 1 0] "uniform float u2" [1 2]
PatchMesh "bicubic" 7 "nonperiodic" 4 "nonperiodic" "Pw" [0 0 0 1 1 0 0 1 2 0 0 1 3 0 0 1 4 0 0 1 5 0 0 1 6 0 0 1 0 1 0 1 1 1 0 1 2 1 0 1 3 1 0 1 4 1 0 1 5 1 0 1 6 1 0 1 0 2 0 1 1 2 0 1 2 2 0 1 3 2 0 1 4 2 0 1 5 2 0 1 6 2 0 2 0 3 0 1 1 3 0 1 2 3 0 1 3 3 0 1 4 3 0 1 5 3 0 1 6 3 0 1] "varying color Cs" [1 0 0 1 0 0 1 0 0 1 0 0 1 0 0 1 0 0]
Geometry "teapot"
Torus [1 0.25 0 360 360]
Hyperboloid 1 0 0 0 1 1 360 "constant float k" 1 "varying float v2" [0 1 2 3]
)");
    ASSERT_EQ(scene.primitives.size(), 13u);
    const auto& p = scene.primitives;
    EXPECT_EQ(p[0].kind, sss::PrimitiveKind::Polygon);
    EXPECT_EQ(p[0].nverts, std::vector<int>{4});
    EXPECT_EQ(p[1].nverts, (std::vector<int>{4, 3}));
    EXPECT_EQ(p[2].verts.size(), 6u);
    EXPECT_EQ(p[2].params.find("Cs")->storage, sss::ParamClass::Uniform);
    EXPECT_EQ(p[3].nloops, (std::vector<int>{1, 2}));
    EXPECT_EQ(p[4].type, "catmull-clark");
    EXPECT_EQ(p[4].tags, (std::vector<std::string>{"interpolateboundary", "crease"}));
    EXPECT_EQ(p[4].tag_intargs, (std::vector<int>{0, 1}));
    EXPECT_EQ(p[4].tag_floatargs, std::vector<double>{5});
    EXPECT_TRUE(p[5].tags.empty());
    EXPECT_EQ(p[6].type, "bilinear");
    // Pz becomes a height field over the unit square.
    const sss::Param* P = p[7].params.find("P");
    ASSERT_TRUE(P);
    EXPECT_EQ(P->element_count(), 16u);
    EXPECT_NEAR(P->numbers[3 * 5 + 0], 1.0 / 3.0, 1e-15);
    EXPECT_NEAR(P->numbers[3 * 5 + 1], 1.0 / 3.0, 1e-15);
    EXPECT_EQ(P->numbers[3 * 5 + 2], 1.0);
    EXPECT_FALSE(p[7].params.has("Pz"));
    EXPECT_EQ(p[8].nu, 3);
    EXPECT_EQ(p[8].nv, 2);
    EXPECT_FALSE(p[8].uwrap);
    // Pw becomes P by the homogeneous divide.
    const sss::Param* P9 = p[9].params.find("P");
    ASSERT_TRUE(P9);
    EXPECT_EQ(P9->element_count(), 28u);
    EXPECT_EQ(P9->numbers[3 * 20], 3.0);
    EXPECT_EQ(P9->numbers[3 * 20 + 1], 1.0);
    EXPECT_TRUE(has_warning(scene, "rational"));
    EXPECT_EQ(p[10].kind, sss::PrimitiveKind::Teapot);
    EXPECT_EQ(p[11].args, (std::vector<double>{1, 0.25, 0, 360, 360}));
    EXPECT_EQ(p[12].args.size(), 7u);
}

TEST(RibGeometry, CountMismatchesAreErrors) {
    const std::string w = "WorldBegin\n";
    expect_rib_error(w + "PointsPolygons [3] [0 1 3] \"P\" [0 0 0 1 0 0 1 1 0]\n",
                     {"PointsPolygons", "\"P\" has 3 points, expected 4"});
    expect_rib_error(w + "PointsPolygons [3 3] [0 1 2] \"P\" [0 0 0 1 0 0 1 1 0]\n",
                     {"vertices"});
    expect_rib_error(w + "PointsPolygons [-3] [] \"P\" [0 0 0]\n", {"nvertices", ">= 3"});
    expect_rib_error(w + "PointsPolygons [3] [0 -1 2] \"P\" [0 0 0 1 0 0 1 1 0]\n",
                     {"vertices", ">= 0"});
    expect_rib_error(
        w + "PointsPolygons [3] [0 1 2] \"P\" [0 0 0 1 0 0 1 1 0] \"N\" [0 0 1]\n",
        {"\"N\"", "expected 3"});
    expect_rib_error(
        w + "PointsPolygons [3] [0 1 2] \"P\" [0 0 0 1 0 0 1 1 0] \"Cs\" [1 0]\n",
        {"Cs", "whole number"});
    expect_rib_error(w + "PointsPolygons [3] [0 1 2]\n", {"missing \"P\""});
    expect_rib_error(w + "Polygon \"P\" [0 0 0 1 0 0]\n", {"Polygon", "at least 3"});
    expect_rib_error(w + "PointsPolygons [3] [0 1 2] \"Pz\" [0 0 0]\n",
                     {"Pz", "patches"});
    expect_rib_error(
        w + "Polygon \"P\" [0 0 0 1 0 0 0 1 0] \"Pw\" [0 0 0 1 1 0 0 1 0 1 0 1]\n",
        {"only one"});
    expect_rib_error(w + "Patch \"bicubic\" \"P\" [0 0 0 1 0 0 0 1 0 1 1 0]\n",
                     {"Patch", "expected 16"});
    expect_rib_error(w + "Patch \"trilinear\" \"P\" [0 0 0]\n", {"trilinear"});
    expect_rib_error(
        w + "PatchMesh \"bicubic\" 5 \"nonperiodic\" 4 \"nonperiodic\" \"P\" [0 0 0]\n",
        {"nu = 5"});
    expect_rib_error(
        w + "PatchMesh \"bilinear\" 2 \"sometimes\" 2 \"nonperiodic\" \"P\" [0 0 0]\n",
        {"periodic"});
    expect_rib_error(
        w + "SubdivisionMesh \"catmull-clark\" [3] [0 1 2] [\"crease\"] [2 0] [0 7] [] "
            "\"P\" [0 0 0 1 0 0 1 1 0]\n",
        {"crease", "out of range"});
    expect_rib_error(w + "Sphere [1 -1 1]\n", {"expected 4 numbers, got 3"});
    expect_rib_error(w + "Sphere 1 -1 1 360 \"varying float q\" [1 2]\n",
                     {"\"q\"", "expected 4"});
    expect_rib_error(w + "Geometry \"teapot\" \"varying float q\" [1 2 3 4]\n",
                     {"teapot"});
    expect_rib_error(w + "Geometry \"bunny\"\nWorldEnd\n",
                     {"Geometry \"bunny\" is not supported"});
    auto scene =
        parse(w + "Geometry \"bunny\"\nGeometry \"bunny\"\nWorldEnd\n", lenient());
    EXPECT_EQ(scene.warnings.size(), 1u);
    EXPECT_TRUE(scene.primitives.empty());
}

TEST(RibGeometry, ObjectInstancesTakeTheInstanceStateAndMoveWithTheCtm) {
    auto scene = parse(R"(WorldBegin
ObjectBegin "ball"
  Translate 1 0 0
  Sphere 1 -1 1 360
  Disk 0 1 360
ObjectEnd
Color 0 1 0
Translate 0 5 0
ObjectInstance "ball"
MotionBegin [0 1]
Translate 0 0 1
Translate 0 0 2
MotionEnd
ObjectInstance "ball"
)",
                       lenient());
    ASSERT_EQ(scene.primitives.size(), 4u);
    expect_near(apply(scene.primitives[0].object_to_world, {0, 0, 0}), {1, 5, 0});
    EXPECT_EQ(scene.primitives[0].attributes->color, glm::dvec3(0, 1, 0));
    EXPECT_EQ(scene.primitives[1].object_to_world, scene.primitives[0].object_to_world);
    expect_near(apply(scene.primitives[2].object_to_world, {0, 0, 0}), {1, 5, 1});
    EXPECT_EQ(scene.primitives[0].source, "test.rib:4");
    // The instance under the moving CTM moves; the one before does not.
    EXPECT_FALSE(scene.primitives[0].motion);
    ASSERT_TRUE(scene.primitives[2].motion);
    expect_near(apply(scene.primitives[2].motion->transforms[1], {0, 0, 0}), {1, 5, 2});
    EXPECT_FALSE(has_warning(scene, "motion blur"));
}

// --- archives -----------------------------------------------------------------

TEST(RibArchives, ReadArchiveIsRelativeToTheIncludingFile) {
    TempFolder tmp;
    tmp.write("parts/a.rib", "Translate 0 1 0\nReadArchive \"b.rib\"\n");
    tmp.write("parts/b.rib", "Sphere 1 -1 1 360\n");
    fs::path main =
        tmp.write("scene.rib", "WorldBegin\nAttributeBegin\nReadArchive \"parts/a.rib\"\n"
                               "AttributeEnd\nDisk 0 1 360\nWorldEnd\n");
    auto scene = sss::read_rib(main.string());
    ASSERT_EQ(scene.primitives.size(), 2u);
    EXPECT_EQ(scene.path, main.string());
    // Every file read, once, in first-read order: the inputs of -newer.
    ASSERT_EQ(scene.sources.size(), 3u);
    EXPECT_EQ(scene.sources[0], main.string());
    EXPECT_NE(scene.sources[1].find("parts/a.rib"), std::string::npos);
    EXPECT_NE(scene.sources[2].find("b.rib"), std::string::npos);
    EXPECT_TRUE(sss::parse_rib("WorldBegin\nWorldEnd\n", "t.rib").sources.empty());
    EXPECT_NE(scene.primitives[0].source.find("b.rib:1"), std::string::npos);
    expect_near(apply(scene.primitives[0].object_to_world, {0, 0, 0}), {0, 1, 0});
    EXPECT_EQ(scene.primitives[1].object_to_world, sss::Matrix4(1.0));

    // Errors inside an archive name the archive.
    tmp.write("parts/bad.rib", "\n\nSphere 1\n");
    fs::path bad = tmp.write("bad.rib", "WorldBegin\nReadArchive \"parts/bad.rib\"\n");
    try {
        sss::read_rib(bad.string());
        FAIL() << "no error";
    } catch (const sss::RibError& e) {
        EXPECT_NE(e.path().find("bad.rib"), std::string::npos);
        EXPECT_NE(e.path().find("parts"), std::string::npos);
        EXPECT_EQ(e.line(), 3);
    }

    fs::path loop = tmp.write("loop.rib", "ReadArchive \"loop.rib\"\n");
    EXPECT_THROW(sss::read_rib(loop.string()), sss::RibError);
    fs::path missing = tmp.write("missing.rib", "\nReadArchive \"nothere.rib\"\n");
    try {
        sss::read_rib(missing.string());
        ADD_FAILURE() << "no IoError";
    } catch (const sss::IoError& e) {
        EXPECT_NE(std::string(e.what()).find("missing.rib:2"), std::string::npos)
            << e.what();
    }
    EXPECT_THROW(sss::read_rib((tmp.path() / "absent.rib").string()), sss::IoError);
}

TEST(RibArchives, InlineArchivesAndDelayedReadArchive) {
    TempFolder tmp;
    tmp.write("geo.rib", "Color 1 0 0\nSphere 1 -1 1 360\n");
    fs::path main = tmp.write("scene.rib", R"(ArchiveBegin "thing"
  Disk 0 1 360
ArchiveEnd
WorldBegin
ReadArchive "thing"
Procedural "DelayedReadArchive" ["geo.rib"] [-1 1 -1 1 -1 1]
Sphere 2 -2 2 360
)");
    auto scene = sss::read_rib(main.string());
    ASSERT_EQ(scene.primitives.size(), 3u);
    EXPECT_EQ(scene.primitives[0].kind, sss::PrimitiveKind::Disk);
    EXPECT_EQ(scene.primitives[1].attributes->color, glm::dvec3(1, 0, 0));
    EXPECT_EQ(scene.primitives[2].attributes->color,
              glm::dvec3(1)); // procedural state restored
}

TEST(RibArchives, ObjImport) {
    TempFolder tmp;
    tmp.write("mesh.obj", R"(# a unit square and a triangle
mtllib x.mtl
o square
v 0 0 0
v 1 0 0
v 1 1 0 1.0
v 0 1 0
vt 0 0
vn 0 0 1
g g1
usemtl red
s off
f 1//1 2//1 3//1 4//1
v 2 0 0
v 3 0 0
v 2 1 0
f -3/1/-1 -2/1/1 -1//1
l 1 2
)");
    fs::path main = tmp.write(
        "scene.rib", "WorldBegin\nTranslate 0 0 1\nReadArchive \"MESH.OBJ\"\nWorldEnd\n");
    // Case-insensitive suffix; the file itself is lower case on disk, so link it.
    fs::copy_file(tmp.path() / "mesh.obj", tmp.path() / "MESH.OBJ");
    auto scene = sss::read_rib(main.string());
    ASSERT_EQ(scene.primitives.size(), 1u);
    const auto& p = scene.primitives[0];
    EXPECT_EQ(p.kind, sss::PrimitiveKind::PointsPolygons);
    EXPECT_EQ(p.nverts, (std::vector<int>{4, 3}));
    EXPECT_EQ(p.verts, (std::vector<int>{0, 1, 2, 3, 4, 5, 6}));
    EXPECT_EQ(p.params.find("P")->element_count(), 7u);
    const sss::Param* N = p.params.find("N");
    ASSERT_TRUE(N);
    EXPECT_EQ(N->storage, sss::ParamClass::FaceVarying);
    EXPECT_EQ(N->type, sss::ParamType::Normal);
    EXPECT_EQ(N->element_count(), 7u);
    expect_near(apply(p.object_to_world, {0, 0, 0}), {0, 0, 1});
    EXPECT_NE(p.source.find("MESH.OBJ:13"), std::string::npos) << p.source;
    EXPECT_TRUE(scene.warnings.empty()) << scene.warnings.front();
}

TEST(RibArchives, ObjWithoutNormalsEverywhereAndObjErrors) {
    TempFolder tmp;
    tmp.write(
        "a.obj",
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 5 5 5\nvn 0 0 1\nf 1//1 2//1 3//1\nf 1 3 2\n");
    tmp.write("bad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\n\nf 1 2 4\n");
    tmp.write("zero.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 0 1 2\n");
    tmp.write("nan.obj", "v 0 nan 0\n");
    fs::path a = tmp.write("a.rib", "WorldBegin\nReadArchive \"a.obj\"\n");
    auto scene = sss::read_rib(a.string());
    ASSERT_EQ(scene.primitives.size(), 1u);
    EXPECT_FALSE(scene.primitives[0].params.has("N"));
    // The unused last vertex is dropped.
    EXPECT_EQ(scene.primitives[0].params.find("P")->element_count(), 3u);

    for (const char* name : {"bad", "zero", "nan"}) {
        fs::path r =
            tmp.write(std::string(name) + ".rib",
                      "WorldBegin\nReadArchive \"" + std::string(name) + ".obj\"\n");
        try {
            sss::read_rib(r.string());
            ADD_FAILURE() << name << ": no error";
        } catch (const sss::RibError& e) {
            EXPECT_NE(e.path().find(std::string(name) + ".obj"), std::string::npos)
                << e.what();
            if (std::string(name) == "bad") {
                EXPECT_EQ(e.line(), 5);
                EXPECT_NE(std::string(e.what()).find("out of range"), std::string::npos);
            }
        }
    }
}

// --- imager and volume shaders --------------------------------------------------

namespace {

TEST(RibShaders, ImagerAtmosphereInteriorExterior) {
    const std::string text =
        "Imager \"background\" \"color bgcolor\" [0.1 0.2 0.3]\n" // 1: camera space
        "Translate 0 0 5\n"
        "WorldBegin\n"
        "Atmosphere \"fog\" \"float distance\" [4]\n" // 4
        "AttributeBegin\n"
        "Translate 1 0 0\n"
        "Interior \"murk\" \"float density\" [2]\n" // 7
        "Exterior \"depthcue\"\n"
        "Sphere 1 -1 1 360\n"
        "AttributeEnd\n"
        "Atmosphere \"null\"\n"
        "Sphere 1 -1 1 360\n"
        "Atmosphere \"fog\"\n"
        "Atmosphere \"\"\n"
        "Sphere 1 -1 1 360\n"
        "WorldEnd\n";
    const sss::Scene scene = parse(text);
    EXPECT_TRUE(scene.warnings.empty());
    ASSERT_TRUE(scene.options.imager);
    const sss::ShaderRef& imager = *scene.options.imager;
    EXPECT_EQ(imager.name, "background");
    EXPECT_EQ(imager.source, "test.rib:1");
    const glm::dvec3 bg = imager.params.get_vec3("bgcolor", glm::dvec3(0.0));
    EXPECT_DOUBLE_EQ(bg.y, 0.2);
    // Given before WorldBegin: camera space, the camera 5 along +z.
    expect_near(apply(imager.shader_to_world, {0, 0, 0}), {0, 0, -5});

    ASSERT_EQ(scene.primitives.size(), 3u);
    const sss::Attributes& a0 = *scene.primitives[0].attributes;
    ASSERT_TRUE(a0.atmosphere && a0.interior && a0.exterior);
    EXPECT_EQ(a0.atmosphere->name, "fog");
    EXPECT_EQ(a0.atmosphere->source, "test.rib:4");
    EXPECT_EQ(a0.atmosphere->params.get_float("distance", 0), 4.0);
    EXPECT_EQ(a0.interior->name, "murk");
    EXPECT_EQ(a0.interior->params.get_float("density", 0), 2.0);
    expect_near(apply(a0.interior->shader_to_world, {0, 0, 0}), {1, 0, 0});
    EXPECT_EQ(a0.exterior->name, "depthcue");
    // AttributeEnd restores them; "null" and "" turn the atmosphere off.
    const sss::Attributes& a1 = *scene.primitives[1].attributes;
    EXPECT_FALSE(a1.atmosphere);
    EXPECT_FALSE(a1.interior);
    EXPECT_FALSE(a1.exterior);
    EXPECT_FALSE(scene.primitives[2].attributes->atmosphere);
}

TEST(RibShaders, CoshadersAreScopedAttributesByHandle) {
    const std::string text =
        "Shader \"layer\" \"outer\" \"float gain\" [3]\n" // camera space
        "Translate 0 0 5\n"
        "WorldBegin\n"
        "AttributeBegin\n"
        "Translate 1 0 0\n"
        "Shader \"noise\" \"inner\"\n"                    // 6
        "Shader \"layer\" \"outer\" \"float gain\" [4]\n" // replaces
        "Sphere 1 -1 1 360\n"
        "AttributeEnd\n"
        "Shader \"spots\" 7\n" // a numeric handle
        "Sphere 1 -1 1 360\n"
        "WorldEnd\n";
    const sss::Scene scene = parse(text);
    EXPECT_TRUE(scene.warnings.empty());
    ASSERT_EQ(scene.primitives.size(), 2u);
    const auto& c0 = scene.primitives[0].attributes->coshaders;
    ASSERT_EQ(c0.size(), 2u);
    EXPECT_EQ(c0[0].handle, "outer");
    EXPECT_EQ(c0[0].shader.name, "layer");
    EXPECT_EQ(c0[0].shader.params.get_float("gain", 0), 4.0);
    EXPECT_EQ(c0[1].handle, "inner");
    EXPECT_EQ(c0[1].shader.source, "test.rib:6");
    expect_near(apply(c0[1].shader.shader_to_world, {0, 0, 0}), {1, 0, 0});
    // AttributeEnd restores the outer one; given before WorldBegin, its
    // shader space is camera space.
    const auto& c1 = scene.primitives[1].attributes->coshaders;
    ASSERT_EQ(c1.size(), 2u);
    EXPECT_EQ(c1[0].shader.params.get_float("gain", 0), 3.0);
    expect_near(apply(c1[0].shader.shader_to_world, {0, 0, 0}), {0, 0, -5});
    EXPECT_EQ(c1[1].handle, "7");
    expect_rib_error("WorldBegin\nShader \"layer\"\n", {"test.rib:2: Shader"});
}

TEST(RibShaders, ImagerNullTurnsItOffAndInsideTheWorldIsIgnored) {
    sss::Scene scene =
        parse("Imager \"background\"\nImager \"null\"\nWorldBegin\nWorldEnd\n");
    EXPECT_FALSE(scene.options.imager);
    scene = parse("Imager \"background\"\nImager \"\"\nWorldBegin\nWorldEnd\n");
    EXPECT_FALSE(scene.options.imager);
    scene = parse("WorldBegin\nImager \"background\"\nWorldEnd\n");
    EXPECT_FALSE(scene.options.imager);
    ASSERT_EQ(scene.warnings.size(), 1u);
    EXPECT_EQ(scene.warnings[0],
              "test.rib:2: Imager inside WorldBegin/WorldEnd has no effect, ignored");
    // Read strictly: no longer "not supported".
    EXPECT_NO_THROW(parse("Imager \"background\"\nWorldBegin\nAtmosphere \"fog\"\n"
                          "Interior \"fog\"\nExterior \"fog\"\nWorldEnd\n"));
    expect_rib_error("Imager\n", {"test.rib:1: Imager"});
    expect_rib_error("WorldBegin\nAtmosphere \"fog\" \"float distance\"\n",
                     {"test.rib:2: Atmosphere"});
}

} // namespace
