// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file triangulator.h
/// Internal: triangulation of one planar polygon with holes
/// (triangulator.cpp), used by the polygon dicer for every face that is not
/// a triangle or a convex quad.

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include <glm/vec2.hpp>

namespace sss::detail {

/// A set of boxes in the plane, each with an id: bulk build, insert, erase,
/// and visiting the live ones that a query reaches. The logarithmic method:
/// static k-d trees (median splits of the box centres) of capacities 2^k,
/// merged like a binary counter on insertion, so that a build or an insert
/// costs O(log^2 n) amortised and a query visits O(log^2 n) nodes for
/// ordinary layouts. Erased boxes are skipped through live counts per node
/// and dropped at the next merge.
class BoxIndex {
public:
    struct Box {
        glm::dvec2 lo, hi;
    };

    /// Forgets everything; ids of the next use may be any in [0, id_limit).
    void reset(int id_limit);
    /// Adds boxes (ids unique and not present).
    void insert(const std::vector<std::pair<Box, int>>& items);
    void insert(const Box& box, int id);
    /// Removes a present id.
    void erase(int id);
    bool contains(int id) const;

    /// Calls visit(id) for every live box of a node for which reach(node box)
    /// holds, down from each tree's root; reach may depend on what visit
    /// found so far. Children are visited lower x first.
    template <class Reach, class Visit>
    void query(Reach&& reach, Visit&& visit) const;

private:
    struct Node {
        Box box;
        int begin = 0, end = 0; ///< slots of the tree's items
        int left = -1, right = -1, parent = -1;
        int live = 0;
    };
    struct Tree {
        std::vector<Box> boxes; ///< per slot
        std::vector<int> ids;   ///< per slot; -1 once erased
        std::vector<int> leaf;  ///< per slot: its leaf node
        std::vector<Node> nodes;
        int live = 0;
    };

    void build(Tree& tree, std::vector<std::pair<Box, int>>& items);
    int build_node(Tree& tree, std::vector<std::pair<Box, int>>& items, int begin,
                   int end, int parent);
    void add_level(std::vector<std::pair<Box, int>>& items);

    std::vector<Tree> m_levels;               ///< level k: empty or about 2^k boxes
    std::vector<std::pair<int, int>> m_where; ///< per id: (level, slot), level -1: absent
    std::vector<std::pair<Box, int>> m_scratch;
    mutable std::vector<int> m_stack; ///< query's traversal stack
};

/// Triangulator of one polygon with holes: ear clipping that always clips
/// the best ear (the one with the shortest longest side), found through a
/// priority queue, with the ears tested against a spatial index of the
/// non-convex vertices; holes are joined to the outer loop by bridges
/// (rightmost hole first), found through spatial indexes of the edges and
/// vertices. O(n log n) for simple polygons with few holes; clipping the
/// smallest ears first halves a many-sided convex polygon level by level
/// instead of fanning it into n slivers. Keeps its buffers between
/// polygons, so a mesh of many faces allocates nothing per face.
class Triangulator {
public:
    /// Triangulates the polygon whose loops are consecutive runs of `points`
    /// (their sizes in `loop_sizes`; the first loop is the outer boundary, the
    /// others are holes), in any winding. Appends counter-clockwise triangles
    /// of indices into `points`. Zero-area loops are skipped (an outer one
    /// gives nothing); holes outside the outer loop are ignored. Collinear,
    /// duplicate and self-intersecting vertices never stop it: a vertex that
    /// encloses no area is dropped, and when no ear is left (a
    /// self-intersecting loop) the most convex vertex is clipped anyway.
    void run(const std::vector<glm::dvec2>& points, const std::vector<int>& loop_sizes,
             std::vector<std::array<int, 3>>& out);

private:
    struct Node {
        glm::dvec2 p;
        int index;
        int prev;
        int next;
        int loop;       ///< 0: the outer loop; k: hole k (bridges belong to 0)
        uint32_t stamp; ///< bumped when the node's neighbours change
        bool alive;     ///< not clipped or dropped
        bool reflex;    ///< in m_reflex (orient(prev, p, next) <= 0)
    };
    /// A candidate in a priority queue: (key, node, the node's stamp then).
    struct Entry {
        double key;
        int node;
        uint32_t stamp;
        uint32_t epoch; ///< m_epoch then (ears: retested when it changed)
    };

