// libFuzzer target: the RIB parser (sss::parse_rib on the input text), then
// the camera of the scene and a coarse dicing of its first primitives, which
// reads every parameter list and topology array the parser accepted.
// docs/fuzzing.md.
//
// ReadArchive reads files: the text is named "<empty temp folder>/fuzz.rib",
// so relative archive names find nothing, and inputs that could name a file
// elsewhere (an archive statement together with a '/' or a backslash escape)
// are skipped, so that the fuzzer never reads the project's own files.

#include <cmath>
#include <cstdlib>
#include <string>
#include <string_view>

#include "fuzz_common.h"
#include "sss/dice/dice.h"
#include "sss/scene/rib.h"

namespace {

void exercise(const sss::Scene& scene) {
    const sss::Camera& cam = scene.options.camera;
    cam.resolved_screen_window();
    cam.world_to_ndc();
    cam.pixel_size_at(1.0);
    sss::DiceControl control;
    control.camera = &cam;
    control.max_micropolygons = 4096; // a ValueError beyond: keeps every run short
    std::size_t diced = 0;
    for (const sss::Primitive& prim : scene.primitives) {
        if (++diced > 8) break;
        try {
            const sss::DicedSurface s = sss::dice_primitive(prim, control);
            sss::fuzz::require(s.normals.size() == s.size() &&
                                   s.areas.size() == s.size() &&
                                   s.radii.size() == s.size() &&
                                   s.vertex_normals.size() == s.vertices.size() &&
                                   s.triangles.size() % 3 == 0,
                               "diced surface sizes disagree");
            for (uint32_t v : s.triangles)
                sss::fuzz::require(v < s.vertices.size(), "triangle index out of range");
        } catch (const sss::Error&) {
            // Malformed geometry the parser leaves to the dicer: a ValueError.
        }
    }
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const sss::fuzz::ScratchFolder folder("rib", false);
    const std::string text(reinterpret_cast<const char*>(data), size);
    if (text.find("Archive") != std::string::npos &&
        sss::fuzz::may_name_outside_files(text))
        return 0;
    // A fuzzer must not run programs: Procedural "RunProgram" would.
    if (text.find("RunProgram") != std::string::npos) return 0;
    sss::fuzz::run_expecting_errors([&] {
        // Leniently: what is not implemented is skipped, the rest exercised.
        sss::RibReadOptions options;
        options.lenient = true;
        const sss::Scene scene = sss::parse_rib(text, folder.file("fuzz.rib"), options);
        exercise(scene);
    });
    return 0;
}
