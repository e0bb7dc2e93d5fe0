// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file volume_test.cpp
/// The volume diffusion (ptfilter -volume 1, -blocker): the light it lets
/// out never exceeds what entered and its fluxes balance, a shape thick
/// against the material keeps the profile's result bit for bit, a thin slab
/// transmits more than a thick one, a blocker absorbs light and darkens the
/// surface above it, results do not depend on the thread count, and what it
/// refuses.

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include <glm/geometric.hpp>

#include "sss/diffusion/material.h"
#include "sss/diffusion/profile.h"
#include "sss/diffusion/slab_transport.h"
#include "sss/diffusion/volume.h"
#include "sss/util/error.h"
#include "sss/util/threads.h"

namespace {

using namespace sss;

/// An nu x nv grid of samples over corner + [0, 1] eu + [0, 1] ev, facing
/// cross(eu, ev).
void add_face(SurfaceSamples& s, std::vector<glm::vec3>* irradiance, glm::vec3 corner,
              glm::vec3 eu, glm::vec3 ev, int nu, int nv, float e) {
    const glm::vec3 n = glm::cross(eu, ev);
    const float area = glm::length(n) / float(nu * nv);
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
            s.positions.push_back(corner + (float(i) + 0.5f) / float(nu) * eu +
                                  (float(j) + 0.5f) / float(nv) * ev);
            s.normals.push_back(glm::normalize(n));
            s.areas.push_back(area);
            if (irradiance) irradiance->push_back(glm::vec3(e));
        }
}

/// The box lo..hi sampled at about `spacing`, outward normals; the top face
/// (z = hi.z) lit with irradiance 1 when `irradiance` is given.
void box(SurfaceSamples& s, std::vector<glm::vec3>* irradiance, glm::vec3 lo,
         glm::vec3 hi, float spacing) {
    const glm::vec3 d = hi - lo;
    const auto cells = [&](float len) {
        return std::max(1, int(std::lround(len / spacing)));
    };
    const int nx = cells(d.x), ny = cells(d.y), nz = cells(d.z);
    const glm::vec3 X(d.x, 0, 0), Y(0, d.y, 0), Z(0, 0, d.z);
    add_face(s, irradiance, {lo.x, lo.y, hi.z}, X, Y, nx, ny, 1.0f); // top, +z
    add_face(s, irradiance, lo, Y, X, ny, nx, 0.0f);                 // bottom, -z
    add_face(s, irradiance, lo, X, Z, nx, nz, 0.0f);                 // -y
    add_face(s, irradiance, {lo.x, hi.y, lo.z}, Z, X, nz, nx, 0.0f); // +y
    add_face(s, irradiance, lo, Z, Y, nz, ny, 0.0f);                 // -x
    add_face(s, irradiance, {hi.x, lo.y, lo.z}, Y, Z, ny, nz, 0.0f); // +x
}

struct Case {
    SurfaceSamples surface;
    std::vector<glm::vec3> irradiance;
    std::vector<glm::vec3> profile; // a stand-in for the profile's result
    ChannelCoefficients channels[3];
    glm::dvec3 reflectance{0.0}; // the classic profile's half-space reflectance
};

/// A w x w x d slab (mm) of a named material, lit on top.
Case slab(const char* material, float w, float d, float spacing) {
    Case c;
    box(c.surface, &c.irradiance, {-w / 2, -w / 2, -d}, {w / 2, w / 2, 0.0f}, spacing);
    c.profile.assign(c.surface.positions.size(), glm::vec3(0.125f, 0.25f, 0.5f));
    const NamedMaterial* m = find_material(material);
    for (int k = 0; k < 3; ++k) {
        c.channels[k] = {m->sigma_s_prime[k], m->sigma_a[k], m->ior};
        c.reflectance[k] =
            Profile::from_coefficients(ProfileKind::Classic, c.channels[k]).total();
    }
    return c;
}

/// Area-weighted mean of a result over the points of one face region.
glm::dvec3 mean_where(const Case& c, const std::vector<glm::vec3>& v, float z,
                      float half) {
    glm::dvec3 s(0.0);
    double a = 0;
    for (std::size_t j = 0; j < v.size(); ++j) {
        const glm::vec3& p = c.surface.positions[j];
        if (std::abs(p.z - z) > 1e-4f || std::abs(p.x) > half || std::abs(p.y) > half)
            continue;
        s += glm::dvec3(v[j]) * double(c.surface.areas[j]);
        a += c.surface.areas[j];
    }
    return s / a;
}

