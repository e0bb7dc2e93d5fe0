// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file dice.cpp
/// The dispatcher: dice_primitive hands each primitive to the dicer of its
/// family (dice_quadric.cpp, dice_patch.cpp, dice_polygon.cpp,
/// dice_subdiv.cpp, dice_curves.cpp, dice_nurbs.cpp, dice_blobby.cpp), and
/// dice_all dices many of them in parallel for the baker and the renderer.

#include "sss/dice/dice.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <exception>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include "dice_common.h"
#include "sss/util/error.h"
#include "sss/util/limits.h"

namespace sss {

namespace {

/// The family's dicer (or, with `estimate`, estimator) of a primitive.
DicedSurface dispatch(const Primitive& prim, const DiceControl& control,
                      DiceEstimate* estimate) {
    switch (prim.kind) {
    case PrimitiveKind::Polygon:
    case PrimitiveKind::GeneralPolygon:
    case PrimitiveKind::PointsPolygons:
    case PrimitiveKind::PointsGeneralPolygons:
        return detail::dice_polygons(prim, control, estimate);
    case PrimitiveKind::SubdivisionMesh:
        return detail::dice_subdivision(prim, control, estimate);
    case PrimitiveKind::Sphere:
    case PrimitiveKind::Cylinder:
    case PrimitiveKind::Cone:
    case PrimitiveKind::Disk:
    case PrimitiveKind::Torus:
    case PrimitiveKind::Hyperboloid:
    case PrimitiveKind::Paraboloid:
        return detail::dice_quadric(prim, control, estimate);
    case PrimitiveKind::Patch:
        return detail::dice_patch(prim, control, estimate);
    case PrimitiveKind::PatchMesh:
        return detail::dice_patch_mesh(prim, control, estimate);
    case PrimitiveKind::Teapot:
        return detail::dice_teapot(prim, control, estimate);
    case PrimitiveKind::Points:
        return detail::dice_points(prim, control, estimate);
    case PrimitiveKind::Curves:
        return detail::dice_curves(prim, control, estimate);
    case PrimitiveKind::NuPatch:
        return detail::dice_nupatch(prim, control, estimate);
    case PrimitiveKind::Blobby:
        return detail::dice_blobby(prim, control, estimate);
    }
    throw ValueError(prim.source + ": unknown primitive kind");
}

/// Runs f(k) for every k < n in parallel; then rethrows the first failure in
/// index order, so that the error is the same for any number of threads.
template <class F>
void for_each_request(std::size_t n, const F& f) {
    std::vector<std::exception_ptr> errors(n);
    tbb::parallel_for(std::size_t(0), n, [&](std::size_t k) {
        try {
            f(k);
        } catch (...) {
            errors[k] = std::current_exception();
        }
    });
    for (const std::exception_ptr& e : errors)
        if (e) std::rethrow_exception(e);
}

} // namespace

DicedSurface dice_primitive(const Primitive& prim, const DiceControl& control) {
    DicedSurface surface = dispatch(prim, control, nullptr);
    // Whatever the family: no point beyond the range reaches a ray tracer
    // (curves overshooting their control points, displacement).
    detail::check_world_range(prim, surface);
    return surface;
}

double DiceJournal::note(double value, const std::string& where) const {
    if (!m_replaying) {
        m_values.push_back(value);
        return value;
    }
    if (m_next >= m_values.size())
        throw ValueError(where + ": motion blur: the primitive dices differently at " +
                         "another time (its deformation changes how it is cut up)");
    return m_values[m_next++];
}

DicedSurface dice_moving(const Primitive& prim, const DiceControl& control,
                         const std::vector<double>& times) {
    if (times.empty()) return dice_primitive(prim, control);
    DiceControl steps = control;
    steps.journal = std::make_shared<DiceJournal>();
    DicedSurface surface = dice_primitive(primitive_at(prim, times.front()), steps);
    for (std::size_t k = 1; k < times.size(); ++k) {
        steps.journal->replay();
        DicedSurface at = dice_primitive(primitive_at(prim, times[k]), steps);
        if (!steps.journal->replayed_all() || at.triangles != surface.triangles ||
            at.vertices.size() != surface.vertices.size())
            throw ValueError(prim.source + ": motion blur: the primitive dices into " +
                             "other triangles at time " + std::to_string(times[k]) +
                             " than at " + std::to_string(times.front()) +
                             " (its deformation changes how it is cut up)");
        surface.step_vertices.push_back(std::move(at.vertices));
        surface.step_normals.push_back(std::move(at.vertex_normals));
    }
    return surface;
}

DiceEstimate estimate_primitive(const Primitive& prim, const DiceControl& control) {
    DiceEstimate estimate;
    dispatch(prim, control, &estimate);
    if (!(estimate.micropolygons <= static_cast<double>(control.max_micropolygons)))
        detail::too_many_micropolygons(prim, control, estimate.micropolygons);
    return estimate;
}

std::vector<DiceEstimate> estimate_dicing(const Scene& scene,
                                          std::span<const DiceRequest> requests,
                                          const std::string& where) {
    std::vector<DiceEstimate> each(requests.size());
    for_each_request(requests.size(), [&](std::size_t k) {
        each[k] = estimate_primitive(scene.primitives[requests[k].primitive],
                                     requests[k].control);
    });
    DiceEstimate total;
    for (const DiceEstimate& e : each) total += e;
    const double cap = 1.8e19; // beyond uint64_t: surely over any limit
    check_limit(Limit::SceneMicropolygons,
                static_cast<uint64_t>(std::min(total.micropolygons, cap)), where);
    return each;
}

std::vector<DicedSurface> dice_all(const Scene& scene,
                                   std::span<const DiceRequest> requests,
                                   const DiceFinish& finish) {
    std::vector<DicedSurface> diced(scene.primitives.size());
    for_each_request(requests.size(), [&](std::size_t k) {
        const DiceRequest& request = requests[k];
        DicedSurface& surface = diced[request.primitive];
        const Primitive& prim = scene.primitives[request.primitive];
        surface = request.times.empty()
                      ? dice_primitive(prim, request.control)
                      : dice_moving(prim, request.control, request.times);
        if (finish) finish(request.primitive, surface);
    });
    return diced;
}

namespace {

/// A k-d tree over the micropolygon centres of a surface, for exact nearest
/// centre queries: leaves of up to kLeaf centres, split at the median of
/// the longest side of their box. Building is O(n log n); a query visits
/// O(log n) nodes for ordinary surfaces, whatever the spread of the
/// micropolygon sizes (a hash grid with cells the size of the largest
/// micropolygon put a whole surface into one cell when one micropolygon was
/// huge: quadratic).
class CentreTree {
public:
    explicit CentreTree(const std::vector<glm::vec3>& centres) : m_p(centres) {
        m_order.resize(centres.size());
        for (std::size_t i = 0; i < centres.size(); ++i)
            m_order[i] = static_cast<uint32_t>(i);
        m_nodes.reserve(2 * (centres.size() / kLeaf + 1));
        build(0, static_cast<uint32_t>(centres.size()));
    }

