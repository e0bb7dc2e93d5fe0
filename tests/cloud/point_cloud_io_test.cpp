// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file point_cloud_io_test.cpp
/// PointCloud container operations and the .ptc / .ply readers and writers:
/// round trips, the byte layout (pinned by hand-crafted files, not by our own
/// writer) and every kind of malformed input.

#include <gtest/gtest.h>

#include "test_util.h"

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <unistd.h>
#include <zlib.h>

#include <glm/geometric.hpp>

#include "sss/cloud/point_cloud.h"
#include "sss/cloud/point_cloud_io.h"
#include "sss/util/error.h"

namespace fs = std::filesystem;
using sss::Channel;
using sss::ChannelType;
using sss::PointCloud;

namespace {

using sss::test::Bytes;
using sss::test::read_bytes;
using sss::test::write_bytes;

// ---------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------

using sss::test::TempDir;

/// prefix + number + suffix; built with += (g++ 12 warns falsely on "x" + to_string).
std::string numbered(const char* prefix, long long n, const char* suffix) {
    std::string s = prefix;
    s += std::to_string(n);
    s += suffix;
    return s;
}

Bytes gzip_bytes(const Bytes& raw) {
    z_stream zs{};
    EXPECT_EQ(deflateInit2(&zs, Z_DEFAULT_COMPRESSION, Z_DEFLATED, 15 + 16, 8,
                           Z_DEFAULT_STRATEGY),
              Z_OK);
    Bytes out(deflateBound(&zs, static_cast<uLong>(raw.size())) + 64);
    zs.next_in = const_cast<Bytef*>(raw.data());
    zs.avail_in = static_cast<uInt>(raw.size());
    zs.next_out = out.data();
    zs.avail_out = static_cast<uInt>(out.size());
    EXPECT_EQ(deflate(&zs, Z_FINISH), Z_STREAM_END);
    out.resize(zs.total_out);
    deflateEnd(&zs);
    return out;
}

// Little-endian byte builder for hand-crafted files.
struct ByteBuilder {
    Bytes b;
    void ensure(std::size_t end) {
        if (b.size() < end) b.resize(end, 0);
    }
    void u32_at(std::size_t off, uint32_t v) {
        ensure(off + 4);
        for (int i = 0; i < 4; ++i) b[off + i] = static_cast<unsigned char>(v >> (8 * i));
    }
    void i32_at(std::size_t off, int32_t v) { u32_at(off, static_cast<uint32_t>(v)); }
    void f32_at(std::size_t off, float v) {
        uint32_t u;
        std::memcpy(&u, &v, 4);
        u32_at(off, u);
    }
    void f64_at(std::size_t off, double v) {
        uint64_t u;
        std::memcpy(&u, &v, 8);
        u32_at(off, static_cast<uint32_t>(u));
        u32_at(off + 4, static_cast<uint32_t>(u >> 32));
    }
    void u16_at(std::size_t off, uint16_t v) {
        ensure(off + 2);
        b[off] = static_cast<unsigned char>(v);
        b[off + 1] = static_cast<unsigned char>(v >> 8);
    }
    void append_text(const std::string& s) { b.insert(b.end(), s.begin(), s.end()); }
    void append_f32(float v) { f32_at(b.size(), v); }
    void append_u16(uint16_t v) { u16_at(b.size(), v); }
};

uint32_t u32_of(const Bytes& b, std::size_t off) {
    return static_cast<uint32_t>(b[off]) | (static_cast<uint32_t>(b[off + 1]) << 8) |
           (static_cast<uint32_t>(b[off + 2]) << 16) |
           (static_cast<uint32_t>(b[off + 3]) << 24);
}
int32_t i32_of(const Bytes& b, std::size_t off) {
    return static_cast<int32_t>(u32_of(b, off));
}
float f32_of(const Bytes& b, std::size_t off) {
    const uint32_t u = u32_of(b, off);
    float f;
    std::memcpy(&f, &u, 4);
    return f;
}
uint16_t u16_of(const Bytes& b, std::size_t off) {
    return static_cast<uint16_t>(b[off] | (b[off + 1] << 8));
}

/// Header offsets from the table in docs/file-formats.md, written out
/// independently of the implementation.
struct Offsets {
    std::size_t world2eye, world2ndc, format, nvars, specs;
};
constexpr Offsets kOffsets[3] = {
    {40, 104, 168, 180, 188}, {56, 120, 184, 196, 204}, {188, 252, 316, 328, 336}};

/// A hand-crafted point: position, raw normal codes, radius, channel data.
struct RawPoint {
    float p[3];
    uint16_t phi, z;
    float radius;
    std::vector<float> data;
};

struct RawPtc {
    int version = 0;
    double npoints = -1; ///< < 0: use points.size()
    int32_t nvars = -1;  ///< < 0: number of spec lines
    int32_t datasize = 4;
    std::vector<std::string> specs = {"float _area", "color _radiance_t"};
    std::vector<RawPoint> points;
    float w2e[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    float w2ndc[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    float format[3] = {0, 0, 1};
    uint32_t magic = 0x63747070;
    int32_t version_field = -1; ///< < 0: version
};

Bytes craft_ptc(const RawPtc& f) {
    const Offsets& o = kOffsets[f.version];
    ByteBuilder bb;
    bb.u32_at(0, f.magic);
    bb.i32_at(4, f.version_field >= 0 ? f.version_field : f.version);
    bb.f64_at(8, f.npoints >= 0 ? f.npoints : static_cast<double>(f.points.size()));
    for (int i = 0; i < 6; ++i)
        bb.f32_at(16 + 4 * i, i < 3 ? -100.0f : 100.0f); // not checked
    if (f.version >= 1) {
        for (int i = 0; i < 4; ++i)
            bb.f32_at(40 + 4 * i, 7.0f); // unknowns: ignored on read
    }
    if (f.version >= 2) {
        bb.f32_at(56, 9.0f);
        for (int i = 0; i < 32; ++i) bb.u32_at(60 + 4 * i, 0xDEADBEEFu);
    }
    for (int i = 0; i < 16; ++i) {
        bb.f32_at(o.world2eye + 4 * i, f.w2e[i]);
        bb.f32_at(o.world2ndc + 4 * i, f.w2ndc[i]);
    }
    for (int i = 0; i < 3; ++i) bb.f32_at(o.format + 4 * i, f.format[i]);
    bb.i32_at(o.nvars, f.nvars >= 0 ? f.nvars : static_cast<int32_t>(f.specs.size()));
    bb.i32_at(o.nvars + 4, f.datasize);
    EXPECT_EQ(bb.b.size(), o.specs);
    for (const std::string& s : f.specs) bb.append_text(s + "\n");
    if (f.version >= 1) {
        bb.append_f32(3.0f);
        bb.append_f32(4.0f);
    }
    for (const RawPoint& p : f.points) {
        for (float v : p.p) bb.append_f32(v);
        bb.append_u16(p.phi);
        bb.append_u16(p.z);
        bb.append_f32(p.radius);
        for (float v : p.data) bb.append_f32(v);
    }
    return bb.b;
}

RawPtc three_point_file(int version) {
    RawPtc f;
    f.version = version;
    f.points = {
        {{0, 0, 0}, 0, 65535, 0.1f, {0.01f, 1, 0, 0}},
        {{1, 2, 3}, 65535, 65535, 0.2f, {0.02f, 0, 1, 0}},
        {{-1, 0.5f, 2}, 49151, 32768, 0.3f, {0.03f, 0.5f, 0.25f, 0.125f}},
    };
    return f;
}

/// Deterministic cloud with every channel type and the awkward normals.
PointCloud make_cloud(std::size_t n, uint32_t seed = 7) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-10.0f, 10.0f);
    std::normal_distribution<float> g(0.0f, 1.0f);
    PointCloud c;
    c.resize(n);
    c.add_channel("_area", ChannelType::Float);
    c.add_channel("_radiance_t", ChannelType::Color);
    c.add_channel("P_ref", ChannelType::Point);
    c.add_channel("dir", ChannelType::Vector);
    c.add_channel("Nb", ChannelType::Normal);
    c.add_channel("xform", ChannelType::Matrix);
    for (std::size_t i = 0; i < n; ++i) {
        c.positions[i] = {u(rng), u(rng), u(rng)};
        glm::vec3 nn{g(rng), g(rng), g(rng)};
        c.normals[i] = glm::normalize(nn);
        c.radii[i] = std::abs(u(rng)) * 0.01f;
    }
    const glm::vec3 special[] = {{0, 0, 0},  {0, 0, 1},  {0, 0, -1},
                                 {1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                 {0, -1, 0}, {0, 0, 5},  {0, -1e-4f, 1}};
    for (std::size_t i = 0; i < std::size(special) && i < n; ++i)
        c.normals[i] = special[i];
    for (Channel& ch : c.channels) {
        for (float& v : ch.data) v = u(rng);
    }
    return c;
}

/// Runs f, expects exception E whose message names path, returns the message.
template <typename E, typename F>
std::string expect_error(F&& f, const std::string& path) {
    try {
        f();
    } catch (const E& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find(path), std::string::npos)
            << "message does not name the file: " << what;
        return what;
    } catch (const std::exception& e) {
        ADD_FAILURE() << "wrong exception type: " << e.what();
        return {};
    }
    ADD_FAILURE() << "no exception for " << path;
    return {};
}

std::string expect_format_error(const std::string& path) {
    return expect_error<sss::FormatError>([&] { sss::read_point_cloud(path); }, path);
}

void expect_same_except_normals(const PointCloud& a, const PointCloud& b) {
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
        ASSERT_EQ(a.positions[i], b.positions[i]) << i;
        ASSERT_EQ(a.radii[i], b.radii[i]) << i;
    }
    ASSERT_EQ(a.channels.size(), b.channels.size());
    for (std::size_t c = 0; c < a.channels.size(); ++c) {
        EXPECT_EQ(a.channels[c].name, b.channels[c].name);
        EXPECT_EQ(a.channels[c].type, b.channels[c].type);
        EXPECT_EQ(a.channels[c].data, b.channels[c].data) << a.channels[c].name;
    }
    EXPECT_EQ(a.world_to_eye, b.world_to_eye);
    EXPECT_EQ(a.world_to_ndc, b.world_to_ndc);
    EXPECT_EQ(a.format, b.format);
}

