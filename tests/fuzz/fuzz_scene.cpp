// libFuzzer target: a whole scene end to end. The input is RIB text:
// sss::parse_rib, then every primitive diced at the scene's ShadingRate
// (sizes, indices and finite coordinates checked), then, when the scene is
// small enough, a bake (every baked cloud consistent and finite, as the
// writers require; the clouds are written where the shaders name them, so
// that texture3d lookups find them) and a 16 x 16 render with one sample per
// pixel (no NaN in any channel). docs/fuzzing.md.
//
// Strict limits keep every run within libFuzzer's -timeout and
// -rss_limit_mb: the resource limits of sss/util/limits.h are set low, the
// memory budget is SSS_MEMORY_LIMIT=1G, oneTBB runs one thread, and scenes
// whose dicing exceeds a few thousand micropolygons per primitive or scene
// are only diced (the render and bake dice the same primitives again).
//
// The scene may name files: shaders along the search path, textures, brick
// maps, clouds (read) and the point clouds of bake3d in a render (written).
// The process works in an empty scratch folder (its current directory) that
// is emptied after every input, and inputs that could name a file outside it
// ('/' or a backslash escape) are skipped. The standard shaders are found
// as the tools find them (SSS_SHADER_DIR, else ../shaders next to the
// executable: scripts/fuzz builds them).

#include <cmath>
#include <cstdlib>
#include <string>
#include <vector>

#include "fuzz_bake.h"
#include "fuzz_cloud.h"
#include "fuzz_common.h"
#include "sss/bake/bake.h"
#include "sss/dice/dice.h"
#include "sss/render/render.h"
#include "sss/scene/rib.h"
#include "sss/util/limits.h"
#include "sss/util/threads.h"

namespace {

constexpr std::size_t kMaxInput = 16 * 1024;
// Dicing caps: above them the scene is diced but neither rendered nor baked.
constexpr std::size_t kPrimitiveMicropolygons = 8000;
constexpr std::size_t kSceneMicropolygons = 20000;
constexpr int kImageSide = 16;

/// The process-wide settings, once: limits, memory budget, one thread.
struct Setup {
    sss::ThreadLimit threads{1};
    Setup() {
        ::setenv("SSS_MEMORY_LIMIT", "1G", 1);
        sss::set_limit(sss::Limit::PrimitiveVertices, 4096);
        sss::set_limit(sss::Limit::PrimitiveMicropolygons, kPrimitiveMicropolygons);
        sss::set_limit(sss::Limit::SceneMicropolygons, kSceneMicropolygons);
        sss::set_limit(sss::Limit::ArchiveDepth, 8);
        sss::set_limit(sss::Limit::StringLength, 4096);
        sss::set_limit(sss::Limit::TokenLength, 1024);
        sss::set_limit(sss::Limit::ImagePixels, 64 * 64);
        sss::set_limit(sss::Limit::ImageSide, 64);
        sss::set_limit(sss::Limit::Bricks, 4096);
    }
};

bool finite3(const glm::vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

void check_surface(const sss::DicedSurface& s) {
    using sss::fuzz::require;
    require(s.normals.size() == s.size() && s.areas.size() == s.size() &&
                s.radii.size() == s.size() &&
                s.vertex_normals.size() == s.vertices.size() &&
                s.triangles.size() % 3 == 0,
            "diced surface sizes disagree");
    for (uint32_t v : s.triangles)
        require(v < s.vertices.size(), "triangle index out of range");
    for (std::size_t i = 0; i < s.size(); ++i) {
        require(finite3(s.centers[i]), "non-finite micropolygon centre");
        require(std::isfinite(s.areas[i]) && s.areas[i] >= 0.0f, "bad micropolygon area");
        require(std::isfinite(s.radii[i]) && s.radii[i] >= 0.0f,
                "bad micropolygon radius");
    }
    for (const glm::vec3& v : s.vertices) require(finite3(v), "non-finite vertex");
}

/// Dices every primitive as the bake does (ShadingRate, the scene's camera)
/// under the caps; false when a primitive fails or the caps are exceeded.
bool dice_everything(const sss::Scene& scene) {
    sss::DiceControl control;
    control.camera = &scene.options.camera;
    control.max_micropolygons = kPrimitiveMicropolygons;
    std::size_t total = 0;
    bool ok = true;
    for (const sss::Primitive& prim : scene.primitives) {
        try {
            const sss::DicedSurface s = sss::dice_primitive(prim, control);
            check_surface(s);
            total += s.size();
        } catch (const sss::Error& e) {
            ok = false; // malformed geometry or over the cap: a clean rejection
            if (sss::fuzz::verbose()) std::fprintf(stderr, "not diced: %s\n", e.what());
        }
        if (total > kSceneMicropolygons) {
            if (sss::fuzz::verbose())
                std::fprintf(stderr, "over %zu micropolygons: not rendered\n",
                             kSceneMicropolygons);
            return false;
        }
    }
    return ok;
}

void render_tiny(const sss::Scene& scene) {
    sss::RenderJobOptions options;
    options.xres = options.yres = kImageSide;
    options.pixel_samples = 1;
    sss::RenderReport report;
    const sss::Image image = sss::render_image(scene, options, &report);
    sss::fuzz::require(image.width == kImageSide && image.height == kImageSide &&
                           image.pixels.size() == std::size_t(kImageSide) * kImageSide *
                                                      image.channels.size(),
                       "rendered image has the wrong size");
    if (sss::fuzz::verbose())
        std::fprintf(stderr, "rendered %zu triangles, %zu camera rays\n",
                     report.triangles, report.camera_rays);
    for (std::size_t i = 0; i < image.pixels.size(); ++i) {
        if (std::isnan(image.pixels[i]))
            sss::fuzz::finding("NaN in rendered channel " +
                               image.channels[i % image.channels.size()]);
    }
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const Setup setup;
    static const sss::fuzz::ScratchFolder folder("scene", true);
    if (size > kMaxInput) return 0;
    const std::string text(reinterpret_cast<const char*>(data), size);
    if (sss::fuzz::may_name_outside_files(text)) return 0;
    // A fuzzer must not run programs: Procedural "RunProgram" would.
    if (text.find("RunProgram") != std::string::npos) return 0;
    sss::fuzz::run_expecting_errors([&] {
        // Leniently: what is not implemented is skipped, the rest exercised.
        sss::RibReadOptions options;
        options.lenient = true;
        const sss::Scene scene = sss::parse_rib(text, folder.file("scene.rib"), options);
        if (!dice_everything(scene)) return;
        sss::fuzz::run_expecting_errors([&] { sss::fuzz::bake_tiny(scene); });
        sss::fuzz::run_expecting_errors([&] { render_tiny(scene); });
    });
    folder.clear();
    return 0;
}
