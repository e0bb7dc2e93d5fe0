// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// ptbake's library side: bake shaders, files, spacing, shadows, determinism.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numeric>

#include <glm/geometric.hpp>

#include "sss/bake/bake.h"
#include "sss/scene/rib.h"
#include "sss/util/error.h"
#include "sss/util/threads.h"

namespace {

const double kPi = 3.14159265358979323846;

sss::Scene scene_of(const std::string& world, const std::string& options = "") {
    return sss::parse_rib("Format 200 200 1\nProjection \"perspective\" \"fov\" 40\n" +
                              options + "Translate 0 0 6\nWorldBegin\n" + world +
                              "WorldEnd\n",
                          "test.rib");
}

std::vector<std::pair<std::string, sss::PointCloud>>
bake(const sss::Scene& scene, sss::BakeOptions opt = {},
     sss::BakeReport* report = nullptr) {
    return sss::bake_clouds(scene, opt, report);
}

double sum_area(const sss::PointCloud& c) {
    const sss::Channel* a = c.find_channel("_area");
    return std::accumulate(a->data.begin(), a->data.end(), 0.0);
}

const std::string kSphere =
    "LightSource \"distantlight\" 1 \"from\" [0 1 0] \"to\" [0 0 0] \"intensity\" [2]\n"
    "Surface \"bake_radiance_t\" \"string filename\" [\"s.ptc\"]\n"
    "Sphere 1 -1 1 360\n";

} // namespace

TEST(Bake, SphereUnderDistantLightMatchesAnalyticValues) {
    sss::BakeOptions opt;
    opt.spacing = 0.04;
    auto files = bake(scene_of(kSphere), opt);
    ASSERT_EQ(files.size(), 1u);
    EXPECT_EQ(files[0].first, "s.ptc");
    const sss::PointCloud& c = files[0].second;
    ASSERT_GT(c.size(), 5000u);
    EXPECT_NEAR(sum_area(c), 4.0 * kPi, 4.0 * kPi * 0.005);
    const sss::Channel* r = c.find_channel("_radiance_t");
    ASSERT_NE(r, nullptr);
    EXPECT_EQ(r->type, sss::ChannelType::Color);
    double worst = 0.0;
    for (std::size_t i = 0; i < c.size(); ++i) {
        glm::dvec3 n = glm::normalize(glm::dvec3(c.positions[i]));
        EXPECT_GT(glm::dot(glm::dvec3(c.normals[i]), n), 0.99);
        double expect = 2.0 * std::max(0.0, n.y);
        worst = std::max(worst, std::abs(r->data[3 * i] - expect));
    }
    EXPECT_LT(worst, 0.01);
}

TEST(Bake, PointBehindAnOccluderGetsNoDirectLight) {
    // A plate at y = 0 lit from above; a square blocker above its centre.
    const std::string world =
        "LightSource \"pointlight\" 1 \"from\" [0 5 0] \"intensity\" [25]\n"
        "  \"string shadowname\" [\"raytrace\"]\n"
        "AttributeBegin\n"
        "Surface \"bake_radiance_t\" \"string filename\" [\"p.ptc\"]\n"
        "Polygon \"P\" [-2 0 -2  -2 0 2  2 0 2  2 0 -2]\n"
        "AttributeEnd\n"
        "Surface \"matte\"\n"
        "Polygon \"P\" [-0.5 1 -0.5  -0.5 1 0.5  0.5 1 0.5  0.5 1 -0.5]\n";
    sss::BakeOptions opt;
    opt.spacing = 0.05;
    sss::BakeReport report;
    auto files = bake(scene_of(world), opt, &report);
    ASSERT_EQ(files.size(), 1u);
    EXPECT_EQ(report.occluder_primitives, 1u);
    const sss::PointCloud& c = files[0].second;
    const sss::Channel* r = c.find_channel("_radiance_t");
    int shadowed = 0, lit = 0;
    for (std::size_t i = 0; i < c.size(); ++i) {
        glm::vec3 p = c.positions[i];
        ASSERT_GT(c.normals[i].y, 0.99f) << "plate normal faces the light";
        double d2 = p.x * p.x + p.z * p.z + 25.0;
        double unshadowed = 25.0 * (5.0 / std::sqrt(d2)) / d2;
        if (std::abs(p.x) < 0.3 && std::abs(p.z) < 0.3) {
            EXPECT_EQ(r->data[3 * i], 0.0f);
            ++shadowed;
        } else if (std::abs(p.x) > 0.8 || std::abs(p.z) > 0.8) {
            EXPECT_NEAR(r->data[3 * i], unshadowed, 1e-4 * unshadowed);
            ++lit;
        }
    }
    EXPECT_GT(shadowed, 50);
    EXPECT_GT(lit, 500);
}