void set_header(PointCloud& c) {
    for (int i = 0; i < 16; ++i) {
        c.world_to_eye[i] = 0.5f * static_cast<float>(i) - 3.25f;
        c.world_to_ndc[i] = 1.0f / static_cast<float>(i + 3);
    }
    c.format = {1920.0f, 1080.0f, 1.5f};
}

// ---------------------------------------------------------------------------
// Channel types and the PointCloud container
// ---------------------------------------------------------------------------

TEST(ChannelType, SizesNamesAndParsing) {
    const std::pair<ChannelType, int> sizes[] = {
        {ChannelType::Float, 1},  {ChannelType::Color, 3},  {ChannelType::Point, 3},
        {ChannelType::Vector, 3}, {ChannelType::Normal, 3}, {ChannelType::Matrix, 16}};
    for (auto [t, k] : sizes) {
        EXPECT_EQ(sss::channel_type_size(t), k);
        EXPECT_EQ(sss::parse_channel_type(sss::channel_type_name(t)), t);
    }
    EXPECT_STREQ(sss::channel_type_name(ChannelType::Color), "color");
    EXPECT_FALSE(sss::parse_channel_type("Float").has_value());
    EXPECT_FALSE(sss::parse_channel_type("int").has_value());
    EXPECT_FALSE(sss::parse_channel_type("").has_value());
}

TEST(PointCloud, ResizeAddChannelDataSizeBounds) {
    PointCloud c;
    EXPECT_EQ(c.bounds().lo, glm::vec3(0.0f));
    EXPECT_EQ(c.bounds().hi, glm::vec3(0.0f));
    c.add_channel("a", ChannelType::Float);
    c.resize(3);
    Channel& col = c.add_channel("col", ChannelType::Color);
    EXPECT_EQ(col.data.size(), 9u);
    EXPECT_EQ(c.find_channel("a")->data.size(), 3u);
    EXPECT_EQ(c.data_size(), 4);
    EXPECT_EQ(&c.add_channel("col", ChannelType::Color), c.find_channel("col"));
    EXPECT_THROW(c.add_channel("col", ChannelType::Vector), sss::ValueError);
    EXPECT_THROW(c.add_channel("", ChannelType::Float), sss::ValueError);
    EXPECT_THROW(c.add_channel("two words", ChannelType::Float), sss::ValueError);
    EXPECT_EQ(c.find_channel("missing"), nullptr);
    const PointCloud& cc = c;
    EXPECT_NE(cc.find_channel("a"), nullptr);

    c.positions = {{1, -2, 3}, {-4, 5, 0}, {0, 0, 9}};
    const sss::Bounds3 b = c.bounds();
    EXPECT_EQ(b.lo, glm::vec3(-4, -2, 0));
    EXPECT_EQ(b.hi, glm::vec3(1, 5, 9));
    c.resize(1);
    EXPECT_EQ(c.normals.size(), 1u);
    EXPECT_EQ(c.radii.size(), 1u);
    EXPECT_EQ(c.find_channel("col")->data.size(), 3u);
}

