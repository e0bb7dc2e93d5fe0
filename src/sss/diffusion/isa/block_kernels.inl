// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file block_kernels.inl
/// The block kernels of block.h, compiled once per instruction-set path:
/// src/sss/CMakeLists.txt generates one file per path that defines
/// SSS_KERNEL_NS and SSS_KERNEL_ISA and includes this one, compiled with the
/// path's -march and -ffp-contract=off (no fused multiply-adds), so every
/// path computes the same IEEE operations in the same order and the results
/// are identical bit for bit.
///
/// Everything here lives in the path's namespace and calls no inline function
/// or template shared with other files (no std:: or glm:: functions): such a
/// function would be emitted here with the path's instructions and the linker
/// could keep this copy for the whole program. A test (diffusion_isa_symbols)
/// checks the objects define no such weak symbol.

#include <cstring>

#include <immintrin.h>

#include "../block.h"
#include "../disk_quadrature.h"

// The receivers of a loop are independent: gcc vectorises them without
// proving it. clang, which builds only the sanitizer suite, does not read
// gcc's pragma and gets none (the sanitizer build is not about speed).
#if defined(__GNUC__) && !defined(__clang__)
#define SSS_IVDEP _Pragma("GCC ivdep")
#else
#define SSS_IVDEP
#endif

#ifndef SSS_KERNEL_NS
#error "compile through a generated file that defines SSS_KERNEL_NS"
#endif

