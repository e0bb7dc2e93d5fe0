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

#include "../block.h"

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

template <bool Quadrupole>
void far_nodes(const BlockTables& tb, const Expansion* expansions, const uint32_t* nodes,
               std::size_t count, BucketBlock& b) {
    const int32_t bits0 = tb.bits0, last = tb.last;
    const int32_t n = int32_t(b.count);
    for (std::size_t k = 0; k < count; ++k) {
        const Expansion& ex = expansions[nodes[k]];
        const float cx = ex.c.x, cy = ex.c.y, cz = ex.c.z;
        for (int ch = 0; ch < 3; ++ch) {
            const TableEntry* T = tb.t[ch];
            const float phi = ex.phi[ch];
            const float* Q = ex.q[ch];
            const float* D = ex.d[ch];
            const float tr = Q[0] + Q[3] + Q[5];
            const float q0 = Q[0], q1 = 2.0f * Q[1], q2 = 2.0f * Q[2], q3 = Q[3],
                        q4 = 2.0f * Q[4], q5 = Q[5];
            const float d0 = D[0], d1 = D[1], d2 = D[2];
            float* acc = b.acc[ch];
#pragma GCC ivdep
            for (int32_t r = 0; r < n; ++r) {
                float wx = b.x[r] - cx, wy = b.y[r] - cy, wz = b.z[r] - cz;
                float q = wx * wx + wy * wy + wz * wz;
                // q >= 0, so its bits order like the value (branch-free).
                int32_t off = imax(float_bits(q) - bits0, 0);
                int32_t idx = imin(off >> kShift, last);
                float frac = float(off & ((1 << kShift) - 1)) * kFracScale;
                float keep = idx < last ? 1.0f : 0.0f;
                idx = imin(idx, last - 1);
                float f = T[idx].f + frac * (T[idx + 1].f - T[idx].f);
                float val = phi * f;
                if constexpr (Quadrupole) {
                    float df = T[idx].df + frac * (T[idx + 1].df - T[idx].df);
                    float d2f = T[idx].d2f + frac * (T[idx + 1].d2f - T[idx].d2f);
                    float wd = wx * d0 + wy * d1 + wz * d2;
                    float wqw = wx * (q0 * wx + q1 * wy + q2 * wz) +
                                wy * (q3 * wy + q4 * wz) + q5 * wz * wz;
                    // Taylor expansion of F(|w - delta|^2) to second order.
                    val += df * (tr - 2.0f * wd) + 2.0f * d2f * wqw;
                }
                acc[r] += keep * val;
            }
        }
    }
}

void far(const BlockTables& t, const Expansion* expansions, const uint32_t* nodes,
         std::size_t n, BucketBlock& b) {
    far_nodes<true>(t, expansions, nodes, n, b);
}

void mono(const BlockTables& t, const Expansion* expansions, const uint32_t* nodes,
          std::size_t n, BucketBlock& b) {
    far_nodes<false>(t, expansions, nodes, n, b);
}

void near(const BlockTables& tb, const float* pos_rho2, const float* power_area,
          uint32_t first, uint32_t count, BucketBlock& b) {
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
#pragma GCC ivdep
        for (int32_t r = 0; r < n; ++r) {
            float wx = b.x[r] - px, wy = b.y[r] - py, wz = b.z[r] - pz;
            float q = wx * wx + wy * wy + wz * wz;
            int32_t off = imax(float_bits(q) - bits0, 0);
            int32_t idx = imin(off >> kShift, last);
            float frac = float(off & ((1 << kShift) - 1)) * kFracScale;
            float keep = (idx < last && b.sorted[r] != self) ? 1.0f : 0.0f;
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

} // namespace

extern const BlockKernels kernels{SSS_KERNEL_ISA, far, mono, near};

} // namespace sss::diffusion_detail::SSS_KERNEL_NS
