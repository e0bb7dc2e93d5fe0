// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file diffusion_test.cpp
/// Tests of the diffusion evaluation (sss/diffusion.h) and of the
/// ptfilter -ssdiffusion job (sss/ssdiffusion.h): the flat-plane energy
/// check, hierarchical against exact evaluation, determinism across thread
/// counts, degenerate clouds, signed irradiance and per-point materials.
///
/// Suite names all contain "Diffusion" so `ctest -R Diffusion` selects them.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "sss/cloud/point_cloud.h"
#include "sss/cloud/synthetic.h"
#include "sss/diffusion/diffusion.h"
#include "sss/diffusion/material.h"
#include "sss/diffusion/profile.h"
#include "sss/diffusion/ssdiffusion.h"
#include "sss/util/error.h"
#include "sss/util/progress.h"
#include "sss/util/threads.h"

#include "diffusion_test_util.h"

namespace {

constexpr double kPi = std::numbers::pi;

const sss::NamedMaterial& material(const char* name) {
    const sss::NamedMaterial* m = sss::find_material(name);
    if (!m) throw std::runtime_error(std::string("test needs material ") + name);
    return *m;
}

using sss::test::material_profiles;
using sss::test::problem_from;

sss::PointCloud sphere_cloud(std::size_t n, double radius,
                             glm::dvec3 light = {1, 0.5, 2}) {
    sss::SyntheticParams sp;
    sp.shape = sss::SyntheticShape::Sphere;
    sp.count = n;
    sp.size = radius;
    sp.light_dir = light;
    return sss::make_synthetic_cloud(sp);
}

sss::PointCloud box_cloud(std::size_t n, double side, double thickness,
                          glm::dvec3 light = {0.3, 0.2, 1}) {
    sss::SyntheticParams sp;
    sp.shape = sss::SyntheticShape::Box;
    sp.count = n;
    sp.size = side;
    sp.thickness = thickness;
    sp.light_dir = light;
    return sss::make_synthetic_cloud(sp);
}

sss::PointCloud plane_cloud(double side, double spacing) {
    sss::SyntheticParams sp;
    sp.shape = sss::SyntheticShape::Plane;
    sp.size = side;
    double per_side = std::round(side / spacing);
    sp.count = std::size_t(per_side * per_side);
    sp.light_dir = {0, 0, 1};
    sp.light_color = {1, 1, 1};
    return sss::make_synthetic_cloud(sp);
}

/// ~count receivers spread evenly over the index range.
std::vector<std::size_t> sample_receivers(std::size_t n, std::size_t count = 200) {
    std::vector<std::size_t> out;
    if (n == 0) return out;
    count = std::min(count, n);
    for (std::size_t k = 0; k < count; ++k)
        out.push_back(k * n / count + (n / count) / 2);
    return out;
}

/// Per channel: RMS over receivers of |h - e| / mean |e|.
glm::dvec3 relative_rms(const std::vector<glm::vec3>& h, const std::vector<glm::dvec3>& e,
                        const std::vector<std::size_t>& receivers) {
    glm::dvec3 out(0.0);
    for (int ch = 0; ch < 3; ++ch) {
        double mean = 0.0, sq = 0.0;
        for (std::size_t k = 0; k < receivers.size(); ++k) mean += std::abs(e[k][ch]);
        mean /= double(receivers.size());
        for (std::size_t k = 0; k < receivers.size(); ++k) {
            double d = double(h[receivers[k]][ch]) - e[k][ch];
            sq += d * d;
        }
        out[ch] = mean > 0 ? std::sqrt(sq / double(receivers.size())) / mean : 0.0;
    }
    return out;
}

double max3(const glm::dvec3& v) {
    return std::max({v.x, v.y, v.z});
}

bool all_finite(const std::vector<glm::vec3>& v) {
    for (const glm::vec3& x : v)
        if (!std::isfinite(x.x) || !std::isfinite(x.y) || !std::isfinite(x.z))
            return false;
    return true;
}

bool bitwise_equal(const std::vector<glm::vec3>& a, const std::vector<glm::vec3>& b) {
    return a.size() == b.size() &&
           (a.empty() ||
            std::memcmp(a.data(), b.data(), a.size() * sizeof(glm::vec3)) == 0);
}

/// Hierarchical result and its error against the exact one on sampled receivers.
struct Comparison {
    std::vector<glm::vec3> h;
    glm::dvec3 rms;
};

Comparison compare_with_exact(const sss::DiffusionProblem& pb,
                              const sss::DiffusionOptions& opt,
                              std::size_t samples = 200) {
    Comparison c;
    c.h = sss::evaluate_diffusion(pb, opt);
    std::vector<std::size_t> rec = sample_receivers(pb.positions.size(), samples);
    std::vector<glm::dvec3> e = sss::evaluate_diffusion_exact(pb, rec);
    c.rms = relative_rms(c.h, e, rec);
    return c;
}

// ---------------------------------------------------------------------------
// Flat plane through sss::ssdiffusion.

/// Per channel median of _ssdiffusion / expected over points within `radius`
/// of the plane's centre.
glm::dvec3 central_median_ratio(const sss::PointCloud& out, double radius,
                                const glm::dvec3& expected) {
    const sss::Channel* ch = out.find_channel("_ssdiffusion");
    if (!ch) throw std::runtime_error("no _ssdiffusion channel");
    glm::dvec3 med(0.0);
    for (int c = 0; c < 3; ++c) {
        std::vector<double> v;
        for (std::size_t i = 0; i < out.size(); ++i) {
            const glm::vec3& p = out.positions[i];
            if (std::hypot(p.x, p.y) <= radius)
                v.push_back(ch->data[3 * i + c] / expected[c]);
        }
        if (v.empty()) throw std::runtime_error("no central points");
        std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
        med[c] = v[v.size() / 2];
    }
    return med;
}

struct PlaneCase {
    const char* material;
    sss::ProfileKind kind;
    double spacing_over_zr; // spacing in units of the red channel's z_r
};

/// Runs the plane case; returns the per-channel median ratio and the point count.
glm::dvec3 run_plane(const PlaneCase& pc, std::size_t* points = nullptr) {
    const double unitlength = 1.0;
    std::vector<sss::Profile> prof = material_profiles(pc.material, unitlength, pc.kind);
    const sss::NamedMaterial& m = material(pc.material);
    double zr = 1.0 / (m.sigma_s_prime.x + m.sigma_a.x) * unitlength; // red channel
    double dmax = 0.0;
    for (const sss::Profile& p : prof) dmax = std::max(dmax, p.dmfp());
    const double side = 20.0 * dmax, spacing = pc.spacing_over_zr * zr;
    sss::PointCloud cloud = plane_cloud(side, spacing);
    if (points) *points = cloud.size();
    sss::SsDiffusionOptions o;
    o.material.preset = pc.material;
    o.material.unitlength = unitlength;
    o.profile = pc.kind;
    sss::PointCloud out = sss::ssdiffusion(cloud, o);
    EXPECT_EQ(out.size(), cloud.size());
    glm::dvec3 expected(prof[0].total(), prof[1].total(), prof[2].total());
    // Central points: within one largest dmfp (and at least 3 spacings) of the centre.
    return central_median_ratio(out, std::max(dmax, 3.0 * spacing), expected);
}

void expect_plane_ratio(const PlaneCase& pc) {
    std::size_t n = 0;
    sss::Stopwatch watch;
    glm::dvec3 r = run_plane(pc, &n);
    std::printf(
        "  plane %s %s spacing %.2f z_r: %zu points, ratio %.4f %.4f %.4f (%.2f s)\n",
        pc.material, sss::profile_kind_name(pc.kind), pc.spacing_over_zr, n, r.x, r.y,
        r.z, watch.seconds());
    for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(r[c], 1.0, 0.01)
            << pc.material << " " << sss::profile_kind_name(pc.kind) << " spacing "
            << pc.spacing_over_zr << " z_r, channel " << c << " (" << n << " points)";
}

} // namespace

// ---------------------------------------------------------------------------
// Flat plane: a uniformly lit, large plane gives albedo x E.
// ---------------------------------------------------------------------------

