// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file tolerance.h
/// The error criterion's tolerance: the whole-cloud terms it is relative to,
/// and each bucket's tolerance from the mean |E| of the region around it and
/// its receivers' profiles.

#include <cstdint>
#include <vector>

#include <glm/vec4.hpp>

#include "sss/diffusion/diffusion.h"

#include "octree.h"
#include "profile_tables.h"

namespace sss::diffusion_detail {

// The whole-cloud terms of the tolerance, the same for every bucket.
struct ToleranceModel {
    double global_abs[3] = {0, 0, 0}; // whole-cloud mean |E|: the floor of the level
    double region = 0;                // width of the region that sets the level
    double tau = 0;                   // relative tolerance
    std::vector<double> reach;        // per profile: disk(sqrt(total area / pi))
};

ToleranceModel tolerance_model(const DiffusionProblem& pb,
                               const DiffusionReference& reference,
                               double max_solid_angle);

// The reference from the sources in the tree's order (Tree::power_area): the
// same sums, in the same order, as the root node's area and abs_phi.
DiffusionReference reference_of(const UninitVector<glm::vec4>& power_area);

// One bucket's tolerance per channel, and the distinct tables of its receivers
// (the error bounds hold for every one of them).
struct BucketTolerance {
    // The bounds the walk tests per channel: the receivers' tables, or with
    // per-point materials their classes' envelopes (Tables::envelopes).
    std::vector<const ChannelTable*> tables[3];
    bool one_material = true;   // every receiver reads the same three tables
    double tol[3] = {0, 0, 0};  // largest error accepted from one node
    double skip[3] = {0, 0, 0}; // largest contribution taken as a monopole untested
};

// first_rc: the channels of the bucket's first receiver.
BucketTolerance bucket_tolerance(const ToleranceModel& model, const DiffusionProblem& pb,
                                 const Tables& tables, const Tree& tree, uint32_t bucket,
                                 const ReceiverChannels& first_rc);

} // namespace sss::diffusion_detail