TEST(PointCloud, AppendMergesChannelsByName) {
    PointCloud a;
    a.resize(2);
    a.positions = {{1, 0, 0}, {2, 0, 0}};
    a.radii = {1, 2};
    a.add_channel("_area", ChannelType::Float).data = {10, 20};
    a.add_channel("onlya", ChannelType::Vector).data = {1, 2, 3, 4, 5, 6};
    a.world_to_eye[3] = 42.0f;

    PointCloud b;
    b.resize(1);
    b.positions = {{3, 0, 0}};
    b.normals = {{0, 0, 1}};
    b.radii = {3};
    b.add_channel("onlyb", ChannelType::Color).data = {7, 8, 9};
    b.add_channel("_area", ChannelType::Float).data = {30};
    b.world_to_eye[3] = -1.0f;

    a.append(b);
    ASSERT_EQ(a.size(), 3u);
    EXPECT_EQ(a.positions[2], glm::vec3(3, 0, 0));
    EXPECT_EQ(a.normals[2], glm::vec3(0, 0, 1));
    EXPECT_EQ(a.radii, (std::vector<float>{1, 2, 3}));
    EXPECT_EQ(a.find_channel("_area")->data, (std::vector<float>{10, 20, 30}));
    EXPECT_EQ(a.find_channel("onlya")->data,
              (std::vector<float>{1, 2, 3, 4, 5, 6, 0, 0, 0}));
    EXPECT_EQ(a.find_channel("onlyb")->data,
              (std::vector<float>{0, 0, 0, 0, 0, 0, 7, 8, 9}));
    EXPECT_EQ(a.world_to_eye[3], 42.0f); // header of *this wins
    EXPECT_EQ(a.channels.size(), 3u);

    // Self-append doubles the cloud.
    a.append(a);
    EXPECT_EQ(a.size(), 6u);
    EXPECT_EQ(a.find_channel("_area")->data,
              (std::vector<float>{10, 20, 30, 10, 20, 30}));

    // A type clash throws and leaves the cloud unchanged.
    PointCloud clash;
    clash.resize(1);
    clash.add_channel("_area", ChannelType::Color);
    clash.add_channel("fresh", ChannelType::Float);
    EXPECT_THROW(a.append(clash), sss::ValueError);
    EXPECT_EQ(a.size(), 6u);
    EXPECT_EQ(a.find_channel("fresh"), nullptr);
}

TEST(PointCloud, ChannelStats) {
    PointCloud c;
    c.resize(4);
    c.radii = {1, 2, 3, 6};
    c.add_channel("col", ChannelType::Color).data = {0, 1, 2, 1, 1, 2, 2, 1, 2, 5, 1, 2};
    const std::vector<sss::ChannelStats> s = sss::channel_stats(c);
    ASSERT_EQ(s.size(), 2u);
    EXPECT_EQ(s[0].name, "radius");
    EXPECT_EQ(s[0].type, ChannelType::Float);
    EXPECT_EQ(s[0].min, (std::vector<double>{1}));
    EXPECT_EQ(s[0].mean, (std::vector<double>{3}));
    EXPECT_EQ(s[0].max, (std::vector<double>{6}));
    EXPECT_EQ(s[1].name, "col");
    EXPECT_EQ(s[1].min, (std::vector<double>{0, 1, 2}));
    EXPECT_EQ(s[1].mean, (std::vector<double>{2, 1, 2}));
    EXPECT_EQ(s[1].max, (std::vector<double>{5, 1, 2}));

    // Double accumulation: summing a million 0.1f in float is off by ~1%.
    PointCloud big;
    big.resize(1'000'000);
    std::fill(big.radii.begin(), big.radii.end(), 0.1f);
    EXPECT_NEAR(sss::channel_stats(big)[0].mean[0], static_cast<double>(0.1f), 1e-9);

    PointCloud empty;
    empty.add_channel("m", ChannelType::Matrix);
    const auto es = sss::channel_stats(empty);
    ASSERT_EQ(es.size(), 2u);
    EXPECT_EQ(es[1].mean.size(), 16u);
}

// ---------------------------------------------------------------------------
// .ptc layout, pinned by hand-crafted bytes
// ---------------------------------------------------------------------------

class PtcVersion : public ::testing::TestWithParam<int> {};

TEST_P(PtcVersion, ReadsHandCraftedFile) {
    const int version = GetParam();
    TempDir dir;
    RawPtc f = three_point_file(version);
    f.w2e[12] = 5.0f;
    f.w2ndc[0] = 2.0f;
    f.format[0] = 640;
    f.format[1] = 480;
    const std::string path = dir.file("crafted.ptc");
    write_bytes(path, craft_ptc(f));

    const PointCloud c = sss::read_ptc(path);
    EXPECT_EQ(c.file_version, version);
    EXPECT_FALSE(c.file_compressed);
    ASSERT_EQ(c.size(), 3u);
    EXPECT_EQ(c.positions[2], glm::vec3(-1, 0.5f, 2));
    EXPECT_EQ(c.radii, (std::vector<float>{0.1f, 0.2f, 0.3f}));
    ASSERT_EQ(c.channels.size(), 2u);
    EXPECT_EQ(c.channels[0].name, "_area");
    EXPECT_EQ(c.channels[0].type, ChannelType::Float);
    EXPECT_EQ(c.channels[1].name, "_radiance_t");
    EXPECT_EQ(c.channels[1].type, ChannelType::Color);
    EXPECT_EQ(c.channels[0].data, (std::vector<float>{0.01f, 0.02f, 0.03f}));
    EXPECT_EQ(c.channels[1].data,
              (std::vector<float>{1, 0, 0, 0, 1, 0, 0.5f, 0.25f, 0.125f}));
    EXPECT_EQ(c.world_to_eye[12], 5.0f);
    EXPECT_EQ(c.world_to_eye[0], 1.0f);
    EXPECT_EQ(c.world_to_ndc[0], 2.0f);
    EXPECT_EQ(c.format, (std::array<float, 3>{640, 480, 1}));
    // Normals: (0, 65535) is +z, (65535, 65535) is "no normal",
    // (49151, 32768) is phi ~ +pi/2, z ~ 0, i.e. +x.
    EXPECT_NEAR(c.normals[0].x, 0.0f, 1e-6);
    EXPECT_NEAR(c.normals[0].y, 0.0f, 1e-6);
    EXPECT_EQ(c.normals[0].z, 1.0f);
    EXPECT_EQ(c.normals[1], glm::vec3(0.0f));
    EXPECT_NEAR(c.normals[2].x, 1.0f, 1e-4);
    EXPECT_NEAR(c.normals[2].y, 0.0f, 1e-4);
    EXPECT_NEAR(c.normals[2].z, 0.0f, 1e-4);
}

