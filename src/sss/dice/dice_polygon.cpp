/// \file dice_polygon.cpp
/// Dicing of polygons (Polygon, GeneralPolygon, PointsPolygons,
/// PointsGeneralPolygons) and Catmull–Clark subdivision meshes.
///
/// Polygons: convex quads are diced like REYES grids, as bilinear patches of
/// nu x nv sub-quads (one micropolygon each, made of two triangles). Every
/// other face is triangulated in the plane of its Newell normal (ear clipping,
/// holes joined to the outer loop by bridges), and every triangle is cut into
/// n x n similar sub-triangles in world space, one micropolygon each, with n
/// = ceil(longest side / (sqrt(2) e)). Thin triangles, for which that would
/// make n^2 needles, are cut in columns across their longest side instead.
/// Subdivision meshes are refined until their control edges are at most twice
/// the dicing length, pushed to the limit surface, and every refined quad is
/// diced as a bilinear patch.
///
/// Watertightness: points on a face's border are computed from that border
/// edge's two end points only, with integer-quotient weights, so two faces
/// that cut a shared edge into the same number of pieces produce bit-identical
/// vertices there. Faces that choose different counts meet in T-junctions;
/// since both sides put their points on the same straight segment, the
/// cracks are only rounding-sized (the ray tracer's epsilon covers them).

#include "sss/dice/dice.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>
#include <glm/vec2.hpp>

#include "dice_detail.h"
#include "mesh_common.h"
#include "sss/util/error.h"
#include "subdivision.h"

namespace sss::detail {

// ---------------------------------------------------------------------------
// Shared helpers (mesh_common.h)

void throw_mesh_error(const Primitive& prim, const std::string& what) {
    const std::string kind = primitive_kind_name(prim.kind);
    throw ValueError((prim.source.empty() ? kind : prim.source + ": " + kind) + ": " +
                     what);
}

std::vector<glm::dvec3> read_positions(const Primitive& prim) {
    const Param* p = prim.params.find("P");
    bool homogeneous = p && p->type == ParamType::HPoint;
    if (!p) {
        p = prim.params.find("Pw");
        homogeneous = true;
    }
    if (!p) throw_mesh_error(prim, "missing \"P\"");
    const std::size_t comps = homogeneous ? 4 : 3;
    if (p->type == ParamType::String ||
        static_cast<std::size_t>(p->element_size()) != comps)
        throw_mesh_error(prim, "\"" + p->name + "\" must have " + std::to_string(comps) +
                                   " numbers per point");
    if (p->numbers.size() % comps != 0)
        throw_mesh_error(prim, "\"" + p->name + "\" has " +
                                   std::to_string(p->numbers.size()) +
                                   " numbers, not a whole number of points");
    std::vector<glm::dvec3> points(p->numbers.size() / comps);
    for (std::size_t i = 0; i < points.size(); ++i) {
        const double* v = &p->numbers[comps * i];
        glm::dvec3 q(v[0], v[1], v[2]);
        if (homogeneous) {
            if (v[3] == 0.0)
                throw_mesh_error(prim,
                                 "\"Pw\" point " + std::to_string(i) + " has w = 0");
            q /= v[3];
        }
        if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z))
            throw_mesh_error(prim, "\"" + p->name + "\" point " + std::to_string(i) +
                                       " is not finite");
        points[i] = q;
    }
    return points;
}

namespace {} // namespace

CornerVec3::CornerVec3(const Primitive& prim, std::string_view name, std::size_t faces,
                       std::size_t points, std::size_t corners) {
    const Param* p = prim.params.find(name);
    if (!p) return;
    std::string quoted(1, '"');
    quoted.append(name);
    quoted.push_back('"');
    if (p->type == ParamType::String || p->element_size() != 3)
        throw_mesh_error(prim, quoted + " must have 3 numbers per value");
    std::size_t needed = 1;
    switch (p->storage) {
    case ParamClass::Constant:
        needed = 1;
        break;
    case ParamClass::Uniform:
        needed = faces;
        break;
    case ParamClass::Varying:
    case ParamClass::Vertex:
        needed = points;
        break;
    case ParamClass::FaceVarying:
    case ParamClass::FaceVertex:
        needed = corners;
        break;
    }
    if (p->element_count() < needed)
        throw_mesh_error(prim, quoted + " (" + param_class_name(p->storage) + ") has " +
                                   std::to_string(p->element_count()) + " values, " +
                                   std::to_string(needed) + " needed");
    for (std::size_t i = 0; i < 3 * needed; ++i)
        if (!std::isfinite(p->numbers[i]))
            throw_mesh_error(prim, quoted + " has a value that is not finite");
    m_data = p->numbers.data();
    m_class = p->storage;
}

