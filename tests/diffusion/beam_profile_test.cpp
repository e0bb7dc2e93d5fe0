// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file beam_profile_test.cpp
/// The sampled profiles (photon beam diffusion and the Monte-Carlo table):
/// their single-scattering part against an independent quadrature, the
/// dimensionless scaling, extremes of the coefficients and albedos, and the
/// table's range. Their disk integrals, inversion and positivity are checked
/// with the other profiles in material_profile_test.cpp.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "sss/diffusion/profile.h"
#include "sss/util/error.h"
#include "sss/util/math.h"

#include "diffusion_test_util.h"

namespace {

using sss::Profile;
using sss::ProfileKind;
constexpr double kInf = std::numeric_limits<double>::infinity();

using sss::test::fresnel_inside;

/// Single scattering under a normal pencil beam at radius r (sigma_t' = 1),
/// by a plain midpoint rule in the first collision's depth (independent of
/// the library's panels).
double single_scattering(double alpha, double eta, double r) {
    double sum = 0.0;
    const int n = 200000;
    const double zmax = 40.0, h = zmax / n;
    for (int i = 0; i < n; ++i) {
        double z = (i + 0.5) * h, d = std::hypot(r, z), mu = z / d;
        sum += std::exp(-z - d) * mu / (d * d) * (1.0 - fresnel_inside(mu, eta));
    }
    return alpha / (4.0 * sss::kPi) * sum * h;
}

TEST(ProfileBeam, LowAlbedoIsSingleScattering) {
    // At alpha' = 0.02 multiple scattering is a few per cent of single
    // scattering within a mean free path (alpha'^2 against alpha'): there the
    // profile is the exact single scattering. Further out multiple
    // scattering, which decays more slowly, takes over.
    for (double eta : {1.0, 1.3, 1.5}) {
        Profile p = Profile::from_coefficients(ProfileKind::Pbd, {0.02, 0.98, eta});
        for (double r : {0.01, 0.05, 0.3}) {
            double ss = single_scattering(0.02, eta, r);
            EXPECT_GT(p.eval(r), ss) << "eta " << eta << " r " << r;
            EXPECT_LT(p.eval(r), 1.03 * ss) << "eta " << eta << " r " << r;
        }
        EXPECT_GT(p.eval(3.0), 1.05 * single_scattering(0.02, eta, 3.0)) << eta;
    }
}

TEST(ProfileBeam, ScalesWithTheTransportMeanFreePath) {
    // R(r) for sigma_t' = s is s^2 R_1(r s): the curve is universal.
    for (ProfileKind kind : {ProfileKind::Pbd, ProfileKind::Mc}) {
        Profile one = Profile::from_coefficients(kind, {0.9, 0.1, 1.3});
        Profile ten = Profile::from_coefficients(kind, {9.0, 1.0, 1.3});
        for (double r : {0.01, 0.5, 2.0, 20.0}) {
            EXPECT_NEAR(ten.eval(r / 10.0), 100.0 * one.eval(r),
                        1e-9 * 100.0 * one.eval(r));
            EXPECT_NEAR(ten.disk(r / 10.0), one.disk(r), 1e-12);
        }
        EXPECT_DOUBLE_EQ(ten.total(), one.total());
        EXPECT_NEAR(ten.dmfp(), one.dmfp() / 10.0, 1e-12 * one.dmfp());
        EXPECT_EQ(one.core_length(), 0.0);
        EXPECT_TRUE(std::isinf(one.eval(0.0)));
    }
}

TEST(ProfileBeam, ExtremeCoefficientsStayFinite) {
    for (ProfileKind kind : {ProfileKind::Pbd, ProfileKind::Mc}) {
        double prev_total = 2.0;
        for (double sa : {0.0, 1e-9, 1e-6, 1e-3, 1.0, 1e3, 1e6, 1e12}) {
            SCOPED_TRACE(std::string(sss::profile_kind_name(kind)) + " sigma_a " +
                         std::to_string(sa));
            Profile p = Profile::from_coefficients(kind, {1.0, sa, 1.3});
            ASSERT_TRUE(std::isfinite(p.total()));
            // Less light comes back the more is absorbed. Without absorption
            // photon beam diffusion returns 3.5 % more than entered (its far
            // field); the Monte-Carlo profile's tail keeps the walk's total, 1.
            EXPECT_GT(p.total(), 0.0);
            EXPECT_LE(p.total(), kind == ProfileKind::Pbd ? 1.04 : 1.0 + 1e-3);
            if (kind == ProfileKind::Mc && sa == 0.0) EXPECT_NEAR(p.total(), 1.0, 1e-3);
            EXPECT_LE(p.total(), prev_total);
            prev_total = p.total();
            double prev = 0.0;
            for (double r : {1e-12, 1e-6, 1e-3, 1.0, 1e3, 1e6}) {
                ASSERT_TRUE(std::isfinite(p.eval(r)) && p.eval(r) >= 0.0) << r;
                const double d = p.disk(r);
                ASSERT_TRUE(std::isfinite(d) && d >= prev) << r;
                prev = d;
            }
            EXPECT_EQ(p.disk(kInf), p.total());
        }
        // No scattering: nothing comes back.
        Profile none = Profile::from_coefficients(kind, {0.0, 1.0, 1.3});
        EXPECT_EQ(none.total(), 0.0);
        EXPECT_EQ(none.eval(1.0), 0.0);
        EXPECT_EQ(none.disk(1.0), 0.0);
    }
}

TEST(ProfileBeam, AlbedosNearZeroAndOne) {
    for (ProfileKind kind : {ProfileKind::Pbd, ProfileKind::Mc}) {
        for (double a : {1e-9, 1e-4, 0.95, 0.99, 0.999}) {
            Profile p = Profile::from_albedo_dmfp(kind, a, 2.0, 1.3);
            EXPECT_NEAR(p.total(), a, 1e-8 + 1e-6 * a)
                << sss::profile_kind_name(kind) << a;
            EXPECT_NEAR(p.dmfp(), 2.0, 1e-9) << sss::profile_kind_name(kind) << a;
        }
    }
}

TEST(ProfileBeam, MonteCarloTableRangeAndCloseness) {
    // The table covers ior 1.0 to 1.6; outside it the error names pbd.
    try {
        Profile::from_coefficients(ProfileKind::Mc, {1.0, 0.1, 2.0});
        FAIL() << "ior 2 accepted";
    } catch (const sss::ValueError& e) {
        EXPECT_NE(std::string(e.what()).find("-profile pbd"), std::string::npos)
            << e.what();
    }
    EXPECT_THROW(Profile::from_albedo_dmfp(ProfileKind::Mc, 0.5, 1.0, 0.9),
                 sss::ValueError);
    // The walk corrects photon beam diffusion by a few per cent to a few tens
    // near the beam and in the far tail, not by factors.
    for (double alpha : {0.05, 0.5, 0.9, 0.999}) {
        Profile pbd =
            Profile::from_coefficients(ProfileKind::Pbd, {alpha, 1 - alpha, 1.3});
        Profile mc = Profile::from_coefficients(ProfileKind::Mc, {alpha, 1 - alpha, 1.3});
        EXPECT_NEAR(mc.total() / pbd.total(), 1.0, 0.15) << alpha;
        for (double r : {0.01, 0.3, 1.0, 3.0})
            EXPECT_NEAR(mc.eval(r) / pbd.eval(r), 1.0, 0.35) << alpha << " r " << r;
    }
}

} // namespace
