// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file dice_polygon.cpp
/// Dicing of polygons (Polygon, GeneralPolygon, PointsPolygons,
/// PointsGeneralPolygons).
///
/// Convex quads are diced like REYES grids, as bilinear patches of
/// nu x nv sub-quads (one micropolygon each, made of two triangles). Every
/// other face is triangulated in the plane of its Newell normal (ear clipping,
/// holes joined to the outer loop by bridges), and every triangle is cut into
/// n x n similar sub-triangles in world space, one micropolygon each, with n
/// = ceil(longest side / (sqrt(2) e)). Thin triangles, for which that would
/// make n^2 needles, are cut in columns across their longest side instead.
///
/// Watertightness: points on a face's border are computed from that border
/// edge's two end points only, with integer-quotient weights, so two faces
/// that cut a shared edge into the same number of pieces produce bit-identical
/// vertices there. Faces that choose different counts meet in T-junctions;
/// since both sides put their points on the same straight segment, the
/// cracks are only rounding-sized (the ray tracer's epsilon covers them).

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include "dice_common.h"
#include "mesh_common.h"
#include "triangulator.h"

namespace sss::detail {

namespace {

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
        fail(prim, "loop " + std::to_string(loop) + " has " + std::to_string(n) +
                       " vertices (at least 3 needed)");
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
        if (prim.nverts.empty()) fail(prim, "no loops");
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
        fail(prim, "not a polygon primitive");
    }
    if (nloops.empty()) fail(prim, "no faces");

    std::size_t loop_total = 0;
    for (std::size_t f = 0; f < nloops.size(); ++f) {
        if (nloops[f] < 1)
            fail(prim, "face " + std::to_string(f) + " has " + std::to_string(nloops[f]) +
                           " loops");
        loop_total += static_cast<std::size_t>(nloops[f]);
    }
    if (loop_total != nverts->size())
        fail(prim, "nloops add up to " + std::to_string(loop_total) + " but " +
                       std::to_string(nverts->size()) + " loop sizes are given");
    std::size_t corner_total = 0;
    for (std::size_t l = 0; l < nverts->size(); ++l) {
        check_loop_size(prim, (*nverts)[l], l);
        corner_total += static_cast<std::size_t>((*nverts)[l]);
    }
    if (corner_total > std::numeric_limits<int32_t>::max())
        fail(prim, "too many vertices");

