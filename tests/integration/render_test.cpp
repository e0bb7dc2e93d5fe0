// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file render_test.cpp
/// Tests of the renderer (sss/render.h) and of light_samples (sss/lights.h):
/// a matte pixel against its hand-computed value, camera framing
/// (perspective, orthographic, ScreenWindow), Sides, Opacity, shadows,
/// determinism across thread counts, beauty = sum of the AOVs, _ssdiffusion
/// lookups in point clouds and brick maps (a sphere lit from behind glows
/// only with subsurface scattering), errors, and the written EXR.
///
/// Suite names start with "Render". Images are small (64 x 48) so that the
/// whole file runs in a few seconds.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <OpenImageIO/imagebuf.h>
#include <glm/geometric.hpp>

#include "sss/bake/bake.h"
#include "sss/brick/brickmap.h"
#include "sss/cloud/point_cloud_io.h"
#include "sss/diffusion/ssdiffusion.h"
#include "sss/light/lights.h"
#include "sss/light/ray_tracer.h"
#include "sss/render/image_io.h"
#include "sss/render/render.h"
#include "sss/rsl/shader_library.h"
#include "sss/scene/rib.h"
#include "sss/util/error.h"
#include "sss/util/threads.h"
#include "sss/util/version.h"
#include "test_util.h"

namespace {

/// A 64 x 48 scene looking down +z at the world origin from 5 units away
/// (world axes = camera axes).
std::string
rib_of(const std::string& world, const std::string& options = "",
       const std::string& projection = "Projection \"perspective\" \"fov\" 30\n") {
    // The built-in AOV layers exist only where the scene asks for them.
    return "Format 64 48 1\nPixelSamples 2 2\n" + projection +
           "DisplayChannel \"color ambient\"\nDisplayChannel \"color diffuse\"\n"
           "DisplayChannel \"color specular\"\nDisplayChannel \"color sss\"\n"
           "DisplayChannel \"float occlusion\"\n" +
           options + "Translate 0 0 5\nWorldBegin\n" + world + "WorldEnd\n";
}

sss::Scene
scene_of(const std::string& world, const std::string& options = "",
         const std::string& projection = "Projection \"perspective\" \"fov\" 30\n") {
    return sss::parse_rib(rib_of(world, options, projection), "test.rib");
}

sss::Image render(const sss::Scene& scene, sss::RenderReport* report = nullptr) {
    return sss::render_image(scene, sss::RenderJobOptions{}, report);
}

float channel(const sss::Image& img, int x, int y, const std::string& name) {
    const int c = img.channel_index(name);
    EXPECT_GE(c, 0) << name;
    return c < 0 ? 0.0f : img.pixel(x, y)[c];
}

/// Mean of a channel over the 2 x 2 pixels around the image centre.
float centre(const sss::Image& img, const std::string& name) {
    const int x = img.width / 2, y = img.height / 2;
    return 0.25f * (channel(img, x - 1, y - 1, name) + channel(img, x, y - 1, name) +
                    channel(img, x - 1, y, name) + channel(img, x, y, name));
}

/// Pixels of the middle row with alpha above one half.
int covered_width(const sss::Image& img) {
    int n = 0;
    for (int x = 0; x < img.width; ++x) n += channel(img, x, img.height / 2, "A") > 0.5f;
    return n;
}

const std::string kFrontLight =
    "LightSource \"distantlight\" 1 \"from\" [0 0 -1] \"to\" [0 0 0] \"intensity\" [1]\n";

} // namespace

TEST(RenderShading, MatteSphereCentreMatchesHandComputedValue) {
    // Facing the light and the camera: N.L = 1, so Ci = Cs (Ka 0.1 + Kd 1).
    const sss::Image img = render(
        scene_of("LightSource \"ambientlight\" 1 \"intensity\" [0.1]\n" + kFrontLight +
                 "Color [0.5 0.6 0.7]\nSurface \"matte\"\nSphere 1 -1 1 360\n"));
    EXPECT_NEAR(centre(img, "R"), 0.55, 0.55 * 0.02);
    EXPECT_NEAR(centre(img, "G"), 0.66, 0.66 * 0.02);
    EXPECT_NEAR(centre(img, "B"), 0.77, 0.77 * 0.02);
    EXPECT_NEAR(centre(img, "A"), 1.0, 1e-6);
    EXPECT_NEAR(centre(img, "ambient.R"), 0.05, 0.001);
    EXPECT_NEAR(centre(img, "Z"), 4.0, 0.02); // the sphere's front, 4 units deep
    EXPECT_EQ(channel(img, 0, 0, "A"), 0.0f); // background
    EXPECT_EQ(channel(img, 0, 0, "R"), 0.0f);
}

