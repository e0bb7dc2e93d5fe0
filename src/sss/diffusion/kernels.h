#pragma once
/// \file kernels.h
/// The evaluation's inner loops: one receiver against a near source (point or
/// disk quadrature) or a far node's expansion, and the vectorised block loops
/// that take one source or node against all receivers of a bucket. Inline:
/// they run in the hot loops of evaluation.cpp.

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "sss/diffusion/diffusion.h"

#include "disk_quadrature.h"
#include "octree.h"
#include "profile_tables.h"

namespace sss::diffusion_detail {

// The three channels' F(q), linear between table entries (0 past the table).
inline void lookup3(const Tables& tables, const ReceiverChannels& rc, float q,
                    float out[3]) {
    Tables::Lookup l = tables.locate(q);
    if (!l.valid) {
        out[0] = out[1] = out[2] = 0.0f;
        return;
    }
    for (int ch = 0; ch < 3; ++ch) {
        const TableEntry* e = rc.table[ch]->entries.data() + l.index;
        out[ch] = e[0].f + l.frac * (e[1].f - e[0].f);
    }
}

// The last coincident-source disk integral per channel (valid within one
// evaluation, where profiles do not move).
struct DiskMemo {
    const Profile* profile = nullptr;
    double rho = -1.0, value = 0.0;
};

// Contribution of sorted source s to receiver at x (never the receiver itself).
inline void near_source(const Tree& tree, const Tables& tables,
                        const ReceiverChannels& rc, const glm::vec3& x, uint32_t s,
                        double acc[3], DiffusionStats& st, DiskMemo memo[3]) {
    const glm::vec4& pr = tree.pos_rho2[s];
    const glm::vec4& pa = tree.power_area[s];
    glm::vec3 w = x - glm::vec3(pr);
    float q = glm::dot(w, w);
    if (pr.w > kNearKappa2 * (q + rc.near_core2)) {
        ++st.quadrature_terms;
        double rho = std::sqrt(double(pr.w));
        if (q == 0.0f) {
            // Coincident source: its disk is centred on the receiver. Coincident
            // points come in big leaves (O(n^2) pairs), usually of equal area:
            // the last disk value per channel is kept, so a pair costs a
            // multiply rather than a closed form with exponentials.
            for (int ch = 0; ch < 3; ++ch) {
                if (!(pa.w > 0)) continue;
                DiskMemo& m = memo[ch];
                if (m.profile != rc.profile[ch] || m.rho != rho)
                    m = {rc.profile[ch], rho, rc.profile[ch]->disk(rho)};
                acc[ch] += pa[ch] / pa.w * m.value;
            }
            return;
        }
        glm::dvec3 u, v;
        disk_frame(glm::dvec3(tree.normal[s]), glm::dvec3(w), u, v);
        double sum[3] = {0, 0, 0};
        for_disk_points(rho, u, v, [&](const glm::dvec3& off, double wt) {
            glm::vec3 d = w - glm::vec3(off);
            float f[3];
            lookup3(tables, rc, glm::dot(d, d), f);
            for (int ch = 0; ch < 3; ++ch) sum[ch] += wt * f[ch];
        });
        for (int ch = 0; ch < 3; ++ch) acc[ch] += sum[ch] * pa[ch];
        return;
    }
    ++st.near_terms;
    float f[3];
    lookup3(tables, rc, q, f);
    for (int ch = 0; ch < 3; ++ch) acc[ch] += double(f[ch] * pa[ch]);
}

// Far-field term of a node for a receiver at x.
inline void far_node(const Tables& tables, const ReceiverChannels& rc,
                     const Expansion& ex, const glm::vec3& x, bool quadrupole,
                     double acc[3]) {
    glm::vec3 w = x - ex.c;
    float q = glm::dot(w, w);
    Tables::Lookup l = tables.locate(q);
    if (!l.valid) return;
    for (int ch = 0; ch < 3; ++ch) {
        const TableEntry* e = rc.table[ch]->entries.data() + l.index;
        float f = e[0].f + l.frac * (e[1].f - e[0].f);
        float val = ex.phi[ch] * f;
        if (quadrupole) {
            float df = e[0].df + l.frac * (e[1].df - e[0].df);
            float d2f = e[0].d2f + l.frac * (e[1].d2f - e[0].d2f);
            const float* Q = ex.q[ch];
            const float* D = ex.d[ch];
            float tr = Q[0] + Q[3] + Q[5];
            float wd = w.x * D[0] + w.y * D[1] + w.z * D[2];
            float wqw = w.x * (Q[0] * w.x + 2.0f * (Q[1] * w.y + Q[2] * w.z)) +
                        w.y * (Q[3] * w.y + 2.0f * Q[4] * w.z) + w.z * Q[5] * w.z;
            // Taylor expansion of F(|w - delta|^2) to second order in delta.
            val += df * (tr - 2.0f * wd) + 2.0f * d2f * wqw;
        }
        acc[ch] += double(val);
    }
}

// Receivers of one bucket in structure-of-arrays form, so the loops over
// receivers vectorise (one source or node against all receivers at once).
constexpr uint32_t kMaxBucket = 64;
struct BucketBlock {
    uint32_t count = 0;
    alignas(64) float x[kMaxBucket], y[kMaxBucket], z[kMaxBucket];
    alignas(64) int32_t sorted[kMaxBucket];
    alignas(64) float acc[3][kMaxBucket];
};

// Adds the far-field terms of node expansions to every receiver of the
// block; all receivers share the channel tables t[0..2].
template <bool Quadrupole>
void block_far(const Tables& tables, const TableEntry* const t[3], const Expansion& ex,
               BucketBlock& b) {
    const int32_t bits0 = int32_t(tables.bits0), last = int32_t(tables.count) - 1;
    const float cx = ex.c.x, cy = ex.c.y, cz = ex.c.z;
    for (int ch = 0; ch < 3; ++ch) {
        const TableEntry* T = t[ch];
        const float phi = ex.phi[ch];
        const float* Q = ex.q[ch];
        const float* D = ex.d[ch];
        const float tr = Q[0] + Q[3] + Q[5];
        const float q0 = Q[0], q1 = 2.0f * Q[1], q2 = 2.0f * Q[2], q3 = Q[3],
                    q4 = 2.0f * Q[4], q5 = Q[5];
        const float d0 = D[0], d1 = D[1], d2 = D[2];
        float* acc = b.acc[ch];
        const int32_t n = int32_t(b.count);
#pragma GCC ivdep
        for (int32_t r = 0; r < n; ++r) {
            float wx = b.x[r] - cx, wy = b.y[r] - cy, wz = b.z[r] - cz;
            float q = wx * wx + wy * wy + wz * wz;
            // q >= 0, so its bits order like the value (branch-free for SIMD).
            int32_t off = std::max(std::bit_cast<int32_t>(q) - bits0, 0);
            int32_t idx = std::min(off >> kShift, last);
            float frac = float(off & ((1 << kShift) - 1)) * kFracScale;
            float keep = idx < last ? 1.0f : 0.0f;
            idx = std::min(idx, last - 1);
            float f = T[idx].f + frac * (T[idx + 1].f - T[idx].f);
            float val = phi * f;
            if constexpr (Quadrupole) {
                float df = T[idx].df + frac * (T[idx + 1].df - T[idx].df);
                float d2f = T[idx].d2f + frac * (T[idx + 1].d2f - T[idx].d2f);
                float wd = wx * d0 + wy * d1 + wz * d2;
                float wqw = wx * (q0 * wx + q1 * wy + q2 * wz) +
                            wy * (q3 * wy + q4 * wz) + q5 * wz * wz;
                val += df * (tr - 2.0f * wd) + 2.0f * d2f * wqw;
            }
            acc[r] += keep * val;
        }
    }
}

// Adds point sources [first, first + count) to every receiver of the block,
// skipping each receiver's own point. Only called when no pair needs the
// disk quadrature.
inline void block_near(const Tables& tables, const TableEntry* const t[3],
                       const Tree& tree, uint32_t first, uint32_t count, BucketBlock& b) {
    const int32_t bits0 = int32_t(tables.bits0), last = int32_t(tables.count) - 1;
    const int32_t n = int32_t(b.count);
    for (uint32_t j = first; j < first + count; ++j) {
        const glm::vec4 p = tree.pos_rho2[j];
        const glm::vec4 pa = tree.power_area[j];
        const TableEntry* T0 = t[0];
        const TableEntry* T1 = t[1];
        const TableEntry* T2 = t[2];
        float* a0 = b.acc[0];
        float* a1 = b.acc[1];
        float* a2 = b.acc[2];
        const float px = p.x, py = p.y, pz = p.z, e0 = pa.x, e1 = pa.y, e2 = pa.z;
        const int32_t self = int32_t(j);
#pragma GCC ivdep
        for (int32_t r = 0; r < n; ++r) {
            float wx = b.x[r] - px, wy = b.y[r] - py, wz = b.z[r] - pz;
            float q = wx * wx + wy * wy + wz * wz;
            int32_t off = std::max(std::bit_cast<int32_t>(q) - bits0, 0);
            int32_t idx = std::min(off >> kShift, last);
            float frac = float(off & ((1 << kShift) - 1)) * kFracScale;
            float keep = (idx < last && b.sorted[r] != self) ? 1.0f : 0.0f;
            idx = std::min(idx, last - 1);
            float f0 = T0[idx].f + frac * (T0[idx + 1].f - T0[idx].f);
            float f1 = T1[idx].f + frac * (T1[idx + 1].f - T1[idx].f);
            float f2 = T2[idx].f + frac * (T2[idx + 1].f - T2[idx].f);
            a0[r] += keep * f0 * e0;
            a1[r] += keep * f1 * e1;
            a2[r] += keep * f2 * e2;
        }
    }
}

} // namespace sss::diffusion_detail
