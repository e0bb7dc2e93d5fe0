// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file dice_common.h
/// Internal: what every dicer of the module shares (how errors name a
/// primitive, the normal rule, small vector helpers) and the entry point of
/// each family of primitives, which only the dispatcher (dice.cpp) calls.

#include <cmath>
#include <string>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "sss/dice/dice.h"

namespace sss::detail {

/// "file.rib:12: Sphere" — how errors name a primitive.
std::string describe(const Primitive& prim);

/// Throws ValueError "<source>: <Kind>: <what>".
[[noreturn]] void fail(const Primitive& prim, const std::string& what);

/// Throws LimitError (Limit::PrimitiveMicropolygons) "<source>: <Kind>: N
/// micropolygons in one primitive exceeds the limit of M (set
/// SSS_LIMIT_PRIMITIVE_MICROPOLYGONS to raise it, or dice coarser ...)",
/// M = control.max_micropolygons; N is what dicing needs, or at least needs.
[[noreturn]] void too_many_micropolygons(const Primitive& prim,
                                         const DiceControl& control, double count);

/// Whether a world-space point is finite and within kMaxWorldCoordinate.
inline bool in_world_range(const glm::dvec3& p) {
    return std::abs(p.x) <= kMaxWorldCoordinate && std::abs(p.y) <= kMaxWorldCoordinate &&
           std::abs(p.z) <= kMaxWorldCoordinate; // NaN fails
}

/// ValueError naming the primitive unless in_world_range(p): "<source>:
/// <Kind>: its surface reaches (x, y, z) in world space, beyond the
/// coordinate range of +-1e+18 ...".
void check_world_point(const Primitive& prim, const glm::dvec3& p);

/// check_world_point for every vertex and micropolygon centre of a diced
/// surface (displacement included).
void check_world_range(const Primitive& prim, const DicedSurface& surface);

/// Normal orientation rule shared by every primitive: the object-space normal
/// is the RenderMan formula dPdu x dPdv (for polygons: (v1-v0) x (v2-v0) summed
/// over the loop, Newell's method), transformed to world space by the inverse
/// transpose of object_to_world, normalised, and negated when
/// attributes->orientation_inside. User-supplied "N" is used as given
/// (transformed as a normal), never flipped.
glm::dvec3 world_normal(const Matrix4& object_to_world, const glm::dvec3& object_normal,
                        bool inside);

/// Cofactor matrix of a: cof(a) * (x cross y) = (a x) cross (a y), and
/// cof(a) = det(a) * inverse(transpose(a)) — the normal transform without
/// the division, defined even for singular matrices.
inline glm::dmat3 cofactor(const glm::dmat3& a) {
    return glm::dmat3(glm::cross(a[1], a[2]), glm::cross(a[2], a[0]),
                      glm::cross(a[0], a[1]));
}

inline bool finite(const glm::dvec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// The families of primitives, one file each; called by dice_primitive and
// estimate_primitive only. With `estimate` set, a family checks the
// primitive as for dicing but only adds what dicing would make to
// *estimate (estimate_primitive), and returns an empty surface.

/// Sphere, Cylinder, Cone, Disk, Torus, Hyperboloid, Paraboloid (dice_quadric.cpp).
DicedSurface dice_quadric(const Primitive& prim, const DiceControl& control,
                          DiceEstimate* estimate = nullptr);
/// Patch "bilinear" / "bicubic" (dice_patch.cpp).
DicedSurface dice_patch(const Primitive& prim, const DiceControl& control,
                        DiceEstimate* estimate = nullptr);
/// PatchMesh (dice_patch.cpp).
DicedSurface dice_patch_mesh(const Primitive& prim, const DiceControl& control,
                             DiceEstimate* estimate = nullptr);
/// Geometry "teapot" (dice_patch.cpp).
DicedSurface dice_teapot(const Primitive& prim, const DiceControl& control,
                         DiceEstimate* estimate = nullptr);
/// Points (dice_curves.cpp).
DicedSurface dice_points(const Primitive& prim, const DiceControl& control,
                         DiceEstimate* estimate = nullptr);
/// Curves "linear" / "cubic" (dice_curves.cpp).
DicedSurface dice_curves(const Primitive& prim, const DiceControl& control,
                         DiceEstimate* estimate = nullptr);
/// NuPatch, trimmed by the current TrimCurve (dice_nurbs.cpp).
DicedSurface dice_nupatch(const Primitive& prim, const DiceControl& control,
                          DiceEstimate* estimate = nullptr);
/// Blobby (dice_blobby.cpp).
DicedSurface dice_blobby(const Primitive& prim, const DiceControl& control,
                         DiceEstimate* estimate = nullptr);
/// The mesh dice_blobby dices: the Blobby's surface polygonized as a
/// PointsPolygons of quads in its object space, with "P", the unit normals
/// "N" (the field's gradient, outward unless Orientation "inside"), the
/// primitive variables (per-leaf ones blended by the leaves' fields, per
/// vertex) and, unless given, "s" and "t" (x and y across the blobs' box).
/// No faces when the surface is empty. ValueError naming the primitive for
/// a malformed program, LimitError past control.max_micropolygons quads.
Primitive blobby_mesh(const Primitive& prim, const DiceControl& control);
/// The matrix of a spline basis in our column-vector layout; a
/// default-constructed Basis stands for Bezier, the RI default
/// (dice_patch.cpp).
glm::dmat4 resolve_basis(const Basis& b);
/// Polygon, GeneralPolygon, PointsPolygons, PointsGeneralPolygons (dice_polygon.cpp).
DicedSurface dice_polygons(const Primitive& prim, const DiceControl& control,
                           DiceEstimate* estimate = nullptr);
/// SubdivisionMesh "catmull-clark" (dice_subdiv.cpp).
DicedSurface dice_subdivision(const Primitive& prim, const DiceControl& control,
                              DiceEstimate* estimate = nullptr);

/// What dicing makes of one flat face of world-space area `area` and
/// perimeter `perimeter` at micropolygon edge `edge`, cut into `pieces`
/// triangles or quads first: the estimate the polygon and subdivision
/// families add up.
DiceEstimate estimate_flat_face(double area, double perimeter, double edge,
                                double pieces);

} // namespace sss::detail