TEST(RenderShading, PlasticHighlightFollowsRenderMansSpecular) {
    // Light and eye both along -z: H = N at the centre, so specular() = Cl.
    const sss::Image img = render(scene_of(
        kFrontLight + "Color [0.2 0.2 0.2]\nSurface \"plastic\" \"Ka\" [0] \"Kd\" [0.5] "
                      "\"Ks\" [0.5] \"roughness\" [0.1] \"specularcolor\" [1 0.5 0.25]\n"
                      "Sphere 1 -1 1 360\n"));
    EXPECT_NEAR(centre(img, "diffuse.R"), 0.1, 0.002);
    // 64x48 pixels: the filter averages a little of the falling-off lobe.
    EXPECT_NEAR(centre(img, "specular.R"), 0.5, 0.03);
    EXPECT_NEAR(centre(img, "specular.G") / centre(img, "specular.R"), 0.5, 1e-3);
    EXPECT_NEAR(centre(img, "specular.B") / centre(img, "specular.R"), 0.25, 1e-3);
}

TEST(RenderCamera, PerspectiveAndOrthographicFraming) {
    const std::string sphere = kFrontLight + "Surface \"matte\"\nSphere 1 -1 1 360\n";
    // Perspective: the silhouette's half-angle is asin(1/5); the screen's
    // half-height tan(15 deg) is 24 pixels.
    const double half =
        std::tan(std::asin(0.2)) / std::tan(15.0 * 3.14159265358979 / 180.0) * 24.0;
    EXPECT_NEAR(covered_width(render(scene_of(sphere))), 2.0 * half, 1.5);
    // Orthographic: the default screen window is [-4/3, 4/3] x [-1, 1]: a
    // unit sphere spans 2 of 8/3 units, 48 pixels, whatever its distance.
    const std::string ortho = "Projection \"orthographic\"\n";
    EXPECT_NEAR(covered_width(render(scene_of(sphere, "", ortho))), 48.0, 1.0);
}

TEST(RenderCamera, ScreenWindowZooms) {
    const std::string sphere =
        kFrontLight + "Surface \"matte\"\nSphere 0.5 -0.5 0.5 360\n";
    const std::string ortho = "Projection \"orthographic\"\n";
    EXPECT_NEAR(covered_width(render(scene_of(sphere, "", ortho))), 24.0, 1.0);
    // Half the window: twice the size.
    const sss::Image zoomed =
        render(scene_of(sphere, "ScreenWindow -0.6666667 0.6666667 -0.5 0.5\n", ortho));
    EXPECT_NEAR(covered_width(zoomed), 48.0, 1.0);
    // An off-centre window moves the sphere: its centre column shifts.
    const sss::Image shifted =
        render(scene_of(sphere, "ScreenWindow -0.3333333 2.3333333 -1 1\n", ortho));
    int first = -1;
    for (int x = 0; x < 64 && first < 0; ++x)
        if (channel(shifted, x, 24, "A") > 0.5f) first = x;
    // Screen x = -0.5 is at raster (-0.5 + 1/3) / (8/3) * 64 = -4: the left
    // edge leaves the picture, the right one (x = 0.5) is at raster 20.
    EXPECT_EQ(first, 0);
    EXPECT_NEAR(covered_width(shifted), 20.0, 1.0);
}

TEST(RenderCamera, ClippingHidesWhatIsOutsideHitherAndYon) {
    const std::string sphere = kFrontLight + "Surface \"matte\"\nSphere 1 -1 1 360\n";
    EXPECT_GT(centre(render(scene_of(sphere, "Clipping 0.1 100\n")), "A"), 0.99f);
    // Yon before the sphere: nothing.
    EXPECT_EQ(centre(render(scene_of(sphere, "Clipping 0.1 3.5\n")), "A"), 0.0f);
    // Hither inside the sphere: the ray starts past its front and sees the
    // inside of its back (Sides 2).
    const sss::Image inside = render(scene_of(sphere, "Clipping 4.5 100\n"));
    EXPECT_GT(centre(inside, "A"), 0.99f);
    EXPECT_NEAR(centre(inside, "Z"), 6.0, 0.01);
}

TEST(RenderGeometry, SidesOneHidesBackFaces) {
    // A disk faces +z: away from this camera.
    const std::string disk = "Surface \"constant\"\nDisk 0 1 360\n";
    EXPECT_GT(centre(render(scene_of(disk)), "A"), 0.99f);
    EXPECT_EQ(centre(render(scene_of("Sides 1\n" + disk)), "A"), 0.0f);
    EXPECT_GT(centre(render(scene_of("Sides 1\nReverseOrientation\n" + disk)), "A"),
              0.99f);
    // One-sided sphere: the front faces are seen, as usual.
    EXPECT_GT(centre(render(scene_of("Sides 1\n" + kFrontLight +
                                     "Surface \"matte\"\nSphere 1 -1 1 360\n")),
                     "R"),
              0.9f);
}