TEST(DiffusionFlatPlane, ClassicWellSampled) {
    // skin1: dmfp / z_r is small, so a plane 20 dmfp wide at 0.2 z_r (red)
    // spacing stays near 80k points (marble would need 3.5 million).
    expect_plane_ratio({"skin1", sss::ProfileKind::Classic, 0.2});
}

TEST(DiffusionFlatPlane, ClassicUnderSampled) {
    expect_plane_ratio({"marble", sss::ProfileKind::Classic, 2.2});
    expect_plane_ratio({"marble", sss::ProfileKind::Classic, 3.0});
    expect_plane_ratio({"marble", sss::ProfileKind::Classic, 4.0});
}

TEST(DiffusionFlatPlane, BetterDipoleWellSampled) {
    expect_plane_ratio({"skin1", sss::ProfileKind::Better, 0.2});
}

TEST(DiffusionFlatPlane, BurleyWellSampled) {
    expect_plane_ratio({"skin1", sss::ProfileKind::Burley, 0.2});
}

TEST(DiffusionFlatPlane, BeamDiffusionAndMonteCarloWellSampled) {
    expect_plane_ratio({"skin1", sss::ProfileKind::Pbd, 0.2});
    expect_plane_ratio({"skin1", sss::ProfileKind::Mc, 0.2});
}

// src/sss/diffusion.cpp (kNearKappa2) and docs/ptfilter.md claim that a
// uniformly lit plane stays within 1 % of albedo x E "from well-sampled down
// to spacings of 9 z_r". This checks the claim per channel, with the spacing
// measured in that channel's own z_r, for materials whose channels have short
// dmfp compared with z_r (skin, ketchup), not just marble.
// Within 1 % where the diffusion length is long against the core (dmfp >= 5 z_r,
// e.g. marble, milk, skin1 red); low-albedo channels with dmfp ~ z_r (skin1
// blue, ketchup) are within 3 % -- a known limit of the point/disk near-field
// model, documented in docs/algorithms.md.
TEST(DiffusionFlatPlane, SamplingSweepEveryChannel) {
    struct Row {
        const char* material;
        double spacing_over_red_zr;
    };
    const Row rows[] = {
        {"marble", 1.0},  {"marble", 1.5},  {"marble", 5.0},  {"skin1", 0.4},
        {"skin1", 0.7},   {"skin1", 1.0},   {"skin1", 1.5},   {"skin1", 2.2},
        {"skin1", 3.0},   {"skin2", 0.4},   {"skin2", 1.0},   {"skin2", 2.2},
        {"ketchup", 0.2}, {"ketchup", 0.4}, {"ketchup", 0.7}, {"ketchup", 1.0},
    };
    for (const Row& row : rows) {
        std::vector<sss::Profile> prof = material_profiles(row.material);
        const sss::NamedMaterial& m = material(row.material);
        double spacing = row.spacing_over_red_zr / (m.sigma_s_prime.x + m.sigma_a.x);
        glm::dvec3 r =
            run_plane({row.material, sss::ProfileKind::Classic, row.spacing_over_red_zr});
        std::printf("  sweep %-8s h = %.2f z_r red: ratio %.4f %.4f %.4f at h/z_r %.2f "
                    "%.2f %.2f\n",
                    row.material, row.spacing_over_red_zr, r.x, r.y, r.z,
                    spacing / prof[0].core_length(), spacing / prof[1].core_length(),
                    spacing / prof[2].core_length());
        for (int c = 0; c < 3; ++c) {
            double h_over_zr = spacing / prof[c].core_length();
            if (h_over_zr > 9.0) continue;
            double tol = prof[c].dmfp() >= 5.0 * prof[c].core_length() ? 0.01 : 0.03;
            EXPECT_NEAR(r[c], 1.0, tol)
                << row.material << " channel " << c << ": spacing " << h_over_zr
                << " z_r of that channel (" << row.spacing_over_red_zr << " z_r red)";
        }
    }
}

TEST(DiffusionFlatPlane, ScalesWithIrradianceAndUnitlength) {
    // E = 2 doubles the result; -unitlength 0.1 with a 10x smaller plane is
    // the same object in cm and gives the same numbers.
    const sss::NamedMaterial& m = material("marble");
    double zr = 1.0 / (m.sigma_s_prime.x + m.sigma_a.x);
    std::vector<sss::Profile> prof = material_profiles("marble");
    double dmax = std::max({prof[0].dmfp(), prof[1].dmfp(), prof[2].dmfp()});
    glm::dvec3 ratio[2];
    for (int k = 0; k < 2; ++k) {
        double u = k == 0 ? 1.0 : 0.1;
        sss::SyntheticParams sp;
        sp.shape = sss::SyntheticShape::Plane;
        sp.size = 20.0 * dmax * u;
        double per_side = std::round(20.0 * dmax / (3.0 * zr));
        sp.count = std::size_t(per_side * per_side);
        sp.light_color = {2, 2, 2};
        sss::PointCloud cloud = sss::make_synthetic_cloud(sp);
        sss::SsDiffusionOptions o;
        o.material.preset = "marble";
        o.material.unitlength = u;
        sss::PointCloud out = sss::ssdiffusion(cloud, o);
        glm::dvec3 expected(2 * prof[0].total(), 2 * prof[1].total(),
                            2 * prof[2].total());
        ratio[k] = central_median_ratio(out, dmax * u, expected);
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(ratio[k][c], 1.0, 0.01) << "unitlength " << u << " ch " << c;
    }
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(ratio[1][c], ratio[0][c], 1e-3) << c;
}

// ---------------------------------------------------------------------------
// Hierarchical against exact
// ---------------------------------------------------------------------------

namespace {

void expect_error_falls(const char* label, const sss::DiffusionProblem& pb) {
    glm::dvec3 err[3];
    const double eps[3] = {4.0, 1.0, 0.25};
    for (int k = 0; k < 3; ++k) {
        sss::DiffusionOptions opt;
        opt.max_solid_angle = eps[k];
        Comparison c = compare_with_exact(pb, opt);
        EXPECT_TRUE(all_finite(c.h)) << label;
        err[k] = c.rms;
        std::printf("  %s maxsolidangle %.2f: RMS error %.5f %.5f %.5f\n", label, eps[k],
                    c.rms.x, c.rms.y, c.rms.z);
    }
    for (int ch = 0; ch < 3; ++ch) {
        EXPECT_LT(err[1][ch], 0.01) << label << " default maxsolidangle, channel " << ch;
        EXPECT_LT(err[2][ch], err[0][ch])
            << label << " channel " << ch << ": error must fall with maxsolidangle";
        // Below about 1e-4 the error stops falling: that is the floor of the
        // profile tables' interpolation (the near terms), reached first by the
        // shortest profile (skin1's blue), where it moves by a few 1e-6 with
        // the tree's shape.
        EXPECT_LE(err[2][ch], err[1][ch] * 1.05 + 1e-5) << label << " channel " << ch;
    }
}

} // namespace

TEST(DiffusionHierarchy, SphereMatchesExact) {
    // Marble, 30k points on a radius-50 mm sphere lit from one side.
    sss::PointCloud cloud = sphere_cloud(30000, 50.0);
    expect_error_falls("sphere marble", problem_from(cloud, material_profiles("marble")));
}

TEST(DiffusionHierarchy, SmallSphereWideProfileMatchesExact) {
    // The profile is wider than the object (radius 10 mm, marble dmfp 8.5 mm).
    sss::PointCloud cloud = sphere_cloud(20000, 10.0);
    expect_error_falls("small sphere marble",
                       problem_from(cloud, material_profiles("marble")));
}

TEST(DiffusionHierarchy, ThinBoxMatchesExact) {
    // 60 x 60 x 1 mm slab of marble (thickness << dmfp): light bleeds to the back.
    sss::PointCloud cloud = box_cloud(30000, 60.0, 1.0);
    expect_error_falls("thin box marble",
                       problem_from(cloud, material_profiles("marble")));
}

