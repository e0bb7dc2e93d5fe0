// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// ptbake with ray-traced global illumination (issue 14): closed-form checks
// of occlusion() and indirectdiffuse() on a plane under a sphere, and a
// furnace (the inside of a glowing sphere) for the recursion of hit shaders.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "sss/bake/bake.h"
#include "sss/scene/rib.h"
#include "test_util.h"

namespace {

/// The plane z = 0 (normal turned towards +z) bakes occlusion and
/// indirect diffuse light; a sphere of radius 1 floats at height 2.
const char* kPlaneShader = R"(
surface bake_gi_plane(string filename = ""; float samples = 64;
                      string distribution = "cosine"; string envmap = "";
                      float adaptive = 0) {
    normal Nn = normalize(ntransform("world", N));
    if (zcomp(Nn) < 0) Nn = -Nn;
    Nn = ntransform("world", "current", Nn);
    float occ = occlusion(P, Nn, samples, "distribution", distribution,
                          "adaptive", adaptive);
    color ind = indirectdiffuse(P, Nn, samples, "environmentmap", envmap,
                                "adaptive", adaptive);
    bake3d(filename, "occ,ind", P, Nn, "occ", occ, "ind", ind);
    Ci = 1;
}
)";

/// The inside of a sphere that glows (Ke) and reflects diffusely (Kd).
const char* kFurnaceShader = R"(
surface furnace(string filename = ""; float samples = 16; float Ke = 1; float Kd = 0.5) {
    normal Nn = normalize(N);
    if (Nn . (point "world" (0, 0, 0) - P) < 0) Nn = -Nn;
    color L = Ke + Kd * indirectdiffuse(P, Nn, samples);
    float depth = 0;
    rayinfo("depth", depth);
    if (depth == 0) bake3d(filename, "L", P, Nn, "L", L);
    Ci = L;
}
)";

sss::Scene scene_in(const sss::test::TempDir& dir, const std::string& options,
                    const std::string& world) {
    const std::string path = dir.file("scene.rib");
    const std::string text = options +
                             "Format 100 100 1\nProjection \"perspective\" \"fov\" 40\n"
                             "Translate 0 0 8\nWorldBegin\n" +
                             world + "WorldEnd\n";
    sss::test::write_text(path, text);
    return sss::parse_rib(text, path);
}

struct PlaneResult {
    double occ_rms = 0.0, ind_rms = 0.0, occ_mean_error = 0.0;
    std::size_t points = 0;
};

/// Bakes the plane under the sphere and compares every point with the form
/// factor of the sphere, F = R^2 d / D^3 (R = 1, centre at height d = 2,
/// D the distance to the centre): cosine-weighted occlusion F, and with a
/// white environment and a sphere of colour c, indirect diffuse 1 - F + c F.
PlaneResult bake_plane(int samples, const std::string& envmap = "", double c = 0.25,
                       bool adaptive = false) {
    sss::test::TempDir dir;
    sss::test::write_text(dir.file("bake_gi_plane.sl"), kPlaneShader);
    const std::string cloud = dir.file("plane.ptc");
    const sss::Scene scene = scene_in(
        dir, "",
        "AttributeBegin\nSurface \"bake_gi_plane\" \"string filename\" [\"" + cloud +
            "\"] \"float samples\" " + std::to_string(samples) + " \"float adaptive\" " +
            (adaptive ? "1" : "0") + " \"string envmap\" [\"" + envmap +
            "\"]\nPolygon \"P\" [-2 -2 0  2 -2 0  2 2 0  -2 2 0]\nAttributeEnd\n"
            "AttributeBegin\nTranslate 0 0 2\nColor [" +
            std::to_string(c) + " " + std::to_string(c) + " " + std::to_string(c) +
            "]\nSurface \"constant\"\nSphere 1 -1 1 360\nAttributeEnd\n");
    sss::BakeOptions opt;
    opt.spacing = 0.1;
    const auto files = sss::bake_clouds(scene, opt, nullptr);
    EXPECT_EQ(files.size(), 1u);
    const sss::PointCloud& pc = files.at(0).second;
    const sss::Channel* occ = pc.find_channel("occ");
    const sss::Channel* ind = pc.find_channel("ind");
    EXPECT_TRUE(occ && ind);
    PlaneResult r;
    r.points = pc.size();
    for (std::size_t i = 0; i < pc.size(); ++i) {
        const glm::vec3 p = pc.positions[i];
        const double D2 = double(p.x) * p.x + double(p.y) * p.y + 4.0;
        const double F = 2.0 / (D2 * std::sqrt(D2));
        const double eo = occ->data[i] - F;
        r.occ_rms += eo * eo;
        r.occ_mean_error += eo;
        const double expected = envmap.empty() ? c * F : 1.0 - F + c * F;
        const double ei = ind->data[3 * i] - expected;
        r.ind_rms += ei * ei;
    }
    r.occ_rms = std::sqrt(r.occ_rms / pc.size());
    r.ind_rms = std::sqrt(r.ind_rms / pc.size());
    r.occ_mean_error /= pc.size();
    return r;
}

} // namespace

