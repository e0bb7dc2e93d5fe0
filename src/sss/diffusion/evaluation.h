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
    // The receivers to evaluate, by sorted position (non-zero: wanted); null:
    // all of them. A bucket on the block path is evaluated whole either way.
    const uint8_t* wanted = nullptr;
    std::size_t wanted_count = 0; // receivers wanted in all (progress total)
};

// Evaluates the (wanted) receivers of the given buckets in parallel into
// result[original index]; sets the term counts of stats.
void evaluate_buckets(const EvaluationContext& cx, const std::vector<uint32_t>& buckets,
                      std::vector<glm::vec3>& result, DiffusionStats& stats);

} // namespace sss::diffusion_detail
