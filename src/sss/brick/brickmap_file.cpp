// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file brickmap_file.cpp
/// The .bkm byte layout (docs/bkm-format.md): encoding of everything before
/// the bricks for the writer, and the reader's validation of the header,
/// channel table, tree directory, node tables and bricks. Every multi-byte
/// value is little-endian whatever the host.

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <set>

#include <unistd.h>

#include "brickmap_format.h"
#include "sss/util/byte_io.h"
#include "sss/util/error.h"
#include "sss/util/limits.h"

namespace sss::detail {

namespace {

// Field offsets of the fixed header (docs/bkm-format.md, "Header").
constexpr std::size_t kOffVersion = 8;
constexpr std::size_t kOffFlags = 12;
constexpr std::size_t kOffFileSize = 16;
constexpr std::size_t kOffChannelCount = 24;
constexpr std::size_t kOffDataSize = 28;
constexpr std::size_t kOffMaxDepth = 32;
constexpr std::size_t kOffTreeCount = 36;
constexpr std::size_t kOffProvenanceLength = 40;
constexpr std::size_t kOffChannelTableBytes = 44;
constexpr std::size_t kOffMaxError = 48;
constexpr std::size_t kOffBboxMin = 56;
constexpr std::size_t kOffBboxMax = 80;
constexpr std::size_t kOffCubeMin = 104;
constexpr std::size_t kOffCubeSide = 128;
constexpr std::size_t kOffWorldToEye = 136;
constexpr std::size_t kOffWorldToNdc = 200;
constexpr std::size_t kOffFormat = 264;
constexpr std::size_t kOffHeadCrc = 276;
constexpr std::size_t kOffBrickData = 280;

constexpr uint8_t kTypeFloat = 0;
constexpr uint8_t kTypeColor = 1;

std::size_t channel_table_bytes(const BrickMapInfo& info) {
    std::size_t n = 0;
    for (const auto& c : info.channels) n += 4 + c.first.size();
    return n;
}

std::string number(double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.9g", v);
    return buf;
}

void store_dvec3(unsigned char* p, const glm::dvec3& v) {
    for (int i = 0; i < 3; ++i) store_f64(p + 8 * i, v[i]);
}
glm::dvec3 load_dvec3(const unsigned char* p) {
    return {load_f64(p), load_f64(p + 8), load_f64(p + 16)};
}
bool finite3(const glm::dvec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

/// Fills the statistics of info from the node tables.
void fill_stats(BkmContents& c) {
    BrickMapInfo& info = c.info;
    info.levels.clear();
    info.trees_used = 0;
    info.total_bricks = 0;
    info.total_samples = 0;
    info.occupancy_nodes = 0;
    for (const auto& nodes : c.trees) {
        bool used = false;
        for (const BkmNode& n : nodes) {
            while (info.levels.size() <= n.depth) {
                BrickMapLevel level;
                level.depth = static_cast<int>(info.levels.size());
                info.levels.push_back(level);
            }
            BrickMapLevel& level = info.levels[n.depth];
            if (n.has_data()) {
                ++level.bricks;
                level.samples += n.samples;
                ++info.total_bricks;
                info.total_samples += n.samples;
                used = true;
            } else {
                ++level.occupancy_nodes;
                ++info.occupancy_nodes;
            }
        }
        if (used) ++info.trees_used;
    }
}

} // namespace

std::string bkm_brick_name(int tree, const BkmNode& node) {
    return "brick of tree " + std::to_string(tree) + ", depth " +
           std::to_string(node.depth) + ", node (" + std::to_string(node.ix) + ", " +
           std::to_string(node.iy) + ", " + std::to_string(node.iz) + ")";
}

void bkm_assign_offsets(BkmContents& contents) {
    const BrickMapInfo& info = contents.info;
    uint64_t offset = kBkmHeaderSize + channel_table_bytes(info) +
                      info.provenance.size() + kBkmTrees * kBkmDirEntrySize;
    for (const auto& nodes : contents.trees) offset += nodes.size() * kBkmNodeSize;
    for (auto& nodes : contents.trees) {
        for (BkmNode& n : nodes) {
            n.offset = offset;
            offset += bkm_brick_size(n, info.data_size);
        }
    }
    contents.info.file_size = offset;
}

std::vector<unsigned char> bkm_encode_head(const BkmContents& contents) {
    const BrickMapInfo& info = contents.info;
    const std::size_t table_bytes = channel_table_bytes(info);
    std::size_t head = kBkmHeaderSize + table_bytes + info.provenance.size() +
                       kBkmTrees * kBkmDirEntrySize;
    for (const auto& nodes : contents.trees) head += nodes.size() * kBkmNodeSize;
    std::vector<unsigned char> out(head, 0);
    unsigned char* h = out.data();

    std::copy(kBkmMagic.begin(), kBkmMagic.end(), h);
    store_u32(h + kOffVersion, kBkmVersion);
    store_u32(h + kOffFlags, (info.ignore_normals ? kBkmFlagIgnoreNormals : 0u) |
                                 (info.omit_geometry ? kBkmFlagOmitGeometry : 0u));
    store_u64(h + kOffFileSize, info.file_size);
    store_u32(h + kOffChannelCount, static_cast<uint32_t>(info.channels.size()));
    store_u32(h + kOffDataSize, static_cast<uint32_t>(info.data_size));
    store_u32(h + kOffMaxDepth, static_cast<uint32_t>(info.max_depth));
    store_u32(h + kOffTreeCount, kBkmTrees);
    store_u32(h + kOffProvenanceLength, static_cast<uint32_t>(info.provenance.size()));
    store_u32(h + kOffChannelTableBytes, static_cast<uint32_t>(table_bytes));
    store_f64(h + kOffMaxError, info.max_error);
    store_dvec3(h + kOffBboxMin, info.bbox_min);
    store_dvec3(h + kOffBboxMax, info.bbox_max);
    store_dvec3(h + kOffCubeMin, info.cube_min);
    store_f64(h + kOffCubeSide, info.cube_side);
    for (int i = 0; i < 16; ++i) {
        store_f32(h + kOffWorldToEye + 4 * i, info.world_to_eye[i]);
        store_f32(h + kOffWorldToNdc + 4 * i, info.world_to_ndc[i]);
    }
    for (int i = 0; i < 3; ++i) store_f32(h + kOffFormat + 4 * i, info.format[i]);
    store_u32(h + kOffHeadCrc, 0); // set last, over everything before the bricks
    store_u64(h + kOffBrickData, head);

    unsigned char* p = h + kBkmHeaderSize;
    for (const auto& [name, type] : info.channels) {
        p[0] = type == ChannelType::Color ? kTypeColor : kTypeFloat;
        p[1] = 0;
        store_u16(p + 2, static_cast<uint16_t>(name.size()));
        std::memcpy(p + 4, name.data(), name.size());
        p += 4 + name.size();
    }
    std::memcpy(p, info.provenance.data(), info.provenance.size());
    p += info.provenance.size();

    uint64_t table = static_cast<uint64_t>(p - h) + kBkmTrees * kBkmDirEntrySize;
    for (const auto& nodes : contents.trees) {
        uint32_t data_bricks = 0;
        for (const BkmNode& n : nodes) data_bricks += n.has_data() ? 1 : 0;
        store_u64(p, table);
        store_u32(p + 8, static_cast<uint32_t>(nodes.size()));
        store_u32(p + 12, data_bricks);
        p += kBkmDirEntrySize;
        table += nodes.size() * kBkmNodeSize;
    }
    for (const auto& nodes : contents.trees) {
        for (const BkmNode& n : nodes) {
            p[0] = n.depth;
            p[1] = n.child_mask;
            p[2] = n.flags;
            p[3] = 0;
            store_u16(p + 4, n.samples);
            store_u16(p + 6, 0);
            store_u32(p + 8, n.ix);
            store_u32(p + 12, n.iy);
            store_u32(p + 16, n.iz);
            store_u32(p + 20, n.first_child);
            store_u64(p + 24, n.offset);
            store_u32(p + 32, n.crc);
            p += kBkmNodeSize;
        }
    }
    store_u32(h + kOffHeadCrc, bkm_crc32(0, out.data(), out.size()));
    return out;
}

uint32_t bkm_crc32(uint32_t crc, const unsigned char* bytes, std::size_t size) {
    return detail::crc32(crc, bytes, size);
}

void bkm_check_brick_crc(const unsigned char* bytes, const BkmNode& node, int tree,
                         int data_size, const std::string& path) {
    const uint64_t size = bkm_brick_size(node, data_size);
    const uint32_t crc = bkm_crc32(0, bytes, static_cast<std::size_t>(size));
    if (crc == node.crc) return;
    char sums[64];
    std::snprintf(sums, sizeof sums, "stored 0x%08x, computed 0x%08x", node.crc, crc);
    throw FormatError(path, bkm_brick_name(tree, node) + " (bytes " +
                                std::to_string(node.offset) + " to " +
                                std::to_string(node.offset + size - 1) +
                                ") fails its CRC-32 check (" + sums +
                                "): the file is corrupt; rebuild it with brickmake");
}

void bkm_pread(int fd, const std::string& path, void* dst, std::size_t size,
               uint64_t offset) {
    auto* out = static_cast<unsigned char*>(dst);
    std::size_t done = 0;
    while (done < size) {
        const ssize_t got =
            ::pread(fd, out + done, size - done, static_cast<off_t>(offset + done));
        if (got < 0) {
            if (errno == EINTR) continue;
            throw IoError(path, std::string("read error: ") + std::strerror(errno));
        }
        if (got == 0) {
            throw FormatError(
                path, "truncated: " + std::to_string(size) +
                          " bytes expected at offset " + std::to_string(offset) +
                          ", the file ends after " + std::to_string(offset + done));
        }
        done += static_cast<std::size_t>(got);
    }
}

namespace {

/// The counts and sizes of a .bkm file's sections, from its header.
struct BkmSizes {
    uint32_t nchannels = 0, data_size = 0, max_depth = 0;
    uint32_t provenance_length = 0, table_bytes = 0;
    uint64_t dir_offset = 0, tables_offset = 0, brick_data = 0;
};

/// The tree directory as read, and its node and data brick counts per tree.
struct BkmDirectory {
    unsigned char bytes[kBkmTrees * kBkmDirEntrySize];
    std::array<uint32_t, kBkmTrees> counts{}, data_counts{};
};

/// Magic, version, flags and file size of header `h`, into `info`.
void read_header_identity(const unsigned char* h, const std::string& path,
                          uint64_t file_size, BrickMapInfo& info) {
    const auto fail = [&](const std::string& what) { return FormatError(path, what); };
    if (!std::equal(kBkmMagic.begin(), kBkmMagic.end(), h))
        throw fail("not a .bkm brick map (bad magic)");
    const uint32_t version = load_u32(h + kOffVersion);
    if (version != kBkmVersion) {
        // Version 1 had no checksums: reading it unchecked would let any
        // corruption through, and a brick map is always cheap to remake.
        throw fail("unsupported .bkm version " + std::to_string(version) +
                   (version < kBkmVersion
                        ? " (written by an older brickmake, without checksums): "
                          "rebuild it with brickmake"
                        : " (this sss reads version " + std::to_string(kBkmVersion) +
                              "; a newer brickmake wrote it)"));
    }
    info.version = version;
    const uint32_t flags = load_u32(h + kOffFlags);
    if (flags & ~(kBkmFlagIgnoreNormals | kBkmFlagOmitGeometry)) {
        char buf[64];
        std::snprintf(buf, sizeof buf, "unknown flags 0x%x in the header", flags);
        throw fail(buf);
    }
    info.ignore_normals = (flags & kBkmFlagIgnoreNormals) != 0;
    info.omit_geometry = (flags & kBkmFlagOmitGeometry) != 0;
    const uint64_t stored_size = load_u64(h + kOffFileSize);
    if (stored_size != file_size) {
        throw fail(stored_size > file_size
                       ? "truncated: the header says " + std::to_string(stored_size) +
                             " bytes but the file has " + std::to_string(file_size)
                       : "the file has " + std::to_string(file_size) +
                             " bytes but the header says " + std::to_string(stored_size));
    }
    info.file_size = file_size;
}

/// The counts, bounds, matrices and section offsets of header `h`, checked
/// against the file before any allocation that depends on them.
BkmSizes read_header_sizes(const unsigned char* h, const std::string& path,
                           uint64_t file_size, BrickMapInfo& info) {
    const auto fail = [&](const std::string& what) { return FormatError(path, what); };
    const uint32_t nchannels = load_u32(h + kOffChannelCount);
    const uint32_t data_size = load_u32(h + kOffDataSize);
    const uint32_t max_depth = load_u32(h + kOffMaxDepth);
    const uint32_t trees = load_u32(h + kOffTreeCount);
    const uint32_t provenance_length = load_u32(h + kOffProvenanceLength);
    const uint32_t table_bytes = load_u32(h + kOffChannelTableBytes);
    if (nchannels < 1 || nchannels > kBkmMaxChannels)
        throw fail("invalid channel count " + std::to_string(nchannels));
    if (data_size < 1 || data_size > kBkmMaxDataSize)
        throw fail("invalid data size " + std::to_string(data_size));
    if (max_depth > kBkmMaxDepth)
        throw fail("invalid maximum depth " + std::to_string(max_depth));
    if (trees != kBkmTrees)
        throw fail("invalid tree count " + std::to_string(trees) + " (must be 7)");
    if (provenance_length > kBkmMaxProvenance)
        throw fail("invalid provenance length " + std::to_string(provenance_length));
    if (table_bytes > nchannels * (4 + kBkmMaxNameLength) || table_bytes < 5 * nchannels)
        throw fail("invalid channel table size " + std::to_string(table_bytes));
    info.data_size = static_cast<int>(data_size);
    info.max_depth = static_cast<int>(max_depth);

    info.max_error = load_f64(h + kOffMaxError);
    if (!std::isfinite(info.max_error) || info.max_error < 0.0)
        throw fail("invalid max error " + number(info.max_error));
    info.bbox_min = load_dvec3(h + kOffBboxMin);
    info.bbox_max = load_dvec3(h + kOffBboxMax);
    info.cube_min = load_dvec3(h + kOffCubeMin);
    info.cube_side = load_f64(h + kOffCubeSide);
    if (!finite3(info.bbox_min) || !finite3(info.bbox_max) ||
        !(info.bbox_min.x <= info.bbox_max.x && info.bbox_min.y <= info.bbox_max.y &&
          info.bbox_min.z <= info.bbox_max.z))
        throw fail("invalid bounding box in the header");
    if (!finite3(info.cube_min) || !std::isfinite(info.cube_side) ||
        !(info.cube_side > 0.0) || !std::isfinite(info.cube_min.x + info.cube_side) ||
        !std::isfinite(info.cube_min.y + info.cube_side) ||
        !std::isfinite(info.cube_min.z + info.cube_side))
        throw fail("invalid root cube in the header");
    for (int i = 0; i < 16; ++i) {
        info.world_to_eye[i] = load_f32(h + kOffWorldToEye + 4 * i);
        info.world_to_ndc[i] = load_f32(h + kOffWorldToNdc + 4 * i);
        if (!std::isfinite(info.world_to_eye[i]))
            throw fail("non-finite value in the world2eye matrix");
        if (!std::isfinite(info.world_to_ndc[i]))
            throw fail("non-finite value in the world2ndc matrix");
    }
    for (int i = 0; i < 3; ++i) {
        info.format[i] = load_f32(h + kOffFormat + 4 * i);
        if (!std::isfinite(info.format[i]))
            throw fail("non-finite value in the image format");
    }

    // Sizes of the variable sections, checked against the file before any
    // allocation that depends on them.
    const uint64_t dir_offset =
        kBkmHeaderSize + uint64_t(table_bytes) + provenance_length;
    const uint64_t tables_offset = dir_offset + kBkmTrees * kBkmDirEntrySize;
    const uint64_t brick_data = load_u64(h + kOffBrickData);
    if (tables_offset > file_size || brick_data < tables_offset ||
        brick_data > file_size) {
        throw fail("invalid section offsets: brick data at " +
                   std::to_string(brick_data) + " in a file of " +
                   std::to_string(file_size) + " bytes");
    }
    return {nchannels,   data_size,  max_depth,     provenance_length,
            table_bytes, dir_offset, tables_offset, brick_data};
}

/// The tree directory, read on its own first: its node counts must fill
/// the node tables exactly, stay within Limit::Bricks and fit in memory
/// before anything is allocated for them.
void read_directory(int fd, const std::string& path, const BkmSizes& s, BkmDirectory& d) {
    const auto fail = [&](const std::string& what) { return FormatError(path, what); };
    bkm_pread(fd, path, d.bytes, sizeof d.bytes, s.dir_offset);
    uint64_t expected_table = s.tables_offset;
    uint64_t total_nodes = 0;
    std::array<uint32_t, kBkmTrees>& counts = d.counts;
    std::array<uint32_t, kBkmTrees>& data_counts = d.data_counts;
    for (int t = 0; t < kBkmTrees; ++t) {
        const unsigned char* e = d.bytes + t * kBkmDirEntrySize;
        const uint64_t table = load_u64(e);
        counts[t] = load_u32(e + 8);
        data_counts[t] = load_u32(e + 12);
        const std::string tree = "tree " + std::to_string(t);
        if (table != expected_table)
            throw fail("node table of " + tree + " at offset " + std::to_string(table) +
                       ", expected " + std::to_string(expected_table));
        if (uint64_t(counts[t]) * kBkmNodeSize > s.brick_data - expected_table)
            throw fail("node count " + std::to_string(counts[t]) + " of " + tree +
                       " does not fit in the file");
        if (data_counts[t] > counts[t])
            throw fail("data brick count of " + tree + " exceeds its node count");
        expected_table += uint64_t(counts[t]) * kBkmNodeSize;
        total_nodes += counts[t];
    }
    if (expected_table != s.brick_data)
        throw fail("brick data at offset " + std::to_string(s.brick_data) +
                   ", expected " + std::to_string(expected_table));
    check_limit(Limit::Bricks, total_nodes, path);
    // The tables as read, the records decoded, and BrickMap's lookup
    // structures over them (brickmap_lookup.cpp): about 120 bytes a node.
    // (Small maps skip the check: it reads cgroup files.)
    const uint64_t need = s.brick_data + total_nodes * 120;
    if (need >= (8u << 20))
        check_memory(need, "opening " + path,
                     "rebuild the map with a larger -maxerror, a smaller -maxdepth or "
                     "-omitgeometry 1");
}

/// The channel table and the provenance text after it, into `info`.
void read_channel_table(const unsigned char* base, const BkmSizes& s, BrickMapInfo& info,
                        const std::string& path) {
    const auto fail = [&](const std::string& what) { return FormatError(path, what); };
    const unsigned char* p = base + kBkmHeaderSize;
    const unsigned char* end = p + s.table_bytes;
    std::set<std::string> names;
    int sum = 0;
    for (uint32_t i = 0; i < s.nchannels; ++i) {
        const std::string which = "channel " + std::to_string(i + 1);
        if (end - p < 4) throw fail("channel table too short (at " + which + ")");
        const uint8_t type = p[0];
        const uint16_t len = load_u16(p + 2);
        if (type != kTypeFloat && type != kTypeColor)
            throw fail("unknown type code " + std::to_string(type) + " of " + which);
        if (p[1] != 0) throw fail("reserved byte of " + which + " is not 0");
        if (len < 1 || len > kBkmMaxNameLength || end - p - 4 < len)
            throw fail("invalid name length " + std::to_string(len) + " of " + which);
        std::string name(reinterpret_cast<const char*>(p + 4), len);
        for (unsigned char ch : name) {
            if (ch <= 0x20 || ch == 0x7f)
                throw fail("invalid character in the name of " + which);
        }
        if (!names.insert(name).second) throw fail("duplicate channel '" + name + "'");
        const ChannelType t =
            type == kTypeColor ? ChannelType::Color : ChannelType::Float;
        sum += channel_type_size(t);
        info.channels.emplace_back(std::move(name), t);
        p += 4 + len;
    }
    if (p != end) throw fail("channel table has trailing bytes");
    if (sum != static_cast<int>(s.data_size)) {
        throw fail("channel sizes add up to " + std::to_string(sum) +
                   " floats per sample but the header data size is " +
                   std::to_string(s.data_size));
    }
    const unsigned char* prov = end;
    info.provenance.assign(reinterpret_cast<const char*>(prov), s.provenance_length);
    if (info.provenance.find('\0') != std::string::npos)
        throw fail("provenance text contains a NUL byte");
}

/// Decodes and checks the node records of tree t from `table`; its bricks
/// start at `expected_brick`. Returns where the next tree's bricks start.
uint64_t read_node_table(const unsigned char* table, int t, uint64_t expected_brick,
                         uint32_t max_depth, int data_size, uint64_t file_size,
                         std::vector<BkmNode>& nodes, const std::string& path) {
    const auto fail = [&](const std::string& what) { return FormatError(path, what); };
    for (std::size_t i = 0; i < nodes.size(); ++i) {
        const unsigned char* r = table + i * kBkmNodeSize;
        BkmNode& n = nodes[i];
        n.depth = r[0];
        n.child_mask = r[1];
        n.flags = r[2];
        n.samples = load_u16(r + 4);
        n.ix = load_u32(r + 8);
        n.iy = load_u32(r + 12);
        n.iz = load_u32(r + 16);
        n.first_child = load_u32(r + 20);
        n.offset = load_u64(r + 24);
        n.crc = load_u32(r + 32);
        const auto bad = [&](const std::string& what) {
            return fail("node " + std::to_string(i) + " of tree " + std::to_string(t) +
                        ": " + what);
        };
        if (r[3] != 0 || load_u16(r + 6) != 0) throw bad("reserved bytes are not 0");
        if (n.flags & ~kBkmNodeHasData) throw bad("unknown flags");
        if (n.depth > max_depth)
            throw bad("depth " + std::to_string(n.depth) + " exceeds the maximum depth");
        const uint64_t limit = uint64_t(1) << n.depth;
        if (n.ix >= limit || n.iy >= limit || n.iz >= limit)
            throw bad("coordinates outside depth " + std::to_string(n.depth));
        if (n.samples < 1 || n.samples > kBrickSamples)
            throw bad("invalid sample count " + std::to_string(n.samples));
        if (n.offset != expected_brick)
            throw bad("brick at offset " + std::to_string(n.offset) + ", expected " +
                      std::to_string(expected_brick));
        const uint64_t size = bkm_brick_size(n, data_size);
        if (size > file_size - expected_brick)
            throw bad("brick beyond the end of the file");
        expected_brick += size;
    }
    return expected_brick;
}

/// Checks the structure of tree t: the root first, every other node the child
/// of exactly one earlier node, children contiguous and in octant order.
void check_tree_structure(const std::vector<BkmNode>& nodes, int t, uint32_t data_count,
                          const std::string& path) {
    const auto fail = [&](const std::string& what) { return FormatError(path, what); };
    if (nodes.empty()) {
        if (data_count != 0)
            throw fail("tree " + std::to_string(t) + " is empty but counts data bricks");
        return;
    }
    if (nodes[0].depth != 0 || !nodes[0].has_data())
        throw fail("tree " + std::to_string(t) +
                   ": the first node is not a root with data");
    uint64_t next = 1;
    uint32_t data = 0;
    for (std::size_t i = 0; i < nodes.size(); ++i) {
        const BkmNode& n = nodes[i];
        const auto bad = [&](const std::string& what) {
            return fail("node " + std::to_string(i) + " of tree " + std::to_string(t) +
                        ": " + what);
        };
        data += n.has_data() ? 1 : 0;
        if (i > 0 && i >= next) throw bad("not the child of any earlier node");
        if (n.child_mask == 0) {
            if (n.first_child != 0) throw bad("first child set without children");
            continue;
        }
        if (n.first_child != next)
            throw bad("first child " + std::to_string(n.first_child) + ", expected " +
                      std::to_string(next));
        const int kids = std::popcount(n.child_mask);
        if (next + kids > nodes.size()) throw bad("children beyond the node table");
        int k = 0;
        for (int o = 0; o < 8; ++o) {
            if (!((n.child_mask >> o) & 1)) continue;
            const BkmNode& ch = nodes[next + k++];
            if (ch.depth != n.depth + 1 || ch.ix != 2 * n.ix + (o & 1) ||
                ch.iy != 2 * n.iy + ((o >> 1) & 1) || ch.iz != 2 * n.iz + ((o >> 2) & 1))
                throw bad("child " + std::to_string(next + k - 1) +
                          " does not match its octant");
            if (ch.has_data() && !n.has_data())
                throw bad("a data brick below an occupancy-only node");
        }
        next += kids;
    }
    if (next != nodes.size()) throw fail("tree " + std::to_string(t) + ": orphan nodes");
    if (data != data_count)
        throw fail("tree " + std::to_string(t) + ": the directory counts " +
                   std::to_string(data_count) + " data bricks, the table has " +
                   std::to_string(data));
}

} // namespace

BkmContents bkm_read_head(int fd, const std::string& path, uint64_t file_size,
                          bool verify_checksums) {
    const auto fail = [&](const std::string& what) { return FormatError(path, what); };
    if (file_size < kBkmHeaderSize) {
        throw fail("file too short for a .bkm header (" + std::to_string(file_size) +
                   " of " + std::to_string(kBkmHeaderSize) + " bytes)");
    }
    unsigned char h[kBkmHeaderSize];
    bkm_pread(fd, path, h, sizeof h, 0);
    BkmContents c;
    BrickMapInfo& info = c.info;
    read_header_identity(h, path, file_size, info);
    const BkmSizes s = read_header_sizes(h, path, file_size, info);
    BkmDirectory d;
    read_directory(fd, path, s, d);

    std::vector<unsigned char> head(static_cast<std::size_t>(s.brick_data));
    std::copy(h, h + kBkmHeaderSize, head.begin());
    bkm_pread(fd, path, head.data() + kBkmHeaderSize, head.size() - kBkmHeaderSize,
              kBkmHeaderSize);
    if (!std::equal(d.bytes, d.bytes + sizeof d.bytes, head.begin() + s.dir_offset))
        throw fail("the file changed while it was read");
    if (verify_checksums) {
        const uint32_t stored = load_u32(h + kOffHeadCrc);
        store_u32(head.data() + kOffHeadCrc, 0); // the field is summed as 0
        const uint32_t crc = bkm_crc32(0, head.data(), head.size());
        if (crc != stored) {
            char sums[64];
            std::snprintf(sums, sizeof sums, "stored 0x%08x, computed 0x%08x", stored,
                          crc);
            throw fail("header and tables (bytes 0 to " +
                       std::to_string(s.brick_data - 1) + ") fail their CRC-32 check (" +
                       sums + "): the file is corrupt; rebuild it with brickmake");
        }
    }
    const unsigned char* base = head.data(); // file offset -> pointer

    read_channel_table(base, s, info, path);

    uint64_t expected_brick = s.brick_data;
    uint64_t table_offset = s.tables_offset;
    for (int t = 0; t < kBkmTrees; ++t) {
        std::vector<BkmNode>& nodes = c.trees[t];
        nodes.resize(d.counts[t]);
        const unsigned char* table = base + table_offset;
        table_offset += uint64_t(d.counts[t]) * kBkmNodeSize;
        expected_brick = read_node_table(table, t, expected_brick, s.max_depth,
                                         info.data_size, file_size, nodes, path);
        check_tree_structure(nodes, t, d.data_counts[t], path);
    }
    if (expected_brick != file_size) {
        throw fail("bricks end at offset " + std::to_string(expected_brick) +
                   " but the file has " + std::to_string(file_size) + " bytes");
    }
    fill_stats(c);
    return c;
}

void bkm_decode_brick(const unsigned char* bytes, const BkmNode& node, int tree,
                      int data_size, const std::string& path, uint64_t mask[8],
                      float* dense, float* packed) {
    int count = 0;
    for (int w = 0; w < 8; ++w) {
        mask[w] = load_u64(bytes + 8 * w);
        count += std::popcount(mask[w]);
    }
    if (count != node.samples) {
        throw FormatError(path, bkm_brick_name(tree, node) + ": the presence mask has " +
                                    std::to_string(count) + " samples, the node record " +
                                    std::to_string(node.samples));
    }
    if (!node.has_data()) return;
    const std::size_t ds = static_cast<std::size_t>(data_size);
    if (dense) std::fill(dense, dense + kBrickSamples * ds, 0.0f);
    const unsigned char* p = bytes + kBkmMaskBytes;
    for (int s = 0; s < kBrickSamples; ++s) {
        if (!((mask[s >> 6] >> (s & 63)) & 1)) continue;
        for (std::size_t k = 0; k < ds; ++k, p += 4) {
            const float v = load_f32(p);
            if (!std::isfinite(v)) {
                throw FormatError(path, bkm_brick_name(tree, node) +
                                            ": non-finite value in sample " +
                                            std::to_string(s));
            }
            if (dense) dense[s * ds + k] = v;
            if (packed) *packed++ = v;
        }
    }
}

} // namespace sss::detail
