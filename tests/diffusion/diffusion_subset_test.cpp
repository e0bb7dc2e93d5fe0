// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file diffusion_subset_test.cpp
/// Tests of evaluate_diffusion_at, evaluate_diffusion_part and the tolerance
/// reference: any subset of the receivers (or any part of a split run),
/// evaluated against the whole cloud, gets bit for bit the numbers of the
/// whole run, for every criterion, path (block, per receiver, coincident
/// points) and thread count.
///
/// Suite names all contain "Diffusion" so `ctest -R Diffusion` selects them.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "sss/cloud/point_cloud.h"
#include "sss/cloud/synthetic.h"
#include "sss/diffusion/diffusion.h"
#include "sss/util/error.h"
#include "sss/util/threads.h"

#include "diffusion_test_util.h"

namespace {

using sss::test::material_profiles;
using sss::test::problem_from;
using sss::test::synthetic;

constexpr sss::Criterion kCriteria[] = {sss::Criterion::Error,
                                        sss::Criterion::SolidAngleBox,
                                        sss::Criterion::SolidAngleCentroid};

sss::DiffusionProblem sphere_problem() {
    return problem_from(synthetic(sss::SyntheticShape::Sphere, 20000, 20.0),
                        material_profiles("marble"));
}

/// Receivers of every kind: a contiguous range, scattered indices, one point,
/// both ends, and repeats.
std::vector<std::vector<std::size_t>> subsets(std::size_t n) {
    std::vector<std::vector<std::size_t>> out;
    std::vector<std::size_t> range(500);
    std::iota(range.begin(), range.end(), n / 3);
    out.push_back(range);
    std::vector<std::size_t> scattered;
    std::mt19937 rng(7);
    for (int k = 0; k < 300; ++k) scattered.push_back(rng() % n);
    out.push_back(scattered);
    out.push_back({n / 2});
    out.push_back({n - 1, 0, n - 1, 17, 17});
    return out;
}

bool same_bits(const glm::vec3& a, const glm::vec3& b) {
    return std::memcmp(&a, &b, sizeof(glm::vec3)) == 0;
}

/// Checks every subset against the whole run, for every criterion, at 1 and
/// 2 threads.
void expect_subsets_match(const sss::DiffusionProblem& pb, const std::string& what,
                          double max_solid_angle = 1.0) {
    for (sss::Criterion crit : kCriteria) {
        sss::DiffusionOptions opt;
        opt.criterion = crit;
        opt.max_solid_angle = max_solid_angle;
        std::vector<glm::vec3> whole = sss::evaluate_diffusion(pb, opt);
        for (const std::vector<std::size_t>& rec : subsets(pb.positions.size())) {
            for (int threads : {1, 2}) {
                sss::ThreadLimit limit(threads);
                std::vector<glm::vec3> part = sss::evaluate_diffusion_at(pb, opt, rec);
                ASSERT_EQ(part.size(), rec.size());
                std::size_t differ = 0;
                for (std::size_t k = 0; k < rec.size(); ++k)
                    if (!same_bits(part[k], whole[rec[k]])) ++differ;
                EXPECT_EQ(differ, 0u)
                    << what << ", " << sss::criterion_name(crit) << ": " << rec.size()
                    << " receivers from " << rec[0] << ", " << threads << " threads";
            }
        }
    }
}

/// Splits the run into 1, 2, 3, 7 and 64 parts at 1 and 2 threads: the parts
/// tile the space-filling order, hold every point once, and their results are
/// the whole run's bit for bit.
void expect_parts_match(const sss::DiffusionProblem& pb, const std::string& what,
                        double max_solid_angle = 1.0) {
    const std::size_t n = pb.positions.size();
    const std::vector<uint32_t> order = sss::space_filling_order(pb);
    ASSERT_EQ(order.size(), n);
    for (sss::Criterion crit : kCriteria) {
        sss::DiffusionOptions opt;
        opt.criterion = crit;
        opt.max_solid_angle = max_solid_angle;
        std::vector<glm::vec3> whole = sss::evaluate_diffusion(pb, opt);
        for (std::size_t parts : {1u, 2u, 3u, 7u, 64u}) {
            for (int threads : {1, 2}) {
                sss::ThreadLimit limit(threads);
                std::vector<int> seen(n, 0);
                std::size_t next = 0, differ = 0;
                for (std::size_t k = 0; k < parts; ++k) {
                    sss::DiffusionPart part =
                        sss::evaluate_diffusion_part(pb, opt, k, parts);
                    ASSERT_EQ(part.first, next) << what << " part " << k << "/" << parts;
                    ASSERT_EQ(part.result.size(), part.receivers.size());
                    // Contiguous in the space-filling order, sizes within one.
                    EXPECT_LE(part.receivers.size(), n / parts + 1);
                    EXPECT_GE(part.receivers.size(), n / parts);
                    for (std::size_t j = 0; j < part.receivers.size(); ++j) {
                        ASSERT_EQ(part.receivers[j], order[next + j]);
                        ++seen[part.receivers[j]];
                        if (!same_bits(part.result[j], whole[part.receivers[j]]))
                            ++differ;
                    }
                    next += part.receivers.size();
                }
                EXPECT_EQ(next, n);
                EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), std::ptrdiff_t(n));
                EXPECT_EQ(differ, 0u) << what << ", " << sss::criterion_name(crit) << ", "
                                      << parts << " parts, " << threads << " threads";
            }
        }
    }
}