TEST(Bake, ObjectsShareOrSplitFilesAndOptionOOverrides) {
    const std::string world =
        "LightSource \"ambientlight\" 1 \"intensity\" [0.5]\n"
        "AttributeBegin\n"
        "Surface \"bake_radiance_t\" \"string filename\" [\"a.ptc\"]\n"
        "Sphere 1 -1 1 360\n"
        "AttributeEnd\n"
        "AttributeBegin\n"
        "Translate 3 0 0\n"
        "Surface \"bake_radiance_t\" \"string filename\" [\"b.%04d.ptc\"]\n"
        "Sphere 0.5 -0.5 0.5 360\n"
        "AttributeEnd\n"
        "AttributeBegin\n"
        "Translate -3 0 0\n"
        "Surface \"bake_radiance_t\" \"string filename\" [\"a.ptc\"]\n"
        "Sphere 0.5 -0.5 0.5 360\n"
        "AttributeEnd\n";
    sss::BakeOptions opt;
    opt.spacing = 0.1;
    opt.frame = 12;
    // The files are known before baking (-newer 1), in the same order.
    EXPECT_EQ(sss::bake_output_files(scene_of(world), opt),
              (std::vector<std::string>{"a.ptc", "b.0012.ptc"}));
    auto files = bake(scene_of(world), opt);
    ASSERT_EQ(files.size(), 2u);
    EXPECT_EQ(files[0].first, "a.ptc");
    EXPECT_EQ(files[1].first, "b.0012.ptc");
    EXPECT_NEAR(sum_area(files[0].second), 5.0 * kPi, 5.0 * kPi * 0.01);
    EXPECT_NEAR(sum_area(files[1].second), kPi, kPi * 0.01);
    const sss::Channel* r = files[0].second.find_channel("_radiance_t");
    for (float v : r->data) EXPECT_FLOAT_EQ(v, 0.5f);

    opt.output = "all.ptc";
    EXPECT_EQ(sss::bake_output_files(scene_of(world), opt),
              std::vector<std::string>{"all.ptc"});
    files = bake(scene_of(world), opt);
    ASSERT_EQ(files.size(), 1u);
    EXPECT_EQ(files[0].first, "all.ptc");
    EXPECT_NEAR(sum_area(files[0].second), 6.0 * kPi, 6.0 * kPi * 0.01);

    // A frame pattern without a frame number is a usage error.
    opt.output.clear();
    opt.frame.reset();
    EXPECT_THROW(bake(scene_of(world), opt), sss::UsageError);
    EXPECT_THROW(sss::bake_output_files(scene_of(world), opt), sss::UsageError);
}

TEST(Bake, ConstantBakesNegativeColourIntoTheSharedFile) {
    const std::string world =
        "LightSource \"distantlight\" 1 \"from\" [0 1 0] \"to\" [0 0 0]\n"
        "AttributeBegin\n"
        "Surface \"bake_radiance_t\" \"string filename\" [\"box.ptc\"]\n"
        "Sphere 2 -2 2 360\n"
        "AttributeEnd\n"
        "AttributeBegin\n"
        "Color [-1 -0.5 -0.25]\n"
        "Surface \"bake_constant\" \"string filename\" [\"box.ptc\"]\n"
        "Sphere 0.5 -0.5 0.5 360\n"
        "AttributeEnd\n";
    sss::BakeOptions opt;
    opt.spacing = 0.1;
    sss::BakeReport report;
    auto files = bake(scene_of(world), opt, &report);
    ASSERT_EQ(files.size(), 1u);
    const sss::PointCloud& c = files[0].second;
    const sss::Channel* r = c.find_channel("_radiance_t");
    std::size_t negative = 0;
    for (std::size_t i = 0; i < c.size(); ++i) {
        if (glm::length(c.positions[i]) < 0.6f) {
            EXPECT_FLOAT_EQ(r->data[3 * i + 0], -1.0f);
            EXPECT_FLOAT_EQ(r->data[3 * i + 1], -0.5f);
            EXPECT_FLOAT_EQ(r->data[3 * i + 2], -0.25f);
            ++negative;
        } else {
            EXPECT_GE(r->data[3 * i], 0.0f);
        }
    }
    EXPECT_GT(negative, 100u);
    EXPECT_EQ(report.files.at(0).objects.size(), 2u);
}