TEST(DiffusionHierarchy, SkinSphereMatchesExact) {
    sss::PointCloud cloud = sphere_cloud(30000, 20.0);
    expect_error_falls("sphere skin1", problem_from(cloud, material_profiles("skin1")));
}

// The hierarchical result is not biased low: negligible nodes are taken as
// monopoles instead of being dropped (issue 17: the default was -0.43 % on
// average at 1M points, every sampled point below the exact value). The mean
// signed error over random receivers, relative to mean |e|, for clouds lit
// from one side and with a negative blocker.
TEST(DiffusionHierarchy, NoBias) {
    struct Case {
        const char* label;
        sss::DiffusionProblem pb;
    };
    std::vector<Case> cases;
    cases.push_back({"sphere marble", problem_from(sphere_cloud(30000, 50.0),
                                                   material_profiles("marble"))});
    cases.push_back({"thin box skin1", problem_from(box_cloud(30000, 60.0, 2.0),
                                                    material_profiles("skin1"))});
    // A blocker: the box's lower half carries negative irradiance.
    sss::DiffusionProblem& blocked = cases.back().pb;
    for (std::size_t i = 0; i < blocked.positions.size(); ++i)
        if (blocked.positions[i].y < 0) blocked.irradiance[i] *= -0.5f;
    for (const Case& c : cases) {
        std::vector<std::size_t> rec = sample_receivers(c.pb.positions.size(), 400);
        std::vector<glm::dvec3> e = sss::evaluate_diffusion_exact(c.pb, rec);
        for (double eps : {0.25, 0.5, 1.0}) {
            sss::DiffusionOptions opt;
            opt.max_solid_angle = eps;
            std::vector<glm::vec3> h = sss::evaluate_diffusion(c.pb, opt);
            for (int ch = 0; ch < 3; ++ch) {
                double mean_abs = 0, bias = 0;
                for (std::size_t k = 0; k < rec.size(); ++k)
                    mean_abs += std::abs(e[k][ch]);
                mean_abs /= double(rec.size());
                for (std::size_t k = 0; k < rec.size(); ++k)
                    bias += (double(h[rec[k]][ch]) - e[k][ch]) / mean_abs;
                bias /= double(rec.size());
                // Dropped nodes: -0.16 % (sphere, red) at 1; monopoles for
                // the negligible nodes: -0.07 %; local expansions: ~-0.01 %.
                // Issue 17: within +-0.05 % at every maxsolidangle up to 1.
                if (std::getenv("SSS_TEST_VERBOSE"))
                    std::printf("%s eps %g ch %d bias %.4f %%\n", c.label, eps, ch,
                                100 * bias);
                EXPECT_LT(std::abs(bias), 0.0005)
                    << c.label << " maxsolidangle " << eps << " channel " << ch
                    << ": mean signed error " << 100 * bias << " %";
            }
        }
    }
}

// Unlit sources (zero power in every channel: the far side of an object lit
// from one side) add exactly 0 to any receiver, so the walk drops their nodes
// whole (issue 17). The result is what it would be if they were evaluated: a
// faint, but not zero, power there gives the same numbers to within that
// power, with about half of the sphere's terms.
TEST(DiffusionHierarchy, UnlitSourcesAreSkippedExactly) {
    sss::DiffusionProblem pb =
        problem_from(sphere_cloud(30000, 50.0), material_profiles("marble"));
    std::size_t unlit = 0;
    sss::DiffusionProblem faint = pb;
    for (glm::vec3& e : faint.irradiance)
        if (e == glm::vec3(0.0f)) {
            e = glm::vec3(1e-30f);
            ++unlit;
        }
    ASSERT_GT(unlit, pb.irradiance.size() / 3);
    sss::DiffusionStats s_unlit, s_faint;
    std::vector<glm::vec3> h = sss::evaluate_diffusion(pb, {}, &s_unlit);
    std::vector<glm::vec3> f = sss::evaluate_diffusion(faint, {}, &s_faint);
    double worst = 0, mean = 0;
    for (std::size_t i = 0; i < h.size(); ++i)
        for (int ch = 0; ch < 3; ++ch) {
            worst = std::max(worst, double(std::abs(h[i][ch] - f[i][ch])));
            mean += double(f[i][ch]) / double(3 * h.size());
        }
    EXPECT_LT(worst, 1e-6 * mean);
    const std::size_t terms_unlit = s_unlit.near_terms + s_unlit.far_terms;
    const std::size_t terms_faint = s_faint.near_terms + s_faint.far_terms;
    EXPECT_LT(double(terms_unlit), 0.75 * double(terms_faint))
        << terms_unlit << " terms against " << terms_faint;

    // Nothing lit: no term at all, and exactly 0 everywhere.
    for (glm::vec3& e : pb.irradiance) e = glm::vec3(0.0f);
    sss::DiffusionStats s_dark;
    std::vector<glm::vec3> d = sss::evaluate_diffusion(pb, {}, &s_dark);
    EXPECT_EQ(s_dark.near_terms + s_dark.far_terms + s_dark.local_terms, 0u);
    for (const glm::vec3& v : d) ASSERT_EQ(v, glm::vec3(0.0f));
}

TEST(DiffusionHierarchy, OtherProfilesMatchExact) {
    sss::PointCloud cloud = sphere_cloud(20000, 30.0);
    for (sss::ProfileKind kind : {sss::ProfileKind::Better, sss::ProfileKind::Burley,
                                  sss::ProfileKind::Pbd, sss::ProfileKind::Mc}) {
        sss::DiffusionProblem pb =
            problem_from(cloud, material_profiles("marble", 1.0, kind));
        Comparison c = compare_with_exact(pb, {});
        std::printf("  sphere marble %s: RMS error %.5f %.5f %.5f\n",
                    sss::profile_kind_name(kind), c.rms.x, c.rms.y, c.rms.z);
        EXPECT_TRUE(all_finite(c.h));
        EXPECT_LT(max3(c.rms), 0.01) << sss::profile_kind_name(kind);
    }
}

TEST(DiffusionHierarchy, ExactWithEveryDiskIntegrated) {
    // ExactDisks::All integrates every source disk: for the sampled profiles
    // that is their own rule (identical results); for the dipoles it adds
    // the near field their rule takes as points, a small difference.
    sss::PointCloud cloud = sphere_cloud(3000, 10.0);
    std::vector<std::size_t> rec;
    for (std::size_t i = 0; i < cloud.size(); i += 60) rec.push_back(i);
    for (sss::ProfileKind kind : {sss::ProfileKind::Classic, sss::ProfileKind::Pbd}) {
        sss::DiffusionProblem pb =
            problem_from(cloud, material_profiles("marble", 1.0, kind));
        std::vector<glm::dvec3> model = sss::evaluate_diffusion_exact(pb, rec);
        std::vector<glm::dvec3> all =
            sss::evaluate_diffusion_exact(pb, rec, nullptr, sss::ExactDisks::All);
        double worst = 0.0;
        for (std::size_t i = 0; i < rec.size(); ++i)
            for (int ch = 0; ch < 3; ++ch)
                worst = std::max(worst, std::abs(all[i][ch] - model[i][ch]) /
                                            std::max(1e-12, std::abs(model[i][ch])));
        if (kind == sss::ProfileKind::Pbd)
            EXPECT_EQ(worst, 0.0);
        else {
            EXPECT_GT(worst, 1e-6);
            EXPECT_LT(worst, 0.05);
        }
    }
}