TEST(RenderGeometry, SemiTransparentSurfacesComposite) {
    // A red plane at half opacity in front of an opaque green one.
    const std::string red =
        "AttributeBegin\nColor [1 0 0]\nOpacity [0.5 0.5 0.5]\n"
        "Surface \"constant\"\n"
        "Polygon \"P\" [-3 -3 0  -3 3 0  3 3 0  3 -3 0]\nAttributeEnd\n";
    const std::string green =
        "AttributeBegin\nColor [0 1 0]\nSurface \"constant\"\n"
        "Polygon \"P\" [-3 -3 1  -3 3 1  3 3 1  3 -3 1]\nAttributeEnd\n";
    const sss::Image both = render(scene_of(red + green));
    EXPECT_NEAR(centre(both, "R"), 0.5, 1e-5);
    EXPECT_NEAR(centre(both, "G"), 0.5, 1e-5);
    EXPECT_NEAR(centre(both, "A"), 1.0, 1e-5);
    EXPECT_NEAR(centre(both, "Z"), 5.0, 1e-4); // the first surface
    // A depth map (shadow pass) sees through semi-transparent surfaces:
    // its depth is the nearest opaque one (zthreshold 0.996), or PRMan's
    // Option "limits" "zthreshold" when lowered below the red plane's 0.5.
    const std::string zfile = "Display \"key.z\" \"zfile\" \"z\"\n";
    EXPECT_NEAR(centre(render(scene_of(red + green, zfile)), "Z"), 6.0, 1e-4);
    EXPECT_NEAR(centre(render(scene_of(
                           red + green,
                           zfile + "Option \"limits\" \"zthreshold\" [0.4 0.4 0.4]\n")),
                       "Z"),
                5.0, 1e-4);
    // Only semi-transparent surfaces: no depth, and no "nothing hit" warning.
    sss::RenderReport report;
    const sss::Image glass = render(scene_of(red, zfile), &report);
    EXPECT_EQ(centre(glass, "Z"), 0.0f);
    for (const std::string& w : report.warnings)
        EXPECT_EQ(w.find("no camera ray hit"), std::string::npos) << w;
    const sss::Image alone = render(scene_of(red));
    EXPECT_NEAR(centre(alone, "R"), 0.5, 1e-5); // premultiplied
    EXPECT_NEAR(centre(alone, "A"), 0.5, 1e-5);
    // Per-channel opacity: the green plane shows through the blue channel only.
    const std::string tinted =
        "AttributeBegin\nColor [0 0 0]\nOpacity [1 1 0]\n"
        "Surface \"constant\"\n"
        "Polygon \"P\" [-3 -3 0  -3 3 0  3 3 0  3 -3 0]\nAttributeEnd\n";
    const std::string white =
        "AttributeBegin\nColor [1 1 1]\nSurface \"constant\"\n"
        "Polygon \"P\" [-3 -3 1  -3 3 1  3 3 1  3 -3 1]\nAttributeEnd\n";
    const sss::Image tint = render(scene_of(tinted + white));
    EXPECT_NEAR(centre(tint, "R"), 0.0, 1e-5);
    EXPECT_NEAR(centre(tint, "B"), 1.0, 1e-5);
}

TEST(RenderLighting, BlockerShadowsTheFloor) {
    // A floor facing the camera at z = 1, lit head-on, with a small square
    // between it and a point light at the eye.
    const std::string world =
        std::string("LightSource \"pointlight\" 1 \"from\" [0 0 -5] "
                    "\"intensity\" [36] %s\n") +
        "Surface \"matte\"\n"
        "Polygon \"P\" [-3 -3 1  -3 3 1  3 3 1  3 -3 1]\n"
        "AttributeBegin\nAttribute \"visibility\" \"int camera\" [0]\n"
        "Polygon \"P\" [-0.3 -0.3 -2  -0.3 0.3 -2  0.3 0.3 -2  0.3 -0.3 -2]\n"
        "AttributeEnd\n";
    auto with = [&](const std::string& shadow) {
        std::string w = world;
        w.replace(w.find("%s"), 2, shadow);
        return render(scene_of(w));
    };
    const sss::Image lit = with("");
    const sss::Image shadowed = with("\"string shadowname\" [\"raytrace\"]");
    EXPECT_NEAR(centre(lit, "R"), 1.0, 0.01); // 36 / 6^2 at N.L = 1
    EXPECT_LT(centre(shadowed, "R"), 0.01);
    // Outside the shadow (the blocker's shadow on the floor is 0.3 * 6 / 3
    // = 0.6 units wide each way; the corner is ~ 3 units out) both agree.
    EXPECT_NEAR(channel(shadowed, 4, 4, "R"), channel(lit, 4, 4, "R"), 1e-6);
    // The camera does not see the blocker.
    EXPECT_NEAR(centre(shadowed, "Z"), 6.0, 1e-3);
}

