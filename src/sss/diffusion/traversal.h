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
    std::vector<uint32_t> near;  // leaves, summed source by source
    std::vector<uint32_t> stack; // the walk's own scratch
};

// Ours: a node is used whole when the error bound of its quadrupole expansion
// is within the bucket's tolerance for every receiver in [blo, bhi], and as its
// monopole when that is accurate enough or when it cannot contribute more than
// the tolerance's skip level (never dropped: that biased results towards 0);
// dropped only beyond the profile tables (where every profile is ~0).
void traverse_error(const Tree& tree, const Tables& tables, const BucketTolerance& tol,
                    const glm::vec3& blo, const glm::vec3& bhi, NodeLists& lists);

// PRMan's: area / squared distance to the node's box (grown by its largest
// source disk) <= eps for receivers in [blo, bhi].
void traverse_solid_angle_box(const Tree& tree, double eps, const glm::vec3& blo,
                              const glm::vec3& bhi, NodeLists& lists);

// Jensen & Buhler's: area / squared distance to the node centroid < eps, and the
// receiver x outside the node box.
void traverse_solid_angle_centroid(const Tree& tree, double eps, const glm::vec3& x,
                                   NodeLists& lists);

} // namespace sss::diffusion_detail
