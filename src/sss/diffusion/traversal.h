// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file traversal.h
/// Walks the octree for a box of receivers and sorts its nodes into far
/// (expanded), monopole-only, near (leaves, point by point) and dropped
/// (beyond every profile's reach), with one function per criterion.

#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "octree.h"
#include "profile_tables.h"
#include "tolerance.h"

namespace sss::diffusion_detail {

// The nodes one traversal keeps, by how they are evaluated.
struct NodeLists {
    std::vector<uint32_t> far;   // expansions (quadrupole with the error criterion)
    std::vector<uint32_t> mono;  // expansions whose dipole and quadrupole are negligible
    std::vector<uint32_t> local; // expansions taken once for the whole bucket (a local
                                 // expansion about the bucket's centre)
    std::vector<uint32_t> near;  // leaves, summed source by source
    std::vector<uint32_t> stack; // the walk's own scratch
};

// Ours: a node is used whole when the error bound of its quadrupole expansion
// is within the bucket's tolerance for every receiver in [blo, bhi], and as its
// monopole when that is accurate enough or when it cannot contribute more than
// the tolerance's skip level (never dropped: that biased results towards 0);
// dropped only beyond the profile tables (where every profile is ~0).
// With `local` (receivers that share one material), a node whose expansion
// re-expanded about the box centre is still within the tolerance everywhere in
// the box goes to the local list instead: its work is shared by the bucket.
// The walk starts at `start` (null: the root): the nodes a receiver group
// left to this bucket (traverse_group).
void traverse_error(const Tree& tree, const Tables& tables, const BucketTolerance& tol,
                    const glm::vec3& blo, const glm::vec3& bhi, bool local,
                    NodeLists& lists, const std::vector<uint32_t>* start = nullptr);

// A receiver group (a node above the buckets, one material): from `start`, the
// nodes whose local expansion about the group box's centre is within the
// tolerance for every receiver in [glo, ghi] go to lists.local (shared by all
// the group's buckets); the others, opened while larger than the group, are
// left to the group's children in lists.near.
void traverse_group(const Tree& tree, const Tables& tables, const BucketTolerance& tol,
                    const glm::vec3& glo, const glm::vec3& ghi,
                    const std::vector<uint32_t>& start, NodeLists& lists);

// PRMan's: area / squared distance to the node's box (grown by its largest
// source disk) <= eps for receivers in [blo, bhi].
void traverse_solid_angle_box(const Tree& tree, double eps, const glm::vec3& blo,
                              const glm::vec3& bhi, NodeLists& lists);

// Jensen & Buhler's: area / squared distance to the node centroid < eps, and the
// receiver x outside the node box.
void traverse_solid_angle_centroid(const Tree& tree, double eps, const glm::vec3& x,
                                   NodeLists& lists);

} // namespace sss::diffusion_detail