TEST(RenderLighting, LightSamplesAddUpToIrradiance) {
    sss::Scene scene = scene_of(
        "LightSource \"ambientlight\" 1 \"intensity\" [0.1] \"lightcolor\" [1 0.5 0.2]\n"
        "LightSource \"distantlight\" 2 \"from\" [1 2 -1] \"to\" [0 0 0]\n"
        "LightSource \"pointlight\" 3 \"from\" [-2 1 -3] \"intensity\" [9] "
        "\"string shadowname\" [\"raytrace\"] \"samples\" [16] \"radius\" [0.5]\n"
        "LightSource \"spotlight\" 4 \"from\" [0 3 -3] \"to\" [0 0 0] \"intensity\" [20] "
        "\"coneangle\" [0.6]\n");
    const std::vector<sss::Light> lights = sss::resolve_lights(scene, nullptr);
    const std::vector<int> active = {0, 1, 2, 3};
    // A blocker for the soft point light.
    sss::RayTracer tracer;
    tracer.add_mesh({{-1.6f, 0.6f, -2.0f}, {-1.0f, 0.6f, -2.0f}, {-1.3f, 1.2f, -2.0f}},
                    {0, 1, 2});
    tracer.commit();
    std::vector<sss::LightSample> samples;
    for (int i = 0; i < 200; ++i) {
        const double a = 0.1 * i, b = 0.37 * i;
        const glm::dvec3 n = glm::normalize(glm::dvec3(
            std::sin(a) * std::cos(b), std::cos(a), std::sin(a) * std::sin(b)));
        const glm::dvec3 p = 0.8 * n - glm::dvec3(0.0, 0.0, 0.3);
        const glm::dvec3 e = sss::irradiance(lights, active, p, n, &tracer, i, 1e-4);
        sss::light_samples(lights, active, p, n, &tracer, i, 1e-4, samples);
        glm::dvec3 sum(0.0);
        for (const sss::LightSample& s : samples) {
            if (s.ambient) {
                EXPECT_EQ(s.direction, glm::dvec3(0.0));
                sum += s.color;
            } else {
                EXPECT_NEAR(glm::length(s.direction), 1.0, 1e-12);
                EXPECT_GT(glm::dot(n, s.direction), 0.0);
                sum += s.color * glm::dot(n, s.direction);
            }
        }
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(sum[c], e[c], 1e-12 * (1.0 + e[c]));
        EXPECT_EQ(samples.front().light, 0);
        EXPECT_TRUE(samples.front().ambient);
    }
}

TEST(RenderDeterminism, SameImageForOneAndTwoThreads) {
    const sss::Scene scene =
        scene_of("LightSource \"ambientlight\" 1 \"intensity\" [0.05]\n"
                 "LightSource \"pointlight\" 2 \"from\" [-2 2 -3] \"intensity\" [20] "
                 "\"string shadowname\" [\"raytrace\"] \"samples\" [4] \"radius\" [0.3]\n"
                 "AttributeBegin\nOpacity [0.6 0.6 0.6]\nSurface \"plastic\"\n"
                 "Sphere 0.7 -0.7 0.7 360\nAttributeEnd\n"
                 "Surface \"skin\" \"float occlusion_samples\" [4]\n"
                 "Polygon \"P\" [-3 -3 1  -3 3 1  3 3 1  3 -3 1]\n");
    sss::Image one, two;
    {
        sss::ThreadLimit limit(1);
        one = render(scene);
    }
    {
        sss::ThreadLimit limit(2);
        two = render(scene);
    }
    ASSERT_EQ(one.pixels.size(), two.pixels.size());
    EXPECT_TRUE(one.pixels == two.pixels);
    // And the soft shadow is there: not every pixel of the floor is the same.
    EXPECT_GT(*std::max_element(one.pixels.begin(), one.pixels.end()), 0.0f);
}

namespace {

/// A unit sphere baked, diffused (marble, 1 unit = 1 mm: thin enough for
/// light to cross it) and written as a .ptc and a .bkm into dir. The light
/// is behind the sphere, at +z.
void make_diffusion_files(const sss::test::TempDir& dir, const std::string& light) {
    sss::Scene bake = scene_of(light + "Surface \"bake_radiance_t\" \"string filename\" "
                                       "[\"s.ptc\"]\nSphere 1 -1 1 360\n");
    sss::BakeOptions bo;
    bo.spacing = 0.08;
    auto clouds = sss::bake_clouds(bake, bo, nullptr);
    ASSERT_EQ(clouds.size(), 1u);
    sss::SsDiffusionOptions so;
    so.material.preset = "marble";
    so.material.unitlength = 1.0;
    const sss::PointCloud ssd = sss::ssdiffusion(clouds[0].second, so);
    sss::write_point_cloud(ssd, dir.file("ssd.ptc"), sss::PointCloudWriteOptions{});
    sss::BrickMapBuildOptions bm;
    bm.max_error = 0.0005;
    sss::build_brick_map({ssd}, bm, dir.file("ssd.bkm"));
}

const std::string kBackLight =
    "LightSource \"pointlight\" 1 \"from\" [0 0 4] \"intensity\" [64]\n";

} // namespace

