// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// SceneRays: secondary rays over a diced scene, hit shading with the hit
// object's own shader, visibility, depth limits, hit modes and transmission.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "sss/binding/scene_rays.h"
#include "sss/binding/scene_shaders.h"
#include "sss/dice/dice.h"
#include "sss/scene/rib.h"
#include "test_util.h"

namespace {

using namespace sss;

/// Ci = Cs, Oi = a fixed opacity, and an output parameter to read back.
const char* kHitColor = R"(
surface hitcolor(float opacity = 1; output varying float marker = 0) {
    marker = 7;
    Oi = opacity;
    Ci = Cs;
}
)";

class QuietServices final : public ShadingServices {
public:
    explicit QuietServices(const Scene& s) : m_scene(s) {}
    const Scene& scene() const override { return m_scene; }
    void message(const std::string&) override {}
    void warning(const std::string& text) override { warnings.push_back(text); }
    std::vector<std::string> warnings;

private:
    const Scene& m_scene;
};

/// A scene (shaders next to it), diced and made into SceneRays.
struct RayScene {
    test::TempDir dir;
    Scene scene;
    SceneShaders shaders;
    std::unique_ptr<ShadingResources> resources;
    std::unique_ptr<QuietServices> services;
    std::vector<DicedSurface> diced;
    std::unique_ptr<SceneRays> rays;

    RayScene(const std::string& options, const std::string& world,
             const std::vector<std::pair<std::string, std::string>>& shaders_sl = {}) {
        test::write_text(dir.file("hitcolor.sl"), kHitColor);
        for (const auto& [name, text] : shaders_sl)
            test::write_text(dir.file(name), text);
        const std::string path = dir.file("scene.rib");
        const std::string text = options +
                                 "Format 64 64 1\nProjection \"perspective\"\n" +
                                 "WorldBegin\n" + world + "WorldEnd\n";
        test::write_text(path, text);
        scene = parse_rib(text, path);
        shaders = bind_scene_shaders(scene, std::nullopt);
        resources = std::make_unique<ShadingResources>();
        services = std::make_unique<QuietServices>(scene);
        std::vector<DiceRequest> requests;
        DiceControl control;
        control.spacing = 0.02;
        for (std::size_t i = 0; i < scene.primitives.size(); ++i)
            requests.push_back({i, control, {}});
        diced = dice_all(scene, requests);
        std::vector<RaySurface> surfaces(scene.primitives.size());
        for (std::size_t i = 0; i < diced.size(); ++i) surfaces[i] = {&diced[i], nullptr};
        rays = std::make_unique<SceneRays>(scene, shaders, *resources, *services,
                                           std::move(surfaces));
    }
};

RayQuery query(RayKind kind, int depth, std::vector<ShadowRay> rays,
               std::vector<std::string> outputs = {"Ci"}) {
    RayQuery q;
    q.kind = kind;
    q.depth = depth;
    q.rays = std::move(rays);
    for (const std::string& o : outputs) {
        q.outputs.push_back(o);
        q.output_floats.push_back(o == "marker" ? 1 : 3);
    }
    return q;
}

const float kInf = std::numeric_limits<float>::infinity();
// From z = -5 towards +z: hits a unit sphere at the origin at t = 4; the
// second ray passes beside it.
const ShadowRay kHitRay{{0, 0, -5}, {0, 0, 1}, 0.0f, kInf};
const ShadowRay kMissRay{{3, 0, -5}, {0, 0, 1}, 0.0f, kInf};

const char* kSphere = "Color [0.2 0.4 0.6]\nSurface \"hitcolor\"\nSphere 1 -1 1 360\n";

} // namespace

