// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// Scene-scale invariance at library level (docs/scene.md, "Scene scale"): the
// same scene scaled by s -- geometry, camera and lights -- bakes to points at
// s x the positions with the same irradiance, diffuses (unitlength x s) to the
// same _ssdiffusion, builds a brick map that looks up the same values, and
// renders the same picture. Power-of-two scales must give bit-identical
// values (no absolute length anywhere in the chain); other scales agree to
// rounding. tests/cli/test_scale.sh runs the tools on the same idea.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "sss/bake/bake.h"
#include "sss/brick/brickmap.h"
#include "sss/diffusion/ssdiffusion.h"
#include "sss/render/render.h"
#include "sss/scene/rib.h"
#include "test_util.h"

namespace {

constexpr double kUnitLength = 0.1; // at s = 1 the scene is in cm

std::string num(double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
}

/// A marble sphere and a torus on a plate, lit by a shadowed distant light
/// and a shadowed point light (intensity x s^2: irradiance falls off as
/// 1/d^2), everything scaled by s. `surface` is the objects' Surface line.
sss::Scene scene_at(double s, const std::string& surface) {
    const std::string object = "AttributeBegin\n" + surface + "\n";
    std::string rib = "Format 64 48 1\nPixelSamples 2 2\n"
                      "Projection \"perspective\" \"fov\" 40\nShadingRate 4\n";
    rib += "Translate 0 0 " + num(6.0 * s) + "\nRotate -25 1 0 0\nWorldBegin\n";
    rib += "Scale " + num(s) + " " + num(s) + " " + num(s) + "\n";
    rib += "LightSource \"ambientlight\" 1 \"intensity\" [0.05]\n";
    rib += "LightSource \"distantlight\" 2 \"from\" [-2 3 -1] \"to\" [0 0 0]"
           " \"intensity\" [0.8] \"string shadowname\" [\"raytrace\"]\n";
    rib += "LightSource \"pointlight\" 3 \"from\" [1.5 2.5 2] \"intensity\" [" +
           num(6.0 * s * s) + "] \"string shadowname\" [\"raytrace\"]\n";
    rib += object + "Sphere 1 -1 1 360\nAttributeEnd\n";
    rib += object + "Translate 1.6 -0.55 0.2\nRotate 70 1 0 0\nTorus 0.4 0.1 0 360 360\n"
                    "AttributeEnd\n";
    rib += object + "Polygon \"P\" [-3 -1 -2.5  -3 -1 2.5  3 -1 2.5  3 -1 -2.5]\n"
                    "AttributeEnd\n";
    rib += "WorldEnd\n";
    return sss::parse_rib(rib, "scale.rib");
}

const char* kBake = "Surface \"bake_radiance_t\" \"string filename\" [\"b.ptc\"]";

sss::PointCloud bake_at(double s, double spacing = 0.0) {
    sss::BakeOptions opt;
    opt.spacing = spacing * s;
    auto files = sss::bake_clouds(scene_at(s, kBake), opt, nullptr);
    EXPECT_EQ(files.size(), 1u);
    return files.empty() ? sss::PointCloud{} : files[0].second;
}

sss::PointCloud diffuse_at(const sss::PointCloud& baked, double s) {
    sss::SsDiffusionOptions opt;
    opt.material.unitlength = kUnitLength * s;
    return sss::ssdiffusion(baked, opt);
}

/// The cloud of s = 1 scaled by s (positions, radii, areas), values kept.
sss::PointCloud scaled(const sss::PointCloud& c, double s) {
    sss::PointCloud out = c;
    for (auto& p : out.positions) p = glm::vec3(glm::dvec3(p) * s);
    for (auto& r : out.radii) r = float(r * s);
    if (sss::Channel* a = out.find_channel("_area"))
        for (float& v : a->data) v = float(v * s * s);
    return out;
}

/// Largest difference of a channel between two clouds, relative to the mean
/// magnitude of the first.
double channel_difference(const sss::PointCloud& a, const sss::PointCloud& b,
                          const std::string& name) {
    const sss::Channel* ca = a.find_channel(name);
    const sss::Channel* cb = b.find_channel(name);
    if (!ca || !cb || ca->data.size() != cb->data.size()) return INFINITY;
    double mean = 0.0, worst = 0.0;
    for (float v : ca->data) mean += std::abs(v);
    mean /= double(ca->data.size());
    for (std::size_t i = 0; i < ca->data.size(); ++i) {
        if (!std::isfinite(cb->data[i])) return INFINITY;
        worst = std::max(worst, std::abs(double(cb->data[i]) - ca->data[i]) / mean);
    }
    return worst;
}

/// Largest |b - s a| over the positions, relative to s x the extent of a.
double position_difference(const sss::PointCloud& a, const sss::PointCloud& b, double s) {
    glm::dvec3 lo(INFINITY), hi(-INFINITY);
    for (const auto& p : a.positions) {
        lo = glm::min(lo, glm::dvec3(p));
        hi = glm::max(hi, glm::dvec3(p));
    }
    const double size = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
    double worst = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i)
        for (int k = 0; k < 3; ++k)
            worst = std::max(worst, std::abs(double(b.positions[i][k]) -
                                             s * double(a.positions[i][k])));
    return worst / (s * size);
}

} // namespace

