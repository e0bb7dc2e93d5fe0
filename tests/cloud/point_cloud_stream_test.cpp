// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file point_cloud_stream_test.cpp
/// PointCloudReader and PointCloudWriter: a cloud read or written a chunk at
/// a time is the cloud read_point_cloud() returns and the file
/// write_point_cloud() writes, byte for byte, for every .ptc version,
/// compressed or not, and .ply.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "sss/cloud/point_cloud.h"
#include "sss/cloud/point_cloud_io.h"
#include "sss/cloud/synthetic.h"
#include "sss/util/error.h"

#include "test_util.h"

namespace {

sss::PointCloud sample_cloud() {
    sss::SyntheticParams sp;
    sp.shape = sss::SyntheticShape::Box;
    sp.count = 5000;
    sp.size = 10.0;
    sss::PointCloud c = sss::make_synthetic_cloud(sp);
    sss::Channel& m = c.add_channel("m", sss::ChannelType::Matrix);
    for (std::size_t i = 0; i < m.data.size(); ++i) m.data[i] = float(i % 97) - 40.0f;
    c.normals[3] = glm::vec3(0.0f); // "no normal"
    c.world_to_ndc[5] = 3.0f;
    c.format = {640.0f, 480.0f, 1.0f};
    return c;
}

bool same_cloud(const sss::PointCloud& a, const sss::PointCloud& b) {
    if (a.size() != b.size() || a.channels.size() != b.channels.size()) return false;
    for (std::size_t c = 0; c < a.channels.size(); ++c)
        if (a.channels[c].name != b.channels[c].name ||
            a.channels[c].type != b.channels[c].type ||
            a.channels[c].data != b.channels[c].data)
            return false;
    return a.positions == b.positions && a.normals == b.normals && a.radii == b.radii &&
           a.world_to_eye == b.world_to_eye && a.world_to_ndc == b.world_to_ndc &&
           a.format == b.format;
}

/// Reads `path` in chunks of `chunk` points and appends them.
sss::PointCloud read_chunked(const std::string& path, std::size_t chunk) {
    sss::PointCloudReader reader(path);
    sss::PointCloud all = reader.header();
    EXPECT_EQ(all.size(), 0u);
    sss::PointCloud part;
    std::size_t total = 0;
    while (std::size_t k = reader.read(part, chunk)) {
        EXPECT_LE(k, chunk);
        EXPECT_EQ(part.size(), k);
        all.append(part);
        total += k;
    }
    EXPECT_EQ(total, reader.size());
    EXPECT_EQ(reader.read(part, chunk), 0u);
    return all;
}

/// Writes `cloud` in chunks of `chunk` points.
void write_chunked(const sss::PointCloud& cloud, const std::string& path,
                   std::size_t chunk, const sss::PointCloudWriteOptions& options) {
    float max_radius = 0.0f;
    for (float r : cloud.radii) max_radius = std::max(max_radius, r);
    sss::PointCloudWriter writer(path, cloud, cloud.size(), cloud.bounds(), max_radius,
                                 options);
    for (std::size_t first = 0; first < cloud.size(); first += chunk) {
        const std::size_t k = std::min(chunk, cloud.size() - first);
        sss::PointCloud part = cloud;
        part.positions.assign(cloud.positions.begin() + first,
                              cloud.positions.begin() + first + k);
        part.normals.assign(cloud.normals.begin() + first,
                            cloud.normals.begin() + first + k);
        part.radii.assign(cloud.radii.begin() + first, cloud.radii.begin() + first + k);
        for (std::size_t c = 0; c < cloud.channels.size(); ++c) {
            const std::size_t w = std::size_t(cloud.channels[c].components());
            part.channels[c].data.assign(cloud.channels[c].data.begin() + first * w,
                                         cloud.channels[c].data.begin() +
                                             (first + k) * w);
        }
        writer.write(part);
    }
    writer.commit();
}

TEST(CloudStream, ChunksAreTheWholeFile) {
    sss::test::TempDir dir("sss_cloud_stream");
    const sss::PointCloud cloud = sample_cloud();
    int file = 0;
    for (const char* ext : {".ptc", ".ply"})
        for (int version = 0; version <= 2; ++version)
            for (bool compress : {false, true}) {
                if (std::string(ext) == ".ply" && (version > 0 || compress)) continue;
                sss::PointCloudWriteOptions o;
                o.ptc_version = version;
                o.compress = compress;
                const std::string tail = std::to_string(file++) + ext;
                const std::string whole = dir.file(std::string("w").append(tail));
                const std::string chunked = dir.file(std::string("c").append(tail));
                sss::write_point_cloud(cloud, whole, o);
                const sss::PointCloud back = sss::read_point_cloud(whole);
                for (std::size_t chunk :
                     {std::size_t(1), std::size_t(777), std::size_t(1) << 20}) {
                    write_chunked(cloud, chunked, chunk, o);
                    EXPECT_TRUE(sss::test::read_bytes(chunked) ==
                                sss::test::read_bytes(whole))
                        << whole << " chunk " << chunk;
                    EXPECT_TRUE(same_cloud(read_chunked(whole, chunk), back))
                        << whole << " chunk " << chunk;
                }
            }
    // An empty cloud.
    sss::PointCloud empty = cloud;
    empty.resize(0);
    sss::write_point_cloud(empty, dir.file("e.ptc"));
    write_chunked(empty, dir.file("e2.ptc"), 10, {});
    EXPECT_TRUE(sss::test::read_bytes(dir.file("e.ptc")) ==
                sss::test::read_bytes(dir.file("e2.ptc")));
    EXPECT_TRUE(same_cloud(read_chunked(dir.file("e.ptc"), 10), empty));
}

TEST(CloudStream, Errors) {
    sss::test::TempDir dir("sss_cloud_stream_err");
    const sss::PointCloud cloud = sample_cloud();
    sss::write_point_cloud(cloud, dir.file("a.ptc"));
    // Truncated: the reader fails where read_point_cloud fails.
    sss::test::Bytes bytes = sss::test::read_bytes(dir.file("a.ptc"));
    bytes.resize(bytes.size() - 10);
    sss::test::write_bytes(dir.file("t.ptc"), bytes);
    EXPECT_THROW(sss::read_point_cloud(dir.file("t.ptc")), sss::FormatError);
    EXPECT_THROW(read_chunked(dir.file("t.ptc"), 100), sss::FormatError);
    EXPECT_THROW(sss::PointCloudReader(dir.file("none.ptc")), sss::IoError);
    // Fewer or more points than announced: nothing is written.
    for (const char* name : {"few.ptc", "few.ply"}) {
        {
            sss::PointCloudWriter writer(dir.file(name), cloud, cloud.size() + 1,
                                         cloud.bounds(), 1.0f);
            writer.write(cloud);
            EXPECT_THROW(writer.commit(), sss::ValueError) << name;
        }
        EXPECT_FALSE(std::filesystem::exists(dir.file(name))) << name;
    }
    {
        sss::PointCloudWriter writer(dir.file("many.ptc"), cloud, 10, cloud.bounds(),
                                     1.0f);
        EXPECT_THROW(writer.write(cloud), sss::ValueError);
    }
    EXPECT_FALSE(std::filesystem::exists(dir.file("many.ptc")));
}

} // namespace