TEST(SceneRays, HitsAreShadedWithTheirOwnShader) {
    RayScene s("", kSphere);
    RayQuery q = query(RayKind::Specular, 1, {kHitRay, kMissRay}, {"Ci", "marker"});
    s.rays->trace(q);
    ASSERT_EQ(q.hit.size(), 2u);
    EXPECT_EQ(q.hit[0], 1);
    EXPECT_EQ(q.hit[1], 0);
    EXPECT_NEAR(q.length[0], 4.0f, 1e-3f);
    EXPECT_TRUE(std::isinf(q.length[1]));
    EXPECT_NEAR(q.values[0][0], 0.2f, 1e-6f);
    EXPECT_NEAR(q.values[0][1], 0.4f, 1e-6f);
    EXPECT_NEAR(q.values[0][2], 0.6f, 1e-6f);
    EXPECT_EQ(q.values[0][3], 0.0f); // the miss
    EXPECT_EQ(q.values[1][0], 7.0f);
    EXPECT_EQ(q.values[1][1], 0.0f);
}

TEST(SceneRays, VisibilityDecidesWhatEachKindOfRaySees) {
    RayScene s("", "Attribute \"visibility\" \"diffuse\" 0\n" + std::string(kSphere));
    RayQuery d = query(RayKind::Diffuse, 1, {kHitRay});
    s.rays->trace(d);
    EXPECT_EQ(d.hit[0], 0);
    RayQuery sp = query(RayKind::Specular, 1, {kHitRay});
    s.rays->trace(sp);
    EXPECT_EQ(sp.hit[0], 1);
    glm::vec3 t{0.0f};
    s.rays->transmit(&kHitRay, 1, &t, 1);
    EXPECT_EQ(t, glm::vec3(0.0f));
}

TEST(SceneRays, DepthLimitsFollowTheShootingPrimitive) {
    RayScene s("", kSphere);
    const Primitive* origin = &s.scene.primitives[0];
    // PRMan's defaults: one diffuse bounce, two specular.
    RayQuery d2 = query(RayKind::Diffuse, 2, {kHitRay});
    d2.origin = origin;
    s.rays->trace(d2);
    EXPECT_EQ(d2.hit[0], 0);
    RayQuery s2 = query(RayKind::Specular, 2, {kHitRay});
    s2.origin = origin;
    s.rays->trace(s2);
    EXPECT_EQ(s2.hit[0], 1);

    RayScene deep("",
                  "Attribute \"trace\" \"maxdiffusedepth\" 3\n" + std::string(kSphere));
    RayQuery d3 = query(RayKind::Diffuse, 3, {kHitRay});
    d3.origin = &deep.scene.primitives[0];
    deep.rays->trace(d3);
    EXPECT_EQ(d3.hit[0], 1);

    RayScene none("Option \"trace\" \"maxdepth\" 0\n", kSphere);
    RayQuery s1 = query(RayKind::Specular, 1, {kHitRay});
    none.rays->trace(s1);
    EXPECT_EQ(s1.hit[0], 0);
    EXPECT_EQ(s1.values[0][0], 0.0f);
}

TEST(SceneRays, OneSidedFacesAreHitAsHitsidesSays) {
    RayScene s("", "Sides 1\n" + std::string(kSphere));
    // From inside the sphere every face is a back face: PRMan's rays hit both
    // sides of one-sided surfaces unless "hitsides" says otherwise (the
    // application note's gather from inside a Sides 1 teapot finds its exits).
    const ShadowRay inside{{0, 0, 0}, {0, 0, 1}, 0.0f, kInf};
    RayQuery q = query(RayKind::Specular, 1, {inside});
    s.rays->trace(q);
    EXPECT_EQ(q.hit[0], 1);
    EXPECT_NEAR(q.length[0], 1.0f, 1e-3f);
    RayQuery front = query(RayKind::Specular, 1, {inside});
    front.hitsides = HitSides::Front;
    s.rays->trace(front);
    EXPECT_EQ(front.hit[0], 0);
    RayQuery back = query(RayKind::Specular, 1, {inside, kHitRay});
    back.hitsides = HitSides::Back;
    s.rays->trace(back);
    EXPECT_EQ(back.hit[0], 1);
    EXPECT_EQ(back.hit[1], 1); // through the front face, to the back one
    EXPECT_NEAR(back.length[1], 6.0f, 1e-3f);
    RayScene two("", kSphere);
    RayQuery q2 =
        query(RayKind::Specular, 1, {ShadowRay{{0, 0, 0}, {0, 0, 1}, 0.0f, kInf}});
    two.rays->trace(q2);
    EXPECT_EQ(q2.hit[0], 1);
    EXPECT_NEAR(q2.length[0], 1.0f, 1e-3f);
}