TEST_P(PtcVersion, WriterUsesDocumentedOffsets) {
    const int version = GetParam();
    TempDir dir;
    PointCloud c;
    c.resize(2);
    c.positions = {{1, 2, 3}, {-4, 5, -6}};
    c.normals = {{0, -1e-4f, 1}, {1, 0, 0}};
    c.radii = {0.25f, 0.75f};
    c.add_channel("_area", ChannelType::Float).data = {11, 12};
    c.add_channel("_radiance_t", ChannelType::Color).data = {1, 2, 3, 4, 5, 6};
    c.world_to_eye[12] = 8.0f;
    c.world_to_ndc[5] = -2.0f;
    c.format = {320, 240, 2};
    const std::string path = dir.file("w.ptc");
    sss::PointCloudWriteOptions opt;
    opt.ptc_version = version;
    sss::write_ptc(c, path, opt);
    const Bytes b = read_bytes(path);
    const Offsets& o = kOffsets[version];

    EXPECT_EQ(std::string(b.begin(), b.begin() + 4), "pptc");
    EXPECT_EQ(u32_of(b, 0), 0x63747070u);
    EXPECT_EQ(i32_of(b, 4), version);
    double np;
    std::memcpy(&np, b.data() + 8, 8);
    EXPECT_EQ(np, 2.0);
    const float box[6] = {-4, 2, -6, 1, 5, 3};
    for (int i = 0; i < 6; ++i) EXPECT_EQ(f32_of(b, 16 + 4 * i), box[i]) << i;
    if (version >= 1) {
        for (int i = 0; i < 4; ++i) EXPECT_EQ(u32_of(b, 40 + 4 * i), 0u);
    }
    if (version >= 2) {
        EXPECT_EQ(f32_of(b, 56), 0.75f); // max radius
        for (int i = 0; i < 32; ++i) EXPECT_EQ(u32_of(b, 60 + 4 * i), 0xDEADBEEFu) << i;
    }
    EXPECT_EQ(f32_of(b, o.world2eye + 4 * 12), 8.0f);
    EXPECT_EQ(f32_of(b, o.world2eye), 1.0f);
    EXPECT_EQ(f32_of(b, o.world2ndc + 4 * 5), -2.0f);
    EXPECT_EQ(f32_of(b, o.format), 320.0f);
    EXPECT_EQ(f32_of(b, o.format + 8), 2.0f);
    EXPECT_EQ(i32_of(b, o.nvars), 2);
    EXPECT_EQ(i32_of(b, o.nvars + 4), 4);
    const std::string specs = "float _area\ncolor _radiance_t\n";
    ASSERT_GE(b.size(), o.specs + specs.size());
    EXPECT_EQ(std::string(b.begin() + o.specs, b.begin() + o.specs + specs.size()),
              specs);
    std::size_t rec = o.specs + specs.size();
    if (version >= 1) {
        EXPECT_EQ(u32_of(b, rec), 0u);
        EXPECT_EQ(u32_of(b, rec + 4), 0u);
        rec += 8;
    }
    const std::size_t record = 20 + 4 * 4;
    ASSERT_EQ(b.size(), rec + 2 * record);
    // Point 1: position, normal codes for +x, radius, then data.
    const std::size_t p1 = rec + record;
    EXPECT_EQ(f32_of(b, p1), -4.0f);
    EXPECT_EQ(f32_of(b, p1 + 8), -6.0f);
    EXPECT_EQ(u16_of(b, p1 + 12), 49151); // round(0.75 * 65535)
    EXPECT_EQ(u16_of(b, p1 + 14), 32768); // round(32767.5), half away from zero
    EXPECT_EQ(f32_of(b, p1 + 16), 0.75f);
    EXPECT_EQ(f32_of(b, p1 + 20), 12.0f);
    EXPECT_EQ(f32_of(b, p1 + 24), 4.0f);
    EXPECT_EQ(f32_of(b, p1 + 32), 6.0f);
    // Point 0: N ~ +z with phi = pi would be (65535, 65535) = "no normal";
    // phi is remapped to 0.
    EXPECT_EQ(u16_of(b, rec + 12), 0);
    EXPECT_EQ(u16_of(b, rec + 14), 65535);
}

INSTANTIATE_TEST_SUITE_P(Versions, PtcVersion, ::testing::Values(0, 1, 2));

TEST(PtcLayout, NormalCodesForAxes) {
    TempDir dir;
    PointCloud c;
    const std::vector<glm::vec3> normals = {{0, 1, 0},     {0, -1, 0}, {-1, 0, 0},
                                            {0, 0, -1},    {0, 0, 0},  {0, 0, 3},
                                            {0, -1e-3f, 1}};
    // Expected (phi, z) with phi = round((atan2(x, y) / 2pi + 0.5) * 65535),
    // z = round((nz + 1) / 2 * 65535).
    // The last one would be (65535, 65535), the "no normal" code, so phi -> 0.
    const uint16_t expected[][2] = {{32768, 32768}, {65535, 32768}, {16384, 32768},
                                    {32768, 0},     {65535, 65535}, {32768, 65535},
                                    {0, 65535}};
    c.resize(normals.size());
    c.normals = normals;
    const std::string path = dir.file("n.ptc");
    sss::write_ptc(c, path);
    const Bytes b = read_bytes(path);
    for (std::size_t i = 0; i < normals.size(); ++i) {
        const std::size_t r = 188 + 20 * i;
        EXPECT_EQ(u16_of(b, r + 12), expected[i][0]) << i;
        EXPECT_EQ(u16_of(b, r + 14), expected[i][1]) << i;
    }
}

TEST(PtcLayout, CommittedPythonMadeFiles) {
    // Written by tests/data/make_tiny_ptc.py with Python's struct module.
    const std::string v0 = std::string(SSS_TEST_DATA_DIR) + "/tiny_v0.ptc";
    const PointCloud a = sss::read_point_cloud(v0);
    EXPECT_EQ(a.file_version, 0);
    EXPECT_FALSE(a.file_compressed);
    ASSERT_EQ(a.size(), 3u);
    EXPECT_EQ(a.world_to_eye[14], 5.0f);
    EXPECT_EQ(a.format, (std::array<float, 3>{640, 480, 1}));
    EXPECT_EQ(a.channels[1].data[8], 0.125f);
    EXPECT_EQ(a.normals[1], glm::vec3(0.0f));

    const std::string v2 = std::string(SSS_TEST_DATA_DIR) + "/tiny_v2_gzip.ptc";
    const PointCloud b = sss::read_point_cloud(v2);
    EXPECT_EQ(b.file_version, 2);
    EXPECT_TRUE(b.file_compressed);
    ASSERT_EQ(b.size(), 3u);
    EXPECT_EQ(b.channels[0].data, a.channels[0].data);
    EXPECT_EQ(b.positions, a.positions);
}

// ---------------------------------------------------------------------------
// Round trips
// ---------------------------------------------------------------------------

struct RoundTripCase {
    int version;
    bool compress;
};

void PrintTo(const RoundTripCase& c, std::ostream* os) {
    *os << "version " << c.version << (c.compress ? ", gzip" : ", plain");
}

class PtcRoundTrip : public ::testing::TestWithParam<RoundTripCase> {};

TEST_P(PtcRoundTrip, ValuesSurvive) {
    const RoundTripCase param = GetParam();
    TempDir dir;
    PointCloud c = make_cloud(5000);
    set_header(c);
    const std::string path = dir.file("rt.ptc");
    sss::PointCloudWriteOptions opt;
    opt.ptc_version = param.version;
    opt.compress = param.compress;
    sss::write_point_cloud(c, path, opt);

    const Bytes raw = read_bytes(path);
    ASSERT_GE(raw.size(), 2u);
    EXPECT_EQ(raw[0] == 0x1f && raw[1] == 0x8b, param.compress);

    const PointCloud r = sss::read_point_cloud(path);
    EXPECT_EQ(r.file_version, param.version);
    EXPECT_EQ(r.file_compressed, param.compress);
    expect_same_except_normals(c, r);
    // Quantisation: z steps of 2/65535 cost up to ~sqrt(2/65535) ~ 0.0055 of
    // the xy part right at the poles, phi steps ~1e-4 elsewhere.
    double worst = 0.0;
    for (std::size_t i = 0; i < c.size(); ++i) {
        const glm::vec3 want = c.normals[i] == glm::vec3(0.0f)
                                   ? glm::vec3(0.0f)
                                   : glm::normalize(c.normals[i]);
        worst = std::max(worst, static_cast<double>(glm::length(r.normals[i] - want)));
        if (c.normals[i] != glm::vec3(0.0f)) {
            EXPECT_NEAR(glm::length(r.normals[i]), 1.0, 1e-5) << i;
        }
    }
    EXPECT_LT(worst, 6e-3);
    EXPECT_EQ(r.normals[0], glm::vec3(0.0f)); // zero normal preserved
    EXPECT_NEAR(r.normals[1].z, 1.0f, 1e-6);  // +z
    EXPECT_NEAR(r.normals[8].z, 1.0f, 1e-6);  // the (65535, 65535) remap case
    EXPECT_NEAR(r.normals[7].z, 1.0f, 1e-6);  // non-unit +z, same code
    EXPECT_NEAR(r.normals[2].z, -1.0f, 1e-6);
    EXPECT_NEAR(r.normals[3].x, 1.0f, 1e-4);
    EXPECT_NEAR(r.normals[4].x, -1.0f, 1e-4);
    EXPECT_NEAR(r.normals[6].y, -1.0f, 1e-4);

    // Typical normals are much better than the polar worst case.
    double sum = 0.0;
    for (std::size_t i = 9; i < c.size(); ++i) {
        sum += glm::length(r.normals[i] - c.normals[i]);
    }
    EXPECT_LT(sum / static_cast<double>(c.size() - 9), 2e-4);

    // Reading and writing again is stable (codes round-trip exactly).
    const std::string again = dir.file("again.ptc");
    sss::write_point_cloud(r, again, opt);
    const PointCloud r2 = sss::read_point_cloud(again);
    EXPECT_EQ(r2.normals, r.normals);
}