double flux_of(const Case& c, const std::vector<glm::vec3>& v, int ch) {
    double s = 0;
    for (std::size_t j = 0; j < v.size(); ++j) s += double(v[j][ch]) * c.surface.areas[j];
    return s;
}

TEST(Volume, LightOutNeverExceedsLightInAndTheFluxesBalance) {
    for (float d : {1.0f, 2.0f}) {
        const Case c = slab("marble", 12.0f, d, 0.25f);
        VolumeReport rep;
        const std::vector<glm::vec3> out = volume_diffusion(
            c.surface, c.irradiance, c.channels, c.reflectance, {}, c.profile, {}, &rep);
        ASSERT_TRUE(rep.needed);
        EXPECT_EQ(rep.thin_points, c.surface.positions.size());
        const double in = 12.0 * 12.0; // the lit top face, irradiance 1
        for (int ch = 0; ch < 3; ++ch) {
            SCOPED_TRACE(ch);
            EXPECT_LE(flux_of(c, out, ch), in);
            EXPECT_LE(rep.flux_in[ch], in);
            EXPECT_GT(rep.flux_out[ch], 0.5 * rep.flux_in[ch]);
            const double balance = rep.flux_out[ch] + rep.flux_absorbed[ch];
            EXPECT_NEAR(balance / rep.flux_in[ch], 1.0, 0.01);
            // The points give off what the solve lets out, what came
            // through corrected to transport theory (by factors the report
            // bounds), and the profile's reflectance where the grid's falls
            // short of it.
            const double lo = std::min(1.0, rep.transmission_min[ch]),
                         hi = std::max(1.0, rep.transmission_max[ch]);
            EXPECT_GE(lo, 0.2);
            EXPECT_LE(hi, 5.0);
            const double extra = rep.reflectance_correction[ch] * in;
            EXPECT_GE(flux_of(c, out, ch), (lo * rep.flux_out[ch] + extra) * (1 - 1e-3));
            EXPECT_LE(flux_of(c, out, ch), (hi * rep.flux_out[ch] + extra) * (1 + 1e-3));
        }
    }
}

TEST(Volume, AThinSlabTransmitsMoreThanAThickOne) {
    const Case thin = slab("marble", 16.0f, 1.0f, 0.25f),
               thick = slab("marble", 16.0f, 4.0f, 0.25f);
    // Every point takes the volume's result, not a blend with the profile's.
    VolumeOptions o;
    o.thin_dmfp = 100.0;
    o.thick_dmfp = 200.0;
    const std::vector<glm::vec3> a =
        volume_diffusion(thin.surface, thin.irradiance, thin.channels, thin.reflectance,
                         {}, thin.profile, o);
    const std::vector<glm::vec3> b =
        volume_diffusion(thick.surface, thick.irradiance, thick.channels,
                         thick.reflectance, {}, thick.profile, o);
    const glm::dvec3 ta = mean_where(thin, a, -1.0f, 3.0f),
                     tb = mean_where(thick, b, -4.0f, 3.0f);
    const glm::dvec3 ra = mean_where(thin, a, 0.0f, 3.0f),
                     rb = mean_where(thick, b, 0.0f, 3.0f);
    for (int ch = 0; ch < 3; ++ch) {
        SCOPED_TRACE(ch);
        EXPECT_GT(ta[ch], 1.5 * tb[ch]);
        EXPECT_LT(ra[ch], rb[ch]); // what a thin slab transmits, it does not reflect
        EXPECT_GT(ta[ch], 0.0);
    }
}