    // The steps, in triangulator.cpp.
    int make_ring(const std::vector<glm::dvec2>& points, int first, int count, bool ccw,
                  int loop);
    bool locally_inside(int a, const glm::dvec2& p) const;
    void bridge_holes();
    int find_bridge(int hole) const;
    void splice(int bridge, int hole);
    void unlink(int n);
    double turn(int n) const;
    bool is_ear(int b) const;
    void classify(int n);
    void emit(int b, std::vector<std::array<int, 3>>& out) const;
    void clip(int b, bool with_triangle, std::vector<std::array<int, 3>>& out);
    bool pop(std::vector<Entry>& heap, Entry& e) const;
    bool fallback(std::vector<std::array<int, 3>>& out);
    void clip_ears(int start, std::vector<std::array<int, 3>>& out);

    const glm::dvec2& pos(int n) const { return m_nodes[n].p; }
    int prev(int n) const { return m_nodes[n].prev; }
    int next(int n) const { return m_nodes[n].next; }

    std::vector<Node> m_nodes;
    std::vector<std::pair<double, int>> m_holes;
    std::vector<char> m_loop_active; ///< per loop: joined to the outer loop
    double m_tolerance = 0.0;
    bool m_indexed = false; ///< spatial indexes (else linear scans: small polygons)
    int m_count = 0;        ///< nodes left in the ring being clipped
    int m_any = -1;         ///< some live node of that ring
    BoxIndex m_reflex;      ///< non-convex nodes, while clipping
    BoxIndex m_points;      ///< every node of an active loop, while bridging
    BoxIndex m_edges;       ///< id: the node starting the edge, while bridging
    std::vector<int> m_edge_owner; ///< per edge id: the node whose edge it is now
    std::vector<int> m_node_edge;  ///< per node: the id of its edge
    std::vector<Entry> m_ears;     ///< ears, best (smallest key) first
    std::vector<Entry> m_convex;   ///< convex nodes, most convex first
    std::vector<Entry> m_flat;     ///< possibly degenerate nodes, lowest index first
    std::vector<std::pair<BoxIndex::Box, int>> m_items;
    long m_rescan_budget = 0; ///< ear tests left for rescans after a failure
    uint32_t m_epoch = 0;     ///< bumped when a node becomes non-convex
};

} // namespace sss::detail

// ---------------------------------------------------------------------------
// BoxIndex::query (a template: the callers' lambdas inline).

namespace sss::detail {

template <class Reach, class Visit>
void BoxIndex::query(Reach&& reach, Visit&& visit) const {
    std::vector<int>& stack = m_stack;
    for (const Tree& tree : m_levels) {
        if (tree.live == 0) continue;
        stack.clear();
        stack.push_back(0);
        while (!stack.empty()) {
            const Node& node = tree.nodes[static_cast<std::size_t>(stack.back())];
            stack.pop_back();
            if (node.live == 0 || !reach(node.box)) continue;
            if (node.left < 0) {
                for (int s = node.begin; s < node.end; ++s)
                    if (tree.ids[static_cast<std::size_t>(s)] >= 0)
                        visit(tree.ids[static_cast<std::size_t>(s)]);
                continue;
            }
            const Node& l = tree.nodes[static_cast<std::size_t>(node.left)];
            const Node& r = tree.nodes[static_cast<std::size_t>(node.right)];
            // Lower x popped first.
            const bool left_first = l.box.lo.x <= r.box.lo.x;
            stack.push_back(left_first ? node.right : node.left);
            stack.push_back(left_first ? node.left : node.right);
        }
    }
}

} // namespace sss::detail