INSTANTIATE_TEST_SUITE_P(All, PtcRoundTrip,
                         ::testing::Values(RoundTripCase{0, false},
                                           RoundTripCase{1, false},
                                           RoundTripCase{2, false},
                                           RoundTripCase{0, true}, RoundTripCase{1, true},
                                           RoundTripCase{2, true}),
                         [](const ::testing::TestParamInfo<RoundTripCase>& info) {
                             return numbered("v", info.param.version,
                                             info.param.compress ? "_gzip" : "_plain");
                         });

TEST(PtcRoundTrip, EmptyCloudAndNoChannels) {
    TempDir dir;
    PointCloud empty;
    const std::string path = dir.file("empty.ptc");
    sss::write_point_cloud(empty, path);
    EXPECT_EQ(read_bytes(path).size(), 188u);
    const PointCloud r = sss::read_point_cloud(path);
    EXPECT_EQ(r.size(), 0u);
    EXPECT_TRUE(r.channels.empty());

    PointCloud one;
    one.resize(1);
    one.positions[0] = {1, 2, 3};
    sss::PointCloudWriteOptions gz;
    gz.compress = true;
    sss::write_point_cloud(one, path, gz); // overwrites atomically
    EXPECT_EQ(sss::read_point_cloud(path).positions, one.positions);
}

TEST(PtcRoundTrip, AppendThenWrite) {
    TempDir dir;
    PointCloud a = make_cloud(10, 1);
    PointCloud b;
    b.resize(4);
    b.add_channel("_area", ChannelType::Float).data = {1, 2, 3, 4};
    b.add_channel("extra", ChannelType::Float).data = {5, 6, 7, 8};
    a.append(b);
    const std::string path = dir.file("merged.ptc");
    sss::write_point_cloud(a, path);
    const PointCloud r = sss::read_point_cloud(path);
    expect_same_except_normals(a, r);
    EXPECT_EQ(r.find_channel("extra")->data[13], 8.0f);
    EXPECT_EQ(r.find_channel("extra")->data[0], 0.0f);
}

TEST(PlyRoundTrip, ExactIncludingNormalsAndTypes) {
    TempDir dir;
    PointCloud c = make_cloud(1000);
    set_header(c);
    for (const std::string name : {"rt.ply", "RT.PLY"}) {
        const std::string path = dir.file(name);
        sss::write_point_cloud(c, path);
        const Bytes raw = read_bytes(path);
        const std::string text(raw.begin(), raw.begin() + 200);
        EXPECT_EQ(text.rfind("ply\nformat binary_little_endian 1.0\n", 0), 0u);
        const PointCloud r = sss::read_point_cloud(path);
        expect_same_except_normals(c, r);
        EXPECT_EQ(r.normals, c.normals); // floats in PLY: exact
        EXPECT_EQ(r.file_version, 0);
    }
}

TEST(PlyRoundTrip, HeaderNamesChannelsAndComments) {
    TempDir dir;
    PointCloud c;
    c.resize(1);
    c.add_channel("_ssdiffusion", ChannelType::Color);
    c.add_channel("m", ChannelType::Matrix);
    c.add_channel("v", ChannelType::Vector);
    const std::string path = dir.file("h.ply");
    sss::write_ply(c, path);
    const Bytes raw = read_bytes(path);
    const std::string all(raw.begin(), raw.end());
    const std::string header = all.substr(0, all.find("end_header\n"));
    for (const char* line :
         {"comment sss_channel color _ssdiffusion\n", "comment sss_channel matrix m\n",
          "element vertex 1\n", "property float x\n", "property float nz\n",
          "property float radius\n", "property float _ssdiffusion_r\n",
          "property float _ssdiffusion_b\n", "property float m_0\n",
          "property float m_15\n", "property float v_x\n", "property float v_z\n"}) {
        EXPECT_NE(header.find(line), std::string::npos) << line;
    }
    // 7 + 3 + 16 + 3 floats and the 3 colour bytes of _ssdiffusion per vertex.
    EXPECT_EQ(all.size() - all.find("end_header\n") - 11, 29u * 4u + 3u);
}

TEST(PlyRead, ForeignBinaryWithoutComments) {
    TempDir dir;
    const std::string path = dir.file("foreign.ply");
    std::string head = "ply\nformat binary_little_endian 1.0\ncomment from elsewhere\n"
                       "element vertex 2\nproperty double x\nproperty float y\n"
                       "property int z\nproperty uchar red\nproperty short temp\n"
                       "property uint8 flag\nelement face 1\n"
                       "property list uchar int vertex_indices\nend_header\n";
    ByteBuilder bb;
    bb.append_text(head);
    for (int i = 0; i < 2; ++i) {
        bb.f64_at(bb.b.size(), 1.5 + i);
        bb.append_f32(-2.0f);
        bb.i32_at(bb.b.size(), -7 + i);
        bb.b.push_back(static_cast<unsigned char>(200 + i));
        bb.u16_at(bb.b.size(), static_cast<uint16_t>(-300));
        bb.b.push_back(1);
    }
    bb.b.insert(bb.b.end(), {3, 0, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0}); // the face, ignored
    write_bytes(path, bb.b);
    const PointCloud c = sss::read_point_cloud(path);
    ASSERT_EQ(c.size(), 2u);
    EXPECT_EQ(c.positions[1], glm::vec3(2.5f, -2.0f, -6.0f));
    EXPECT_EQ(c.normals[0], glm::vec3(0.0f));
    EXPECT_EQ(c.radii[1], 0.0f);
    ASSERT_EQ(c.channels.size(), 3u);
    EXPECT_EQ(c.channels[0].name, "red");
    EXPECT_EQ(c.channels[0].type, ChannelType::Float);
    EXPECT_EQ(c.channels[0].data, (std::vector<float>{200, 201}));
    EXPECT_EQ(c.channels[1].name, "temp");
    EXPECT_EQ(c.channels[1].data, (std::vector<float>{-300, -300}));
    EXPECT_EQ(c.channels[2].name, "flag");
}