TEST(Volume, AThickShapeKeepsTheProfilesResultBitForBit) {
    // 60 mm of skin1 is 16 dmfp in red: nothing is thin.
    const Case c = slab("skin1", 60.0f, 60.0f, 2.0f);
    VolumeReport rep;
    const std::vector<glm::vec3> out = volume_diffusion(
        c.surface, c.irradiance, c.channels, c.reflectance, {}, c.profile, {}, &rep);
    EXPECT_FALSE(rep.needed);
    EXPECT_EQ(rep.thin_points, 0u);
    ASSERT_EQ(out.size(), c.profile.size());
    for (std::size_t j = 0; j < out.size(); ++j) ASSERT_EQ(out[j], c.profile[j]) << j;
    // Under diffuse light the profile's result comes back raised by transport
    // theory's ratio for a deep slab (more the more the medium absorbs).
    VolumeOptions o;
    o.diffuse_light = true;
    VolumeReport drep;
    const std::vector<glm::vec3> diffuse = volume_diffusion(
        c.surface, c.irradiance, c.channels, c.reflectance, {}, c.profile, o, &drep);
    EXPECT_FALSE(drep.needed);
    EXPECT_GT(drep.diffuse_ratio.x, 1.0);
    EXPECT_GT(drep.diffuse_ratio.z, drep.diffuse_ratio.x);
    for (int ch = 0; ch < 3; ++ch) {
        const NamedMaterial* m = find_material("skin1");
        const double alpha =
            m->sigma_s_prime[ch] / (m->sigma_s_prime[ch] + m->sigma_a[ch]);
        EXPECT_DOUBLE_EQ(drep.diffuse_ratio[ch],
                         diffuse_reflectance_ratio(alpha, m->ior));
        for (std::size_t j = 0; j < out.size(); j += 97)
            ASSERT_FLOAT_EQ(diffuse[j][ch],
                            float(c.profile[j][ch] * drep.diffuse_ratio[ch]));
    }
}

TEST(Volume, ABlockerAbsorbsLightAndDarkensTheSurfaceAboveIt) {
    const Case c = slab("skin1", 16.0f, 6.0f, 0.25f);
    SurfaceSamples bone;
    box(bone, nullptr, {-3.0f, -3.0f, -4.0f}, {3.0f, 3.0f, -1.5f}, 0.25f);
    VolumeReport with, without;
    const std::vector<glm::vec3> a = volume_diffusion(
        c.surface, c.irradiance, c.channels, c.reflectance, {bone}, c.profile, {}, &with);
    const std::vector<glm::vec3> b = volume_diffusion(
        c.surface, c.irradiance, c.channels, c.reflectance, {}, c.profile, {}, &without);
    const glm::dvec3 above_a = mean_where(c, a, 0.0f, 2.0f),
                     above_b = mean_where(c, b, 0.0f, 2.0f);
    const glm::dvec3 below_a = mean_where(c, a, -6.0f, 2.0f),
                     below_b = mean_where(c, b, -6.0f, 2.0f);
    for (int ch = 0; ch < 3; ++ch) {
        SCOPED_TRACE(ch);
        EXPECT_GT(with.flux_blocked[ch], 0.0);
        EXPECT_EQ(without.flux_blocked[ch], 0.0);
        const double balance =
            with.flux_out[ch] + with.flux_absorbed[ch] + with.flux_blocked[ch];
        EXPECT_NEAR(balance / with.flux_in[ch], 1.0, 0.01);
        EXPECT_LT(above_a[ch], above_b[ch]);
    }
    // The far face, behind the bone, in red (the channel that reaches it).
    EXPECT_LT(below_a[0], 0.7 * below_b[0]);
}

TEST(Volume, ResultsDoNotDependOnTheThreadCount) {
    const Case c = slab("marble", 10.0f, 1.5f, 0.2f);
    std::vector<glm::vec3> one, two;
    {
        ThreadLimit limit(1);
        one = volume_diffusion(c.surface, c.irradiance, c.channels, c.reflectance, {},
                               c.profile, {});
    }
    {
        ThreadLimit limit(2);
        two = volume_diffusion(c.surface, c.irradiance, c.channels, c.reflectance, {},
                               c.profile, {});
    }
    ASSERT_EQ(one.size(), two.size());
    for (std::size_t j = 0; j < one.size(); ++j) ASSERT_EQ(one[j], two[j]) << j;
}

TEST(Volume, Refuses) {
    Case c = slab("marble", 4.0f, 1.0f, 0.5f);
    std::vector<glm::vec3> short_profile(c.profile.begin(), c.profile.end() - 1);
    EXPECT_THROW(volume_diffusion(c.surface, c.irradiance, c.channels, c.reflectance, {},
                                  short_profile, {}),
                 ValueError);
    c.channels[1].sigma_s_prime = 0.0;
    EXPECT_THROW(volume_diffusion(c.surface, c.irradiance, c.channels, c.reflectance, {},
                                  c.profile, {}),
                 ValueError);
}

} // namespace