// Baking: the same micropolygons (ShadingRate dicing at the surface's
// distance, and -spacing L*s) at s x the positions, with the same irradiance.
// Shadow-ray offsets and dicing are relative to the scene: nothing changes.
TEST(SceneScale, BakeGivesScaledPointsAndEqualIrradiance) {
    for (double spacing : {0.0, 0.08}) {
        const sss::PointCloud ref = bake_at(1.0, spacing);
        ASSERT_GT(ref.size(), 1000u);
        for (double s : {1e-6, 1e-4, 1e4, 1e6}) {
            SCOPED_TRACE("spacing " + num(spacing) + " s " + num(s));
            const sss::PointCloud c = bake_at(s, spacing);
            ASSERT_EQ(c.size(), ref.size());
            EXPECT_LT(position_difference(ref, c, s), 1e-6);
            const sss::PointCloud expect = scaled(ref, s);
            EXPECT_LT(channel_difference(expect, c, "_area"), 1e-5);
            EXPECT_LT(channel_difference(ref, c, "_radiance_t"), 1e-5);
        }
    }
}

// Diffusion: ptfilter's -unitlength follows the scene, so the profile in scene
// units scales with it and sum R A E does not change. The evaluation is done
// in mm: in scene units its float tables overflowed or underflowed for very
// small or very large material lengths (all values wrong by up to 200 % at
// unitlength 1e-8 or 1e6, and differing by up to 8e-4 from tree decisions
// that rounding flipped at every other scale).
TEST(SceneScale, DiffusionIsTheSameAtEveryScale) {
    const sss::PointCloud baked = bake_at(1.0);
    const sss::PointCloud ref = diffuse_at(baked, 1.0);
    sss::SsDiffusionOptions exact_opt;
    exact_opt.exact = true;
    exact_opt.material.unitlength = kUnitLength;
    const sss::PointCloud ref_exact = sss::ssdiffusion(baked, exact_opt);
    for (double s : {1e-7, 1e-4, 1e-2, 3.0, 1e4, 1e7}) {
        SCOPED_TRACE("s " + num(s));
        const sss::PointCloud in = scaled(baked, s);
        const sss::PointCloud out = diffuse_at(in, s);
        ASSERT_EQ(out.size(), ref.size());
        EXPECT_LT(channel_difference(ref, out, "_ssdiffusion"), 1e-4);
        if (s != 1e-7 && s != 1e7) continue; // the all-pairs sum is slow
        exact_opt.material.unitlength = kUnitLength * s;
        EXPECT_LT(channel_difference(ref_exact, sss::ssdiffusion(in, exact_opt),
                                     "_ssdiffusion"),
                  1e-5);
    }
}

