/// \file triangulator.cpp
/// Ear clipping of a polygon with holes: the loops are linked into rings,
/// every hole is bridged to the outer ring (rightmost holes first), and ears
/// are clipped, with a fallback for collinear, duplicate or
/// self-intersecting vertices.

#include "triangulator.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

namespace sss::detail {

namespace {

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

} // namespace

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

    const int outer = make_ring(points, 0, loop_sizes[0], true);
    if (outer < 0) return;
    int start = loop_sizes[0];
    for (std::size_t l = 1; l < loop_sizes.size(); ++l) {
        const int ring = make_ring(points, start, loop_sizes[l], false);
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
    // Rightmost holes first, so each bridge sees the holes already joined.
    std::sort(m_holes.begin(), m_holes.end(),
              [](const auto& a, const auto& b) { return a.first > b.first; });
    for (const auto& [x, hole] : m_holes) {
        const int bridge = find_bridge(hole, outer);
        if (bridge >= 0) splice(bridge, hole);
        // A hole outside the outer loop cannot be joined: it is ignored.
    }
    clip_ears(outer, out);
}

/// Links one loop into a ring wound counter-clockwise (`ccw`) or clockwise.
/// Returns a node of the ring, or -1 for a loop with zero area.
int Triangulator::make_ring(const std::vector<glm::dvec2>& points, int first, int count,
                            bool ccw) {
    double area = 0.0;
    for (int i = 0; i < count; ++i)
        area += orient(points[first], points[first + i], points[first + (i + 1) % count]);
    if (area == 0.0) return -1;
    const bool reverse = (area > 0.0) != ccw;
    const int base = static_cast<int>(m_nodes.size());
    for (int i = 0; i < count; ++i) {
        const int k = reverse ? count - 1 - i : i;
        m_nodes.push_back({points[first + k], first + k, base + (i + count - 1) % count,
                           base + (i + 1) % count});
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

/// The outer-ring node the hole's rightmost node `hole` can be joined to:
/// cast a ray towards +x, take the nearest edge hit, then the visible
/// vertex closest in angle to the ray (the standard hole-bridging method).
int Triangulator::find_bridge(int hole, int outer) const {
    const glm::dvec2 h = pos(hole);
    int edge = -1;
    double hit_x = std::numeric_limits<double>::infinity();
    int p = outer;
    do {
        const glm::dvec2 &a = pos(p), &b = pos(next(p));
        // The ray leaves the interior through an upward edge (CCW ring).
        if (a.y <= h.y && b.y >= h.y && a.y != b.y) {
            const double x = a.x + (h.y - a.y) * (b.x - a.x) / (b.y - a.y);
            if (x >= h.x && x < hit_x) {
                hit_x = x;
                edge = p;
            }
        }
        p = next(p);
    } while (p != outer);
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
    p = outer;
    do {
        const glm::dvec2 q = pos(p);
        if ((q == c || in_triangle(h, hit, c, q)) && locally_inside(p, h)) {
            const double dx = q.x - h.x;
            const double tan = q == h     ? 0.0
                               : dx > 0.0 ? std::abs(q.y - h.y) / dx
                                          : std::numeric_limits<double>::infinity();
            const double dist = glm::length(q - h);
            if (tan < best_tan || (tan == best_tan && dist < best_dist)) {
                best = p;
                best_tan = tan;
                best_dist = dist;
            }
        }
        p = next(p);
    } while (p != outer);
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
}

void Triangulator::unlink(int n) {
    m_nodes[prev(n)].next = next(n);
    m_nodes[next(n)].prev = prev(n);
}

bool Triangulator::is_ear(int b) const {
    const int a = prev(b), c = next(b);
    const glm::dvec2 &pa = pos(a), &pb = pos(b), &pc = pos(c);
    if (orient(pa, pb, pc) <= 0.0) return false;
    for (int p = next(c); p != a; p = next(p)) {
        const glm::dvec2& q = pos(p);
        // Bridge duplicates share a position with an ear corner: not inside.
        if (q == pa || q == pb || q == pc) continue;
        // Only reflex (or flat) vertices can lie inside an ear.
        if (orient(pos(prev(p)), q, pos(next(p))) > 0.0) continue;
        if (in_ccw_triangle(pa, pb, pc, q)) return false;
    }
    return true;
}

void Triangulator::emit(int b, std::vector<std::array<int, 3>>& out) const {
    out.push_back({m_nodes[prev(b)].index, m_nodes[b].index, m_nodes[next(b)].index});
}

/// When a whole turn finds no ear (collinear or duplicate vertices, or a
/// self-intersecting loop): drop a degenerate vertex if there is one (it
/// encloses no area), else clip the most convex vertex anyway. Returns the
/// node to continue from.
int Triangulator::clip_fallback(int start, std::vector<std::array<int, 3>>& out) {
    int p = start;
    do {
        if (std::abs(orient(pos(prev(p)), pos(p), pos(next(p)))) <= m_tolerance) {
            const int after = next(p);
            unlink(p);
            return after;
        }
        p = next(p);
    } while (p != start);
    int best = start;
    double best_turn = -std::numeric_limits<double>::infinity();
    p = start;
    do {
        const double turn = orient(pos(prev(p)), pos(p), pos(next(p)));
        if (turn > best_turn) {
            best_turn = turn;
            best = p;
        }
        p = next(p);
    } while (p != start);
    emit(best, out);
    const int after = next(best);
    unlink(best);
    return after;
}

void Triangulator::clip_ears(int start, std::vector<std::array<int, 3>>& out) {
    int count = 1;
    for (int p = next(start); p != start; p = next(p)) ++count;
    int ear = start, stop = start;
    while (count > 3) {
        if (is_ear(ear)) {
            emit(ear, out);
            const int after = next(ear);
            unlink(ear);
            --count;
            ear = stop = after;
            continue;
        }
        ear = next(ear);
        if (ear == stop) {
            ear = stop = clip_fallback(ear, out);
            --count;
        }
    }
    if (count == 3) emit(ear, out);
}

} // namespace sss::detail