TEST(RenderSubsurface, BackLitSphereGlowsOnlyWithDiffusion) {
    sss::test::TempDir dir("sss_render");
    make_diffusion_files(dir, kBackLight);
    const sss::Image matte =
        render(scene_of(kBackLight + "Surface \"matte\"\nSphere 1 -1 1 360\n"));
    EXPECT_LT(centre(matte, "R"), 1e-6); // no light reaches the camera side
    for (const std::string file : {"ssd.bkm", "ssd.ptc"}) {
        const sss::Image sss_img = render(
            scene_of(kBackLight + "Surface \"read_ssdiffusion\" \"string filename\" [\"" +
                     dir.file(file) + "\"]\nSphere 1 -1 1 360\n"));
        EXPECT_GT(centre(sss_img, "R"), 0.08) << file;
        EXPECT_GT(centre(sss_img, "sss.R"), 0.08) << file;
        EXPECT_NEAR(centre(sss_img, "R"), centre(sss_img, "sss.R"), 1e-6) << file;
        // Marble scatters red farthest: more red than blue comes through.
        EXPECT_GT(centre(sss_img, "R"), centre(sss_img, "B")) << file;
    }
}

TEST(RenderSubsurface, BeautyIsTheSumOfTheAovs) {
    sss::test::TempDir dir("sss_render");
    const std::string light = "LightSource \"ambientlight\" 1 \"intensity\" [0.05]\n"
                              "LightSource \"pointlight\" 2 \"from\" [2 2 -4] "
                              "\"intensity\" [25] \"string shadowname\" [\"raytrace\"]\n";
    make_diffusion_files(dir, light);
    const std::string bkm = dir.file("ssd.bkm");
    const sss::Scene scene = scene_of(
        light +
        "AttributeBegin\nTranslate -1.2 0.6 0\nScale 0.5 0.5 0.5\n"
        "Surface \"matte\"\nSphere 1 -1 1 360\nAttributeEnd\n"
        "AttributeBegin\nTranslate 1.2 0.6 0\nScale 0.5 0.5 0.5\n"
        "Color [0.8 0.5 0.3]\n"
        "Surface \"plastic\"\nSphere 1 -1 1 360\nAttributeEnd\n"
        "AttributeBegin\nColor [0.9 0.8 0.7]\nSurface \"read_ssdiffusion\" "
        "\"Ka\" [1] \"Kd\" [0.2] \"string filename\" [\"" +
        bkm +
        "\"]\nSphere 1 -1 1 360\nAttributeEnd\n"
        "AttributeBegin\nSurface \"skin\" \"float occlusion_samples\" [8] "
        "\"float Ka\" [1] \"string filename\" [\"" +
        bkm +
        "\"]\nPolygon \"P\" [-3 -3 1.5  -3 3 1.5  3 3 1.5  3 -3 1.5]\nAttributeEnd\n");
    const sss::Image img = render(scene);
    double worst = 0.0, total_sss = 0.0, total_spec = 0.0, total_amb = 0.0;
    double min_occ = 1.0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x)
            for (const char* c : {"R", "G", "B"}) {
                const std::string s(c);
                const double sum = channel(img, x, y, "ambient." + s) +
                                   channel(img, x, y, "diffuse." + s) +
                                   channel(img, x, y, "specular." + s) +
                                   channel(img, x, y, "sss." + s);
                worst = std::max(worst, std::abs(sum - channel(img, x, y, s)));
                total_sss += channel(img, x, y, "sss." + s);
                total_spec += channel(img, x, y, "specular." + s);
                total_amb += channel(img, x, y, "ambient." + s);
                if (channel(img, x, y, "A") > 0.999f)
                    min_occ =
                        std::min(min_occ, double(channel(img, x, y, "occlusion." + s)));
            }
    EXPECT_LT(worst, 1e-4);
    EXPECT_GT(total_sss, 1.0);
    EXPECT_GT(total_spec, 0.1);
    EXPECT_GT(total_amb, 0.1);
    EXPECT_LT(min_occ, 0.9); // the floor next to the sphere is occluded
}

