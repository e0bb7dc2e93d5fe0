// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file bkm_integrity_test.cpp
/// Brick maps under hostile input: every byte of a small map changed makes
/// opening, verify() (what brickinfo runs) or the lookups that read the
/// changed brick fail with a FormatError (no byte may change without harm:
/// docs/bkm-format.md, "Integrity"); older versions are refused with a hint;
/// BrickMapChecksums::Ignore still runs the structural checks; Limit::Bricks
/// and the memory budget stop brickmake before it builds and readers before
/// they allocate.

#include <gtest/gtest.h>

#include "test_util.h"

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <fcntl.h>
#include <unistd.h>

#include "sss/brick/brickmap.h"
#include "sss/cloud/point_cloud.h"
#include "sss/cloud/synthetic.h"
#include "sss/util/error.h"
#include "sss/util/limits.h"

using sss::BrickMap;
using sss::BrickMapBuildOptions;
using sss::BrickMapChecksums;
using sss::PointCloud;
using sss::test::Bytes;
using sss::test::read_bytes;
using sss::test::TempDir;
using sss::test::write_bytes;

namespace {

uint32_t get_u32(const Bytes& b, std::size_t at) {
    uint32_t v = 0;
    for (int i = 3; i >= 0; --i) v = (v << 8) | b[at + i];
    return v;
}
uint64_t get_u64(const Bytes& b, std::size_t at) {
    return uint64_t(get_u32(b, at)) | (uint64_t(get_u32(b, at + 4)) << 32);
}
void put_u32(Bytes& b, std::size_t at, uint32_t v) {
    for (int i = 0; i < 4; ++i) b[at + i] = static_cast<unsigned char>(v >> (8 * i));
}

bool contains(const std::string& s, const std::string& part) {
    return s.find(part) != std::string::npos;
}

/// A small sphere with a varying float channel: several trees, data bricks
/// at more than one depth and occupancy-only nodes, a few KB.
PointCloud small_sphere() {
    sss::SyntheticParams p;
    p.count = 600;
    p.size = 1.0;
    PointCloud c = sss::make_synthetic_cloud(p);
    c.channels.clear();
    sss::Channel& v = c.add_channel("v", sss::ChannelType::Float);
    for (std::size_t i = 0; i < c.size(); ++i)
        v.data[i] = std::sin(4.0f * c.positions[i].x) + c.positions[i].y;
    return c;
}

/// One node record of a file, decoded from its bytes (docs/bkm-format.md).
struct Node {
    int tree = 0, depth = 0;
    uint32_t ix = 0, iy = 0, iz = 0;
    bool data = false;
    uint64_t offset = 0, end = 0; ///< the brick's bytes
};

std::vector<Node> nodes_of(const Bytes& b) {
    const std::size_t dir_at = 288 + get_u32(b, 44) + get_u32(b, 40);
    std::vector<Node> out;
    for (int t = 0; t < 7; ++t) {
        const uint64_t table = get_u64(b, dir_at + 16 * t);
        const uint32_t count = get_u32(b, dir_at + 16 * t + 8);
        for (uint32_t i = 0; i < count; ++i) {
            const std::size_t r = static_cast<std::size_t>(table) + 36 * i;
            Node n;
            n.tree = t;
            n.depth = b[r];
            n.data = (b[r + 2] & 1) != 0;
            n.ix = get_u32(b, r + 8);
            n.iy = get_u32(b, r + 12);
            n.iz = get_u32(b, r + 16);
            n.offset = get_u64(b, r + 24);
            out.push_back(n);
        }
    }
    for (std::size_t i = 0; i < out.size(); ++i)
        out[i].end = i + 1 < out.size() ? out[i + 1].offset : b.size();
    return out;
}

/// A lookup that reads node's brick: at its centre, with its tree's normal
/// and the filter radius of fractional depth d + 0.5 (levels d and d + 1).
void lookup_node(const BrickMap& map, const Node& n, float* out) {
    const sss::BrickMapInfo& info = map.info();
    const double edge = info.cube_side / std::ldexp(1.0, n.depth);
    const glm::vec3 p(info.cube_min + (glm::dvec3(n.ix, n.iy, n.iz) + 0.5) * edge);
    glm::vec3 normal(0.0f);
    if (n.tree > 0) normal[(n.tree - 1) / 2] = n.tree % 2 == 1 ? 1.0f : -1.0f;
    const double radius = info.cube_side / (14.0 * std::ldexp(std::sqrt(2.0), n.depth));
    map.lookup(p, normal, static_cast<float>(radius), out);
}

/// Sets an environment variable for a scope.
class ScopedEnv {
public:
    ScopedEnv(const char* name, const std::string& value) : m_name(name) {
        setenv(name, value.c_str(), 1);
    }
    ~ScopedEnv() { unsetenv(m_name); }
    ScopedEnv(const ScopedEnv&) = delete;
    ScopedEnv& operator=(const ScopedEnv&) = delete;

private:
    const char* m_name;
};

/// Overrides a limit for a scope.
class ScopedLimit {
public:
    ScopedLimit(sss::Limit which, uint64_t value) : m_which(which) {
        sss::set_limit(which, value);
    }
    ~ScopedLimit() { sss::set_limit(m_which, 0); }
    ScopedLimit(const ScopedLimit&) = delete;
    ScopedLimit& operator=(const ScopedLimit&) = delete;

private:
    sss::Limit m_which;
};

} // namespace

