// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file cloud_part_test.cpp
/// Part files (.ptpart) and their join: round trips, the merge in any order
/// equal to the whole cloud, and every damaged, missing, repeated or foreign
/// part refused before anything is written.

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "sss/cloud/cloud_part.h"
#include "sss/cloud/point_cloud_io.h"
#include "sss/util/error.h"

#include "test_util.h"

namespace {

/// A cloud with every kind of data: normals (one zero), radii, a float, a
/// color and a matrix channel, header matrices and format.
sss::PointCloud sample_cloud(std::size_t n) {
    sss::PointCloud c;
    c.resize(n);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-5.0f, 5.0f);
    for (std::size_t i = 0; i < n; ++i) {
        c.positions[i] = {u(rng), u(rng), u(rng)};
        c.normals[i] = i == 0 ? glm::vec3(0.0f) : glm::vec3(0.0f, 0.6f, 0.8f);
        c.radii[i] = 0.01f * float(i + 1);
    }
    sss::Channel& a = c.add_channel("_area", sss::ChannelType::Float);
    for (std::size_t i = 0; i < n; ++i) a.data[i] = float(i);
    sss::Channel& col = c.add_channel("_ssdiffusion", sss::ChannelType::Color);
    for (std::size_t i = 0; i < col.data.size(); ++i) col.data[i] = u(rng);
    sss::Channel& m = c.add_channel("xform", sss::ChannelType::Matrix);
    for (std::size_t i = 0; i < m.data.size(); ++i) m.data[i] = float(i % 17);
    c.world_to_eye[3] = 2.5f;
    c.world_to_ndc[7] = -1.0f;
    c.format = {640.0f, 480.0f, 1.0f};
    return c;
}

/// Splits `whole` into `parts` parts over a shuffled order (as a space-filling
/// order would scatter indices) and writes them; returns their paths.
std::vector<std::string> write_parts(const sss::PointCloud& whole, uint32_t parts,
                                     const std::string& dir, uint64_t fingerprint = 42,
                                     sss::PointCloudWriteOptions wopt = {}) {
    const std::size_t n = whole.size();
    std::vector<uint64_t> order(n);
    std::iota(order.begin(), order.end(), 0);
    std::shuffle(order.begin(), order.end(), std::mt19937(9));
    std::vector<std::string> paths;
    for (uint32_t k = 0; k < parts; ++k) {
        const std::size_t first = n * k / parts, end = n * (k + 1) / parts;
        sss::CloudPart p;
        p.info = {k + 1, parts, fingerprint, n, first, end - first, wopt};
        p.indices.assign(order.begin() + std::ptrdiff_t(first),
                         order.begin() + std::ptrdiff_t(end));
        p.points.world_to_eye = whole.world_to_eye;
        p.points.world_to_ndc = whole.world_to_ndc;
        p.points.format = whole.format;
        for (const sss::Channel& ch : whole.channels)
            p.points.add_channel(ch.name, ch.type);
        p.points.resize(end - first);
        for (std::size_t j = 0; j < end - first; ++j) {
            const std::size_t i = p.indices[j];
            p.points.positions[j] = whole.positions[i];
            p.points.normals[j] = whole.normals[i];
            p.points.radii[j] = whole.radii[i];
            for (std::size_t c = 0; c < whole.channels.size(); ++c) {
                const std::size_t w = std::size_t(whole.channels[c].components());
                for (std::size_t q = 0; q < w; ++q)
                    p.points.channels[c].data[w * j + q] =
                        whole.channels[c].data[w * i + q];
            }
        }
        paths.push_back(dir + "/p" + std::to_string(k + 1) + ".ptpart");
        sss::write_cloud_part(p, paths.back());
    }
    return paths;
}

