// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file mesh_walk_test.cpp
/// The random walk inside triangle meshes: energy bookkeeping with and
/// without an absorbing blocker, light leaving through a hole counted as
/// lost, the total reflectance of a thick box against the half-space walk, a
/// blocker darkening the surface above it, results that do not depend on the
/// thread count, and options it refuses.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include <glm/geometric.hpp>

#include "sss/truth/half_space.h"
#include "sss/truth/mesh_walk.h"
#include "sss/util/error.h"
#include "sss/util/threads.h"

namespace {

using namespace sss;

/// The box lo..hi as 12 triangles (outward, though the walk does not care).
TriangleMesh box(glm::vec3 lo, glm::vec3 hi) {
    TriangleMesh m;
    for (int k = 0; k < 8; ++k)
        m.vertices.push_back(
            {k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z});
    m.triangles = {0, 2, 1, 1, 2, 3,  // z = lo
                   4, 5, 6, 5, 7, 6,  // z = hi
                   0, 1, 4, 1, 5, 4,  // y = lo
                   2, 6, 3, 3, 6, 7,  // y = hi
                   0, 4, 2, 2, 4, 6,  // x = lo
                   1, 3, 5, 3, 7, 5}; // x = hi
    return m;
}

/// An nu x nv grid of points over the parallelogram corner + [0, 1] edge_u +
/// [0, 1] edge_v, facing cross(edge_u, edge_v), each standing for its cell.
void add_face(MeshWalkSource& s, glm::vec3 corner, glm::vec3 edge_u, glm::vec3 edge_v,
              int nu, int nv, glm::vec3 irradiance) {
    const glm::vec3 n = glm::cross(edge_u, edge_v);
    const float area = glm::length(n) / float(nu * nv);
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
            s.positions.push_back(corner + (float(i) + 0.5f) / float(nu) * edge_u +
                                  (float(j) + 0.5f) / float(nv) * edge_v);
            s.normals.push_back(glm::normalize(n));
            s.areas.push_back(area);
            s.irradiance.push_back(irradiance);
        }
}

/// An n x n grid over [x0, x1] x [y0, y1] at height z, facing +z.
MeshWalkSource top_grid(float x0, float x1, float y0, float y1, float z, int n,
                        glm::vec3 irradiance) {
    MeshWalkSource s;
    add_face(s, {x0, y0, z}, {x1 - x0, 0.0f, 0.0f}, {0.0f, y1 - y0, 0.0f}, n, n,
             irradiance);
    return s;
}

/// The unit cube, 10 transport mean free paths wide in channel 0, lit on top.
MeshWalkOptions cube_options() {
    MeshWalkOptions o;
    o.medium = {box(glm::vec3(0.0f), glm::vec3(1.0f))};
    o.sigma_s_prime = {10.0, 5.0, 20.0};
    o.sigma_a = glm::dvec3(0.0);
    o.eta = 1.3;
    o.photons = 4'000;
    o.batches = 16;
    return o;
}

MeshWalkSource cube_source() {
    return top_grid(0.0f, 1.0f, 0.0f, 1.0f, 1.0f, 4, {1.0f, 0.5f, 2.0f});
}

/// Every channel's flux in = out + blocked + truncated (no absorption in the
/// medium, so no Russian roulette), and the exitance sums to the flux out.
void expect_balance(const MeshWalkResult& r, const MeshWalkSource& s) {
    for (int c = 0; c < 3; ++c) {
        const double in = r.flux_in[c];
        EXPECT_GT(in, 0.0);
        EXPECT_EQ(r.flux_absorbed[c], 0.0);
        EXPECT_EQ(r.flux_lost[c], 0.0);
        EXPECT_NEAR(r.flux_out[c] + r.flux_blocked[c] + r.flux_truncated[c], in,
                    1e-9 * in)
            << "channel " << c;
        double exits = 0.0;
        for (std::size_t i = 0; i < s.areas.size(); ++i)
            exits += r.exitance[i][c] * double(s.areas[i]);
        EXPECT_NEAR(exits, r.flux_out[c], 1e-9 * in) << "channel " << c;
    }
}

