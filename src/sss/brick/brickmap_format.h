// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file brickmap_format.h
/// Internal: the .bkm byte layout of docs/bkm-format.md, shared by the writer
/// (brickmap_build.cpp) and the reader (brickmap_lookup.cpp); the encoding and
/// validation live in brickmap_file.cpp. Not installed.

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "sss/brick/brickmap.h"

namespace sss::detail {

/// "SSSBKM" and two zero bytes.
inline constexpr std::array<unsigned char, 8> kBkmMagic{'S', 'S', 'S', 'B',
                                                        'K', 'M', 0,   0};
/// Version 2 added the CRC-32 checksums (docs/bkm-format.md, "Integrity");
/// version 1 files are refused with "rebuild it with brickmake".
inline constexpr uint32_t kBkmVersion = 2;
inline constexpr int kBkmTrees = 7;
/// Deepest depth a file may use: node coordinates stay below 2^20 and a
/// sample's lattice coordinate 7 * 2^20 still fits comfortably in 32 bits.
inline constexpr int kBkmMaxDepth = 20;
/// Limits that keep a hostile header from driving huge allocations; far
/// beyond real maps (a brick of 1024 floats per sample is already 2 MB).
inline constexpr int kBkmMaxDataSize = 1024;
inline constexpr int kBkmMaxChannels = 1024;
inline constexpr std::size_t kBkmMaxProvenance = 1u << 20;
inline constexpr std::size_t kBkmMaxNameLength = 255;

inline constexpr std::size_t kBkmHeaderSize = 288;  ///< fixed header
inline constexpr std::size_t kBkmDirEntrySize = 16; ///< per tree
inline constexpr std::size_t kBkmNodeSize = 36;     ///< per node record
inline constexpr std::size_t kBkmMaskBytes = 64;    ///< 512 presence bits
inline constexpr int kBrickSamples = 512;           ///< 8 x 8 x 8

inline constexpr uint32_t kBkmFlagIgnoreNormals = 1u;
inline constexpr uint32_t kBkmFlagOmitGeometry = 2u;
/// Node flag: the node's brick carries sample data (otherwise it is an
/// occupancy-only node: presence mask, no data).
inline constexpr uint8_t kBkmNodeHasData = 1u;

/// One node record as stored (see docs/bkm-format.md, "Node tables").
struct BkmNode {
    uint8_t depth = 0;
    uint8_t child_mask = 0; ///< bit o: child octant o exists (o = x | y << 1 | z << 2)
    uint8_t flags = 0;      ///< kBkmNodeHasData
    uint16_t samples = 0;   ///< present samples in the brick (1..512)
    uint32_t ix = 0, iy = 0, iz = 0;
    uint32_t first_child = 0; ///< table index of the first child (0 if none)
    uint64_t offset = 0;      ///< file offset of the brick
    uint32_t crc = 0;         ///< CRC-32 of the brick's bytes

    bool has_data() const { return (flags & kBkmNodeHasData) != 0; }
};

/// Bytes of a node's brick: the presence mask, plus the present samples'
/// floats for a data brick.
inline uint64_t bkm_brick_size(const BkmNode& node, int data_size) {
    return kBkmMaskBytes +
           (node.has_data() ? uint64_t(4) * uint64_t(data_size) * node.samples : 0);
}

/// Everything in a file before the bricks: header fields (in info) and the
/// node table of each tree, in file order (breadth first, Morton order
/// within a depth).
struct BkmContents {
    BrickMapInfo info;
    std::array<std::vector<BkmNode>, kBkmTrees> trees;
};

/// Sets every node's brick offset (bricks follow the node tables in table
/// order, tree 0 first) and info.file_size.
void bkm_assign_offsets(BkmContents& contents);
/// Encodes everything before the first brick (call bkm_assign_offsets first
/// and set every node's crc): the header's checksum covers all of it.
std::vector<unsigned char> bkm_encode_head(const BkmContents& contents);
/// Reads and validates everything before the bricks from an open file of
/// file_size bytes: FormatError naming path on any inconsistency (with
/// verify_checksums, also a header-and-tables checksum that does not match),
/// LimitError for more nodes than Limit::Bricks, OutOfMemoryError when the
/// tables would not fit in memory. Also fills the derived statistics of info
/// (levels, totals, file size).
BkmContents bkm_read_head(int fd, const std::string& path, uint64_t file_size,
                          bool verify_checksums);

/// CRC-32 (zlib's: ISO-HDLC, the one of gzip and PNG) of size bytes,
/// continuing from crc (0 to start).
uint32_t bkm_crc32(uint32_t crc, const unsigned char* bytes, std::size_t size);
/// FormatError unless a brick's bytes match its node record's checksum:
/// names the brick and its byte range.
void bkm_check_brick_crc(const unsigned char* bytes, const BkmNode& node, int tree,
                         int data_size, const std::string& path);

/// Validates and decodes one brick's bytes (bkm_brick_size(node) of them):
/// mask gets the 512 presence bits (bit s % 64 of word s / 64), dense (if not
/// null, 512 * data_size floats) the samples in index order with absent
/// samples zero, packed (if not null, node.samples * data_size floats) the
/// present samples only, in index order (the file's order). FormatError
/// naming path and the brick on a mask that disagrees with the node record
/// or a non-finite value.
void bkm_decode_brick(const unsigned char* bytes, const BkmNode& node, int tree,
                      int data_size, const std::string& path, uint64_t mask[8],
                      float* dense, float* packed = nullptr);

/// Reads exactly size bytes at offset with pread; FormatError if the file
/// ends first (it shrank after it was opened), IoError on a read error.
void bkm_pread(int fd, const std::string& path, void* dst, std::size_t size,
               uint64_t offset);

/// "tree 3, depth 5, node (4, 9, 17)": names a brick in messages.
std::string bkm_brick_name(int tree, const BkmNode& node);

/// Morton code of node coordinates (x in bit 0, y in bit 1, z in bit 2 of
/// each triple); coordinates below 2^21.
inline uint64_t bkm_spread3(uint32_t v) {
    uint64_t x = v & 0x1fffffu;
    x = (x | (x << 32)) & 0x1f00000000ffffull;
    x = (x | (x << 16)) & 0x1f0000ff0000ffull;
    x = (x | (x << 8)) & 0x100f00f00f00f00full;
    x = (x | (x << 4)) & 0x10c30c30c30c30c3ull;
    x = (x | (x << 2)) & 0x1249249249249249ull;
    return x;
}
inline uint64_t bkm_morton(uint32_t x, uint32_t y, uint32_t z) {
    return bkm_spread3(x) | (bkm_spread3(y) << 1) | (bkm_spread3(z) << 2);
}
inline uint32_t bkm_compact3(uint64_t x) {
    x &= 0x1249249249249249ull;
    x = (x | (x >> 2)) & 0x10c30c30c30c30c3ull;
    x = (x | (x >> 4)) & 0x100f00f00f00f00full;
    x = (x | (x >> 8)) & 0x1f0000ff0000ffull;
    x = (x | (x >> 16)) & 0x1f00000000ffffull;
    x = (x | (x >> 32)) & 0x1fffffull;
    return static_cast<uint32_t>(x);
}

} // namespace sss::detail
