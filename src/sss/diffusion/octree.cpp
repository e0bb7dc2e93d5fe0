// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
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

// A point's Morton code and original index; sorted by both, so that the
// order does not depend on the thread count.
struct MortonKey {
    uint64_t code;
    uint32_t index;
    bool operator<(const MortonKey& o) const {
        return code < o.code || (code == o.code && index < o.index);
    }
};

// Sorts the keys: one radix pass on the 12 highest bits in which the codes
// differ (per chunk of the input, so the order within a bucket is the input's
// whatever the thread count), then each bucket on its own, in parallel. About
// twice as fast as a parallel quicksort of the whole array, whose upper levels
// move every key through memory (16M points: 0.54 s; issue 17).
void sort_keys(UninitVector<MortonKey>& keys) {
    const std::size_t n = keys.size();
    if (n < 2) return;
    uint64_t lo = keys[0].code, hi = keys[0].code;
    for (const MortonKey& k : keys) {
        lo = std::min(lo, k.code);
        hi = std::max(hi, k.code);
    }
    if (lo == hi) return; // one code: already in index order
    constexpr int kBits = 12;
    constexpr std::size_t kBuckets = std::size_t(1) << kBits;
    const int top = 63 - std::countl_zero(lo ^ hi); // highest differing bit
    const int shift = std::max(0, top + 1 - kBits);
    auto bucket_of = [&](uint64_t code) {
        return std::size_t((code >> shift) & (kBuckets - 1));
    };
    // Fixed chunks, not the thread count, decide where each key lands.
    constexpr std::size_t kChunk = std::size_t(1) << 18;
    const std::size_t chunks = (n + kChunk - 1) / kChunk;
    std::vector<std::size_t> offset(chunks * kBuckets, 0); // [chunk][bucket]
    oneapi::tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
        std::size_t* count = &offset[c * kBuckets];
        for (std::size_t i = c * kChunk; i < std::min(n, (c + 1) * kChunk); ++i)
            ++count[bucket_of(keys[i].code)];
    });
    std::vector<std::size_t> bucket_begin(kBuckets + 1, 0);
    std::size_t total = 0;
    for (std::size_t b = 0; b < kBuckets; ++b) {
        bucket_begin[b] = total;
        for (std::size_t c = 0; c < chunks; ++c) {
            const std::size_t count = offset[c * kBuckets + b];
            offset[c * kBuckets + b] = total;
            total += count;
        }
    }
    bucket_begin[kBuckets] = total;
    UninitVector<MortonKey> sorted(n);
    oneapi::tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
        std::size_t* next = &offset[c * kBuckets];
        for (std::size_t i = c * kChunk; i < std::min(n, (c + 1) * kChunk); ++i)
            sorted[next[bucket_of(keys[i].code)]++] = keys[i];
    });
    UninitVector<MortonKey>().swap(keys);
    oneapi::tbb::parallel_for(
        oneapi::tbb::blocked_range<std::size_t>(0, kBuckets, 16),
        [&](const oneapi::tbb::blocked_range<std::size_t>& range) {
            for (std::size_t b = range.begin(); b != range.end(); ++b) {
                auto first = sorted.begin() + std::ptrdiff_t(bucket_begin[b]);
                auto last = sorted.begin() + std::ptrdiff_t(bucket_begin[b + 1]);
                // Unique keys: the sorted order is the same whichever sort.
                if (last - first > (std::ptrdiff_t(1) << 16))
                    oneapi::tbb::parallel_sort(first, last);
                else
                    std::sort(first, last);
            }
        });
    keys.swap(sorted);
}

// Morton codes on a 2^21 grid over the points' bounding cube, sorted.
UninitVector<MortonKey> sorted_morton(const std::vector<glm::vec3>& positions) {
    const std::size_t n = positions.size();
    glm::dvec3 lo(std::numeric_limits<double>::max()),
        hi(-std::numeric_limits<double>::max());
    for (const glm::vec3& p : positions) {
        lo = glm::min(lo, glm::dvec3(p));
        hi = glm::max(hi, glm::dvec3(p));
    }
    double extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z, 1e-30});
    double scale = double((1u << 21) - 1) / extent;
    UninitVector<MortonKey> keys(n);
    oneapi::tbb::parallel_for(
        oneapi::tbb::blocked_range<std::size_t>(0, n, 4096),
        [&](const oneapi::tbb::blocked_range<std::size_t>& range) {
            for (std::size_t i = range.begin(); i != range.end(); ++i) {
                glm::dvec3 g = (glm::dvec3(positions[i]) - lo) * scale;
                uint64_t code = spread_bits(uint64_t(g.x)) |
                                spread_bits(uint64_t(g.y)) << 1 |
                                spread_bits(uint64_t(g.z)) << 2;
                keys[i] = {code, uint32_t(i)};
            }
        });
    sort_keys(keys);
    return keys;
}

