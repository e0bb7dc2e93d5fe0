// libFuzzer target: the shading engine on generated shaders. The input
// bytes drive rsl_generator.h, which writes a well-typed RSL surface shader
// (loops, user functions, recursion, texture/environment/textureinfo on
// files that exist and names that do not, bake3d and texture3d, illuminance,
// strings, arrays) into the scratch folder beside a tiny RIB (a sphere under
// a point and an ambient light); the scene then goes through the pipeline as
// in fuzz_scene.cpp: parse_rib, dicing, a bake (bake_clouds: the bake3d
// cloud checked and written) and a 16 x 16 render (no NaN in any channel:
// the generated shader passes what it outputs through a guard that maps
// NaN and infinities to 0). An sss::Error (a compile error, such as the
// recursion's, or a limit) is an expected outcome. docs/fuzzing.md.
//
// About one loop in 256 has a condition that may never become false: the
// engine's budgets (set low here) must end it with their error, well within
// libFuzzer's -timeout. SSS_FUZZ_RUNAWAY=0 leaves such loops out.
//
// The inputs name no file: the generator writes every name, all relative to
// the scratch folder (the current directory), which is emptied after every
// input. The textures the shaders read are made once (maketx through the
// library's texture plugin) and written back after each clean-up.

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

#include "fuzz_bake.h"
#include "fuzz_cloud.h"
#include "fuzz_common.h"
#include "rsl_generator.h"
#include "sss/bake/bake.h"
#include "sss/binding/texture_library.h"
#include "sss/cloud/point_cloud_io.h"
#include "sss/image/image_file.h"
#include "sss/render/render.h"
#include "sss/scene/rib.h"
#include "sss/util/limits.h"
#include "sss/util/threads.h"

namespace {

constexpr int kImageSide = 16;

const char* const kRib = R"(Format 16 16 1
PixelSamples 1 1
ShadingRate 4
Projection "perspective" "fov" [40]
Translate 0 0 4
WorldBegin
LightSource "pointlight" 1 "from" [2 2 -2] "intensity" [8]
LightSource "ambientlight" 2 "intensity" [0.1]
Color [0.8 0.6 0.4]
Surface "fuzzgen"
Sphere 1 -1 1 360
WorldEnd
)";

std::string read_bytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)),
                       std::istreambuf_iterator<char>());
}

/// The textures the generated shaders read: a small picture made into a
/// MIP-mapped texture and a lat-long environment map, plus the picture.
std::vector<std::pair<std::string, std::string>> make_assets() {
    const int w = 16, h = 8;
    std::vector<float> rgb(std::size_t(w) * h * 3);
    for (std::size_t i = 0; i < rgb.size(); ++i)
        rgb[i] = float(i % 7) / 6.0f + (i % 3 == 0 ? 0.5f : 0.0f);
    sss::ImageFileSpec spec;
    spec.format = "openexr";
    spec.width = w;
    spec.height = h;
    spec.channel_names = {"R", "G", "B"};
    spec.stored = sss::PixelType::Half;
    sss::write_image_file("picture.exr", spec, sss::PixelType::Float, rgb.data());
    sss::TextureLibrary textures;
    sss::TextureLibrary::Make tex;
    tex.input = "picture.exr";
    tex.output = "tex.tx";
    tex.swrap = tex.twrap = "periodic";
    textures.make_texture(tex, "fuzz_engine");
    sss::TextureLibrary::Make env = tex;
    env.output = "env.tx";
    env.latlong = true;
    textures.make_texture(env, "fuzz_engine");
    // The cloud texture3d reads before a bake has written it: 64 points on
    // the sphere of the scene.
    sss::PointCloud cloud;
    cloud.resize(64);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const float a = 0.1f * float(i), z = 1.0f - 2.0f * (float(i) + 0.5f) / 64.0f;
        const float r = std::sqrt(1.0f - z * z);
        cloud.positions[i] = cloud.normals[i] =
            glm::vec3(r * std::cos(a), r * std::sin(a), z);
        cloud.radii[i] = 0.2f;
    }
    cloud.add_channel("_f", sss::ChannelType::Float).data.assign(64, 0.5f);
    cloud.add_channel("_c", sss::ChannelType::Color).data.assign(64 * 3, 0.25f);
    sss::write_point_cloud(cloud, "bake.ptc");
    std::vector<std::pair<std::string, std::string>> assets;
    for (const char* name : {"picture.exr", "tex.tx", "env.tx", "bake.ptc"})
        assets.emplace_back(name, read_bytes(name));
    return assets;
}

