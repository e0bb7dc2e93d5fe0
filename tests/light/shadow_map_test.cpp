// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file shadow_map_test.cpp
/// Tests of depth-map shadow lookups (sss/light/shadow_map.h) on hand-made
/// maps: points in front of the stored depth are lit, behind it shadowed,
/// the bias moves the boundary, blur and samples give fractions at an edge,
/// points outside the map or behind its camera are lit, and the scene's
/// Option "shadow" "bias".
///
/// Suite names start with "ShadowMap".

#include <gtest/gtest.h>

#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

#include "sss/light/shadow_map.h"

namespace {

using sss::ShadowLookup;
using sss::ShadowMap;

/// An orthographic map looking along world +z from the origin, covering
/// x, y in [-1, 1] with n x n texels: a plane at depth 5 where x < 0 (the
/// map's left half), nothing (kNoSurfaceDepth) where x > 0.
ShadowMap half_plane_map(int n = 16) {
    ShadowMap m;
    m.width = m.height = n;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
            m.depth.push_back(x < n / 2 ? 5.0f : sss::kNoSurfaceDepth);
    return m; // identity matrices: camera = world, screen x, y = world x, y
}

float at(const ShadowMap& m, glm::dvec3 p, const ShadowLookup& look) {
    return sss::shadow_fraction(m, p, glm::dvec3(0.0), glm::dvec3(0.0), look);
}

TEST(ShadowMap, InFrontLitBehindShadowed) {
    const ShadowMap m = half_plane_map();
    ShadowLookup look;
    look.bias = 0.0f;
    EXPECT_EQ(at(m, {-0.5, 0.3, 4.0}, look), 0.0f);  // in front of the plane
    EXPECT_EQ(at(m, {-0.5, 0.3, 6.0}, look), 1.0f);  // behind it
    EXPECT_EQ(at(m, {0.5, 0.3, 6.0}, look), 0.0f);   // nothing stored there
    EXPECT_EQ(at(m, {-0.5, 0.3, -1.0}, look), 0.0f); // behind the map's camera
    EXPECT_EQ(at(m, {-1.5, 0.3, 6.0}, look), 0.0f);  // outside the map
    EXPECT_EQ(at(m, {-0.5, 1.2, 6.0}, look), 0.0f);
}

TEST(ShadowMap, BiasMovesTheBoundary) {
    const ShadowMap m = half_plane_map();
    ShadowLookup look;
    look.bias = 0.2f;
    EXPECT_EQ(at(m, {-0.5, 0.0, 5.1}, look), 0.0f); // within the bias: lit
    EXPECT_EQ(at(m, {-0.5, 0.0, 5.3}, look), 1.0f);
    look.bias = 0.05f;
    EXPECT_EQ(at(m, {-0.5, 0.0, 5.1}, look), 1.0f);
    // The default is PRMan's.
    EXPECT_EQ(ShadowLookup{}.bias, sss::kDefaultShadowBias);
    EXPECT_EQ(at(m, {-0.5, 0.0, 5.2}, ShadowLookup{}), 0.0f);
}

TEST(ShadowMap, BlurGivesFractionsAtAnEdge) {
    const ShadowMap m = half_plane_map(64);
    ShadowLookup look;
    look.bias = 0.0f;
    look.samples = 64;
    look.sblur = look.tblur = 0.2f;
    // On the edge (x = 0): about half the region is shadowed.
    const float edge = at(m, {0.0, 0.0, 6.0}, look);
    EXPECT_GT(edge, 0.35f);
    EXPECT_LT(edge, 0.65f);
    // 0.08 (0.04 map units) into the shadow: about 0.7, not all.
    const float inside = at(m, {-0.08, 0.0, 6.0}, look);
    EXPECT_GT(inside, edge + 0.1f);
    EXPECT_LT(inside, 1.0f);
    // Far from the edge the blurred lookup is whole.
    EXPECT_EQ(at(m, {-0.5, 0.0, 6.0}, look), 1.0f);
    EXPECT_EQ(at(m, {0.5, 0.0, 6.0}, look), 0.0f);
    // The same point gives the same answer (the jitter is the point's hash).
    EXPECT_EQ(at(m, {0.0, 0.0, 6.0}, look), edge);
    // Without blur nor footprint the edge is hard.
    ShadowLookup hard;
    hard.bias = 0.0f;
    hard.samples = 64;
    EXPECT_EQ(at(m, {-0.02, 0.0, 6.0}, hard), 1.0f);
    EXPECT_EQ(at(m, {0.02, 0.0, 6.0}, hard), 0.0f);
}

TEST(ShadowMap, FootprintAndWidth) {
    const ShadowMap m = half_plane_map(64);
    ShadowLookup look;
    look.bias = 0.0f;
    look.samples = 64;
    // A footprint 0.4 wide across the edge blurs like blur 0.2 (both are
    // in map units: the map spans 2 world units).
    const glm::dvec3 du(0.4, 0.0, 0.0), dv(0.0, 0.4, 0.0);
    const float f = sss::shadow_fraction(m, {0.0, 0.0, 6.0}, du, dv, look);
    EXPECT_GT(f, 0.35f);
    EXPECT_LT(f, 0.65f);
    // width 0 shrinks it to a texel: hard again.
    look.swidth = look.twidth = 0.0f;
    EXPECT_EQ(sss::shadow_fraction(m, {-0.02, 0.0, 6.0}, du, dv, look), 1.0f);
    // Non-finite input is lit, never NaN.
    EXPECT_EQ(sss::shadow_fraction(m, {std::nan(""), 0.0, 6.0}, du, dv, look), 0.0f);
}

TEST(ShadowMap, PerspectiveProjection) {
    // A perspective map: screen = (x / z, y / z) (90 degrees).
    ShadowMap m = half_plane_map();
    m.world_to_screen = sss::Matrix4(0.0);
    m.world_to_screen[0][0] = 1.0;
    m.world_to_screen[1][1] = 1.0;
    m.world_to_screen[2][3] = 1.0; // w = z
    ShadowLookup look;
    look.bias = 0.0f;
    EXPECT_EQ(at(m, {-3.0, 0.0, 6.0}, look), 1.0f); // x / z = -0.5: left half
    EXPECT_EQ(at(m, {3.0, 0.0, 6.0}, look), 0.0f);
    EXPECT_EQ(at(m, {-9.0, 0.0, 6.0}, look), 0.0f); // outside the 90 degrees
}

TEST(ShadowMap, SceneBias) {
    sss::Scene scene;
    EXPECT_EQ(sss::scene_shadow_bias(scene), sss::kDefaultShadowBias);
    sss::Param b;
    b.name = "bias0";
    b.type = sss::ParamType::Float;
    b.numbers = {0.1};
    scene.options.groups["shadow"].set(b);
    EXPECT_FLOAT_EQ(sss::scene_shadow_bias(scene), 0.1f);
    b.name = "bias1";
    b.numbers = {0.3};
    scene.options.groups["shadow"].set(b);
    EXPECT_FLOAT_EQ(sss::scene_shadow_bias(scene), 0.2f);
    b.name = "bias";
    b.numbers = {0.05};
    scene.options.groups["shadow"].set(b);
    EXPECT_FLOAT_EQ(sss::scene_shadow_bias(scene), 0.05f);
}

} // namespace
