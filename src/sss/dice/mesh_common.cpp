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
    const double n = std::max(1.0, std::ceil(length / edge));
    // Every piece is at least one micropolygon: one side beyond the budget is
    // reported here, before any count can overflow.
    if (!(n <= static_cast<double>(control.max_micropolygons)) || !(n <= 1e9))
        fail(prim, "would dice into more than " +
                       std::to_string(control.max_micropolygons) + " micropolygons");
    return static_cast<std::size_t>(n);
}

void check_budget(const Primitive& prim, const DiceControl& control, std::size_t count) {
    if (count > control.max_micropolygons)
        fail(prim, "would dice into " + std::to_string(count) +
                       " micropolygons, more than the limit of " +
                       std::to_string(control.max_micropolygons));
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
    const std::size_t base = w.vertex;
    const std::size_t first = w.mp;
    std::size_t emitted = 0;
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
            if (w.with_parametric) {
                ++emitted;
                const std::array<glm::dvec3, 4> st3{
                    glm::dvec3(q.st[0], 0.0), glm::dvec3(q.st[1], 0.0),
                    glm::dvec3(q.st[2], 0.0), glm::dvec3(q.st[3], 0.0)};
                w.parametric(u, v, 1.0 / du, 1.0 / dv, glm::dvec2(bilinear(st3, u, v)),
                             bilinear_dpdu(q.p, v), bilinear_dpdv(q.p, u));
            }
        }
    // A shading grid when no sub-quad collapsed.
    if (w.with_parametric && emitted == nu * nv)
        w.out.grids.push_back({first, int(nu), int(nv)});
}

} // namespace sss::detail