TEST(RenderErrors, MissingDiffusionFileNamesTheShaderAndTheFile) {
    const sss::Scene scene = scene_of(
        "Surface \"read_ssdiffusion\" \"string filename\" [\"/nonexistent/x.bkm\"]\n"
        "Sphere 1 -1 1 360\n");
    try {
        render(scene);
        FAIL() << "no error";
    } catch (const sss::Error& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("test.rib:"), std::string::npos) << what;
        EXPECT_NE(what.find("read_ssdiffusion"), std::string::npos) << what;
        EXPECT_NE(what.find("/nonexistent/x.bkm"), std::string::npos) << what;
    }
    // No filename at all: read_ssdiffusion (as the application note's) then
    // has no subsurface term.
    EXPECT_NO_THROW(
        render(scene_of("Surface \"read_ssdiffusion\"\nSphere 1 -1 1 360\n")));
    // A parameter of the wrong type.
    EXPECT_THROW(render(scene_of("Surface \"plastic\" \"string roughness\" [\"x\"]\n"
                                 "Sphere 1 -1 1 360\n")),
                 sss::ValueError);
}

TEST(RenderErrors, UnknownShadersAreErrorsNamingTheSearchPath) {
    // A shader the search path does not have stops the render (it used to
    // render a grey headlight with exit 0).
    try {
        render(scene_of("Surface \"wood\"\nSphere 1 -1 1 360\n"));
        FAIL() << "no error";
    } catch (const sss::ShaderNotFoundError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("test.rib:"), std::string::npos) << what;
        EXPECT_NE(what.find("shader \"wood\" not found"), std::string::npos) << what;
        EXPECT_NE(what.find("search path"), std::string::npos) << what;
    }
    // No Surface at all: defaultsurface, Ka 0.2 + Kd 0.8 |N.I|, 1 at the centre.
    const sss::Image img = render(scene_of("Sphere 1 -1 1 360\n"));
    EXPECT_NEAR(centre(img, "R"), 1.0, 0.01);
}

TEST(RenderOutput, WritesDisplaysWithLayersMetadataAndFramePatterns) {
    sss::test::TempDir dir("sss_render");
    const std::string rib =
        rib_of(kFrontLight + "Surface \"plastic\"\nSphere 1 -1 1 360\n",
               "Display \"" + dir.file("beauty.####.exr") +
                   "\" \"openexr\" \"rgba\"\n"
                   "Display \"+" +
                   dir.file("spec.####.exr") + "\" \"openexr\" \"specular\"\n");
    const sss::Scene scene = sss::parse_rib(rib, dir.file("scene.rib"));
    sss::RenderJobOptions opt;
    opt.frame = 7;
    opt.command_line = "render -frame 7 scene.rib";
    const sss::RenderReport report = sss::render_scene(scene, opt);
    ASSERT_EQ(report.files.size(), 2u);
    EXPECT_EQ(report.files[0], dir.file("beauty.0007.exr"));
    EXPECT_EQ(report.files[1], dir.file("spec.0007.exr"));
    EXPECT_GT(report.camera_rays, 64u * 48u * 4u - 1u);

    const sss::Image beauty = sss::read_image(report.files[0]);
    for (const char* c : {"R", "G", "B", "A", "ambient.R", "diffuse.G", "specular.B",
                          "sss.R", "occlusion.G"})
        EXPECT_GE(beauty.channel_index(c), 0) << c;
    EXPECT_EQ(sss::read_image_attribute(report.files[0], "Software"),
              std::string("render (sss) ") + sss::version_string());
    EXPECT_EQ(sss::read_image_attribute(report.files[0], "sss:commandLine"),
              opt.command_line);
    EXPECT_EQ(sss::read_image_attribute(report.files[0], "sss:pixelSamples"), "2 2");
    EXPECT_FALSE(sss::read_image_attribute(report.files[0], "renderTimeSeconds").empty());
    const sss::Image spec = sss::read_image(report.files[1]);
    EXPECT_GT(spec.channel_count(), 0);

    // -o replaces the primary Display.
    opt.output = dir.file("other.%d.exr");
    const sss::RenderReport again = sss::render_scene(scene, opt);
    EXPECT_EQ(again.files[0], dir.file("other.7.exr"));
}

