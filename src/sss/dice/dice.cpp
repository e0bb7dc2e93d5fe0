/// \file dice.cpp
/// The dispatcher: dice_primitive hands each primitive to the dicer of its
/// family (dice_quadric.cpp, dice_patch.cpp, dice_polygon.cpp,
/// dice_subdiv.cpp).

#include "sss/dice/dice.h"

#include "dice_common.h"
#include "sss/util/error.h"

namespace sss {

DicedSurface dice_primitive(const Primitive& prim, const DiceControl& control) {
    switch (prim.kind) {
    case PrimitiveKind::Polygon:
    case PrimitiveKind::GeneralPolygon:
    case PrimitiveKind::PointsPolygons:
    case PrimitiveKind::PointsGeneralPolygons:
        return detail::dice_polygons(prim, control);
    case PrimitiveKind::SubdivisionMesh:
        return detail::dice_subdivision(prim, control);
    case PrimitiveKind::Sphere:
    case PrimitiveKind::Cylinder:
    case PrimitiveKind::Cone:
    case PrimitiveKind::Disk:
    case PrimitiveKind::Torus:
    case PrimitiveKind::Hyperboloid:
    case PrimitiveKind::Paraboloid:
        return detail::dice_quadric(prim, control);
    case PrimitiveKind::Patch:
        return detail::dice_patch(prim, control);
    case PrimitiveKind::PatchMesh:
        return detail::dice_patch_mesh(prim, control);
    case PrimitiveKind::Teapot:
        return detail::dice_teapot(prim, control);
    }
    throw ValueError(prim.source + ": unknown primitive kind");
}

} // namespace sss
