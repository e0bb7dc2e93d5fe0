// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// Per-point materials: the quantised profiles with each receiver's gain
// against every receiver's own, unquantised material, and the gain itself
// through the library's evaluations.

#include <cmath>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>

#include "sss/cloud/synthetic.h"
#include "sss/diffusion/diffusion.h"
#include "sss/diffusion/ssdiffusion.h"
#include "sss/util/error.h"

#include "diffusion_test_util.h"

namespace {

constexpr double kIor = 1.5;

// A lit sphere whose albedo and mean free path vary continuously over the
// surface, between lo and hi per channel (the mean free path in octaves), in
// patches about `patch` mm across: far more distinct values than profiles.
struct Variation {
    double radius;
    glm::dvec3 albedo_lo, albedo_hi, dmfp_lo, dmfp_hi;
    double patch;
};

sss::PointCloud varying_sphere(std::size_t n, const Variation& v) {
    sss::PointCloud c = sss::test::synthetic(sss::SyntheticShape::Sphere, n, v.radius);
    std::vector<float>& a = c.add_channel("_albedo", sss::ChannelType::Color).data;
    std::vector<float>& d =
        c.add_channel("_diffusemeanfreepath", sss::ChannelType::Color).data;
    a.resize(3 * c.size());
    d.resize(3 * c.size());
    for (std::size_t i = 0; i < c.size(); ++i) {
        const glm::dvec3 p = glm::dvec3(c.positions[i]) / v.patch;
        for (int ch = 0; ch < 3; ++ch) {
            const double s = 0.5 + 0.5 * std::sin(p.x + ch) * std::cos(p.y / 1.5);
            const double t = 0.5 + 0.5 * std::cos(p.z / 1.25 + ch);
            a[3 * i + ch] =
                float(v.albedo_lo[ch] + s * (v.albedo_hi[ch] - v.albedo_lo[ch]));
            d[3 * i + ch] =
                float(v.dmfp_lo[ch] * std::pow(v.dmfp_hi[ch] / v.dmfp_lo[ch], t));
        }
    }
    return c;
}

// ssdiffusion with the cloud's own per-point materials against an exact sum
// in which each of 200 receivers has its own material as read: per channel,
// RMS and largest error over the receivers, as fractions of their mean.
void error_against_own_materials(const sss::PointCloud& cloud, glm::dvec3& rms,
                                 glm::dvec3& worst, std::size_t& profiles) {
    sss::SsDiffusionOptions o;
    o.material.albedo_from_file = o.material.dmfp_from_file = true;
    o.material.ior = kIor;
    sss::SsDiffusionReport rep;
    const sss::PointCloud out = sss::ssdiffusion(cloud, o, &rep);
    profiles = rep.distinct_profiles;
    const std::vector<float>& h = out.find_channel("_ssdiffusion")->data;
    // (The other points' materials do not enter a receiver's sum.)
    sss::DiffusionProblem pb = sss::test::problem_from(cloud, {});
    for (int ch = 0; ch < 3; ++ch)
        pb.profiles.push_back(
            sss::Profile::from_albedo_dmfp(sss::ProfileKind::Classic, 0.5, 1.0, kIor));
    pb.profile_index.assign(cloud.size(), glm::u32vec3(0, 1, 2));
    const std::vector<float>& a = cloud.find_channel("_albedo")->data;
    const std::vector<float>& d = cloud.find_channel("_diffusemeanfreepath")->data;
    std::vector<std::size_t> rec;
    for (std::size_t k = 0; k < 200; ++k) rec.push_back(k * cloud.size() / 200 + 7);
    for (std::size_t i : rec)
        for (int ch = 0; ch < 3; ++ch) {
            pb.profile_index[i][ch] = uint32_t(pb.profiles.size());
            pb.profiles.push_back(sss::Profile::from_albedo_dmfp(
                sss::ProfileKind::Classic, a[3 * i + ch], d[3 * i + ch], kIor));
        }
    const std::vector<glm::dvec3> e = sss::evaluate_diffusion_exact(pb, rec);
    for (int ch = 0; ch < 3; ++ch) {
        double mean = 0, sq = 0;
        worst[ch] = 0;
        for (const glm::dvec3& v : e) mean += std::abs(v[ch]) / double(e.size());
        for (std::size_t k = 0; k < rec.size(); ++k) {
            const double err = (double(h[3 * rec[k] + ch]) - e[k][ch]) / mean;
            sq += err * err / double(rec.size());
            worst[ch] = std::max(worst[ch], std::abs(err));
        }
        rms[ch] = std::sqrt(sq);
        std::printf("  channel %d: %zu profiles, RMS %.5f, largest %.5f of the mean\n",
                    ch, profiles, rms[ch], worst[ch]);
    }
}

// The sphere's error against its receivers' own materials, per channel
// within `rms_limit` (RMS) and `worst_limit` (largest), with at most 128
// profiles.
void expect_within(const Variation& v, double rms_limit, double worst_limit) {
    glm::dvec3 rms, worst;
    std::size_t profiles = 0;
    error_against_own_materials(varying_sphere(30000, v), rms, worst, profiles);
    EXPECT_LE(profiles, 128u);
    for (int ch = 0; ch < 3; ++ch) {
        EXPECT_LT(rms[ch], rms_limit) << "channel " << ch;
        EXPECT_LT(worst[ch], worst_limit) << "channel " << ch;
    }
}

// A painted object: the ranges of per_point_bench's sphere (albedo 0.2 wide,
// 1.4 octaves of mean free path per channel) in patches a few mm across.
// Measured RMS 0.0015-0.0033 (largest 0.007-0.019) with 115 profiles; each
// receiver with its table's albedo instead of its own: RMS 0.04-0.06; the
// earlier quantisation to at most 1024 profiles without the gains: RMS
// 0.0036-0.0041 (largest 0.010-0.020).
TEST(PerPointMaterials, PaintedSphereKeepsEachReceiversOwnResult) {
    expect_within(
        {25.0, {0.6, 0.5, 0.4}, {0.8, 0.7, 0.6}, {3.0, 2.0, 1.5}, {8.0, 5.5, 4.0}, 4.0},
        0.005, 0.03);
}

// A hard case: most of the albedo range and four octaves of mean free path
// on a sphere no wider than the longest, so the quantisation is coarse.
// Measured RMS 0.010-0.016 (largest 0.06-0.14) with 117 profiles; each
// receiver with its table's albedo instead of its own: RMS 0.11-0.13; the
// earlier quantisation to at most 1024 profiles without the gains: RMS
// 0.011-0.021 (largest 0.04-0.15).
TEST(PerPointMaterials, WideRangesStayWithinTheQuantisationsError) {
    expect_within({10.0,
                   {0.2, 0.2, 0.2},
                   {0.95, 0.95, 0.95},
                   {0.5, 0.5, 0.5},
                   {8.0, 8.0, 8.0},
                   2.0},
                  0.025, 0.2);
}

// The quantisation reads the points in parallel chunks: an impossible value
// is still reported at the first such point in the cloud's order.
TEST(PerPointMaterials, FirstImpossibleValueIsNamed) {
    const Variation v{
        25.0, {0.6, 0.5, 0.4}, {0.8, 0.7, 0.6}, {3.0, 2.0, 1.5}, {8.0, 5.5, 4.0}, 4.0};
    sss::PointCloud cloud = varying_sphere(60000, v);
    std::vector<float>& d = cloud.find_channel("_diffusemeanfreepath")->data;
    d[3 * 45000 + 2] = -1.0f;
    d[3 * 20001 + 1] = 0.0f;
    sss::SsDiffusionOptions o;
    o.material.albedo_from_file = o.material.dmfp_from_file = true;
    try {
        sss::ssdiffusion(cloud, o);
        FAIL() << "no error";
    } catch (const sss::ValueError& e) {
        EXPECT_NE(std::string(e.what()).find("at point 20001"), std::string::npos)
            << e.what();
    }
}

sss::DiffusionProblem lit_sphere_problem() {
    return sss::test::problem_from(
        sss::test::synthetic(sss::SyntheticShape::Sphere, 4000, 10.0),
        sss::test::material_profiles("skin1"));
}

TEST(PerPointMaterials, ReceiverGainScalesEachResult) {
    const sss::DiffusionProblem pb = lit_sphere_problem();
    sss::DiffusionProblem scaled = pb;
    scaled.receiver_gain.resize(pb.positions.size());
    for (std::size_t i = 0; i < pb.positions.size(); ++i)
        scaled.receiver_gain[i] = glm::vec3(2.0f, 0.5f, i % 2 ? 4.0f : 0.0f);
    const std::vector<glm::vec3> plain = sss::evaluate_diffusion(pb, {});
    const std::vector<glm::vec3> gained = sss::evaluate_diffusion(scaled, {});
    const std::vector<std::size_t> rec = {0, 1, 1234, 3999};
    const std::vector<glm::dvec3> exact = sss::evaluate_diffusion_exact(pb, rec);
    const std::vector<glm::dvec3> exact_gained =
        sss::evaluate_diffusion_exact(scaled, rec);
    // Powers of two: the same bits scaled.
    for (std::size_t i = 0; i < pb.positions.size(); ++i)
        ASSERT_EQ(gained[i], plain[i] * scaled.receiver_gain[i]) << "point " << i;
    for (std::size_t k = 0; k < rec.size(); ++k)
        EXPECT_EQ(exact_gained[k], exact[k] * glm::dvec3(scaled.receiver_gain[rec[k]]));
    // The moved problem (whose arrays the octree takes over) as well.
    sss::DiffusionProblem moved = scaled;
    EXPECT_EQ(sss::evaluate_diffusion(std::move(moved), {}), gained);
}

TEST(PerPointMaterials, ReceiverGainOfTheWrongSizeIsRefused) {
    sss::DiffusionProblem pb = lit_sphere_problem();
    pb.receiver_gain.assign(pb.positions.size() - 1, glm::vec3(1.0f));
    try {
        sss::evaluate_diffusion(pb, {});
        FAIL() << "no error";
    } catch (const sss::ValueError& e) {
        EXPECT_NE(std::string(e.what()).find("3999 receiver gains for 4000 points"),
                  std::string::npos)
            << e.what();
    }
}

} // namespace
