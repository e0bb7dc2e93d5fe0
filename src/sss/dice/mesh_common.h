// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file mesh_common.h
/// Internal: what the polygon and subdivision-mesh dicers share
/// (dice_polygon.cpp, dice_subdiv.cpp, subdivision.cpp): positions and
/// per-corner primitive variables, the normal transform, dicing lengths and
/// budgets, the output writer and the bilinear quad dicer (mesh_common.cpp).

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "dice_common.h"
#include "sss/dice/dice.h"
#include "sss/scene/scene.h"

namespace sss::detail {

/// The object-space positions of "P" (or "Pw", divided by w). ValueError when
/// both are missing, the number count is not a whole number of points, or a
/// coordinate is not finite.
std::vector<glm::dvec3> read_positions(const Primitive& prim);

/// A 3-component primitive variable ("Cs", "N") looked up per face corner
/// through its storage class: constant (one value), uniform (per face),
/// varying/vertex (per point, by vertex index) or facevarying/facevertex (per
/// face corner, in face order).
class CornerVec3 {
public:
    /// Absent variable: present() is false. ValueError when it is given with
    /// the wrong type or fewer values than its class needs for this primitive
    /// (`faces` uniform values, `points` vertex values, `corners` facevarying).
    CornerVec3(const Primitive& prim, std::string_view name, std::size_t faces,
               std::size_t points, std::size_t corners);

    bool present() const { return m_data != nullptr; }
    /// Value at corner `corner` (running corner number) of face `face`, whose
    /// point index is `point`.
    glm::dvec3 at(std::size_t face, std::size_t point, std::size_t corner) const {
        std::size_t i = 0;
        switch (m_class) {
        case ParamClass::Constant:
            i = 0;
            break;
        case ParamClass::Uniform:
            i = face;
            break;
        case ParamClass::Varying:
        case ParamClass::Vertex:
            i = point;
            break;
        case ParamClass::FaceVarying:
        case ParamClass::FaceVertex:
            i = corner;
            break;
        }
        const double* v = m_data + 3 * i;
        return {v[0], v[1], v[2]};
    }

private:
    const double* m_data = nullptr;
    ParamClass m_class = ParamClass::Constant;
};

/// Texture coordinates per face corner: "st" (two numbers per value), else
/// "s" and "t" (one each), looked up like CornerVec3; present() is false
/// when neither is given, has_s() / has_t() tell which are.
class CornerTexCoords {
public:
    CornerTexCoords(const Primitive& prim, std::size_t faces, std::size_t points,
                    std::size_t corners);