// Every byte of the file XORed with 0x01 and with 0xff: the header and
// tables fail when the map is opened, a brick when it is read (verify(), a
// lookup at that brick, read_brick, read_occupancy). No change is accepted.
TEST(BkmIntegrity, EveryChangedByteIsAFormatError) {
    TempDir dir;
    BrickMapBuildOptions o;
    o.max_depth = 1;
    o.max_error = 0.7;
    sss::build_brick_map({small_sphere()}, o, dir.file("good.bkm"));
    const Bytes good = read_bytes(dir.file("good.bkm"));
    const std::vector<Node> nodes = nodes_of(good);
    const uint64_t first_brick = get_u64(good, 280);

    // What the map must hold for the sweep to reach every kind of region.
    ASSERT_LT(good.size(), 8000u);
    {
        const BrickMap map(dir.file("good.bkm"));
        EXPECT_EQ(map.verify(), nodes.size());
        EXPECT_GE(map.info().trees_used, 6u);
        EXPECT_GT(map.info().occupancy_nodes, 0u);
        EXPECT_GE(map.info().levels.size(), 2u);
        EXPECT_GT(map.info().levels[1].bricks, 0u);
        float out[1];
        for (const Node& n : nodes) lookup_node(map, n, out); // reads every data brick
        EXPECT_EQ(map.bricks_loaded(), map.info().total_bricks);
    }

    const std::string bad = dir.file("bad.bkm");
    write_bytes(bad, good);
    const int fd = ::open(bad.c_str(), O_WRONLY | O_CLOEXEC);
    ASSERT_GE(fd, 0);
    const auto set_byte = [&](std::size_t at, unsigned char value) {
        ASSERT_EQ(::pwrite(fd, &value, 1, static_cast<off_t>(at)), 1);
    };
    std::size_t accepted = 0, at_open = 0, at_read = 0;
    float out[1];
    std::vector<float> data;
    std::vector<uint8_t> present;
    for (std::size_t at = 0; at < good.size(); ++at) {
        const Node* node = nullptr;
        for (const Node& n : nodes)
            if (at >= n.offset && at < n.end) node = &n;
        ASSERT_EQ(node != nullptr, at >= first_brick) << at;
        for (unsigned char pattern : {0x01, 0xff}) {
            // The one byte changed in place (rewriting the file each time
            // would take most of the test's time).
            set_byte(at, good[at] ^ pattern);
            const std::string where =
                "byte " + std::to_string(at) + " ^ " + std::to_string(pattern);
            try {
                const BrickMap map(bad, 1u << 20);
                if (!node) {
                    ++accepted;
                    ADD_FAILURE() << where << ": the header and tables were accepted";
                    continue;
                }
                // The changed brick fails every read of it; verify() finds it.
                try {
                    map.verify();
                    ++accepted;
                    ADD_FAILURE() << where << ": verify() accepted it";
                } catch (const sss::FormatError& e) {
                    ++at_read;
                    const std::string what = e.what();
                    EXPECT_TRUE(contains(what, bad)) << what;
                    EXPECT_TRUE(contains(what, "CRC-32")) << what;
                    EXPECT_TRUE(
                        contains(what, "bytes " + std::to_string(node->offset) + " to "))
                        << what;
                }
                EXPECT_THROW(map.read_occupancy(node->tree, node->depth, node->ix,
                                                node->iy, node->iz, present),
                             sss::FormatError)
                    << where;
                if (node->data) {
                    EXPECT_THROW(lookup_node(map, *node, out), sss::FormatError) << where;
                    EXPECT_THROW(map.read_brick(node->tree, node->depth, node->ix,
                                                node->iy, node->iz, data, present),
                                 sss::FormatError)
                        << where;
                }
            } catch (const sss::FormatError& e) {
                ++at_open;
                EXPECT_FALSE(node) << where << ": a brick's byte failed the opening";
                EXPECT_TRUE(contains(e.what(), bad)) << e.what();
            }
        }
        set_byte(at, good[at]);
    }
    ::close(fd);
    EXPECT_EQ(accepted, 0u);
    EXPECT_EQ(at_open, 2 * first_brick);
    EXPECT_EQ(at_read, 2 * (good.size() - first_brick));
}