// Per-point materials (-diffusemeanfreepath fromfile, in mm) follow
// -unitlength the same way.
TEST(SceneScale, PerPointMaterialDiffusionIsTheSameAtEveryScale) {
    sss::PointCloud baked = bake_at(1.0);
    sss::Channel& dmfp =
        baked.add_channel("_diffusemeanfreepath", sss::ChannelType::Color);
    dmfp.data.resize(3 * baked.size());
    for (std::size_t i = 0; i < baked.size(); ++i)
        for (int c = 0; c < 3; ++c)
            dmfp.data[3 * i + c] =
                float(2.0 + 4.0 * c + (baked.positions[i].x > 0 ? 3 : 0));
    sss::SsDiffusionOptions opt;
    opt.material.dmfp_from_file = true;
    opt.material.unitlength = kUnitLength;
    const sss::PointCloud ref = sss::ssdiffusion(baked, opt);
    for (double s : {1e-7, 1e7}) {
        SCOPED_TRACE("s " + num(s));
        opt.material.unitlength = kUnitLength * s;
        EXPECT_LT(channel_difference(ref, sss::ssdiffusion(scaled(baked, s), opt),
                                     "_ssdiffusion"),
                  1e-4);
    }
}

// Power-of-two scales change only exponents: with no absolute length in the
// chain, bake, diffusion, brick map and render give bit-identical values.
TEST(SceneScale, PowerOfTwoScalesAreBitIdentical) {
    sss::test::TempDir dir("sss_scale");
    std::vector<float> ref_pixels, ref_lookups;
    sss::PointCloud ref_ssd;
    for (double s : {1.0, std::ldexp(1.0, -20), std::ldexp(1.0, 20)}) {
        SCOPED_TRACE("s " + num(s));
        const sss::PointCloud baked = bake_at(s);
        const sss::PointCloud ssd = diffuse_at(baked, s);
        // Built with += (g++ 12 warns falsely, -Wrestrict, on "x" + string).
        std::string name = "s";
        name += num(std::log2(s));
        name += ".bkm";
        const std::string bkm = dir.file(name);
        sss::build_brick_map({ssd}, sss::BrickMapBuildOptions{}, bkm);
        const sss::BrickMap map(bkm);
        std::vector<float> lookups(3 * ssd.size());
        for (std::size_t i = 0; i < ssd.size(); i += 7)
            map.lookup(ssd.positions[i], ssd.normals[i], 0.0f, &lookups[3 * i]);
        sss::Scene scene = scene_at(
            s, "Surface \"read_ssdiffusion\" \"string filename\" [\"" + bkm +
                   "\"] \"float Ka\" [1] \"float Kd\" [0.1] \"float occlusion_samples\" "
                   "[4] \"float occlusion_maxdist\" [" +
                   num(1.5 * s) + "]");
        const sss::Image img = sss::render_image(scene, sss::RenderJobOptions{}, nullptr);
        if (s == 1.0) {
            ref_ssd = ssd;
            ref_lookups = lookups;
            ref_pixels = img.pixels;
            double sum = 0.0;
            for (float v : img.pixels) sum += v;
            EXPECT_GT(sum, 100.0); // a picture, not a black frame
            continue;
        }
        ASSERT_EQ(ssd.size(), ref_ssd.size());
        EXPECT_EQ(position_difference(ref_ssd, ssd, s), 0.0);
        EXPECT_EQ(channel_difference(ref_ssd, ssd, "_ssdiffusion"), 0.0);
        EXPECT_EQ(lookups, ref_lookups);
        // Depth (Z) is a length: s x that of s = 1; every other channel equal.
        ASSERT_EQ(img.pixels.size(), ref_pixels.size());
        const int z = img.channel_index("Z");
        const int nch = img.channel_count();
        std::size_t differ = 0;
        for (std::size_t i = 0; i < ref_pixels.size(); ++i) {
            const bool depth = int(i % nch) == z;
            const float expect = depth ? float(ref_pixels[i] * s) : ref_pixels[i];
            differ += img.pixels[i] != expect;
        }
        EXPECT_EQ(differ, 0u);
    }
}