TEST(SceneRays, PrimitiveHitModeUsesTheAttributes) {
    RayScene s("", "Attribute \"shade\" \"specularhitmode\" \"primitive\"\n"
                   "Color [0.5 0.25 1]\nSurface \"constant\"\nSphere 1 -1 1 360\n");
    RayQuery q = query(RayKind::Specular, 1, {kHitRay});
    s.rays->trace(q);
    ASSERT_EQ(q.hit[0], 1);
    EXPECT_EQ(q.values[0][0], 0.5f);
    EXPECT_EQ(q.values[0][1], 0.25f);
    EXPECT_EQ(q.values[0][2], 1.0f);
}

TEST(SceneRays, TransmissionMultipliesTheOpacities) {
    // Through both walls of a sphere of opacity 0.5: 0.25 gets through.
    RayScene s("", "Opacity [0.5 0.5 0.5]\n" + std::string(kSphere));
    const ShadowRay through{{0, 0, -5}, {0, 0, 1}, 0.0f, 10.0f};
    glm::vec3 t{0.0f};
    s.rays->transmit(&through, 1, &t, 1);
    EXPECT_NEAR(t.x, 0.25f, 1e-6f);
    // Stopping inside: one wall.
    const ShadowRay half{{0, 0, -5}, {0, 0, 1}, 0.0f, 5.0f};
    s.rays->transmit(&half, 1, &t, 1);
    EXPECT_NEAR(t.y, 0.5f, 1e-6f);

    // "shader": the hit shader's Oi (0.1) decides.
    RayScene sh("", "Attribute \"shade\" \"transmissionhitmode\" \"shader\"\n"
                    "Surface \"hitcolor\" \"float opacity\" 0.1\nSphere 1 -1 1 360\n");
    sh.rays->transmit(&through, 1, &t, 1);
    EXPECT_NEAR(t.z, 0.81f, 1e-5f);

    // Opaque: all or nothing.
    RayScene o("", kSphere);
    o.rays->transmit(&through, 1, &t, 1);
    EXPECT_EQ(t, glm::vec3(0.0f));
    o.rays->transmit(&kMissRay, 1, &t, 1);
    EXPECT_EQ(t, glm::vec3(1.0f));
}

TEST(SceneRays, ResultsDoNotDependOnBatching) {
    // Many rays at once give each ray the result it gets alone.
    RayScene s("", kSphere);
    std::vector<ShadowRay> many;
    for (int k = 0; k < 600; ++k) {
        const float x = -1.5f + 3.0f * static_cast<float>(k) / 599.0f;
        many.push_back(ShadowRay{{x, 0.1f, -5}, {0, 0, 1}, 0.0f, kInf});
    }
    RayQuery all = query(RayKind::Specular, 1, many, {"Ci", "marker"});
    s.rays->trace(all);
    for (int k : {0, 250, 300, 599}) {
        RayQuery one =
            query(RayKind::Specular, 1, {many[std::size_t(k)]}, {"Ci", "marker"});
        s.rays->trace(one);
        EXPECT_EQ(one.hit[0], all.hit[std::size_t(k)]);
        EXPECT_EQ(one.values[1][0], all.values[1][std::size_t(k)]);
    }
}

namespace {
/// A mirror that gathers 8 rays per hit: inside a sphere with no depth limit
/// worth the name the ray tree would grow 8 times per level.
const char* kGreedy = R"(
surface greedy(float samples = 8) {
    color c = 0;
    gather("illuminance", P, faceforward(normalize(N), I), PI / 2, samples,
           "surface:Ci", c) {
        Ci += c / samples;
    }
    Ci += 0.01;
}
)";
} // namespace

