// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file tolerance.cpp
/// The error criterion's tolerance: the whole-cloud terms, each bucket's local
/// reference level and the tolerance that follows for its receivers.

#include "tolerance.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "sss/util/math.h"

namespace sss::diffusion_detail {

namespace {

// Local reference level: the node whose mean |E| the bucket's tolerance is
// relative to, the bucket's largest ancestor under two region widths across.
uint32_t reference_node(const Tree& tree, uint32_t bucket, double region) {
    uint32_t up = bucket;
    while (tree.nodes[up].parent != kNone) {
        const Node& nd = tree.nodes[up];
        if (glm::length(nd.hi - nd.lo) >= 2.0 * region) break;
        up = nd.parent;
    }
    return up;
}

} // namespace

DiffusionReference reference_of(const UninitVector<glm::vec4>& power_area) {
    double asum = 0, aphi[3] = {0, 0, 0};
    for (const glm::vec4& pa : power_area) {
        asum += pa.w;
        for (int ch = 0; ch < 3; ++ch) {
            double w = pa[ch];
            aphi[ch] += std::abs(w);
        }
    }
    DiffusionReference ref;
    ref.area = float(asum);
    for (int ch = 0; ch < 3; ++ch) ref.abs_power[ch] = float(aphi[ch]);
    return ref;
}

ToleranceModel tolerance_model(const DiffusionProblem& pb,
                               const DiffusionReference& reference,
                               double max_solid_angle) {
    ToleranceModel m;
    // Reference magnitude for the error tolerance: the local mean |E| over a
    // region about one diffusion length wide (with a floor at a fraction of the
    // global mean, so dark regions do not demand unbounded work).
    for (int ch = 0; ch < 3; ++ch)
        m.global_abs[ch] =
            reference.area > 0 ? reference.abs_power[ch] / reference.area : 0.0;
    for (const Profile& p : pb.profiles)
        if (p.total() > 0)
            m.region = std::max(m.region, std::min(p.dmfp(), p.cutoff_radius(1e-3)));
    // Calibrated so that the default (1) gives about 0.05 % RMS error and a
    // mean error within +-0.05 % on smooth lit objects (docs/ptfilter.md has
    // the measured table); 4e-3 before the local expansions (issue 17).
    m.tau = 8e-3 * max_solid_angle;
    // The tolerance scales with albedo x E, what a large, well-sampled surface
    // returns. A cloud can return far less: when the whole object is small
    // against the profile (at most disk(sqrt(total area / pi)), the profile's
    // share inside a disk of the cloud's area) or when the areas cover only a
    // fraction of the surface the points span (tiny areas). Without these
    // bounds every node was dropped as negligible there (100 % error).
    m.reach.resize(pb.profiles.size());
    const double rho_all = std::sqrt(double(reference.area) / kPi);
    for (std::size_t k = 0; k < pb.profiles.size(); ++k)
        m.reach[k] = pb.profiles[k].disk(rho_all);
    return m;
}

BucketTolerance bucket_tolerance(const ToleranceModel& model, const DiffusionProblem& pb,
                                 const Tables& tables, const Tree& tree, uint32_t bucket,
                                 const ReceiverChannels& first_rc) {
    BucketTolerance bt;
    const Node& node = tree.nodes[bucket];
    // The smallest total and reach of the receivers' profiles per channel, and
    // the bounds the walk tests (distinct tables, or their envelopes).
    double tot_min[3], reach_min[3];
    for (int ch = 0; ch < 3; ++ch) {
        tot_min[ch] = first_rc.profile[ch]->total();
        reach_min[ch] =
            model.reach[std::size_t(first_rc.profile[ch] - pb.profiles.data())];
        bt.tables[ch].assign(1, first_rc.table[ch]);
    }
    if (tree.per_point()) {
        const bool envelopes = !tables.envelopes.empty();
        const uint32_t first = tree.material[node.first];
        // (A group's scan covers thousands of receivers, in runs that share
        // one material: each run is looked at once.)
        thread_local KeyPositions seen[3];
        for (int ch = 0; ch < 3; ++ch) {
            bt.tables[ch].clear();
            seen[ch].reset(envelopes ? tables.envelopes.size() : tables.channels.size());
        }
        for (uint32_t s = node.first; s < node.first + node.count; ++s) {
            if (s > node.first && tree.material[s] == tree.material[s - 1]) continue;
            if (tree.material[s] != first) bt.one_material = false;
            const glm::u32vec3 idx = tree.profiles_of(s);
            for (int ch = 0; ch < 3; ++ch) {
                const uint32_t k = idx[ch];
                const uint32_t key = envelopes ? tables.envelope_of[k] : k;
                tot_min[ch] = std::min(tot_min[ch], pb.profiles[k].total());
                reach_min[ch] = std::min(reach_min[ch], model.reach[k]);
                if (seen[ch].find(key) != KeyPositions::kNone) continue;
                seen[ch].set(key, uint32_t(bt.tables[ch].size()));
                bt.tables[ch].push_back(envelopes ? &tables.envelopes[key]
                                                  : &tables.channels[key]);
            }
        }
        if (bt.one_material)
            for (int ch = 0; ch < 3; ++ch) bt.tables[ch].assign(1, first_rc.table[ch]);
    }
    const uint32_t up = reference_node(tree, bucket, model.region);
    // Area density of the region: its points' areas against a quarter
    // of its squared diagonal (>= 1 for any surface patch that the
    // points sample: a flat square patch gives 2).
    double diag = glm::length(tree.nodes[up].hi - tree.nodes[up].lo);
    double density =
        diag > 0 ? std::min(1.0, 4.0 * tree.nodes[up].area / (diag * diag)) : 1.0;
    for (int ch = 0; ch < 3; ++ch) {
        double level = tree.nodes[up].area > 0
                           ? tree.expansions[up].abs_phi[ch] / tree.nodes[up].area
                           : 0.0;
        level = std::max(level, 0.05 * model.global_abs[ch]);
        bt.tol[ch] = model.tau * std::min(tot_min[ch] * density, reach_min[ch]) * level;
        bt.skip[ch] = 0.05 * bt.tol[ch];
    }
    return bt;
}

} // namespace sss::diffusion_detail

namespace sss {

DiffusionReference diffusion_reference(const DiffusionProblem& problem) {
    return diffusion_detail::reference_of(
        diffusion_detail::sorted_sources(problem).power_area);
}

} // namespace sss
