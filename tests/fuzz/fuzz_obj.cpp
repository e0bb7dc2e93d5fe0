// libFuzzer target: the Wavefront OBJ importer, reached as a scene reaches
// it: the input is written as mesh.obj next to a fixed RIB whose world is
// `ReadArchive "mesh.obj"` (src/sss/scene/obj_import.cpp turns it into one
// PointsPolygons). The mesh is then diced at the RIB's ShadingRate with a
// cap of 8000 micropolygons (an sss::Error beyond), checking sizes, indices
// and finite coordinates. docs/fuzzing.md.
//
// OBJ statements that name files (mtllib) are ignored by the importer, so
// no input can make the target read anything but mesh.obj.

#include <cmath>
#include <string>

#include "fuzz_common.h"
#include "sss/dice/dice.h"
#include "sss/scene/rib.h"
#include "sss/util/limits.h"

namespace {

const char* const kScene = R"(Format 64 64 1
Projection "perspective" "fov" 40
ShadingRate 4
Translate 0 0 5
WorldBegin
ReadArchive "mesh.obj"
WorldEnd
)";

bool finite3(const glm::vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

void exercise(const sss::Scene& scene) {
    using sss::fuzz::require;
    sss::DiceControl control;
    control.camera = &scene.options.camera;
    control.max_micropolygons = 8000;
    for (const sss::Primitive& prim : scene.primitives) {
        const sss::DicedSurface s = sss::dice_primitive(prim, control);
        require(s.normals.size() == s.size() && s.areas.size() == s.size() &&
                    s.radii.size() == s.size() &&
                    s.vertex_normals.size() == s.vertices.size() &&
                    s.triangles.size() % 3 == 0,
                "diced surface sizes disagree");
        for (uint32_t v : s.triangles)
            require(v < s.vertices.size(), "triangle index out of range");
        for (std::size_t i = 0; i < s.size(); ++i) {
            require(finite3(s.centers[i]) && std::isfinite(s.areas[i]) &&
                        std::isfinite(s.radii[i]),
                    "non-finite micropolygon");
        }
        for (const glm::vec3& v : s.vertices) require(finite3(v), "non-finite vertex");
    }
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const sss::fuzz::ScratchFolder folder("obj", false);
    static const bool limited = [] {
        sss::set_limit(sss::Limit::PrimitiveVertices, 1 << 16);
        sss::set_limit(sss::Limit::PrimitiveMicropolygons, 8000);
        return true;
    }();
    (void)limited;
    sss::fuzz::write_file(folder.file("mesh.obj"), data, size);
    sss::fuzz::run_expecting_errors([&] {
        const sss::Scene scene = sss::parse_rib(kScene, folder.file("scene.rib"));
        exercise(scene);
    });
    return 0;
}
