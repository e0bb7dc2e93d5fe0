// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file octree.h
/// The octree over the Morton-sorted sources: nodes with their bounds, area and
/// disk sizes, and each node's moments (monopole, dipole, quadrupole) per channel.

#include <cstdint>
#include <vector>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "sss/diffusion/diffusion.h"
#include "sss/util/uninitialized.h"

#include "profile_tables.h"

namespace sss::diffusion_detail {

// Octree over Morton-sorted points.
constexpr uint32_t kLeafSize = 16;
constexpr uint32_t kNone = 0xffffffffu;

struct Node {
    glm::vec3 lo, hi;
    uint32_t first = 0, count = 0;
    uint32_t child_first = kNone;
    uint32_t child_count = 0;
    uint32_t parent = kNone;
    float area = 0;
    float radius = 0;  // max |p - c|
    float max_rho = 0; // largest source disk radius
};

// Moments of a node about its centroid c, per colour channel.
struct Expansion {
    glm::vec3 c;
    float phi[3];
    float abs_phi[3];
    float d[3][3]; // sum A E (p - c)
    float q[3][6]; // sum A E (p - c)(p - c)^T: xx xy xz yy yz zz
    // (|d| is computed where needed: 12 bytes less per node, issue 17.)
};

// The large arrays are UninitVectors: filled in parallel right after their
// allocation (see sss/util/uninitialized.h).
struct Tree {
    std::vector<Node> nodes;
    UninitVector<Expansion> expansions;
    UninitVector<uint32_t> order; // sorted position -> original index
    // Sorted source data.
    UninitVector<glm::vec4> pos_rho2;   // x y z rho^2
    UninitVector<glm::vec4> power_area; // A E (rgb), A
    // Empty when no source disk can need the disk quadrature, the only reader
    // of the normals (see build_tree()).
    UninitVector<glm::vec3> normal;
    // Per-point materials (else empty): each receiver's material in sorted
    // order, an index into `materials`, the distinct triples of channel
    // profile indices (DiffusionProblem::profile_index) in the order first
    // met; and the receivers' gains (DiffusionProblem::receiver_gain).
    UninitVector<uint32_t> material;
    std::vector<glm::u32vec3> materials;
    UninitVector<glm::vec3> receiver_gain;

    bool per_point() const { return !material.empty(); }
    // The profile indices of the receiver at sorted position s.
    glm::u32vec3 profiles_of(uint32_t s) const { return materials[material[s]]; }
};

// Sorts the sources into Morton order and builds the nodes (breadth first,
// leaves of at most kLeafSize points) and their moments. Deterministic: the
// tree does not depend on the thread count.
// With `release` (the problem pb itself), its positions, normals and areas are
// freed as soon as the tree holds their sorted copies: the caller must not
// need them any more.
// Without `normals`, Tree::normal stays empty (12 bytes per point less): the
// caller has checked that no source disk is large enough for near_source()'s
// disk quadrature (normals_needed()).
Tree build_tree(const DiffusionProblem& pb, DiffusionProblem* release = nullptr,
                bool normals = true);

// Whether some source disk of the problem may be integrated by the disk
// quadrature, the only reader of the sources' normals: near_source() does so
// when rho^2 > kNearKappa2 (r^2 + near_core2), and r^2 >= 0, near_core2 >= the
// smallest core^2 of all tables. False is a guarantee; true may be pessimistic.
bool normals_needed(const DiffusionProblem& pb, const Tables& tables);

// The sources in the tree's order (order, pos_rho2, power_area, normal),
// without the nodes.
Tree sorted_sources(const DiffusionProblem& pb);

// The tree's order alone (sorted position -> original index): what
// build_tree() sorts the points into, at the cost of the sort only.
std::vector<uint32_t> morton_order(const std::vector<glm::vec3>& positions);

// Squared distance between two boxes (0 when they overlap).
inline float box_distance2(const glm::vec3& alo, const glm::vec3& ahi,
                           const glm::vec3& blo, const glm::vec3& bhi) {
    glm::vec3 gap = glm::max(glm::vec3(0.0f), glm::max(blo - ahi, alo - bhi));
    return glm::dot(gap, gap);
}

} // namespace sss::diffusion_detail