// The distinct triples of profile indices, keyed by open addressing in a
// table at least twice their number.
class TripleIndex {
public:
    // The triple's index, added (as the next) if new.
    uint32_t find_or_add(const glm::u32vec3& t, std::vector<glm::u32vec3>& triples) {
        if (2 * (triples.size() + 1) > m_slots.size()) grow(triples);
        const std::size_t at = place(t, triples);
        if (m_slots[at] == kEmpty) {
            m_slots[at] = uint32_t(triples.size());
            triples.push_back(t);
        }
        return m_slots[at];
    }

private:
    static constexpr uint32_t kEmpty = UINT32_MAX;
    std::size_t place(const glm::u32vec3& t,
                      const std::vector<glm::u32vec3>& triples) const {
        const std::size_t mask = m_slots.size() - 1;
        const uint64_t h = (uint64_t(t.x) * 0x9E3779B97F4A7C15ull) ^
                           (uint64_t(t.y) * 0xC2B2AE3D27D4EB4Full) ^
                           (uint64_t(t.z) * 0x165667B19E3779F9ull);
        std::size_t at = std::size_t(h >> 32) & mask;
        while (m_slots[at] != kEmpty && triples[m_slots[at]] != t) at = (at + 1) & mask;
        return at;
    }
    void grow(const std::vector<glm::u32vec3>& triples) {
        m_slots.assign(std::max<std::size_t>(64, 2 * m_slots.size()), kEmpty);
        for (uint32_t k = 0; k < triples.size(); ++k)
            m_slots[place(triples[k], triples)] = k;
    }
    std::vector<uint32_t> m_slots;
};

// Per-point materials: tree.material and tree.materials. The triples are
// gathered in sorted order first (in parallel); the scan is then serial but
// reads them in one run, and a receiver with its predecessor's material (the
// usual case) costs one comparison.
void sort_materials(const DiffusionProblem& pb, const UninitVector<MortonKey>& keys,
                    Tree& tree) {
    const std::size_t n = keys.size();
    UninitVector<glm::u32vec3> sorted(n);
    oneapi::tbb::parallel_for(oneapi::tbb::blocked_range<std::size_t>(0, n, 4096),
                              [&](const oneapi::tbb::blocked_range<std::size_t>& range) {
                                  for (std::size_t s = range.begin(); s != range.end();
                                       ++s)
                                      sorted[s] = pb.profile_index[keys[s].index];
                              });
    tree.material.resize(n);
    TripleIndex index;
    for (std::size_t s = 0; s < n; ++s)
        tree.material[s] = s > 0 && sorted[s] == sorted[s - 1]
                               ? tree.material[s - 1]
                               : index.find_or_add(sorted[s], tree.materials);
}

// The sources in Morton order: tree.order and the sorted source arrays. With
// `release`, each of the problem's arrays is freed as soon as its last sorted
// copy is made, so that the problem and the tree are never held whole at once
// (the peak of ptfilter's memory otherwise, issue 17).
void sort_sources(const DiffusionProblem& pb, const UninitVector<MortonKey>& keys,
                  Tree& tree, bool normals, DiffusionProblem* release) {
    const std::size_t n = keys.size();
    // Gathers: each sorted position is written once, in parallel.
    auto gather = [&](auto&& body) {
        oneapi::tbb::parallel_for(
            oneapi::tbb::blocked_range<std::size_t>(0, n, 4096),
            [&](const oneapi::tbb::blocked_range<std::size_t>& range) {
                for (std::size_t s = range.begin(); s != range.end(); ++s)
                    body(s, keys[s].index);
            });
    };
    tree.order.resize(n);
    gather([&](std::size_t s, uint32_t i) { tree.order[s] = i; });
    tree.pos_rho2.resize(n);
    gather([&](std::size_t s, uint32_t i) {
        tree.pos_rho2[s] = glm::vec4(pb.positions[i], float(pb.areas[i] / kPi));
    });
    if (release) std::vector<glm::vec3>().swap(release->positions);
    if (normals) {
        tree.normal.resize(n);
        gather([&](std::size_t s, uint32_t i) {
            tree.normal[s] = pb.normals.empty() ? glm::vec3(0) : pb.normals[i];
        });
    }
    if (release) std::vector<glm::vec3>().swap(release->normals);
    tree.power_area.resize(n);
    gather([&](std::size_t s, uint32_t i) {
        const float a = pb.areas[i];
        tree.power_area[s] = glm::vec4(pb.irradiance[i] * a, a);
    });
    if (release) std::vector<float>().swap(release->areas);
    if (!pb.profile_index.empty()) sort_materials(pb, keys, tree);
    if (release) std::vector<glm::u32vec3>().swap(release->profile_index);
    if (!pb.receiver_gain.empty()) {
        tree.receiver_gain.resize(n);
        gather([&](std::size_t s, uint32_t i) {
            tree.receiver_gain[s] = pb.receiver_gain[i];
        });
    }
    if (release) std::vector<glm::vec3>().swap(release->receiver_gain);
}