namespace {

// ---------------------------------------------------------------------------
// Normals


/// The normal rule of dice_detail.h with the matrix prepared once per
/// primitive (world_normal rebuilds it on every call, too slow for millions
/// of corner normals). The cofactor matrix (det * inverse transpose) is
/// defined even for singular transforms, and maps object cross products to
/// world cross products; its sign is calibrated against world_normal so the
/// two can never disagree (mirror transforms included).
class NormalTransform {
public:
    explicit NormalTransform(const Primitive& prim) {
        const glm::dmat3 a(prim.object_to_world);
        m_matrix = glm::dmat3(glm::cross(a[1], a[2]), glm::cross(a[2], a[0]),
                              glm::cross(a[0], a[1]));
        const glm::dvec3 probe(0.267, 0.535, 0.802);
        const glm::dvec3 reference = world_normal(prim.object_to_world, probe, false);
        m_user_sign = glm::dot(reference, m_matrix * probe) < 0.0 ? -1.0 : 1.0;
        m_geometric_sign =
            attributes_of(prim).orientation_inside ? -m_user_sign : m_user_sign;
    }
    /// World direction of a user-supplied object-space normal, not normalised.
    glm::dvec3 user(const glm::dvec3& n) const { return m_user_sign * (m_matrix * n); }
    /// Unit world normal from an object-space formula normal (orientation applied).
    glm::dvec3 geometric(const glm::dvec3& n) const {
        return safe_normalize(m_geometric_sign * (m_matrix * n));
    }
    /// Unit world normal from a cross product of world-space edges (the
    /// cofactor image of the object-space formula normal).
    glm::dvec3 geometric_from_world_cross(const glm::dvec3& c) const {
        return safe_normalize(m_geometric_sign * c);
    }
    /// n / |n|, or zero for a zero or non-finite vector (never NaN).
    static glm::dvec3 safe_normalize(const glm::dvec3& n) {
        const double len = glm::length(n);
        return len > 0.0 && std::isfinite(len) ? n * (1.0 / len) : glm::dvec3(0.0);
    }

private:
    glm::dmat3 m_matrix{1.0};
    double m_user_sign = 1.0;
    double m_geometric_sign = 1.0;
};

/// World position of an object-space point (projective matrices divide by w).
glm::dvec3 to_world(const Matrix4& m, const glm::dvec3& p) {
    const glm::dvec4 h = m * glm::dvec4(p, 1.0);
    return h.w == 1.0 ? glm::dvec3(h) : glm::dvec3(h) / h.w;
}

/// Micropolygon edge length at a world point, checked.
double edge_length(const Primitive& prim, const DiceControl& control, const glm::dvec3& p,
                   double shading_rate) {
    double e = 0.0;
    try {
        e = control.edge_length_at(p, shading_rate);
    } catch (const ValueError& err) {
        throw_mesh_error(prim, err.what()); // name the primitive
    }
    if (!(e > 0.0) || !std::isfinite(e))
        throw_mesh_error(prim, "dicing edge length " + std::to_string(e) +
                                   " is not a positive number");
    return e;
}

/// Number of pieces for a length: ceil(length / edge), at least 1.
std::size_t piece_count(const Primitive& prim, const DiceControl& control, double length,
                        double edge) {
    const double n = std::max(1.0, std::ceil(length / edge));
    // Every piece is at least one micropolygon: one side beyond the budget is
    // reported here, before any count can overflow.
    if (!(n <= static_cast<double>(control.max_micropolygons)) || !(n <= 1e9))
        throw_mesh_error(prim, "would dice into more than " +
                                   std::to_string(control.max_micropolygons) +
                                   " micropolygons");
    return static_cast<std::size_t>(n);
}

void check_budget(const Primitive& prim, const DiceControl& control, std::size_t count) {
    if (count > control.max_micropolygons)
        throw_mesh_error(prim, "would dice into " + std::to_string(count) +
                                   " micropolygons, more than the limit of " +
                                   std::to_string(control.max_micropolygons));
}

glm::vec3 to_float(const glm::dvec3& v) {
    return glm::vec3(v);
}

/// Fills a DicedSurface whose arrays were sized beforehand.
struct SurfaceWriter {
    DicedSurface& out;
    bool with_colors;
    std::size_t mp = 0;
    std::size_t vertex = 0;
    std::size_t triangle = 0;

