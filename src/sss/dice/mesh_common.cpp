// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file mesh_common.cpp
/// What the polygon and subdivision-mesh dicers share: reading positions and
/// per-corner primitive variables, dicing lengths and budgets, and the
/// bilinear dicing of quads.
///
/// Watertightness: points on a quad's border are computed from that border
/// edge's two end points only, with integer-quotient weights, so two faces
/// that cut a shared edge into the same number of pieces produce bit-identical
/// vertices there.

#include "mesh_common.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "sss/util/error.h"

namespace sss::detail {

std::vector<glm::dvec3> read_positions(const Primitive& prim) {
    const Param* p = prim.params.find("P");
    bool homogeneous = p && p->type == ParamType::HPoint;
    if (!p) {
        p = prim.params.find("Pw");
        homogeneous = true;
    }
    if (!p) fail(prim, "missing \"P\"");
    const std::size_t comps = homogeneous ? 4 : 3;
    if (p->type == ParamType::String ||
        static_cast<std::size_t>(p->element_size()) != comps)
        fail(prim, "\"" + p->name + "\" must have " + std::to_string(comps) +
                       " numbers per point");
    if (p->numbers.size() % comps != 0)
        fail(prim, "\"" + p->name + "\" has " + std::to_string(p->numbers.size()) +
                       " numbers, not a whole number of points");
    std::vector<glm::dvec3> points(p->numbers.size() / comps);
    for (std::size_t i = 0; i < points.size(); ++i) {
        const double* v = &p->numbers[comps * i];
        glm::dvec3 q(v[0], v[1], v[2]);
        if (homogeneous) {
            if (v[3] == 0.0)
                fail(prim, "\"Pw\" point " + std::to_string(i) + " has w = 0");
            q /= v[3];
        }
        if (!finite(q))
            fail(prim,
                 "\"" + p->name + "\" point " + std::to_string(i) + " is not finite");
        points[i] = q;
    }
    return points;
}

CornerVec3::CornerVec3(const Primitive& prim, std::string_view name, std::size_t faces,
                       std::size_t points, std::size_t corners) {
    const Param* p = prim.params.find(name);
    if (!p) return;
    std::string quoted(1, '"');
    quoted.append(name);
    quoted.push_back('"');
    if (p->type == ParamType::String || p->element_size() != 3)
        fail(prim, quoted + " must have 3 numbers per value");
    const std::size_t needed =
        ClassCounts{faces, points, points, corners, corners}.of(p->storage);
    if (p->element_count() < needed)
        fail(prim, quoted + " (" + param_class_name(p->storage) + ") has " +
                       std::to_string(p->element_count()) + " values, " +
                       std::to_string(needed) + " needed");
    for (std::size_t i = 0; i < 3 * needed; ++i)
        if (!std::isfinite(p->numbers[i]))
            fail(prim, quoted + " has a value that is not finite");
    m_data = p->numbers.data();
    m_class = p->storage;
}

CornerTexCoords::CornerTexCoords(const Primitive& prim, std::size_t faces,
                                 std::size_t points, std::size_t corners) {
    const std::size_t needed_by_class[] = {1, faces, points, points, corners, corners};
    const auto read = [&](const char* name, int width, Channel& channel) {
        const Param* p = prim.params.find(name);
        if (!p) return false;
        const std::string quoted = std::string("\"") + name + "\"";
        if (p->type == ParamType::String || p->element_size() != width)
            fail(prim,
                 quoted + " must have " + std::to_string(width) + " numbers per value");
        const std::size_t needed = needed_by_class[static_cast<int>(p->storage)];
        if (p->element_count() < needed)
            fail(prim, quoted + " (" + param_class_name(p->storage) + ") has " +
                           std::to_string(p->element_count()) + " values, " +
                           std::to_string(needed) + " needed");
        for (std::size_t i = 0; i < width * needed; ++i)
            if (!std::isfinite(p->numbers[i]))
                fail(prim, quoted + " has a value that is not finite");
        channel = {p->numbers.data(), width, p->storage};
        return true;
    };
    if (read("st", 2, m_s)) {
        m_t = m_s;
        ++m_t.data;
        return;
    }
    read("s", 1, m_s);
    read("t", 1, m_t);
}

/// Micropolygon edge length at a world point, checked.
double edge_length(const Primitive& prim, const DiceControl& control, const glm::dvec3& p,
                   double shading_rate) {
    double e = 0.0;
    try {
        e = control.edge_length_at(p, shading_rate);
    } catch (const ValueError& err) {
        fail(prim, err.what()); // name the primitive
    }
    if (!(e > 0.0) || !std::isfinite(e))
        fail(prim,
             "dicing edge length " + std::to_string(e) + " is not a positive number");
    return e;
}

/// Number of pieces for a length: ceil(length / edge), at least 1.
std::size_t piece_count(const Primitive& prim, const DiceControl& control, double length,
                        double edge) {
    const double n = control.note(std::max(1.0, std::ceil(length / edge)), prim);
    // Every piece is at least one micropolygon: one side beyond the budget is
    // reported here, before any count can overflow.
    if (!(n <= static_cast<double>(control.max_micropolygons)) || !(n <= 1e9))
        too_many_micropolygons(prim, control, n);
    return static_cast<std::size_t>(n);
}

void check_budget(const Primitive& prim, const DiceControl& control, std::size_t count) {
    if (count > control.max_micropolygons)
        too_many_micropolygons(prim, control, static_cast<double>(count));
}

void allocate(const Primitive& prim, DicedSurface& out, std::size_t micropolygons,
              std::size_t vertices, std::size_t triangles, bool with_colors) {
    if (vertices > std::numeric_limits<uint32_t>::max())
        fail(prim, "diced surface has more vertices than 32-bit indices address");
    out.resize(micropolygons, vertices, triangles, with_colors);
}

void QuadDicer::dice(const QuadCorners& q, std::size_t nu, std::size_t nv,
                     SurfaceWriter& w) {
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
    const std::array<glm::dvec3, 4> st3{
        glm::dvec3(q.st[0], 0.0), glm::dvec3(q.st[1], 0.0), glm::dvec3(q.st[2], 0.0),
        glm::dvec3(q.st[3], 0.0)};
    const std::size_t base = w.vertex;
    const std::size_t first = w.mp;
    std::size_t emitted = 0;
    m_cells.clear();
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
            if (w.with_parametric)
                w.vertex_parametric(u, v, glm::dvec2(bilinear(st3, u, v)));
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
                (a1 * (p00 + p10 + p11) + a2 * (p00 + p11 + p01)) * (1.0 / (3.0 * area));
            const double radius =
                std::sqrt(std::max({glm::dot(p00 - centre, p00 - centre),
                                    glm::dot(p10 - centre, p10 - centre),
                                    glm::dot(p11 - centre, p11 - centre),
                                    glm::dot(p01 - centre, p01 - centre)}));
            const double u = (double(i) + 0.5) / du, v = (double(j) + 0.5) / dv;
            const glm::dvec3 col =
                w.with_colors ? bilinear(q.color, u, v) : glm::dvec3(0.0);
            w.micropolygon(centre, normal_at(u, v), area, radius, col);
            if (w.displace) m_cells.push_back(j * nu + i);
            if (w.with_parametric) {
                ++emitted;
                w.parametric(u, v, 1.0 / du, 1.0 / dv, glm::dvec2(bilinear(st3, u, v)),
                             bilinear_dpdu(q.p, v), bilinear_dpdv(q.p, u));
            }
        }
    // A shading grid when no sub-quad collapsed.
    if (w.with_parametric && emitted == nu * nv)
        w.out.grids.push_back({first, int(nu), int(nv)});
    if (w.displace) displace(q, nu, nv, base, first, w);
}