TEST(DiffusionHierarchy, ClassicCriteriaRunAndAreFinite) {
    sss::PointCloud cloud = sphere_cloud(20000, 30.0);
    sss::DiffusionProblem pb = problem_from(cloud, material_profiles("marble"));
    for (sss::Criterion crit :
         {sss::Criterion::SolidAngleBox, sss::Criterion::SolidAngleCentroid}) {
        for (double eps : {1.0, 0.25}) {
            sss::DiffusionOptions opt;
            opt.criterion = crit;
            opt.max_solid_angle = eps;
            sss::DiffusionStats stats;
            Comparison c = compare_with_exact(pb, opt);
            sss::evaluate_diffusion(pb, opt, &stats);
            std::printf("  criterion %s maxsolidangle %.2f: RMS error %.4f %.4f %.4f\n",
                        sss::criterion_name(crit), eps, c.rms.x, c.rms.y, c.rms.z);
            ASSERT_EQ(c.h.size(), cloud.size());
            EXPECT_TRUE(all_finite(c.h)) << sss::criterion_name(crit);
            EXPECT_GT(stats.far_terms, 0u) << sss::criterion_name(crit);
            // Loose sanity bound: these criteria are known to be rough
            // (algorithms.md key finding 3: several % RMS at eps 1).
            EXPECT_LT(max3(c.rms), 0.25) << sss::criterion_name(crit) << " eps " << eps;
        }
    }
    sss::Criterion parsed;
    ASSERT_TRUE(sss::parse_criterion("bbox", parsed));
    EXPECT_EQ(parsed, sss::Criterion::SolidAngleBox);
    ASSERT_TRUE(sss::parse_criterion("prman", parsed));
    EXPECT_EQ(parsed, sss::Criterion::SolidAngleBox);
    ASSERT_TRUE(sss::parse_criterion("jensen", parsed));
    EXPECT_EQ(parsed, sss::Criterion::SolidAngleCentroid);
    ASSERT_TRUE(sss::parse_criterion("error", parsed));
    EXPECT_EQ(parsed, sss::Criterion::Error);
    EXPECT_FALSE(sss::parse_criterion("nosuch", parsed));
}

TEST(DiffusionHierarchy, ExactIsPairwiseSum) {
    // A handful of far-apart points: the exact path is the plain pair sum
    // (no disk quadrature) plus the exact self disk.
    std::vector<sss::Profile> prof = material_profiles("skin1");
    sss::DiffusionProblem pb;
    pb.positions = {{0, 0, 0}, {3, 0, 0}, {0, 4, 0}, {1, 1, 5}};
    pb.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
    pb.areas = {0.01f, 0.02f, 0.005f, 0.01f};
    pb.irradiance = {{1, 2, 3}, {0.5, 0.5, 0.5}, {-1, 0, 1}, {2, 1, 0}};
    pb.profiles = prof;
    std::vector<glm::dvec3> e = sss::evaluate_diffusion_exact(pb);
    std::vector<glm::vec3> h = sss::evaluate_diffusion(pb, {});
    ASSERT_EQ(e.size(), 4u);
    for (std::size_t i = 0; i < 4; ++i) {
        for (int ch = 0; ch < 3; ++ch) {
            double sum = 0.0;
            for (std::size_t j = 0; j < 4; ++j) {
                double a = pb.areas[j];
                if (i == j) {
                    sum += pb.irradiance[j][ch] * prof[ch].disk(std::sqrt(a / kPi));
                } else {
                    double r = glm::length(glm::dvec3(pb.positions[i]) -
                                           glm::dvec3(pb.positions[j]));
                    sum += prof[ch].eval(r) * a * pb.irradiance[j][ch];
                }
            }
            EXPECT_NEAR(e[i][ch], sum, 1e-12 * std::abs(sum) + 1e-300) << i << " " << ch;
            // The hierarchical path reads R from a table linear in r^2
            // (32 entries per octave): about 0.5 % in the far tail, which is
            // all that point 2's green channel receives.
            EXPECT_NEAR(h[i][ch], sum, 6e-3 * std::abs(sum) + 1e-9) << i << " " << ch;
        }
    }
    // Receivers subset.
    std::vector<glm::dvec3> e2 = sss::evaluate_diffusion_exact(pb, {2, 0});
    ASSERT_EQ(e2.size(), 2u);
    EXPECT_EQ(e2[0], e[2]);
    EXPECT_EQ(e2[1], e[0]);
}

// ---------------------------------------------------------------------------
// Determinism
// ---------------------------------------------------------------------------

TEST(DiffusionDeterminism, ThreadCountDoesNotChangeOutput) {
    sss::PointCloud sphere = sphere_cloud(20000, 30.0);
    sss::PointCloud box = box_cloud(20000, 50.0, 2.0);
    for (const sss::PointCloud* cloud : {&sphere, &box}) {
        sss::DiffusionProblem pb = problem_from(*cloud, material_profiles("marble"));
        for (sss::Criterion crit : {sss::Criterion::Error, sss::Criterion::SolidAngleBox,
                                    sss::Criterion::SolidAngleCentroid}) {
            sss::DiffusionOptions opt;
            opt.criterion = crit;
            std::vector<glm::vec3> one, two, two_again;
            {
                sss::ThreadLimit limit(1);
                one = sss::evaluate_diffusion(pb, opt);
            }
            {
                sss::ThreadLimit limit(2);
                two = sss::evaluate_diffusion(pb, opt);
                two_again = sss::evaluate_diffusion(pb, opt);
            }
            EXPECT_TRUE(bitwise_equal(one, two)) << sss::criterion_name(crit);
            EXPECT_TRUE(bitwise_equal(two, two_again)) << sss::criterion_name(crit);
        }
        std::vector<std::size_t> rec = sample_receivers(pb.positions.size(), 300);
        std::vector<glm::dvec3> e1, e2;
        {
            sss::ThreadLimit limit(1);
            e1 = sss::evaluate_diffusion_exact(pb, rec);
        }
        {
            sss::ThreadLimit limit(2);
            e2 = sss::evaluate_diffusion_exact(pb, rec);
        }
        ASSERT_EQ(e1.size(), e2.size());
        EXPECT_EQ(std::memcmp(e1.data(), e2.data(), e1.size() * sizeof(glm::dvec3)), 0);
    }
}

TEST(DiffusionDeterminism, PerPointMaterialsThreadIndependent) {
    sss::PointCloud cloud = sphere_cloud(20000, 20.0);
    {
        sss::Channel& a = cloud.add_channel("_albedo", sss::ChannelType::Color);
        a.data.resize(3 * cloud.size());
        for (std::size_t i = 0; i < cloud.size(); ++i)
            for (int c = 0; c < 3; ++c)
                a.data[3 * i + c] =
                    cloud.positions[i].x > 0 ? 0.8f - 0.2f * c : 0.3f + 0.1f * c;
    }
    {
        sss::Channel& d =
            cloud.add_channel("_diffusemeanfreepath", sss::ChannelType::Color);
        d.data.resize(3 * cloud.size());
        for (std::size_t i = 0; i < cloud.size(); ++i)
            for (int c = 0; c < 3; ++c)
                d.data[3 * i + c] = 1.0f + 4.0f * float(i % 7) / 7.0f + float(c);
    }
    sss::SsDiffusionOptions o;
    o.material.albedo_from_file = o.material.dmfp_from_file = true;
    sss::PointCloud one, two;
    {
        sss::ThreadLimit limit(1);
        one = sss::ssdiffusion(cloud, o);
    }
    {
        sss::ThreadLimit limit(2);
        two = sss::ssdiffusion(cloud, o);
    }
    ASSERT_EQ(one.channels.size(), two.channels.size());
    EXPECT_EQ(one.channels[0].data, two.channels[0].data);
}

// ---------------------------------------------------------------------------
// Degenerate clouds
// ---------------------------------------------------------------------------

TEST(DiffusionRobustness, EmptyCloud) {
    sss::DiffusionProblem pb;
    pb.profiles = material_profiles("marble");
    EXPECT_TRUE(sss::evaluate_diffusion(pb, {}).empty());
    EXPECT_TRUE(sss::evaluate_diffusion_exact(pb).empty());
    sss::PointCloud empty;
    sss::SsDiffusionOptions defaults;
    sss::PointCloud out = sss::ssdiffusion(empty, defaults);
    EXPECT_EQ(out.size(), 0u);
    const sss::Channel* ch = out.find_channel("_ssdiffusion");
    ASSERT_NE(ch, nullptr);
    EXPECT_EQ(ch->type, sss::ChannelType::Color);
}

