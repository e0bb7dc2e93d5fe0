// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file subdivision.cpp
/// Catmull–Clark subdivision of RenderMan SubdivisionMesh primitives: level-0
/// topology and tags, one refinement step (smooth, boundary, crease and corner
/// rules with semi-sharp creases), and the limit positions and normals.
///
/// Boundaries. RenderMan renders the faces touching a boundary only with the
/// "interpolateboundary" tag; without it the surface stops at the limit of the
/// interior faces. Dropping faces would silently lose surface (and baked
/// area), so boundary faces are always kept here and boundary edges always
/// follow the cubic B-spline curve rule. The tag's argument chooses what
/// happens at boundary corners (vertices with a single face): 1 (the default
/// when the tag has no argument) pins them as sharp corners, 2 ("edges only")
/// and 0 smooth them along the boundary curve; no tag behaves like 0.
///
/// Semi-sharp creases use the standard rule (DeRose et al. 1998): an edge of
/// sharpness s >= 1 is subdivided with the sharp rule and its two halves get
/// s - 1; 0 < s < 1 blends the smooth and sharp results with weight s. Vertex
/// rules blend the same way with the mean sharpness of the sharp edges at the
/// vertex. "corner" sharpness decrements the same way.

#include "subdivision.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include <glm/geometric.hpp>

#include "mesh_common.h"
#include "sss/util/math.h"

namespace sss::detail {

namespace {

constexpr float kInfinitelySharp = std::numeric_limits<float>::infinity();

uint64_t edge_key(int a, int b) {
    const auto lo = static_cast<uint64_t>(std::min(a, b));
    const auto hi = static_cast<uint64_t>(std::max(a, b));
    return (lo << 32) | hi;
}

/// Sharpness after one subdivision step (infinity stays infinite).
float decremented(float s) {
    return s > 1.0f ? s - 1.0f : 0.0f;
}

/// Blend weight of a sharp rule for sharpness s: 0 smooth, 1 fully sharp.
double sharp_weight(double s) {
    return std::min(1.0, std::max(0.0, s));
}

/// Sorted (key, edge) pairs for finding the edge between two vertices.
using EdgeIndex = std::vector<std::pair<uint64_t, int>>;

int find_edge(const EdgeIndex& index, int a, int b) {
    const uint64_t key = edge_key(a, b);
    const auto it = std::lower_bound(index.begin(), index.end(), std::make_pair(key, -1));
    return it != index.end() && it->first == key ? it->second : -1;
}

/// Per-vertex sums one refinement or limit pass scatters from faces and edges,
/// so that no vertex-to-neighbour lists are needed.
struct VertexSums {
    std::vector<glm::dvec3> sharp_neighbours; ///< other ends of sharp edges
    std::vector<int> edges;                   ///< incident edges
    std::vector<int> faces;                   ///< incident faces
    std::vector<int> sharp_edges;             ///< incident edges with sharpness > 0
    std::vector<float> sharpness;             ///< sum of those sharpnesses

    void scatter_edges(const SubdivMesh& m) {
        const auto nv = static_cast<std::size_t>(m.vertex_count());
        sharp_neighbours.assign(nv, glm::dvec3(0.0));
        edges.assign(nv, 0);
        faces.assign(nv, 0);
        sharp_edges.assign(nv, 0);
        sharpness.assign(nv, 0.0f);
        for (int e = 0; e < m.edge_count(); ++e) {
            const auto [a, b] = m.edge_vertices[e];
            ++edges[a];
            ++edges[b];
            const float s = m.edge_sharpness[e];
            if (s > 0.0f) {
                sharp_neighbours[a] += m.points[b];
                sharp_neighbours[b] += m.points[a];
                ++sharp_edges[a];
                ++sharp_edges[b];
                sharpness[a] += s;
                sharpness[b] += s;
            }
        }
        for (int v : m.corner_vertex) ++faces[v];
    }