void call_displace(SurfaceWriter& w, DisplaceGrid& g) {
    const std::size_t n = g.size();
    thread_local std::vector<glm::vec3> given_p, given_n;
    given_p = g.P;
    given_n = g.N;
    g.primitive = w.prim;
    g.sequence = w.sequence++;
    (*w.displace)(g);
    if (g.P.size() != n || g.N.size() != n)
        fail(*w.prim, "displacement returned a wrong number of points");
    for (std::size_t k = 0; k < n; ++k) {
        const glm::dvec3 p(g.P[k]);
        if (!finite(p)) g.P[k] = given_p[k];
        const glm::dvec3 nn(g.N[k]);
        const double len = glm::length(nn);
        g.N[k] = len > 0.0 && std::isfinite(len) ? glm::vec3(nn / len) : given_n[k];
    }
}

void QuadDicer::displace(const QuadCorners& q, std::size_t nu, std::size_t nv,
                         std::size_t base, std::size_t first, SurfaceWriter& w) {
    const double fu = static_cast<double>(nu), fv = static_cast<double>(nv);
    const std::array<glm::dvec3, 4> st3{
        glm::dvec3(q.st[0], 0.0), glm::dvec3(q.st[1], 0.0), glm::dvec3(q.st[2], 0.0),
        glm::dvec3(q.st[3], 0.0)};
    // One grid: point (i, j) at (u, v) = ((i + offset) / fu, (j + offset) / fv).
    const auto fill = [&](std::size_t gu, std::size_t gv, double offset) {
        m_disp.resize(gu * gv);
        m_disp.grid = true;
        m_disp.nu = static_cast<int>(gu);
        m_disp.nv = static_cast<int>(gv);
        for (std::size_t j = 0; j < gv; ++j)
            for (std::size_t i = 0; i < gu; ++i) {
                const std::size_t k = j * gu + i;
                const double u = (double(i) + offset) / fu, v = (double(j) + offset) / fv;
                m_disp.u[k] = static_cast<float>(u);
                m_disp.v[k] = static_cast<float>(v);
                m_disp.du[k] = static_cast<float>(1.0 / fu);
                m_disp.dv[k] = static_cast<float>(1.0 / fv);
                const glm::dvec3 st = bilinear(st3, u, v);
                m_disp.s[k] = static_cast<float>(st.x);
                m_disp.t[k] = static_cast<float>(st.y);
                m_disp.dPdu[k] = to_float(bilinear_dpdu(q.p, v));
                m_disp.dPdv[k] = to_float(bilinear_dpdv(q.p, u));
            }
    };
    // The vertices (as written), displaced.
    fill(nu + 1, nv + 1, 0.0);
    for (std::size_t k = 0; k < (nu + 1) * (nv + 1); ++k) {
        m_disp.P[k] = w.out.vertices[base + k];
        m_disp.N[k] = w.out.vertex_normals[base + k];
        m_disp.Ng[k] = m_disp.N[k];
    }
    call_displace(w, m_disp);
    for (std::size_t k = 0; k < (nu + 1) * (nv + 1); ++k) {
        w.out.vertices[base + k] = m_disp.P[k];
        w.out.vertex_normals[base + k] = m_disp.N[k];
        m_grid[k] = glm::dvec3(m_disp.P[k]);
    }
    // The cell centres, displaced: the micropolygons' centres and normals.
    fill(nu, nv, 0.5);
    for (std::size_t j = 0; j < nv; ++j)
        for (std::size_t i = 0; i < nu; ++i) {
            const std::size_t k = j * nu + i;
            const double u = (double(i) + 0.5) / fu, v = (double(j) + 0.5) / fv;
            m_disp.P[k] = to_float(bilinear(q.p, u, v));
            // The undisplaced normal: the interpolated one, else the cell's.
            glm::dvec3 n = NormalTransform::safe_normalize(bilinear(q.normal, u, v));
            if (!(glm::dot(n, n) > 0.0)) n = q.fallback_normal;
            m_disp.N[k] = to_float(n);
            m_disp.Ng[k] = m_disp.N[k];
        }
    call_displace(w, m_disp);
    for (std::size_t m = first; m < w.mp; ++m) {
        const std::size_t c = m_cells[m - first];
        const std::size_t i = c % nu, j = c / nu;
        const std::size_t k00 = j * (nu + 1) + i, k10 = k00 + 1;
        const std::size_t k01 = k00 + nu + 1, k11 = k01 + 1;
        const glm::dvec3 &p00 = m_grid[k00], &p10 = m_grid[k10];
        const glm::dvec3 &p11 = m_grid[k11], &p01 = m_grid[k01];
        const glm::dvec3 centre(m_disp.P[c]);
        const double area = 0.5 * glm::length(glm::cross(p10 - p00, p11 - p00)) +
                            0.5 * glm::length(glm::cross(p11 - p00, p01 - p00));
        w.out.centers[m] = m_disp.P[c];
        w.out.normals[m] = m_disp.N[c];
        w.out.areas[m] = static_cast<float>(area);
        w.out.radii[m] = static_cast<float>(std::sqrt(std::max(
            {glm::dot(p00 - centre, p00 - centre), glm::dot(p10 - centre, p10 - centre),
             glm::dot(p11 - centre, p11 - centre),
             glm::dot(p01 - centre, p01 - centre)})));
    }
}

