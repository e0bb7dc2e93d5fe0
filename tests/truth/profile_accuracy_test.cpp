// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file profile_accuracy_test.cpp
/// The profiles against the walk: the comparison's arithmetic on a walk made
/// of a profile's own fluxes, then real walks where the classic dipole must
/// be as wrong as the light says and photon beam diffusion and the
/// Monte-Carlo table as right; the table writer's output.

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>

#include "sss/truth/profile_accuracy.h"
#include "sss/truth/profile_report.h"

namespace {

using namespace sss;

Profile unit_profile(ProfileKind kind, double alpha, double eta) {
    return Profile::from_coefficients(kind, {alpha, 1.0 - alpha, eta});
}

TEST(TruthProfileAccuracy, ArithmeticOnAProfilesOwnFluxes) {
    const Profile p = unit_profile(ProfileKind::Pbd, 0.9, 1.3);
    HalfSpaceResult w;
    for (int i = 0; i <= 200; ++i) w.edges.push_back(0.05 * i);
    w.multiple = profile_annulus_flux(p, w.edges);
    w.single.assign(w.multiple.size(), 0.0);
    w.single_error.assign(w.multiple.size(), 0.0);
    w.multiple_error.assign(w.multiple.size(), 0.0);
    w.total = p.total();
    ProfileAccuracy a = compare_with_walk(p, w);
    EXPECT_NEAR(a.l1w, 0.0, 1e-12);
    EXPECT_NEAR(a.d_rd, 0.0, 1e-12);
    for (double r : a.range_ratio) EXPECT_NEAR(r, 1.0, 1e-12);
    // A walk 10 % darker everywhere: the profile is 1/0.9 - 1 too bright.
    for (double& f : w.multiple) f *= 0.9;
    w.total *= 0.9;
    a = compare_with_walk(p, w);
    EXPECT_NEAR(a.l1w, 1.0 / 0.9 - 1.0, 1e-9);
    EXPECT_NEAR(a.d_rd, 1.0 / 0.9 - 1.0, 1e-9);
    // The annuli must reach 10 l.
    w.edges.resize(100);
    w.multiple.resize(99);
    EXPECT_THROW(compare_with_walk(p, w), ValueError);
}

TEST(TruthProfileAccuracy, ProfilesAgainstTheLight) {
    // skin1 (ior 1.3; alpha' 0.959, 0.838, 0.678) walked with a seed the table
    // was not made with. Classic: 28-75 % L1w; photon beam diffusion within
    // 10 %; the Monte-Carlo table within 3 % and 2 % in total reflectance,
    // each allowed the walk's own noise.
    ProfileReportOptions o;
    o.material.preset = "skin1";
    o.profiles = {ProfileKind::Classic, ProfileKind::Pbd, ProfileKind::Mc};
    o.photons = 150'000;
    o.batches = 32;
    const ProfileReport r = profile_report(o);
    for (int ch = 0; ch < 3; ++ch) {
        const ChannelReport& c = r.channel[ch];
        const ProfileAccuracy& classic = c.accuracy[0];
        const ProfileAccuracy& pbd = c.accuracy[1];
        const ProfileAccuracy& mc = c.accuracy[2];
        const double noise = mc.l1w_noise;
        EXPECT_LT(noise, 0.04) << ch;
        EXPECT_GT(classic.l1w, 0.25) << ch;
        EXPECT_LT(pbd.l1w, 0.10 + noise) << ch;
        EXPECT_LT(mc.l1w, 0.03 + noise) << ch;
        EXPECT_LT(std::abs(mc.d_rd), 0.02 + 3.0 * mc.d_rd_error) << ch;
        // The classic dipole misses the single-scattering peak at the beam.
        EXPECT_LT(classic.range_ratio[0], 0.2) << ch;
        EXPECT_NEAR(mc.range_ratio[0], 1.0, 0.05) << ch;
    }
    const std::string text = format_profile_report(r);
    EXPECT_NE(text.find("channel b: alpha' 0.677852"), std::string::npos) << text;
    std::istringstream tsv(profile_report_tsv(r));
    std::string line;
    int rows = 0;
    while (std::getline(tsv, line)) ++rows;
    EXPECT_EQ(rows, 1 + 3 * 3);
}

TEST(TruthProfileAccuracy, TableWriterNodesAndRatios) {
    McTableOptions o;
    o.eta = {1.0, 1.4};
    o.albedo = {0.5, 0.95};
    o.photons = 20'000;
    o.batches = 16;
    const std::string text = make_mc_table(o);
    std::istringstream in(text);
    std::string line;
    int ratios = 0;
    while (std::getline(in, line)) {
        if (line.rfind("ratio ", 0) != 0) continue;
        ++ratios;
        std::istringstream ls(line.substr(6));
        int e, a;
        ls >> e >> a;
        double x, lo = 1e9, hi = 0.0;
        int n = 0;
        while (ls >> x) lo = std::min(lo, x), hi = std::max(hi, x), ++n;
        EXPECT_EQ(n, 45) << line;
        // Photon beam diffusion is within tens of per cent of the walk.
        EXPECT_GT(lo, 0.5) << line;
        EXPECT_LT(hi, 1.6) << line;
    }
    EXPECT_EQ(ratios, 4);
    EXPECT_NE(text.find("\neta 1 1.4\n"), std::string::npos);
    o.albedo = {0.0};
    EXPECT_THROW(make_mc_table(o), ValueError);
}

} // namespace
