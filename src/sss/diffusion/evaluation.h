// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file evaluation.h
/// The hierarchical evaluation proper: receiver buckets, and for each bucket
/// the traversal of its criterion followed by the vectorised block path (one
/// material) or the receiver-by-receiver path.

#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "sss/diffusion/diffusion.h"

#include "block.h"
#include "octree.h"
#include "profile_tables.h"
#include "tolerance.h"

namespace sss::diffusion_detail {

// Receiver buckets: maximal nodes of at most kMaxBucket points (or leaves)
// that share one traversal, in depth-first order.
std::vector<uint32_t> choose_buckets(const Tree& tree);

// What the evaluation of every bucket reads.
struct EvaluationContext {
    const DiffusionProblem& pb;
    const DiffusionOptions& options;
    const Tables& tables;
    const Tree& tree;
    const ToleranceModel& tolerance;
    // The block kernels of the options' instruction-set path.
    const BlockKernels& kernels = block_kernels(options.isa);
    // The receivers to evaluate, by sorted position (non-zero: wanted); null:
    // all of them. A bucket on the block path is evaluated whole either way.
    const uint8_t* wanted = nullptr;
    std::size_t wanted_count = 0; // receivers wanted in all (progress total)
    // A part (range_end > range_first): only the receivers at sorted positions
    // [range_first, range_end), written to result[s - range_first], so that a
    // part's result is the size of the part, not of the cloud.
    uint32_t range_first = 0, range_end = 0;
    // Per-point materials: material_near_rows() of the tree's materials
    // (null: the near pairs read each channel's profile rows).
    const float* material_rows = nullptr;

    bool ranged() const { return range_end > range_first; }
    // Whether the receiver at sorted position s is evaluated.
    bool wants(uint32_t s) const {
        if (ranged()) return s >= range_first && s < range_end;
        return !wanted || wanted[s];
    }
    // Where its result goes (original: its index in the problem).
    std::size_t slot(uint32_t s, uint32_t original) const {
        return ranged() ? std::size_t(s - range_first) : std::size_t(original);
    }
};

// Evaluates the (wanted) receivers of the given buckets in parallel into
// result[cx.slot(...)]; sets the term counts of stats.
void evaluate_buckets(const EvaluationContext& cx, const std::vector<uint32_t>& buckets,
                      std::vector<glm::vec3>& result, DiffusionStats& stats);

} // namespace sss::diffusion_detail