TEST(DiffusionSubset, Sphere) {
    expect_subsets_match(sphere_problem(), "sphere");
}

TEST(DiffusionPart, SphereParts) {
    expect_parts_match(sphere_problem(), "sphere");
}

TEST(DiffusionPart, PerPointMaterialsAndCoincidentParts) {
    sss::DiffusionProblem pb = problem_from(
        synthetic(sss::SyntheticShape::Plane, 4000, 10.0), material_profiles("marble"));
    for (std::size_t i = 0; i < 300; ++i) {
        pb.positions[i] = pb.positions[0];
        pb.normals[i] = pb.normals[0];
    }
    std::vector<sss::Profile> more = material_profiles("ketchup");
    pb.profiles.insert(pb.profiles.end(), more.begin(), more.end());
    pb.profile_index.resize(pb.positions.size());
    for (std::size_t i = 0; i < pb.positions.size(); ++i)
        pb.profile_index[i] = i % 7 == 0 ? glm::u32vec3(3, 4, 5) : glm::u32vec3(0, 1, 2);
    expect_parts_match(pb, "per point, coincident", 0.5);
}

TEST(DiffusionPart, EdgeCases) {
    sss::DiffusionProblem pb = sphere_problem();
    EXPECT_THROW(sss::evaluate_diffusion_part(pb, {}, 4, 4), sss::ValueError);
    EXPECT_THROW(sss::evaluate_diffusion_part(pb, {}, 0, 0), sss::ValueError);
    EXPECT_THROW(sss::part_range(10, 3, 3), sss::ValueError);
    // More parts than points: empty parts, and the others one point each.
    EXPECT_EQ(sss::part_range(3, 0, 5), std::make_pair(std::size_t(0), std::size_t(0)));
    EXPECT_EQ(sss::part_range(3, 4, 5), std::make_pair(std::size_t(2), std::size_t(3)));
    EXPECT_EQ(sss::part_range(4000000000u, 1, 2).first, 2000000000u);
    sss::DiffusionProblem tiny = pb;
    tiny.positions.resize(3);
    tiny.normals.resize(3);
    tiny.areas.resize(3);
    tiny.irradiance.resize(3);
    std::size_t total = 0;
    for (std::size_t k = 0; k < 5; ++k)
        total += sss::evaluate_diffusion_part(tiny, {}, k, 5).receivers.size();
    EXPECT_EQ(total, 3u);
    sss::DiffusionProblem empty;
    empty.profiles = material_profiles("marble");
    EXPECT_TRUE(sss::evaluate_diffusion_part(empty, {}, 0, 2).receivers.empty());
    // The overload that frees the problem's geometry gives the same part.
    sss::DiffusionPart kept = sss::evaluate_diffusion_part(pb, {}, 2, 3);
    sss::DiffusionProblem copy = pb;
    sss::DiffusionPart freed = sss::evaluate_diffusion_part(std::move(copy), {}, 2, 3);
    EXPECT_TRUE(copy.positions.empty() && copy.areas.empty());
    EXPECT_EQ(freed.receivers, kept.receivers);
    ASSERT_EQ(freed.result.size(), kept.result.size());
    EXPECT_EQ(std::memcmp(freed.result.data(), kept.result.data(),
                          kept.result.size() * sizeof(glm::vec3)),
              0);
    // A part's work is about its share of the whole run's.
    sss::DiffusionStats quarter, all;
    sss::evaluate_diffusion_part(pb, {}, 1, 4, &quarter);
    sss::evaluate_diffusion(pb, {}, &all);
    EXPECT_LT(quarter.far_terms + quarter.near_terms,
              (all.far_terms + all.near_terms) / 3);
}