TEST(Bake, SssParamsBakesMaterialChannelsWithNoise) {
    const std::string world =
        "LightSource \"ambientlight\" 1\n"
        "Surface \"bake_sss_params\" \"string filename\" [\"m.ptc\"]\n"
        "  \"color albedo\" [0.2 0.3 0.4] \"color albedo2\" [0.6 0.7 0.8]\n"
        "  \"color dmfp\" [1 2 3] \"color dmfp2\" [2 4 6] \"float noisefreq\" [3]\n"
        "Sphere 1 -1 1 360\n";
    sss::BakeOptions opt;
    opt.spacing = 0.05;
    auto files = bake(scene_of(world), opt);
    const sss::PointCloud& c = files.at(0).second;
    const sss::Channel* a = c.find_channel("_albedo");
    const sss::Channel* d = c.find_channel("_diffusemeanfreepath");
    ASSERT_NE(a, nullptr);
    ASSERT_NE(d, nullptr);
    ASSERT_NE(c.find_channel("_radiance_t"), nullptr);
    float lo = 1, hi = 0;
    for (std::size_t i = 0; i < c.size(); ++i) {
        float t = (a->data[3 * i] - 0.2f) / 0.4f; // blend factor from red albedo
        ASSERT_GE(t, -1e-4f);
        ASSERT_LE(t, 1.0001f);
        EXPECT_NEAR(a->data[3 * i + 2], 0.4f + 0.4f * t, 1e-4f);
        EXPECT_NEAR(d->data[3 * i + 1], 2.0f + 2.0f * t, 1e-3f);
        lo = std::min(lo, t);
        hi = std::max(hi, t);
    }
    EXPECT_GT(hi - lo, 0.3f) << "the noise must vary over the sphere";
}

TEST(Bake, SpacingFromMaterialAndTheCoarseSpacingWarning) {
    sss::MaterialSpec skin;
    skin.preset = "skin1";
    skin.unitlength = 1.0; // mm
    const double mfp = sss::material_mean_free_path(skin);
    EXPECT_NEAR(mfp, 1.0 / (1.01 + 0.48), 0.01); // blue channel of skin1
    sss::BakeOptions opt;
    opt.material = skin;
    opt.spacing = 4.0 * mfp;
    sss::BakeReport report;
    const std::string world =
        "LightSource \"ambientlight\" 1\n"
        "Surface \"bake_radiance_t\" \"string filename\" [\"s.ptc\"]\n"
        "Sphere 10 -10 10 360\n";
    bake(scene_of(world), opt, &report);
    bool warned = false;
    for (const std::string& w : report.warnings)
        warned = warned || w.find("mean free path") != std::string::npos;
    EXPECT_TRUE(warned);

    opt.spacing = 0.0;
    opt.spacing_from_material = true;
    report = {};
    auto files = bake(scene_of(world), opt, &report);
    for (const std::string& w : report.warnings)
        EXPECT_EQ(w.find("mean free path"), std::string::npos) << w;
    EXPECT_LE(report.max_spacing, mfp * 1.0001);
    EXPECT_GT(report.max_spacing, mfp * 0.5);
}