TEST(BakeGi, OcclusionOfAPlaneUnderASphereIsItsFormFactor) {
    const PlaneResult r = bake_plane(256);
    ASSERT_GT(r.points, 1000u);
    // Stratified cosine sampling: the error per point is a few 1e-3.
    EXPECT_LT(r.occ_rms, 0.01);
    EXPECT_LT(std::abs(r.occ_mean_error), 0.002);
    // Without an environment only the sphere's light (c F) arrives.
    EXPECT_LT(r.ind_rms, 0.01 * 0.25 + 0.003);
}

TEST(BakeGi, NoiseFallsAsSamplesRise) {
    const double e16 = bake_plane(16).occ_rms;
    const PlaneResult p64 = bake_plane(64);
    const double e64 = p64.occ_rms;
    const double e256 = bake_plane(256).occ_rms;
    std::printf(
        "occlusion RMS error per point: 16 rays %.5f, 64 rays %.5f, 256 rays %.5f\n", e16,
        e64, e256);
    // Adaptive sampling stops after a quarter of the rays when they all
    // agree: faster, but it misses small occluders (documented).
    const PlaneResult a64 = bake_plane(64, "", 0.25, true);
    std::printf(
        "64 rays: mean error %.5f; adaptive, 64 rays: RMS %.5f, mean error %.5f\n",
        p64.occ_mean_error, a64.occ_rms, a64.occ_mean_error);
    EXPECT_LT(e64, e16 / 1.5);
    // 16 times the samples: at least the Monte Carlo rate (4x less noise)
    // less a margin; stratification does better.
    EXPECT_LT(e256, e16 / 3.0);
}

TEST(BakeGi, IndirectDiffuseSeesTheEnvironmentAndTheLitSphere) {
    sss::test::TempDir dir;
    const std::string white = dir.file("white.exr");
    const std::string cmd =
        "oiiotool --pattern constant:color=1,1,1 32x16 3 -d half -o '" + white +
        "' >/dev/null 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << "oiiotool is needed (openimageio-tools)";
    const PlaneResult r = bake_plane(256, white, 0.25);
    EXPECT_LT(r.ind_rms, 0.01);
}

TEST(BakeGi, FurnaceConvergesToTheGeometricSeries) {
    // Inside a closed sphere every ray hits the wall, whose radiance is the
    // same everywhere: with D diffuse bounces L = Ke (1 - Kd^(D+1)) / (1 - Kd).
    for (int depth : {1, 3}) {
        sss::test::TempDir dir;
        sss::test::write_text(dir.file("furnace.sl"), kFurnaceShader);
        const std::string cloud = dir.file("furnace.ptc");
        const sss::Scene scene =
            scene_in(dir, "",
                     "Attribute \"trace\" \"maxdiffusedepth\" " + std::to_string(depth) +
                         "\nSurface \"furnace\" \"string filename\" [\"" + cloud +
                         "\"] \"float Kd\" 0.5\nSphere 1 -1 1 360\n");
        sss::BakeOptions opt;
        opt.spacing = 0.25;
        const auto files = sss::bake_clouds(scene, opt, nullptr);
        ASSERT_EQ(files.size(), 1u);
        const sss::PointCloud& pc = files[0].second;
        const sss::Channel* L = pc.find_channel("L");
        ASSERT_TRUE(L);
        const double expected = (1.0 - std::pow(0.5, depth + 1)) / 0.5;
        double worst = 0.0;
        for (std::size_t i = 0; i < pc.size(); ++i)
            worst = std::max(worst, std::abs(L->data[3 * i] - expected));
        EXPECT_LT(worst, 1e-3) << "maxdiffusedepth " << depth;
    }
}