TEST(PlyRead, ForeignAsciiFromTestData) {
    const std::string path = std::string(SSS_TEST_DATA_DIR) + "/tiny_foreign.ply";
    const PointCloud c = sss::read_point_cloud(path);
    ASSERT_EQ(c.size(), 3u);
    EXPECT_EQ(c.positions[2], glm::vec3(-1, 0.5f, 2));
    ASSERT_EQ(c.channels.size(), 2u);
    EXPECT_EQ(c.channels[0].name, "red");
    EXPECT_EQ(c.channels[0].data, (std::vector<float>{255, 128, 0}));
    EXPECT_EQ(c.channels[1].name, "confidence");
    EXPECT_EQ(c.channels[1].data, (std::vector<float>{0.5f, 0.25f, 1.0f}));
}

TEST(PlyRead, NormalsAndRadiusFromOtherTools) {
    TempDir dir;
    const std::string path = dir.file("n.ply");
    const std::string text =
        "ply\r\nformat ascii 1.0\r\nelement vertex 1\r\n"
        "property float x\r\nproperty float y\r\nproperty float z\r\n"
        "property float nx\r\nproperty float ny\r\nproperty float nz\r\n"
        "property float radius\r\nend_header\r\n1 2 3 0 1 0 +0.5\r\n";
    write_bytes(path, Bytes(text.begin(), text.end()));
    const PointCloud c = sss::read_point_cloud(path);
    ASSERT_EQ(c.size(), 1u);
    EXPECT_EQ(c.normals[0], glm::vec3(0, 1, 0));
    EXPECT_EQ(c.radii[0], 0.5f);
    EXPECT_TRUE(c.channels.empty());
}

// ---------------------------------------------------------------------------
// Bad .ptc input
// ---------------------------------------------------------------------------

TEST(PtcBadInput, MissingFileAndDirectoryAreIoErrors) {
    TempDir dir;
    const std::string missing = dir.file("nope.ptc");
    expect_error<sss::IoError>([&] { sss::read_point_cloud(missing); }, missing);
    const std::string folder = dir.path().string();
    expect_error<sss::IoError>([&] { sss::read_ptc(folder); }, folder);
}

TEST(PtcBadInput, WrongMagic) {
    TempDir dir;
    RawPtc f = three_point_file(0);
    f.magic = 0x70707463; // byte-swapped
    const std::string path = dir.file("magic.ptc");
    write_bytes(path, craft_ptc(f));
    EXPECT_NE(expect_format_error(path).find("magic"), std::string::npos);
}

TEST(PtcBadInput, UnsupportedVersions) {
    TempDir dir;
    for (int32_t v : {3, 4, -1, 1000}) {
        RawPtc f = three_point_file(2);
        f.version_field = v; // layout of v2, claimed version v
        if (v < 0) {
            Bytes b = craft_ptc(f);
            b[4] = b[5] = b[6] = b[7] = 0xff;
            const std::string path = dir.file("vneg.ptc");
            write_bytes(path, b);
            EXPECT_NE(expect_format_error(path).find("version -1"), std::string::npos);
            continue;
        }
        const std::string path = dir.file(numbered("v", v, ".ptc"));
        write_bytes(path, craft_ptc(f));
        EXPECT_NE(expect_format_error(path).find("version " + std::to_string(v)),
                  std::string::npos);
    }
}

TEST(PtcBadInput, TruncatedAtEveryOffset) {
    TempDir dir;
    for (int version = 0; version <= 2; ++version) {
        const Bytes full = craft_ptc(three_point_file(version));
        const std::size_t specs = kOffsets[version].specs;
        for (std::size_t len = 0; len < full.size(); ++len) {
            const std::string path = dir.file(numbered("t", len, ".ptc"));
            write_bytes(path, Bytes(full.begin(), full.begin() + len));
            const std::string msg = expect_format_error(path);
            if (len < specs) {
                EXPECT_NE(msg.find("too short"), std::string::npos) << msg;
            } else {
                EXPECT_NE(msg.find("truncated"), std::string::npos) << msg;
            }
        }
        // The same holds inside a gzip stream.
        const Bytes gz = gzip_bytes(full);
        for (std::size_t len = 0; len < gz.size(); len += 7) {
            const std::string path = dir.file(numbered("tz", len, ".ptc"));
            write_bytes(path, Bytes(gz.begin(), gz.begin() + len));
            expect_format_error(path);
        }
    }
}

TEST(PtcBadInput, TruncatedDataNamesThePoint) {
    TempDir dir;
    const Bytes full = craft_ptc(three_point_file(0));
    const std::string path = dir.file("cut.ptc");
    write_bytes(path, Bytes(full.begin(), full.end() - 10)); // last point incomplete
    try {
        sss::read_point_cloud(path);
        FAIL();
    } catch (const sss::FormatError& e) {
        EXPECT_EQ(e.point(), 2);
        EXPECT_EQ(e.path(), path);
    }
    // Gzip: the reader finds out only when the data ends.
    RawPtc f = three_point_file(1);
    f.npoints = 5;
    const std::string gz = dir.file("cut_gz.ptc");
    write_bytes(gz, gzip_bytes(craft_ptc(f)));
    try {
        sss::read_point_cloud(gz);
        FAIL();
    } catch (const sss::FormatError& e) {
        EXPECT_EQ(e.point(), 3);
        EXPECT_NE(std::string(e.what()).find(gz), std::string::npos);
    }
}

TEST(PtcBadInput, TrailingGarbageIsIgnored) {
    TempDir dir;
    Bytes b = craft_ptc(three_point_file(1));
    b.insert(b.end(), {'j', 'u', 'n', 'k'});
    const std::string path = dir.file("trail.ptc");
    write_bytes(path, b);
    EXPECT_EQ(sss::read_point_cloud(path).size(), 3u);
    // After a gzip stream as well.
    Bytes gz = gzip_bytes(craft_ptc(three_point_file(2)));
    gz.insert(gz.end(), 100, 'x');
    const std::string gz_path = dir.file("trail_gz.ptc");
    write_bytes(gz_path, gz);
    EXPECT_EQ(sss::read_point_cloud(gz_path).size(), 3u);
}

TEST(PtcBadInput, ChannelSizesNotAddingUp) {
    TempDir dir;
    for (int32_t ds : {3, 5, 0}) {
        RawPtc f = three_point_file(0);
        f.datasize = ds;
        const std::string path = dir.file(numbered("ds", ds, ".ptc"));
        write_bytes(path, craft_ptc(f));
        EXPECT_NE(expect_format_error(path).find("datasize"), std::string::npos);
    }
}

TEST(PtcBadInput, HugePointCountFailsFastWithoutAllocating) {
    TempDir dir;
    for (double n : {1e15, 4e15, 9007199254740992.0, 1e6}) {
        RawPtc f = three_point_file(2);
        f.npoints = n;
        const Bytes raw = craft_ptc(f);
        for (bool gz : {false, true}) {
            const std::string path =
                dir.file(std::string("huge") + (gz ? "_gz" : "") + ".ptc");
            write_bytes(path, gz ? gzip_bytes(raw) : raw);
            const auto t0 = std::chrono::steady_clock::now();
            const std::string msg = expect_format_error(path);
            const double secs =
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t0)
                    .count();
            EXPECT_LT(secs, 1.0);
            EXPECT_NE(msg.find("claims"), std::string::npos) << msg;
        }
    }
}