/// The process-wide settings, once: limits as fuzz_scene sets them, memory
/// budget, one thread, the scratch folder and its textures.
struct Setup {
    sss::ThreadLimit threads{1};
    sss::fuzz::ScratchFolder folder{"engine", true};
    std::vector<std::pair<std::string, std::string>> assets;
    bool runaway = false;

    Setup() {
        ::setenv("SSS_MEMORY_LIMIT", "1G", 1);
        sss::set_limit(sss::Limit::PrimitiveVertices, 4096);
        sss::set_limit(sss::Limit::PrimitiveMicropolygons, 8000);
        sss::set_limit(sss::Limit::SceneMicropolygons, 20000);
        sss::set_limit(sss::Limit::ArchiveDepth, 8);
        sss::set_limit(sss::Limit::StringLength, 4096);
        sss::set_limit(sss::Limit::TokenLength, 1024);
        sss::set_limit(sss::Limit::ImagePixels, 64 * 64);
        sss::set_limit(sss::Limit::ImageSide, 64);
        sss::set_limit(sss::Limit::Bricks, 4096);
        // The engine's budgets, low: a runaway loop, string or array ends in
        // well under libFuzzer's -timeout with the budget's error.
        sss::set_limit(sss::Limit::ShaderOperations, 100'000);
        sss::set_limit(sss::Limit::ShaderStringLength, 1 << 16);
        sss::set_limit(sss::Limit::ShaderArrayLength, 1 << 16);
        sss::set_limit(sss::Limit::Bake3dPoints, 1'000'000);
        sss::set_limit(sss::Limit::Bake3dFiles, 16);
        // SSS_FUZZ_RUNAWAY=0 leaves out the constructs that may not end.
        const char* r = std::getenv("SSS_FUZZ_RUNAWAY");
        runaway = !(r && std::string(r) == "0");
        try {
            assets = make_assets();
        } catch (const sss::Error& e) {
            sss::fuzz::finding(std::string("cannot make the textures: ") + e.what());
        }
    }

    /// Writes the textures back after the folder was emptied.
    void restore() const {
        for (const auto& [name, bytes] : assets)
            sss::fuzz::write_file(folder.file(name),
                                  reinterpret_cast<const uint8_t*>(bytes.data()),
                                  bytes.size());
    }
};

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
    for (std::size_t i = 0; i < image.pixels.size(); ++i) {
        if (!std::isfinite(image.pixels[i]))
            sss::fuzz::finding("non-finite value in rendered channel " +
                               image.channels[i % image.channels.size()]);
    }
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const Setup setup;
    if (size > 4096) return 0; // the generator uses a few hundred bytes at most
    setup.folder.clear();
    setup.restore();
    sss::fuzz::ByteChoices choices(data, size);
    sss::fuzz::GeneratorFiles files;
    files.textures = {"tex.tx", "picture.exr"};
    files.environments = {"env.tx"};
    sss::fuzz::RslGenerator generator(choices, files, setup.runaway);
    const std::string source = generator.shader("fuzzgen");
    if (sss::fuzz::verbose()) std::fprintf(stderr, "%s", source.c_str());
    sss::fuzz::write_file(setup.folder.file("fuzzgen.sl"),
                          reinterpret_cast<const uint8_t*>(source.data()), source.size());
    sss::fuzz::run_expecting_errors([&] {
        const std::string rib_path = setup.folder.file("scene.rib");
        const sss::Scene scene = sss::parse_rib(kRib, rib_path);
        if (source.find("bake3d") != std::string::npos)
            sss::fuzz::run_expecting_errors([&] { sss::fuzz::bake_tiny(scene); });
        sss::fuzz::run_expecting_errors([&] { render_tiny(scene); });
    });
    return 0;
}