    bool present() const { return m_s.data || m_t.data; }
    /// (s, t) at a corner; a missing coordinate is `fallback`'s.
    glm::dvec2 at(std::size_t face, std::size_t point, std::size_t corner,
                  const glm::dvec2& fallback) const {
        return {m_s.data ? m_s.at(face, point, corner) : fallback.x,
                m_t.data ? m_t.at(face, point, corner) : fallback.y};
    }

private:
    struct Channel {
        const double* data = nullptr;
        int stride = 1;
        ParamClass storage = ParamClass::Constant;
        double at(std::size_t face, std::size_t point, std::size_t corner) const {
            std::size_t i = 0;
            switch (storage) {
            case ParamClass::Constant:
                break;
            case ParamClass::Uniform:
                i = face;
                break;
            case ParamClass::Varying:
            case ParamClass::Vertex:
                i = point;
                break;
            case ParamClass::FaceVarying:
            case ParamClass::FaceVertex:
                i = corner;
                break;
            }
            return data[stride * i];
        }
    };
    Channel m_s, m_t;
};

// ---------------------------------------------------------------------------
// Normals and dicing lengths

/// The normal rule of dice_common.h with the matrix prepared once per
/// primitive (world_normal rebuilds it on every call, too slow for millions
/// of corner normals). The cofactor matrix (det * inverse transpose) is
/// defined even for singular transforms, and maps object cross products to
/// world cross products; its sign is calibrated against world_normal so the
/// two can never disagree (mirror transforms included).
class NormalTransform {
public:
    explicit NormalTransform(const Primitive& prim) {
        m_matrix = cofactor(glm::dmat3(prim.object_to_world));
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
inline glm::dvec3 to_world(const Matrix4& m, const glm::dvec3& p) {
    const glm::dvec4 h = m * glm::dvec4(p, 1.0);
    return h.w == 1.0 ? glm::dvec3(h) : glm::dvec3(h) / h.w;
}

/// Micropolygon edge length at a world point, checked.
double edge_length(const Primitive& prim, const DiceControl& control, const glm::dvec3& p,
                   double shading_rate);

/// Number of pieces for a length: ceil(length / edge), at least 1.
std::size_t piece_count(const Primitive& prim, const DiceControl& control, double length,
                        double edge);

/// LimitError (too_many_micropolygons) when `count` micropolygons exceed the
/// control's budget.
void check_budget(const Primitive& prim, const DiceControl& control, std::size_t count);

// ---------------------------------------------------------------------------
// Output

inline glm::vec3 to_float(const glm::dvec3& v) {
    return glm::vec3(v);
}

/// Fills a DicedSurface whose arrays were sized beforehand (the parametric
/// ones too when `with_parametric`).
struct SurfaceWriter {
    DicedSurface& out;
    bool with_colors;
    bool with_parametric = false;
    /// Displacement (DiceControl::displace), when set, of `prim`.
    const DisplaceHook* displace = nullptr;
    const Primitive* prim = nullptr;
    uint64_t sequence = 0; ///< hook calls so far
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
    /// Parametric data (u, v, s, t) of the last vertex.
    void vertex_parametric(double u, double v, const glm::dvec2& st) {
        out.vertex_uvst[vertex - 1] = glm::vec4(glm::dvec4(u, v, st.x, st.y));
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
    /// Parametric data of the last micropolygon.
    void parametric(double u, double v, double du, double dv, const glm::dvec2& st,
                    const glm::dvec3& dpdu, const glm::dvec3& dpdv) {
        const std::size_t k = mp - 1;
        out.u[k] = static_cast<float>(u);
        out.v[k] = static_cast<float>(v);
        out.du[k] = static_cast<float>(du);
        out.dv[k] = static_cast<float>(dv);
        out.s[k] = static_cast<float>(st.x);
        out.t[k] = static_cast<float>(st.y);
        out.dPdu[k] = to_float(dpdu);
        out.dPdv[k] = to_float(dpdv);
    }
    void finish() {
        out.resize(mp, vertex, triangle, with_colors);
        if (with_parametric) out.resize_parametric(mp, vertex);
    }
};

/// Sizes `out`; ValueError when its vertices cannot be addressed by 32-bit indices.
void allocate(const Primitive& prim, DicedSurface& out, std::size_t micropolygons,
              std::size_t vertices, std::size_t triangles, bool with_colors);

inline glm::dvec3 bilinear(const std::array<glm::dvec3, 4>& c, double u, double v) {
    return (c[0] * (1.0 - u) + c[1] * u) * (1.0 - v) + (c[3] * (1.0 - u) + c[2] * u) * v;
}

/// d bilinear / du and d bilinear / dv (corners as bilinear()).
inline glm::dvec3 bilinear_dpdu(const std::array<glm::dvec3, 4>& c, double v) {
    return (c[1] - c[0]) * (1.0 - v) + (c[2] - c[3]) * v;
}
inline glm::dvec3 bilinear_dpdv(const std::array<glm::dvec3, 4>& c, double u) {
    return (c[3] * (1.0 - u) + c[2] * u) - (c[0] * (1.0 - u) + c[1] * u);
}

constexpr std::array<glm::dvec3, 4> kZero4{glm::dvec3(0.0), glm::dvec3(0.0),
                                           glm::dvec3(0.0), glm::dvec3(0.0)};

/// One quad to dice, in world space, corners in winding order.
struct QuadCorners {
    std::array<glm::dvec3, 4> p = kZero4;
    std::array<glm::dvec3, 4> normal = kZero4; ///< interpolated, then normalised
    std::array<glm::dvec3, 4> color = kZero4;  ///< used when the writer has colours
    glm::dvec3 fallback_normal{0.0};           ///< where the interpolation vanishes
    /// Texture coordinates at the corners (used with parametric data).
    std::array<glm::dvec2, 4> st{glm::dvec2(0, 0), glm::dvec2(1, 0), glm::dvec2(1, 1),
                                 glm::dvec2(0, 1)};
};

/// Dices a quad as a bilinear patch of nu x nv sub-quads (nu along corners
/// 0->1). Each sub-quad is one micropolygon made of two emitted triangles:
/// its area is theirs, its centre their area-weighted centroid.
class QuadDicer {
public:
    void dice(const QuadCorners& q, std::size_t nu, std::size_t nv, SurfaceWriter& w);

private:
    /// With displacement: moves the grid just written (vertices from
    /// `base`, micropolygons from `first`, cell of each in m_cells).
    void displace(const QuadCorners& q, std::size_t nu, std::size_t nv, std::size_t base,
                  std::size_t first, SurfaceWriter& w);

    std::vector<glm::dvec3> m_grid;
    std::vector<std::size_t> m_cells;
    DisplaceGrid m_disp;
};

/// Calls the writer's displacement hook on g; normals come back unit (the
/// ones given where the shader left none), positions finite.
void call_displace(SurfaceWriter& w, DisplaceGrid& g);

/// With displacement: moves the vertices written from `vertex0` on as
/// unrelated points (triangulated faces have no grid), then gives the
/// micropolygons from `mp0` on (one per triangle from `triangle0` on) the
/// centroid, area, radius and normal of their displaced triangle, and the
/// vertices the area-weighted normals of their displaced triangles.
void displace_triangles(SurfaceWriter& w, std::size_t vertex0, std::size_t mp0,
                        std::size_t triangle0);

} // namespace sss::detail
