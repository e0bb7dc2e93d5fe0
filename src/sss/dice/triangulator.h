#pragma once
/// \file triangulator.h
/// Internal: ear clipping of one planar polygon with holes
/// (triangulator.cpp), used by the polygon dicer for every face that is not
/// a triangle or a convex quad.

#include <array>
#include <utility>
#include <vector>

#include <glm/vec2.hpp>

namespace sss::detail {

/// Ear-clipping triangulator for one polygon with holes. Keeps its buffers
/// between polygons so a mesh of many faces allocates nothing per face.
class Triangulator {
public:
    /// Triangulates the polygon whose loops are consecutive runs of `points`
    /// (their sizes in `loop_sizes`; the first loop is the outer boundary, the
    /// others are holes), in any winding. Appends counter-clockwise triangles
    /// of indices into `points`.
    void run(const std::vector<glm::dvec2>& points, const std::vector<int>& loop_sizes,
             std::vector<std::array<int, 3>>& out);

private:
    struct Node {
        glm::dvec2 p;
        int index;
        int prev;
        int next;
    };

    // The steps, in triangulator.cpp.
    int make_ring(const std::vector<glm::dvec2>& points, int first, int count, bool ccw);
    bool locally_inside(int a, const glm::dvec2& p) const;
    int find_bridge(int hole, int outer) const;
    void splice(int bridge, int hole);
    void unlink(int n);
    bool is_ear(int b) const;
    void emit(int b, std::vector<std::array<int, 3>>& out) const;
    int clip_fallback(int start, std::vector<std::array<int, 3>>& out);
    void clip_ears(int start, std::vector<std::array<int, 3>>& out);

    const glm::dvec2& pos(int n) const { return m_nodes[n].p; }
    int prev(int n) const { return m_nodes[n].prev; }
    int next(int n) const { return m_nodes[n].next; }

    std::vector<Node> m_nodes;
    std::vector<std::pair<double, int>> m_holes;
    double m_tolerance = 0.0;
};

} // namespace sss::detail
