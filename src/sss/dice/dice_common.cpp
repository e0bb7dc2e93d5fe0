// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file dice_common.cpp
/// What every dicer shares: how errors name a primitive, the normal rule and
/// the dicing rate (DiceControl::edge_length_at).

#include "dice_common.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>
#include <glm/vec4.hpp>

#include "sss/util/error.h"
#include "sss/util/limits.h"

namespace sss {

namespace detail {

std::string describe(const Primitive& prim) {
    std::string kind = primitive_kind_name(prim.kind);
    return prim.source.empty() ? kind : prim.source + ": " + kind;
}

void fail(const Primitive& prim, const std::string& what) {
    throw ValueError(describe(prim) + ": " + what);
}

void too_many_micropolygons(const Primitive& prim, const DiceControl& control,
                            double count) {
    char needed[32];
    std::snprintf(needed, sizeof needed, count < 1e15 ? "%.0f" : "%.3g", count);
    throw LimitError(
        Limit::PrimitiveMicropolygons,
        describe(prim) + ": " + needed + " " + limit_what(Limit::PrimitiveMicropolygons) +
            " exceeds the limit of " + std::to_string(control.max_micropolygons) +
            " (set " + limit_variable(Limit::PrimitiveMicropolygons) +
            " to raise it, or dice coarser: a larger spacing or "
            "ShadingRate)");
}

void check_world_point(const Primitive& prim, const glm::dvec3& p) {
    if (in_world_range(p)) return;
    char buf[160];
    std::snprintf(buf, sizeof buf,
                  "its surface reaches (%.4g, %.4g, %.4g) in world space, beyond the "
                  "coordinate range of +-%.0e (check \"P\", \"Pw\" and the transforms)",
                  p.x, p.y, p.z, kMaxWorldCoordinate);
    fail(prim, buf);
}

void check_world_range(const Primitive& prim, const DicedSurface& surface) {
    for (const glm::vec3& v : surface.vertices) check_world_point(prim, glm::dvec3(v));
    for (const glm::vec3& c : surface.centers) check_world_point(prim, glm::dvec3(c));
}

DiceEstimate estimate_flat_face(double area, double perimeter, double edge,
                                double pieces) {
    // Quads become about area / e^2 micropolygons, triangles 1.15 to 2 times
    // that (similar sub-triangles); the ceilings add about one row of cells
    // along each side, and every piece is at least one micropolygon.
    const double cells = area / (edge * edge);
    DiceEstimate e;
    e.micropolygons = 1.25 * cells + perimeter / edge + pieces;
    e.vertices = e.micropolygons + 2.0 * perimeter / edge + 3.0 * pieces;
    e.triangles = 2.0 * e.micropolygons;
    return e;
}

glm::dvec3 world_normal(const Matrix4& object_to_world, const glm::dvec3& object_normal,
                        bool inside) {
    // Inverse transpose = cofactor / det: the cofactor gives the direction,
    // the sign of det keeps it (mirrors stay outward).
    const glm::dmat3 a(object_to_world);
    glm::dvec3 n = cofactor(a) * object_normal;
    if (glm::determinant(a) < 0.0) n = -n;
    const double len = glm::length(n);
    if (!(len > 0.0) || !std::isfinite(len)) return glm::dvec3(0.0);
    n /= len;
    return inside ? -n : n;
}

} // namespace detail

double DiceControl::edge_length_at(const glm::dvec3& world_p, double shading_rate) const {
    if (!(coarsening >= 1.0) || !std::isfinite(coarsening))
        throw ValueError("dice coarsening must be a finite number >= 1");
    if (std::isnan(spacing) || spacing < 0.0)
        throw ValueError("dice spacing must be a number >= 0 (0: use the ShadingRate)");
    if (spacing > 0.0) {
        if (!std::isfinite(spacing)) throw ValueError("dice spacing must be finite");
        return spacing * coarsening;
    }
    if (!camera)
        throw ValueError(
            "dicing by ShadingRate needs a camera (or give a fixed spacing)");
    if (!std::isfinite(shading_rate) || !(shading_rate > 0.0))
        throw ValueError("ShadingRate must be a finite number > 0");
    const glm::dvec4 h = camera->world_to_camera * glm::dvec4(world_p, 1.0);
    const glm::dvec3 pc = h.w == 1.0 ? glm::dvec3(h) : glm::dvec3(h) / h.w;
    // Distance from the eye, not depth: dicing ignores the orientation.
    const double distance = std::max(glm::length(pc), camera->near_clip);
    return std::sqrt(shading_rate) * camera->pixel_size_at(distance) * coarsening;
}

} // namespace sss