// A change the checksums catch would otherwise have been read: without them
// the same file opens and returns other values (so the check is what stops it).
TEST(BkmIntegrity, WithoutChecksumsAChangedValueIsRead) {
    TempDir dir;
    const PointCloud cloud = small_sphere();
    BrickMapBuildOptions o;
    o.max_depth = 2;
    sss::build_brick_map({cloud}, o, dir.file("m.bkm"));
    Bytes b = read_bytes(dir.file("m.bkm"));
    const std::vector<Node> nodes = nodes_of(b);
    const Node& root = nodes.front(); // a data brick: the root of the first tree
    ASSERT_TRUE(root.data);
    b[root.offset + 64 + 3] ^= 0x40; // the first value's exponent
    write_bytes(dir.file("m.bkm"), b);
    const BrickMap checked(dir.file("m.bkm"));
    const BrickMap unchecked(dir.file("m.bkm"), 1u << 20, BrickMapChecksums::Ignore);
    float out[1];
    EXPECT_THROW(lookup_node(checked, root, out), sss::FormatError);
    EXPECT_THROW(checked.verify(), sss::FormatError);
    EXPECT_NO_THROW(lookup_node(unchecked, root, out));
    EXPECT_EQ(unchecked.verify(), nodes.size());
}

TEST(BkmIntegrity, OtherVersionsAreRefused) {
    TempDir dir;
    sss::build_brick_map({small_sphere()}, {}, dir.file("m.bkm"));
    const Bytes good = read_bytes(dir.file("m.bkm"));
    for (uint32_t version : {1u, 3u}) {
        Bytes b = good;
        put_u32(b, 8, version);
        write_bytes(dir.file("v.bkm"), b);
        try {
            BrickMap map(dir.file("v.bkm"));
            ADD_FAILURE() << "version " << version << " accepted";
        } catch (const sss::FormatError& e) {
            const std::string what = e.what();
            EXPECT_TRUE(
                contains(what, "unsupported .bkm version " + std::to_string(version)))
                << what;
            if (version == 1) {
                EXPECT_TRUE(contains(what, "rebuild it with brickmake")) << what;
            }
        }
    }
    EXPECT_EQ(BrickMap(dir.file("m.bkm")).info().version, 2u);
}