TEST(TruthMeshWalk, EnergyIsConservedWithoutAbsorption) {
    const MeshWalkSource s = cube_source();
    MeshWalkOptions o = cube_options();
    MeshWalkResult r = walk_mesh(o, s);
    EXPECT_EQ(r.photons, o.photons);
    EXPECT_GT(r.collisions, 0u);
    EXPECT_NEAR(r.flux_in.x, 1.0, 1e-6);
    EXPECT_NEAR(r.flux_in.y, 0.5, 1e-6);
    EXPECT_NEAR(r.flux_in.z, 2.0, 1e-6);
    expect_balance(r, s);
    EXPECT_EQ(r.flux_blocked, glm::dvec3(0.0));
    EXPECT_EQ(r.flux_truncated, glm::dvec3(0.0));

    // Paths stopped early are counted, not lost.
    o.max_collisions = 20;
    r = walk_mesh(o, s);
    expect_balance(r, s);
    for (int c = 0; c < 3; ++c) EXPECT_GT(r.flux_truncated[c], 0.0);

    // An absorbing inclusion takes its share.
    o = cube_options();
    o.blockers = {box(glm::vec3(0.3f), glm::vec3(0.7f))};
    r = walk_mesh(o, s);
    expect_balance(r, s);
    for (int c = 0; c < 3; ++c) {
        EXPECT_GT(r.flux_blocked[c], 4.0 * r.flux_blocked_error[c]);
        EXPECT_LT(r.flux_blocked[c], r.flux_out[c]);
    }
}

TEST(TruthMeshWalk, LightLeavingThroughAHoleIsLost) {
    // The cube without its top face: light leaves through the hole into
    // nothing, and is counted as lost rather than walked forever.
    const MeshWalkSource s = cube_source();
    MeshWalkOptions o = cube_options();
    o.medium[0].triangles.erase(o.medium[0].triangles.begin() + 6,
                                o.medium[0].triangles.begin() + 12);
    const MeshWalkResult r = walk_mesh(o, s);
    for (int c = 0; c < 3; ++c) {
        EXPECT_GT(r.flux_lost[c], 0.3 * r.flux_in[c]);
        EXPECT_NEAR(r.flux_out[c] + r.flux_lost[c] + r.flux_truncated[c], r.flux_in[c],
                    1e-9 * r.flux_in[c]);
    }
}

TEST(TruthMeshWalk, ThickBoxReflectsAsTheHalfSpace) {
    // A box 200 x 200 x 100 transport mean free paths (l = 0.1), lit by a
    // patch of 5 x 5 l at the centre of its top face: nothing reaches the
    // other faces, so the light leaving per unit entering is the half-space's
    // total diffuse reflectance.
    const glm::dvec3 albedo{0.9, 0.5, 0.97};
    MeshWalkOptions o;
    o.medium = {box({-10.0f, -10.0f, -10.0f}, {10.0f, 10.0f, 0.0f})};
    o.sigma_s_prime = 10.0 * albedo;
    o.sigma_a = 10.0 * (1.0 - albedo);
    o.eta = 1.3;
    o.photons = 60'000;
    o.batches = 32;
    const MeshWalkSource s =
        top_grid(-0.25f, 0.25f, -0.25f, 0.25f, 0.0f, 5, glm::vec3(1.0f));
    const MeshWalkResult r = walk_mesh(o, s);
    for (int c = 0; c < 3; ++c) {
        HalfSpaceOptions h;
        h.albedo = albedo[c];
        h.eta = o.eta;
        h.incidence = Incidence::Diffuse;
        h.photons = 60'000;
        h.batches = 32;
        h.seed = 11;
        h.edges = {0.0, 100.0};
        const HalfSpaceResult want = walk_half_space(h);
        const double got = r.flux_out[c] / r.flux_in[c];
        const double error = r.flux_out_error[c] / r.flux_in[c];
        EXPECT_LT(error, 0.003);
        EXPECT_NEAR(got, want.total, 4.0 * std::hypot(error, want.total_error))
            << "albedo " << albedo[c] << ": box " << got << " +- " << error
            << ", half-space " << want.total << " +- " << want.total_error;
        EXPECT_EQ(r.flux_lost[c], 0.0);
        EXPECT_EQ(r.flux_blocked[c], 0.0);
    }
}