    /// Weight of the sharp (crease or corner) rule at v: 0 when fewer than two
    /// sharp edges meet there (smooth vertex or dart).
    double crease_weight(int v) const {
        if (sharp_edges[v] < 2) return 0.0;
        return sharp_weight(static_cast<double>(sharpness[v]) / sharp_edges[v]);
    }
};

} // namespace

bool SubdivMesh::all_quads() const {
    for (int f = 0; f < face_count(); ++f)
        if (face_start[f + 1] - face_start[f] != 4) return false;
    return true;
}

namespace {

/// Applies the tags (creases, corners, holes) to `m`, whose edges are in
/// `edge_index`; returns the interpolateboundary mode (0 without the tag).
int apply_tags(const Primitive& prim, const EdgeIndex& edge_index, SubdivMesh& m) {
    const int npoints = static_cast<int>(m.points.size());
    const int nfaces = static_cast<int>(prim.nverts.size());
    if (prim.tag_nargs.size() != 2 * prim.tags.size())
        fail(prim, "tags need 2 argument counts each (" +
                       std::to_string(prim.tags.size()) + " tags, " +
                       std::to_string(prim.tag_nargs.size()) + " counts)");
    int boundary_mode = 0;
    std::size_t ip = 0, fp = 0;
    for (std::size_t t = 0; t < prim.tags.size(); ++t) {
        const int ni = prim.tag_nargs[2 * t], nf = prim.tag_nargs[2 * t + 1];
        if (ni < 0 || nf < 0 || ip + ni > prim.tag_intargs.size() ||
            fp + nf > prim.tag_floatargs.size())
            fail(prim, "tag \"" + prim.tags[t] +
                           "\" has more arguments than the tag lists hold");
        const int* ints = prim.tag_intargs.data() + ip;
        const double* floats = prim.tag_floatargs.data() + fp;
        ip += ni;
        fp += nf;
        const std::string& tag = prim.tags[t];
        auto sharpness_arg = [&](double s) {
            if (std::isnan(s)) fail(prim, "tag \"" + tag + "\": NaN sharpness");
            return static_cast<float>(std::max(0.0, s));
        };
        auto vertex_arg = [&](int v) {
            if (v < 0 || v >= npoints)
                fail(prim, "tag \"" + tag + "\": vertex " + std::to_string(v) +
                               " out of range");
            return v;
        };
        if (tag == "interpolateboundary") {
            boundary_mode = ni > 0 ? ints[0] : 1;
        } else if (tag == "crease") {
            if (ni < 2 || nf < 1)
                fail(prim, "tag \"crease\" needs at least 2 vertices and a "
                           "sharpness");
            const float s = sharpness_arg(floats[0]);
            for (int k = 0; k + 1 < ni; ++k) {
                // A crease between vertices with no edge between them is ignored,
                // as the renderers do.
                const int e =
                    find_edge(edge_index, vertex_arg(ints[k]), vertex_arg(ints[k + 1]));
                if (e >= 0 && m.edge_faces[e][1] >= 0) m.edge_sharpness[e] = s;
            }
        } else if (tag == "corner") {
            if (ni > 0 && nf < 1) fail(prim, "tag \"corner\" needs a sharpness");
            for (int k = 0; k < ni; ++k)
                m.vertex_sharpness[vertex_arg(ints[k])] =
                    sharpness_arg(nf == ni ? floats[k] : floats[0]);
        } else if (tag == "hole") {
            for (int k = 0; k < ni; ++k) {
                if (ints[k] < 0 || ints[k] >= nfaces)
                    fail(prim, "tag \"hole\": face " + std::to_string(ints[k]) +
                                   " out of range");
                m.face_hole[ints[k]] = 1;
            }
        }
        // The reader keeps no other tag but the face-varying ones, which
        // change nothing here (face-varying values are bilinear per face).
    }
    return boundary_mode;
}

} // namespace

SubdivMesh build_subdiv_mesh(const Primitive& prim) {
    if (prim.type != "catmull-clark")
        fail(prim, "unsupported subdivision scheme \"" + prim.type +
                       "\" (only \"catmull-clark\" is supported)");
    SubdivMesh m;
    m.points = read_positions(prim);
    const int npoints = static_cast<int>(m.points.size());
    const int nfaces = static_cast<int>(prim.nverts.size());
    if (nfaces == 0) fail(prim, "no faces");

    // Faces and corners.
    m.face_start.resize(nfaces + 1);
    m.face_start[0] = 0;
    for (int f = 0; f < nfaces; ++f) {
        const int n = prim.nverts[f];
        if (n < 3)
            fail(prim, "face " + std::to_string(f) + " has " + std::to_string(n) +
                           " vertices (at least 3 needed)");
        if (m.face_start[f] > std::numeric_limits<int>::max() - n)
            fail(prim, "too many face vertices");
        m.face_start[f + 1] = m.face_start[f] + n;
    }
    const int ncorners = m.face_start[nfaces];
    if (static_cast<std::size_t>(ncorners) != prim.verts.size())
        fail(prim, "nverts add up to " + std::to_string(ncorners) + " but " +
                       std::to_string(prim.verts.size()) + " vertex indices are given");
    m.corner_vertex = prim.verts;
    for (int c = 0; c < ncorners; ++c) {
        const int v = m.corner_vertex[c];
        if (v < 0 || v >= npoints)
            fail(prim, "vertex index " + std::to_string(v) + " out of range (" +
                           std::to_string(npoints) + " points in \"P\")");
    }
    std::vector<int> corner_face(ncorners);
    for (int f = 0; f < nfaces; ++f) {
        const int s = m.face_start[f], e = m.face_start[f + 1];
        for (int c = s; c < e; ++c) {
            corner_face[c] = f;
            // A repeated vertex makes an edge meet itself: no valid topology.
            for (int d = s; d < c; ++d)
                if (m.corner_vertex[d] == m.corner_vertex[c])
                    fail(prim, "face " + std::to_string(f) + " uses vertex " +
                                   std::to_string(m.corner_vertex[c]) + " twice");
        }
    }

    // Edges: sort the corners by the (unordered) vertex pair of their edge.
    auto next_corner = [&](int c) {
        const int f = corner_face[c];
        return c + 1 < m.face_start[f + 1] ? c + 1 : m.face_start[f];
    };
    EdgeIndex by_key(ncorners);
    for (int c = 0; c < ncorners; ++c)
        by_key[c] = {edge_key(m.corner_vertex[c], m.corner_vertex[next_corner(c)]), c};
    std::sort(by_key.begin(), by_key.end());
    m.corner_edge.resize(ncorners);
    EdgeIndex edge_index;
    edge_index.reserve(ncorners / 2 + 4);
    for (std::size_t i = 0; i < by_key.size();) {
        std::size_t j = i;
        while (j < by_key.size() && by_key[j].first == by_key[i].first) ++j;
        const int c0 = by_key[i].second;
        const int a = m.corner_vertex[c0], b = m.corner_vertex[next_corner(c0)];
        if (j - i > 2)
            fail(prim, "edge " + std::to_string(a) + "-" + std::to_string(b) +
                           " is shared by " + std::to_string(j - i) +
                           " faces (non-manifold)");
        const int e = m.edge_count();
        m.edge_vertices.push_back({a, b});
        m.edge_faces.push_back(
            {corner_face[c0], j - i == 2 ? corner_face[by_key[i + 1].second] : -1});
        m.edge_sharpness.push_back(j - i == 2 ? 0.0f : kInfinitelySharp);
        for (std::size_t k = i; k < j; ++k) m.corner_edge[by_key[k].second] = e;
        edge_index.emplace_back(by_key[i].first, e);
        i = j;
    }
    m.vertex_sharpness.assign(npoints, 0.0f);
    m.face_hole.assign(nfaces, 0);

    const int boundary_mode = apply_tags(prim, edge_index, m);
    if (boundary_mode == 1) {
        VertexSums sums;
        sums.scatter_edges(m);
        for (int v = 0; v < npoints; ++v)
            if (sums.faces[v] == 1) m.vertex_sharpness[v] = kInfinitelySharp;
    }

    // Colours, linear through subdivision: stored per corner, which covers
    // every storage class the same way.
    CornerVec3 cs(prim, "Cs", nfaces, npoints, ncorners);
    if (cs.present()) {
        m.corner_colors.resize(ncorners);
        for (int c = 0; c < ncorners; ++c)
            m.corner_colors[c] = glm::vec3(cs.at(corner_face[c], m.corner_vertex[c], c));
    }
    return m;
}

SubdivMesh refine_subdiv_mesh(const SubdivMesh& m) {
    const int nv = m.vertex_count(), ne = m.edge_count(), nf = m.face_count();
    const int nc = m.corner_count();
    SubdivMesh r;
    r.points.resize(static_cast<std::size_t>(nv) + ne + nf);
    const int edge_base = nv, face_base = nv + ne;

    // Face points.
    for (int f = 0; f < nf; ++f) {
        glm::dvec3 sum(0.0);
        for (int c = m.face_start[f]; c < m.face_start[f + 1]; ++c)
            sum += m.points[m.corner_vertex[c]];
        r.points[face_base + f] = sum / double(m.face_start[f + 1] - m.face_start[f]);
    }
    // Edge points; also the edge-midpoint sums of the vertex rule.
    std::vector<glm::dvec3> midpoint_sum(nv, glm::dvec3(0.0));
    for (int e = 0; e < ne; ++e) {
        const auto [a, b] = m.edge_vertices[e];
        const glm::dvec3 mid = 0.5 * (m.points[a] + m.points[b]);
        midpoint_sum[a] += mid;
        midpoint_sum[b] += mid;
        const auto [f0, f1] = m.edge_faces[e];
        const double w = f1 < 0 ? 1.0 : sharp_weight(m.edge_sharpness[e]);
        glm::dvec3 p = mid;
        if (w < 1.0) {
            const glm::dvec3 smooth =
                0.5 * mid + 0.25 * (r.points[face_base + f0] + r.points[face_base + f1]);
            p = smooth + w * (mid - smooth);
        }
        r.points[edge_base + e] = p;
    }
    // Vertex points.
    VertexSums sums;
    sums.scatter_edges(m);
    std::vector<glm::dvec3> face_point_sum(nv, glm::dvec3(0.0));
    for (int f = 0; f < nf; ++f)
        for (int c = m.face_start[f]; c < m.face_start[f + 1]; ++c)
            face_point_sum[m.corner_vertex[c]] += r.points[face_base + f];
    for (int v = 0; v < nv; ++v) {
        const glm::dvec3 p = m.points[v];
        const int n = sums.edges[v];
        if (n == 0 || sums.faces[v] == 0) { // isolated point: not on the surface
            r.points[v] = p;
            continue;
        }
        const double crease = sums.crease_weight(v);
        glm::dvec3 smooth = p;
        if (crease < 1.0) {
            const glm::dvec3 q = face_point_sum[v] / double(sums.faces[v]);
            const glm::dvec3 rr = midpoint_sum[v] / double(n);
            smooth = (q + 2.0 * rr + double(n - 3) * p) / double(n);
        }
        // Crease rule with two sharp edges, corner rule (stay put) with more.
        const glm::dvec3 sharp =
            sums.sharp_edges[v] == 2 ? (sums.sharp_neighbours[v] + 6.0 * p) / 8.0 : p;
        glm::dvec3 out = smooth + crease * (sharp - smooth);
        const double corner = sharp_weight(m.vertex_sharpness[v]);
        out += corner * (p - out);
        r.points[v] = out;
    }

    // Topology: corner c of face f becomes the quad
    // (vertex, edge point of its edge, face point, edge point of the previous edge).
    r.face_start.resize(nc + 1);
    for (int q = 0; q <= nc; ++q) r.face_start[q] = 4 * q;
    r.corner_vertex.resize(4 * static_cast<std::size_t>(nc));
    r.corner_edge.resize(r.corner_vertex.size());
    const int ne_r = 2 * ne + nc;
    r.edge_vertices.resize(ne_r);
    r.edge_sharpness.resize(ne_r);
    r.edge_faces.assign(ne_r, {-1, -1});
    for (int e = 0; e < ne; ++e) {
        const auto [a, b] = m.edge_vertices[e];
        r.edge_vertices[2 * e] = {a, edge_base + e};
        r.edge_vertices[2 * e + 1] = {edge_base + e, b};
        const float s =
            m.edge_faces[e][1] < 0 ? kInfinitelySharp : decremented(m.edge_sharpness[e]);
        r.edge_sharpness[2 * e] = s;
        r.edge_sharpness[2 * e + 1] = s;
    }
    // The half of edge e that touches vertex v.
    auto half = [&](int e, int v) {
        return m.edge_vertices[e][0] == v ? 2 * e : 2 * e + 1;
    };
    for (int f = 0; f < nf; ++f) {
        const int s = m.face_start[f], end = m.face_start[f + 1];
        for (int c = s; c < end; ++c) {
            const int cp = c > s ? c - 1 : end - 1;
            const int v = m.corner_vertex[c];
            const int e = m.corner_edge[c], ep = m.corner_edge[cp];
            const std::size_t q = 4 * static_cast<std::size_t>(c);
            r.corner_vertex[q + 0] = v;
            r.corner_vertex[q + 1] = edge_base + e;
            r.corner_vertex[q + 2] = face_base + f;
            r.corner_vertex[q + 3] = edge_base + ep;
            r.corner_edge[q + 0] = half(e, v);
            r.corner_edge[q + 1] = 2 * ne + c;
            r.corner_edge[q + 2] = 2 * ne + cp;
            r.corner_edge[q + 3] = half(ep, v);
            r.edge_vertices[2 * ne + c] = {edge_base + e, face_base + f};
            r.edge_sharpness[2 * ne + c] = 0.0f;
        }
    }
    for (int q = 0; q < nc; ++q)
        for (int k = 0; k < 4; ++k) {
            auto& faces = r.edge_faces[r.corner_edge[4 * q + k]];
            (faces[0] < 0 ? faces[0] : faces[1]) = q;
        }

    r.vertex_sharpness.assign(r.points.size(), 0.0f);
    for (int v = 0; v < nv; ++v)
        r.vertex_sharpness[v] = decremented(m.vertex_sharpness[v]);
    r.face_hole.resize(nc);
    for (int f = 0; f < nf; ++f)
        for (int c = m.face_start[f]; c < m.face_start[f + 1]; ++c)
            r.face_hole[c] = m.face_hole[f];

    if (!m.corner_colors.empty()) {
        r.corner_colors.resize(r.corner_vertex.size());
        for (int f = 0; f < nf; ++f) {
            const int s = m.face_start[f], end = m.face_start[f + 1];
            glm::vec3 centre(0.0f);
            for (int c = s; c < end; ++c) centre += m.corner_colors[c];
            centre /= float(end - s);
            for (int c = s; c < end; ++c) {
                const int cn = c + 1 < end ? c + 1 : s;
                const int cp = c > s ? c - 1 : end - 1;
                const std::size_t q = 4 * static_cast<std::size_t>(c);
                r.corner_colors[q + 0] = m.corner_colors[c];
                r.corner_colors[q + 1] =
                    0.5f * (m.corner_colors[c] + m.corner_colors[cn]);
                r.corner_colors[q + 2] = centre;
                r.corner_colors[q + 3] =
                    0.5f * (m.corner_colors[c] + m.corner_colors[cp]);
            }
        }
    }
    return r;
}

namespace {

/// Weights of the two tangent stencils for one valence n: edge neighbour j
/// gets a_n cos(2 pi j / n) (resp. sin), face diagonal j gets
/// cos(2 pi j / n) + cos(2 pi (j + 1) / n) (resp. sin).
struct TangentWeights {
    int valence = 0;
    std::vector<double> edge_cos, edge_sin, diagonal_cos, diagonal_sin;