    t.corner_point.resize(corner_total);
    if (indexed) {
        if (prim.verts.size() != corner_total)
            fail(prim, "nverts add up to " + std::to_string(corner_total) + " but " +
                           std::to_string(prim.verts.size()) +
                           " vertex indices are given");
        for (std::size_t c = 0; c < corner_total; ++c) {
            const int v = prim.verts[c];
            if (v < 0 || static_cast<std::size_t>(v) >= npoints)
                fail(prim, "vertex index " + std::to_string(v) + " out of range (" +
                               std::to_string(npoints) + " points in \"P\")");
            t.corner_point[c] = static_cast<uint32_t>(v);
            t.points_referenced =
                std::max(t.points_referenced, static_cast<std::size_t>(v) + 1);
        }
    } else {
        if (corner_total != npoints)
            fail(prim, "\"P\" has " + std::to_string(npoints) + " points, " +
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
    /// Texture coordinates, for DicedSurface::vertex_uvst (u and v are 0:
    /// triangles have no parametrisation).
    std::array<glm::dvec2, 3> st{glm::dvec2(0.0), glm::dvec2(0.0), glm::dvec2(0.0)};
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
            if (w.with_parametric)
                w.vertex_parametric(0.0, 0.0, b0 * t.st[0] + b1 * t.st[1] + b2 * t.st[2]);
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
        plan.first = static_cast<int>(control.note(plan.first, prim));
        const glm::dvec3 &a = p[plan.first], &b = p[(plan.first + 1) % 3],
                         &c = p[(plan.first + 2) % 3];
        const glm::dvec3 ab = b - a;
        // C projects inside AB: AB is the longest side, so A and B are acute.
        plan.foot = std::clamp(glm::dot(c - a, ab) / glm::dot(ab, ab), 0.0, 1.0);
        plan.height = glm::length(glm::cross(ab, c - a)) / plan.longest;
        // The cut follows from these (motion blur replays them).
        plan.foot = control.note(plan.foot, prim);
        plan.height = control.note(plan.height, prim);
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
                if (w.with_parametric)
                    w.vertex_parametric(0.0, 0.0,
                                        bary.x * t.st[r] + bary.y * t.st[(r + 1) % 3] +
                                            bary.z * t.st[(r + 2) % 3]);
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

/// The u and v of a quad's corners, in winding order.
constexpr std::array<glm::dvec2, 4> kQuadUV{glm::dvec2(0, 0), glm::dvec2(1, 0),
                                            glm::dvec2(1, 1), glm::dvec2(0, 1)};

/// The world position of every point, and the micropolygon edge length at
/// every point a corner uses (0 at the others).
void world_points(const Primitive& prim, const DiceControl& control,
                  const Attributes& attr, const PolygonTopology& topo,
                  const std::vector<glm::dvec3>& points, std::vector<glm::dvec3>& world,
                  std::vector<double>& edge) {
    const Matrix4& m = prim.object_to_world;
    std::vector<uint8_t> used(points.size(), 0);
    for (uint32_t p : topo.corner_point) used[p] = 1;
    for (std::size_t i = 0; i < points.size(); ++i) {
        world[i] = to_world(m, points[i]);
        if (used[i]) {
            check_world_point(prim, world[i]);
            edge[i] = control.note(
                edge_length(prim, control, world[i], attr.shading_rate), prim);
        }
    }
}

/// Adds the faces' estimate: per face its outer loop's area, every loop's
/// perimeter, the finest edge at its corners; a convex quad is one piece,
/// anything else about as many triangles as corners.
void estimate_polygons(const PolygonTopology& topo, const std::vector<glm::dvec3>& world,
                       const std::vector<double>& edge, DiceEstimate& estimate) {
    const std::size_t nfaces = topo.face_loops.size() - 1;
    for (std::size_t f = 0; f < nfaces; ++f) {
        const int l0 = topo.face_loops[f], l1 = topo.face_loops[f + 1];
        const auto c0 = static_cast<std::size_t>(topo.loop_corners[l0]);
        const auto c1 = static_cast<std::size_t>(topo.loop_corners[l0 + 1]);
        const auto cend = static_cast<std::size_t>(topo.loop_corners[l1]);
        const auto at = [&](std::size_t c) -> const glm::dvec3& {
            return world[topo.corner_point[c]];
        };
        glm::dvec3 newell(0.0);
        for (std::size_t c = c0 + 1; c + 1 < c1; ++c)
            newell += glm::cross(at(c) - at(c0), at(c + 1) - at(c0));
        double perimeter = 0.0, e = std::numeric_limits<double>::infinity();
        for (int l = l0; l < l1; ++l) {
            const auto b = static_cast<std::size_t>(topo.loop_corners[l]);
            const auto n = static_cast<std::size_t>(topo.loop_corners[l + 1]) - b;
            for (std::size_t k = 0; k < n; ++k) {
                perimeter += glm::length(at(b + (k + 1) % n) - at(b + k));
                e = std::min(e, edge[topo.corner_point[b + k]]);
            }
        }
        const double corners = static_cast<double>(cend - c0);
        const double pieces = l1 - l0 == 1 && corners == 4 ? 1.0 : corners - 2.0;
        estimate += estimate_flat_face(0.5 * glm::length(newell), perimeter, e, pieces);
    }
}

/// Convex quads stay quads (diced like REYES grids); every other face is
/// triangulated in object space (affine maps keep the result valid). Also
/// the world normal of every face (0 for a face without area).
void face_jobs(const PolygonTopology& topo, const std::vector<glm::dvec3>& points,
               const Matrix4& m, const Attributes& attr, std::vector<FaceJob>& jobs,
               std::vector<glm::dvec3>& face_normal) {
    const std::size_t nfaces = topo.face_loops.size() - 1;
    const std::size_t ncorners = topo.corner_point.size();
    jobs.reserve(ncorners);
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
}

/// The output's sizes.
struct DiceTotals {
    std::size_t mp = 0, vertices = 0, triangles = 0;
};

/// The piece counts of every job (and whether a triangle is diced in
/// columns), then the exact output sizes, checked against the budget.
DiceTotals count_pieces(const Primitive& prim, const DiceControl& control,
                        const PolygonTopology& topo, const std::vector<glm::dvec3>& world,
                        const std::vector<double>& edge, std::vector<FaceJob>& jobs) {
    DiceTotals total;
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
            total.mp += nu * nv;
            total.vertices += (nu + 1) * (nv + 1);
            total.triangles += 2 * nu * nv;
        } else {
            const double longest = std::sqrt(std::max(
                {glm::dot(w[1] - w[0], w[1] - w[0]), glm::dot(w[2] - w[1], w[2] - w[1]),
                 glm::dot(w[0] - w[2], w[0] - w[2])}));
            const double area2 = glm::length(glm::cross(w[1] - w[0], w[2] - w[0]));
            // Zero-area (collinear or repeated corner) triangles add nothing.
            if (!(control.note(area2 > 1e-12 * longest * longest ? 1.0 : 0.0, prim) >
                  0.5))
                continue;
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
                total.mp += columns.micropolygons;
                total.vertices += columns.vertices;
                total.triangles += columns.micropolygons;
            } else {
                total.mp += n * n;
                total.vertices += (n + 1) * (n + 2) / 2;
                total.triangles += n * n;
            }
        }
        check_budget(prim, control, total.mp);
    }
    return total;
}

} // namespace