    /// The centre nearest to c (squared float distance as dot(e, e)); of
    /// equally near ones the lowest index. `guesses` are any centres: the
    /// nearer one bounds the search from the start.
    uint32_t nearest(const glm::vec3& c, uint32_t guess, uint32_t guess2) const {
        Best best{dist2(guess, c), guess};
        const float d2 = dist2(guess2, c);
        if (d2 < best.d || (d2 == best.d && guess2 < best.i)) best = {d2, guess2};
        thread_local std::vector<uint32_t> stack;
        stack.clear();
        stack.push_back(0);
        while (!stack.empty()) {
            const Node& node = m_nodes[stack.back()];
            stack.pop_back();
            if (pruned(node, c, best)) continue;
            if (node.left < 0) {
                for (uint32_t k = node.begin; k < node.end; ++k) {
                    const uint32_t i = m_order[k];
                    const float d = dist2(i, c);
                    if (d < best.d || (d == best.d && i < best.i)) best = {d, i};
                }
                continue;
            }
            // Nearer child last: it is popped first.
            const Node& a = m_nodes[static_cast<std::size_t>(node.left)];
            const Node& b = m_nodes[static_cast<std::size_t>(node.right)];
            const double da = box_dist2(a, c), db = box_dist2(b, c);
            const bool a_first = da < db || (da == db && a.min_index < b.min_index);
            stack.push_back(static_cast<uint32_t>(a_first ? node.right : node.left));
            stack.push_back(static_cast<uint32_t>(a_first ? node.left : node.right));
        }
        return best.i;
    }

private:
    static constexpr uint32_t kLeaf = 8;