namespace {

/// Bakes diffuse(N) over a unit sphere lit by `lights` (RIB), alone in the
/// scene; returns the baked values (RGB per point).
std::vector<float> bake_sphere_diffuse(const sss::test::TempDir& dir,
                                       const std::string& lights) {
    sss::test::write_text(dir.file("bake_diffuse.sl"), R"(
surface bake_diffuse(string filename = "") {
    normal Nn = normalize(N);
    color d = diffuse(Nn);
    bake3d(filename, "d", P, Nn, "d", d);
    Ci = d;
}
)");
    const std::string cloud = dir.file("d.ptc");
    const sss::Scene scene = scene_in(
        dir,
        "Option \"searchpath\" \"string archive\" [\"" + dir.path().string() + "\"]\n",
        lights + "Surface \"bake_diffuse\" \"string filename\" [\"" + cloud +
            "\"]\nSphere 1 -1 1 360\n");
    sss::BakeOptions opt;
    opt.spacing = 0.2;
    const auto files = sss::bake_clouds(scene, opt, nullptr);
    const sss::Channel* d = files.at(0).second.find_channel("d");
    return d ? d->data : std::vector<float>{};
}

std::string bin_dir() {
    const char* b = std::getenv("SSS_BIN_DIR");
    return b ? b : "";
}

} // namespace

TEST(BakeGi, EnvlightWithAWhiteMapGivesOne) {
    sss::test::TempDir dir;
    const std::string white = dir.file("white.exr");
    const std::string cmd =
        "oiiotool --pattern constant:color=1,1,1 32x16 3 -d half -o '" + white +
        "' >/dev/null 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << "oiiotool is needed (openimageio-tools)";
    const std::vector<float> d =
        bake_sphere_diffuse(dir, "LightSource \"envlight\" 1 \"string envmap\" [\"" +
                                     white + "\"] \"float samples\" [64]\n");
    ASSERT_GT(d.size(), 300u);
    for (float v : d) ASSERT_NEAR(v, 1.0f, 1e-3f);
}

TEST(BakeGi, EnvlightAndTheEnvdomeDomeAgree) {
    // The same probe (envdome's sky, brought down to 16 x 8 pixels so that
    // ray sampling of the sun is not too noisy) as envlight and as a dome of
    // 256 lights: diffuse(N) over a sphere agrees within a few per cent.
    const std::string bin = bin_dir();
    ASSERT_FALSE(bin.empty()) << "SSS_BIN_DIR names the tools";
    sss::test::TempDir dir;
    const std::string sky = dir.file("sky.exr"), small = dir.file("small.exr");
    const std::string cmd =
        "'" + bin + "/envdome' -sky 128 64 '" + sky + "' >/dev/null && oiiotool '" + sky +
        "' --resize:filter=box 16x8 -o '" + small + "' >/dev/null && '" + bin +
        "/envdome' -n 256 '" + small + "' '" + dir.file("dome.rib") + "' >/dev/null";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    const std::vector<float> env =
        bake_sphere_diffuse(dir, "LightSource \"envlight\" 1 \"string envmap\" [\"" +
                                     small + "\"] \"float samples\" [1024]\n");
    const std::vector<float> dome =
        bake_sphere_diffuse(dir, "ReadArchive \"dome.rib\"\n");
    ASSERT_EQ(env.size(), dome.size());
    ASSERT_GT(env.size(), 300u);
    double sum_e = 0.0, sum_d = 0.0, err2 = 0.0, ref2 = 0.0;
    for (std::size_t i = 0; i < env.size(); ++i) {
        sum_e += env[i];
        sum_d += dome[i];
        err2 += (env[i] - dome[i]) * (env[i] - dome[i]);
        ref2 += dome[i] * dome[i];
    }
    std::printf("envlight / dome: mean ratio %.4f, relative RMS difference %.4f\n",
                sum_e / sum_d, std::sqrt(err2 / ref2));
    EXPECT_NEAR(sum_e / sum_d, 1.0, 0.03);
    EXPECT_LT(std::sqrt(err2 / ref2), 0.08);
}

