// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file diffusion.h
/// Subsurface diffusion over a point cloud: M_o(x_i) = sum_j R(|x_i - P_j|) A_j E_j,
/// evaluated exactly (all pairs) or hierarchically over an octree.
/// May use: cloud and util.
///
/// The diffusion module owns the materials, the profiles, the hierarchical and
/// exact evaluations and the ptfilter -ssdiffusion job (ssdiffusion.h). Its private
/// pieces (tables, octree, traversal, kernels)
/// live next to its sources.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include <glm/ext/vector_uint3.hpp>
#include <glm/vec3.hpp>

#include "sss/diffusion/profile.h"
#include "sss/util/isa.h"

namespace sss {

class Progress;

/// How the octree decides that a node is far enough to be used whole.
enum class Criterion {
    /// Ours (default): a bound on the error of the node's second-order
    /// (quadrupole) expansion, from the profile's derivatives and the node's
    /// size and power, against a tolerance relative to the local result.
    Error,
    /// PRMan's: area / squared distance to the node's bounding box <= maxsolidangle.
    SolidAngleBox,
    /// Jensen & Buhler's: area / squared distance to the node centroid <=
    /// maxsolidangle, and the receiver outside the node box.
    SolidAngleCentroid
};

/// Parses "error", "bbox"/"prman", "centroid"/"jensen".
bool parse_criterion(const char* name, Criterion& out);
const char* criterion_name(Criterion c);

/// The points and materials of one evaluation, every length in one unit. The
/// float profile tables need the profiles' lengths (dmfp) within roughly 1e-5
/// to 1e5 of that unit, so ssdiffusion() passes mm, not scene units.
struct DiffusionProblem {
    std::vector<glm::vec3> positions;
    std::vector<glm::vec3> normals;    ///< used to orient near-field source disks
    std::vector<float> areas;          ///< >= 0
    std::vector<glm::vec3> irradiance; ///< signed (blockers are negative)
    /// Distinct channel profiles; by default point i uses profiles[0..2] for r, g, b.
    std::vector<Profile> profiles;
    /// Optional per-point channel -> profile index (receiver's material).
    std::vector<glm::u32vec3> profile_index;
    /// Optional per-point factor on each channel of the point's result (empty:
    /// 1). Per-point materials that share quantised profiles set it to the
    /// point's own total reflectance over its profile's, which keeps the
    /// quantisation's error second order.
    std::vector<glm::vec3> receiver_gain;
};

/// The whole-cloud quantities the error criterion's tolerance is relative to.
/// Every other input of a receiver's result is local to it or part of the
/// octree, so a run over part of the receivers gives the whole run's numbers
/// when it is given the whole cloud's reference (a farm that splits the
/// receivers across machines passes the same reference to every part).
struct DiffusionReference {
    /// Total source area, sum A: bounds the tolerance for objects small
    /// against the profile.
    float area = 0;
    /// Sum |A E| per channel; abs_power / area, the cloud's mean |E|, is the
    /// floor of the local reference level.
    float abs_power[3] = {0, 0, 0};