DicedSurface dice_polygons(const Primitive& prim, const DiceControl& control,
                           DiceEstimate* estimate) {
    const Attributes& attr = attributes_of(prim);
    const std::vector<glm::dvec3> points = read_positions(prim);
    const PolygonTopology topo = polygon_topology(prim, points.size());
    const std::size_t nfaces = topo.face_loops.size() - 1;
    const std::size_t ncorners = topo.corner_point.size();
    const CornerVec3 cs(prim, "Cs", nfaces, topo.points_referenced, ncorners);
    const CornerVec3 user_n(prim, "N", nfaces, topo.points_referenced, ncorners);
    const CornerTexCoords st(prim, nfaces, topo.points_referenced, ncorners);
    const NormalTransform normals(prim);
    const Matrix4& m = prim.object_to_world;

    std::vector<glm::dvec3> world(points.size());
    std::vector<double> edge(points.size(), 0.0);
    world_points(prim, control, attr, topo, points, world, edge);
    if (estimate) {
        estimate_polygons(topo, world, edge, *estimate);
        return {};
    }

    std::vector<FaceJob> jobs;
    std::vector<glm::dvec3> face_normal(nfaces, glm::dvec3(0.0));
    face_jobs(topo, points, m, attr, jobs, face_normal);
    const DiceTotals total = count_pieces(prim, control, topo, world, edge, jobs);

    DicedSurface out;
    allocate(prim, out, total.mp, total.vertices, total.triangles, cs.present());
    SurfaceWriter writer{out, cs.present(), control.grids};
    if (control.displace) {
        writer.displace = &control.displace;
        writer.prim = &prim;
    }
    if (control.grids) out.resize_parametric(total.mp, total.vertices);
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
                if (st.present()) quad.st[k] = st.at(job.face, p, c, kQuadUV[k]);
            } else {
                tri.p[k] = world[p];
                tri.user_normal[k] = un;
                tri.color[k] = col;
                tri.st[k] = st.at(job.face, p, c, glm::dvec2(0.0));
            }
        }
        const std::size_t vertex0 = writer.vertex, mp0 = writer.mp,
                          triangle0 = writer.triangle;
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
        if (writer.displace && job.corners != 4)
            displace_triangles(writer, vertex0, mp0, triangle0);
    }
    writer.finish();
    return out;
}

} // namespace sss::detail