TEST(Bake, ShadingRateDicesFartherObjectsCoarser) {
    const std::string world =
        "LightSource \"ambientlight\" 1\n"
        "Surface \"bake_radiance_t\" \"string filename\" [\"near.ptc\"]\n"
        "Sphere 0.5 -0.5 0.5 360\n"
        "AttributeBegin\n"
        "Translate 0 0 12\n"
        "Surface \"bake_radiance_t\" \"string filename\" [\"far.ptc\"]\n"
        "Sphere 0.5 -0.5 0.5 360\n"
        "AttributeEnd\n";
    auto files = bake(scene_of(world, "ShadingRate 2\n"));
    ASSERT_EQ(files.size(), 2u);
    // Eye distances 6 and 18: 3x the pixel size, 9x fewer points.
    double ratio = double(files[0].second.size()) / double(files[1].second.size());
    EXPECT_GT(ratio, 5.0);
    EXPECT_LT(ratio, 14.0);
    EXPECT_NEAR(sum_area(files[1].second), kPi, kPi * 0.01);
}

TEST(Bake, OutputDoesNotDependOnTheThreadCount) {
    const std::string world =
        "LightSource \"pointlight_rts\" 1 \"from\" [1 3 -2] \"intensity\" [10]\n"
        "  \"samples\" [8] \"radius\" [0.3]\n"
        "Surface \"bake_radiance_t\" \"string filename\" [\"t.ptc\"]\n"
        "Torus 1 0.3 0 360 360\n"
        "Sphere 0.4 -0.4 0.4 360\n";
    sss::BakeOptions opt;
    opt.spacing = 0.03;
    std::vector<float> one, two;
    {
        sss::ThreadLimit limit(1);
        one = bake(scene_of(world), opt).at(0).second.find_channel("_radiance_t")->data;
    }
    {
        sss::ThreadLimit limit(2);
        two = bake(scene_of(world), opt).at(0).second.find_channel("_radiance_t")->data;
    }
    ASSERT_EQ(one.size(), two.size());
    EXPECT_TRUE(one == two);
}