    void prepare(int n) {
        if (n == valence) return;
        valence = n;
        edge_cos.resize(n);
        edge_sin.resize(n);
        diagonal_cos.resize(n);
        diagonal_sin.resize(n);
        const double step = 2.0 * kPi / n;
        const double a = 1.0 + std::cos(step) +
                         std::cos(kPi / n) * std::sqrt(2.0 * (9.0 + std::cos(step)));
        for (int j = 0; j < n; ++j) {
            const double c0 = std::cos(step * j), c1 = std::cos(step * (j + 1));
            const double s0 = std::sin(step * j), s1 = std::sin(step * (j + 1));
            edge_cos[j] = a * c0;
            edge_sin[j] = a * s0;
            diagonal_cos[j] = c0 + c1;
            diagonal_sin[j] = s0 + s1;
        }
    }
};

/// Limit normal at a smooth interior vertex from the tangent stencils of
/// Halstead, Kass and DeRose (1993), walking the vertex's ring of quads.
/// Returns a zero vector when the ring cannot be walked (irregular topology).
glm::dvec3 stencil_normal(const SubdivMesh& m, int v, int first_corner, int valence,
                          std::vector<glm::dvec3>& ring_edge,
                          std::vector<glm::dvec3>& ring_diagonal,
                          TangentWeights& weights) {
    ring_edge.resize(valence);
    ring_diagonal.resize(valence);
    const int f0 = first_corner / 4;
    int f = f0;
    int enter = m.corner_edge[first_corner];
    for (int j = 0; j < valence; ++j) {
        int local = -1;
        for (int k = 0; k < 4; ++k)
            if (m.corner_vertex[4 * f + k] == v) local = k;
        if (local < 0) return glm::dvec3(0.0);
        const int out = m.corner_edge[4 * f + local];
        const int in = m.corner_edge[4 * f + (local + 3) % 4];
        const int other = enter == out ? in : enter == in ? out : -1;
        if (other < 0) return glm::dvec3(0.0);
        auto far_end = [&](int e) {
            const auto [a, b] = m.edge_vertices[e];
            return m.points[a == v ? b : a];
        };
        ring_edge[j] = far_end(enter);
        ring_diagonal[j] = m.points[m.corner_vertex[4 * f + (local + 2) % 4]];
        const auto [g0, g1] = m.edge_faces[other];
        const int g = g0 == f ? g1 : g0;
        if (g < 0) return glm::dvec3(0.0);
        f = g;
        enter = other;
    }
    if (f != f0) return glm::dvec3(0.0);

    weights.prepare(valence);
    glm::dvec3 tc(0.0), ts(0.0);
    for (int j = 0; j < valence; ++j) {
        tc += weights.edge_cos[j] * ring_edge[j] +
              weights.diagonal_cos[j] * ring_diagonal[j];
        ts += weights.edge_sin[j] * ring_edge[j] +
              weights.diagonal_sin[j] * ring_diagonal[j];
    }
    return glm::cross(tc, ts);
}

} // namespace

SubdivLimit subdiv_limit(const SubdivMesh& m) {
    const int nv = m.vertex_count(), nf = m.face_count();
    VertexSums sums;
    sums.scatter_edges(m);
    // Neighbour sums of the smooth limit stencil: edge neighbours and the
    // diagonal corner of each incident quad.
    std::vector<glm::dvec3> neighbour_sum(nv, glm::dvec3(0.0)),
        diagonal_sum(nv, glm::dvec3(0.0));
    std::vector<int> first_corner(nv, -1);
    for (int e = 0; e < m.edge_count(); ++e) {
        const auto [a, b] = m.edge_vertices[e];
        neighbour_sum[a] += m.points[b];
        neighbour_sum[b] += m.points[a];
    }
    for (int f = 0; f < nf; ++f)
        for (int k = 0; k < 4; ++k) {
            const int v = m.corner_vertex[4 * f + k];
            diagonal_sum[v] += m.points[m.corner_vertex[4 * f + (k + 2) % 4]];
            if (first_corner[v] < 0) first_corner[v] = 4 * f + k;
        }

    SubdivLimit lim;
    lim.points.resize(nv);
    std::vector<glm::dvec3> vertex_normal(nv, glm::dvec3(0.0));
    std::vector<glm::dvec3> ring_edge, ring_diagonal;
    TangentWeights weights;
    for (int v = 0; v < nv; ++v) {
        const glm::dvec3 p = m.points[v];
        const int n = sums.edges[v];
        if (n == 0 || sums.faces[v] == 0) {
            lim.points[v] = p;
            continue;
        }
        const double crease = sums.crease_weight(v);
        const double corner = sharp_weight(m.vertex_sharpness[v]);
        glm::dvec3 smooth = p;
        if (crease < 1.0 && sums.faces[v] == n) {
            const double dn = n;
            smooth = (dn * dn * p + 4.0 * neighbour_sum[v] + diagonal_sum[v]) /
                     (dn * (dn + 5.0));
        }
        // The limit of the cubic B-spline crease curve, or the corner itself.
        const glm::dvec3 sharp =
            sums.sharp_edges[v] == 2 ? (sums.sharp_neighbours[v] + 4.0 * p) / 6.0 : p;
        glm::dvec3 out = smooth + crease * (sharp - smooth);
        out += corner * (p - out);
        lim.points[v] = out;
        if (sums.sharp_edges[v] == 0 && corner == 0.0 && sums.faces[v] == n && n >= 3)
            vertex_normal[v] = stencil_normal(m, v, first_corner[v], n, ring_edge,
                                              ring_diagonal, weights);
    }

    // Corner normals: the vertex's limit normal where it is smooth, else the
    // face's own normal at that corner (keeps creases and boundaries sharp).
    lim.corner_normals.resize(m.corner_vertex.size());
    for (int f = 0; f < nf; ++f) {
        const int* cv = &m.corner_vertex[4 * f];
        const glm::dvec3 diagonal_normal = glm::cross(
            lim.points[cv[2]] - lim.points[cv[0]], lim.points[cv[3]] - lim.points[cv[1]]);
        for (int k = 0; k < 4; ++k) {
            const glm::dvec3 p = lim.points[cv[k]];
            glm::dvec3 own = glm::cross(lim.points[cv[(k + 1) % 4]] - p,
                                        lim.points[cv[(k + 3) % 4]] - p);
            if (!(glm::dot(own, own) > 0.0)) own = diagonal_normal;
            glm::dvec3 n = vertex_normal[cv[k]];
            if (glm::dot(n, n) > 0.0) {
                // Ring walk direction is arbitrary: orient by the face winding.
                if (glm::dot(n, own) < 0.0) n = -n;
            } else {
                n = own;
            }
            const double len = glm::length(n);
            lim.corner_normals[4 * f + k] = len > 0.0 ? n / len : glm::dvec3(0.0);
        }
    }
    return lim;
}

} // namespace sss::detail