TEST(RenderOutput, FilesReadAndWrittenAreKnownBeforeRendering) {
    // Two diffusion shaders on one map (listed once), one on another, with a
    // frame pattern; a primary and an additional Display, and an "it" one.
    const sss::Scene scene =
        scene_of("Surface \"read_ssdiffusion\" \"string filename\" [\"m.####.bkm\"]\n"
                 "Sphere 1 -1 1 360\n"
                 "Surface \"skin\" \"string filename\" [\"m.####.bkm\"]\n"
                 "Sphere 0.5 -0.5 0.5 360\n"
                 "Surface \"read_ssdiffusion\" \"string filename\" [\"n.ptc\"]\n"
                 "Disk 0 1 360\n"
                 "Surface \"matte\"\nDisk 0 2 360\n",
                 "Display \"img.$F4.exr\" \"openexr\" \"rgba\"\n"
                 "Display \"+sss.png\" \"png\" \"sss\"\n"
                 "Display \"+view\" \"it\" \"rgb\"\n");
    sss::RenderJobOptions opt;
    opt.frame = 5;
    sss::RenderFiles files = sss::render_files(scene, opt);
    // The maps the shaders read, then the shaders themselves.
    ASSERT_GE(files.inputs.size(), 4u);
    EXPECT_EQ(std::vector<std::string>(files.inputs.begin(), files.inputs.begin() + 2),
              (std::vector<std::string>{"m.0005.bkm", "n.ptc"}));
    for (const char* shader : {"read_ssdiffusion.slo", "skin.slo", "matte.slo"})
        EXPECT_TRUE(
            std::any_of(files.inputs.begin(), files.inputs.end(),
                        [&](const std::string& f) { return f.ends_with(shader); }))
            << shader;
    EXPECT_EQ(files.outputs,
              (std::vector<std::string>{"img.0005.exr", "sss.png", "view.exr"}));
    // -o replaces the primary Display's file.
    opt.output = "beauty.png";
    files = sss::render_files(scene, opt);
    EXPECT_EQ(files.outputs,
              (std::vector<std::string>{"beauty.png", "sss.png", "view.exr"}));
    // Without Displays: "<scene>.exr".
    EXPECT_EQ(sss::render_files(scene_of(""), {}).outputs,
              std::vector<std::string>{"test.exr"});
}

TEST(RenderShading, DerivativesAtHitsComeFromThePixelFootprint) {
    // An orthographic view of a plane facing the camera, 20 x 20 pixels over
    // a 2 x 2 screen window: one pixel is 0.1 x 0.1 on the plane. A shader
    // that differentiates is shaded with its hits' neighbours, so Du(P),
    // area(P) and the derivative of a function of P are the pixel's.
    sss::test::TempDir dir("sss_render_deriv");
    sss::test::write_text(dir.file("footprint.sl"), R"(
surface footprint() {
    float a = area(P);
    float du = length(Du(P));
    float dx = Du(xcomp(P) * xcomp(P));
    Ci = color(a * 100, du * 10, 0);
    Oi = 1;
}
)");
    const std::string rib =
        "Format 20 20 1\nPixelSamples 1 1\nProjection \"orthographic\"\n"
        "ScreenWindow -1 1 -1 1\nTranslate 0 0 5\nWorldBegin\n"
        "Surface \"footprint\"\n"
        "Polygon \"P\" [-3 -3 0  -3 3 0  3 3 0  3 -3 0]\nWorldEnd\n";
    const sss::Scene scene = sss::parse_rib(rib, dir.file("scene.rib"));
    const sss::Image img = render(scene);
    EXPECT_NEAR(centre(img, "R"), 1.0, 1e-3); // area = 0.01
    EXPECT_NEAR(centre(img, "G"), 1.0, 1e-3); // |Du(P)| = 0.1
}

TEST(RenderDisplacement, DisplacedSphereHasALargerSilhouette) {
    sss::test::TempDir dir;
    sss::test::write_text(dir.file("grow.sl"), "displacement grow(float amount = 0.1) {\n"
                                               "    P += amount * normalize(N);\n"
                                               "    N = calculatenormal(P);\n}\n");
    const auto covered = [&](const std::string& displacement) {
        const std::string path = dir.file("scene.rib");
        const std::string text =
            rib_of(kFrontLight + displacement + "Surface \"matte\"\nSphere 1 -1 1 360\n");
        sss::test::write_text(path, text);
        sss::RenderReport report;
        const sss::Image img = render(sss::parse_rib(text, path), &report);
        for (const std::string& w : report.warnings) ADD_FAILURE() << w;
        int n = 0;
        for (int y = 0; y < img.height; ++y)
            for (int x = 0; x < img.width; ++x) n += channel(img, x, y, "A") > 0.5f;
        return n;
    };
    // The silhouette of a sphere of radius r, 5 units away, in pixels
    // (fov 30 across the 48 pixels of the image's height).
    const auto disc = [](double r) {
        const double half =
            std::tan(std::asin(r / 5.0)) / std::tan(15.0 * M_PI / 180.0) * 24;
        return M_PI * half * half;
    };
    const int plain = covered("");
    const int grown = covered("Attribute \"displacementbound\" \"sphere\" [0.1]\n"
                              "Displacement \"grow\"\n");
    EXPECT_NEAR(plain, disc(1.0), 0.03 * disc(1.0));
    EXPECT_NEAR(grown, disc(1.1), 0.03 * disc(1.1));
    EXPECT_GT(grown, plain + 100);
}