TEST(PtcBadInput, InvalidPointCounts) {
    TempDir dir;
    const double bad[] = {-1.0,
                          -1e300,
                          2.5,
                          std::numeric_limits<double>::quiet_NaN(),
                          std::numeric_limits<double>::infinity(),
                          1e300};
    int i = 0;
    for (double n : bad) {
        RawPtc f = three_point_file(0);
        f.npoints = 0; // placeholder, patched below
        Bytes b = craft_ptc(f);
        std::memcpy(b.data() + 8, &n, 8);
        const std::string path = dir.file(numbered("np", i++, ".ptc"));
        write_bytes(path, b);
        expect_format_error(path);
    }
}

TEST(PtcBadInput, BadChannelCountsAndDatasize) {
    TempDir dir;
    const std::pair<int32_t, int32_t> cases[] = {
        {-1, 4}, {2, -4}, {1 << 30, 4}, {2, 1 << 30}};
    int i = 0;
    for (auto [nvars, ds] : cases) {
        RawPtc f = three_point_file(1);
        f.nvars = nvars;
        f.datasize = ds;
        Bytes b = craft_ptc(f);
        if (nvars < 0) {
            for (int k = 0; k < 4; ++k) b[kOffsets[1].nvars + k] = 0xff;
        }
        const std::string path = dir.file(numbered("nv", i++, ".ptc"));
        write_bytes(path, b);
        expect_format_error(path);
    }
}

TEST(PtcBadInput, UnknownTypeAndMalformedSpecs) {
    TempDir dir;
    const std::vector<std::vector<std::string>> specs = {
        {"float _area", "colour _radiance_t"},               // unknown type
        {"float _area", "color"},                            // no name
        {"float _area", "color a b"},                        // three words
        {"float _area", ""},                                 // empty line
        {"float _area", "color _radiance_t", "float _area"}, // duplicate (and size)
    };
    int i = 0;
    for (const auto& s : specs) {
        RawPtc f = three_point_file(0);
        f.specs = s;
        const std::string path = dir.file(numbered("spec", i++, ".ptc"));
        write_bytes(path, craft_ptc(f));
        const std::string msg = expect_format_error(path);
        if (i == 1) {
            EXPECT_NE(msg.find("unknown channel type 'colour'"), std::string::npos);
        }
    }
    // A spec line that never ends.
    RawPtc f = three_point_file(0);
    f.points.clear();
    f.specs = {"float _area", "color " + std::string(10000, 'x')};
    const std::string path = dir.file("long.ptc");
    write_bytes(path, craft_ptc(f));
    expect_format_error(path);
}

TEST(PtcBadInput, NonFiniteAndNegativeValuesNameThePoint) {
    TempDir dir;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    struct Case {
        const char* what;
        void (*patch)(RawPoint&, float);
        float value;
    };
    const Case cases[] = {
        {"position", [](RawPoint& p, float v) { p.p[1] = v; }, nan},
        {"position", [](RawPoint& p, float v) { p.p[0] = v; }, -inf},
        {"radius", [](RawPoint& p, float v) { p.radius = v; }, nan},
        {"negative radius", [](RawPoint& p, float v) { p.radius = v; }, -0.5f},
        {"channel '_radiance_t'", [](RawPoint& p, float v) { p.data[3] = v; }, nan},
        {"channel '_area'", [](RawPoint& p, float v) { p.data[0] = v; }, inf},
    };
    int i = 0;
    for (const Case& c : cases) {
        for (bool gz : {false, true}) {
            RawPtc f = three_point_file(2);
            c.patch(f.points[2], c.value);
            const std::string path = dir.file(numbered("nan", i++, ".ptc"));
            const Bytes raw = craft_ptc(f);
            write_bytes(path, gz ? gzip_bytes(raw) : raw);
            try {
                sss::read_point_cloud(path);
                ADD_FAILURE() << c.what;
            } catch (const sss::FormatError& e) {
                const std::string msg = e.what();
                EXPECT_EQ(e.point(), 2) << msg;
                EXPECT_NE(msg.find("(point 2)"), std::string::npos) << msg;
                EXPECT_NE(msg.find(c.what), std::string::npos) << msg;
                EXPECT_NE(msg.find(path), std::string::npos) << msg;
            }
        }
    }
}

TEST(PtcBadInput, NonFiniteHeaderMatrix) {
    TempDir dir;
    RawPtc f = three_point_file(0);
    f.w2e[5] = std::numeric_limits<float>::quiet_NaN();
    const std::string path = dir.file("m.ptc");
    write_bytes(path, craft_ptc(f));
    EXPECT_NE(expect_format_error(path).find("world2eye"), std::string::npos);
}

TEST(PtcBadInput, CorruptGzipStream) {
    TempDir dir;
    PointCloud c = make_cloud(2000);
    const std::string good = dir.file("good.ptc");
    sss::PointCloudWriteOptions opt;
    opt.compress = true;
    sss::write_point_cloud(c, good, opt);
    const Bytes b = read_bytes(good);
    ASSERT_GT(b.size(), 100u);

    // Garbage in the middle of the deflate data.
    Bytes bad = b;
    for (std::size_t i = b.size() / 2; i < b.size() / 2 + 16; ++i) bad[i] ^= 0x5a;
    const std::string path = dir.file("corrupt.ptc");
    write_bytes(path, bad);
    expect_format_error(path);

    // A flipped byte in the CRC trailer only.
    Bytes crc = b;
    crc[crc.size() - 6] ^= 0x01;
    const std::string crc_path = dir.file("crc.ptc");
    write_bytes(crc_path, crc);
    expect_format_error(crc_path);

    // Deflate data that is not deflate at all after a valid gzip header.
    Bytes junk(74, 0xff);
    std::copy(b.begin(), b.begin() + 10, junk.begin());
    const std::string junk_path = dir.file("junk.ptc");
    write_bytes(junk_path, junk);
    const std::string msg = expect_format_error(junk_path);
    EXPECT_NE(msg.find("gzip"), std::string::npos) << msg;
}

// ---------------------------------------------------------------------------
// Bad .ply input
// ---------------------------------------------------------------------------