TEST(DiffusionRobustness, SinglePointIsItsOwnDisk) {
    for (sss::ProfileKind kind :
         {sss::ProfileKind::Classic, sss::ProfileKind::Better, sss::ProfileKind::Burley,
          sss::ProfileKind::Pbd, sss::ProfileKind::Mc}) {
        std::vector<sss::Profile> prof = material_profiles("skin1", 1.0, kind);
        sss::DiffusionProblem pb;
        pb.positions = {{1, 2, 3}};
        pb.normals = {{0, 0, 1}};
        pb.areas = {2.0f};
        pb.irradiance = {{1.0f, 0.5f, 2.0f}};
        pb.profiles = prof;
        std::vector<glm::vec3> h = sss::evaluate_diffusion(pb, {});
        std::vector<glm::dvec3> e = sss::evaluate_diffusion_exact(pb);
        ASSERT_EQ(h.size(), 1u);
        ASSERT_EQ(e.size(), 1u);
        for (int ch = 0; ch < 3; ++ch) {
            double expect = pb.irradiance[0][ch] * prof[ch].disk(std::sqrt(2.0 / kPi));
            EXPECT_NEAR(h[0][ch], expect, 1e-6 * expect)
                << sss::profile_kind_name(kind) << ch;
            EXPECT_NEAR(e[0][ch], expect, 1e-12 * expect)
                << sss::profile_kind_name(kind) << ch;
        }
    }
}

TEST(DiffusionRobustness, ManyIdenticalPoints) {
    std::vector<sss::Profile> prof = material_profiles("marble");
    sss::DiffusionProblem pb;
    const std::size_t n = 10000;
    pb.positions.assign(n, glm::vec3(0.5f, -0.25f, 1.0f));
    pb.normals.assign(n, glm::vec3(0, 0, 1));
    const float area = 1e-4f;
    pb.areas.assign(n, area);
    pb.irradiance.assign(n, glm::vec3(1.0f, 0.5f, 0.25f));
    pb.profiles = prof;
    sss::Stopwatch watch;
    std::vector<glm::vec3> h = sss::evaluate_diffusion(pb, {});
    double seconds = watch.seconds();
    ASSERT_EQ(h.size(), n);
    EXPECT_TRUE(all_finite(h));
    EXPECT_LT(seconds, 5.0) << "10 000 coincident points took " << seconds << " s";
    std::vector<std::size_t> rec = {0, 1, n / 2, n - 1};
    std::vector<glm::dvec3> e = sss::evaluate_diffusion_exact(pb, rec);
    for (std::size_t k = 0; k < rec.size(); ++k)
        for (int ch = 0; ch < 3; ++ch) {
            double expect = double(n) * pb.irradiance[0][ch] *
                            prof[ch].disk(std::sqrt(double(area) / kPi));
            EXPECT_NEAR(e[k][ch], expect, 1e-9 * expect);
            EXPECT_NEAR(h[rec[k]][ch], e[k][ch], 1e-3 * e[k][ch]) << rec[k] << " " << ch;
        }
}

TEST(DiffusionRobustness, PointsOnALine) {
    std::vector<sss::Profile> prof = material_profiles("skin1");
    sss::DiffusionProblem pb;
    const std::size_t n = 3000;
    for (std::size_t i = 0; i < n; ++i) {
        pb.positions.push_back({0.05f * float(i), 0.0f, 0.0f});
        pb.normals.push_back({0, 0, 1});
        pb.areas.push_back(0.0025f);
        pb.irradiance.push_back(glm::vec3(1.0f + 0.5f * std::sin(0.01f * float(i))));
    }
    pb.profiles = prof;
    Comparison c = compare_with_exact(pb, {});
    EXPECT_TRUE(all_finite(c.h));
    EXPECT_LT(max3(c.rms), 0.01) << c.rms.x << " " << c.rms.y << " " << c.rms.z;
    // Without normals (zero vectors: disks face the receiver).
    pb.normals.assign(n, glm::vec3(0));
    Comparison c2 = compare_with_exact(pb, {});
    EXPECT_TRUE(all_finite(c2.h));
    EXPECT_LT(max3(c2.rms), 0.01);
    // No normals array at all.
    pb.normals.clear();
    Comparison c3 = compare_with_exact(pb, {});
    EXPECT_TRUE(all_finite(c3.h));
    EXPECT_LT(max3(c3.rms), 0.01);
}

TEST(DiffusionRobustness, FlatRandomCloud) {
    // All z = 0, random positions (some very close pairs), varying irradiance.
    std::vector<sss::Profile> prof = material_profiles("skin1");
    sss::DiffusionProblem pb;
    std::mt19937_64 rng(42);
    std::uniform_real_distribution<float> u(-15.0f, 15.0f);
    const std::size_t n = 20000;
    const float area = 30.0f * 30.0f / float(n);
    for (std::size_t i = 0; i < n; ++i) {
        glm::vec3 p(u(rng), u(rng), 0.0f);
        pb.positions.push_back(p);
        pb.normals.push_back({0, 0, 1});
        pb.areas.push_back(area);
        pb.irradiance.push_back(
            glm::vec3(p.x > 0 ? 1.0f : 0.1f, 0.5f, 1.0f + 0.05f * p.y));
    }
    pb.profiles = prof;
    Comparison c = compare_with_exact(pb, {});
    EXPECT_TRUE(all_finite(c.h));
    EXPECT_LT(max3(c.rms), 0.01) << c.rms.x << " " << c.rms.y << " " << c.rms.z;
}

TEST(DiffusionRobustness, ZeroAreas) {
    sss::PointCloud cloud = sphere_cloud(5000, 10.0);
    sss::DiffusionProblem pb = problem_from(cloud, material_profiles("marble"));
    std::vector<float> areas = pb.areas;
    pb.areas.assign(pb.areas.size(), 0.0f);
    std::vector<glm::vec3> h = sss::evaluate_diffusion(pb, {});
    ASSERT_EQ(h.size(), cloud.size());
    for (const glm::vec3& v : h) ASSERT_EQ(v, glm::vec3(0.0f));
    for (const glm::dvec3& v :
         sss::evaluate_diffusion_exact(pb, sample_receivers(h.size())))
        ASSERT_EQ(v, glm::dvec3(0.0));
    // Every other point with zero area: matches exact.
    pb.areas = areas;
    for (std::size_t i = 0; i < pb.areas.size(); i += 2) pb.areas[i] = 0.0f;
    Comparison c = compare_with_exact(pb, {});
    EXPECT_TRUE(all_finite(c.h));
    EXPECT_LT(max3(c.rms), 0.01);
}

TEST(DiffusionRobustness, NegativeIrradianceIsExactNegation) {
    sss::PointCloud cloud = sphere_cloud(20000, 30.0);
    sss::DiffusionProblem pos = problem_from(cloud, material_profiles("marble"));
    pos.irradiance.assign(pos.irradiance.size(), glm::vec3(1.0f));
    sss::DiffusionProblem neg = pos;
    neg.irradiance.assign(neg.irradiance.size(), glm::vec3(-1.0f));
    std::vector<glm::vec3> hp = sss::evaluate_diffusion(pos, {});
    std::vector<glm::vec3> hn = sss::evaluate_diffusion(neg, {});
    ASSERT_EQ(hp.size(), hn.size());
    std::size_t mismatches = 0;
    for (std::size_t i = 0; i < hp.size(); ++i)
        if (hn[i] != -hp[i]) ++mismatches;
    EXPECT_EQ(mismatches, 0u);
    EXPECT_GT(hp[0].x, 0.0f);
    // Same with the sphere's directional lighting.
    sss::DiffusionProblem lit = problem_from(cloud, material_profiles("marble"));
    sss::DiffusionProblem dark = lit;
    for (glm::vec3& e : dark.irradiance) e = -e;
    hp = sss::evaluate_diffusion(lit, {});
    hn = sss::evaluate_diffusion(dark, {});
    mismatches = 0;
    for (std::size_t i = 0; i < hp.size(); ++i)
        if (hn[i] != -hp[i]) ++mismatches;
    EXPECT_EQ(mismatches, 0u);
}

