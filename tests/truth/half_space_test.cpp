// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file half_space_test.cpp
/// The half-space random walk against values it must reproduce: total
/// reflectance from Chandrasekhar's H-function (eta = 1), the closed-form
/// single scattering, energy bookkeeping without absorption, Fresnel's
/// formulas, and results that do not depend on the thread count.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

#include "sss/truth/half_space.h"
#include "sss/util/error.h"
#include "sss/util/threads.h"

namespace {

using namespace sss;

HalfSpaceResult walk(double albedo, double eta, Incidence incidence, uint64_t photons,
                     uint64_t seed = 7) {
    HalfSpaceOptions o;
    o.albedo = albedo;
    o.eta = eta;
    o.incidence = incidence;
    o.photons = photons;
    o.batches = 32;
    o.seed = seed;
    return walk_half_space(o);
}

/// `got` within 4 standard errors of `want` (and the error itself small).
void expect_within(double got, double error, double want, double max_error,
                   const char* what) {
    EXPECT_LT(error, max_error) << what;
    EXPECT_NEAR(got, want, 4.0 * error) << what << ": " << got << " +- " << error;
}

TEST(TruthHalfSpace, TotalReflectanceMatchesChandrasekhar) {
    // Total diffuse reflectance of a half-space at eta = 1 (H-function values,
    // ../shared/reference/truth.md), normal and diffuse incidence.
    struct Case {
        double albedo;
        Incidence incidence;
        double want;
    };
    for (const Case& c : {Case{0.99, Incidence::Pencil, 0.752721},
                          Case{0.99, Incidence::Diffuse, 0.794564},
                          Case{0.5, Incidence::Pencil, 0.115226},
                          Case{0.5, Incidence::Diffuse, 0.146544}}) {
        const HalfSpaceResult r = walk(c.albedo, 1.0, c.incidence, 200'000);
        expect_within(r.total, r.total_error, c.want, 0.002, "total reflectance");
        EXPECT_EQ(r.truncated, 0.0);
        // Everything that entered left or was absorbed (Russian roulette keeps
        // the balance in expectation only).
        EXPECT_NEAR(r.total + r.absorbed, 1.0, 0.01);
    }
}

TEST(TruthHalfSpace, SingleScatteringMatchesTheClosedForm) {
    // eta = 1: alpha' / 2 * (1 - ln 2) in all.
    const double albedo = 0.99;
    const double all =
        single_scattering_flux(albedo, 1.0, 0.0, std::numeric_limits<double>::infinity());
    EXPECT_NEAR(all, albedo / 2.0 * (1.0 - std::numbers::ln2), 1e-7);
    const HalfSpaceResult r = walk(albedo, 1.0, Incidence::Pencil, 200'000);
    expect_within(r.total_single, r.total_single_error, all, 0.002, "single, eta 1");

    // With a boundary (eta 1.4: Fresnel on the way out, total internal
    // reflection past 45.6 degrees), annulus by annulus.
    HalfSpaceOptions o;
    o.albedo = 0.8;
    o.eta = 1.4;
    o.photons = 200'000;
    o.batches = 32;
    o.edges = {0.0, 0.1, 0.3, 1.0, 3.0};
    const HalfSpaceResult s = walk_half_space(o);
    for (std::size_t a = 0; a + 1 < o.edges.size(); ++a) {
        const double want =
            single_scattering_flux(o.albedo, o.eta, o.edges[a], o.edges[a + 1]);
        EXPECT_GT(want, 0.0);
        expect_within(s.single[a], s.single_error[a], want, 0.002, "single, eta 1.4");
    }
}

TEST(TruthHalfSpace, WithoutAbsorptionEverythingLeavesOrIsCounted) {
    HalfSpaceOptions o;
    o.albedo = 1.0;
    o.eta = 1.4;
    o.photons = 4'000;
    o.batches = 8;
    o.max_collisions = 20'000;
    const HalfSpaceResult r = walk_half_space(o);
    EXPECT_EQ(r.absorbed, 0.0);
    EXPECT_NEAR(r.total + r.truncated, 1.0, 1e-12);
    // Walks end at the boundary with probability 1; those still inside after
    // 20000 collisions are a few per cent (the return time's tail is ~ n^-1/2).
    EXPECT_LT(r.truncated, 0.05);
    EXPECT_GT(r.total, 0.95);
}

TEST(TruthHalfSpace, ResultsDoNotDependOnTheThreadCount) {
    HalfSpaceOptions o;
    o.albedo = 0.9;
    o.eta = 1.3;
    o.incidence = Incidence::Diffuse;
    o.photons = 20'000;
    o.batches = 16;
    HalfSpaceResult one, two;
    {
        ThreadLimit limit(1);
        one = walk_half_space(o);
    }
    {
        ThreadLimit limit(2);
        two = walk_half_space(o);
    }
    EXPECT_EQ(one.total, two.total);
    EXPECT_EQ(one.single, two.single);
    EXPECT_EQ(one.multiple, two.multiple);
    EXPECT_EQ(one.total_error, two.total_error);
    // Another seed is another estimate.
    o.seed = 2;
    EXPECT_NE(walk_half_space(o).total, one.total);
}

TEST(TruthHalfSpace, FresnelReflectance) {
    EXPECT_NEAR(fresnel_reflectance(1.0, 1.0, 1.5), 0.04, 1e-12);
    EXPECT_NEAR(fresnel_reflectance(1.0, 1.5, 1.0), 0.04, 1e-12);
    EXPECT_EQ(fresnel_reflectance(0.3, 1.0, 1.0), 0.0);
    // Past the critical angle (sin = 1 / 1.4) inside: total internal reflection.
    EXPECT_EQ(fresnel_reflectance(std::cos(0.8), 1.4, 1.0), 1.0);
    EXPECT_LT(fresnel_reflectance(std::cos(0.7), 1.4, 1.0), 1.0);
    // Grazing from outside reflects everything.
    EXPECT_NEAR(fresnel_reflectance(0.0, 1.0, 1.4), 1.0, 1e-12);
}

TEST(TruthHalfSpace, OptionsOutOfRangeAreRefused) {
    HalfSpaceOptions o;
    o.photons = 100;
    o.batches = 4;
    for (const auto& bad : std::initializer_list<void (*)(HalfSpaceOptions&)>{
             [](HalfSpaceOptions& x) { x.albedo = 1.5; },
             [](HalfSpaceOptions& x) { x.albedo = std::nan(""); },
             [](HalfSpaceOptions& x) { x.eta = 0.0; },
             [](HalfSpaceOptions& x) { x.batches = 0; },
             [](HalfSpaceOptions& x) { x.batches = 1000; },
             [](HalfSpaceOptions& x) {
                 x.edges = {0.5, 1.0};
             },
             [](HalfSpaceOptions& x) {
                 x.edges = {0.0, 1.0, 1.0};
             },
             [](HalfSpaceOptions& x) { x.max_collisions = 0; }}) {
        HalfSpaceOptions x = o;
        bad(x);
        EXPECT_THROW(walk_half_space(x), ValueError);
    }
}

} // namespace

namespace {

using namespace sss;

TEST(TruthHalfSpace, SweepMatchesChandrasekharAndTheSingleWalk) {
    // One set of paths for several albedos: the H-function totals at eta 1,
    // and at eta 1.3 the walk of each albedo on its own.
    HalfSpaceSweepOptions s;
    s.albedos = {0.5, 0.9, 0.99};
    s.eta = 1.0;
    s.photons = 100'000;
    s.batches = 32;
    std::vector<HalfSpaceResult> r = walk_half_space_sweep(s);
    ASSERT_EQ(r.size(), 3u);
    expect_within(r[0].total, r[0].total_error, 0.115226, 0.002, "sweep 0.5");
    expect_within(r[2].total, r[2].total_error, 0.752721, 0.002, "sweep 0.99");
    for (const HalfSpaceResult& x : r) {
        EXPECT_LT(x.truncated, 1e-11);
        EXPECT_NEAR(x.total + x.absorbed + x.truncated, 1.0, 1e-12);
    }
    // Single scattering is the order-1 weight: albedo times the walk's.
    EXPECT_NEAR(r[1].total_single / r[2].total_single, 0.9 / 0.99, 1e-12);

    s.eta = 1.3;
    s.edges = {0.0, 0.3, 1.0, 3.0, 10.0};
    r = walk_half_space_sweep(s);
    HalfSpaceOptions o;
    o.albedo = 0.9;
    o.eta = 1.3;
    o.photons = 100'000;
    o.batches = 32;
    o.seed = 5;
    o.edges = s.edges;
    const HalfSpaceResult w = walk_half_space(o);
    for (std::size_t a = 0; a + 1 < s.edges.size(); ++a) {
        const double err = std::hypot(w.multiple_error[a], r[1].multiple_error[a]);
        EXPECT_NEAR(r[1].multiple[a], w.multiple[a], 4.0 * err) << "annulus " << a;
    }
    EXPECT_NEAR(r[1].total, w.total, 4.0 * std::hypot(w.total_error, r[1].total_error));

    // The same thread independence as one walk, and bad albedos refused.
    HalfSpaceSweepOptions t = s;
    t.photons = 5'000;
    std::vector<HalfSpaceResult> one, two;
    {
        ThreadLimit limit(1);
        one = walk_half_space_sweep(t);
    }
    {
        ThreadLimit limit(2);
        two = walk_half_space_sweep(t);
    }
    EXPECT_EQ(one[2].multiple, two[2].multiple);
    t.albedos = {0.5, 1.0};
    EXPECT_THROW(walk_half_space_sweep(t), ValueError);
    t.albedos = {};
    EXPECT_THROW(walk_half_space_sweep(t), ValueError);
}

} // namespace
