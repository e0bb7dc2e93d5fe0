/// \file octree.cpp
/// Builds the octree: Morton codes and their sort, the sorted source arrays,
/// the breadth-first node split and the node moments.

#include "octree.h"

#include "disk_quadrature.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <utility>

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/parallel_sort.h>

#include "sss/util/math.h"

namespace sss::diffusion_detail {

namespace {

uint64_t spread_bits(uint64_t x) {
    x &= 0x1fffff;
    x = (x | x << 32) & 0x1f00000000ffffull;
    x = (x | x << 16) & 0x1f0000ff0000ffull;
    x = (x | x << 8) & 0x100f00f00f00f00full;
    x = (x | x << 4) & 0x10c30c30c30c30c3ull;
    x = (x | x << 2) & 0x1249249249249249ull;
    return x;
}

// (Morton code, original index), sorted.
using MortonKeys = std::vector<std::pair<uint64_t, uint32_t>>;

// Morton codes on a 2^21 grid over the points' bounding cube, sorted.
MortonKeys sorted_morton_keys(const std::vector<glm::vec3>& positions) {
    const std::size_t n = positions.size();
    glm::dvec3 lo(std::numeric_limits<double>::max()),
        hi(-std::numeric_limits<double>::max());
    for (const glm::vec3& p : positions) {
        lo = glm::min(lo, glm::dvec3(p));
        hi = glm::max(hi, glm::dvec3(p));
    }
    double extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z, 1e-30});
    double scale = double((1u << 21) - 1) / extent;
    MortonKeys keys(n);
    oneapi::tbb::parallel_for(std::size_t(0), n, [&](std::size_t i) {
        glm::dvec3 g = (glm::dvec3(positions[i]) - lo) * scale;
        uint64_t code = spread_bits(uint64_t(g.x)) | spread_bits(uint64_t(g.y)) << 1 |
                        spread_bits(uint64_t(g.z)) << 2;
        keys[i] = {code, uint32_t(i)};
    });
    // Unique (code, index) keys make the order independent of the thread count.
    oneapi::tbb::parallel_sort(keys.begin(), keys.end());
    return keys;
}

// The sources in Morton order: tree.order and the sorted source arrays.
void sort_sources(const DiffusionProblem& pb, const MortonKeys& keys, Tree& tree,
                  bool normals = true) {
    const std::size_t n = keys.size();
    tree.order.resize(n);
    tree.pos_rho2.resize(n);
    tree.power_area.resize(n);
    if (normals) tree.normal.resize(n);
    // A gather: each sorted position is written once, in parallel.
    oneapi::tbb::parallel_for(
        oneapi::tbb::blocked_range<std::size_t>(0, n, 4096),
        [&](const oneapi::tbb::blocked_range<std::size_t>& range) {
            for (std::size_t s = range.begin(); s != range.end(); ++s) {
                const uint32_t i = keys[s].second;
                tree.order[s] = i;
                float a = pb.areas[i];
                tree.pos_rho2[s] = glm::vec4(pb.positions[i], float(a / kPi));
                tree.power_area[s] = glm::vec4(pb.irradiance[i] * a, a);
                if (normals)
                    tree.normal[s] = pb.normals.empty() ? glm::vec3(0) : pb.normals[i];
            }
        });
}

// Breadth-first construction: children are appended contiguously after
// their parents, so a reverse sweep is bottom-up. No recursion.
void split_nodes(const MortonKeys& keys, Tree& tree) {
    const std::size_t n = keys.size();
    tree.nodes.reserve(n / 2 + 8);
    Node root;
    root.first = 0;
    root.count = uint32_t(n);
    tree.nodes.push_back(root);
    for (std::size_t k = 0; k < tree.nodes.size(); ++k) {
        Node node = tree.nodes[k];
        if (node.count <= kLeafSize) continue;
        uint64_t a = keys[node.first].first, b = keys[node.first + node.count - 1].first;
        uint64_t diff = a ^ b;
        if (diff == 0) continue; // coincident at octree resolution: one big leaf
        int top = 63 - std::countl_zero(diff);
        int shift = (top / 3) * 3;
        uint32_t child_first = uint32_t(tree.nodes.size());
        uint32_t begin = node.first, end = node.first + node.count;
        uint32_t children = 0;
        for (uint32_t s = begin; s < end;) {
            uint64_t digit = (keys[s].first >> shift) & 7u;
            // Codes are sorted and share the bits above `shift`.
            auto it = std::upper_bound(
                keys.begin() + s, keys.begin() + end, digit,
                [shift](uint64_t d, const std::pair<uint64_t, uint32_t>& kv) {
                    return d < ((kv.first >> shift) & 7u);
                });
            uint32_t e = uint32_t(it - keys.begin());
            Node child;
            child.first = s;
            child.count = e - s;
            child.parent = uint32_t(k);
            tree.nodes.push_back(child);
            ++children;
            s = e;
        }
        tree.nodes[k].child_first = child_first;
        tree.nodes[k].child_count = children;
    }
}