TEST(DiffusionSubset, ThinBoxOtherSettings) {
    sss::DiffusionProblem pb =
        problem_from(synthetic(sss::SyntheticShape::Box, 20000, 40.0),
                     material_profiles("skin1", 1.0, sss::ProfileKind::Better));
    expect_subsets_match(pb, "thin box", 0.3);
}

// Per-point materials: buckets of mixed materials take the receiver-by-receiver
// path with the error criterion.
TEST(DiffusionSubset, PerPointMaterials) {
    sss::DiffusionProblem pb = sphere_problem();
    std::vector<sss::Profile> more = material_profiles("ketchup");
    pb.profiles.insert(pb.profiles.end(), more.begin(), more.end());
    pb.profile_index.resize(pb.positions.size());
    for (std::size_t i = 0; i < pb.positions.size(); ++i)
        pb.profile_index[i] = (i % 5 == 0 || pb.positions[i].x > 5.0f)
                                  ? glm::u32vec3(3, 4, 5)
                                  : glm::u32vec3(0, 1, 2);
    expect_subsets_match(pb, "per point");
}

// Identical points make one big leaf whose sum is shared by its receivers.
TEST(DiffusionSubset, CoincidentPoints) {
    sss::DiffusionProblem pb = problem_from(
        synthetic(sss::SyntheticShape::Plane, 4000, 10.0), material_profiles("marble"));
    for (std::size_t i = 0; i < 300; ++i) {
        pb.positions[i] = pb.positions[0];
        pb.normals[i] = pb.normals[0];
    }
    expect_subsets_match(pb, "coincident");
}

// The default reference is diffusion_reference(problem); passing it changes
// nothing, passing another changes the error criterion's numbers.
TEST(DiffusionSubset, ReferenceIsAnInput) {
    sss::DiffusionProblem pb = sphere_problem();
    sss::DiffusionOptions opt;
    std::vector<glm::vec3> whole = sss::evaluate_diffusion(pb, opt);
    sss::DiffusionReference ref = sss::diffusion_reference(pb);
    EXPECT_GT(ref.area, 0.0f);
    EXPECT_GT(ref.abs_power[0], 0.0f);
    EXPECT_EQ(sss::diffusion_reference(pb), ref); // deterministic
    opt.reference = ref;
    std::vector<glm::vec3> given = sss::evaluate_diffusion(pb, opt);
    ASSERT_EQ(given.size(), whole.size());
    EXPECT_EQ(std::memcmp(given.data(), whole.data(), whole.size() * sizeof(glm::vec3)),
              0);

    // A part of the cloud (its first half as its own problem) has another
    // reference; the whole one is what a part's run must be given.
    sss::DiffusionProblem half = pb;
    const std::size_t m = pb.positions.size() / 2;
    half.positions.resize(m);
    half.normals.resize(m);
    half.areas.resize(m);
    half.irradiance.resize(m);
    EXPECT_NE(sss::diffusion_reference(half), ref);

    // A higher floor of the tolerance: less work, other numbers.
    sss::DiffusionReference bright = ref;
    for (float& p : bright.abs_power) p *= 100.0f;
    sss::DiffusionStats own, loose;
    opt.reference = ref;
    sss::evaluate_diffusion(pb, opt, &own);
    opt.reference = bright;
    std::vector<glm::vec3> other = sss::evaluate_diffusion(pb, opt, &loose);
    EXPECT_NE(std::memcmp(other.data(), whole.data(), whole.size() * sizeof(glm::vec3)),
              0);
    EXPECT_LT(loose.far_terms + loose.near_terms, own.far_terms + own.near_terms);
}

TEST(DiffusionSubset, EdgeCases) {
    sss::DiffusionProblem pb = sphere_problem();
    const std::size_t n = pb.positions.size();
    EXPECT_TRUE(sss::evaluate_diffusion_at(pb, {}, {}).empty());
    EXPECT_THROW(sss::evaluate_diffusion_at(pb, {}, {0, n}), sss::ValueError);

    // One receiver costs its bucket, not the cloud.
    sss::DiffusionStats one, all;
    sss::evaluate_diffusion_at(pb, {}, {n / 2}, &one);
    sss::evaluate_diffusion(pb, {}, &all);
    EXPECT_EQ(one.nodes, all.nodes);
    EXPECT_LT(100 * (one.far_terms + one.near_terms), all.far_terms + all.near_terms);

    sss::DiffusionProblem empty;
    empty.profiles = material_profiles("marble");
    EXPECT_TRUE(sss::evaluate_diffusion_at(empty, {}, {}).empty());
    EXPECT_THROW(sss::evaluate_diffusion_at(empty, {}, {0}), sss::ValueError);
    EXPECT_EQ(sss::diffusion_reference(empty), sss::DiffusionReference{});
}

} // namespace
