#pragma once
// Internal interface between dice.cpp (dispatch, parametric surfaces) and
// dice_polygon.cpp (polygons and subdivision meshes).

#include "sss/dice/dice.h"

namespace sss::detail {

// Polygon, GeneralPolygon, PointsPolygons, PointsGeneralPolygons.
DicedSurface dice_polygons(const Primitive& prim, const DiceControl& control);
// SubdivisionMesh "catmull-clark".
DicedSurface dice_subdivision(const Primitive& prim, const DiceControl& control);

// Normal orientation rule shared by every primitive: the object-space normal
// is the RenderMan formula dPdu x dPdv (for polygons: (v1-v0) x (v2-v0) summed
// over the loop, Newell's method), transformed to world space by the inverse
// transpose of object_to_world, normalised, and negated when
// attributes->orientation_inside. User-supplied "N" is used as given
// (transformed as a normal), never flipped.
glm::dvec3 world_normal(const Matrix4& object_to_world, const glm::dvec3& object_normal,
                        bool inside);

} // namespace sss::detail