// Moments from each node's own points (N log N work, in parallel, exact
// in double about the node centroid).
void compute_moments(Tree& tree) {
    tree.expansions.resize(tree.nodes.size());
    oneapi::tbb::parallel_for(std::size_t(0), tree.nodes.size(), [&](std::size_t k) {
        Node& node = tree.nodes[k];
        const uint32_t b = node.first, e = node.first + node.count;
        glm::dvec3 wsum_p(0), asum_p(0), psum(0);
        double wsum = 0, asum = 0;
        glm::dvec3 blo(std::numeric_limits<double>::max()),
            bhi(-std::numeric_limits<double>::max());
        float max_rho2 = 0;
        for (uint32_t s = b; s < e; ++s) {
            glm::dvec3 p(tree.pos_rho2[s]);
            const glm::vec4& pa = tree.power_area[s];
            // |power| weights keep the centroid inside the node even when
            // irradiance is negative or cancels.
            double w = std::abs(pa.x) + std::abs(pa.y) + std::abs(pa.z);
            wsum += w;
            wsum_p += w * p;
            asum += pa.w;
            asum_p += double(pa.w) * p;
            psum += p;
            blo = glm::min(blo, p);
            bhi = glm::max(bhi, p);
            max_rho2 = std::max(max_rho2, tree.pos_rho2[s].w);
        }
        glm::dvec3 c = wsum > 0   ? wsum_p / wsum
                       : asum > 0 ? asum_p / asum
                                  : psum / double(e - b);
        Expansion ex{};
        ex.c = glm::vec3(c);
        double phi[3] = {0, 0, 0}, aphi[3] = {0, 0, 0}, d[3][3] = {}, q[3][6] = {};
        double r2max = 0;
        for (uint32_t s = b; s < e; ++s) {
            glm::dvec3 dp = glm::dvec3(tree.pos_rho2[s]) - c;
            r2max = std::max(r2max, glm::dot(dp, dp));
            const glm::vec4& pa = tree.power_area[s];
            for (int ch = 0; ch < 3; ++ch) {
                double w = pa[ch];
                phi[ch] += w;
                aphi[ch] += std::abs(w);
                d[ch][0] += w * dp.x;
                d[ch][1] += w * dp.y;
                d[ch][2] += w * dp.z;
                q[ch][0] += w * dp.x * dp.x;
                q[ch][1] += w * dp.x * dp.y;
                q[ch][2] += w * dp.x * dp.z;
                q[ch][3] += w * dp.y * dp.y;
                q[ch][4] += w * dp.y * dp.z;
                q[ch][5] += w * dp.z * dp.z;
            }
        }
        for (int ch = 0; ch < 3; ++ch) {
            ex.phi[ch] = float(phi[ch]);
            ex.abs_phi[ch] = float(aphi[ch]);
            for (int i = 0; i < 3; ++i) ex.d[ch][i] = float(d[ch][i]);
            for (int i = 0; i < 6; ++i) ex.q[ch][i] = float(q[ch][i]);
        }
        tree.expansions[k] = ex;
        node.lo = glm::vec3(blo);
        node.hi = glm::vec3(bhi);
        node.area = float(asum);
        node.radius = float(std::sqrt(r2max));
        node.max_rho = std::sqrt(max_rho2);
    });
}

} // namespace

bool normals_needed(const DiffusionProblem& pb, const Tables& tables) {
    if (tables.channels.empty()) return true;
    float max_area = 0.0f;
    for (float a : pb.areas) max_area = std::max(max_area, a);
    // Tree::pos_rho2's w, rounded as sort_sources() rounds it (monotonic).
    const float max_rho2 = float(max_area / kPi);
    float min_core2 = std::numeric_limits<float>::max();
    for (const ChannelTable& t : tables.channels)
        min_core2 = std::min(min_core2, t.core2);
    // near_source(): rho^2 > kNearKappa2 * (q + near_core2) in double, with
    // float(q + near_core2) >= near_core2 >= min_core2 for q >= 0.
    return !(double(max_rho2) <= kNearKappa2 * double(min_core2));
}

Tree build_tree(const DiffusionProblem& pb, DiffusionProblem* release, bool normals) {
    Tree tree;
    MortonKeys keys = sorted_morton_keys(pb.positions);
    sort_sources(pb, keys, tree, normals);
    if (release) {
        // The tree holds sorted copies now.
        std::vector<glm::vec3>().swap(release->positions);
        std::vector<glm::vec3>().swap(release->normals);
        std::vector<float>().swap(release->areas);
    }
    split_nodes(keys, tree);
    MortonKeys().swap(keys); // before the moments allocate the expansions
    compute_moments(tree);
    return tree;
}

Tree sorted_sources(const DiffusionProblem& pb) {
    Tree tree;
    sort_sources(pb, sorted_morton_keys(pb.positions), tree);
    return tree;
}

std::vector<uint32_t> morton_order(const std::vector<glm::vec3>& positions) {
    MortonKeys keys = sorted_morton_keys(positions);
    std::vector<uint32_t> order(keys.size());
    for (std::size_t s = 0; s < keys.size(); ++s) order[s] = keys[s].second;
    return order;
}

} // namespace sss::diffusion_detail