TEST(PlyBadInput, Rejections) {
    TempDir dir;
    const std::string vx = "element vertex 1\nproperty float x\nproperty float y\n"
                           "property float z\n";
    const std::pair<std::string, const char*> cases[] = {
        {"plx\nformat ascii 1.0\n" + vx + "end_header\n0 0 0\n", "not a PLY"},
        {"ply\nformat binary_big_endian 1.0\n" + vx + "end_header\n", "big_endian"},
        {"ply\nformat ascii 2.0\n" + vx + "end_header\n0 0 0\n", "version"},
        {"ply\n" + vx + "end_header\n0 0 0\n", "format"},
        {"ply\nformat ascii 1.0\n" + vx + "property list uchar int idx\nend_header\n",
         "list properties not supported"},
        {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
         "end_header\n0 0\n",
         "'z'"},
        {"ply\nformat ascii 1.0\nelement face 0\n" + vx + "end_header\n0 0 0\n",
         "first element"},
        {"ply\nformat ascii 1.0\n" + vx, "end_header"},
        {"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
         "property float z\nend_header\n0.000 0.000 0.000\n1.0 1.0\n",
         "(point 1)"},
        {"ply\nformat ascii 1.0\n" + vx + "end_header\n0 nan 0\n", "(point 0)"},
        {"ply\nformat ascii 1.0\n" + vx + "end_header\n0 zero 0\n", "malformed number"},
        {"ply\nformat ascii 1.0\n" + vx + "property float radius\nend_header\n0 0 0 -1\n",
         "negative radius"},
        {"ply\nformat ascii 1.0\ncomment sss_channel colour c\n" + vx +
             "end_header\n0 0 0\n",
         "unknown channel type"},
        {"ply\nformat ascii 1.0\ncomment sss_channel color c\n" + vx +
             "property float c_r\nend_header\n0 0 0 1\n",
         "c_g"},
        {"ply\nformat ascii 1.0\nelement vertex -1\nend_header\n", "vertex count"},
        {"ply\nformat ascii 1.0\n" + vx + "property float x\nend_header\n", "duplicate"},
        {"ply\nformat binary_little_endian 1.0\nelement vertex 1000000000000\n"
         "property float x\nproperty float y\nproperty float z\nend_header\n",
         "claims"},
    };
    int i = 0;
    for (const auto& [text, needle] : cases) {
        const std::string path = dir.file(numbered("bad", i++, ".ply"));
        write_bytes(path, Bytes(text.begin(), text.end()));
        const std::string msg = expect_format_error(path);
        EXPECT_NE(msg.find(needle), std::string::npos) << "case " << i - 1 << ": " << msg;
    }
}

TEST(PlyBadInput, TruncatedBinaryNamesThePoint) {
    TempDir dir;
    PointCloud c = make_cloud(10);
    const std::string path = dir.file("t.ply");
    sss::write_point_cloud(c, path);
    Bytes b = read_bytes(path);
    b.resize(b.size() - 1);
    write_bytes(path, b);
    try {
        sss::read_point_cloud(path);
        FAIL();
    } catch (const sss::FormatError& e) {
        EXPECT_EQ(e.point(), 9);
    }
}

// ---------------------------------------------------------------------------
// Writing
// ---------------------------------------------------------------------------

TEST(PointCloudWrite, RefusesNonFiniteBeforeCreatingAnything) {
    TempDir dir;
    for (const char* name : {"out.ptc", "out.ply"}) {
        PointCloud c = make_cloud(5);
        c.find_channel("_area")->data[3] = std::numeric_limits<float>::quiet_NaN();
        const std::string path = dir.file(name);
        EXPECT_THROW(sss::write_point_cloud(c, path), sss::ValueError);
        c = make_cloud(5);
        c.positions[1].y = std::numeric_limits<float>::infinity();
        EXPECT_THROW(sss::write_point_cloud(c, path), sss::ValueError);
        c = make_cloud(5);
        c.radii[4] = -1.0f;
        EXPECT_THROW(sss::write_point_cloud(c, path), sss::ValueError);
        c = make_cloud(5);
        c.world_to_ndc[0] = std::numeric_limits<float>::quiet_NaN();
        EXPECT_THROW(sss::write_point_cloud(c, path), sss::ValueError);
        c = make_cloud(5);
        c.radii.pop_back();
        EXPECT_THROW(sss::write_point_cloud(c, path), sss::ValueError);
        c = make_cloud(5);
        c.channels[1].data.push_back(1.0f);
        EXPECT_THROW(sss::write_point_cloud(c, path), sss::ValueError);
    }
    EXPECT_TRUE(fs::is_empty(dir.path())) << "a temporary or target file was left behind";
}

TEST(PointCloudWrite, FailedWriteLeavesTargetUntouched) {
    TempDir dir;
    const std::string path = dir.file("keep.ptc");
    sss::write_point_cloud(make_cloud(3), path);
    const Bytes before = read_bytes(path);
    PointCloud bad = make_cloud(3);
    bad.normals[0].x = std::numeric_limits<float>::quiet_NaN();
    EXPECT_THROW(sss::write_point_cloud(bad, path), sss::ValueError);
    EXPECT_EQ(read_bytes(path), before);
    sss::PointCloudWriteOptions v3;
    v3.ptc_version = 3;
    EXPECT_THROW(sss::write_point_cloud(make_cloud(3), path, v3), sss::ValueError);
    EXPECT_EQ(read_bytes(path), before);
    // Only the target is in the folder: no temporaries left over.
    EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()),
              1);
}

TEST(PointCloudWrite, UnwritableTargetIsIoError) {
    TempDir dir;
    const std::string path = dir.file("no/such/dir/out.ptc");
    EXPECT_THROW(sss::write_point_cloud(make_cloud(2), path), sss::IoError);
    EXPECT_THROW(sss::write_point_cloud(make_cloud(2), dir.file("no/x.ply")),
                 sss::IoError);
}

TEST(PointCloudWrite, PlyRefusesClashingPropertyNames) {
    TempDir dir;
    PointCloud c;
    c.resize(1);
    c.add_channel("radius", ChannelType::Float);
    EXPECT_THROW(sss::write_ply(c, dir.file("a.ply")), sss::ValueError);
    PointCloud d;
    d.resize(1);
    d.add_channel("c", ChannelType::Color);
    d.add_channel("c_r", ChannelType::Float);
    EXPECT_THROW(sss::write_ply(d, dir.file("b.ply")), sss::ValueError);
    sss::write_ptc(d, dir.file("b.ptc")); // fine in .ptc
}

// ---------------------------------------------------------------------------
// ptinfo report
// ---------------------------------------------------------------------------

TEST(DescribePointCloud, ListsHeaderChannelsAndStats) {
    const std::string path = std::string(SSS_TEST_DATA_DIR) + "/tiny_v0.ptc";
    const PointCloud c = sss::read_point_cloud(path);
    const std::string s = sss::describe_point_cloud(path, c, true);
    for (const char* line :
         {"format: ptc version 0\n", "compressed: no\n", "points: 3\n",
          "bbox: min -1 0 0  max 1 2 3\n",
          "world2eye: 1 0 0 0 | 0 1 0 0 | 0 0 1 0 | 0 0 5 1\n",
          "image format: 640 480 1\n", "  float _area\n",
          "    min 0.01  mean 0.02  max 0.03\n", "  color _radiance_t\n",
          "    b: min 0  mean 0.0416667  max 0.125\n",
          "radius: min 0.1  mean 0.2  max 0.3\n"}) {
        EXPECT_NE(s.find(line), std::string::npos) << line << "\n---\n" << s;
    }
    EXPECT_EQ(s.find("world2ndc"), std::string::npos);
    const std::string quiet = sss::describe_point_cloud(path, c, false);
    EXPECT_EQ(quiet.find("mean"), std::string::npos);
    EXPECT_NE(quiet.find("  color _radiance_t\n"), std::string::npos);
}

} // namespace
