#pragma once
/// \file dice_common.h
/// Internal: what every dicer of the module shares (how errors name a
/// primitive, the normal rule, small vector helpers) and the entry point of
/// each family of primitives, which only the dispatcher (dice.cpp) calls.

#include <cmath>
#include <string>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include "sss/dice/dice.h"

namespace sss::detail {

/// "file.rib:12: Sphere" — how errors name a primitive.
std::string describe(const Primitive& prim);

/// Throws ValueError "<source>: <Kind>: <what>".
[[noreturn]] void fail(const Primitive& prim, const std::string& what);

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

// The families of primitives, one file each; called by dice_primitive only.

/// Sphere, Cylinder, Cone, Disk, Torus, Hyperboloid, Paraboloid (dice_quadric.cpp).
DicedSurface dice_quadric(const Primitive& prim, const DiceControl& control);
/// Patch "bilinear" / "bicubic" (dice_patch.cpp).
DicedSurface dice_patch(const Primitive& prim, const DiceControl& control);
/// PatchMesh (dice_patch.cpp).
DicedSurface dice_patch_mesh(const Primitive& prim, const DiceControl& control);
/// Geometry "teapot" (dice_patch.cpp).
DicedSurface dice_teapot(const Primitive& prim, const DiceControl& control);
/// Polygon, GeneralPolygon, PointsPolygons, PointsGeneralPolygons (dice_polygon.cpp).
DicedSurface dice_polygons(const Primitive& prim, const DiceControl& control);
/// SubdivisionMesh "catmull-clark" (dice_subdiv.cpp).
DicedSurface dice_subdivision(const Primitive& prim, const DiceControl& control);

} // namespace sss::detail
