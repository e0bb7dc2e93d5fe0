// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file evaluation.cpp
/// Evaluates receiver buckets: the bucket's traversal (once per bucket for the
/// error criterion, once per receiver for the classic ones), then the
/// vectorised block loops or the receiver-by-receiver loops, in parallel over
/// buckets.

#include "evaluation.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <deque>
#include <memory>
#include <stdexcept>

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>

#include "sss/util/progress.h"

#include "block.h"
#include "kernels.h"
#include "traversal.h"

namespace sss::diffusion_detail {

namespace {

// A bucket's local expansion per channel about its box centre: the sum of
// its local list's node expansions re-expanded to second order, evaluated as
// l0 + l1 . d + d^T L2 d at d = x - centre.
struct LocalExpansion {
    glm::dvec3 centre{0.0};
    double l0[3] = {0, 0, 0};
    double l1[3][3] = {};
    double l2[3][6] = {}; // xx xy xz yy yz zz
};

// Re-expands each node of `nodes` about the centre and adds it: with
// w = centre - c, G(w) = F(|w|^2), grad G = 2 F' w, H = 4 F'' w w^T + 2 F' I,
// the node's sum phi G(w + d - delta) over its points (moments phi, D, Q) is
// to second order: phi G - grad G . D + tr(H Q) / 2 + (phi grad G - H D) . d
// + d^T (phi H / 2) d. The block kernels' local() sums the nodes (vectorised
// over nodes, the same bits on every instruction-set path).
void add_local(const EvaluationContext& cx, const BlockTables& t,
               const std::vector<uint32_t>& nodes, LocalExpansion& le) {
    if (nodes.empty()) return;
    double sums[3][10];
    const double centre[3] = {le.centre.x, le.centre.y, le.centre.z};
    cx.kernels.local(t, cx.tree.expansions.data(), nodes.data(), nodes.size(), centre,
                     sums);
    for (int ch = 0; ch < 3; ++ch) {
        le.l0[ch] += sums[ch][0];
        for (int a = 0; a < 3; ++a) le.l1[ch][a] += sums[ch][1 + a];
        for (int a = 0; a < 6; ++a) le.l2[ch][a] += sums[ch][4 + a];
    }
}

// `from` moved to a new centre: the same quadratic, exactly.
void translate(const LocalExpansion& from, const glm::dvec3& centre, LocalExpansion& to) {
    const glm::dvec3 s = centre - from.centre;
    to.centre = centre;
    for (int ch = 0; ch < 3; ++ch) {
        const double* L2 = from.l2[ch];
        const glm::dvec3 l1(from.l1[ch][0], from.l1[ch][1], from.l1[ch][2]);
        const glm::dvec3 l2s(L2[0] * s.x + L2[1] * s.y + L2[2] * s.z,
                             L2[1] * s.x + L2[3] * s.y + L2[4] * s.z,
                             L2[2] * s.x + L2[4] * s.y + L2[5] * s.z);
        to.l0[ch] = from.l0[ch] + glm::dot(l1, s) + glm::dot(s, l2s);
        for (int a = 0; a < 3; ++a) to.l1[ch][a] = l1[a] + 2.0 * l2s[a];
        std::copy(L2, L2 + 6, to.l2[ch]);
    }
}

double local_value(const LocalExpansion& le, int ch, const glm::dvec3& d) {
    const double* L2 = le.l2[ch];
    const double* L1 = le.l1[ch];
    return le.l0[ch] + L1[0] * d.x + L1[1] * d.y + L1[2] * d.z +
           d.x * (L2[0] * d.x + 2.0 * (L2[1] * d.y + L2[2] * d.z)) +
           d.y * (L2[3] * d.y + 2.0 * L2[4] * d.z) + L2[5] * d.z * d.z;
}

// The sum over the last big leaf of identical points, for one material.
struct CoincidentSum {
    uint32_t node = kNone;
    const ChannelTable* table[3] = {nullptr, nullptr, nullptr};
    double sum[3] = {0, 0, 0};
};

// Per-point materials through the block loops (each receiver reads its own
// profiles' rows).
bool per_point_rows(const EvaluationContext& cx) {
    return cx.tree.per_point() && !cx.tables.profile_rows.empty();
}

// The channels of the receiver at sorted position s.
ReceiverChannels receiver_at(const EvaluationContext& cx, uint32_t s) {
    return receiver_channels(cx.pb, cx.tables,
                             cx.tree.per_point() ? cx.tree.profiles_of(s)
                                                 : glm::u32vec3(0, 1, 2));
}

// Per-point materials: the local expansions about `centre`, one per distinct
// table of each channel among a node's receivers (the expansion is linear in
// the profile, so each receiver takes its own table's). Neighbours mostly
// share a few tables.
struct MixedLocal {
    glm::dvec3 centre{0.0};
    std::vector<const ChannelTable*> tables[3];
    // Per table: l0, l1 (x y z), l2 (xx xy xz yy yz zz), as LocalExpansion.
    std::vector<std::array<double, 10>> coef[3];
};

uint32_t find_table(const std::vector<const ChannelTable*>& v, const ChannelTable* t) {
    return uint32_t(std::find(v.begin(), v.end(), t) - v.begin());
}

// translate() for one channel's coefficients, moved by s.
std::array<double, 10> translate_channel(const std::array<double, 10>& c,
                                         const glm::dvec3& s) {
    const double* L2 = c.data() + 4;
    const glm::dvec3 l1(c[1], c[2], c[3]);
    const glm::dvec3 l2s(L2[0] * s.x + L2[1] * s.y + L2[2] * s.z,
                         L2[1] * s.x + L2[3] * s.y + L2[4] * s.z,
                         L2[2] * s.x + L2[4] * s.y + L2[5] * s.z);
    std::array<double, 10> out = c;
    out[0] = c[0] + glm::dot(l1, s) + glm::dot(s, l2s);
    for (int a = 0; a < 3; ++a) out[1 + a] = l1[a] + 2.0 * l2s[a];
    return out;
}

// local_value() of one channel's coefficients.
double mixed_value(const std::array<double, 10>& c, const glm::dvec3& d) {
    const double* L2 = c.data() + 4;
    return c[0] + c[1] * d.x + c[2] * d.y + c[3] * d.z +
           d.x * (L2[0] * d.x + 2.0 * (L2[1] * d.y + L2[2] * d.z)) +
           d.y * (L2[3] * d.y + 2.0 * L2[4] * d.z) + L2[5] * d.z * d.z;
}

// The expansions of the receivers [first, first + count) (sorted) about
// `centre`: the parent's (null: none) moved there, plus `nodes` expanded with
// each distinct table. `index` (or null) gets each receiver's table per
// channel.
void mixed_level(const EvaluationContext& cx, const MixedLocal* parent,
                 const glm::dvec3& centre, uint32_t first, uint32_t count,
                 const std::vector<uint32_t>& nodes, MixedLocal& out,
                 uint32_t (*index)[kMaxBucket]) {
    out.centre = centre;
    thread_local KeyPositions seen[3];
    for (int ch = 0; ch < 3; ++ch) {
        out.tables[ch].clear();
        seen[ch].reset(cx.tables.channels.size());
    }
    for (uint32_t r = 0; r < count; ++r) {
        // (Neighbours mostly share their material.)
        if (r > 0 && cx.tree.material[first + r] == cx.tree.material[first + r - 1]) {
            if (index)
                for (int ch = 0; ch < 3; ++ch) index[ch][r] = index[ch][r - 1];
            continue;
        }
        const glm::u32vec3 k = cx.tree.profiles_of(first + r);
        for (int ch = 0; ch < 3; ++ch) {
            auto& v = out.tables[ch];
            uint32_t i = seen[ch].find(k[ch]);
            if (i == KeyPositions::kNone) {
                i = uint32_t(v.size());
                seen[ch].set(k[ch], i);
                v.push_back(&cx.tables.channels[k[ch]]);
            }
            if (index) index[ch][r] = i;
        }
    }
    std::size_t pairs = 0;
    for (int ch = 0; ch < 3; ++ch) {
        auto& coef = out.coef[ch];
        coef.assign(out.tables[ch].size(), std::array<double, 10>{});
        // (A node's receivers are among its parent's, so are their tables.)
        if (parent)
            for (std::size_t j = 0; j < coef.size(); ++j) {
                const uint32_t pi = find_table(parent->tables[ch], out.tables[ch][j]);
                if (pi >= parent->coef[ch].size())
                    throw std::logic_error("diffusion: a receiver's table is not its "
                                           "group's");
                coef[j] =
                    translate_channel(parent->coef[ch][pi], centre - parent->centre);
            }
        pairs += coef.size();
    }
    if (nodes.empty()) return;
    // Every (channel, table) pair at once: the nodes' moments are read once.
    thread_local std::vector<const TableEntry*> table;
    thread_local std::vector<int32_t> channel;
    thread_local std::vector<double> scratch, sums;
    table.clear();
    channel.clear();
    for (int ch = 0; ch < 3; ++ch)
        for (const ChannelTable* t : out.tables[ch]) {
            table.push_back(t->entries.data());
            channel.push_back(ch);
        }
    scratch.resize(pairs * 10 * kLocalLanes);
    sums.resize(pairs * 10);
    const LocalPairs lp{table.data(), channel.data(), int32_t(pairs),
                        int32_t(cx.tables.bits0), int32_t(cx.tables.count) - 1};
    const double c[3] = {centre.x, centre.y, centre.z};
    cx.kernels.local_pairs(lp, cx.tree.expansions.data(), nodes.data(), nodes.size(), c,
                           scratch.data(), sums.data());
    std::size_t p = 0;
    for (int ch = 0; ch < 3; ++ch)
        for (std::array<double, 10>& coef : out.coef[ch]) {
            for (int a = 0; a < 10; ++a)
                coef[std::size_t(a)] += sums[10 * p + std::size_t(a)];
            ++p;
        }
}

// One thread's scratch, reused from bucket to bucket, and its counters.
struct Scratch {
    NodeLists lists;
    std::unique_ptr<BucketBlock> block = std::make_unique<BucketBlock>();
    DiskMemo memo[3];
    SelfTerm self;
    CoincidentSum coincident;
    LocalExpansion local_expansion;
    DiffusionStats local;
    // A block of mixed materials: each receiver's channels, its bucket's
    // local expansions and which of them each receiver reads per channel.
    ReceiverChannels rcs[kMaxBucket];
    MixedLocal bucket_local;
    uint32_t le_index[3][kMaxBucket];
};

// The interleaved rows when the receivers read channels 0, 1 and 2.
const float* rows_of(const Tables& tables, const ReceiverChannels& rc) {
    if (tables.rows.empty()) return nullptr;
    for (int ch = 0; ch < 3; ++ch)
        if (rc.table[ch] != &tables.channels[std::size_t(ch)]) return nullptr;
    return tables.rows.data();
}

// Buckets with the error criterion: one traversal for the bucket, then the
// vectorised block loops over its receivers. Always the whole bucket, wanted
// or not: each receiver then keeps its place in the vector loops, so a subset
// gets the whole run's numbers bit for bit. One material: every receiver
// reads first_rc's tables, and `inherited` is the local expansion of the
// bucket's receiver group (or null). `mixed` (per-point materials): each
// reads its own profiles' rows (Tables::profile_rows) and its own tables'
// local expansions, on top of `inherited_mixed` (the group's, or null).
void evaluate_block(const EvaluationContext& cx, const Node& bucket,
                    const ReceiverChannels& first_rc, bool mixed, Scratch& w,
                    std::vector<glm::vec3>& result, const LocalExpansion* inherited,
                    const MixedLocal* inherited_mixed = nullptr) {
    const Tree& tree = cx.tree;
    const Tables& tables = cx.tables;
    const DiffusionProblem& pb = cx.pb;
    BucketBlock& block = *w.block;
    DiffusionStats& local = w.local;
    block.count = bucket.count;
    // The receivers' smallest core: the near loops' quadrature test.
    float core2 = first_rc.near_core2;
    for (uint32_t r = 0; r < bucket.count; ++r) {
        const glm::vec4& pr = tree.pos_rho2[bucket.first + r];
        block.x[r] = pr.x;
        block.y[r] = pr.y;
        block.z[r] = pr.z;
        block.sorted[r] = int32_t(bucket.first + r);
        for (int ch = 0; ch < 3; ++ch) block.acc[ch][r] = 0.0f;
        // The self term reads the receiver's irradiance and the result goes to
        // its slot, both at its original index: one cache miss per receiver
        // (6 % of the run at 1M points) unless fetched now, while the kernels
        // below work.
        const uint32_t s = bucket.first + r;
        if (cx.wants(s)) {
            const uint32_t original = tree.order[s];
            __builtin_prefetch(&pb.irradiance[original], 0, 1);
            __builtin_prefetch(&result[cx.slot(s, original)], 1, 1);
        }
        if (mixed) {
            const ReceiverChannels& rc = w.rcs[r] =
                r > 0 && tree.material[s] == tree.material[s - 1] ? w.rcs[r - 1]
                                                                  : receiver_at(cx, s);
            core2 = std::min(core2, rc.near_core2);
            block.core2[r] = rc.near_core2;
            for (int ch = 0; ch < 3; ++ch)
                block.base[ch][r] =
                    int32_t(std::size_t(rc.table[ch] - tables.channels.data()) *
                            tables.count * kProfileRowFloats);
            if (cx.material_rows)
                block.mbase[r] = int32_t(std::size_t(tree.material[s]) * tables.count *
                                         kProfileRowFloats);
        }
    }
    if (mixed)
        for (uint32_t r = bucket.count; r < ((bucket.count + 7) & ~7u); ++r) {
            for (int ch = 0; ch < 3; ++ch) block.base[ch][r] = 0;
            block.mbase[r] = 0;
        }
    const BlockTables t{{first_rc.table[0]->entries.data(),
                         first_rc.table[1]->entries.data(),
                         first_rc.table[2]->entries.data()},
                        int32_t(tables.bits0),
                        int32_t(tables.count) - 1,
                        mixed ? nullptr : rows_of(tables, first_rc),
                        mixed ? tables.profile_rows.data() : nullptr,
                        mixed ? cx.material_rows : nullptr};
    const auto rc_of = [&](uint32_t r) -> const ReceiverChannels& {
        return mixed ? w.rcs[r] : first_rc;
    };
    const BlockKernels& kernels = cx.kernels;
    const float* pos_rho2 = &tree.pos_rho2.data()->x;
    const float* power_area = &tree.power_area.data()->x;
    kernels.far(t, tree.expansions.data(), w.lists.far.data(), w.lists.far.size(), block);
    kernels.mono(t, tree.expansions.data(), w.lists.mono.data(), w.lists.mono.size(),
                 block);
    std::size_t plain = 0;
    for (uint32_t k : w.lists.near) {
        const Node& leaf = tree.nodes[k];
        float d2 = box_distance2(bucket.lo, bucket.hi, leaf.lo, leaf.hi);
        plain += leaf.count;
        if (leaf.max_rho * leaf.max_rho <= kNearKappa2 * (d2 + core2)) {
            kernels.near(t, pos_rho2, power_area, leaf.first, leaf.count, block, -1.0f);
            continue;
        }
        // Close, large source disks: the pairs that need the disk quadrature
        // one by one, the others (usually nearly all) in the kernel. (The
        // whole leaf went pair by pair before: coarse clouds spent most of
        // their time there.) The sampled profiles' kernel takes the moderately
        // close disks as their second-order means and only the larger ones are
        // left.
        const bool coreless = first_rc.disk_means;
        if (coreless)
            kernels.near_disks(t, pos_rho2, power_area, &tree.normal.data()->x,
                               leaf.first, leaf.count, block);
        else
            kernels.near(t, pos_rho2, power_area, leaf.first, leaf.count, block, core2);
        // (Receiver r's own core with per-point materials, as the kernel.)
        const auto left = [&](float rho2, float q, uint32_t r) {
            return coreless ? rho2 > kTaylorDisk2 * q
                            : needs_quadrature(rho2, q, mixed ? block.core2[r] : core2);
        };
        float max_rho2 = 0.0f; // (exact: max_rho is its rounded square root)
        for (uint32_t j = leaf.first; j < leaf.first + leaf.count; ++j)
            max_rho2 = std::max(max_rho2, tree.pos_rho2[j].w);
        for (uint32_t r = 0; r < bucket.count; ++r) {
            const uint32_t s = bucket.first + r;
            const glm::vec3 x(block.x[r], block.y[r], block.z[r]);
            // No pair of this receiver needs it when the leaf's largest disk
            // does not at the leaf box's distance (q >= that distance).
            if (!left(max_rho2, box_distance2(x, x, leaf.lo, leaf.hi), r)) continue;
            double acc[3] = {0, 0, 0};
            bool any = false;
            for (uint32_t j = leaf.first; j < leaf.first + leaf.count; ++j) {
                const glm::vec3 wv = x - glm::vec3(tree.pos_rho2[j]);
                const float q = glm::dot(wv, wv);
                if (j != s && left(tree.pos_rho2[j].w, q, r)) {
                    quadrature_source(tree, tables, rc_of(r), wv, q, j, acc, local,
                                      w.memo);
                    any = true;
                }
            }
            if (any)
                for (int ch = 0; ch < 3; ++ch) block.acc[ch][r] += float(acc[ch]);
        }
    }
    local.near_terms += plain * bucket.count;
    local.far_terms += (w.lists.far.size() + w.lists.mono.size()) * bucket.count;
    local.local_terms += w.lists.local.size();
    LocalExpansion& le = w.local_expansion;
    const glm::dvec3 centre = 0.5 * (glm::dvec3(bucket.lo) + glm::dvec3(bucket.hi));
    if (inherited)
        translate(*inherited, centre, le);
    else
        le = LocalExpansion{centre};
    if (mixed)
        mixed_level(cx, inherited_mixed, centre, bucket.first, bucket.count,
                    w.lists.local, w.bucket_local, w.le_index);
    else
        add_local(cx, t, w.lists.local, le);
    for (uint32_t r = 0; r < bucket.count; ++r) {
        uint32_t s = bucket.first + r;
        if (!cx.wants(s)) continue;
        uint32_t original = tree.order[s];
        double rho = std::sqrt(double(tree.pos_rho2[s].w));
        // Self term: the receiver's own disk, integrated exactly.
        double self[3];
        w.self(rc_of(r), rho, pb.irradiance[original], self);
        glm::vec3& out = result[cx.slot(s, original)];
        const glm::dvec3 d = glm::dvec3(block.x[r], block.y[r], block.z[r]) - centre;
        for (int ch = 0; ch < 3; ++ch) {
            const double l =
                mixed ? mixed_value(w.bucket_local.coef[ch][w.le_index[ch][r]], d)
                      : local_value(le, ch, d);
            double v = double(block.acc[ch][r]) + l + self[ch];
            if (!tree.receiver_gain.empty()) v *= double(tree.receiver_gain[s][ch]);
            out[ch] = std::isfinite(v) ? float(v) : 0.0f;
        }
    }
}

// Identical points (one big leaf k, receiver s at x among them): the leaf's sum
// is the same for every receiver there, so it is formed once per material and
// each receiver subtracts its own term (O(n), not O(n^2)).
void add_coincident_leaf(const EvaluationContext& cx, uint32_t k,
                         const ReceiverChannels& rc, const glm::vec3& x, uint32_t s,
                         double acc[3], Scratch& w) {
    const Tree& tree = cx.tree;
    const Node& leaf = tree.nodes[k];
    CoincidentSum& coincident = w.coincident;
    if (coincident.node != k || !std::equal(rc.table, rc.table + 3, coincident.table)) {
        coincident.node = k;
        std::copy(rc.table, rc.table + 3, coincident.table);
        std::fill(coincident.sum, coincident.sum + 3, 0.0);
        for (uint32_t j = leaf.first; j < leaf.first + leaf.count; ++j)
            near_source(tree, cx.tables, rc, x, j, coincident.sum, w.local, w.memo);
    }
    double own[3] = {0, 0, 0};
    if (s >= leaf.first && s < leaf.first + leaf.count)
        near_source(tree, cx.tables, rc, x, s, own, w.local, w.memo);
    for (int ch = 0; ch < 3; ++ch) acc[ch] += coincident.sum[ch] - own[ch];
}

// The node lists for a receiver at x: the classic criteria walk the octree
// per receiver, as PRMan does; the error criterion's bucket lists serve every
// receiver of the bucket.
void walk_receiver(const EvaluationContext& cx, const glm::vec3& x, NodeLists& lists) {
    const double eps = cx.options.max_solid_angle;
    switch (cx.options.criterion) {
    case Criterion::Error:
        break;
    case Criterion::SolidAngleBox:
        traverse_solid_angle_box(cx.tree, eps, x, x, lists);
        break;
    case Criterion::SolidAngleCentroid:
        traverse_solid_angle_centroid(cx.tree, eps, x, lists);
        break;
    }
}

// Mixed materials and the classic criteria: receiver by receiver.
void evaluate_each(const EvaluationContext& cx, const Node& bucket,
                   const ReceiverChannels& first_rc, Scratch& w,
                   std::vector<glm::vec3>& result) {
    const Tree& tree = cx.tree;
    const Tables& tables = cx.tables;
    const DiffusionProblem& pb = cx.pb;
    const NodeLists& lists = w.lists;
    // The far list's nodes are expanded to second order with the error
    // criterion only. Keep this a run-time value, as it always was: where the
    // compiler knows it is true, it fuses phi * F into the quadrupole sum
    // (FMA) in far_node, and mixed-material results change in the last bits.
    const bool quadrupole = cx.options.criterion == Criterion::Error;
    for (uint32_t s = bucket.first; s < bucket.first + bucket.count; ++s) {
        if (!cx.wants(s)) continue;
        uint32_t original = tree.order[s];
        ReceiverChannels rc = tree.per_point() ? receiver_at(cx, s) : first_rc;
        glm::vec3 x(tree.pos_rho2[s]);
        walk_receiver(cx, x, w.lists);
        double acc[3];
        double rho = std::sqrt(double(tree.pos_rho2[s].w));
        w.self(rc, rho, pb.irradiance[original], acc);
        for (uint32_t k : lists.far)
            far_node(tables, rc, tree.expansions[k], x, quadrupole, acc);
        for (uint32_t k : lists.mono)
            far_node(tables, rc, tree.expansions[k], x, false, acc);
        for (uint32_t k : lists.near) {
            const Node& leaf = tree.nodes[k];
            if (leaf.count > kLeafSize && leaf.lo == leaf.hi && x == leaf.lo) {
                add_coincident_leaf(cx, k, rc, x, s, acc, w);
                continue;
            }
            for (uint32_t j = leaf.first; j < leaf.first + leaf.count; ++j)
                if (j != s) near_source(tree, tables, rc, x, j, acc, w.local, w.memo);
        }
        w.local.far_terms += lists.far.size() + lists.mono.size();
        glm::vec3& out = result[cx.slot(s, original)];
        for (int ch = 0; ch < 3; ++ch) {
            double v = acc[ch];
            if (!tree.receiver_gain.empty()) v *= double(tree.receiver_gain[s][ch]);
            out[ch] = std::isfinite(v) ? float(v) : 0.0f;
        }
    }
}

// One bucket: with the error criterion, one traversal for the bucket (from
// the nodes its receiver group left to it, with the group's local expansion),
// then the vectorised block loops when its receivers share one material;
// otherwise receiver by receiver, from the root.
void evaluate_bucket(const EvaluationContext& cx, uint32_t bucket_node, Scratch& w,
                     std::vector<glm::vec3>& result,
                     const std::vector<uint32_t>* start = nullptr,
                     const LocalExpansion* inherited = nullptr,
                     const MixedLocal* inherited_mixed = nullptr) {
    const Tree& tree = cx.tree;
    const Node& bucket = tree.nodes[bucket_node];
    ReceiverChannels first_rc = receiver_at(cx, bucket.first);
    if (cx.options.criterion == Criterion::Error) {
        BucketTolerance tol =
            bucket_tolerance(cx.tolerance, cx.pb, cx.tables, tree, bucket_node, first_rc);
        if (bucket.count <= kMaxBucket && per_point_rows(cx)) {
            // Per-point materials: the walk's lists hold for every receiver's
            // (it takes the worst), and each receiver reads its own profiles.
            traverse_error(tree, cx.tables, tol, bucket.lo, bucket.hi, true, w.lists,
                           start);
            evaluate_block(cx, bucket, first_rc, true, w, result, nullptr,
                           inherited_mixed);
            return;
        }
        if (bucket.count <= kMaxBucket && tol.one_material) {
            traverse_error(tree, cx.tables, tol, bucket.lo, bucket.hi, true, w.lists,
                           start);
            evaluate_block(cx, bucket, first_rc, false, w, result, inherited);
            return;
        }
        // Every node from the root: what the group shared is not used here.
        traverse_error(tree, cx.tables, tol, bucket.lo, bucket.hi, false, w.lists);
    }
    evaluate_each(cx, bucket, first_rc, w, result);
}

// How many of the bucket's receivers are wanted.
std::size_t wanted_in(const EvaluationContext& cx, const Node& bucket) {
    if (cx.ranged()) {
        const uint32_t lo = std::max(bucket.first, cx.range_first);
        const uint32_t hi = std::min(bucket.first + bucket.count, cx.range_end);
        return hi > lo ? hi - lo : 0;
    }
    if (!cx.wanted) return bucket.count;
    return std::size_t(std::count_if(cx.wanted + bucket.first,
                                     cx.wanted + bucket.first + bucket.count,
                                     [](uint8_t w) { return w != 0; }));
}

// Receiver groups: nodes above the buckets whose tolerance is the one of every
// bucket below (one material, narrower than the tolerance's region, see
// reference_node() in tolerance.cpp), at most kMaxGroup points.
constexpr uint32_t kMaxGroup = 4096;

bool groups_allowed(const EvaluationContext& cx) {
    return cx.options.criterion == Criterion::Error &&
           (!cx.tree.per_point() || per_point_rows(cx));
}

bool is_group(const EvaluationContext& cx, const Node& node) {
    return node.count <= kMaxGroup &&
           double(glm::length(node.hi - node.lo)) < 2.0 * cx.tolerance.region;
}

// The group evaluation's scratch per depth below the group's root.
struct GroupLevel {
    std::vector<uint32_t> start;
    LocalExpansion le;
    MixedLocal mixed; // per-point materials
};

// Node k of a receiver group, holding the (sorted, wanted) buckets
// [b0, b1): the nodes its local expansion can take go into it (on top of
// the parent's, moved to k's centre); the rest is left to the children, down
// to the buckets. `done(bucket)` counts progress.
template <class Done>
void evaluate_group(const EvaluationContext& cx, uint32_t k, std::size_t depth,
                    const std::vector<uint32_t>& start, const LocalExpansion& parent,
                    const MixedLocal* parent_mixed, const uint32_t* b0,
                    const uint32_t* b1, Scratch& w, std::deque<GroupLevel>& levels,
                    std::vector<glm::vec3>& result, Done&& done) {
    const Tree& tree = cx.tree;
    const Node& node = tree.nodes[k];
    if (b1 - b0 == 1 && *b0 == k) {
        evaluate_bucket(cx, k, w, result, &start, &parent, parent_mixed);
        done(k);
        return;
    }
    if (levels.size() <= depth) levels.resize(depth + 1);
    GroupLevel& lv = levels[depth];
    ReceiverChannels rc = receiver_at(cx, node.first);
    BucketTolerance tol = bucket_tolerance(cx.tolerance, cx.pb, cx.tables, tree, k, rc);
    traverse_group(tree, cx.tables, tol, node.lo, node.hi, start, w.lists);
    lv.start.swap(w.lists.near);
    const glm::dvec3 centre = 0.5 * (glm::dvec3(node.lo) + glm::dvec3(node.hi));
    const bool mixed = per_point_rows(cx);
    if (mixed) {
        mixed_level(cx, parent_mixed, centre, node.first, node.count, w.lists.local,
                    lv.mixed, nullptr);
    } else {
        translate(parent, centre, lv.le);
        const BlockTables t{{rc.table[0]->entries.data(), rc.table[1]->entries.data(),
                             rc.table[2]->entries.data()},
                            int32_t(cx.tables.bits0),
                            int32_t(cx.tables.count) - 1,
                            rows_of(cx.tables, rc)};
        add_local(cx, t, w.lists.local, lv.le);
    }
    w.local.local_terms += w.lists.local.size();
    for (uint32_t c = node.child_first; c < node.child_first + node.child_count; ++c) {
        const Node& child = tree.nodes[c];
        auto in_child = [&](uint32_t b) { return tree.nodes[b].first < child.first; };
        const uint32_t* c0 = std::partition_point(b0, b1, in_child);
        const uint32_t* c1 = std::partition_point(c0, b1, [&](uint32_t b) {
            return tree.nodes[b].first < child.first + child.count;
        });
        if (c1 > c0)
            evaluate_group(cx, c, depth + 1, levels[depth].start, levels[depth].le,
                           mixed ? &levels[depth].mixed : nullptr, c0, c1, w, levels,
                           result, done);
    }
}

} // namespace

std::vector<uint32_t> choose_buckets(const Tree& tree) {
    std::vector<uint32_t> buckets; // node index
    std::vector<uint32_t> stack{0};
    while (!stack.empty()) {
        uint32_t k = stack.back();
        stack.pop_back();
        const Node& node = tree.nodes[k];
        if (node.count <= kMaxBucket || node.child_count == 0) {
            buckets.push_back(k);
            continue;
        }
        for (uint32_t c = node.child_count; c-- > 0;)
            stack.push_back(node.child_first + c);
    }
    return buckets;
}

const BlockKernels& block_kernels(Isa isa) {
    switch (resolve_isa(isa)) {
    case Isa::Avx512:
        return isa_avx512::kernels;
    case Isa::Avx2:
        return isa_avx2::kernels;
    default:
        return isa_x86_64::kernels;
    }
}

void evaluate_buckets(const EvaluationContext& cx, const std::vector<uint32_t>& buckets,
                      std::vector<glm::vec3>& result, DiffusionStats& stats) {
    const std::size_t n = cx.ranged() ? std::size_t(cx.range_end - cx.range_first)
                          : cx.wanted
                              ? cx.wanted_count
                              : cx.tree.order.size(); // (pb's positions may be freed)
    const Tree& tree = cx.tree;
    // Each bucket's receiver group: its highest ancestor that is a group
    // (itself when there is none). The buckets are in depth-first order, so a
    // group's buckets are contiguous: groups[g] = {root, first bucket}.
    std::vector<std::pair<uint32_t, std::size_t>> groups;
    for (std::size_t bi = 0; bi < buckets.size(); ++bi) {
        uint32_t root = buckets[bi];
        if (groups_allowed(cx))
            while (tree.nodes[root].parent != kNone &&
                   is_group(cx, tree.nodes[tree.nodes[root].parent]))
                root = tree.nodes[root].parent;
        if (groups.empty() || groups.back().first != root) groups.push_back({root, bi});
    }
    const std::vector<uint32_t> from_root{0};
    const LocalExpansion none;
    std::atomic<std::size_t> done{0};
    if (cx.options.progress) cx.options.progress->set_unit("points");
    std::atomic<std::size_t> far_total{0}, near_total{0}, quad_total{0}, local_total{0};
    oneapi::tbb::parallel_for(
        oneapi::tbb::blocked_range<std::size_t>(0, groups.size(), 1),
        [&](const oneapi::tbb::blocked_range<std::size_t>& range) {
            Scratch w;
            std::deque<GroupLevel> levels; // a deque: growing keeps references
            auto count_done = [&](uint32_t bucket) {
                const std::size_t count = wanted_in(cx, tree.nodes[bucket]);
                std::size_t now = done.fetch_add(count) + count;
                if (cx.options.progress) cx.options.progress->update(now, n);
            };
            for (std::size_t g = range.begin(); g != range.end(); ++g) {
                const std::size_t end =
                    g + 1 < groups.size() ? groups[g + 1].second : buckets.size();
                evaluate_group(cx, groups[g].first, 0, from_root, none, nullptr,
                               buckets.data() + groups[g].second, buckets.data() + end, w,
                               levels, result, count_done);
            }
            far_total += w.local.far_terms;
            near_total += w.local.near_terms;
            quad_total += w.local.quadrature_terms;
            local_total += w.local.local_terms;
        });
    stats.far_terms = far_total;
    stats.near_terms = near_total;
    stats.quadrature_terms = quad_total;
    stats.local_terms = local_total;
    stats.isa = cx.kernels.isa;
}

} // namespace sss::diffusion_detail