// BrickMapChecksums::Ignore (the fuzz target's mode) still runs every
// structural check, with the specific messages.
TEST(BkmIntegrity, IgnoringChecksumsKeepsTheStructuralChecks) {
    TempDir dir;
    sss::build_brick_map({small_sphere()}, {}, dir.file("m.bkm"));
    const Bytes good = read_bytes(dir.file("m.bkm"));
    const auto error = [&](const Bytes& b, BrickMapChecksums mode) -> std::string {
        write_bytes(dir.file("x.bkm"), b);
        try {
            const BrickMap map(dir.file("x.bkm"), 1u << 20, mode);
            map.verify();
        } catch (const sss::FormatError& e) {
            return e.what();
        }
        return "";
    };
    const std::size_t dir_at = 288 + get_u32(good, 44) + get_u32(good, 40);
    Bytes b = good;
    put_u32(b, dir_at + 5 * 16 + 8, 0xfffffff0u); // tree 5's node count
    EXPECT_TRUE(contains(error(b, BrickMapChecksums::Ignore), "does not fit"));
    EXPECT_TRUE(contains(error(b, BrickMapChecksums::Verify), "does not fit"));
    b = good;
    b[dir_at + 7 * 16 + 3] = 1; // the first node record's reserved byte
    EXPECT_TRUE(contains(error(b, BrickMapChecksums::Ignore), "reserved bytes"));
    EXPECT_TRUE(contains(error(b, BrickMapChecksums::Verify), "header and tables"));
    b = good;
    put_u32(b, static_cast<std::size_t>(get_u64(good, 280)) + 64, 0x7fc00000u); // NaN
    EXPECT_TRUE(contains(error(b, BrickMapChecksums::Ignore), "non-finite value"));
    EXPECT_TRUE(contains(error(b, BrickMapChecksums::Verify), "CRC-32"));
    EXPECT_EQ(error(good, BrickMapChecksums::Verify), "");
}

// ---------------------------------------------------------------------------
// Limits and memory
// ---------------------------------------------------------------------------

namespace {

/// Points scattered through a cube with tiny footprints: at -maxdepth 12
/// nearly every point has a node of its own at every depth.
PointCloud scattered(std::size_t count) {
    PointCloud c;
    c.positions.resize(count);
    c.normals.assign(count, glm::vec3(0.0f, 0.0f, 1.0f));
    c.radii.assign(count, 1e-5f);
    sss::Channel& v = c.add_channel("v", sss::ChannelType::Float);
    uint64_t s = 12345;
    for (std::size_t i = 0; i < count; ++i) {
        for (int a = 0; a < 3; ++a) {
            s = s * 6364136223846793005ull + 1442695040888963407ull;
            c.positions[i][a] = float((s >> 11) * 0x1.0p-53) * 2.0f - 1.0f;
        }
        v.data[i] = float(i % 7);
    }
    return c;
}

} // namespace

TEST(BkmLimits, BrickmakeStopsBeforeBuildingMoreBricksThanTheLimit) {
    TempDir dir;
    const PointCloud cloud = scattered(2000);
    BrickMapBuildOptions o;
    o.max_depth = 12;
    {
        const ScopedLimit limit(sss::Limit::Bricks, 5000);
        try {
            sss::build_brick_map({cloud}, o, dir.file("m.bkm"));
            ADD_FAILURE() << "built beyond the brick limit";
        } catch (const sss::LimitError& e) {
            const std::string what = e.what();
            EXPECT_EQ(e.which(), sss::Limit::Bricks);
            EXPECT_TRUE(contains(what, "SSS_LIMIT_BRICKS")) << what;
            EXPECT_TRUE(contains(what, "exceeds the limit of 5000")) << what;
            EXPECT_TRUE(contains(what, "before pruning")) << what;
            EXPECT_TRUE(contains(what, "-maxdepth (now 12)")) << what;
        }
        EXPECT_FALSE(std::filesystem::exists(dir.file("m.bkm")));
    }
    // The estimate is a lower bound: whatever passes it, the nodes written
    // are checked too, and readers refuse maps beyond the limit.
    o.max_depth = 4;
    const sss::BrickMapBuildReport r =
        sss::build_brick_map({cloud}, o, dir.file("m.bkm"));
    const BrickMap map(dir.file("m.bkm"));
    const uint64_t nodes = map.info().total_bricks + map.info().occupancy_nodes;
    EXPECT_EQ(r.bricks_before_pruning, nodes);
    {
        const ScopedLimit limit(sss::Limit::Bricks, nodes - 1);
        try {
            sss::build_brick_map({cloud}, o, dir.file("n.bkm"));
            ADD_FAILURE() << "wrote more bricks than the limit";
        } catch (const sss::LimitError& e) {
            EXPECT_TRUE(contains(e.what(), "SSS_LIMIT_BRICKS")) << e.what();
        }
        // Readers apply the same limit: the map is refused before its tables
        // are decoded.
        try {
            BrickMap again(dir.file("m.bkm"));
            ADD_FAILURE() << "opened a map beyond the brick limit";
        } catch (const sss::LimitError& e) {
            const std::string what = e.what();
            EXPECT_TRUE(contains(what, dir.file("m.bkm"))) << what;
            EXPECT_TRUE(contains(what, std::to_string(nodes) + " bricks")) << what;
        }
    }
    EXPECT_NO_THROW(BrickMap(dir.file("m.bkm")));
}