TEST(DiffusionRobustness, MixedSignsMatchExact) {
    // Light plus a negative ambient ("blocker"): E in [-0.4, 0.6].
    sss::SyntheticParams sp;
    sp.shape = sss::SyntheticShape::Sphere;
    sp.count = 20000;
    sp.size = 20.0;
    sp.ambient = -0.4;
    sss::PointCloud cloud = sss::make_synthetic_cloud(sp);
    sss::DiffusionProblem pb = problem_from(cloud, material_profiles("marble"));
    Comparison c = compare_with_exact(pb, {});
    EXPECT_TRUE(all_finite(c.h));
    EXPECT_LT(max3(c.rms), 0.01) << c.rms.x << " " << c.rms.y << " " << c.rms.z;
    // Random signs per point: heavy cancellation inside every node.
    std::mt19937 rng(7);
    for (glm::vec3& e : pb.irradiance) e = glm::vec3((rng() & 1) ? 1.0f : -1.0f) + 0.1f;
    Comparison r = compare_with_exact(pb, {});
    EXPECT_TRUE(all_finite(r.h));
    EXPECT_LT(max3(r.rms), 0.01) << r.rms.x << " " << r.rms.y << " " << r.rms.z;
}

TEST(DiffusionRobustness, ExtremeMaterials) {
    // Spectralon (no absorption, infinite dmfp) and albedo 0.999 stay finite.
    sss::PointCloud cloud = sphere_cloud(5000, 10.0);
    for (const char* name : {"spectralon", "cream", "ketchup"}) {
        sss::DiffusionProblem pb = problem_from(cloud, material_profiles(name));
        std::vector<glm::vec3> h = sss::evaluate_diffusion(pb, {});
        EXPECT_TRUE(all_finite(h)) << name;
    }
    std::vector<sss::Profile> hi;
    for (int ch = 0; ch < 3; ++ch)
        hi.push_back(
            sss::Profile::from_albedo_dmfp(sss::ProfileKind::Classic, 0.999, 5.0, 1.3));
    sss::DiffusionProblem pb = problem_from(cloud, hi);
    Comparison c = compare_with_exact(pb, {});
    EXPECT_TRUE(all_finite(c.h));
    EXPECT_LT(max3(c.rms), 0.01);
}

// ---------------------------------------------------------------------------
// sss::ssdiffusion: channels, output, per-point materials
// ---------------------------------------------------------------------------

namespace {

sss::PointCloud lit_plane(double side, std::size_t count) {
    sss::SyntheticParams sp;
    sp.shape = sss::SyntheticShape::Plane;
    sp.size = side;
    sp.count = count;
    sp.light_dir = {0.3, 0, 1};
    sp.ambient = 0.1;
    return sss::make_synthetic_cloud(sp);
}

void add_color(sss::PointCloud& cloud, const std::string& name, glm::vec3 value) {
    sss::Channel& c = cloud.add_channel(name, sss::ChannelType::Color);
    c.data.resize(3 * cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i)
        for (int k = 0; k < 3; ++k) c.data[3 * i + k] = value[k];
}

std::vector<float> output_of(const sss::PointCloud& out) {
    const sss::Channel* c = out.find_channel("_ssdiffusion");
    return c ? c->data : std::vector<float>{};
}

/// Largest |a - b| / max|b| over all values.
double max_relative_difference(const std::vector<float>& a, const std::vector<float>& b) {
    double scale = 0.0, diff = 0.0;
    for (float v : b) scale = std::max(scale, double(std::abs(v)));
    for (std::size_t i = 0; i < a.size() && i < b.size(); ++i)
        diff = std::max(diff, double(std::abs(a[i] - b[i])));
    return scale > 0 ? diff / scale : diff;
}

template <typename F>
std::string value_error_message(F&& f) {
    try {
        f();
    } catch (const sss::ValueError& e) {
        return e.what();
    } catch (const std::exception& e) {
        return std::string("WRONG EXCEPTION TYPE: ") + e.what();
    }
    return "NO EXCEPTION";
}

} // namespace

TEST(DiffusionSsdiffusion, OutputCloudLayout) {
    sss::PointCloud cloud = lit_plane(20.0, 2500);
    cloud.world_to_eye[3] = 7.0f;
    cloud.format = {640.0f, 480.0f, 1.0f};
    sss::SsDiffusionOptions o;
    o.material.preset = "skin1";
    sss::SsDiffusionReport rep;
    sss::PointCloud out = sss::ssdiffusion(cloud, o, &rep);
    EXPECT_EQ(out.positions, cloud.positions);
    EXPECT_EQ(out.normals, cloud.normals);
    EXPECT_EQ(out.radii, cloud.radii);
    EXPECT_EQ(out.world_to_eye, cloud.world_to_eye);
    EXPECT_EQ(out.format, cloud.format);
    ASSERT_EQ(out.channels.size(), 1u);
    EXPECT_EQ(out.channels[0].name, "_ssdiffusion");
    EXPECT_EQ(out.channels[0].type, sss::ChannelType::Color);
    EXPECT_EQ(out.channels[0].data.size(), 3 * cloud.size());
    EXPECT_FALSE(rep.material_lines.empty());
    EXPECT_EQ(rep.distinct_profiles, 3u);
    // Same as the library evaluation on the same problem.
    std::vector<glm::vec3> h =
        sss::evaluate_diffusion(problem_from(cloud, material_profiles("skin1")), {});
    for (std::size_t i = 0; i < cloud.size(); ++i)
        for (int k = 0; k < 3; ++k) ASSERT_EQ(out.channels[0].data[3 * i + k], h[i][k]);
    // keep_channels copies the inputs.
    o.keep_channels = true;
    sss::PointCloud kept = sss::ssdiffusion(cloud, o);
    EXPECT_NE(kept.find_channel("_area"), nullptr);
    EXPECT_NE(kept.find_channel("_radiance_t"), nullptr);
    EXPECT_NE(kept.find_channel("_ssdiffusion"), nullptr);
    // exact = true gives nearly the same numbers.
    o.keep_channels = false;
    o.exact = true;
    sss::PointCloud exact = sss::ssdiffusion(cloud, o);
    EXPECT_LT(max_relative_difference(output_of(out), output_of(exact)), 0.01);
}

TEST(DiffusionSsdiffusion, ConstantPerPointMaterialEqualsConstantMaterial) {
    sss::PointCloud cloud = lit_plane(30.0, 20000);
    const glm::vec3 albedo(0.6f, 0.4f, 0.2f), dmfp(3.0f, 1.5f, 0.7f);
    add_color(cloud, "_albedo", albedo);
    add_color(cloud, "_diffusemeanfreepath", dmfp);
    for (sss::ProfileKind kind :
         {sss::ProfileKind::Classic, sss::ProfileKind::Better, sss::ProfileKind::Burley,
          sss::ProfileKind::Pbd, sss::ProfileKind::Mc}) {
        sss::SsDiffusionOptions constant;
        constant.profile = kind;
        constant.material.albedo = glm::dvec3(albedo);
        constant.material.dmfp = glm::dvec3(dmfp);
        std::vector<float> ref = output_of(sss::ssdiffusion(cloud, constant));
        for (int mode = 0; mode < 3; ++mode) {
            sss::SsDiffusionOptions o = constant;
            if (mode != 1) o.material.albedo.reset(), o.material.albedo_from_file = true;
            if (mode != 2) o.material.dmfp.reset(), o.material.dmfp_from_file = true;
            sss::SsDiffusionReport rep;
            std::vector<float> got = output_of(sss::ssdiffusion(cloud, o, &rep));
            EXPECT_LT(max_relative_difference(got, ref), 0.005)
                << sss::profile_kind_name(kind) << " mode " << mode;
            EXPECT_LE(rep.distinct_profiles, 3u) << sss::profile_kind_name(kind);
        }
    }
    // With unitlength: the file's dmfp is in mm too.
    sss::SsDiffusionOptions c10;
    c10.material.albedo = glm::dvec3(albedo);
    c10.material.dmfp = glm::dvec3(dmfp);
    c10.material.unitlength = 2.0;
    sss::SsDiffusionOptions f10 = c10;
    f10.material.albedo.reset();
    f10.material.dmfp.reset();
    f10.material.albedo_from_file = f10.material.dmfp_from_file = true;
    EXPECT_LT(max_relative_difference(output_of(sss::ssdiffusion(cloud, f10)),
                                      output_of(sss::ssdiffusion(cloud, c10))),
              0.005);
}