TEST(RenderShading, TextureCoordinatesAtHitsFollowTheSurface) {
    // An orthographic view of a square that fills the screen window, 40 x 40
    // pixels: its s and t (and u and v) at a pixel are the pixel's place on
    // the square, and Du(s) du is s's change over one pixel.
    sss::test::TempDir dir("sss_render_st");
    sss::test::write_text(dir.file("st.sl"), R"(
surface st() {
    Ci = color(s, t, Du(s) * du * 20);
    Oi = 1;
}
)");
    sss::test::write_text(dir.file("uv.sl"), R"(
surface uv() {
    Ci = color(u, v, Dv(v) * dv * 40);
    Oi = 1;
}
)");
    const auto image = [&](const std::string& surface, const std::string& st) {
        const std::string rib =
            "Format 40 40 1\nPixelSamples 4 4\nProjection \"orthographic\"\n"
            "ScreenWindow -1 1 -1 1\nTranslate 0 0 5\nWorldBegin\n"
            "Surface \"" +
            surface + "\"\nPolygon \"P\" [-1 -1 0  1 -1 0  1 1 0  -1 1 0]" + st +
            "\nWorldEnd\n";
        return render(sss::parse_rib(rib, dir.file("scene.rib")));
    };
    // "st" doubles s; the image's y runs down, t up.
    const sss::Image st = image("st", " \"st\" [0 0  2 0  2 1  0 1]");
    const sss::Image uv = image("uv", "");
    for (int y : {3, 11, 20, 27, 36})
        for (int x : {2, 9, 19, 30, 37}) {
            const float fx = (x + 0.5f) / 40.0f, fy = 1.0f - (y + 0.5f) / 40.0f;
            EXPECT_NEAR(channel(st, x, y, "R"), 2.0f * fx, 1e-2) << x << " " << y;
            EXPECT_NEAR(channel(st, x, y, "G"), fy, 1e-2) << x << " " << y;
            EXPECT_NEAR(channel(st, x, y, "B"), 1.0f, 1e-3) << x << " " << y;
            EXPECT_NEAR(channel(uv, x, y, "R"), fx, 1e-2) << x << " " << y;
            EXPECT_NEAR(channel(uv, x, y, "G"), fy, 1e-2) << x << " " << y;
            EXPECT_NEAR(channel(uv, x, y, "B"), 1.0f, 1e-3) << x << " " << y;
        }
}

TEST(RenderShading, PaintedPlasticShowsItsTexture) {
    // A 2 x 2 checker of four colours (32 x 32 texels, so that filtering
    // blends them only near the quadrants' borders) on a square that fills
    // the screen: each quadrant's inside shows its colour, lit by an ambient
    // light of intensity 1 (Ka 1, no diffuse or specular).
    sss::test::TempDir dir("sss_render_texture");
    const float colours[4][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 0.5f}};
    constexpr int kTexels = 32;
    OIIO::ImageBuf checker(OIIO::ImageSpec(kTexels, kTexels, 3, OIIO::TypeDesc::FLOAT));
    for (int y = 0; y < kTexels; ++y)
        for (int x = 0; x < kTexels; ++x)
            checker.setpixel(x, y, colours[2 * (y / 16) + x / 16], 3);
    const std::string map = dir.file("checker.exr");
    ASSERT_TRUE(checker.write(map)) << checker.geterror();
    const std::string rib =
        "Format 32 32 1\nPixelSamples 2 2\nProjection \"orthographic\"\n"
        "ScreenWindow -1 1 -1 1\nTranslate 0 0 5\nWorldBegin\n"
        "LightSource \"ambientlight\" 1 \"intensity\" [1]\n"
        "Surface \"paintedplastic\" \"float Ka\" [1] \"float Kd\" [0] \"float Ks\" [0] "
        "\"string texturename\" [\"" +
        map +
        "\"]\n"
        // t = 0 at the top of the image, as texture maps have it.
        "Polygon \"P\" [-1 -1 0  1 -1 0  1 1 0  -1 1 0] \"st\" [0 1  1 1  1 0  0 0]\n"
        "WorldEnd\n";
    sss::RenderReport report;
    const sss::Image img = render(sss::parse_rib(rib, dir.file("scene.rib")), &report);
    for (const std::string& w : report.warnings) ADD_FAILURE() << w;
    for (int y : {3, 7, 12, 19, 24, 28})
        for (int x : {3, 7, 12, 19, 24, 28}) {
            const float* want = colours[2 * (y / 16) + x / 16];
            EXPECT_NEAR(channel(img, x, y, "R"), want[0], 1e-2) << x << " " << y;
            EXPECT_NEAR(channel(img, x, y, "G"), want[1], 1e-2) << x << " " << y;
            EXPECT_NEAR(channel(img, x, y, "B"), want[2], 1e-2) << x << " " << y;
        }
}