void displace_triangles(SurfaceWriter& w, std::size_t vertex0, std::size_t mp0,
                        std::size_t triangle0) {
    DicedSurface& out = w.out;
    const std::size_t n = w.vertex - vertex0;
    if (n == 0) return;
    thread_local DisplaceGrid g;
    g.resize(n);
    g.grid = false;
    g.nu = static_cast<int>(n);
    g.nv = 1;
    for (std::size_t k = 0; k < n; ++k) {
        g.P[k] = out.vertices[vertex0 + k];
        g.N[k] = out.vertex_normals[vertex0 + k];
        g.Ng[k] = g.N[k];
        g.u[k] = g.v[k] = g.du[k] = g.dv[k] = g.s[k] = g.t[k] = 0.0f;
        g.dPdu[k] = g.dPdv[k] = glm::vec3(0.0f);
    }
    call_displace(w, g);
    thread_local std::vector<glm::dvec3> normal_sum;
    normal_sum.assign(n, glm::dvec3(0.0));
    for (std::size_t k = 0; k < n; ++k) out.vertices[vertex0 + k] = g.P[k];
    for (std::size_t t = triangle0; t < w.triangle; ++t) {
        const uint32_t* v = &out.triangles[3 * t];
        const glm::dvec3 a(out.vertices[v[0]]), b(out.vertices[v[1]]),
            c(out.vertices[v[2]]);
        // Oriented like the undisplaced normal of the triangle's micropolygon.
        glm::dvec3 cross = glm::cross(b - a, c - a);
        const std::size_t m = mp0 + (t - triangle0);
        if (glm::dot(cross, glm::dvec3(out.normals[m])) < 0.0) cross = -cross;
        for (int k = 0; k < 3; ++k) normal_sum[v[k] - vertex0] += cross;
        const glm::dvec3 centre = (a + b + c) * (1.0 / 3.0);
        const double len = glm::length(cross);
        out.centers[m] = to_float(centre);
        if (len > 0.0 && std::isfinite(len)) out.normals[m] = to_float(cross / len);
        out.areas[m] = static_cast<float>(0.5 * len);
        out.radii[m] = static_cast<float>(std::sqrt(
            std::max({glm::dot(a - centre, a - centre), glm::dot(b - centre, b - centre),
                      glm::dot(c - centre, c - centre)})));
    }
    for (std::size_t k = 0; k < n; ++k) {
        const glm::dvec3 s = NormalTransform::safe_normalize(normal_sum[k]);
        if (glm::dot(s, s) > 0.0) out.vertex_normals[vertex0 + k] = to_float(s);
    }
}

} // namespace sss::detail
