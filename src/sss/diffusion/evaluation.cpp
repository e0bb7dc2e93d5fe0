/// \file evaluation.cpp
/// Evaluates receiver buckets: the bucket's traversal (once per bucket for the
/// error criterion, once per receiver for the classic ones), then the
/// vectorised block loops or the receiver-by-receiver loops, in parallel over
/// buckets.

#include "evaluation.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>

#include "sss/util/progress.h"

#include "kernels.h"
#include "traversal.h"

namespace sss::diffusion_detail {

namespace {

// The sum over the last big leaf of identical points, for one material.
struct CoincidentSum {
    uint32_t node = kNone;
    const ChannelTable* table[3] = {nullptr, nullptr, nullptr};
    double sum[3] = {0, 0, 0};
};

// One thread's scratch, reused from bucket to bucket, and its counters.
struct Scratch {
    NodeLists lists;
    std::unique_ptr<BucketBlock> block = std::make_unique<BucketBlock>();
    DiskMemo memo[3];
    CoincidentSum coincident;
    DiffusionStats local;
};

// Buckets of one material with the error criterion: one traversal for the
// bucket, then the vectorised block loops over its receivers. Always the whole
// bucket, wanted or not: each receiver then keeps its place in the vector
// loops, so a subset gets the whole run's numbers bit for bit.
void evaluate_block(const EvaluationContext& cx, const Node& bucket,
                    const ReceiverChannels& first_rc, Scratch& w,
                    std::vector<glm::vec3>& result) {
    const Tree& tree = cx.tree;
    const Tables& tables = cx.tables;
    const DiffusionProblem& pb = cx.pb;
    BucketBlock& block = *w.block;
    DiffusionStats& local = w.local;
    block.count = bucket.count;
    for (uint32_t r = 0; r < bucket.count; ++r) {
        const glm::vec4& pr = tree.pos_rho2[bucket.first + r];
        block.x[r] = pr.x;
        block.y[r] = pr.y;
        block.z[r] = pr.z;
        block.sorted[r] = int32_t(bucket.first + r);
        for (int ch = 0; ch < 3; ++ch) block.acc[ch][r] = 0.0f;
    }
    const TableEntry* t[3] = {first_rc.table[0]->entries.data(),
                              first_rc.table[1]->entries.data(),
                              first_rc.table[2]->entries.data()};
    for (uint32_t k : w.lists.far) block_far<true>(tables, t, tree.expansions[k], block);
    for (uint32_t k : w.lists.mono)
        block_far<false>(tables, t, tree.expansions[k], block);
    std::size_t plain = 0;
    for (uint32_t k : w.lists.near) {
        const Node& leaf = tree.nodes[k];
        float d2 = box_distance2(bucket.lo, bucket.hi, leaf.lo, leaf.hi);
        if (leaf.max_rho * leaf.max_rho <= kNearKappa2 * (d2 + first_rc.near_core2)) {
            block_near(tables, t, tree, leaf.first, leaf.count, block);
            plain += leaf.count;
            continue;
        }
        // Close, large source disks: per pair, with quadrature where
        // needed.
        for (uint32_t r = 0; r < bucket.count; ++r) {
            uint32_t s = bucket.first + r;
            glm::vec3 x(block.x[r], block.y[r], block.z[r]);
            double acc[3] = {0, 0, 0};
            for (uint32_t j = leaf.first; j < leaf.first + leaf.count; ++j)
                if (j != s) near_source(tree, tables, first_rc, x, j, acc, local, w.memo);
            for (int ch = 0; ch < 3; ++ch) block.acc[ch][r] += float(acc[ch]);
        }
    }
    local.near_terms += plain * bucket.count;
    local.far_terms += (w.lists.far.size() + w.lists.mono.size()) * bucket.count;
    for (uint32_t r = 0; r < bucket.count; ++r) {
        uint32_t s = bucket.first + r;
        if (!cx.wants(s)) continue;
        uint32_t original = tree.order[s];
        double rho = std::sqrt(double(tree.pos_rho2[s].w));
        glm::vec3& out = result[cx.slot(s, original)];
        for (int ch = 0; ch < 3; ++ch) {
            // Self term: the receiver's own disk, integrated exactly.
            double v = double(block.acc[ch][r]) + double(pb.irradiance[original][ch]) *
                                                      first_rc.profile[ch]->disk(rho);
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
        ReceiverChannels rc =
            pb.profile_index.empty() ? first_rc : receiver_channels(pb, tables, original);
        glm::vec3 x(tree.pos_rho2[s]);
        walk_receiver(cx, x, w.lists);
        double acc[3];
        double rho = std::sqrt(double(tree.pos_rho2[s].w));
        for (int ch = 0; ch < 3; ++ch)
            acc[ch] = double(pb.irradiance[original][ch]) * rc.profile[ch]->disk(rho);
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
            out[ch] = std::isfinite(v) ? float(v) : 0.0f;
        }
    }
}

// One bucket: with the error criterion, one traversal for the bucket, then the
// vectorised block loops when its receivers share one material; otherwise
// receiver by receiver.
void evaluate_bucket(const EvaluationContext& cx, uint32_t bucket_node, Scratch& w,
                     std::vector<glm::vec3>& result) {
    const Tree& tree = cx.tree;
    const Node& bucket = tree.nodes[bucket_node];
    ReceiverChannels first_rc =
        receiver_channels(cx.pb, cx.tables, tree.order[bucket.first]);
    if (cx.options.criterion == Criterion::Error) {
        BucketTolerance tol =
            bucket_tolerance(cx.tolerance, cx.pb, cx.tables, tree, bucket_node, first_rc);
        traverse_error(tree, cx.tables, tol, bucket.lo, bucket.hi, w.lists);
        bool uniform = bucket.count <= kMaxBucket && tol.tables[0].size() == 1 &&
                       tol.tables[1].size() == 1 && tol.tables[2].size() == 1;
        if (uniform) {
            evaluate_block(cx, bucket, first_rc, w, result);
            return;
        }
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

void evaluate_buckets(const EvaluationContext& cx, const std::vector<uint32_t>& buckets,
                      std::vector<glm::vec3>& result, DiffusionStats& stats) {
    const std::size_t n = cx.ranged() ? std::size_t(cx.range_end - cx.range_first)
                          : cx.wanted ? cx.wanted_count
                                      : cx.pb.positions.size();
    std::atomic<std::size_t> done{0};
    std::atomic<std::size_t> far_total{0}, near_total{0}, quad_total{0};
    oneapi::tbb::parallel_for(
        oneapi::tbb::blocked_range<std::size_t>(0, buckets.size(), 1),
        [&](const oneapi::tbb::blocked_range<std::size_t>& range) {
            Scratch w;
            for (std::size_t bi = range.begin(); bi != range.end(); ++bi) {
                evaluate_bucket(cx, buckets[bi], w, result);
                const std::size_t count = wanted_in(cx, cx.tree.nodes[buckets[bi]]);
                std::size_t now = done.fetch_add(count) + count;
                if (cx.options.progress) cx.options.progress->update(now, n);
            }
            far_total += w.local.far_terms;
            near_total += w.local.near_terms;
            quad_total += w.local.quadrature_terms;
        });
    stats.far_terms = far_total;
    stats.near_terms = near_total;
    stats.quadrature_terms = quad_total;
}

} // namespace sss::diffusion_detail