namespace sss::diffusion_detail::SSS_KERNEL_NS {

namespace {

inline int32_t imax(int32_t a, int32_t b) {
    return a > b ? a : b;
}
inline int32_t imin(int32_t a, int32_t b) {
    return a < b ? a : b;
}
inline int32_t float_bits(float f) {
    int32_t i;
    __builtin_memcpy(&i, &f, sizeof i);
    return i;
}

// A node's expansion as the far kernels use it: its centre and, per channel,
// phi, the quadrupole's trace, its six terms (off-diagonal ones doubled) and
// the dipole.
struct NodeTerms {
    float cx, cy, cz;
    float phi[3], tr[3], q[3][6], d[3][3];
    explicit NodeTerms(const Expansion& ex) : cx(ex.c.x), cy(ex.c.y), cz(ex.c.z) {
        for (int ch = 0; ch < 3; ++ch) {
            const float* Q = ex.q[ch];
            phi[ch] = ex.phi[ch];
            tr[ch] = Q[0] + Q[3] + Q[5];
            q[ch][0] = Q[0];
            q[ch][1] = 2.0f * Q[1];
            q[ch][2] = 2.0f * Q[2];
            q[ch][3] = Q[3];
            q[ch][4] = 2.0f * Q[4];
            q[ch][5] = Q[5];
            for (int a = 0; a < 3; ++a) d[ch][a] = ex.d[ch][a];
        }
    }
    // The Taylor expansion of F(|w - delta|^2) beyond the monopole, to second
    // order, for channel ch at offset w from the centre.
    float second_order(int ch, float wx, float wy, float wz, float df, float d2f) const {
        float wd = wx * d[ch][0] + wy * d[ch][1] + wz * d[ch][2];
        float wqw = wx * (q[ch][0] * wx + q[ch][1] * wy + q[ch][2] * wz) +
                    wy * (q[ch][3] * wy + q[ch][4] * wz) + q[ch][5] * wz * wz;
        return df * (tr[ch] - 2.0f * wd) + 2.0f * d2f * wqw;
    }
};

template <bool Quadrupole>
void far_nodes_tables(const BlockTables& tb, const Expansion* expansions,
                      const uint32_t* nodes, std::size_t count, BucketBlock& b) {
    const int32_t bits0 = tb.bits0, last = tb.last;
    const int32_t n = int32_t(b.count);
    const TableEntry* T0 = tb.t[0];
    const TableEntry* T1 = tb.t[1];
    const TableEntry* T2 = tb.t[2];
    float* a0 = b.acc[0];
    float* a1 = b.acc[1];
    float* a2 = b.acc[2];
    for (std::size_t k = 0; k < count; ++k) {
        const NodeTerms m(expansions[nodes[k]]);
        const float cx = m.cx, cy = m.cy, cz = m.cz;
        const float* phi = m.phi;
        // The three channels in one pass: the receiver's offset and table
        // position are computed once for all of them.
        SSS_IVDEP
        for (int32_t r = 0; r < n; ++r) {
            float wx = b.x[r] - cx, wy = b.y[r] - cy, wz = b.z[r] - cz;
            float qq = wx * wx + wy * wy + wz * wz;
            // qq >= 0, so its bits order like the value (branch-free).
            int32_t off = imax(float_bits(qq) - bits0, 0);
            int32_t idx = imin(off >> kShift, last);
            float frac = float(off & ((1 << kShift) - 1)) * kFracScale;
            float keep = idx < last ? 1.0f : 0.0f;
            idx = imin(idx, last - 1);
            float v0 = phi[0] * (T0[idx].f + frac * (T0[idx + 1].f - T0[idx].f));
            float v1 = phi[1] * (T1[idx].f + frac * (T1[idx + 1].f - T1[idx].f));
            float v2 = phi[2] * (T2[idx].f + frac * (T2[idx + 1].f - T2[idx].f));
            if constexpr (Quadrupole) {
                // Taylor expansion of F(|w - delta|^2) to second order.
                const TableEntry* T[3] = {T0, T1, T2};
                float* v[3] = {&v0, &v1, &v2};
                for (int ch = 0; ch < 3; ++ch) {
                    float df = T[ch][idx].df + frac * (T[ch][idx + 1].df - T[ch][idx].df);
                    float d2f =
                        T[ch][idx].d2f + frac * (T[ch][idx + 1].d2f - T[ch][idx].d2f);
                    *v[ch] += m.second_order(ch, wx, wy, wz, df, d2f);
                }
            }
            a0[r] += keep * v0;
            a1[r] += keep * v1;
            a2[r] += keep * v2;
        }
    }
}

// The interleaved rows (Tables::rows): each receiver's table position goes
// to b.idx (as a float offset into the rows), and the first `Groups` groups
// of its row ({F}, {F'}, {F''}: six values each) to b.val[6 g + c], so that
// the arithmetic reads them as arrays. One row load per receiver replaces
// the 6 to 18 element loads of the per-channel tables.
//
// The rows of 8 (AVX2, and AVX-512 at 256 bits) or 4 (SSE2) receivers are
// loaded whole and transposed in registers; receivers past n read row 0
// (locate_rows() clears their positions) into scratch slots nobody reads.
#if defined(__AVX2__)
// The first six floats of the eight rows at p[0..8) as six columns (the 8 x 8
// transpose: unpack pairs, shuffle quads, then the 128-bit halves).
inline void transpose8(const float* const p[8], __m256 col[6]) {
    __m256 r[8], t[8], tt[8];
    for (int i = 0; i < 8; ++i) r[i] = _mm256_loadu_ps(p[i]);
    for (int i = 0; i < 4; ++i) {
        t[2 * i] = _mm256_unpacklo_ps(r[2 * i], r[2 * i + 1]);
        t[2 * i + 1] = _mm256_unpackhi_ps(r[2 * i], r[2 * i + 1]);
    }
    for (int h = 0; h < 2; ++h) {
        tt[4 * h + 0] = _mm256_shuffle_ps(t[4 * h], t[4 * h + 2], 0x44);
        tt[4 * h + 1] = _mm256_shuffle_ps(t[4 * h], t[4 * h + 2], 0xEE);
        tt[4 * h + 2] = _mm256_shuffle_ps(t[4 * h + 1], t[4 * h + 3], 0x44);
        tt[4 * h + 3] = _mm256_shuffle_ps(t[4 * h + 1], t[4 * h + 3], 0xEE);
    }
    col[0] = _mm256_permute2f128_ps(tt[0], tt[4], 0x20);
    col[1] = _mm256_permute2f128_ps(tt[1], tt[5], 0x20);
    col[2] = _mm256_permute2f128_ps(tt[2], tt[6], 0x20);
    col[3] = _mm256_permute2f128_ps(tt[3], tt[7], 0x20);
    col[4] = _mm256_permute2f128_ps(tt[0], tt[4], 0x31);
    col[5] = _mm256_permute2f128_ps(tt[1], tt[5], 0x31);
}

// Rows of receivers [r0, r0 + 8), group g, into b.val.
inline void read_rows8(const float* rows, BucketBlock& b, int32_t r0, int g) {
    const float* p[8];
    for (int i = 0; i < 8; ++i) p[i] = rows + b.idx[r0 + i] + 8 * g;
    __m256 col[6];
    transpose8(p, col);
    for (int c = 0; c < 6; ++c) _mm256_storeu_ps(b.val[6 * g + c] + r0, col[c]);
}

// Per-point materials: channel ch's profile rows of receivers [r0, r0 + 8)
// into the slots the interleaved rows fill ({F}: 2 ch, 2 ch + 1; {F'}: 6 +
// 2 ch, ...; the first `groups` of them).
inline void read_profile_rows8(const float* rows, BucketBlock& b, int32_t r0, int ch,
                               int groups) {
    const float* p[8];
    for (int i = 0; i < 8; ++i) p[i] = rows + b.base[ch][r0 + i] + b.idx[r0 + i];
    __m256 col[6];
    transpose8(p, col);
    for (int g = 0; g < groups; ++g) {
        _mm256_storeu_ps(b.val[6 * g + 2 * ch] + r0, col[2 * g]);
        _mm256_storeu_ps(b.val[6 * g + 2 * ch + 1] + r0, col[2 * g + 1]);
    }
}
#else
// The first eight floats of the four rows at p[0..4) as eight columns (SSE:
// two 4 x 4 transposes).
inline void transpose4(const float* const p[4], __m128 col[8]) {
    __m128 a0 = _mm_loadu_ps(p[0]), a1 = _mm_loadu_ps(p[1]), a2 = _mm_loadu_ps(p[2]),
           a3 = _mm_loadu_ps(p[3]);
    _MM_TRANSPOSE4_PS(a0, a1, a2, a3);
    __m128 c0 = _mm_loadu_ps(p[0] + 4), c1 = _mm_loadu_ps(p[1] + 4),
           c2 = _mm_loadu_ps(p[2] + 4), c3 = _mm_loadu_ps(p[3] + 4);
    _MM_TRANSPOSE4_PS(c0, c1, c2, c3);
    col[0] = a0, col[1] = a1, col[2] = a2, col[3] = a3;
    col[4] = c0, col[5] = c1, col[6] = c2, col[7] = c3;
}

// Rows of receivers [r0, r0 + 4), group g, into b.val.
inline void read_rows4(const float* rows, BucketBlock& b, int32_t r0, int g) {
    const float* p[4];
    for (int i = 0; i < 4; ++i) p[i] = rows + b.idx[r0 + i] + 8 * g;
    __m128 col[8];
    transpose4(p, col);
    for (int c = 0; c < 6; ++c) _mm_storeu_ps(b.val[6 * g + c] + r0, col[c]);
}

// read_profile_rows8() for four receivers.
inline void read_profile_rows4(const float* rows, BucketBlock& b, int32_t r0, int ch,
                               int groups) {
    const float* p[4];
    for (int i = 0; i < 4; ++i) p[i] = rows + b.base[ch][r0 + i] + b.idx[r0 + i];
    __m128 col[8];
    transpose4(p, col);
    for (int g = 0; g < groups; ++g) {
        _mm_storeu_ps(b.val[6 * g + 2 * ch] + r0, col[2 * g]);
        _mm_storeu_ps(b.val[6 * g + 2 * ch + 1] + r0, col[2 * g + 1]);
    }
}
#endif

// The first Groups groups of every receiver's row into b.val: the interleaved
// rows (PerLane false) or, per channel, each receiver's own profile rows.
template <int Groups, bool PerLane = false>
__attribute__((always_inline)) inline void read_rows(const BlockTables& tb,
                                                     BucketBlock& b, int32_t n) {
#if defined(__AVX2__)
    // (The AVX-512 path too: its kernels prefer 256-bit vectors, which were
    // faster than 512-bit ones here.)
    for (int32_t r0 = 0; r0 < n; r0 += 8) {
        if constexpr (PerLane) {
            if (Groups == 1 && tb.material_rows) {
                // The receivers' materials' rows: one load each, as one material's.
                const float* p[8];
                for (int i = 0; i < 8; ++i)
                    p[i] = tb.material_rows + b.mbase[r0 + i] + b.idx[r0 + i];
                __m256 col[6];
                transpose8(p, col);
                for (int c = 0; c < 6; ++c) _mm256_storeu_ps(b.val[c] + r0, col[c]);
                continue;
            }
            for (int ch = 0; ch < 3; ++ch)
                read_profile_rows8(tb.profile_rows, b, r0, ch, Groups);
        } else {
            for (int g = 0; g < Groups; ++g) read_rows8(tb.rows, b, r0, g);
        }
    }
#else
    for (int32_t r0 = 0; r0 < n; r0 += 4) {
        if constexpr (PerLane) {
            for (int ch = 0; ch < 3; ++ch)
                read_profile_rows4(tb.profile_rows, b, r0, ch, Groups);
        } else {
            for (int g = 0; g < Groups; ++g) read_rows4(tb.rows, b, r0, g);
        }
    }
#endif
}

// Whether a source disk of radius^2 rho2 at squared distance q needs the disk
// quadrature: kernels.h's needs_quadrature(), the same operations, repeated
// here because the kernels call no inline code shared with other files.
inline bool needs_quadrature(float rho2, float q, float core2) {
    return double(rho2) > kNearKappa2 * double(q + core2);
}

// The table position of every receiver against a source or node centre at
// (px, py, pz): b.idx (row offset), b.frac, and b.keep = 0 past the tables'
// end, for the receiver `self` (sorted position; -1: none) and, with Quad,
// where a source disk of radius^2 rho2 needs the quadrature (see near()).
// With per-point materials (Stride kProfileRowFloats) the quadrature test
// takes each receiver's own core (b.core2).
template <bool Quad = false, int Stride = kRowFloats>
inline void locate_rows(const BlockTables& tb, float px, float py, float pz, int32_t self,
                        BucketBlock& b, int32_t n, float rho2 = 0.0f,
                        float core2 = 0.0f) {
    constexpr bool kPerLane = Stride == kProfileRowFloats;
    const int32_t bits0 = tb.bits0, last = tb.last;
    SSS_IVDEP
    for (int32_t r = 0; r < n; ++r) {
        float wx = b.x[r] - px, wy = b.y[r] - py, wz = b.z[r] - pz;
        float q = wx * wx + wy * wy + wz * wz;
        int32_t off = imax(float_bits(q) - bits0, 0);
        int32_t idx = imin(off >> kShift, last);
        b.frac[r] = float(off & ((1 << kShift) - 1)) * kFracScale;
        bool keep = idx < last && b.sorted[r] != self;
        if constexpr (Quad)
            keep = keep && !needs_quadrature(rho2, q, kPerLane ? b.core2[r] : core2);
        b.keep[r] = keep ? 1.0f : 0.0f;
        b.idx[r] = imin(idx, last - 1) * Stride;
    }
    // read_rows() reads whole vectors of (at most 8) receivers.
    for (int32_t r = n; r < ((n + 7) & ~7); ++r) b.idx[r] = 0;
}

// far_nodes_tables() and near_tables() on the interleaved rows: the same
// operations in the same order, so the same bits.
template <bool Quadrupole, bool PerLane>
void far_nodes_rows(const BlockTables& tb, const Expansion* expansions,
                    const uint32_t* nodes, std::size_t count, BucketBlock& b) {
    const int32_t n = int32_t(b.count);
    float* a0 = b.acc[0];
    float* a1 = b.acc[1];
    float* a2 = b.acc[2];
    const float* V[18];
    for (int c = 0; c < 18; ++c) V[c] = b.val[c];
    for (std::size_t k = 0; k < count; ++k) {
        const NodeTerms m(expansions[nodes[k]]);
        const float cx = m.cx, cy = m.cy, cz = m.cz;
        const float* phi = m.phi;
        locate_rows<false, PerLane ? kProfileRowFloats : kRowFloats>(tb, cx, cy, cz, -1,
                                                                     b, n);
        read_rows<Quadrupole ? 3 : 1, PerLane>(tb, b, n);
        const float* frac = b.frac;
        const float* keep = b.keep;
        SSS_IVDEP
        for (int32_t r = 0; r < n; ++r) {
            const float fr = frac[r];
            float v0 = phi[0] * (V[0][r] + fr * V[1][r]);
            float v1 = phi[1] * (V[2][r] + fr * V[3][r]);
            float v2 = phi[2] * (V[4][r] + fr * V[5][r]);
            if constexpr (Quadrupole) {
                float wx = b.x[r] - cx, wy = b.y[r] - cy, wz = b.z[r] - cz;
                float* v[3] = {&v0, &v1, &v2};
                for (int ch = 0; ch < 3; ++ch) {
                    float df = V[6 + 2 * ch][r] + fr * V[7 + 2 * ch][r];
                    float d2f = V[12 + 2 * ch][r] + fr * V[13 + 2 * ch][r];
                    *v[ch] += m.second_order(ch, wx, wy, wz, df, d2f);
                }
            }
            a0[r] += keep[r] * v0;
            a1[r] += keep[r] * v1;
            a2[r] += keep[r] * v2;
        }
    }
}

template <bool Quad, bool PerLane>
void near_rows(const BlockTables& tb, const float* pos_rho2, const float* power_area,
               uint32_t first, uint32_t count, BucketBlock& b, float core2) {
    const int32_t n = int32_t(b.count);
    float* a0 = b.acc[0];
    float* a1 = b.acc[1];
    float* a2 = b.acc[2];
    const float* V[6];
    for (int c = 0; c < 6; ++c) V[c] = b.val[c];
    for (uint32_t j = first; j < first + count; ++j) {
        const float e0 = power_area[4 * j], e1 = power_area[4 * j + 1],
                    e2 = power_area[4 * j + 2];
        locate_rows<Quad, PerLane ? kProfileRowFloats : kRowFloats>(
            tb, pos_rho2[4 * j], pos_rho2[4 * j + 1], pos_rho2[4 * j + 2], int32_t(j), b,
            n, pos_rho2[4 * j + 3], core2);
        read_rows<1, PerLane>(tb, b, n);
        const float* frac = b.frac;
        const float* keep = b.keep;
        SSS_IVDEP
        for (int32_t r = 0; r < n; ++r) {
            const float fr = frac[r];
            float f0 = V[0][r] + fr * V[1][r];
            float f1 = V[2][r] + fr * V[3][r];
            float f2 = V[4][r] + fr * V[5][r];
            a0[r] += keep[r] * f0 * e0;
            a1[r] += keep[r] * f1 * e1;
            a2[r] += keep[r] * f2 * e2;
        }
    }
}

template <bool Quad>
void near_tables(const BlockTables& tb, const float* pos_rho2, const float* power_area,
                 uint32_t first, uint32_t count, BucketBlock& b, float core2);

// Source disks of moderate size (radius^2 at most kTaylorDisk2 times the
// squared distance) for profiles without a core: the disk's mean to second
// order, F + rho^2/2 (F' + |w_t|^2 F''), w_t the offset within the disk's
// plane (normal: the source's; a zero normal faces the receiver, w_t = 0).
// Larger disks are skipped for the caller's quadrature.
// The rows and the per-channel tables do the same operations in the same
// order.
// A source's normal for in-plane offsets, |w_t|^2 = has max(0, q - (w.n)^2 / n^2):
// 0 for a zero normal (the disk faces the receiver). Locals, so that the
// receivers' loop stays vectorised.
#define SSS_DISK_PLANE(normals, j)                                                       \
    const float* nrm = (normals) + 3 * std::size_t(j);                                   \
    const float nx = nrm[0], ny = nrm[1], nz = nrm[2];                                   \
    const float nn = nx * nx + ny * ny + nz * nz;                                        \
    const float inv_n2 = nn > 0.0f ? 1.0f / nn : 0.0f, has = nn > 0.0f ? 1.0f : 0.0f

template <bool PerLane>
void near_disks_rows(const BlockTables& tb, const float* pos_rho2,
                     const float* power_area, const float* normals, uint32_t first,
                     uint32_t count, BucketBlock& b) {
    const int32_t n = int32_t(b.count);
    const float* V[18];
    for (int c = 0; c < 18; ++c) V[c] = b.val[c];
    float* acc[3] = {b.acc[0], b.acc[1], b.acc[2]};
    for (uint32_t j = first; j < first + count; ++j) {
        const float e[3] = {power_area[4 * j], power_area[4 * j + 1],
                            power_area[4 * j + 2]};
        const float px = pos_rho2[4 * j], py = pos_rho2[4 * j + 1],
                    pz = pos_rho2[4 * j + 2];
        const float rho2 = pos_rho2[4 * j + 3], h = 0.5f * rho2;
        SSS_DISK_PLANE(normals, j);
        locate_rows<false, PerLane ? kProfileRowFloats : kRowFloats>(tb, px, py, pz,
                                                                     int32_t(j), b, n);
        read_rows<3, PerLane>(tb, b, n);
        const float* frac = b.frac;
        const float* keep = b.keep;
        SSS_IVDEP
        for (int32_t r = 0; r < n; ++r) {
            const float wx = b.x[r] - px, wy = b.y[r] - py, wz = b.z[r] - pz;
            const float q = wx * wx + wy * wy + wz * wz;
            const float k = rho2 > kTaylorDisk2 * q ? 0.0f : keep[r];
            const float wn = wx * nx + wy * ny + wz * nz;
            const float t2 = q - wn * wn * inv_n2;
            const float wt2 = has * (t2 > 0.0f ? t2 : 0.0f);
            const float fr = frac[r];
            for (int ch = 0; ch < 3; ++ch) {
                const float f = V[2 * ch][r] + fr * V[2 * ch + 1][r];
                const float df = V[6 + 2 * ch][r] + fr * V[7 + 2 * ch][r];
                const float d2f = V[12 + 2 * ch][r] + fr * V[13 + 2 * ch][r];
                acc[ch][r] += k * (f + h * (df + wt2 * d2f)) * e[ch];
            }
        }
    }
}

void near_disks_tables(const BlockTables& tb, const float* pos_rho2,
                       const float* power_area, const float* normals, uint32_t first,
                       uint32_t count, BucketBlock& b) {
    const int32_t bits0 = tb.bits0, last = tb.last;
    const int32_t n = int32_t(b.count);
    float* acc[3] = {b.acc[0], b.acc[1], b.acc[2]};
    for (uint32_t j = first; j < first + count; ++j) {
        const float px = pos_rho2[4 * j], py = pos_rho2[4 * j + 1],
                    pz = pos_rho2[4 * j + 2];
        const float e[3] = {power_area[4 * j], power_area[4 * j + 1],
                            power_area[4 * j + 2]};
        const int32_t self = int32_t(j);
        const float rho2 = pos_rho2[4 * j + 3], h = 0.5f * rho2;
        SSS_DISK_PLANE(normals, j);
        SSS_IVDEP
        for (int32_t r = 0; r < n; ++r) {
            const float wx = b.x[r] - px, wy = b.y[r] - py, wz = b.z[r] - pz;
            const float q = wx * wx + wy * wy + wz * wz;
            int32_t off = imax(float_bits(q) - bits0, 0);
            int32_t idx = imin(off >> kShift, last);
            const float fr = float(off & ((1 << kShift) - 1)) * kFracScale;
            const bool kept = idx < last && b.sorted[r] != self;
            const float k = rho2 > kTaylorDisk2 * q ? 0.0f : (kept ? 1.0f : 0.0f);
            const float wn = wx * nx + wy * ny + wz * nz;
            const float t2 = q - wn * wn * inv_n2;
            const float wt2 = has * (t2 > 0.0f ? t2 : 0.0f);
            idx = imin(idx, last - 1);
            for (int ch = 0; ch < 3; ++ch) {
                const TableEntry* T = tb.t[ch];
                const float f = T[idx].f + fr * (T[idx + 1].f - T[idx].f);
                const float df = T[idx].df + fr * (T[idx + 1].df - T[idx].df);
                const float d2f = T[idx].d2f + fr * (T[idx + 1].d2f - T[idx].d2f);
                acc[ch][r] += k * (f + h * (df + wt2 * d2f)) * e[ch];
            }
        }
    }
}

void near_disks(const BlockTables& t, const float* pos_rho2, const float* power_area,
                const float* normals, uint32_t first, uint32_t count, BucketBlock& b) {
    if (t.profile_rows)
        near_disks_rows<true>(t, pos_rho2, power_area, normals, first, count, b);
    else if (t.rows)
        near_disks_rows<false>(t, pos_rho2, power_area, normals, first, count, b);
    else
        near_disks_tables(t, pos_rho2, power_area, normals, first, count, b);
}

template <bool Quadrupole>
void far_nodes(const BlockTables& t, const Expansion* expansions, const uint32_t* nodes,
               std::size_t n, BucketBlock& b) {
    if (t.profile_rows)
        far_nodes_rows<Quadrupole, true>(t, expansions, nodes, n, b);
    else if (t.rows)
        far_nodes_rows<Quadrupole, false>(t, expansions, nodes, n, b);
    else
        far_nodes_tables<Quadrupole>(t, expansions, nodes, n, b);
}

template <bool Quad>
void near_pairs(const BlockTables& t, const float* pos_rho2, const float* power_area,
                uint32_t first, uint32_t count, BucketBlock& b, float core2) {
    if (t.profile_rows)
        near_rows<Quad, true>(t, pos_rho2, power_area, first, count, b, core2);
    else if (t.rows)
        near_rows<Quad, false>(t, pos_rho2, power_area, first, count, b, core2);
    else
        near_tables<Quad>(t, pos_rho2, power_area, first, count, b, core2);
}

void near(const BlockTables& t, const float* pos_rho2, const float* power_area,
          uint32_t first, uint32_t count, BucketBlock& b, float quadrature_core2) {
    if (quadrature_core2 >= 0.0f)
        near_pairs<true>(t, pos_rho2, power_area, first, count, b, quadrature_core2);
    else
        near_pairs<false>(t, pos_rho2, power_area, first, count, b, 0.0f);
}

void far(const BlockTables& t, const Expansion* expansions, const uint32_t* nodes,
         std::size_t n, BucketBlock& b) {
    far_nodes<true>(t, expansions, nodes, n, b);
}

void mono(const BlockTables& t, const Expansion* expansions, const uint32_t* nodes,
          std::size_t n, BucketBlock& b) {
    far_nodes<false>(t, expansions, nodes, n, b);
}

template <bool Quad>
void near_tables(const BlockTables& tb, const float* pos_rho2, const float* power_area,
                 uint32_t first, uint32_t count, BucketBlock& b, float core2) {
    const int32_t bits0 = tb.bits0, last = tb.last;
    const int32_t n = int32_t(b.count);
    const TableEntry* T0 = tb.t[0];
    const TableEntry* T1 = tb.t[1];
    const TableEntry* T2 = tb.t[2];
    float* a0 = b.acc[0];
    float* a1 = b.acc[1];
    float* a2 = b.acc[2];
    for (uint32_t j = first; j < first + count; ++j) {
        const float px = pos_rho2[4 * j], py = pos_rho2[4 * j + 1],
                    pz = pos_rho2[4 * j + 2];
        const float e0 = power_area[4 * j], e1 = power_area[4 * j + 1],
                    e2 = power_area[4 * j + 2];
        const int32_t self = int32_t(j);
        const float rho2 = pos_rho2[4 * j + 3];
        SSS_IVDEP
        for (int32_t r = 0; r < n; ++r) {
            float wx = b.x[r] - px, wy = b.y[r] - py, wz = b.z[r] - pz;
            float q = wx * wx + wy * wy + wz * wz;
            int32_t off = imax(float_bits(q) - bits0, 0);
            int32_t idx = imin(off >> kShift, last);
            float frac = float(off & ((1 << kShift) - 1)) * kFracScale;
            bool kept = idx < last && b.sorted[r] != self;
            if constexpr (Quad) kept = kept && !needs_quadrature(rho2, q, core2);
            float keep = kept ? 1.0f : 0.0f;
            idx = imin(idx, last - 1);
            float f0 = T0[idx].f + frac * (T0[idx + 1].f - T0[idx].f);
            float f1 = T1[idx].f + frac * (T1[idx + 1].f - T1[idx].f);
            float f2 = T2[idx].f + frac * (T2[idx + 1].f - T2[idx].f);
            a0[r] += keep * f0 * e0;
            a1[r] += keep * f1 * e1;
            a2[r] += keep * f2 * e2;
        }
    }
}

void local(const BlockTables& tb, const Expansion* expansions, const uint32_t* nodes,
           std::size_t count, const double centre[3], double out[3][10]) {
    constexpr int L = kLocalLanes;
    const int32_t bits0 = tb.bits0, last = tb.last;
    const float ox = float(centre[0]), oy = float(centre[1]), oz = float(centre[2]);
    alignas(64) double acc[3][10][L];
    for (int ch = 0; ch < 3; ++ch)
        for (int c = 0; c < 10; ++c)
            for (int j = 0; j < L; ++j) acc[ch][c][j] = 0.0;
    for (std::size_t base = 0; base < count; base += L) {
        const int m = count - base < std::size_t(L) ? int(count - base) : L;
        // The lanes' nodes as arrays (lanes past the end repeat the first
        // node and are weighted 0).
        alignas(64) float wxf[L], wyf[L], wzf[L], live[L];
        alignas(64) float phi[3][L], D[3][3][L], Q[3][6][L];
        for (int j = 0; j < L; ++j) {
            const Expansion& ex = expansions[nodes[base + std::size_t(j < m ? j : 0)]];
            wxf[j] = ox - ex.c.x;
            wyf[j] = oy - ex.c.y;
            wzf[j] = oz - ex.c.z;
            live[j] = j < m ? 1.0f : 0.0f;
            for (int ch = 0; ch < 3; ++ch) {
                phi[ch][j] = ex.phi[ch];
                for (int a = 0; a < 3; ++a) D[ch][a][j] = ex.d[ch][a];
                for (int a = 0; a < 6; ++a) Q[ch][a][j] = ex.q[ch][a];
            }
        }
        for (int ch = 0; ch < 3; ++ch) {
            const TableEntry* T = tb.t[ch];
            double* a0 = acc[ch][0];
            double *a1x = acc[ch][1], *a1y = acc[ch][2], *a1z = acc[ch][3];
            double *a2xx = acc[ch][4], *a2xy = acc[ch][5], *a2xz = acc[ch][6];
            double *a2yy = acc[ch][7], *a2yz = acc[ch][8], *a2zz = acc[ch][9];
            SSS_IVDEP
            for (int j = 0; j < L; ++j) {
                const float q = wxf[j] * wxf[j] + wyf[j] * wyf[j] + wzf[j] * wzf[j];
                const int32_t off = imax(float_bits(q) - bits0, 0);
                int32_t idx = imin(off >> kShift, last);
                const double frac = double(float(off & ((1 << kShift) - 1)) * kFracScale);
                // Beyond the tables (every profile ~0) or past the end: 0.
                const double keep = (idx < last && live[j] > 0.0f) ? 1.0 : 0.0;
                idx = imin(idx, last - 1);
                const double f =
                    keep *
                    (double(T[idx].f) + frac * (double(T[idx + 1].f) - double(T[idx].f)));
                const double df =
                    keep * (double(T[idx].df) +
                            frac * (double(T[idx + 1].df) - double(T[idx].df)));
                const double d2f =
                    keep * (double(T[idx].d2f) +
                            frac * (double(T[idx + 1].d2f) - double(T[idx].d2f)));
                const double wx = wxf[j], wy = wyf[j], wz = wzf[j];
                const double p = phi[ch][j];
                const double dx = D[ch][0][j], dy = D[ch][1][j], dz = D[ch][2][j];
                const double q0 = Q[ch][0][j], q1 = Q[ch][1][j], q2 = Q[ch][2][j],
                             q3 = Q[ch][3][j], q4 = Q[ch][4][j], q5 = Q[ch][5][j];
                // With G(w) = F(|w|^2): grad G = 2 F' w, H = 4 F'' w w^T + 2 F' I;
                // the node's sum about the centre to second order (see
                // local_expansion() in evaluation.cpp).
                const double wd = wx * dx + wy * dy + wz * dz;
                const double qwx = q0 * wx + q1 * wy + q2 * wz;
                const double qwy = q1 * wx + q3 * wy + q4 * wz;
                const double qwz = q2 * wx + q4 * wy + q5 * wz;
                const double wqw = wx * qwx + wy * qwy + wz * qwz;
                const double tr = q0 + q3 + q5;
                const double df2 = 2.0 * df, d2f2 = 2.0 * d2f;
                a0[j] += p * f - df2 * wd + d2f2 * wqw + df * tr;
                const double gw = df2 * p - 2.0 * d2f2 * wd;
                a1x[j] += gw * wx - df2 * dx;
                a1y[j] += gw * wy - df2 * dy;
                a1z[j] += gw * wz - df2 * dz;
                const double h = d2f2 * p, dp = df * p;
                a2xx[j] += h * wx * wx + dp;
                a2xy[j] += h * wx * wy;
                a2xz[j] += h * wx * wz;
                a2yy[j] += h * wy * wy + dp;
                a2yz[j] += h * wy * wz;
                a2zz[j] += h * wz * wz + dp;
            }
        }
    }
    for (int ch = 0; ch < 3; ++ch)
        for (int c = 0; c < 10; ++c) {
            double sum = 0.0;
            for (int j = 0; j < L; ++j) sum += acc[ch][c][j];
            out[ch][c] = sum;
        }
}

void local_pairs(const LocalPairs& lp, const Expansion* expansions, const uint32_t* nodes,
                 std::size_t count, const double centre[3], double* scratch,
                 double* out) {
    constexpr int L = kLocalLanes;
    const int32_t bits0 = lp.bits0, last = lp.last, pairs = lp.pairs;
    const float ox = float(centre[0]), oy = float(centre[1]), oz = float(centre[2]);
    for (int32_t p = 0; p < pairs * 10 * L; ++p) scratch[p] = 0.0;
    for (std::size_t base = 0; base < count; base += L) {
        const int m = count - base < std::size_t(L) ? int(count - base) : L;
        // Per lane (node; lanes past the end repeat the first, weighted 0)
        // and channel, the coefficients of F, F' and F'' in the node's sum
        // about the centre to second order (see local()): each pair then
        // adds its own table's values times them.
        alignas(64) int32_t idx[L];
        alignas(64) double frac[L], keep[L];
        alignas(64) double cf[3][L], cdf[3][10][L], cd2f[3][10][L];
        for (int j = 0; j < L; ++j) {
            const Expansion& ex = expansions[nodes[base + std::size_t(j < m ? j : 0)]];
            const float wxf = ox - ex.c.x, wyf = oy - ex.c.y, wzf = oz - ex.c.z;
            const float q = wxf * wxf + wyf * wyf + wzf * wzf;
            const int32_t off = imax(float_bits(q) - bits0, 0);
            const int32_t i = imin(off >> kShift, last);
            frac[j] = double(float(off & ((1 << kShift) - 1)) * kFracScale);
            keep[j] = (i < last && j < m) ? 1.0 : 0.0;
            idx[j] = imin(i, last - 1);
            const double wx = wxf, wy = wyf, wz = wzf;
            for (int ch = 0; ch < 3; ++ch) {
                const double p = ex.phi[ch];
                const double dx = ex.d[ch][0], dy = ex.d[ch][1], dz = ex.d[ch][2];
                const float* Q = ex.q[ch];
                const double q0 = Q[0], q1 = Q[1], q2 = Q[2], q3 = Q[3], q4 = Q[4],
                             q5 = Q[5];
                const double wd = wx * dx + wy * dy + wz * dz;
                const double wqw = wx * (q0 * wx + q1 * wy + q2 * wz) +
                                   wy * (q1 * wx + q3 * wy + q4 * wz) +
                                   wz * (q2 * wx + q4 * wy + q5 * wz);
                cf[ch][j] = p;
                cdf[ch][0][j] = (q0 + q3 + q5) - 2.0 * wd;
                cdf[ch][1][j] = 2.0 * (p * wx - dx);
                cdf[ch][2][j] = 2.0 * (p * wy - dy);
                cdf[ch][3][j] = 2.0 * (p * wz - dz);
                cdf[ch][4][j] = p;
                cdf[ch][5][j] = 0.0;
                cdf[ch][6][j] = 0.0;
                cdf[ch][7][j] = p;
                cdf[ch][8][j] = 0.0;
                cdf[ch][9][j] = p;
                const double h = 2.0 * p, g = -4.0 * wd;
                cd2f[ch][0][j] = 2.0 * wqw;
                cd2f[ch][1][j] = g * wx;
                cd2f[ch][2][j] = g * wy;
                cd2f[ch][3][j] = g * wz;
                cd2f[ch][4][j] = h * wx * wx;
                cd2f[ch][5][j] = h * wx * wy;
                cd2f[ch][6][j] = h * wx * wz;
                cd2f[ch][7][j] = h * wy * wy;
                cd2f[ch][8][j] = h * wy * wz;
                cd2f[ch][9][j] = h * wz * wz;
            }
        }
        for (int32_t pr = 0; pr < pairs; ++pr) {
            const TableEntry* T = lp.table[pr];
            const int ch = lp.channel[pr];
            double* acc = scratch + std::size_t(pr) * 10 * L;
            alignas(64) double f[L], df[L], d2f[L];
            for (int j = 0; j < L; ++j) {
                const TableEntry& a = T[idx[j]];
                const TableEntry& b = T[idx[j] + 1];
                f[j] = keep[j] * (double(a.f) + frac[j] * (double(b.f) - double(a.f)));
                df[j] =
                    keep[j] * (double(a.df) + frac[j] * (double(b.df) - double(a.df)));
                d2f[j] =
                    keep[j] * (double(a.d2f) + frac[j] * (double(b.d2f) - double(a.d2f)));
            }
            SSS_IVDEP
            for (int j = 0; j < L; ++j) acc[j] += f[j] * cf[ch][j];
            for (int c = 0; c < 10; ++c) {
                double* ac = acc + c * L;
                const double* a1 = cdf[ch][c];
                const double* a2 = cd2f[ch][c];
                SSS_IVDEP
                for (int j = 0; j < L; ++j) ac[j] += df[j] * a1[j] + d2f[j] * a2[j];
            }
        }
    }
    for (int32_t pr = 0; pr < pairs; ++pr)
        for (int c = 0; c < 10; ++c) {
            double sum = 0.0;
            for (int j = 0; j < L; ++j)
                sum += scratch[(std::size_t(pr) * 10 + c) * L + j];
            out[pr * 10 + c] = sum;
        }
}

} // namespace

extern const BlockKernels kernels{SSS_KERNEL_ISA, far,   mono,       near,
                                  near_disks,     local, local_pairs};

} // namespace sss::diffusion_detail::SSS_KERNEL_NS