// Breadth-first construction: children are appended contiguously after
// their parents, so a reverse sweep is bottom-up. No recursion.
void split_nodes(const UninitVector<MortonKey>& keys, Tree& tree) {
    const std::size_t n = keys.size();
    tree.nodes.reserve(n / 2 + 8);
    Node root;
    root.first = 0;
    root.count = uint32_t(n);
    tree.nodes.push_back(root);
    for (std::size_t k = 0; k < tree.nodes.size(); ++k) {
        Node node = tree.nodes[k];
        if (node.count <= kLeafSize) continue;
        uint64_t a = keys[node.first].code, b = keys[node.first + node.count - 1].code;
        uint64_t diff = a ^ b;
        if (diff == 0) continue; // coincident at octree resolution: one big leaf
        int top = 63 - std::countl_zero(diff);
        int shift = (top / 3) * 3;
        uint32_t child_first = uint32_t(tree.nodes.size());
        uint32_t begin = node.first, end = node.first + node.count;
        uint32_t children = 0;
        for (uint32_t s = begin; s < end;) {
            uint64_t digit = (keys[s].code >> shift) & 7u;
            // Codes are sorted and share the bits above `shift`.
            auto it = std::upper_bound(keys.begin() + s, keys.begin() + end, digit,
                                       [shift](uint64_t d, const MortonKey& key) {
                                           return d < ((key.code >> shift) & 7u);
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

// A node's moments per channel, summed in double about its centroid.
struct Moments {
    double phi[3] = {0, 0, 0}, aphi[3] = {0, 0, 0}, d[3][3] = {}, q[3][6] = {};
};

// The moments about c as the node's (float) expansion.
Expansion to_expansion(const glm::dvec3& c, const Moments& m) {
    Expansion ex{};
    ex.c = glm::vec3(c);
    for (int ch = 0; ch < 3; ++ch) {
        ex.phi[ch] = float(m.phi[ch]);
        ex.abs_phi[ch] = float(m.aphi[ch]);
        for (int i = 0; i < 3; ++i) ex.d[ch][i] = float(m.d[ch][i]);
        for (int i = 0; i < 6; ++i) ex.q[ch][i] = float(m.q[ch][i]);
    }
    return ex;
}

// A leaf's moments and bounds from its points, in double about its centroid.
void leaf_moments(Tree& tree, uint32_t k) {
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
    Moments m;
    double r2max = 0;
    for (uint32_t s = b; s < e; ++s) {
        glm::dvec3 dp = glm::dvec3(tree.pos_rho2[s]) - c;
        r2max = std::max(r2max, glm::dot(dp, dp));
        const glm::vec4& pa = tree.power_area[s];
        for (int ch = 0; ch < 3; ++ch) {
            double w = pa[ch];
            m.phi[ch] += w;
            m.aphi[ch] += std::abs(w);
            m.d[ch][0] += w * dp.x;
            m.d[ch][1] += w * dp.y;
            m.d[ch][2] += w * dp.z;
            m.q[ch][0] += w * dp.x * dp.x;
            m.q[ch][1] += w * dp.x * dp.y;
            m.q[ch][2] += w * dp.x * dp.z;
            m.q[ch][3] += w * dp.y * dp.y;
            m.q[ch][4] += w * dp.y * dp.z;
            m.q[ch][5] += w * dp.z * dp.z;
        }
    }
    tree.expansions[k] = to_expansion(c, m);
    node.lo = glm::vec3(blo);
    node.hi = glm::vec3(bhi);
    node.area = float(asum);
    node.radius = float(std::sqrt(r2max));
    node.max_rho = std::sqrt(max_rho2);
}

// An inner node's moments from its children's (the parallel axis theorem, in
// double): O(children), where summing its points again was O(points) per
// level (issue 17). The centroid weights are the children's: sum |power| is
// their abs_phi, then their area, then their point count, as leaf_moments()
// falls back. The radius is exact: the farthest point from the centroid.
void inner_moments(Tree& tree, uint32_t k) {
    Node& node = tree.nodes[k];
    const uint32_t c0 = node.child_first, c1 = node.child_first + node.child_count;
    double wsum = 0, asum = 0;
    glm::dvec3 wsum_p(0), asum_p(0), csum_p(0);
    glm::vec3 lo = tree.nodes[c0].lo, hi = tree.nodes[c0].hi;
    float max_rho = 0;
    for (uint32_t c = c0; c < c1; ++c) {
        const Node& child = tree.nodes[c];
        const Expansion& ce = tree.expansions[c];
        const glm::dvec3 cc(ce.c);
        const double w = double(ce.abs_phi[0]) + ce.abs_phi[1] + ce.abs_phi[2];
        wsum += w;
        wsum_p += w * cc;
        asum += child.area;
        asum_p += double(child.area) * cc;
        csum_p += double(child.count) * cc;
        lo = glm::min(lo, child.lo);
        hi = glm::max(hi, child.hi);
        max_rho = std::max(max_rho, child.max_rho);
    }
    const glm::dvec3 c = wsum > 0   ? wsum_p / wsum
                         : asum > 0 ? asum_p / asum
                                    : csum_p / double(node.count);
    Moments m;
    for (uint32_t ci = c0; ci < c1; ++ci) {
        const Expansion& ce = tree.expansions[ci];
        const glm::dvec3 sv = glm::dvec3(ce.c) - c;
        const double s[3] = {sv.x, sv.y, sv.z};
        for (int ch = 0; ch < 3; ++ch) {
            const double p = ce.phi[ch];
            const double dc[3] = {ce.d[ch][0], ce.d[ch][1], ce.d[ch][2]};
            m.phi[ch] += p;
            m.aphi[ch] += ce.abs_phi[ch];
            for (int a = 0; a < 3; ++a) m.d[ch][a] += dc[a] + p * s[a];
            // Q about c: sum w (dp + s)(dp + s)^T = Q_c + s D^T + D s^T + phi s s^T.
            int i = 0;
            for (int a = 0; a < 3; ++a)
                for (int bb = a; bb < 3; ++bb, ++i)
                    m.q[ch][i] +=
                        ce.q[ch][i] + s[a] * dc[bb] + dc[a] * s[bb] + p * s[a] * s[bb];
        }
    }
    double r2max = 0;
    for (uint32_t s = node.first; s < node.first + node.count; ++s) {
        const glm::dvec3 dp = glm::dvec3(tree.pos_rho2[s]) - c;
        r2max = std::max(r2max, glm::dot(dp, dp));
    }
    tree.expansions[k] = to_expansion(c, m);
    node.lo = lo;
    node.hi = hi;
    node.area = float(asum);
    node.radius = float(std::sqrt(r2max));
    node.max_rho = max_rho;
}

// Moments bottom-up, a level at a time: the breadth-first order keeps each
// depth contiguous, and a node's children are one level below it. In
// parallel within a level; no node depends on the thread count.
void compute_moments(Tree& tree) {
    tree.expansions.resize(tree.nodes.size());
    // [begin, end) of each depth: the next depth is the children of this one.
    std::vector<std::pair<uint32_t, uint32_t>> levels;
    for (uint32_t begin = 0, end = 1; begin < end;) {
        levels.push_back({begin, end});
        uint32_t next = end;
        for (uint32_t k = begin; k < end; ++k)
            if (tree.nodes[k].child_count > 0)
                next = tree.nodes[k].child_first + tree.nodes[k].child_count;
        begin = end;
        end = next;
    }
    for (std::size_t l = levels.size(); l-- > 0;) {
        oneapi::tbb::parallel_for(
            oneapi::tbb::blocked_range<uint32_t>(levels[l].first, levels[l].second, 256),
            [&](const oneapi::tbb::blocked_range<uint32_t>& range) {
                for (uint32_t k = range.begin(); k != range.end(); ++k) {
                    if (tree.nodes[k].child_count == 0)
                        leaf_moments(tree, k);
                    else
                        inner_moments(tree, k);
                }
            });
    }
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
    UninitVector<MortonKey> keys = sorted_morton(pb.positions);
    sort_sources(pb, keys, tree, normals, release);
    split_nodes(keys, tree);
    UninitVector<MortonKey>().swap(keys); // before the moments allocate the expansions
    compute_moments(tree);
    return tree;
}

Tree sorted_sources(const DiffusionProblem& pb) {
    Tree tree;
    sort_sources(pb, sorted_morton(pb.positions), tree, true, nullptr);
    return tree;
}

std::vector<uint32_t> morton_order(const std::vector<glm::vec3>& positions) {
    const UninitVector<MortonKey> keys = sorted_morton(positions);
    std::vector<uint32_t> order(keys.size());
    for (std::size_t s = 0; s < keys.size(); ++s) order[s] = keys[s].index;
    return order;
}

} // namespace sss::diffusion_detail
