// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file slab_transport_test.cpp
/// The slab transport solution against a random walk through the same slab
/// (written here, one dimension, independent of the solver), for normal and
/// diffuse light, thin and thick, absorbing and not, matched and mismatched
/// boundaries; its limits (a thick slab transmits nothing, no light is made)
/// and what it refuses.

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "sss/diffusion/slab_transport.h"
#include "sss/util/error.h"

namespace {

using namespace sss;

double fresnel(double mu, double eta) { // from inside, index eta / 1
    const double s2 = (1.0 - mu * mu) * eta * eta;
    if (s2 >= 1.0) return 1.0;
    const double ct = std::sqrt(1.0 - s2);
    const double rs = (eta * mu - ct) / (eta * mu + ct),
                 rp = (mu - eta * ct) / (mu + eta * ct);
    return 0.5 * (rs * rs + rp * rp);
}

/// Scattered light out of the top and the bottom per path entering.
SlabLight walk(double alpha, double eta, double d, bool diffuse, int paths) {
    std::mt19937_64 rng(12345);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    SlabLight out;
    for (int p = 0; p < paths; ++p) {
        double mu = 1.0; // direction cosine, positive downwards
        if (diffuse) {
            double c = 0;
            do {
                c = std::sqrt(u(rng));
                const double s = std::sqrt(1.0 - c * c) / eta;
                mu = std::sqrt(1.0 - s * s);
            } while (u(rng) >= 1.0 - fresnel(mu, eta));
        }
        double z = 0, w = 1;
        bool scattered = false;
        for (int step = 0; step < 100000; ++step) {
            const double next = z + mu * -std::log(1.0 - u(rng));
            if (next > 0.0 && next < d) {
                z = next;
                w *= alpha;
                scattered = true;
                mu = 2.0 * u(rng) - 1.0;
                if (w < 1e-3) {
                    if (u(rng) >= 0.1) break;
                    w *= 10.0;
                }
                continue;
            }
            z = next >= d ? d : 0.0;
            if (u(rng) < fresnel(std::abs(mu), eta)) {
                mu = -mu;
                continue;
            }
            if (scattered) (z == d ? out.transmittance : out.reflectance) += w;
            break;
        }
    }
    out.reflectance /= paths;
    out.transmittance /= paths;
    return out;
}

struct Case {
    double alpha, eta, d;
    bool diffuse;
};

TEST(SlabTransport, AgreesWithTheWalk) {
    const Case cases[] = {{0.678, 1.3, 3.0, false}, {0.678, 1.3, 7.45, false},
                          {0.678, 1.3, 3.0, true},  {0.838, 1.3, 5.25, true},
                          {0.959, 1.3, 1.5, false}, {0.998, 1.5, 2.6, false},
                          {0.5, 1.0, 1.0, false},   {0.99, 1.6, 0.5, true}};
    for (const Case& c : cases) {
        const SlabLight t = slab_transport(c.alpha, c.eta, c.d, c.diffuse);
        const SlabLight w = walk(c.alpha, c.eta, c.d, c.diffuse, 200000);
        SCOPED_TRACE(testing::Message()
                     << "alpha " << c.alpha << " eta " << c.eta << " d " << c.d
                     << (c.diffuse ? " diffuse" : " normal"));
        EXPECT_NEAR(t.reflectance / w.reflectance, 1.0, 0.02);
        // The deep slab's transmission is a few thousand paths' worth.
        EXPECT_NEAR(t.transmittance / w.transmittance, 1.0, c.d > 7 ? 0.06 : 0.025);
    }
}

TEST(SlabTransport, Limits) {
    // Thick: nothing through, and the reflectance of a half-space.
    const SlabLight thick = slab_transport(0.9, 1.4, 30.0, false);
    const SlabLight thicker = slab_transport(0.9, 1.4, 36.0, false);
    EXPECT_LT(thick.transmittance, 1e-6);
    EXPECT_NEAR(thick.reflectance, thicker.reflectance, 1e-4);
    // No light is made, and without absorption none is lost but what
    // crosses unscattered (exp(-d) of a normal beam, less its reflections).
    for (double d : {0.2, 1.0, 4.0}) {
        const SlabLight s = slab_transport(0.999999, 1.0, d, false);
        EXPECT_NEAR(s.reflectance + s.transmittance + std::exp(-d), 1.0, 2e-3) << d;
        const SlabLight a = slab_transport(0.5, 1.33, d, true);
        EXPECT_LT(a.reflectance + a.transmittance, 0.5);
    }
    // Diffuse light enters shallower: back more, through less.
    const SlabLight n = slab_transport(0.8, 1.3, 5.0, false);
    const SlabLight f = slab_transport(0.8, 1.3, 5.0, true);
    EXPECT_GT(f.reflectance, n.reflectance);
    EXPECT_LT(f.transmittance, n.transmittance);
}

TEST(SlabTransport, DiffuseLightComesBackMoreTheMoreTheMediumAbsorbs) {
    // The walk of a deep slab under both lights (skin1's blue: about 1.08).
    const double r = diffuse_reflectance_ratio(0.678, 1.3);
    const SlabLight n = walk(0.678, 1.3, 30.0, false, 200000);
    const SlabLight d = walk(0.678, 1.3, 30.0, true, 200000);
    EXPECT_NEAR(r, d.reflectance / n.reflectance, 0.02);
    EXPECT_GT(r, diffuse_reflectance_ratio(0.84, 1.3));
    EXPECT_GT(diffuse_reflectance_ratio(0.84, 1.3),
              diffuse_reflectance_ratio(0.999, 1.3));
    EXPECT_GT(diffuse_reflectance_ratio(0.999, 1.3), 1.0);
}

TEST(SlabTransport, Refuses) {
    EXPECT_THROW(slab_transport(1.0, 1.3, 1.0, false), ValueError);
    EXPECT_THROW(slab_transport(-0.1, 1.3, 1.0, false), ValueError);
    EXPECT_THROW(slab_transport(0.5, 0.9, 1.0, false), ValueError);
    EXPECT_THROW(slab_transport(0.5, 1.3, 0.0, false), ValueError);
    EXPECT_THROW(slab_transport(0.5, 1.3, std::nan(""), false), ValueError);
}

} // namespace