TEST(DiffusionSsdiffusion, VaryingPerPointMaterialMatchesExact) {
    // Two albedos (y > 0 / y < 0) and a dmfp that grows with |x| in 0.25 mm
    // steps; hierarchical ssdiffusion against an exact all-pairs sum with the
    // same per-receiver profiles on 300 sampled receivers.
    sss::PointCloud cloud = sphere_cloud(20000, 10.0);
    auto albedo_of = [&](std::size_t i, int c) {
        return cloud.positions[i].y > 0 ? 0.9f - 0.1f * float(c) : 0.2f + 0.1f * float(c);
    };
    auto dmfp_of = [&](std::size_t i, int c) {
        return 1.0f + 0.25f * std::floor(std::abs(cloud.positions[i].x)) +
               0.5f * float(c);
    };
    {
        sss::Channel& a = cloud.add_channel("_albedo", sss::ChannelType::Color);
        a.data.resize(3 * cloud.size());
        for (std::size_t i = 0; i < cloud.size(); ++i)
            for (int c = 0; c < 3; ++c) a.data[3 * i + c] = albedo_of(i, c);
    }
    {
        sss::Channel& d =
            cloud.add_channel("_diffusemeanfreepath", sss::ChannelType::Color);
        d.data.resize(3 * cloud.size());
        for (std::size_t i = 0; i < cloud.size(); ++i)
            for (int c = 0; c < 3; ++c) d.data[3 * i + c] = dmfp_of(i, c);
    }
    sss::SsDiffusionOptions o;
    o.material.albedo_from_file = o.material.dmfp_from_file = true;
    sss::SsDiffusionReport rep;
    sss::PointCloud out = sss::ssdiffusion(cloud, o, &rep);
    EXPECT_GT(rep.distinct_profiles, 3u);
    std::vector<glm::vec3> h(cloud.size());
    const sss::Channel* res = out.find_channel("_ssdiffusion");
    ASSERT_NE(res, nullptr);
    for (std::size_t i = 0; i < cloud.size(); ++i)
        h[i] = {res->data[3 * i], res->data[3 * i + 1], res->data[3 * i + 2]};

    // The reference problem: one profile per distinct (albedo, dmfp).
    sss::DiffusionProblem pb = problem_from(cloud, {});
    std::vector<std::pair<float, float>> keys;
    pb.profile_index.resize(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i)
        for (int c = 0; c < 3; ++c) {
            std::pair<float, float> key(albedo_of(i, c), dmfp_of(i, c));
            auto it = std::find(keys.begin(), keys.end(), key);
            if (it == keys.end()) {
                keys.push_back(key);
                pb.profiles.push_back(sss::Profile::from_albedo_dmfp(
                    sss::ProfileKind::Classic, key.first, key.second, 1.5));
                it = keys.end() - 1;
            }
            pb.profile_index[i][c] = uint32_t(it - keys.begin());
        }
    std::vector<std::size_t> rec = sample_receivers(cloud.size(), 300);
    std::vector<glm::dvec3> e = sss::evaluate_diffusion_exact(pb, rec);
    glm::dvec3 rms = relative_rms(h, e, rec);
    std::printf("  per-point material sphere: RMS error %.5f %.5f %.5f\n", rms.x, rms.y,
                rms.z);
    for (int c = 0; c < 3; ++c) EXPECT_LT(rms[c], 0.01) << "channel " << c;
}

TEST(DiffusionSsdiffusion, PerPointMaterialErrors) {
    sss::PointCloud cloud = lit_plane(10.0, 400);
    {
        sss::SsDiffusionOptions o;
        o.material.albedo_from_file = true;
        std::string msg = value_error_message([&] { sss::ssdiffusion(cloud, o); });
        EXPECT_NE(msg.find("_albedo"), std::string::npos) << msg;
    }
    {
        sss::SsDiffusionOptions o;
        o.material.dmfp_from_file = true;
        std::string msg = value_error_message([&] { sss::ssdiffusion(cloud, o); });
        EXPECT_NE(msg.find("_diffusemeanfreepath"), std::string::npos) << msg;
    }
    {
        sss::PointCloud c = cloud;
        add_color(c, "_diffusemeanfreepath", glm::vec3(1.0f));
        c.find_channel("_diffusemeanfreepath")->data[3 * 17 + 1] = -2.0f;
        sss::SsDiffusionOptions o;
        o.material.dmfp_from_file = true;
        std::string msg = value_error_message([&] { sss::ssdiffusion(c, o); });
        EXPECT_NE(msg.find("point"), std::string::npos) << msg;
        EXPECT_NE(msg.find("17"), std::string::npos) << msg;
        c.find_channel("_diffusemeanfreepath")->data[3 * 17 + 1] = 0.0f;
        msg = value_error_message([&] { sss::ssdiffusion(c, o); });
        EXPECT_NE(msg.find("point"), std::string::npos) << msg;
    }
    {
        sss::PointCloud c = cloud;
        add_color(c, "_albedo", glm::vec3(0.5f));
        c.find_channel("_albedo")->data[3 * 5] = -0.5f;
        sss::SsDiffusionOptions o;
        o.material.albedo_from_file = true;
        std::string msg = value_error_message([&] { sss::ssdiffusion(c, o); });
        EXPECT_NE(msg.find("point"), std::string::npos) << msg;
        // Albedo >= 1 in the file is clamped with a warning.
        c.find_channel("_albedo")->data[3 * 5] = 1.5f;
        sss::SsDiffusionReport rep;
        sss::PointCloud out;
        ASSERT_NO_THROW(out = sss::ssdiffusion(c, o, &rep));
        EXPECT_FALSE(rep.warnings.empty());
        for (float v : output_of(out)) ASSERT_TRUE(std::isfinite(v));
    }
    {
        // A float channel where a colour is expected.
        sss::PointCloud c = cloud;
        sss::Channel& f = c.add_channel("_albedo", sss::ChannelType::Float);
        f.data.assign(c.size(), 0.5f);
        sss::SsDiffusionOptions o;
        o.material.albedo_from_file = true;
        std::string msg = value_error_message([&] { sss::ssdiffusion(c, o); });
        EXPECT_NE(msg.find("_albedo"), std::string::npos) << msg;
    }
}

TEST(DiffusionSsdiffusion, InputChannelErrors) {
    sss::PointCloud cloud = lit_plane(10.0, 400);
    {
        sss::SsDiffusionOptions o;
        o.radiance_channel = "nosuch";
        std::string msg = value_error_message([&] { sss::ssdiffusion(cloud, o); });
        EXPECT_NE(msg.find("nosuch"), std::string::npos) << msg;
    }
    {
        sss::PointCloud c = cloud;
        c.find_channel("_area")->data[3] = -1.0f;
        sss::SsDiffusionOptions defaults;
        std::string msg = value_error_message([&] { sss::ssdiffusion(c, defaults); });
        EXPECT_NE(msg.find("point 3"), std::string::npos) << msg;
    }
    {
        // No area channel: pi r^2 from the radii, with a warning.
        sss::SsDiffusionOptions o;
        o.area_channel = "_nosucharea";
        sss::SsDiffusionReport rep;
        sss::PointCloud out;
        ASSERT_NO_THROW(out = sss::ssdiffusion(cloud, o, &rep));
        EXPECT_FALSE(rep.warnings.empty());
    }
    {
        sss::SsDiffusionOptions o;
        o.material.preset = "nosuch";
        EXPECT_THROW(sss::ssdiffusion(cloud, o), sss::UsageError);
        o.material.preset = "marble";
        o.material.unitlength = 0.0;
        EXPECT_THROW(sss::ssdiffusion(cloud, o), sss::ValueError);
    }
}