TEST(Bake, ClearErrors) {
    sss::BakeOptions opt;
    opt.spacing = 0.1;
    // Nothing to bake.
    EXPECT_THROW(bake(scene_of("Surface \"matte\"\nSphere 1 -1 1 360\n"), opt),
                 sss::ValueError);
    // No file name.
    try {
        bake(scene_of("Surface \"bake_radiance_t\"\nSphere 1 -1 1 360\n"), opt);
        FAIL();
    } catch (const sss::ValueError& e) {
        EXPECT_NE(std::string(e.what()).find("test.rib:"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("filename"), std::string::npos);
    }
    // A channel the shader does not make.
    EXPECT_THROW(
        bake(scene_of("Surface \"bake_radiance_t\" \"string filename\" [\"x.ptc\"]"
                      " \"string displaychannels\" [\"_foo\"]\n"
                      "Sphere 1 -1 1 360\n"),
             opt),
        sss::ValueError);
    // Impossible albedo.
    EXPECT_THROW(
        bake(scene_of("Surface \"bake_sss_params\" \"string filename\" [\"x.ptc\"]"
                      " \"color albedo\" [1.5 0.5 0.5]\nSphere 1 -1 1 360\n"),
             opt),
        sss::ValueError);
}

TEST(Bake, CurvedSurfacesDoNotShadowThemselves) {
    // A convex sphere: every point facing a shadowed light is fully lit, at
    // coarse and fine dicing (the traced triangles are chords inside it).
    for (double spacing : {0.2, 0.05}) {
        const std::string world =
            "LightSource \"distantlight\" 1 \"from\" [1 2 -3] \"to\" [0 0 0]\n"
            "  \"string shadowname\" [\"raytrace\"]\n"
            "Surface \"bake_radiance_t\" \"string filename\" [\"s.ptc\"]\n"
            "Sphere 1 -1 1 360\n";
        sss::BakeOptions opt;
        opt.spacing = spacing;
        auto files = bake(scene_of(world), opt);
        const sss::PointCloud& c = files.at(0).second;
        const sss::Channel* r = c.find_channel("_radiance_t");
        const glm::dvec3 l = glm::normalize(glm::dvec3(1, 2, -3));
        std::size_t wrong = 0;
        for (std::size_t i = 0; i < c.size(); ++i) {
            double expect = std::max(0.0, glm::dot(glm::dvec3(c.normals[i]), l));
            if (std::abs(r->data[3 * i] - expect) > 1e-5) ++wrong;
        }
        EXPECT_EQ(wrong, 0u) << "spacing " << spacing << ", " << c.size() << " points";
    }
}

TEST(Bake, FlatReceiverShadowEdgeIsWhereGeometrySaysIt) {
    // A sphere of radius 1 touching a plate, lit at 45 degrees: a plate point
    // is shadowed exactly when its ray to the light passes within 1 of the
    // centre. Ray offsets must not move that edge (a 45-degree light moves it
    // by as much as the offset).
    const std::string world =
        "LightSource \"distantlight\" 1 \"from\" [1 1 0] \"to\" [0 0 0]\n"
        "  \"string shadowname\" [\"raytrace\"]\n"
        "AttributeBegin\n"
        "Surface \"bake_radiance_t\" \"string filename\" [\"p.ptc\"]\n"
        "Polygon \"P\" [-2 -1 -2  -2 -1 2  2 -1 2  2 -1 -2]\n"
        "AttributeEnd\n"
        "Surface \"matte\"\n"
        "Sphere 1 -1 1 360\n";
    sss::BakeOptions opt;
    opt.spacing = 0.02;
    auto files = bake(scene_of(world), opt);
    const sss::PointCloud& c = files.at(0).second;
    const sss::Channel* r = c.find_channel("_radiance_t");
    const glm::dvec3 l = glm::normalize(glm::dvec3(1, 1, 0));
    std::size_t wrong = 0, near_edge = 0, shadowed = 0;
    for (std::size_t i = 0; i < c.size(); ++i) {
        glm::dvec3 p(c.positions[i]);
        double along = glm::dot(-p, l);
        double miss = along > 0.0 ? glm::length(p + along * l) : glm::length(p);
        // The occluder is diced 8x coarser than the plate: its outline is a
        // polygon inscribed in the sphere, within about 0.003 of it.
        if (std::abs(miss - 1.0) < 0.005) {
            ++near_edge;
            continue;
        }
        float expect = miss < 1.0 ? 0.0f : float(l.y);
        shadowed += miss < 1.0;
        if (std::abs(r->data[3 * i] - expect) > 1e-5f) ++wrong;
    }
    EXPECT_GT(near_edge, 0u);
    EXPECT_GT(shadowed, 1000u);
    EXPECT_EQ(wrong, 0u) << "of " << c.size() << " points";
}

TEST(Bake, SpacingFromEachObjectsOwnMaterial) {
    // Without -material, -spacing mfp dices each bake_sss_params object at its
    // own smallest mean free path (dmfp in mm, scene units from unitlength).
    const std::string world =
        "LightSource \"ambientlight\" 1\n"
        "Surface \"bake_sss_params\" \"string filename\" [\"m.ptc\"]\n"
        "  \"color albedo\" [0.8 0.8 0.8] \"color dmfp\" [2 2 2]\n"
        "Sphere 5 -5 5 360\n";
    sss::BakeOptions opt;
    opt.spacing_from_material = true;
    opt.unitlength = 0.1; // cm scene: 1 mm = 0.1 units
    sss::MaterialSpec m;
    m.albedo = glm::dvec3(0.8);
    m.dmfp = glm::dvec3(2.0);
    m.unitlength = 0.1;
    const double mfp = sss::material_mean_free_path(m);
    sss::BakeReport report;
    bake(scene_of(world), opt, &report);
    EXPECT_LE(report.max_spacing, mfp * 1.0001);
    EXPECT_GT(report.max_spacing, mfp * 0.5);
    for (const std::string& w : report.warnings)
        EXPECT_EQ(w.find("mean free path"), std::string::npos) << w;

    // An object without material parameters cannot pick its spacing.
    EXPECT_THROW(
        bake(scene_of("Surface \"bake_radiance_t\" \"string filename\" [\"x.ptc\"]\n"
                      "Sphere 1 -1 1 360\n"),
             opt),
        sss::UsageError);
}
