// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file diffusion_memory_test.cpp
/// Tests of the low-memory paths: the consuming evaluation (the problem's
/// geometry freed once the octree holds it, the result written over the
/// irradiance), the sources' normals kept only when the disk quadrature may
/// read them, and SsDiffusionFiles (inputs streamed twice, no whole cloud
/// held) against ssdiffusion() written whole, byte for byte. The memory
/// itself is measured by the CLI test cli.test_ptfilter_memory.
///
/// Suite names all contain "Diffusion" so `ctest -R Diffusion` selects them.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include <unistd.h>

#include <glm/geometric.hpp>

#include "sss/cloud/point_cloud.h"
#include "sss/cloud/point_cloud_io.h"
#include "sss/cloud/synthetic.h"
#include "sss/diffusion/diffusion.h"
#include "sss/diffusion/ssdiffusion.h"
#include "sss/util/error.h"
#include "sss/util/math.h"
#include "sss/util/threads.h"

#include "diffusion_test_util.h"
#include "test_util.h"

namespace {

using sss::test::material_profiles;
using sss::test::problem_from;
using sss::test::synthetic;

constexpr sss::Criterion kCriteria[] = {sss::Criterion::Error,
                                        sss::Criterion::SolidAngleBox,
                                        sss::Criterion::SolidAngleCentroid};

bool same_bits(const std::vector<glm::vec3>& a, const std::vector<glm::vec3>& b) {
    return a.size() == b.size() &&
           (a.empty() ||
            std::memcmp(a.data(), b.data(), a.size() * sizeof(glm::vec3)) == 0);
}

/// The consuming evaluation against the const one, every criterion, 1 and 2 threads.
void expect_consuming_matches(const sss::DiffusionProblem& pb, const std::string& what) {
    for (sss::Criterion crit : kCriteria) {
        sss::DiffusionOptions opt;
        opt.criterion = crit;
        const std::vector<glm::vec3> reference = sss::evaluate_diffusion(pb, opt);
        for (int threads : {1, 2}) {
            sss::ThreadLimit limit(threads);
            sss::DiffusionProblem copy = pb;
            sss::DiffusionStats stats;
            std::vector<glm::vec3> consumed =
                sss::evaluate_diffusion(std::move(copy), opt, &stats);
            EXPECT_TRUE(same_bits(consumed, reference))
                << what << ", " << sss::criterion_name(crit) << ", " << threads
                << " threads";
            EXPECT_GT(stats.nodes, 0u);
        }
    }
}

TEST(DiffusionMemory, ConsumingEvaluationIsBitIdentical) {
    expect_consuming_matches(
        problem_from(synthetic(sss::SyntheticShape::Sphere, 20000, 20.0),
                     material_profiles("marble")),
        "sphere");
    // Per-point materials (receiver-by-receiver path) and a thin box.
    sss::DiffusionProblem box = problem_from(
        synthetic(sss::SyntheticShape::Box, 6000, 15.0), material_profiles("skin1"));
    std::vector<sss::Profile> more = material_profiles("marble");
    box.profiles.insert(box.profiles.end(), more.begin(), more.end());
    box.profile_index.resize(box.positions.size());
    for (std::size_t i = 0; i < box.positions.size(); ++i)
        box.profile_index[i] = i % 3 ? glm::u32vec3(0, 1, 2) : glm::u32vec3(3, 4, 5);
    expect_consuming_matches(box, "box with two materials");
    // Coincident points (one big leaf) and negative irradiance.
    sss::DiffusionProblem same = problem_from(
        synthetic(sss::SyntheticShape::Plane, 400, 5.0), material_profiles("ketchup"));
    for (std::size_t i = 0; i < 100; ++i) same.positions[i] = same.positions[0];
    for (std::size_t i = 0; i < same.irradiance.size(); i += 7)
        same.irradiance[i] = -same.irradiance[i];
    expect_consuming_matches(same, "coincident points");
    // Empty and one point.
    sss::DiffusionProblem empty;
    empty.profiles = material_profiles("marble");
    EXPECT_TRUE(sss::evaluate_diffusion(std::move(empty), {}).empty());
    sss::DiffusionProblem one = problem_from(
        synthetic(sss::SyntheticShape::Plane, 1, 5.0), material_profiles("marble"));
    expect_consuming_matches(one, "one point");
}

/// A square grid of points with the given area each, normals tilted at random
/// (seed) or all +z, lit uniformly.
sss::DiffusionProblem grid(double area, const std::vector<sss::Profile>& profiles,
                           unsigned seed) {
    sss::DiffusionProblem pb;
    const int side = 40;
    const double step = std::sqrt(area);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> tilt(-0.5f, 0.5f);
    for (int y = 0; y < side; ++y)
        for (int x = 0; x < side; ++x) {
            pb.positions.push_back(glm::vec3(float(x * step), float(y * step), 0.0f));
            pb.normals.push_back(
                seed ? glm::normalize(glm::vec3(tilt(rng), tilt(rng), 1.0f))
                     : glm::vec3(0, 0, 1));
            pb.areas.push_back(float(area));
            pb.irradiance.push_back(glm::vec3(1.0f, 0.5f, 0.25f));
        }
    pb.profiles = profiles;
    return pb;
}

// The octree keeps the sources' normals only when a source disk may be
// integrated by the quadrature (rho^2 > kNearKappa2 (r^2 + core^2), the only
// reader of the normals). Just below that threshold the normals are not
// stored: the evaluation must then never read them (a crash, or an ASan
// report, if the kernels' condition and the octree's test drift apart), and
// the result cannot depend on them. Well above it, it does.
TEST(DiffusionMemory, NormalsOnlyWhereTheQuadratureMayReadThem) {
    const std::vector<sss::Profile> profiles = material_profiles("skin1");
    double core2 = 1e30;
    for (const sss::Profile& p : profiles)
        core2 = std::min(core2, p.core_length() * p.core_length());
    // rho^2 = area / pi; the threshold is 0.1 core^2.
    const double below = 0.99 * 0.1 * core2 * sss::kPi;
    const double above = 20.0 * core2;
    for (sss::Criterion crit : kCriteria) {
        sss::DiffusionOptions opt;
        opt.criterion = crit;
        const auto flat = sss::evaluate_diffusion(grid(below, profiles, 0), opt);
        const auto tilted = sss::evaluate_diffusion(grid(below, profiles, 5), opt);
        EXPECT_TRUE(same_bits(flat, tilted)) << sss::criterion_name(crit);
        sss::DiffusionProblem consumed = grid(below, profiles, 5);
        EXPECT_TRUE(same_bits(sss::evaluate_diffusion(std::move(consumed), opt), tilted));
        const auto flat_big = sss::evaluate_diffusion(grid(above, profiles, 0), opt);
        const auto tilted_big = sss::evaluate_diffusion(grid(above, profiles, 5), opt);
        EXPECT_FALSE(same_bits(flat_big, tilted_big)) << sss::criterion_name(crit);
    }
}

// ---------------------------------------------------------------------------
// SsDiffusionFiles: streamed from files, byte for byte what ssdiffusion() of
// the merged inputs writes.

/// Runs both ways and compares the output files.
void expect_files_match(const std::vector<std::string>& inputs, const std::string& output,
                        const sss::SsDiffusionOptions& o,
                        const sss::PointCloudWriteOptions& w, const std::string& what) {
    sss::PointCloud merged = sss::read_point_cloud(inputs[0]);
    for (std::size_t i = 1; i < inputs.size(); ++i)
        merged.append(sss::read_point_cloud(inputs[i]));
    sss::SsDiffusionReport whole_report;
    const sss::PointCloud whole = sss::ssdiffusion(merged, o, &whole_report);
    const std::string expected =
        output + ".expected" + output.substr(output.find_last_of('.'));
    sss::write_point_cloud(whole, expected, w);

    sss::SsDiffusionFiles job(inputs, o);
    sss::SsDiffusionReport report;
    job.filter(&report);
    job.write(output, w);
    EXPECT_EQ(job.size(), merged.size()) << what;
    EXPECT_EQ(report.warnings, whole_report.warnings) << what;
    EXPECT_EQ(report.distinct_profiles, whole_report.distinct_profiles) << what;
    EXPECT_EQ(report.stats.far_terms, whole_report.stats.far_terms) << what;
    const sss::test::Bytes got = sss::test::read_bytes(output);
    EXPECT_FALSE(got.empty()) << what;
    EXPECT_TRUE(got == sss::test::read_bytes(expected)) << what;
}

TEST(SsdiffusionFiles, ByteIdenticalToTheWholeCloud) {
    sss::test::TempDir dir("sss_ssd_files");
    const std::string a = dir.file("a.ptc"), b = dir.file("b.ptc"), c = dir.file("c.ply"),
                      gz = dir.file("gz.ptc");
    sss::PointCloud sphere = synthetic(sss::SyntheticShape::Sphere, 70000, 20.0);
    sphere.world_to_eye[3] = 2.5f;
    sss::write_point_cloud(sphere, a);
    // Another input with one more channel and no _area: zero areas there.
    sss::PointCloud box = synthetic(sss::SyntheticShape::Box, 3000, 10.0, 0.1);
    for (glm::vec3& p : box.positions) p += glm::vec3(30.0f, 0.0f, 0.0f);
    sss::Channel& extra = box.add_channel("extra", sss::ChannelType::Float);
    for (std::size_t i = 0; i < extra.data.size(); ++i) extra.data[i] = float(i);
    box.channels.erase(box.channels.begin()); // _area
    sss::write_point_cloud(box, b);
    sss::write_point_cloud(synthetic(sss::SyntheticShape::Plane, 2000, 8.0), c);
    sss::PointCloudWriteOptions zipped;
    zipped.compress = true;
    sss::write_point_cloud(sphere, gz, zipped);

    sss::SsDiffusionOptions o;
    expect_files_match({a}, dir.file("o1.ptc"), o, {}, "one input");
    expect_files_match({a, b}, dir.file("o2.ptc"), o, {}, "two inputs");
    sss::PointCloudWriteOptions v2;
    v2.ptc_version = 2;
    v2.compress = true;
    sss::SsDiffusionOptions keep = o;
    keep.keep_channels = true;
    keep.material.unitlength = 0.1;
    expect_files_match({b, a, c}, dir.file("o3.ptc"), keep, v2, "keep, three inputs, v2");
    expect_files_match({gz, c}, dir.file("o4.ply"), keep, {}, "gzip and ply in, ply out");
    sss::SsDiffusionOptions radius = o;
    radius.area_channel = "_none"; // pi radius^2, with a warning
    radius.diffusion.criterion = sss::Criterion::SolidAngleBox;
    expect_files_match({c}, dir.file("o5.ptc"), radius, {}, "areas from radii");
    sss::SsDiffusionOptions exact = o;
    exact.exact = true;
    expect_files_match({c}, dir.file("o6.ptc"), exact, {}, "exact");
    // Per-point materials from a channel.
    sss::PointCloud plane = synthetic(sss::SyntheticShape::Plane, 3000, 8.0);
    sss::Channel& albedo = plane.add_channel("_albedo", sss::ChannelType::Color);
    for (std::size_t i = 0; i < albedo.data.size(); ++i)
        albedo.data[i] = 0.3f + 0.6f * float(i % 7) / 7.0f;
    sss::write_point_cloud(plane, dir.file("albedo.ptc"));
    sss::SsDiffusionOptions per_point = o;
    per_point.material.albedo_from_file = true;
    expect_files_match({dir.file("albedo.ptc"), c}, dir.file("o7.ptc"), per_point, {},
                       "per-point albedo");
    // An empty input.
    sss::PointCloud none = sphere;
    none.resize(0);
    sss::write_point_cloud(none, dir.file("empty.ptc"));
    expect_files_match({dir.file("empty.ptc")}, dir.file("o8.ptc"), o, {}, "empty");
}

TEST(SsdiffusionFiles, Errors) {
    sss::test::TempDir dir("sss_ssd_files_err");
    const std::string a = dir.file("a.ptc");
    sss::PointCloud cloud = synthetic(sss::SyntheticShape::Plane, 500, 8.0);
    sss::write_point_cloud(cloud, a);
    // Missing radiance channel: the same error as ssdiffusion().
    sss::SsDiffusionOptions o;
    o.radiance_channel = "_nothing";
    {
        sss::SsDiffusionFiles job({a}, o);
        EXPECT_THROW(job.filter(), sss::MissingChannelError);
    }
    // A negative area, named as ssdiffusion() names it.
    const sss::SsDiffusionOptions defaults;
    sss::PointCloud bad = cloud;
    bad.find_channel("_area")->data[17] = -1.0f;
    sss::write_point_cloud(bad, dir.file("bad.ptc"));
    std::string whole_error, files_error;
    try {
        sss::ssdiffusion(bad, defaults);
    } catch (const sss::ValueError& e) {
        whole_error = e.what();
    }
    try {
        sss::SsDiffusionFiles job({dir.file("bad.ptc")}, defaults);
        job.filter();
    } catch (const sss::ValueError& e) {
        files_error = e.what();
    }
    EXPECT_FALSE(whole_error.empty());
    EXPECT_EQ(files_error, whole_error);
    // Channels of one name and two types.
    sss::PointCloud other = cloud;
    other.channels[0].type = sss::ChannelType::Color;
    other.channels[0].data.resize(3 * other.size());
    sss::write_point_cloud(other, dir.file("other.ptc"));
    EXPECT_THROW(sss::SsDiffusionFiles({a, dir.file("other.ptc")}, defaults),
                 sss::ValueError);
    // An input that changes between the two reads: nothing written.
    {
        sss::SsDiffusionFiles job({a}, defaults);
        job.filter();
        sss::PointCloud changed = cloud;
        changed.resize(400);
        sss::write_point_cloud(changed, a);
        EXPECT_THROW(job.write(dir.file("out.ptc")), sss::IoError);
        EXPECT_FALSE(std::filesystem::exists(dir.file("out.ptc")));
    }
    // A missing input.
    EXPECT_THROW(sss::SsDiffusionFiles({dir.file("none.ptc")}, defaults), sss::IoError);
}

} // namespace
