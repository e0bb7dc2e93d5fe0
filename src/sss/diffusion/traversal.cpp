// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file traversal.cpp
/// The octree walk, and the per-node test of each criterion that steers it.

#include "traversal.h"

#include <algorithm>
#include <cmath>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vector_relational.hpp>

namespace sss::diffusion_detail {

namespace {

// What a criterion makes of one node.
enum class Verdict {
    Far,   // use the node's expansion
    Mono,  // use its monopole only
    Local, // use its expansion re-expanded about the receivers' centre
    Defer, // (receiver groups) leave it to the group's children
    Drop,  // negligible
    Open   // too close: a leaf goes to the near list, a node to its children
};

// Depth-first walk from the start nodes (null: the root); judge(node,
// expansion) -> Verdict. Deferred nodes are kept in lists.near.
template <class Judge>
void walk(const Tree& tree, NodeLists& lists, Judge&& judge,
          const std::vector<uint32_t>* start = nullptr) {
    lists.far.clear();
    lists.mono.clear();
    lists.local.clear();
    lists.near.clear();
    std::vector<uint32_t>& stack = lists.stack;
    stack.clear();
    if (start)
        stack.assign(start->rbegin(), start->rend());
    else
        stack.push_back(0);
    while (!stack.empty()) {
        uint32_t k = stack.back();
        stack.pop_back();
        const Node& node = tree.nodes[k];
        switch (judge(node, tree.expansions[k])) {
        case Verdict::Far:
            lists.far.push_back(k);
            break;
        case Verdict::Mono:
            lists.mono.push_back(k);
            break;
        case Verdict::Local:
            lists.local.push_back(k);
            break;
        case Verdict::Drop:
            break;
        case Verdict::Defer:
            lists.near.push_back(k);
            break;
        case Verdict::Open:
            if (node.child_count == 0) {
                lists.near.push_back(k);
            } else {
                for (uint32_t c = node.child_count; c-- > 0;)
                    stack.push_back(node.child_first + c);
            }
            break;
        }
    }
}

// A node whose sources all have zero power in every channel (the unlit side
// of an object): whatever the receiver, it adds exactly 0, so dropping it
// (with everything below it) changes no bit of the result.
inline bool dark(const Expansion& ex) {
    return ex.abs_phi[0] == 0.0f && ex.abs_phi[1] == 0.0f && ex.abs_phi[2] == 0.0f;
}

} // namespace

void traverse_error(const Tree& tree, const Tables& tables, const BucketTolerance& tol,
                    const glm::vec3& blo, const glm::vec3& bhi, bool local,
                    NodeLists& lists, const std::vector<uint32_t>* start) {
    // Radius of the receivers' box about its centre (where a local expansion
    // is made); 0 without local expansions, so the test below never passes.
    const float rb = local ? 0.5f * glm::length(bhi - blo) : -1.0f;
    // The tolerances' inverses: the judge below runs for every node visited,
    // and a division there was a tenth of the walk's time.
    const double inv_tol[3] = {1.0 / tol.tol[0], 1.0 / tol.tol[1], 1.0 / tol.tol[2]};
    walk(
        tree, lists,
        [&](const Node& node, const Expansion& ex) {
            if (dark(ex)) return Verdict::Drop;
            float d2 = box_distance2(blo, bhi, node.lo, node.hi);
            float r = node.radius;
            // Single points are exact as near terms; the expansion
            // needs the receivers outside the node: 1.2 radii, where the
            // error bound below decides (1.5 before issue 17 opened 3 % more
            // nodes for the same error; 1.1 saves nothing more).
            if (!(node.count > 1 && d2 > 1.44f * r * r)) return Verdict::Open;
            Tables::Lookup l = tables.locate(d2);
            // Beyond the tables every profile has lost all but 1e-7: nothing.
            if (!l.valid) return Verdict::Drop;
            const uint32_t i = l.index;
            // The largest third-order remainder per unit length cubed,
            // against the tolerance (over channels and receiver tables).
            float ratio = 0.0f;
            for (int ch = 0; ch < 3; ++ch)
                for (const ChannelTable* ct : tol.tables[ch])
                    ratio =
                        std::max(ratio, float(double(ex.abs_phi[ch]) *
                                              ct->bounds[i].error_bound * inv_tol[ch]));
            // The local expansion's remainder: third order in the displacement
            // from the node's centroid plus the one from the box centre.
            const float rl = r + rb;
            if (rb >= 0.0f && d2 > 1.44f * rl * rl && rl * rl * rl * ratio <= 1.0f)
                return Verdict::Local; // implies accept
            const bool accept = r * r * r * ratio <= 1.0f;
            bool negligible = true, mono = accept;
            // Farthest receiver from the centroid bounds |w|.
            const double wmax =
                glm::length(glm::max(glm::abs(blo - ex.c), glm::abs(bhi - ex.c)));
            for (int ch = 0; ch < 3; ++ch) {
                const double ap = ex.abs_phi[ch];
                // Error of dropping the dipole and quadrupole terms: the same
                // factors for every receiver table.
                const double m2 = ap * r * r;
                const float* dv = ex.d[ch];
                const double d_norm =
                    mono ? std::sqrt(double(dv[0]) * dv[0] + double(dv[1]) * dv[1] +
                                     double(dv[2]) * dv[2])
                         : 0.0;
                for (const ChannelTable* ct : tol.tables[ch]) {
                    const TableBounds& b = ct->bounds[i];
                    if (ap * b.max_value > tol.skip[ch]) negligible = false;
                    if (!mono) continue;
                    double mono_err = b.max_d1 * (m2 + 2.0 * wmax * d_norm) +
                                      2.0 * b.max_d2 * wmax * wmax * m2;
                    if (mono_err > 0.1 * tol.tol[ch]) mono = false;
                }
            }
            // A negligible node is still counted, as its monopole (one table
            // lookup): dropping it lost a term of the sign of the light every
            // time, which biased the result low (-0.43 % on average at 1M points,
            // most of the default's error; issue 17).
            if (negligible || (accept && mono)) return Verdict::Mono;
            return accept ? Verdict::Far : Verdict::Open;
        },
        start);
}

void traverse_group(const Tree& tree, const Tables& tables, const BucketTolerance& tol,
                    const glm::vec3& glo, const glm::vec3& ghi,
                    const std::vector<uint32_t>& start, NodeLists& lists) {
    const float rg = 0.5f * glm::length(ghi - glo);
    walk(
        tree, lists,
        [&](const Node& node, const Expansion& ex) {
            if (dark(ex)) return Verdict::Drop;
            float d2 = box_distance2(glo, ghi, node.lo, node.hi);
            float r = node.radius;
            const float rl = r + rg;
            if (node.count > 1 && d2 > 2.25f * rl * rl) {
                Tables::Lookup l = tables.locate(d2);
                if (!l.valid) return Verdict::Drop;
                bool shared = true;
                for (int ch = 0; ch < 3 && shared; ++ch)
                    for (const ChannelTable* ct : tol.tables[ch])
                        if (double(ex.abs_phi[ch]) * rl * rl * rl *
                                ct->bounds[l.index].error_bound >
                            tol.tol[ch])
                            shared = false;
                if (shared) return Verdict::Local;
            }
            // Open the larger of the two: a source node bigger than the group
            // may have children the group can share; a smaller one is left to
            // the group's children.
            if (node.child_count > 0 && r > rg) return Verdict::Open;
            return Verdict::Defer;
        },
        &start);
}

void traverse_solid_angle_box(const Tree& tree, double eps, const glm::vec3& blo,
                              const glm::vec3& bhi, NodeLists& lists) {
    walk(tree, lists, [&](const Node& node, const Expansion&) {
        glm::vec3 g(node.max_rho);
        float d2 = box_distance2(blo, bhi, node.lo - g, node.hi + g);
        bool accept = d2 > 0.0f && node.area <= eps * d2;
        return accept ? Verdict::Far : Verdict::Open;
    });
}

void traverse_solid_angle_centroid(const Tree& tree, double eps, const glm::vec3& x,
                                   NodeLists& lists) {
    walk(tree, lists, [&](const Node& node, const Expansion& ex) {
        bool inside = glm::all(glm::greaterThanEqual(x, node.lo)) &&
                      glm::all(glm::lessThanEqual(x, node.hi));
        glm::vec3 w = x - ex.c;
        bool accept = !inside && node.area < eps * glm::dot(w, w);
        return accept ? Verdict::Far : Verdict::Open;
    });
}

} // namespace sss::diffusion_detail