    struct Node {
        glm::dvec3 lo, hi;
        uint32_t begin = 0, end = 0;
        uint32_t min_index = 0;
        int32_t left = -1, right = -1;
    };
    struct Best {
        float d;
        uint32_t i;
    };

    float dist2(uint32_t i, const glm::vec3& c) const {
        const glm::vec3 e = m_p[i] - c;
        return glm::dot(e, e);
    }
    static double box_dist2(const Node& n, const glm::vec3& c) {
        const glm::dvec3 p(c);
        const glm::dvec3 d = glm::max(glm::max(n.lo - p, p - n.hi), glm::dvec3(0.0));
        return glm::dot(d, d);
    }
    /// Whether no centre of the node can beat `best` (nearer, or as near with
    /// a lower index). The box distance, in double, is shrunk by far more
    /// than the rounding of the centres' float distances.
    static bool pruned(const Node& n, const glm::vec3& c, const Best& best) {
        const double lower = box_dist2(n, c) * (1.0 - 1e-5);
        const double d = best.d;
        return lower > d || (lower >= d && n.min_index >= best.i);
    }

    int32_t build(uint32_t begin, uint32_t end) {
        const auto index = static_cast<int32_t>(m_nodes.size());
        m_nodes.emplace_back();
        Node node;
        node.begin = begin;
        node.end = end;
        node.lo = glm::dvec3(std::numeric_limits<double>::infinity());
        node.hi = -node.lo;
        node.min_index = std::numeric_limits<uint32_t>::max();
        for (uint32_t k = begin; k < end; ++k) {
            const glm::dvec3 p(m_p[m_order[k]]);
            node.lo = glm::min(node.lo, p);
            node.hi = glm::max(node.hi, p);
            node.min_index = std::min(node.min_index, m_order[k]);
        }
        if (end - begin > kLeaf) {
            const glm::dvec3 size = node.hi - node.lo;
            const int axis = size.x >= size.y && size.x >= size.z ? 0
                             : size.y >= size.z                   ? 1
                                                                  : 2;
            const uint32_t mid = begin + (end - begin) / 2;
            std::nth_element(m_order.begin() + begin, m_order.begin() + mid,
                             m_order.begin() + end, [&](uint32_t a, uint32_t b) {
                                 const float pa = m_p[a][axis], pb = m_p[b][axis];
                                 return pa < pb || (pa == pb && a < b);
                             });
            node.left = build(begin, mid);
            node.right = build(mid, end);
        }
        m_nodes[static_cast<std::size_t>(index)] = node;
        return index;
    }

    const std::vector<glm::vec3>& m_p;
    std::vector<uint32_t> m_order;
    std::vector<Node> m_nodes;
};

} // namespace

std::vector<glm::vec3> triangle_colors(const DicedSurface& d) {
    std::vector<glm::vec3> colors;
    if (d.colors.empty() || d.triangles.empty() || d.size() == 0) return colors;
    const CentreTree tree(d.centers);
    const std::size_t triangles = d.triangles.size() / 3;
    colors.resize(triangles);
    uint32_t previous = 0;
    for (std::size_t t = 0; t < triangles; ++t) {
        const glm::vec3 c =
            (d.vertices[d.triangles[3 * t]] + d.vertices[d.triangles[3 * t + 1]] +
             d.vertices[d.triangles[3 * t + 2]]) /
            3.0f;
        // Dicers emit a micropolygon's triangles about where and when they
        // emit it: the proportional index and the previous triangle's answer
        // are close first guesses.
        const auto guess =
            static_cast<uint32_t>(std::min(d.size() - 1, t * d.size() / triangles));
        previous = tree.nearest(c, guess, previous);
        colors[t] = d.colors[previous];
    }
    return colors;
}

} // namespace sss
