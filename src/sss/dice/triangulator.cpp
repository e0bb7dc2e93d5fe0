// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file triangulator.cpp
/// Triangulation of a polygon with holes: the loops are linked into rings,
/// every hole is bridged to the outer ring (rightmost holes first), and ears
/// are clipped best first, with a fallback for collinear, duplicate or
/// self-intersecting vertices.
///
/// Cost: every vertex is classified (convex or not, an ear or not) once at
/// the start and again each time a neighbour is clipped, so a polygon of n
/// vertices needs O(n) ear tests and O(n log n) priority-queue work. An ear
/// test looks only at the non-convex vertices inside the ear's box, found
/// in a k-d tree (BoxIndex); holes find their bridges through k-d trees of
/// the edges and vertices. The classic scan of the whole ring per ear test
/// made a 64000-vertex polygon take 40 s. Polygons of at most kLinear
/// vertices scan instead: the same answers without building trees.
///
/// Quality: the ear with the shortest longest side goes first. A convex
/// polygon of n vertices loses every other vertex per round, so its
/// triangles double in size level by level (about log2 n sizes) instead of
/// a fan of n slivers across the whole polygon, which the dicer would cut
/// into n x (diameter / spacing) needles.

#include "triangulator.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

namespace sss::detail {

namespace {

/// Polygons of at most this many vertices (bridges included) are clipped
/// with linear scans: cheaper than building the trees.
constexpr int kLinear = 32;
/// Boxes per k-d tree leaf.
constexpr int kLeafBoxes = 4;

double orient(const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c) {
    return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

/// Inclusive point-in-triangle test for a counter-clockwise triangle.
bool in_ccw_triangle(const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c,
                     const glm::dvec2& p) {
    return orient(a, b, p) >= 0.0 && orient(b, c, p) >= 0.0 && orient(c, a, p) >= 0.0;
}

/// Inclusive point-in-triangle test for either winding.
bool in_triangle(const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c,
                 const glm::dvec2& p) {
    const double d1 = orient(a, b, p), d2 = orient(b, c, p), d3 = orient(c, a, p);
    const bool neg = d1 < 0.0 || d2 < 0.0 || d3 < 0.0;
    const bool pos = d1 > 0.0 || d2 > 0.0 || d3 > 0.0;
    return !(neg && pos);
}

BoxIndex::Box box_of(const glm::dvec2& a, const glm::dvec2& b) {
    return {glm::min(a, b), glm::max(a, b)};
}

bool overlaps(const BoxIndex::Box& x, const BoxIndex::Box& y) {
    return x.lo.x <= y.hi.x && y.lo.x <= x.hi.x && x.lo.y <= y.hi.y && y.lo.y <= x.hi.y;
}

/// Whether the box lies strictly to the right of the line a -> b (so
/// outside a counter-clockwise triangle with that edge).
bool right_of(const BoxIndex::Box& box, const glm::dvec2& a, const glm::dvec2& b) {
    return orient(a, b, box.lo) < 0.0 && orient(a, b, box.hi) < 0.0 &&
           orient(a, b, {box.lo.x, box.hi.y}) < 0.0 &&
           orient(a, b, {box.hi.x, box.lo.y}) < 0.0;
}

/// Priority-queue order: smallest key first, then lowest node.
bool later(double ka, int na, double kb, int nb) {
    return ka > kb || (ka == kb && na > nb);
}

} // namespace

// ---------------------------------------------------------------------------
// BoxIndex

void BoxIndex::reset(int id_limit) {
    m_levels.clear();
    m_where.assign(static_cast<std::size_t>(std::max(id_limit, 0)), {-1, -1});
}

bool BoxIndex::contains(int id) const {
    return id >= 0 && static_cast<std::size_t>(id) < m_where.size() &&
           m_where[static_cast<std::size_t>(id)].first >= 0;
}

void BoxIndex::insert(const Box& box, int id) {
    m_scratch.clear();
    m_scratch.emplace_back(box, id);
    add_level(m_scratch);
}

void BoxIndex::insert(const std::vector<std::pair<Box, int>>& items) {
    if (items.empty()) return;
    m_scratch = items;
    add_level(m_scratch);
}

void BoxIndex::add_level(std::vector<std::pair<Box, int>>& items) {
    for (const auto& [box, id] : items)
        if (static_cast<std::size_t>(id) >= m_where.size())
            m_where.resize(static_cast<std::size_t>(id) + 1, {-1, -1});
    // A binary counter: merge the levels below the first empty one that can
    // hold them all.
    std::size_t k = 0;
    for (;; ++k) {
        if (k == m_levels.size()) m_levels.emplace_back();
        Tree& t = m_levels[k];
        if (t.live == 0 && (std::size_t(1) << k) >= items.size()) break;
        for (std::size_t s = 0; s < t.ids.size(); ++s)
            if (t.ids[s] >= 0) items.emplace_back(t.boxes[s], t.ids[s]);
        t = Tree{};
    }
    Tree& tree = m_levels[k];
    build(tree, items);
    for (std::size_t s = 0; s < tree.ids.size(); ++s)
        m_where[static_cast<std::size_t>(tree.ids[s])] = {static_cast<int>(k),
                                                          static_cast<int>(s)};
}

void BoxIndex::build(Tree& tree, std::vector<std::pair<Box, int>>& items) {
    tree = Tree{};
    const int n = static_cast<int>(items.size());
    tree.nodes.reserve(static_cast<std::size_t>(2 * (n / kLeafBoxes + 1)));
    tree.leaf.resize(items.size());
    build_node(tree, items, 0, n, -1);
    tree.boxes.resize(items.size());
    tree.ids.resize(items.size());
    for (std::size_t s = 0; s < items.size(); ++s) {
        tree.boxes[s] = items[s].first;
        tree.ids[s] = items[s].second;
    }
    tree.live = n;
}

int BoxIndex::build_node(Tree& tree, std::vector<std::pair<Box, int>>& items, int begin,
                         int end, int parent) {
    const int index = static_cast<int>(tree.nodes.size());
    tree.nodes.emplace_back();
    Node node;
    node.begin = begin;
    node.end = end;
    node.parent = parent;
    node.live = end - begin;
    node.box = items[static_cast<std::size_t>(begin)].first;
    glm::dvec2 clo = 0.5 * (node.box.lo + node.box.hi), chi = clo;
    for (int s = begin; s < end; ++s) {
        const Box& b = items[static_cast<std::size_t>(s)].first;
        node.box.lo = glm::min(node.box.lo, b.lo);
        node.box.hi = glm::max(node.box.hi, b.hi);
        const glm::dvec2 c = 0.5 * (b.lo + b.hi);
        clo = glm::min(clo, c);
        chi = glm::max(chi, c);
    }
    if (end - begin > kLeafBoxes) {
        const int axis = chi.x - clo.x >= chi.y - clo.y ? 0 : 1;
        const int mid = begin + (end - begin) / 2;
        std::nth_element(items.begin() + begin, items.begin() + mid, items.begin() + end,
                         [axis](const auto& a, const auto& b) {
                             const double ca = a.first.lo[axis] + a.first.hi[axis];
                             const double cb = b.first.lo[axis] + b.first.hi[axis];
                             return ca < cb || (ca == cb && a.second < b.second);
                         });
        node.left = build_node(tree, items, begin, mid, index);
        node.right = build_node(tree, items, mid, end, index);
    } else {
        for (int s = begin; s < end; ++s) tree.leaf[static_cast<std::size_t>(s)] = index;
    }
    tree.nodes[static_cast<std::size_t>(index)] = node;
    return index;
}

void BoxIndex::erase(int id) {
    auto& where = m_where[static_cast<std::size_t>(id)];
    Tree& tree = m_levels[static_cast<std::size_t>(where.first)];
    const auto slot = static_cast<std::size_t>(where.second);
    tree.ids[slot] = -1;
    for (int n = tree.leaf[slot]; n >= 0;
         n = tree.nodes[static_cast<std::size_t>(n)].parent)
        --tree.nodes[static_cast<std::size_t>(n)].live;
    if (--tree.live == 0) tree = Tree{};
    where = {-1, -1};
}

// ---------------------------------------------------------------------------
// Rings and holes

void Triangulator::run(const std::vector<glm::dvec2>& points,
                       const std::vector<int>& loop_sizes,
                       std::vector<std::array<int, 3>>& out) {
    m_nodes.clear();
    m_holes.clear();
    glm::dvec2 lo(std::numeric_limits<double>::max()),
        hi(-std::numeric_limits<double>::max());
    for (const glm::dvec2& p : points) {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    const double extent = glm::length(hi - lo);
    m_tolerance = 1e-12 * extent * extent;
    m_loop_active.assign(loop_sizes.size(), 0);

    const int outer = make_ring(points, 0, loop_sizes[0], true, 0);
    if (outer < 0) return;
    m_loop_active[0] = 1;
    int start = loop_sizes[0];
    for (std::size_t l = 1; l < loop_sizes.size(); ++l) {
        const int ring =
            make_ring(points, start, loop_sizes[l], false, static_cast<int>(l));
        start += loop_sizes[l];
        if (ring < 0) continue; // zero-area hole: removes nothing
        int right = ring;
        for (int p = m_nodes[ring].next; p != ring; p = m_nodes[p].next)
            if (m_nodes[p].p.x > m_nodes[right].p.x ||
                (m_nodes[p].p.x == m_nodes[right].p.x &&
                 m_nodes[p].p.y < m_nodes[right].p.y))
                right = p;
        m_holes.emplace_back(m_nodes[right].p.x, right);
    }
    // Each bridge adds two nodes.
    m_indexed = m_nodes.size() + 2 * m_holes.size() > static_cast<std::size_t>(kLinear);
    if (!m_holes.empty()) bridge_holes();
    clip_ears(outer, out);
}

/// Links one loop into a ring wound counter-clockwise (`ccw`) or clockwise.
/// Returns a node of the ring, or -1 for a loop with zero area.
int Triangulator::make_ring(const std::vector<glm::dvec2>& points, int first, int count,
                            bool ccw, int loop) {
    double area = 0.0;
    for (int i = 0; i < count; ++i)
        area += orient(points[first], points[first + i], points[first + (i + 1) % count]);
    if (area == 0.0) return -1;
    const bool reverse = (area > 0.0) != ccw;
    const int base = static_cast<int>(m_nodes.size());
    for (int i = 0; i < count; ++i) {
        const int k = reverse ? count - 1 - i : i;
        m_nodes.push_back({points[first + k], first + k, base + (i + count - 1) % count,
                           base + (i + 1) % count, loop, 0u, true, false});
    }
    return base;
}

/// True when the direction from node a towards p leaves a into the
/// polygon's interior (between its two edges).
bool Triangulator::locally_inside(int a, const glm::dvec2& p) const {
    const glm::dvec2 &pa = pos(prev(a)), &va = pos(a), &na = pos(next(a));
    if (orient(pa, va, na) >= 0.0)
        return orient(pa, va, p) >= 0.0 && orient(va, na, p) >= 0.0;
    return orient(pa, va, p) >= 0.0 || orient(va, na, p) >= 0.0;
}

void Triangulator::bridge_holes() {
    // Rightmost holes first, so each bridge sees the holes already joined.
    std::sort(m_holes.begin(), m_holes.end(), [](const auto& a, const auto& b) {
        return a.first > b.first || (a.first == b.first && a.second < b.second);
    });
    if (m_indexed) {
        const int capacity = static_cast<int>(m_nodes.size() + 2 * m_holes.size());
        m_points.reset(capacity);
        m_edges.reset(2 * capacity);
        m_edge_owner.clear();
        m_node_edge.assign(static_cast<std::size_t>(capacity), -1);
        m_items.clear();
        for (int n = 0; n < static_cast<int>(m_nodes.size()); ++n)
            m_items.emplace_back(box_of(pos(n), pos(n)), n);
        m_points.insert(m_items);
        m_items.clear();
        for (int n = 0; n < static_cast<int>(m_nodes.size()); ++n) {
            m_items.emplace_back(box_of(pos(n), pos(next(n))), n);
            m_edge_owner.push_back(n);
            m_node_edge[static_cast<std::size_t>(n)] = n;
        }
        m_edges.insert(m_items);
    }
    for (const auto& [x, hole] : m_holes) {
        const int bridge = find_bridge(hole);
        // A hole outside the outer loop cannot be joined: it is ignored.
        if (bridge < 0) continue;
        m_loop_active[static_cast<std::size_t>(m_nodes[hole].loop)] = 1;
        splice(bridge, hole);
    }
}

/// The node of the active rings that the hole's rightmost node `hole` can
/// be joined to: cast a ray towards +x, take the nearest edge hit, then the
/// visible vertex closest in angle to the ray (the standard hole-bridging
/// method). -1 when the ray meets no edge.
int Triangulator::find_bridge(int hole) const {
    const glm::dvec2 h = pos(hole);
    int edge = -1;
    double hit_x = std::numeric_limits<double>::infinity();
    const auto try_edge = [&](int p) {
        if (!m_loop_active[static_cast<std::size_t>(m_nodes[p].loop)]) return;
        const glm::dvec2 &a = pos(p), &b = pos(next(p));
        // The ray leaves the interior through an upward edge (CCW ring).
        if (a.y <= h.y && b.y >= h.y && a.y != b.y) {
            const double x = a.x + (h.y - a.y) * (b.x - a.x) / (b.y - a.y);
            if (x >= h.x && (x < hit_x || (x == hit_x && p < edge))) {
                hit_x = x;
                edge = p;
            }
        }
    };
    if (m_indexed) {
        m_edges.query(
            [&](const BoxIndex::Box& b) {
                return b.hi.x >= h.x && b.lo.x <= hit_x && b.lo.y <= h.y && b.hi.y >= h.y;
            },
            [&](int id) { try_edge(m_edge_owner[static_cast<std::size_t>(id)]); });
    } else {
        for (int p = 0; p < static_cast<int>(m_nodes.size()); ++p) try_edge(p);
    }
    if (edge < 0) return -1;
    // The hit vertex, or else the hit edge's end point further along +x.
    // Either may have duplicates from earlier bridges: the search below
    // picks the copy whose sector the bridge enters.
    const glm::dvec2 hit(hit_x, h.y);
    const int candidate = pos(edge) == hit                  ? edge
                          : pos(next(edge)) == hit          ? next(edge)
                          : pos(edge).x > pos(next(edge)).x ? edge
                                                            : next(edge);
    const glm::dvec2 c = pos(candidate);

    int best = -1;
    double best_tan = std::numeric_limits<double>::infinity(), best_dist = best_tan;
    const auto try_node = [&](int p) {
        if (!m_loop_active[static_cast<std::size_t>(m_nodes[p].loop)]) return;
        const glm::dvec2 q = pos(p);
        if ((q == c || in_triangle(h, hit, c, q)) && locally_inside(p, h)) {
            const double dx = q.x - h.x;
            const double tan = q == h     ? 0.0
                               : dx > 0.0 ? std::abs(q.y - h.y) / dx
                                          : std::numeric_limits<double>::infinity();
            const double dist = glm::length(q - h);
            if (tan < best_tan || (tan == best_tan && dist < best_dist) ||
                (tan == best_tan && dist == best_dist && p < best)) {
                best = p;
                best_tan = tan;
                best_dist = dist;
            }
        }
    };
    if (m_indexed) {
        const BoxIndex::Box reach{glm::min(glm::min(h, hit), c),
                                  glm::max(glm::max(h, hit), c)};
        m_points.query([&](const BoxIndex::Box& b) { return overlaps(b, reach); },
                       try_node);
    } else {
        for (int p = 0; p < static_cast<int>(m_nodes.size()); ++p) try_node(p);
    }
    return best >= 0 ? best : candidate;
}

/// Joins the hole ring at `hole` into the outer ring at `bridge` with two
/// coincident edges (the bridge is walked in both directions).
void Triangulator::splice(int bridge, int hole) {
    const int bridge2 = static_cast<int>(m_nodes.size());
    m_nodes.push_back(m_nodes[bridge]);
    const int hole2 = bridge2 + 1;
    m_nodes.push_back(m_nodes[hole]);
    const int after = next(bridge), before = prev(hole);
    m_nodes[bridge].next = hole;
    m_nodes[hole].prev = bridge;
    m_nodes[before].next = hole2;
    m_nodes[hole2].prev = before;
    m_nodes[hole2].next = bridge2;
    m_nodes[bridge2].prev = hole2;
    m_nodes[bridge2].next = after;
    m_nodes[after].prev = bridge2;
    if (!m_indexed) return;
    // The copies are vertices too; bridge -> after is now bridge2's edge,
    // and the bridge is two new edges (bridge -> hole, hole2 -> bridge2).
    m_points.insert(box_of(pos(bridge2), pos(bridge2)), bridge2);
    m_points.insert(box_of(pos(hole2), pos(hole2)), hole2);
    if (m_node_edge.size() < m_nodes.size()) m_node_edge.resize(m_nodes.size(), -1);
    const int moved = m_node_edge[static_cast<std::size_t>(bridge)];
    m_edge_owner[static_cast<std::size_t>(moved)] = bridge2;
    m_node_edge[static_cast<std::size_t>(bridge2)] = moved;
    for (const int owner : {bridge, hole2}) {
        const int id = static_cast<int>(m_edge_owner.size());
        m_edge_owner.push_back(owner);
        m_node_edge[static_cast<std::size_t>(owner)] = id;
        m_edges.insert(box_of(pos(owner), pos(next(owner))), id);
    }
}

// ---------------------------------------------------------------------------
// Ear clipping

void Triangulator::unlink(int n) {
    m_nodes[prev(n)].next = next(n);
    m_nodes[next(n)].prev = prev(n);
}

double Triangulator::turn(int n) const {
    return orient(pos(prev(n)), pos(n), pos(next(n)));
}

/// Whether convex node b is an ear: no non-convex node inside its triangle
/// (bridge duplicates of its corners excepted).
bool Triangulator::is_ear(int b) const {
    const int a = prev(b), c = next(b);
    const glm::dvec2 &pa = pos(a), &pb = pos(b), &pc = pos(c);
    if (orient(pa, pb, pc) <= 0.0) return false;
    bool blocked = false;
    const auto test = [&](int p) {
        if (p == a || p == b || p == c || !m_nodes[p].reflex) return;
        const glm::dvec2& q = pos(p);
        // Bridge duplicates share a position with an ear corner: not inside.
        if (q == pa || q == pb || q == pc) return;
        if (in_ccw_triangle(pa, pb, pc, q)) blocked = true;
    };
    if (m_indexed) {
        const BoxIndex::Box tri{glm::min(glm::min(pa, pb), pc),
                                glm::max(glm::max(pa, pb), pc)};
        m_reflex.query(
            [&](const BoxIndex::Box& box) {
                return !blocked && overlaps(box, tri) && !right_of(box, pa, pb) &&
                       !right_of(box, pb, pc) && !right_of(box, pc, pa);
            },
            test);
    } else {
        for (int p = next(c); p != a && !blocked; p = next(p)) test(p);
    }
    return !blocked;
}

/// After a node's neighbours changed (or at the start): its convexity (and
/// its place in m_reflex), and fresh candidates in the queues.
void Triangulator::classify(int n) {
    Node& node = m_nodes[n];
    ++node.stamp;
    const double t = turn(n);
    const bool reflex = !(t > 0.0);
    if (reflex != node.reflex) {
        node.reflex = reflex;
        if (reflex) ++m_epoch;
        if (m_indexed) {
            if (reflex)
                m_reflex.insert(box_of(pos(n), pos(n)), n);
            else
                m_reflex.erase(n);
        }
    }
    const auto push = [&](std::vector<Entry>& heap, double key) {
        heap.push_back({key, n, node.stamp, m_epoch});
        std::push_heap(heap.begin(), heap.end(), [](const Entry& x, const Entry& y) {
            return later(x.key, x.node, y.key, y.node);
        });
    };
    if (std::abs(t) <= m_tolerance) push(m_flat, static_cast<double>(n));
    if (t > 0.0) {
        push(m_convex, -t);
        if (is_ear(n)) {
            const glm::dvec2 &a = pos(prev(n)), &b = pos(n), &c = pos(next(n));
            const double longest = std::max(
                {glm::dot(b - a, b - a), glm::dot(c - b, c - b), glm::dot(a - c, a - c)});
            push(m_ears, longest);
        }
    }
}

void Triangulator::emit(int b, std::vector<std::array<int, 3>>& out) const {
    out.push_back({m_nodes[prev(b)].index, m_nodes[b].index, m_nodes[next(b)].index});
}

/// Removes node b from the ring (emitting its triangle when
/// `with_triangle`) and reclassifies its neighbours.
void Triangulator::clip(int b, bool with_triangle, std::vector<std::array<int, 3>>& out) {
    if (with_triangle) emit(b, out);
    const int a = prev(b), c = next(b);
    unlink(b);
    m_nodes[b].alive = false;
    if (m_nodes[b].reflex && m_indexed) m_reflex.erase(b);
    --m_count;
    if (m_any == b) m_any = c;
    classify(a);
    classify(c);
}

/// Pops the best valid entry of a queue: a live node whose neighbours have
/// not changed since it was pushed (ears: and still an ear, retested when
/// some node became non-convex meanwhile; flat nodes: still flat).
bool Triangulator::pop(std::vector<Entry>& heap, Entry& e) const {
    const auto order = [](const Entry& x, const Entry& y) {
        return later(x.key, x.node, y.key, y.node);
    };
    while (!heap.empty()) {
        std::pop_heap(heap.begin(), heap.end(), order);
        e = heap.back();
        heap.pop_back();
        const Node& node = m_nodes[e.node];
        if (!node.alive || node.stamp != e.stamp) continue;
        if (&heap == &m_ears && e.epoch != m_epoch && !is_ear(e.node)) continue;
        if (&heap == &m_flat && !(std::abs(turn(e.node)) <= m_tolerance)) continue;
        if (&heap == &m_convex && !(turn(e.node) > 0.0)) continue;
        return true;
    }
    return false;
}

/// When no ear is left (collinear or duplicate vertices, or a
/// self-intersecting loop): drop a degenerate vertex if there is one (it
/// encloses no area); else look for ears the queue missed (a
/// self-intersecting loop breaks the rule that only a clipped ear's
/// neighbours change), within a budget of ear tests; else clip the most
/// convex vertex anyway (or, with none convex, any). False when nothing
/// could be done.
bool Triangulator::fallback(std::vector<std::array<int, 3>>& out) {
    Entry e;
    if (pop(m_flat, e)) {
        clip(e.node, false, out);
        return true;
    }
    if (m_rescan_budget >= m_count) {
        m_rescan_budget -= m_count;
        bool found = false;
        int p = m_any;
        for (int k = 0; k < m_count; ++k, p = next(p)) {
            classify(p);
            found = found || !m_ears.empty();
        }
        if (found) return true;
    }
    if (pop(m_convex, e)) {
        clip(e.node, true, out);
        return true;
    }
    if (m_any < 0 || m_count < 3) return false;
    clip(m_any, true, out);
    return true;
}

void Triangulator::clip_ears(int start, std::vector<std::array<int, 3>>& out) {
    m_count = 1;
    for (int p = next(start); p != start; p = next(p)) ++m_count;
    m_any = start;
    if (m_count < 3) return;
    m_ears.clear();
    m_convex.clear();
    m_flat.clear();
    m_epoch = 0;
    // Convexity first (the ear tests need every non-convex node), then the
    // candidates.
    int p = start;
    do {
        m_nodes[p].reflex = !(turn(p) > 0.0);
        p = next(p);
    } while (p != start);
    if (m_indexed) {
        m_reflex.reset(static_cast<int>(m_nodes.size()));
        m_items.clear();
        p = start;
        do {
            if (m_nodes[p].reflex) m_items.emplace_back(box_of(pos(p), pos(p)), p);
            p = next(p);
        } while (p != start);
        m_reflex.insert(m_items);
    }
    p = start;
    do {
        classify(p);
        p = next(p);
    } while (p != start);
    m_rescan_budget = 4L * m_count + 64;

    while (m_count > 3) {
        Entry e;
        if (pop(m_ears, e)) {
            clip(e.node, true, out);
            continue;
        }
        if (!fallback(out)) break;
    }
    if (m_count == 3) emit(m_any, out);
}

} // namespace sss::detail