TEST(BakeGi, TraceBiasMovesTheRayOrigins) {
    // Attribute "trace" "bias" 3.5 on the plane: its rays start above the
    // sphere (which spans heights 1 to 3), so nothing occludes them.
    sss::test::TempDir dir;
    sss::test::write_text(dir.file("bake_gi_plane.sl"), kPlaneShader);
    const std::string cloud = dir.file("plane.ptc");
    const sss::Scene scene = scene_in(
        dir, "",
        "AttributeBegin\nAttribute \"trace\" \"bias\" [3.5]\n"
        "Surface \"bake_gi_plane\" \"string filename\" [\"" +
            cloud +
            "\"]\nPolygon \"P\" [-1 -1 0  1 -1 0  1 1 0  -1 1 0]\nAttributeEnd\n"
            "AttributeBegin\nTranslate 0 0 2\nSurface \"constant\"\nSphere 1 -1 1 360\n"
            "AttributeEnd\n");
    sss::BakeOptions opt;
    opt.spacing = 0.2;
    const auto files = sss::bake_clouds(scene, opt, nullptr);
    const sss::Channel* occ = files.at(0).second.find_channel("occ");
    ASSERT_TRUE(occ);
    ASSERT_GT(occ->data.size(), 50u);
    for (float v : occ->data) EXPECT_EQ(v, 0.0f);
}

TEST(BakeGi, WhiteFurnaceBakesOneEverywhere) {
    // White surfaces (Ci = indirectdiffuse) under a white environment: the
    // light is 1 everywhere, at every bounce (a ray cut off by the depth
    // limit sees the white environment, which is what the surfaces it would
    // have hit send too). Any energy lost or gained in the hit shading shows.
    sss::test::TempDir dir;
    const std::string white = dir.file("white.exr");
    const std::string cmd =
        "oiiotool --pattern constant:color=1,1,1 32x16 3 -d half -o '" + white +
        "' >/dev/null 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << "oiiotool is needed (openimageio-tools)";
    sss::test::write_text(dir.file("white_gi.sl"), R"(
surface white_gi(string filename = ""; string envmap = ""; float up = 0) {
    normal Nn = normalize(N);
    if (up != 0) {
        Nn = normalize(ntransform("world", Nn));
        if (zcomp(Nn) < 0) Nn = -Nn;
        Nn = ntransform("world", "current", Nn);
    }
    Ci = indirectdiffuse(P, Nn, 16, "environmentmap", envmap);
    float depth = 0;
    rayinfo("depth", depth);
    if (depth == 0) bake3d(filename, "L", P, Nn, "L", Ci);
}
)");
    const std::string cloud = dir.file("white.ptc");
    const std::string args =
        " \"string filename\" [\"" + cloud + "\"] \"string envmap\" [\"" + white + "\"]";
    const sss::Scene scene = scene_in(
        dir, "",
        "Attribute \"trace\" \"maxdiffusedepth\" [2]\n"
        "AttributeBegin\nSurface \"white_gi\"" +
            args +
            " \"float up\" [1]\nPolygon \"P\" [-2 -2 0  2 -2 0  2 2 0  -2 2 0]\n"
            "AttributeEnd\nAttributeBegin\nTranslate 0 0 1.2\nSurface \"white_gi\"" +
            args + "\nSphere 1 -1 1 360\nAttributeEnd\n");
    sss::BakeOptions opt;
    opt.spacing = 0.25;
    const auto files = sss::bake_clouds(scene, opt, nullptr);
    ASSERT_EQ(files.size(), 1u);
    const sss::Channel* L = files[0].second.find_channel("L");
    ASSERT_TRUE(L);
    ASSERT_GT(L->data.size(), 300u);
    double worst = 0.0;
    for (float v : L->data) worst = std::max(worst, std::abs(double(v) - 1.0));
    EXPECT_LT(worst, 1e-3);
}