TEST(TruthMeshWalk, BlockerDarkensTheSurfaceAboveIt) {
    // A slab 10 x 10 x 4 l lit uniformly on top (channel 0 only), with and
    // without an absorbing block 3 x 3 x 1.7 l just under the centre. Points
    // without light cover the other faces, so that what leaves through them
    // is not tallied on top.
    MeshWalkOptions o;
    o.medium = {box({0.0f, 0.0f, -4.0f}, {10.0f, 10.0f, 0.0f})};
    o.sigma_s_prime = glm::dvec3(0.99);
    o.sigma_a = glm::dvec3(0.01);
    o.eta = 1.3;
    o.photons = 40'000;
    o.batches = 32;
    MeshWalkSource s = top_grid(0.0f, 10.0f, 0.0f, 10.0f, 0.0f, 10, {1.0f, 0.0f, 0.0f});
    const glm::vec3 dark(0.0f), x(10.0f, 0.0f, 0.0f), y(0.0f, 10.0f, 0.0f),
        z(0.0f, 0.0f, 4.0f);
    add_face(s, -z, y, x, 10, 10, dark);
    add_face(s, -z, x, z, 10, 4, dark);
    add_face(s, y - z, z, x, 4, 10, dark);
    add_face(s, -z, z, y, 4, 10, dark);
    add_face(s, x - z, y, z, 10, 4, dark);
    const MeshWalkResult open = walk_mesh(o, s);
    o.blockers = {box({3.5f, 3.5f, -2.0f}, {6.5f, 6.5f, -0.3f})};
    const MeshWalkResult blocked = walk_mesh(o, s);
    EXPECT_EQ(open.flux_in.y, 0.0); // a channel without light is not walked
    EXPECT_EQ(open.flux_out.y, 0.0);
    EXPECT_EQ(open.exitance.size(), 360u);
    EXPECT_GT(blocked.flux_blocked.x, 0.0);
    // The four points over the block's centre, (4.5 | 5.5, 4.5 | 5.5).
    double a = 0.0, b = 0.0, var = 0.0;
    for (std::size_t i : {44u, 45u, 54u, 55u}) {
        ASSERT_NEAR(s.positions[i].x, i % 10 == 4 ? 4.5f : 5.5f, 1e-6f);
        a += open.exitance[i].x;
        b += blocked.exitance[i].x;
        var += open.exitance_error[i].x * open.exitance_error[i].x +
               blocked.exitance_error[i].x * blocked.exitance_error[i].x;
    }
    EXPECT_LT(b, a - 4.0 * std::sqrt(var)) << "open " << a / 4 << ", blocked " << b / 4;
    // A corner far from the block hardly notices it.
    EXPECT_NEAR(blocked.exitance[0].x, open.exitance[0].x,
                4.0 * std::hypot(open.exitance_error[0].x, blocked.exitance_error[0].x));
}