    void micropolygon(const glm::dvec3& centre, const glm::dvec3& normal, double area,
                      double radius, const glm::dvec3& color) {
        if (mp >= out.centers.size()) overflow();
        out.centers[mp] = to_float(centre);
        out.normals[mp] = to_float(normal);
        out.areas[mp] = static_cast<float>(area);
        out.radii[mp] = static_cast<float>(radius);
        if (with_colors) out.colors[mp] = to_float(color);
        ++mp;
    }
    void add_vertex(const glm::dvec3& p, const glm::dvec3& n) {
        if (vertex >= out.vertices.size()) overflow();
        out.vertices[vertex] = to_float(p);
        out.vertex_normals[vertex] = to_float(n);
        ++vertex;
    }
    void add_triangle(std::size_t a, std::size_t b, std::size_t c) {
        if (3 * triangle >= out.triangles.size()) overflow();
        out.triangles[3 * triangle + 0] = static_cast<uint32_t>(a);
        out.triangles[3 * triangle + 1] = static_cast<uint32_t>(b);
        out.triangles[3 * triangle + 2] = static_cast<uint32_t>(c);
        ++triangle;
    }
    /// The counting pass and the dicing disagree: a bug, never bad input.
    [[noreturn]] static void overflow() {
        throw std::logic_error("dice_mesh: more micropolygons than counted");
    }
    void finish() { out.resize(mp, vertex, triangle, with_colors); }
};

void allocate(const Primitive& prim, DicedSurface& out, std::size_t micropolygons,
              std::size_t vertices, std::size_t triangles, bool with_colors) {
    if (vertices > std::numeric_limits<uint32_t>::max())
        throw_mesh_error(prim,
                         "diced surface has more vertices than 32-bit indices address");
    out.resize(micropolygons, vertices, triangles, with_colors);
}

glm::dvec3 bilinear(const std::array<glm::dvec3, 4>& c, double u, double v) {
    return (c[0] * (1.0 - u) + c[1] * u) * (1.0 - v) + (c[3] * (1.0 - u) + c[2] * u) * v;
}

constexpr std::array<glm::dvec3, 4> kZero4{glm::dvec3(0.0), glm::dvec3(0.0),
                                           glm::dvec3(0.0), glm::dvec3(0.0)};

/// One quad to dice, in world space, corners in winding order.
struct QuadCorners {
    std::array<glm::dvec3, 4> p = kZero4;
    std::array<glm::dvec3, 4> normal = kZero4; ///< interpolated, then normalised
    std::array<glm::dvec3, 4> color = kZero4;  ///< used when the writer has colours
    glm::dvec3 fallback_normal{0.0};           ///< where the interpolation vanishes
};

/// Dices a quad as a bilinear patch of nu x nv sub-quads (nu along corners
/// 0->1). Each sub-quad is one micropolygon made of two emitted triangles:
/// its area is theirs, its centre their area-weighted centroid.
class QuadDicer {
public:
    void dice(const QuadCorners& q, std::size_t nu, std::size_t nv, SurfaceWriter& w) {
        m_grid.resize((nu + 1) * (nv + 1));
        const double du = static_cast<double>(nu), dv = static_cast<double>(nv);
        // Flat faces (one normal at all corners) skip the interpolation.
        const bool flat = q.normal[1] == q.normal[0] && q.normal[2] == q.normal[0] &&
                          q.normal[3] == q.normal[0];
        const glm::dvec3 flat_normal = NormalTransform::safe_normalize(q.normal[0]);
        auto normal_at = [&](double u, double v) {
            const glm::dvec3 n =
                flat ? flat_normal
                     : NormalTransform::safe_normalize(bilinear(q.normal, u, v));
            return glm::dot(n, n) > 0.0 ? n : q.fallback_normal;
        };
        const std::size_t base = w.vertex;
        for (std::size_t j = 0; j <= nv; ++j)
            for (std::size_t i = 0; i <= nu; ++i) {
                const double u = double(i) / du, v = double(j) / dv;
                glm::dvec3 p;
                // Border points from the border's two end points only, with
                // integer-quotient weights: identical in the neighbouring quad.
                if (j == 0)
                    p = q.p[0] * (double(nu - i) / du) + q.p[1] * u;
                else if (j == nv)
                    p = q.p[3] * (double(nu - i) / du) + q.p[2] * u;
                else if (i == 0)
                    p = q.p[0] * (double(nv - j) / dv) + q.p[3] * v;
                else if (i == nu)
                    p = q.p[1] * (double(nv - j) / dv) + q.p[2] * v;
                else
                    p = bilinear(q.p, u, v);
                m_grid[j * (nu + 1) + i] = p;
                w.add_vertex(p, normal_at(u, v));
            }
        for (std::size_t j = 0; j < nv; ++j)
            for (std::size_t i = 0; i < nu; ++i) {
                const std::size_t k00 = j * (nu + 1) + i, k10 = k00 + 1;
                const std::size_t k01 = k00 + nu + 1, k11 = k01 + 1;
                w.add_triangle(base + k00, base + k10, base + k11);
                w.add_triangle(base + k00, base + k11, base + k01);
                const glm::dvec3 &p00 = m_grid[k00], &p10 = m_grid[k10];
                const glm::dvec3 &p11 = m_grid[k11], &p01 = m_grid[k01];
                const double a1 = 0.5 * glm::length(glm::cross(p10 - p00, p11 - p00));
                const double a2 = 0.5 * glm::length(glm::cross(p11 - p00, p01 - p00));
                const double area = a1 + a2;
                if (!(area > 0.0)) continue; // collapsed: no surface, no point
                const glm::dvec3 centre =
                    (a1 * (p00 + p10 + p11) + a2 * (p00 + p11 + p01)) *
                    (1.0 / (3.0 * area));
                const double radius =
                    std::sqrt(std::max({glm::dot(p00 - centre, p00 - centre),
                                        glm::dot(p10 - centre, p10 - centre),
                                        glm::dot(p11 - centre, p11 - centre),
                                        glm::dot(p01 - centre, p01 - centre)}));
                const double u = (double(i) + 0.5) / du, v = (double(j) + 0.5) / dv;
                const glm::dvec3 col =
                    w.with_colors ? bilinear(q.color, u, v) : glm::dvec3(0.0);
                w.micropolygon(centre, normal_at(u, v), area, radius, col);
            }
    }

private:
    std::vector<glm::dvec3> m_grid;
};

// ---------------------------------------------------------------------------
// Triangulation

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

/// Ear-clipping triangulator for one polygon with holes. Keeps its buffers
/// between polygons so a mesh of many faces allocates nothing per face.
class Triangulator {
public:
    /// Triangulates the polygon whose loops are consecutive runs of `points`
    /// (their sizes in `loop_sizes`; the first loop is the outer boundary, the
    /// others are holes), in any winding. Appends counter-clockwise triangles
    /// of indices into `points`.
    void run(const std::vector<glm::dvec2>& points, const std::vector<int>& loop_sizes,
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

private:
    struct Node {
        glm::dvec2 p;
        int index;
        int prev;
        int next;
    };
    std::vector<Node> m_nodes;
    std::vector<std::pair<double, int>> m_holes;
    double m_tolerance = 0.0;

    const glm::dvec2& pos(int n) const { return m_nodes[n].p; }
    int prev(int n) const { return m_nodes[n].prev; }
    int next(int n) const { return m_nodes[n].next; }

    /// Links one loop into a ring wound counter-clockwise (`ccw`) or clockwise.
    /// Returns a node of the ring, or -1 for a loop with zero area.
    int make_ring(const std::vector<glm::dvec2>& points, int first, int count, bool ccw) {
        double area = 0.0;
        for (int i = 0; i < count; ++i)
            area +=
                orient(points[first], points[first + i], points[first + (i + 1) % count]);
        if (area == 0.0) return -1;
        const bool reverse = (area > 0.0) != ccw;
        const int base = static_cast<int>(m_nodes.size());
        for (int i = 0; i < count; ++i) {
            const int k = reverse ? count - 1 - i : i;
            m_nodes.push_back({points[first + k], first + k,
                               base + (i + count - 1) % count, base + (i + 1) % count});
        }
        return base;
    }

    /// True when the direction from node a towards p leaves a into the
    /// polygon's interior (between its two edges).
    bool locally_inside(int a, const glm::dvec2& p) const {
        const glm::dvec2 &pa = pos(prev(a)), &va = pos(a), &na = pos(next(a));
        if (orient(pa, va, na) >= 0.0)
            return orient(pa, va, p) >= 0.0 && orient(va, na, p) >= 0.0;
        return orient(pa, va, p) >= 0.0 || orient(va, na, p) >= 0.0;
    }

    /// The outer-ring node the hole's rightmost node `hole` can be joined to:
    /// cast a ray towards +x, take the nearest edge hit, then the visible
    /// vertex closest in angle to the ray (the standard hole-bridging method).
    int find_bridge(int hole, int outer) const {
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
    void splice(int bridge, int hole) {
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

    void unlink(int n) {
        m_nodes[prev(n)].next = next(n);
        m_nodes[next(n)].prev = prev(n);
    }

    bool is_ear(int b) const {
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

    void emit(int b, std::vector<std::array<int, 3>>& out) const {
        out.push_back({m_nodes[prev(b)].index, m_nodes[b].index, m_nodes[next(b)].index});
    }

    /// When a whole turn finds no ear (collinear or duplicate vertices, or a
    /// self-intersecting loop): drop a degenerate vertex if there is one (it
    /// encloses no area), else clip the most convex vertex anyway. Returns the
    /// node to continue from.
    int clip_fallback(int start, std::vector<std::array<int, 3>>& out) {
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

    void clip_ears(int start, std::vector<std::array<int, 3>>& out) {
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
};

// ---------------------------------------------------------------------------
// Polygons

/// Faces -> loops -> corners of any of the four polygon primitives.
struct PolygonTopology {
    std::vector<int> face_loops;        ///< face count + 1 offsets into loop_corners
    std::vector<int> loop_corners;      ///< loop count + 1 offsets into corner_point
    std::vector<uint32_t> corner_point; ///< point index of each corner
    std::size_t points_referenced = 0;  ///< largest point index + 1
};

void check_loop_size(const Primitive& prim, int n, std::size_t loop) {
    if (n < 3)
        throw_mesh_error(prim, "loop " + std::to_string(loop) + " has " +
                                   std::to_string(n) + " vertices (at least 3 needed)");
}

PolygonTopology polygon_topology(const Primitive& prim, std::size_t npoints) {
    PolygonTopology t;
    std::vector<int> nloops; // per face
    const std::vector<int>* nverts = &prim.nverts;
    std::vector<int> single;
    bool indexed = false;
    switch (prim.kind) {
    case PrimitiveKind::Polygon:
        single.push_back(static_cast<int>(npoints));
        nverts = &single;
        nloops.push_back(1);
        break;
    case PrimitiveKind::GeneralPolygon:
        if (prim.nverts.empty()) throw_mesh_error(prim, "no loops");
        nloops.push_back(static_cast<int>(prim.nverts.size()));
        break;
    case PrimitiveKind::PointsPolygons:
        nloops.assign(prim.nverts.size(), 1);
        indexed = true;
        break;
    case PrimitiveKind::PointsGeneralPolygons:
        nloops = prim.nloops;
        indexed = true;
        break;
    default:
        throw_mesh_error(prim, "not a polygon primitive");
    }
    if (nloops.empty()) throw_mesh_error(prim, "no faces");

    std::size_t loop_total = 0;
    for (std::size_t f = 0; f < nloops.size(); ++f) {
        if (nloops[f] < 1)
            throw_mesh_error(prim, "face " + std::to_string(f) + " has " +
                                       std::to_string(nloops[f]) + " loops");
        loop_total += static_cast<std::size_t>(nloops[f]);
    }
    if (loop_total != nverts->size())
        throw_mesh_error(prim, "nloops add up to " + std::to_string(loop_total) +
                                   " but " + std::to_string(nverts->size()) +
                                   " loop sizes are given");
    std::size_t corner_total = 0;
    for (std::size_t l = 0; l < nverts->size(); ++l) {
        check_loop_size(prim, (*nverts)[l], l);
        corner_total += static_cast<std::size_t>((*nverts)[l]);
    }
    if (corner_total > std::numeric_limits<int32_t>::max())
        throw_mesh_error(prim, "too many vertices");

    t.corner_point.resize(corner_total);
    if (indexed) {
        if (prim.verts.size() != corner_total)
            throw_mesh_error(prim, "nverts add up to " + std::to_string(corner_total) +
                                       " but " + std::to_string(prim.verts.size()) +
                                       " vertex indices are given");
        for (std::size_t c = 0; c < corner_total; ++c) {
            const int v = prim.verts[c];
            if (v < 0 || static_cast<std::size_t>(v) >= npoints)
                throw_mesh_error(prim, "vertex index " + std::to_string(v) +
                                           " out of range (" + std::to_string(npoints) +
                                           " points in \"P\")");
            t.corner_point[c] = static_cast<uint32_t>(v);
            t.points_referenced =
                std::max(t.points_referenced, static_cast<std::size_t>(v) + 1);
        }
    } else {
        if (corner_total != npoints)
            throw_mesh_error(prim, "\"P\" has " + std::to_string(npoints) + " points, " +
                                       std::to_string(corner_total) + " expected");
        for (std::size_t c = 0; c < corner_total; ++c)
            t.corner_point[c] = static_cast<uint32_t>(c);
        t.points_referenced = npoints;
    }

    t.face_loops.resize(nloops.size() + 1);
    t.face_loops[0] = 0;
    for (std::size_t f = 0; f < nloops.size(); ++f)
        t.face_loops[f + 1] = t.face_loops[f] + nloops[f];
    t.loop_corners.resize(nverts->size() + 1);
    t.loop_corners[0] = 0;
    for (std::size_t l = 0; l < nverts->size(); ++l)
        t.loop_corners[l + 1] = t.loop_corners[l] + (*nverts)[l];
    return t;
}

/// One triangle of a triangulated face, or one convex quad face, by corner.
struct FaceJob {
    std::array<uint32_t, 4> corner;
    uint32_t face;
    uint32_t corners;   ///< 3 or 4
    uint32_t pieces[2]; ///< triangle: n x n (pieces[0]); quad: nu x nv; 0 = dropped
    bool columns;       ///< thin triangle: diced in columns (ColumnDicer)
};

/// Per-face-corner attributes of one triangle being diced, in world space.
struct TriangleCorners {
    std::array<glm::dvec3, 3> p{glm::dvec3(0.0), glm::dvec3(0.0), glm::dvec3(0.0)};
    /// Unnormalised; used only with "N".
    std::array<glm::dvec3, 3> user_normal{glm::dvec3(0.0), glm::dvec3(0.0),
                                          glm::dvec3(0.0)};
    /// Used only with "Cs".
    std::array<glm::dvec3, 3> color{glm::dvec3(0.0), glm::dvec3(0.0), glm::dvec3(0.0)};
};

/// Cuts one triangle into n x n similar sub-triangles, one micropolygon each
/// (all of area A / n^2, all with the same radius: the down-pointing ones are
/// point reflections of the up-pointing ones).
void dice_triangle(const TriangleCorners& t, std::size_t n, const glm::dvec3& face_normal,
                   bool user_normals, SurfaceWriter& w) {
    const glm::dvec3 &w0 = t.p[0], &w1 = t.p[1], &w2 = t.p[2];
    const double nn = static_cast<double>(n);
    const double area = 0.5 * glm::length(glm::cross(w1 - w0, w2 - w0)) / (nn * nn);
    const glm::dvec3 centroid = (w0 + w1 + w2) / 3.0;
    const double radius = std::sqrt(std::max({glm::dot(w0 - centroid, w0 - centroid),
                                              glm::dot(w1 - centroid, w1 - centroid),
                                              glm::dot(w2 - centroid, w2 - centroid)})) /
                          nn;
    auto normal_at = [&](double b1, double b2) {
        if (!user_normals) return face_normal;
        const glm::dvec3 n = NormalTransform::safe_normalize(
            (1.0 - b1 - b2) * t.user_normal[0] + b1 * t.user_normal[1] +
            b2 * t.user_normal[2]);
        return glm::dot(n, n) > 0.0 ? n : face_normal;
    };
    const bool colors = w.with_colors;

    // Grid vertices, row j (weight j/n on w2), column i (weight i/n on w1).
    // Weights are exact quotients of integers, so a shared edge's points depend
    // only on its two end points and n: watertight for equal n.
    const std::size_t base = w.vertex;
    for (std::size_t j = 0; j <= n; ++j)
        for (std::size_t i = 0; i + j <= n; ++i) {
            const double b1 = double(i) / nn, b2 = double(j) / nn,
                         b0 = double(n - i - j) / nn;
            w.add_vertex(w0 * b0 + w1 * b1 + w2 * b2, normal_at(b1, b2));
        }
    // Row j starts after rows 0..j-1 of n+1, n, ... vertices.
    auto vertex_index = [&](std::size_t i, std::size_t j) {
        return base + j * (n + 1) - j * (j - 1) / 2 + i;
    };
    for (std::size_t j = 0; j < n; ++j)
        for (std::size_t i = 0; i + j < n; ++i) {
            // Up-pointing sub-triangle (i,j) (i+1,j) (i,j+1).
            {
                const double b1 = (double(i) + 1.0 / 3.0) / nn,
                             b2 = (double(j) + 1.0 / 3.0) / nn;
                const glm::dvec3 c = w0 * (1.0 - b1 - b2) + w1 * b1 + w2 * b2;
                const glm::dvec3 col = colors ? (1.0 - b1 - b2) * t.color[0] +
                                                    b1 * t.color[1] + b2 * t.color[2]
                                              : glm::dvec3(0.0);
                w.micropolygon(c, normal_at(b1, b2), area, radius, col);
                w.add_triangle(vertex_index(i, j), vertex_index(i + 1, j),
                               vertex_index(i, j + 1));
            }
            if (i + j + 1 < n) {
                // Down-pointing sub-triangle (i+1,j) (i+1,j+1) (i,j+1).
                const double b1 = (double(i) + 2.0 / 3.0) / nn,
                             b2 = (double(j) + 2.0 / 3.0) / nn;
                const glm::dvec3 c = w0 * (1.0 - b1 - b2) + w1 * b1 + w2 * b2;
                const glm::dvec3 col = colors ? (1.0 - b1 - b2) * t.color[0] +
                                                    b1 * t.color[1] + b2 * t.color[2]
                                              : glm::dvec3(0.0);
                w.micropolygon(c, normal_at(b1, b2), area, radius, col);
                w.add_triangle(vertex_index(i + 1, j), vertex_index(i + 1, j + 1),
                               vertex_index(i, j + 1));
            }
        }
}

/// Column dicing of a thin triangle, for which n x n similar pieces would be
/// needles (n follows the longest side, so a sliver would get n^2 pieces for
/// an area worth about n). The triangle is cut by lines perpendicular to its
/// longest side AB, at most e apart (one of them through the apex C); each
/// line is cut into pieces of at most e, and neighbouring lines are zipped
/// into triangles, so no piece is longer than about sqrt(2) e whatever the
/// triangle's shape. AB is cut uniformly; the other two sides are cut where
/// the lines meet them.
class ColumnDicer {
public:
    struct Plan {
        int first = 0;          ///< corner starting the longest side AB
        double longest = 0.0;   ///< |AB|
        double height = 0.0;    ///< distance of C from AB
        double foot = 0.0;      ///< where C projects onto AB, as a fraction of AB
        std::size_t pieces = 0; ///< uniform cuts of AB
        std::size_t micropolygons = 0;
        std::size_t vertices = 0;
    };

    static Plan plan(const Primitive& prim, const DiceControl& control,
                     const std::array<glm::dvec3, 3>& p, double e) {
        Plan plan;
        for (int k = 0; k < 3; ++k) {
            const double len = glm::length(p[(k + 1) % 3] - p[k]);
            if (len > plan.longest) {
                plan.longest = len;
                plan.first = k;
            }
        }
        const glm::dvec3 &a = p[plan.first], &b = p[(plan.first + 1) % 3],
                         &c = p[(plan.first + 2) % 3];
        const glm::dvec3 ab = b - a;
        // C projects inside AB: AB is the longest side, so A and B are acute.
        plan.foot = std::clamp(glm::dot(c - a, ab) / glm::dot(ab, ab), 0.0, 1.0);
        plan.height = glm::length(glm::cross(ab, c - a)) / plan.longest;
        plan.pieces = piece_count(prim, control, plan.longest, e);
        piece_count(prim, control, plan.height, e); // budget check of the tallest line
        bool first = true;
        std::size_t previous = 0;
        for_each_line(plan, [&](std::size_t, double u, bool) {
            const std::size_t q = line_pieces(plan, u, e);
            plan.vertices += q + 1;
            if (!first) plan.micropolygons += previous + q;
            first = false;
            previous = q;
        });
        return plan;
    }

    void dice(const TriangleCorners& t, const Plan& plan, double e,
              const glm::dvec3& face_normal, bool user_normals, SurfaceWriter& w) {
        const int r = plan.first;
        const glm::dvec3 &a = t.p[r], &b = t.p[(r + 1) % 3], &c = t.p[(r + 2) % 3];
        auto blend = [&](const std::array<glm::dvec3, 3>& v, const glm::dvec3& bary) {
            return bary.x * v[r] + bary.y * v[(r + 1) % 3] + bary.z * v[(r + 2) % 3];
        };
        auto normal_at = [&](const glm::dvec3& bary) {
            if (!user_normals) return face_normal;
            const glm::dvec3 n =
                NormalTransform::safe_normalize(blend(t.user_normal, bary));
            return glm::dot(n, n) > 0.0 ? n : face_normal;
        };
        m_points.clear();
        m_bary.clear();
        m_line_start.clear();
        const std::size_t base = w.vertex;
        const double n0 = static_cast<double>(plan.pieces);
        for_each_line(plan, [&](std::size_t i, double u, bool uniform) {
            m_line_start.push_back(m_points.size());
            // Foot of the line on AB (from AB's ends only when on the uniform
            // cuts: watertight seams) and its top on AC or BC.
            const glm::dvec3 foot = uniform ? a * (double(plan.pieces - i) / n0) + b * u
                                            : a * (1.0 - u) + b * u;
            const glm::dvec3 foot_bary(1.0 - u, u, 0.0);
            glm::dvec3 top_bary;
            if (u <= plan.foot && plan.foot > 0.0) {
                const double v = u / plan.foot;
                top_bary = glm::dvec3(1.0 - v, 0.0, v);
            } else {
                const double v = (1.0 - u) / (1.0 - plan.foot);
                top_bary = glm::dvec3(0.0, 1.0 - v, v);
            }
            const glm::dvec3 top =
                u == plan.foot ? c : a * top_bary.x + b * top_bary.y + c * top_bary.z;
            const std::size_t q = line_pieces(plan, u, e);
            for (std::size_t j = 0; j <= q; ++j) {
                const double v = q > 0 ? double(j) / double(q) : 0.0;
                const glm::dvec3 p = j == 0   ? foot
                                     : j == q ? top
                                              : foot + v * (top - foot);
                const glm::dvec3 bary = foot_bary + v * (top_bary - foot_bary);
                m_points.push_back(p);
                m_bary.push_back(bary);
                w.add_vertex(p, normal_at(bary));
            }
        });
        m_line_start.push_back(m_points.size());
        auto emit = [&](std::size_t i0, std::size_t i1, std::size_t i2) {
            w.add_triangle(base + i0, base + i1, base + i2);
            const glm::dvec3 &p0 = m_points[i0], &p1 = m_points[i1], &p2 = m_points[i2];
            const glm::dvec3 centre = (p0 + p1 + p2) * (1.0 / 3.0);
            const double area = 0.5 * glm::length(glm::cross(p1 - p0, p2 - p0));
            const double radius = std::sqrt(std::max(
                {glm::dot(p0 - centre, p0 - centre), glm::dot(p1 - centre, p1 - centre),
                 glm::dot(p2 - centre, p2 - centre)}));
            const glm::dvec3 bary = (m_bary[i0] + m_bary[i1] + m_bary[i2]) * (1.0 / 3.0);
            const glm::dvec3 col = w.with_colors ? blend(t.color, bary) : glm::dvec3(0.0);
            w.micropolygon(centre, normal_at(bary), area, radius, col);
        };
        // Zip each pair of neighbouring lines from AB upwards, always taking
        // the shorter of the two possible next rungs (compact triangles).
        auto dist2 = [&](std::size_t p, std::size_t q) {
            const glm::dvec3 d = m_points[p] - m_points[q];
            return glm::dot(d, d);
        };
        for (std::size_t k = 0; k + 2 < m_line_start.size(); ++k) {
            const std::size_t l = m_line_start[k], r2 = m_line_start[k + 1];
            const std::size_t ql = r2 - l - 1, qr = m_line_start[k + 2] - r2 - 1;
            std::size_t i = 0, j = 0;
            while (i < ql || j < qr) {
                const bool left = j == qr || (i < ql && dist2(l + i + 1, r2 + j) <=
                                                            dist2(l + i, r2 + j + 1));
                if (left) {
                    emit(l + i, r2 + j, l + i + 1);
                    ++i;
                } else {
                    emit(l + i, r2 + j, r2 + j + 1);
                    ++j;
                }
            }
        }
    }

private:
    std::vector<std::size_t> m_line_start;
    std::vector<glm::dvec3> m_points;
    std::vector<glm::dvec3> m_bary;

    /// Calls f(cut, u, uniform) for every line, by increasing u (fraction of
    /// AB): the uniform cuts u = cut / pieces (uniform true), and the apex's
    /// foot (uniform false) unless it falls on one of them.
    template <typename F>
    static void for_each_line(const Plan& plan, F&& f) {
        const double n0 = static_cast<double>(plan.pieces);
        bool foot_done = false;
        for (std::size_t i = 0; i <= plan.pieces; ++i) {
            const double u = double(i) / n0;
            if (!foot_done && plan.foot < u) {
                f(i, plan.foot, false);
                foot_done = true;
            }
            if (u == plan.foot) foot_done = true;
            f(i, u, true);
        }
    }

    /// Pieces of the line at u: its length over e, rounded up (0 at a corner).
    static std::size_t line_pieces(const Plan& plan, double u, double e) {
        double fraction = 0.0;
        if (u <= plan.foot && plan.foot > 0.0)
            fraction = u / plan.foot;
        else if (plan.foot < 1.0)
            fraction = (1.0 - u) / (1.0 - plan.foot);
        else
            fraction = 1.0;
        const double len = fraction * plan.height;
        return len > 0.0 ? std::max<std::size_t>(1, std::size_t(std::ceil(len / e))) : 0;
    }
};

/// An orthonormal basis (u, v) of the plane with normal n, with u x v = n, so
/// a loop wound counter-clockwise about n is counter-clockwise in (u, v).
void plane_basis(const glm::dvec3& n, glm::dvec3& u, glm::dvec3& v) {
    const glm::dvec3 a = std::abs(n.x) < 0.6   ? glm::dvec3(1, 0, 0)
                         : std::abs(n.y) < 0.6 ? glm::dvec3(0, 1, 0)
                                               : glm::dvec3(0, 0, 1);
    u = glm::normalize(glm::cross(a, n));
    v = glm::cross(n, u);
}

} // namespace

DicedSurface dice_polygons(const Primitive& prim, const DiceControl& control) {
    const Attributes& attr = attributes_of(prim);
    const std::vector<glm::dvec3> points = read_positions(prim);
    const PolygonTopology topo = polygon_topology(prim, points.size());
    const std::size_t nfaces = topo.face_loops.size() - 1;
    const std::size_t ncorners = topo.corner_point.size();
    const CornerVec3 cs(prim, "Cs", nfaces, topo.points_referenced, ncorners);
    const CornerVec3 user_n(prim, "N", nfaces, topo.points_referenced, ncorners);
    const NormalTransform normals(prim);
    const Matrix4& m = prim.object_to_world;

    std::vector<glm::dvec3> world(points.size());
    std::vector<double> edge(points.size(), 0.0);
    {
        std::vector<uint8_t> used(points.size(), 0);
        for (uint32_t p : topo.corner_point) used[p] = 1;
        for (std::size_t i = 0; i < points.size(); ++i) {
            world[i] = to_world(m, points[i]);
            if (used[i])
                edge[i] = edge_length(prim, control, world[i], attr.shading_rate);
        }
    }

    // Convex quads stay quads (diced like REYES grids); every other face is
    // triangulated in object space (affine maps keep the result valid).
    std::vector<FaceJob> jobs;
    jobs.reserve(ncorners);
    std::vector<glm::dvec3> face_normal(nfaces, glm::dvec3(0.0));
    Triangulator triangulator;
    std::vector<glm::dvec2> flat;
    std::vector<int> loop_sizes;
    std::vector<std::array<int, 3>> local;
    for (std::size_t f = 0; f < nfaces; ++f) {
        const int l0 = topo.face_loops[f], l1 = topo.face_loops[f + 1];
        const auto c0 = static_cast<uint32_t>(topo.loop_corners[l0]);
        const auto c1 = static_cast<uint32_t>(topo.loop_corners[l0 + 1]);
        auto at = [&](uint32_t c) -> const glm::dvec3& {
            return points[topo.corner_point[c]];
        };
        // Newell normal of the outer loop: RenderMan's formula normal.
        const glm::dvec3 origin = at(c0);
        glm::dvec3 newell(0.0);
        for (uint32_t c = c0 + 1; c + 1 < c1; ++c)
            newell += glm::cross(at(c) - origin, at(c + 1) - origin);
        if (!(glm::dot(newell, newell) > 0.0)) continue; // no area at all
        face_normal[f] = world_normal(m, newell, attr.orientation_inside);
        const auto face = static_cast<uint32_t>(f);
        if (l1 - l0 == 1 && c1 - c0 == 3) {
            jobs.push_back({{c0, c0 + 1, c0 + 2, 0}, face, 3, {0, 0}, false});
            continue;
        }
        if (l1 - l0 == 1 && c1 - c0 == 4) {
            bool convex = true;
            for (uint32_t k = 0; k < 4; ++k) {
                const glm::dvec3& p = at(c0 + k);
                const glm::dvec3 turn =
                    glm::cross(at(c0 + (k + 1) % 4) - p, at(c0 + (k + 3) % 4) - p);
                convex = convex && glm::dot(turn, newell) > 0.0;
            }
            if (convex) {
                jobs.push_back({{c0, c0 + 1, c0 + 2, c0 + 3}, face, 4, {0, 0}, false});
                continue;
            }
        }
        glm::dvec3 u, v;
        plane_basis(glm::normalize(newell), u, v);
        const auto cend = static_cast<uint32_t>(topo.loop_corners[l1]);
        flat.clear();
        for (uint32_t c = c0; c < cend; ++c) {
            const glm::dvec3 d = at(c) - origin;
            flat.emplace_back(glm::dot(d, u), glm::dot(d, v));
        }
        loop_sizes.clear();
        for (int l = l0; l < l1; ++l)
            loop_sizes.push_back(topo.loop_corners[l + 1] - topo.loop_corners[l]);
        local.clear();
        triangulator.run(flat, loop_sizes, local);
        for (const auto& t : local)
            jobs.push_back(
                {{c0 + t[0], c0 + t[1], c0 + t[2], 0}, face, 3, {0, 0}, false});
    }

    // Piece counts, then exact output sizes.
    std::size_t total_mp = 0, total_vertices = 0, total_triangles = 0;
    for (FaceJob& job : jobs) {
        std::array<glm::dvec3, 4> w;
        double e = std::numeric_limits<double>::infinity();
        for (uint32_t k = 0; k < job.corners; ++k) {
            const uint32_t p = topo.corner_point[job.corner[k]];
            w[k] = world[p];
            e = std::min(e, edge[p]);
        }
        if (job.corners == 4) {
            const std::size_t nu = piece_count(
                prim, control,
                std::max(glm::length(w[1] - w[0]), glm::length(w[2] - w[3])), e);
            const std::size_t nv = piece_count(
                prim, control,
                std::max(glm::length(w[3] - w[0]), glm::length(w[2] - w[1])), e);
            job.pieces[0] = static_cast<uint32_t>(nu);
            job.pieces[1] = static_cast<uint32_t>(nv);
            total_mp += nu * nv;
            total_vertices += (nu + 1) * (nv + 1);
            total_triangles += 2 * nu * nv;
        } else {
            const double longest = std::sqrt(std::max(
                {glm::dot(w[1] - w[0], w[1] - w[0]), glm::dot(w[2] - w[1], w[2] - w[1]),
                 glm::dot(w[0] - w[2], w[0] - w[2])}));
            const double area2 = glm::length(glm::cross(w[1] - w[0], w[2] - w[0]));
            // Zero-area (collinear or repeated corner) triangles add nothing.
            if (!(area2 > 1e-12 * longest * longest)) continue;
            // Sub-triangle edges up to sqrt(2) e, the diagonal of an e x e
            // micropolygon: a right triangle's sub-triangles pair up into e x e
            // squares, and the count stays near area / e^2 (with n = longest / e
            // triangles would get 2.3 to 4.6 times as many micropolygons as quads).
            const std::size_t n = piece_count(prim, control, longest / std::sqrt(2.0), e);
            job.pieces[0] = static_cast<uint32_t>(n);
            const ColumnDicer::Plan columns =
                n > 2 ? ColumnDicer::plan(prim, control, {w[0], w[1], w[2]}, e)
                      : ColumnDicer::Plan{};
            // Slivers: columns when they need less than half the pieces.
            job.columns = n > 2 && 2 * columns.micropolygons < n * n;
            if (job.columns) {
                total_mp += columns.micropolygons;
                total_vertices += columns.vertices;
                total_triangles += columns.micropolygons;
            } else {
                total_mp += n * n;
                total_vertices += (n + 1) * (n + 2) / 2;
                total_triangles += n * n;
            }
        }
        check_budget(prim, control, total_mp);
    }

    DicedSurface out;
    allocate(prim, out, total_mp, total_vertices, total_triangles, cs.present());
    SurfaceWriter writer{out, cs.present()};
    TriangleCorners tri;
    QuadCorners quad;
    QuadDicer quad_dicer;
    ColumnDicer column_dicer;
    for (const FaceJob& job : jobs) {
        if (job.pieces[0] == 0) continue;
        const glm::dvec3& n = face_normal[job.face];
        for (uint32_t k = 0; k < job.corners; ++k) {
            const uint32_t c = job.corner[k];
            const uint32_t p = topo.corner_point[c];
            const glm::dvec3 un =
                user_n.present() ? normals.user(user_n.at(job.face, p, c)) : n;
            const glm::dvec3 col = cs.present() ? cs.at(job.face, p, c) : glm::dvec3(0.0);
            if (job.corners == 4) {
                quad.p[k] = world[p];
                quad.normal[k] = un;
                quad.color[k] = col;
            } else {
                tri.p[k] = world[p];
                tri.user_normal[k] = un;
                tri.color[k] = col;
            }
        }
        if (job.corners == 4) {
            quad.fallback_normal = n;
            quad_dicer.dice(quad, job.pieces[0], job.pieces[1], writer);
        } else if (job.columns) {
            double e = std::numeric_limits<double>::infinity();
            for (uint32_t k = 0; k < 3; ++k)
                e = std::min(e, edge[topo.corner_point[job.corner[k]]]);
            column_dicer.dice(tri, ColumnDicer::plan(prim, control, tri.p, e), e, n,
                              user_n.present(), writer);
        } else {
            dice_triangle(tri, job.pieces[0], n, user_n.present(), writer);
        }
    }
    writer.finish();
    return out;
}

// ---------------------------------------------------------------------------
// Subdivision meshes

namespace {

/// Refinement stops before a level would exceed this many faces (memory);
/// the bilinear dicing of the last level still reaches the dicing length.
constexpr std::size_t kMaxRefinedFaces = std::size_t(1) << 20;
constexpr int kMaxLevels = 8;

} // namespace

DicedSurface dice_subdivision(const Primitive& prim, const DiceControl& control) {
    const Attributes& attr = attributes_of(prim);
    const Matrix4& m = prim.object_to_world;
    const NormalTransform normals(prim);
    // "N" is not used: the limit surface has exact normals of its own.
    SubdivMesh mesh = build_subdiv_mesh(prim);

    std::vector<glm::dvec3> world;
    std::vector<double> edge;
    auto measure = [&](const std::vector<glm::dvec3>& points) {
        world.resize(points.size());
        edge.resize(points.size());
        for (std::size_t i = 0; i < points.size(); ++i) {
            world[i] = to_world(m, points[i]);
            edge[i] = edge_length(prim, control, world[i], attr.shading_rate);
        }
    };
    // Uniform refinement until every control edge is at most twice the dicing
    // length at its ends; the first step is forced when faces are not quads.
    const std::size_t face_budget = std::min(kMaxRefinedFaces, control.max_micropolygons);
    for (int level = 0;; ++level) {
        if (mesh.all_quads()) {
            if (level >= kMaxLevels ||
                static_cast<std::size_t>(mesh.corner_count()) > face_budget)
                break;
            measure(mesh.points);
            bool fine = true;
            for (const auto& [a, b] : mesh.edge_vertices)
                if (glm::length(world[a] - world[b]) > 2.0 * std::min(edge[a], edge[b])) {
                    fine = false;
                    break;
                }
            if (fine) break;
        }
        mesh = refine_subdiv_mesh(mesh);
    }

    const SubdivLimit limit = subdiv_limit(mesh);
    measure(limit.points);
    std::vector<glm::dvec3> corner_normal(limit.corner_normals.size());
    for (std::size_t c = 0; c < corner_normal.size(); ++c)
        corner_normal[c] = normals.geometric(limit.corner_normals[c]);

    // Sub-quad counts per face, then exact output sizes.
    const int nf = mesh.face_count();
    std::vector<std::array<uint32_t, 2>> pieces(nf, {0, 0});
    std::size_t total_mp = 0, total_vertices = 0;
    for (int f = 0; f < nf; ++f) {
        if (mesh.face_hole[f]) continue;
        const int* v = &mesh.corner_vertex[4 * f];
        const double e = std::min({edge[v[0]], edge[v[1]], edge[v[2]], edge[v[3]]});
        const double lu = std::max(glm::length(world[v[1]] - world[v[0]]),
                                   glm::length(world[v[2]] - world[v[3]]));
        const double lv = std::max(glm::length(world[v[3]] - world[v[0]]),
                                   glm::length(world[v[2]] - world[v[1]]));
        const std::size_t nu = piece_count(prim, control, lu, e);
        const std::size_t nv = piece_count(prim, control, lv, e);
        pieces[f] = {static_cast<uint32_t>(nu), static_cast<uint32_t>(nv)};
        total_mp += nu * nv;
        total_vertices += (nu + 1) * (nv + 1);
        check_budget(prim, control, total_mp);
    }

    const bool with_colors = !mesh.corner_colors.empty();
    DicedSurface out;
    allocate(prim, out, total_mp, total_vertices, 2 * total_mp, with_colors);
    SurfaceWriter writer{out, with_colors};
    QuadDicer dicer;
    QuadCorners q;
    for (int f = 0; f < nf; ++f) {
        if (pieces[f][0] == 0) continue;
        for (int k = 0; k < 4; ++k) {
            const std::size_t c = 4 * static_cast<std::size_t>(f) + k;
            q.p[k] = world[mesh.corner_vertex[c]];
            q.normal[k] = corner_normal[c];
            if (with_colors) q.color[k] = glm::dvec3(mesh.corner_colors[c]);
        }
        q.fallback_normal = normals.geometric_from_world_cross(
            glm::cross(q.p[2] - q.p[0], q.p[3] - q.p[1]));
        dicer.dice(q, pieces[f][0], pieces[f][1], writer);
    }
    writer.finish();
    return out;
}

} // namespace sss::detail
