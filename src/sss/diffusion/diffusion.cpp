/// \file diffusion.cpp
/// The criterion names and evaluate_diffusion: profile tables, octree,
/// tolerance and the bucket evaluation, in that order.

#include "sss/diffusion/diffusion.h"

#include <optional>

#include "sss/util/error.h"
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

using diffusion_detail::build_tables;
using diffusion_detail::build_tree;
using diffusion_detail::choose_buckets;
using diffusion_detail::evaluate_buckets;
using diffusion_detail::Tables;
using diffusion_detail::tolerance_model;
using diffusion_detail::ToleranceModel;
using diffusion_detail::Tree;

std::vector<glm::vec3> evaluate_diffusion(const DiffusionProblem& pb,
                                          const DiffusionOptions& options,
                                          DiffusionStats* stats_out) {
    const std::size_t n = pb.positions.size();
    std::vector<glm::vec3> result(n, glm::vec3(0.0f));
    if (n == 0) return result;
    if (pb.profiles.size() < 3 && pb.profile_index.empty())
        throw ValueError("diffusion needs three channel profiles");
    Stopwatch watch;
    DiffusionStats stats;
    Tables tables = build_tables(pb.profiles);
    Tree tree = build_tree(pb);
    stats.nodes = tree.nodes.size();
    stats.build_seconds = watch.seconds();
    ToleranceModel tolerance = tolerance_model(pb, tree, options.max_solid_angle);
    evaluate_buckets({pb, options, tables, tree, tolerance}, choose_buckets(tree), result,
                     stats);
    stats.eval_seconds = watch.seconds() - stats.build_seconds;
    if (stats_out) *stats_out = stats;
    return result;
}

} // namespace sss
