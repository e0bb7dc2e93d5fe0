// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file diffusion.cpp
/// The criterion names and evaluate_diffusion: profile tables, octree,
/// tolerance and the bucket evaluation, in that order.

#include "sss/diffusion/diffusion.h"

#include <algorithm>
#include <optional>
#include <string>
#include <utility>

#include "sss/util/error.h"
#include "sss/util/limits.h"
#include "sss/util/name_table.h"
#include "sss/util/progress.h"

#include "evaluation.h"
#include "octree.h"
#include "profile_tables.h"
#include "tolerance.h"

namespace sss {

namespace {

// The first name of a criterion is the one written; "prman" and "jensen" are
// accepted aliases.
constexpr NameTable<Criterion, 5> kCriterionNames({{
    {Criterion::Error, "error"},
    {Criterion::SolidAngleBox, "bbox"},
    {Criterion::SolidAngleBox, "prman"},
    {Criterion::SolidAngleCentroid, "centroid"},
    {Criterion::SolidAngleCentroid, "jensen"},
}});

} // namespace

bool parse_criterion(const char* name, Criterion& out) {
    std::optional<Criterion> c = kCriterionNames.parse(name);
    if (c) out = *c;
    return c.has_value();
}

const char* criterion_name(Criterion c) {
    return kCriterionNames.name(c);
}

namespace {

using namespace diffusion_detail;

// Which receivers one evaluation computes.
struct Selection {
    const std::vector<std::size_t>* receivers = nullptr; // these (result[original])
    std::size_t part = 0, parts = 0; // with parts > 0: this part (result[s - first])
};

// Evaluates the selected receivers (all by default) against the whole cloud.
// For a part, also sets its first position and receivers in `part_out`.
// `release`: the problem itself (pb), whose positions, normals and areas are
// freed once the octree holds them (the evaluation reads only the octree, the
// irradiance and the materials).
void evaluate(const DiffusionProblem& pb, const DiffusionOptions& options,
              const Selection& selection, std::vector<glm::vec3>& result,
              DiffusionStats* stats_out, DiffusionPart* part_out = nullptr,
              DiffusionProblem* release = nullptr) {
    if (pb.profiles.size() < 3 && pb.profile_index.empty())
        throw ValueError("diffusion needs three channel profiles");
    if (!pb.receiver_gain.empty() && pb.receiver_gain.size() != pb.irradiance.size())
        throw ValueError("diffusion: " + std::to_string(pb.receiver_gain.size()) +
                         " receiver gains for " + std::to_string(pb.irradiance.size()) +
                         " points");
    Stopwatch watch;
    DiffusionStats stats;
    std::optional<ScopedStage> stage(std::in_place, "building the octree");
    Tables tables = build_tables(pb.profiles, !pb.profile_index.empty());
    // The normals only when some disk may need the quadrature; frees pb's
    // geometry with `release`.
    Tree tree = build_tree(pb, release, normals_needed(pb, tables));
    stats.nodes = tree.nodes.size();
    stats.build_seconds = watch.seconds();
    const DiffusionReference reference =
        options.reference ? *options.reference : reference_of(tree.power_area);
    ToleranceModel tolerance = tolerance_model(pb, reference, options.max_solid_angle);
    std::vector<uint32_t> buckets = choose_buckets(tree);
    EvaluationContext cx{pb, options, tables, tree, tolerance};
    const std::vector<float> material_rows = material_near_rows(tables, tree.materials);
    if (!material_rows.empty()) cx.material_rows = material_rows.data();
    std::vector<uint8_t> wanted;
    if (selection.receivers) {
        // Wanted receivers by sorted position; only their buckets are evaluated.
        std::vector<uint32_t> position(tree.order.size());
        for (std::size_t s = 0; s < tree.order.size(); ++s)
            position[tree.order[s]] = uint32_t(s);
        wanted.assign(tree.order.size(), 0);
        for (std::size_t i : *selection.receivers) wanted[position[i]] = 1;
        cx.wanted = wanted.data();
        cx.wanted_count =
            std::size_t(std::count(wanted.begin(), wanted.end(), uint8_t(1)));
        std::erase_if(buckets, [&](uint32_t k) {
            const Node& b = tree.nodes[k];
            return std::none_of(wanted.begin() + b.first,
                                wanted.begin() + b.first + b.count,
                                [](uint8_t w) { return w != 0; });
        });
    } else if (selection.parts > 0) {
        // Named variables, not a structured binding: clang 14 cannot
        // capture a binding in the lambda below.
        const auto range = part_range(tree.order.size(), selection.part, selection.parts);
        const auto first = range.first, end = range.second;
        part_out->first = first;
        part_out->receivers.assign(tree.order.begin() + first, tree.order.begin() + end);
        result.assign(end - first, glm::vec3(0.0f));
        if (end == first) {
            if (stats_out) *stats_out = stats;
            return;
        }
        cx.range_first = uint32_t(first);
        cx.range_end = uint32_t(end);
        std::erase_if(buckets, [&](uint32_t k) {
            const Node& b = tree.nodes[k];
            return b.first + b.count <= first || b.first >= end;
        });
    }
    stage.emplace("evaluating the diffusion");
    evaluate_buckets(cx, buckets, result, stats);
    stats.eval_seconds = watch.seconds() - stats.build_seconds;
    if (stats_out) *stats_out = stats;
}

} // namespace

std::vector<glm::vec3> evaluate_diffusion(const DiffusionProblem& pb,
                                          const DiffusionOptions& options,
                                          DiffusionStats* stats_out) {
    const std::size_t n = pb.positions.size();
    std::vector<glm::vec3> result(n, glm::vec3(0.0f));
    if (n == 0) return result;
    evaluate(pb, options, Selection{}, result, stats_out);
    return result;
}

std::vector<glm::vec3> evaluate_diffusion(DiffusionProblem&& pb,
                                          const DiffusionOptions& options,
                                          DiffusionStats* stats_out) {
    if (pb.positions.empty())
        return evaluate_diffusion(std::as_const(pb), options, stats_out);
    // The result is the irradiance's own memory: a receiver's irradiance is
    // read by its self term only, just before its result is stored there.
    evaluate(pb, options, Selection{}, pb.irradiance, stats_out, nullptr, &pb);
    return std::move(pb.irradiance);
}

std::vector<glm::vec3> evaluate_diffusion_at(const DiffusionProblem& pb,
                                             const DiffusionOptions& options,
                                             const std::vector<std::size_t>& receivers,
                                             DiffusionStats* stats_out) {
    const std::size_t n = pb.positions.size();
    for (std::size_t i : receivers)
        if (i >= n)
            throw ValueError("diffusion receiver " + std::to_string(i) +
                             " out of range (" + std::to_string(n) + " points)");
    if (receivers.empty()) {
        if (stats_out) *stats_out = DiffusionStats{};
        return {};
    }
    std::vector<glm::vec3> all(n, glm::vec3(0.0f));
    evaluate(pb, options, Selection{&receivers}, all, stats_out);
    std::vector<glm::vec3> out(receivers.size());
    for (std::size_t k = 0; k < receivers.size(); ++k) out[k] = all[receivers[k]];
    return out;
}

std::pair<std::size_t, std::size_t> part_range(std::size_t n, std::size_t part,
                                               std::size_t parts) {
    if (parts == 0 || part >= parts)
        throw ValueError("part " + std::to_string(part + 1) + " of " +
                         std::to_string(parts) + " does not exist");
    // n * part fits in 64 bits: n < 2^32 (the octree's indices), parts < 2^32.
    auto bound = [&](std::size_t k) {
        return std::size_t((unsigned __int128)(n)*k / parts);
    };
    return {bound(part), bound(part + 1)};
}

namespace {

DiffusionPart evaluate_part(const DiffusionProblem& pb, const DiffusionOptions& options,
                            std::size_t part, std::size_t parts,
                            DiffusionStats* stats_out, DiffusionProblem* release) {
    DiffusionPart out;
    part_range(pb.positions.size(), part, parts); // validates part and parts
    if (pb.positions.empty()) {
        if (stats_out) *stats_out = DiffusionStats{};
        return out;
    }
    evaluate(pb, options, Selection{nullptr, part, parts}, out.result, stats_out, &out,
             release);
    return out;
}

} // namespace

DiffusionPart evaluate_diffusion_part(const DiffusionProblem& pb,
                                      const DiffusionOptions& options, std::size_t part,
                                      std::size_t parts, DiffusionStats* stats_out) {
    return evaluate_part(pb, options, part, parts, stats_out, nullptr);
}

DiffusionPart evaluate_diffusion_part(DiffusionProblem&& pb,
                                      const DiffusionOptions& options, std::size_t part,
                                      std::size_t parts, DiffusionStats* stats_out) {
    return evaluate_part(pb, options, part, parts, stats_out, &pb);
}

std::vector<uint32_t> space_filling_order(const DiffusionProblem& pb) {
    return morton_order(pb.positions);
}

} // namespace sss