TEST(BkmLimits, BrickmakeChecksTheMemoryItNeedsFirst) {
    TempDir dir;
    const PointCloud cloud = scattered(20000); // ~150000 nodes: about 250 MB
    BrickMapBuildOptions o;
    o.max_depth = 12;
    // A budget of what the process holds now plus 32 MB.
    const uint64_t budget = sss::resident_memory() + (32u << 20);
    const ScopedEnv env("SSS_MEMORY_LIMIT", std::to_string(budget));
    try {
        sss::build_brick_map({cloud}, o, dir.file("m.bkm"));
        ADD_FAILURE() << "no memory check";
    } catch (const sss::OutOfMemoryError& e) {
        const std::string what = e.what();
        EXPECT_TRUE(contains(what, "SSS_MEMORY_LIMIT")) << what;
        EXPECT_TRUE(contains(what, "lower -maxdepth")) << what;
    }
    EXPECT_FALSE(std::filesystem::exists(dir.file("m.bkm")));
}

TEST(BkmLimits, NodeCountsTheFileCannotHoldFailBeforeAllocating) {
    TempDir dir;
    sss::build_brick_map({small_sphere()}, {}, dir.file("m.bkm"));
    const Bytes good = read_bytes(dir.file("m.bkm"));
    const std::size_t dir_at = 288 + get_u32(good, 44) + get_u32(good, 40);
    // Every tree claiming 2^32 - 1 nodes: 7 * 2^32 (about 2^35) records.
    Bytes b = good;
    for (int t = 0; t < 7; ++t) put_u32(b, dir_at + 16 * t + 8, 0xffffffffu);
    write_bytes(dir.file("x.bkm"), b);
    try {
        BrickMap map(dir.file("x.bkm"), 1u << 20, BrickMapChecksums::Ignore);
        ADD_FAILURE() << "accepted";
    } catch (const sss::FormatError& e) {
        EXPECT_TRUE(contains(e.what(), "does not fit in the file")) << e.what();
    }
    // The first brick's offset moved to the end of a larger file: the node
    // tables no longer fill the space before it.
    b = good;
    b.resize(good.size() + (1u << 20), 0);
    for (int i = 0; i < 8; ++i)
        b[16 + i] = static_cast<unsigned char>(b.size() >> (8 * i));
    for (int i = 0; i < 8; ++i)
        b[280 + i] = static_cast<unsigned char>(b.size() >> (8 * i));
    write_bytes(dir.file("x.bkm"), b);
    try {
        BrickMap map(dir.file("x.bkm"), 1u << 20, BrickMapChecksums::Ignore);
        ADD_FAILURE() << "accepted";
    } catch (const sss::FormatError& e) {
        EXPECT_TRUE(contains(e.what(), "brick data at offset")) << e.what();
    }
}