TEST(TruthMeshWalk, ResultsDoNotDependOnTheThreadCount) {
    const MeshWalkSource s = cube_source();
    MeshWalkOptions o = cube_options();
    o.sigma_a = glm::dvec3(0.5); // Russian roulette too
    o.blockers = {box(glm::vec3(0.3f), glm::vec3(0.7f))};
    o.photons = 3'000;
    o.batches = 40; // more than one wave
    MeshWalkResult one, two;
    {
        ThreadLimit limit(1);
        one = walk_mesh(o, s);
    }
    {
        ThreadLimit limit(2);
        two = walk_mesh(o, s);
    }
    EXPECT_EQ(one.exitance, two.exitance);
    EXPECT_EQ(one.exitance_error, two.exitance_error);
    EXPECT_EQ(one.flux_out, two.flux_out);
    EXPECT_EQ(one.flux_blocked, two.flux_blocked);
    EXPECT_EQ(one.flux_absorbed, two.flux_absorbed);
    EXPECT_EQ(one.flux_out_error, two.flux_out_error);
    EXPECT_EQ(one.collisions, two.collisions);
    // Another seed is another estimate.
    o.seed = 2;
    const MeshWalkResult other = walk_mesh(o, s);
    for (int c = 0; c < 3; ++c) EXPECT_NE(other.flux_out[c], one.flux_out[c]);
}

TEST(TruthMeshWalk, BadOptionsAndSourcesAreRefused) {
    const MeshWalkOptions good = cube_options();
    const MeshWalkSource source = cube_source();
    const double nan = std::numeric_limits<double>::quiet_NaN();
    for (const auto& bad : std::initializer_list<void (*)(MeshWalkOptions&)>{
             [](MeshWalkOptions& x) { x.medium.clear(); },
             [](MeshWalkOptions& x) { x.medium[0].triangles.clear(); },
             [](MeshWalkOptions& x) { x.medium[0].triangles.push_back(99); },
             [](MeshWalkOptions& x) {
                 x.blockers = {TriangleMesh{{}, {0, 1, 2}}};
             },
             [](MeshWalkOptions& x) { x.sigma_s_prime.y = -1.0; },
             [](MeshWalkOptions& x) { x.sigma_a.z = -0.1; },
             [](MeshWalkOptions& x) {
                 x.sigma_a.x = std::numeric_limits<double>::infinity();
             },
             [](MeshWalkOptions& x) { x.eta = 0.0; },
             [](MeshWalkOptions& x) { x.photons = 0; },
             [](MeshWalkOptions& x) { x.batches = 0; },
             [](MeshWalkOptions& x) { x.batches = 5'000; },
             [](MeshWalkOptions& x) { x.max_collisions = 0; }}) {
        MeshWalkOptions x = good;
        bad(x);
        EXPECT_THROW(walk_mesh(x, source), ValueError);
    }
    MeshWalkOptions eta_nan = good;
    eta_nan.eta = nan;
    EXPECT_THROW(walk_mesh(eta_nan, source), ValueError);
    for (const auto& bad : std::initializer_list<void (*)(MeshWalkSource&)>{
             [](MeshWalkSource& x) { x.areas.pop_back(); },
             [](MeshWalkSource& x) {
                 x.normals.push_back({0.0f, 0.0f, 1.0f});
             },
             [](MeshWalkSource& x) { x = MeshWalkSource{}; },
             [](MeshWalkSource& x) { x.irradiance[3].y = -1.0f; },
             [](MeshWalkSource& x) { x.irradiance[2].x = std::nanf(""); },
             [](MeshWalkSource& x) { x.areas[1] = -0.5f; },
             [](MeshWalkSource& x) { x.normals[0] = glm::vec3(0.0f); },
             [](MeshWalkSource& x) { x.positions[0].x = std::nanf(""); },
             [](MeshWalkSource& x) {
                 for (glm::vec3& e : x.irradiance) e = glm::vec3(0.0f);
             }}) {
        MeshWalkSource x = source;
        bad(x);
        EXPECT_THROW(walk_mesh(good, x), ValueError);
    }
    // The point is named.
    MeshWalkSource x = source;
    x.irradiance[3].y = -1.0f;
    try {
        walk_mesh(good, x);
        ADD_FAILURE() << "no error";
    } catch (const ValueError& e) {
        EXPECT_NE(std::string(e.what()).find("point 3"), std::string::npos) << e.what();
    }
}

} // namespace
