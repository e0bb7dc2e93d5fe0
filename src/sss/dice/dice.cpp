/// \file dice.cpp
/// The dispatcher: dice_primitive hands each primitive to the dicer of its
/// family (dice_quadric.cpp, dice_patch.cpp, dice_polygon.cpp,
/// dice_subdiv.cpp), and dice_all dices many of them in parallel for the
/// baker and the renderer.

#include "sss/dice/dice.h"

#include <exception>
#include <string>
#include <vector>

#include <tbb/parallel_for.h>

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

std::vector<DicedSurface> dice_all(const Scene& scene,
                                   std::span<const DiceRequest> requests,
                                   const DiceFinish& finish) {
    std::vector<DicedSurface> diced(scene.primitives.size());
    // One message per request, so that the first failure in request order is
    // reported whichever thread met it first.
    std::vector<std::string> errors(requests.size());
    tbb::parallel_for(std::size_t(0), requests.size(), [&](std::size_t k) {
        try {
            const DiceRequest& request = requests[k];
            DicedSurface& surface = diced[request.primitive];
            surface =
                dice_primitive(scene.primitives[request.primitive], request.control);
            if (finish) finish(request.primitive, surface);
        } catch (const std::exception& e) {
            errors[k] = e.what();
        }
    });
    for (const std::string& e : errors)
        if (!e.empty()) throw ValueError(e);
    return diced;
}

} // namespace sss