// The report's summary of the values (ptfilter -progress 2): min, mean and max
// of every channel over the output, and eight points spread over it with their
// values as written; a part summarises its own points, by whole-output index.
TEST(DiffusionSsdiffusion, ReportSummarisesTheValues) {
    const sss::PointCloud cloud = sphere_cloud(5000, 20.0);
    sss::SsDiffusionOptions o;
    sss::SsDiffusionReport report;
    const sss::PointCloud out = sss::ssdiffusion(cloud, o, &report);
    const sss::Channel* c = out.find_channel("_ssdiffusion");
    ASSERT_NE(c, nullptr);
    const sss::ValueSummary& v = report.values;
    ASSERT_EQ(v.count, out.size());
    for (int ch = 0; ch < 3; ++ch) {
        double lo = 1e30, hi = -1e30, sum = 0;
        for (std::size_t i = 0; i < out.size(); ++i) {
            lo = std::min(lo, double(c->data[3 * i + ch]));
            hi = std::max(hi, double(c->data[3 * i + ch]));
            sum += c->data[3 * i + ch];
        }
        EXPECT_EQ(v.min[ch], lo);
        EXPECT_EQ(v.max[ch], hi);
        EXPECT_NEAR(v.mean[ch], sum / double(out.size()), 1e-12 * hi);
        EXPECT_LT(lo, hi); // a lit sphere: not one value
    }
    ASSERT_EQ(v.sample.size(), 8u);
    EXPECT_EQ(v.sample.front().first, 0u);
    EXPECT_EQ(v.sample.back().first, out.size() - 1);
    for (const auto& [index, value] : v.sample)
        for (int ch = 0; ch < 3; ++ch) EXPECT_EQ(value[ch], c->data[3 * index + ch]);

    sss::SsDiffusionReport part_report;
    sss::SsDiffusionPart part = sss::ssdiffusion_part(cloud, o, 1, 3, &part_report);
    EXPECT_EQ(part_report.values.count, part.points.size());
    ASSERT_EQ(part_report.values.sample.size(), 8u);
    for (std::size_t k = 1; k < 8; ++k)
        EXPECT_LT(part_report.values.sample[k - 1].first,
                  part_report.values.sample[k].first);
    for (const auto& [index, value] : part_report.values.sample)
        for (int ch = 0; ch < 3; ++ch) EXPECT_EQ(value[ch], c->data[3 * index + ch]);
}

// A split run's parts hold, at their indices, exactly the records of the
// whole output (every channel, keep_channels, per-point materials, -exact),
// and the signature changes with every option that changes numbers.
TEST(DiffusionSsdiffusion, PartsEqualTheWholeOutput) {
    sss::PointCloud cloud = lit_plane(20.0, 3000);
    cloud.world_to_eye[3] = 7.0f;
    add_color(cloud, "_albedo", glm::vec3(0.6f, 0.4f, 0.2f));
    std::vector<sss::SsDiffusionOptions> variants(3);
    variants[0].material.preset = "skin1";
    variants[1].keep_channels = true;
    variants[1].material.albedo_from_file = true;
    variants[2].exact = true;
    for (const sss::SsDiffusionOptions& o : variants) {
        sss::PointCloud whole = sss::ssdiffusion(cloud, o);
        for (std::size_t parts : {1u, 3u}) {
            std::size_t next = 0;
            for (std::size_t k = 0; k < parts; ++k) {
                sss::SsDiffusionPart p = sss::ssdiffusion_part(cloud, o, k, parts);
                EXPECT_EQ(p.total, cloud.size());
                EXPECT_EQ(p.first, next);
                next += p.points.size();
                ASSERT_EQ(p.indices.size(), p.points.size());
                ASSERT_EQ(p.points.channels.size(), whole.channels.size());
                EXPECT_EQ(p.points.world_to_eye, whole.world_to_eye);
                for (std::size_t j = 0; j < p.indices.size(); ++j) {
                    const std::size_t i = p.indices[j];
                    ASSERT_EQ(p.points.positions[j], whole.positions[i]);
                    ASSERT_EQ(p.points.normals[j], whole.normals[i]);
                    ASSERT_EQ(p.points.radii[j], whole.radii[i]);
                    for (std::size_t c = 0; c < whole.channels.size(); ++c) {
                        const std::size_t w = std::size_t(whole.channels[c].components());
                        for (std::size_t q = 0; q < w; ++q)
                            ASSERT_EQ(p.points.channels[c].data[w * j + q],
                                      whole.channels[c].data[w * i + q])
                                << whole.channels[c].name << " point " << i;
                    }
                }
            }
            EXPECT_EQ(next, cloud.size());
        }
    }
    EXPECT_THROW(sss::ssdiffusion_part(cloud, variants[0], 3, 3), sss::ValueError);

    // The signature: equal for equal options, different for each change.
    sss::SsDiffusionOptions base;
    const std::string sig = sss::ssdiffusion_signature(base);
    EXPECT_EQ(sss::ssdiffusion_signature(base), sig);
    std::vector<sss::SsDiffusionOptions> changed(8, base);
    changed[0].material.preset = "skin1";
    changed[1].material.unitlength = 0.1;
    changed[2].diffusion.max_solid_angle = 0.5;
    changed[3].diffusion.criterion = sss::Criterion::SolidAngleBox;
    changed[4].profile = sss::ProfileKind::Better;
    changed[5].exact = true;
    changed[6].keep_channels = true;
    changed[7].radiance_channel = "_irradiance";
    for (std::size_t k = 0; k < changed.size(); ++k)
        EXPECT_NE(sss::ssdiffusion_signature(changed[k]), sig) << "change " << k;
}

// Every instruction-set path of the block kernels gives the baseline's result
// bit for bit (they are compiled without fused multiply-adds), with one
// material (block path), per-point materials (receiver path, baseline code)
// and a part.
TEST(DiffusionIsa, PathsGiveIdenticalResults) {
    sss::PointCloud cloud = sphere_cloud(20000, 50.0);
    sss::DiffusionProblem pb = problem_from(cloud, material_profiles("marble"));
    for (double eps : {0.25, 1.0, 8.0}) {
        sss::DiffusionOptions opt;
        opt.max_solid_angle = eps;
        opt.isa = sss::Isa::X86_64;
        sss::DiffusionStats st;
        const std::vector<glm::vec3> base = sss::evaluate_diffusion(pb, opt, &st);
        EXPECT_EQ(st.isa, sss::Isa::X86_64);
        for (sss::Isa isa : sss::supported_isas()) {
            opt.isa = isa;
            const std::vector<glm::vec3> h = sss::evaluate_diffusion(pb, opt, &st);
            EXPECT_EQ(st.isa, isa);
            ASSERT_EQ(h.size(), base.size());
            std::size_t differ = 0;
            for (std::size_t i = 0; i < h.size(); ++i)
                differ += std::memcmp(&h[i], &base[i], sizeof(glm::vec3)) != 0;
            EXPECT_EQ(differ, 0u) << sss::isa_name(isa) << " eps " << eps;
        }
    }
    // Per-point materials (two, by hemisphere): the kernels then read the
    // channels' own tables instead of the interleaved rows. The sphere is
    // coarse enough that near pairs need the disk quadrature in both.
    sss::DiffusionProblem mixed = pb;
    for (const sss::Profile& p : material_profiles("skin1")) mixed.profiles.push_back(p);
    mixed.profile_index.resize(mixed.positions.size());
    for (std::size_t i = 0; i < mixed.positions.size(); ++i)
        mixed.profile_index[i] =
            mixed.positions[i].x < 0 ? glm::u32vec3(0, 1, 2) : glm::u32vec3(3, 4, 5);
    sss::DiffusionOptions opt;
    opt.isa = sss::Isa::X86_64;
    sss::DiffusionStats st;
    const std::vector<glm::vec3> base = sss::evaluate_diffusion(mixed, opt, &st);
    EXPECT_GT(st.quadrature_terms, 0u);
    for (sss::Isa isa : sss::supported_isas()) {
        opt.isa = isa;
        const std::vector<glm::vec3> h = sss::evaluate_diffusion(mixed, opt);
        std::size_t differ = 0;
        for (std::size_t i = 0; i < h.size(); ++i)
            differ += std::memcmp(&h[i], &base[i], sizeof(glm::vec3)) != 0;
        EXPECT_EQ(differ, 0u) << sss::isa_name(isa) << " per-point materials";
    }
}