void expect_same(const sss::PointCloud& a, const sss::PointCloud& b) {
    EXPECT_EQ(a.positions, b.positions);
    EXPECT_EQ(a.normals, b.normals);
    EXPECT_EQ(a.radii, b.radii);
    EXPECT_EQ(a.world_to_eye, b.world_to_eye);
    EXPECT_EQ(a.world_to_ndc, b.world_to_ndc);
    EXPECT_EQ(a.format, b.format);
    ASSERT_EQ(a.channels.size(), b.channels.size());
    for (std::size_t c = 0; c < a.channels.size(); ++c) {
        EXPECT_EQ(a.channels[c].name, b.channels[c].name);
        EXPECT_EQ(a.channels[c].type, b.channels[c].type);
        EXPECT_EQ(a.channels[c].data, b.channels[c].data);
    }
}

std::string bytes_of(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(f), {}};
}

void put_bytes(const std::string& path, const std::string& bytes) {
    std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

template <class E>
std::string error_of(const std::function<void()>& f) {
    try {
        f();
    } catch (const E& e) {
        return e.what();
    } catch (const std::exception& e) {
        return std::string("WRONG EXCEPTION TYPE: ") + e.what();
    }
    return "NO EXCEPTION";
}

TEST(CloudPart, RoundTripAndMergeInAnyOrder) {
    sss::test::TempDir dir;
    const std::string root = dir.path().string();
    const sss::PointCloud whole = sample_cloud(1001);
    sss::PointCloudWriteOptions wopt{2, true};
    for (uint32_t parts : {1u, 2u, 5u}) {
        std::vector<std::string> paths = write_parts(whole, parts, root, 7, wopt);
        sss::CloudPartInfo info = sss::read_cloud_part_info(paths.back());
        EXPECT_EQ(info.part, parts);
        EXPECT_EQ(info.parts, parts);
        EXPECT_EQ(info.fingerprint, 7u);
        EXPECT_EQ(info.total, 1001u);
        EXPECT_EQ(info.first + info.count, 1001u);
        EXPECT_EQ(info.write_options.ptc_version, 2);
        EXPECT_TRUE(info.write_options.compress);
        sss::CloudPart p = sss::read_cloud_part(paths[0]);
        EXPECT_EQ(p.indices.size(), p.points.size());
        std::reverse(paths.begin(), paths.end());
        sss::PointCloudWriteOptions got;
        sss::PointCloud merged = sss::merge_cloud_parts(paths, got);
        expect_same(merged, whole);
        EXPECT_EQ(got.ptc_version, 2);
        EXPECT_TRUE(got.compress);
        for (const std::string& q : paths) std::filesystem::remove(q);
    }
    // An empty cloud in one part, and more parts than points.
    sss::PointCloud none = sample_cloud(0);
    sss::PointCloudWriteOptions got;
    expect_same(sss::merge_cloud_parts(write_parts(none, 1, root), got), none);
    sss::PointCloud three = sample_cloud(3);
    expect_same(sss::merge_cloud_parts(write_parts(three, 5, root), got), three);
}

TEST(CloudPart, MissingRepeatedAndForeignParts) {
    sss::test::TempDir dir;
    const std::string root = dir.path().string();
    const sss::PointCloud whole = sample_cloud(500);
    std::filesystem::create_directories(root + "/a");
    std::filesystem::create_directories(root + "/b");
    std::filesystem::create_directories(root + "/c");
    std::vector<std::string> a = write_parts(whole, 4, root + "/a", 1);
    std::vector<std::string> b = write_parts(whole, 4, root + "/b", 2);
    std::vector<std::string> c = write_parts(whole, 3, root + "/c", 1);
    sss::PointCloudWriteOptions got;
    auto merge = [&](std::vector<std::string> paths) {
        return error_of<sss::Error>([&] { sss::merge_cloud_parts(paths, got); });
    };
    EXPECT_NE(merge({a[0], a[1], a[3]}).find("missing part 3 of 4"), std::string::npos)
        << merge({a[0], a[1], a[3]});
    EXPECT_NE(merge({a[0], a[1], a[1], a[3]}).find("part 2/4 given twice"),
              std::string::npos);
    EXPECT_NE(merge({a[0], a[1], b[2], a[3]}).find("is not from the job of"),
              std::string::npos);
    EXPECT_NE(merge({a[0], a[1], c[2], a[3]}).find("is not from the job of"),
              std::string::npos);
    EXPECT_NE(merge({}).find("no part files"), std::string::npos);
    EXPECT_NE(merge({a[0], a[1], a[2], a[3], root + "/nope.ptpart"}).find("nope"),
              std::string::npos);
    // A point cloud is not a part.
    sss::write_point_cloud(whole, root + "/w.ptc");
    EXPECT_NE(merge({root + "/w.ptc"}).find("not a part file"), std::string::npos);
}

TEST(CloudPart, DamageIsAlwaysAnError) {
    sss::test::TempDir dir;
    const std::string root = dir.path().string();
    const sss::PointCloud whole = sample_cloud(40);
    std::vector<std::string> paths = write_parts(whole, 2, root);
    const std::string good = bytes_of(paths[0]);
    sss::PointCloudWriteOptions got;
    // Every truncation, and every byte changed, fails the merge.
    std::size_t accepted = 0;
    for (std::size_t len = 0; len < good.size(); len += (len < 300 ? 1 : 37)) {
        put_bytes(paths[0], good.substr(0, len));
        if (error_of<sss::Error>([&] { sss::merge_cloud_parts(paths, got); }) ==
            "NO EXCEPTION")
            ++accepted;
    }
    EXPECT_EQ(accepted, 0u) << "truncations accepted";
    put_bytes(paths[0], good + "x");
    EXPECT_NE(error_of<sss::FormatError>([&] {
                  sss::merge_cloud_parts(paths, got);
              }).find("bytes after its end"),
              std::string::npos);
    for (std::size_t at = 0; at < good.size(); ++at) {
        std::string bad = good;
        bad[at] = char(bad[at] ^ 0x20);
        put_bytes(paths[0], bad);
        const std::string e =
            error_of<sss::Error>([&] { sss::merge_cloud_parts(paths, got); });
        if (e == "NO EXCEPTION" || e.find("WRONG") == 0) {
            ADD_FAILURE() << "byte " << at << ": " << e;
            break;
        }
    }
    put_bytes(paths[0], good);
    expect_same(sss::merge_cloud_parts(paths, got), whole);
}

TEST(CloudPart, InconsistentPartsAreNotWritten) {
    sss::test::TempDir dir;
    const std::string root = dir.path().string();
    sss::CloudPart p;
    p.info = {3, 2, 0, 10, 0, 0, {}};
    const std::string path = root + "/x.ptpart";
    EXPECT_THROW(sss::write_cloud_part(p, path), sss::ValueError);
    p.info = {1, 2, 0, 10, 0, 1, {}};
    p.points.resize(1);
    p.indices = {10}; // out of range
    EXPECT_THROW(sss::write_cloud_part(p, path), sss::ValueError);
    EXPECT_FALSE(std::filesystem::exists(path));
}

TEST(CloudPart, FingerprintSeesEveryChange) {
    const sss::PointCloud base = sample_cloud(100);
    const uint64_t f = sss::cloud_fingerprint(base);
    EXPECT_EQ(sss::cloud_fingerprint(sample_cloud(100)), f);
    EXPECT_NE(sss::cloud_fingerprint(base, 1), f);
    std::vector<sss::PointCloud> changed(6, base);
    changed[0].positions[50].x += 1e-6f;
    changed[1].normals[3].z = -changed[1].normals[3].z;
    changed[2].radii[99] *= 2.0f;
    changed[3].channels[1].data[7] += 1.0f;
    changed[4].channels[0].name = "_area2";
    changed[5].world_to_eye[0] = 2.0f;
    for (std::size_t k = 0; k < changed.size(); ++k)
        EXPECT_NE(sss::cloud_fingerprint(changed[k]), f) << "change " << k;
    EXPECT_NE(sss::cloud_fingerprint(sample_cloud(99)), f);
}

} // namespace
