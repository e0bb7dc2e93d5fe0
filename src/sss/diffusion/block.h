// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file block.h
/// The vectorised block kernels: one source or node against all receivers of
/// a bucket. They are compiled once per instruction-set path
/// (isa/block_kernels.inl, see sss/util/isa.h) and reached through a table of
/// function pointers, so the library itself stays baseline x86-64.

#include <cstddef>
#include <cstdint>

#include "sss/util/isa.h"

#include "octree.h"
#include "profile_tables.h"

namespace sss::diffusion_detail {

// Receivers of one bucket in structure-of-arrays form, so the loops over
// receivers vectorise (one source or node against all receivers at once).
constexpr uint32_t kMaxBucket = 128;
struct BucketBlock {
    uint32_t count = 0;
    alignas(64) float x[kMaxBucket], y[kMaxBucket], z[kMaxBucket];
    alignas(64) int32_t sorted[kMaxBucket];
    alignas(64) float acc[3][kMaxBucket];
    // The kernels' scratch: each receiver's table position, and the values
    // read there (see Tables::rows).
    alignas(64) int32_t idx[kMaxBucket];
    alignas(64) float frac[kMaxBucket], keep[kMaxBucket];
    alignas(64) float val[18][kMaxBucket];
    // With per-point materials (BlockTables::profile_rows): each receiver's
    // profile per channel, as its float offset into the profile rows (the
    // lanes past count up to a multiple of 8 hold 0).
    alignas(64) int32_t base[3][kMaxBucket];
    // ... and its material's offset into BlockTables::material_rows.
    alignas(64) int32_t mbase[kMaxBucket];
    alignas(64) float core2[kMaxBucket]; // each receiver's near_core2
};

// The three channel tables every receiver of a block reads, and the table
// range (plain data: the kernels call no shared inline code, see
// isa/block_kernels.inl).
struct BlockTables {
    const TableEntry* t[3];
    int32_t bits0; // float bits of the tables' first q
    int32_t last;  // index of the last entry
    // Tables::rows when t are channels 0, 1 and 2, else null.
    const float* rows;
    // Tables::profile_rows when the receivers' profiles differ (read through
    // BucketBlock::base; t and rows are then unused by far, mono, near and
    // near_disks), else null.
    const float* profile_rows = nullptr;
    // With profile_rows: the materials' near rows (material_near_rows(),
    // read through BucketBlock::mbase), or null.
    const float* material_rows = nullptr;
};

// Per-point materials: the (channel, table) pairs whose local expansions a
// node of receivers needs (plain data, as BlockTables).
struct LocalPairs {
    const TableEntry* const* table; // pairs of them
    const int32_t* channel;         // each pair's channel (its moments)
    int32_t pairs;
    int32_t bits0, last; // as BlockTables
};

struct BlockKernels {
    Isa isa;
    // Adds the expansions of nodes[0..n) to every receiver: second order
    // (far) or the monopole alone (mono).
    void (*far)(const BlockTables& t, const Expansion* expansions, const uint32_t* nodes,
                std::size_t n, BucketBlock& b);
    void (*mono)(const BlockTables& t, const Expansion* expansions, const uint32_t* nodes,
                 std::size_t n, BucketBlock& b);
    // Adds point sources [first, first + count) to every receiver, skipping
    // each receiver's own point; pos_rho2 and power_area are the tree's
    // sorted arrays as floats (4 per point). With quadrature_core2 >= 0 (the
    // receivers' near_core2), the pairs whose source disk needs the disk
    // quadrature (near_source()'s test) are skipped too, for the caller to
    // add (with profile_rows: each receiver's own b.core2, quadrature_core2
    // their smallest); below 0, the caller has checked that no pair does.
    void (*near)(const BlockTables& t, const float* pos_rho2, const float* power_area,
                 uint32_t first, uint32_t count, BucketBlock& b, float quadrature_core2);
    // The same for receivers whose profiles have no core (near_core2 = 0):
    // each source disk (normals: the tree's, 3 floats per point) as its
    // second-order mean (kTaylorDisk2); the pairs whose disk is larger than
    // that are skipped, for the caller's quadrature.
    void (*near_disks)(const BlockTables& t, const float* pos_rho2,
                       const float* power_area, const float* normals, uint32_t first,
                       uint32_t count, BucketBlock& b);
    // The second-order local expansion about `centre` of the expansions of
    // nodes[0..n) (evaluation.cpp's LocalExpansion), in double: out[ch] =
    // {l0, l1 x y z, l2 xx xy xz yy yz zz}, overwritten. The nodes are summed
    // in kLocalLanes interleaved partial sums, reduced in lane order at the
    // end: every path does the same operations and gives the same bits.
    void (*local)(const BlockTables& t, const Expansion* expansions,
                  const uint32_t* nodes, std::size_t n, const double centre[3],
                  double out[3][10]);
    // local() for every pair of `p`, each with its channel's moments: out is
    // p.pairs blocks of 10, overwritten; scratch holds p.pairs * 10 *
    // kLocalLanes doubles. The nodes' moments are read once for all pairs.
    void (*local_pairs)(const LocalPairs& p, const Expansion* expansions,
                        const uint32_t* nodes, std::size_t n, const double centre[3],
                        double* scratch, double* out);
};
constexpr int kLocalLanes = 8;

// The kernels of one path (Auto: resolve_isa()); throws UsageError when the
// CPU lacks it.
const BlockKernels& block_kernels(Isa isa);

// Per path (isa/block_kernels.inl compiled with the path's flags).
namespace isa_x86_64 {
extern const BlockKernels kernels;
}
namespace isa_avx2 {
extern const BlockKernels kernels;
}
namespace isa_avx512 {
extern const BlockKernels kernels;
}

} // namespace sss::diffusion_detail