    bool operator==(const DiffusionReference&) const = default;
};

/// The reference of a whole problem: the sums in double over the points in
/// the octree's (Morton) order, rounded to float, exactly as evaluate_diffusion()
/// forms them when options.reference is unset. O(n log n) (it sorts the points).
DiffusionReference diffusion_reference(const DiffusionProblem& problem);

/// Evaluation settings.
struct DiffusionOptions {
    /// PRMan's time/quality knob: smaller is slower and more accurate.
    double max_solid_angle = 1.0;
    Criterion criterion = Criterion::Error;
    Progress* progress = nullptr; ///< optional ALF_PROGRESS reporter
    /// The tolerance reference; unset: the problem's own (diffusion_reference()).
    std::optional<DiffusionReference> reference;
    /// The kernels' instruction-set path (sss/util/isa.h); all paths give
    /// identical results. Auto: SSS_ISA, else the best the CPU has.
    Isa isa = Isa::Auto;
};

/// Counters of one hierarchical evaluation.
struct DiffusionStats {
    std::size_t nodes = 0;            ///< octree nodes
    std::size_t far_terms = 0;        ///< node expansions evaluated (sum over receivers)
    std::size_t near_terms = 0;       ///< point-point terms evaluated
    std::size_t quadrature_terms = 0; ///< near sources integrated as disks
    /// node expansions re-expanded once for a whole bucket of receivers (sum
    /// over buckets; each serves every receiver of its bucket)
    std::size_t local_terms = 0;
    double build_seconds = 0;
    double eval_seconds = 0;
    Isa isa = Isa::Auto; ///< the kernels' path that ran
};

/// Hierarchical evaluation at every point. Deterministic: the result does not
/// depend on the thread count. Memory is linear in the point count.
std::vector<glm::vec3> evaluate_diffusion(const DiffusionProblem& problem,
                                          const DiffusionOptions& options,
                                          DiffusionStats* stats = nullptr);

/// The same evaluation, bit for bit, consuming the problem to keep the peak
/// memory low: its positions, normals and areas are freed as soon as the
/// octree holds sorted copies of them, and the result is written over its
/// irradiance (each receiver's irradiance is read once, by its own self
/// term, before its result replaces it) and returned. At the peak the process
/// holds the octree and 13 bytes per point besides.
std::vector<glm::vec3> evaluate_diffusion(DiffusionProblem&& problem,
                                          const DiffusionOptions& options,
                                          DiffusionStats* stats = nullptr);

/// Hierarchical evaluation at the given receivers (indices into the problem's
/// points, repeats allowed) against the whole cloud: result[k] is bit for bit
/// what evaluate_diffusion(problem, options) gives at receivers[k], whatever
/// the subset and the thread count, for the same options.reference. Builds the
/// whole octree; the evaluation work is that of the receivers' buckets (up to
/// 64 neighbouring points each). Throws ValueError on an index out of range.
/// Stats count the work done; progress counts distinct receivers.
std::vector<glm::vec3> evaluate_diffusion_at(const DiffusionProblem& problem,
                                             const DiffusionOptions& options,
                                             const std::vector<std::size_t>& receivers,
                                             DiffusionStats* stats = nullptr);

/// One part of an evaluation split across machines (ptfilter -part K/N).
struct DiffusionPart {
    /// Position of the part's first receiver in the space-filling order.
    std::size_t first = 0;
    /// The part's receivers (indices into the problem's points), in the
    /// space-filling order.
    std::vector<uint32_t> receivers;
    /// result[k] is the diffusion at receivers[k].
    std::vector<glm::vec3> result;
};

/// The positions [first, end) of part `part` (0-based) of `parts` in an order
/// of n points: floor(n part / parts) to floor(n (part + 1) / parts), so the
/// parts cover every point once and differ in size by at most one. Throws
/// ValueError unless part < parts.
std::pair<std::size_t, std::size_t> part_range(std::size_t n, std::size_t part,
                                               std::size_t parts);

/// The receivers of part `part` (0-based) of `parts`: a contiguous range
/// (part_range()) of the octree's Morton order, so each part is a compact
/// region of space, evaluated against the whole cloud. result is bit for bit
/// what evaluate_diffusion() gives at those receivers, whatever the thread
/// count; memory for results is the part's, not the cloud's. Progress counts
/// the part's receivers. Throws ValueError for part >= parts.
DiffusionPart evaluate_diffusion_part(const DiffusionProblem& problem,
                                      const DiffusionOptions& options, std::size_t part,
                                      std::size_t parts, DiffusionStats* stats = nullptr);
/// The same, freeing the problem's positions, normals and areas as soon as
/// the octree holds them (28 bytes per point less at the peak); the problem
/// is left with its irradiance and materials only.
DiffusionPart evaluate_diffusion_part(DiffusionProblem&& problem,
                                      const DiffusionOptions& options, std::size_t part,
                                      std::size_t parts, DiffusionStats* stats = nullptr);

/// The points' space-filling (Morton) order, as evaluate_diffusion_part()
/// splits it: order[s] is the index of the point at position s.
std::vector<uint32_t> space_filling_order(const DiffusionProblem& problem);

/// Which source disks the exact evaluation integrates over (the others are
/// points).
enum class ExactDisks {
    /// The point model's rule: disks close against their distance softened
    /// by the profile's core length (rho^2 > 0.1 (r^2 + core^2)); for the
    /// sampled profiles (pbd, mc) every disk with rho^2 > 1e-3 r^2.
    Model,
    /// Every disk with rho^2 > 1e-3 r^2, whatever the profile: the reference
    /// that also measures the point model's near field.
    All
};

/// Exact evaluation in double precision, all pairs, at the given receivers
/// (all points when empty). The same point model as the hierarchical path:
/// exact self disk, disk integration of close sources.
std::vector<glm::dvec3> evaluate_diffusion_exact(
    const DiffusionProblem& problem, const std::vector<std::size_t>& receivers = {},
    Progress* progress = nullptr, ExactDisks disks = ExactDisks::Model);

} // namespace sss