TEST(SceneRays, RunawayRayTreesStopAtTheBudget) {
    RayScene s("Option \"trace\" \"maxdepth\" 64\n",
               "Attribute \"trace\" \"maxspeculardepth\" 64\nSurface \"greedy\"\n"
               "Sphere 1 -1 1 360\n",
               {{"greedy.sl", kGreedy}});
    RayQuery q =
        query(RayKind::Specular, 1, {ShadowRay{{0, 0, 0}, {0, 0, 1}, 0.0f, kInf}});
    q.origin = &s.scene.primitives[0];
    s.rays->trace(q); // 8^63 rays without the budget
    ASSERT_EQ(q.hit[0], 1);
    EXPECT_GT(q.values[0][0], 0.01f);
    EXPECT_TRUE(std::isfinite(q.values[0][0]));
    EXPECT_LE(s.rays->rays_traced(), 16384u + 8u);
    ASSERT_EQ(s.services->warnings.size(), 1u);
    EXPECT_NE(s.services->warnings[0].find("deeper rays miss"), std::string::npos);
}

namespace {
/// Interior: Ci plus the segment's length in green; Exterior: Ci halved and
/// Oi set to 0.25 (traced rays run them on the segment to the hit).
const char* kInteriorSl = "volume inside() { Ci += color(0, length(I), 0); }";
const char* kExteriorSl = "volume outside() { Ci *= 0.5; Oi = 0.25; }";
const char* kVolumes =
    "AttributeBegin\nTranslate 10 0 0\nExterior \"outside\"\nSurface \"hitcolor\"\n"
    "Disk 0 0.5 360\nAttributeEnd\n"
    "Color [0.2 0.4 0.6]\nInterior \"inside\"\nSurface \"hitcolor\"\nSphere 1 -1 1 360\n";
} // namespace

TEST(SceneRays, InteriorAndExteriorShadersRunOnTracedSegments) {
    RayScene s("", kVolumes, {{"inside.sl", kInteriorSl}, {"outside.sl", kExteriorSl}});
    ASSERT_TRUE(s.shaders.any_interior_exterior);
    ASSERT_TRUE(s.shaders.exterior_of[0] && s.shaders.interior_of[1]);
    // Leaving the disk (its Exterior) and reaching the sphere's front face:
    // the segment ran outside, through the disk's exterior.
    RayQuery out = query(RayKind::Specular, 1, {kHitRay}, {"Ci", "Oi"});
    out.origin = &s.scene.primitives[0];
    s.rays->trace(out);
    ASSERT_EQ(out.hit[0], 1);
    EXPECT_NEAR(out.values[0][0], 0.1f, 1e-6f);
    EXPECT_NEAR(out.values[0][2], 0.3f, 1e-6f);
    EXPECT_NEAR(out.values[1][0], 0.25f, 1e-6f);
    // From the sphere's centre (a ray leaving its inside): the back face at
    // distance 1, through the sphere's Interior.
    RayQuery in = query(RayKind::Specular, 1,
                        {ShadowRay{{0, 0, 0}, {0, 0, 1}, 0.0f, kInf}}, {"Ci", "Oi"});
    in.origin = &s.scene.primitives[1];
    s.rays->trace(in);
    ASSERT_EQ(in.hit[0], 1);
    EXPECT_NEAR(in.values[0][0], 0.2f, 1e-6f);
    EXPECT_NEAR(in.values[0][1], 0.4f + 1.0f, 2e-3f); // the chord of the diced sphere
    EXPECT_NEAR(in.values[1][0], 1.0f, 1e-6f);        // Oi untouched
    // A ray whose origin is not a primitive (or one without an Exterior):
    // the front-face hit runs no volume.
    RayQuery none = query(RayKind::Specular, 1, {kHitRay});
    s.rays->trace(none);
    EXPECT_NEAR(none.values[0][0], 0.2f, 1e-6f);
    // Queries that do not ask for Ci or Oi run no volume shader.
    RayQuery marker = query(RayKind::Specular, 1, {kHitRay}, {"marker"});
    marker.origin = &s.scene.primitives[0];
    s.rays->trace(marker);
    EXPECT_EQ(marker.values[0][0], 7.0f);
}
