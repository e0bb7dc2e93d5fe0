// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file kernels.h
/// The receiver-by-receiver path's inner loops: one receiver against a near
/// source (point or disk quadrature) or a far node's expansion (the block
/// kernels, one node against a whole bucket, are in block.h). Inline: they run
/// in the hot loops of evaluation.cpp.

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

// The receivers' self terms: irradiance times the disk integral of their own
// radius, per channel. The last radius's integrals are kept (points of equal
// area, as diced grids and synthetic clouds have, share them: three closed
// forms with exponentials each otherwise), and an unlit receiver needs none.
struct SelfTerm {
    const Profile* profile[3] = {nullptr, nullptr, nullptr};
    double rho = -1.0, disk[3] = {0, 0, 0};

    // out[ch] = irradiance[ch] * profile[ch]->disk(rho).
    void operator()(const ReceiverChannels& rc, double rho_, const glm::vec3& irradiance,
                    double out[3]) {
        if (irradiance == glm::vec3(0.0f)) {
            // 0 times a finite integral.
            for (int ch = 0; ch < 3; ++ch) out[ch] = double(irradiance[ch]) * 0.0;
            return;
        }
        if (rho_ != rho || !std::equal(rc.profile, rc.profile + 3, profile)) {
            rho = rho_;
            for (int ch = 0; ch < 3; ++ch) {
                profile[ch] = rc.profile[ch];
                disk[ch] = rc.profile[ch]->disk(rho_);
            }
        }
        for (int ch = 0; ch < 3; ++ch) out[ch] = double(irradiance[ch]) * disk[ch];
    }
};

// Whether source disk of radius^2 rho2 at squared distance q from a receiver
// is integrated by the disk quadrature rather than taken as a point (the
// block kernels repeat this test, operation for operation).
inline bool needs_quadrature(float rho2, float q, float near_core2) {
    return rho2 > kNearKappa2 * (q + near_core2);
}

// The mean of F over a source disk of radius^2 rho2 with unit normal n (zero:
// facing the receiver) at offset w (q = |w|^2), to second order, times the
// source's power.
inline void disk_taylor(const Tables& tables, const ReceiverChannels& rc,
                        const glm::vec3& n, const glm::vec3& w, float q, float rho2,
                        const glm::vec4& pa, double acc[3]) {
    Tables::Lookup l = tables.locate(q);
    if (!l.valid) return;
    const float n2 = glm::dot(n, n);
    const float wn = n2 > 0.0f ? glm::dot(w, n) : 0.0f;
    const float wt2 = n2 > 0.0f ? std::max(0.0f, q - wn * wn / n2) : 0.0f;
    for (int ch = 0; ch < 3; ++ch) {
        const TableEntry* e = rc.table[ch]->entries.data() + l.index;
        const float f = e[0].f + l.frac * (e[1].f - e[0].f);
        const float df = e[0].df + l.frac * (e[1].df - e[0].df);
        const float d2f = e[0].d2f + l.frac * (e[1].d2f - e[0].d2f);
        acc[ch] += double((f + 0.5f * rho2 * (df + wt2 * d2f)) * pa[ch]);
    }
}

// The disk quadrature of sorted source s for a receiver at offset w = x - p_s
// (q = |w|^2), for a pair that needs_quadrature().
inline void quadrature_source(const Tree& tree, const Tables& tables,
                              const ReceiverChannels& rc, const glm::vec3& w, float q,
                              uint32_t s, double acc[3], DiffusionStats& st,
                              DiskMemo memo[3]) {
    const glm::vec4& pa = tree.power_area[s];
    ++st.quadrature_terms;
    double rho = std::sqrt(double(tree.pos_rho2[s].w));
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
    if (rc.disk_means && tree.pos_rho2[s].w <= kTaylorDisk2 * q) {
        // The sampled profiles (1/r at the source) take a moderately close
        // disk as its mean to second order (kTaylorDisk2).
        disk_taylor(tables, rc, tree.normal[s], w, q, tree.pos_rho2[s].w, pa, acc);
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
}

// Contribution of sorted source s to receiver at x (never the receiver itself).
inline void near_source(const Tree& tree, const Tables& tables,
                        const ReceiverChannels& rc, const glm::vec3& x, uint32_t s,
                        double acc[3], DiffusionStats& st, DiskMemo memo[3]) {
    const glm::vec4& pr = tree.pos_rho2[s];
    const glm::vec4& pa = tree.power_area[s];
    glm::vec3 w = x - glm::vec3(pr);
    float q = glm::dot(w, w);
    if (needs_quadrature(pr.w, q, rc.near_core2)) {
        quadrature_source(tree, tables, rc, w, q, s, acc, st, memo);
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

} // namespace sss::diffusion_detail
