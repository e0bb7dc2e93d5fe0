/// \file diffusion.cpp
/// The criterion names and evaluate_diffusion: profile tables, octree,
/// tolerance and the bucket evaluation, in that order.

#include "sss/diffusion/diffusion.h"

#include <algorithm>
#include <optional>
#include <string>

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

// Evaluates into result[original index]: every receiver (receivers null) or
// the listed ones against the whole cloud.
void evaluate(const DiffusionProblem& pb, const DiffusionOptions& options,
              const std::vector<std::size_t>* receivers, std::vector<glm::vec3>& result,
              DiffusionStats* stats_out) {
    if (pb.profiles.size() < 3 && pb.profile_index.empty())
        throw ValueError("diffusion needs three channel profiles");
    Stopwatch watch;
    DiffusionStats stats;
    std::optional<ScopedStage> stage(std::in_place, "building the octree");
    Tables tables = build_tables(pb.profiles);
    Tree tree = build_tree(pb);
    stats.nodes = tree.nodes.size();
    stats.build_seconds = watch.seconds();
    const DiffusionReference reference =
        options.reference ? *options.reference : reference_of(tree.power_area);
    ToleranceModel tolerance = tolerance_model(pb, reference, options.max_solid_angle);
    std::vector<uint32_t> buckets = choose_buckets(tree);
    EvaluationContext cx{pb, options, tables, tree, tolerance};
    std::vector<uint8_t> wanted;
    if (receivers) {
        // Wanted receivers by sorted position; only their buckets are evaluated.
        std::vector<uint32_t> position(tree.order.size());
        for (std::size_t s = 0; s < tree.order.size(); ++s)
            position[tree.order[s]] = uint32_t(s);
        wanted.assign(tree.order.size(), 0);
        for (std::size_t i : *receivers) wanted[position[i]] = 1;
        cx.wanted = wanted.data();
        cx.wanted_count =
            std::size_t(std::count(wanted.begin(), wanted.end(), uint8_t(1)));
        std::erase_if(buckets, [&](uint32_t k) {
            const Node& b = tree.nodes[k];
            return std::none_of(wanted.begin() + b.first,
                                wanted.begin() + b.first + b.count,
                                [](uint8_t w) { return w != 0; });
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
    evaluate(pb, options, nullptr, result, stats_out);
    return result;
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
    evaluate(pb, options, &receivers, all, stats_out);
    std::vector<glm::vec3> out(receivers.size());
    for (std::size_t k = 0; k < receivers.size(); ++k) out[k] = all[receivers[k]];
    return out;
}

} // namespace sss
