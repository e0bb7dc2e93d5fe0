// libFuzzer target: image files as shaders and tools read them. The input is
// written as an image in the scratch folder, its extension chosen by its
// magic (.png, .jpg, .exr, .hdr, TIFF as .tx or .tif; anything else by its
// first byte), then looked up through the library's texture services as
// texture(), environment(), shadow() and textureinfo() do in a render
// (sss::TextureLibrary: OpenImageIO's TextureSystem in the texture plugin,
// the depth-map reader): 2-D lookups of one and three channels at points on,
// off and around the image with blur, width, filter and MIP options, the
// 4-point form, environment directions (NaN and zero included), shadow
// lookups and every textureinfo key. Then envdome's probe reader
// (sss::read_image) and, for a lat-long sized picture, its median cut.
//
// A lookup that fails with an error message, an sss::Error, or values are
// expected; values must be finite when the picture is an 8-bit format
// (PNG, JPEG) that read_image read in full. A crash, an abort inside
// OpenImageIO, another exception, a run over the timeout or over the memory
// limit is a finding. docs/fuzzing.md.

#include <cmath>
#include <cstdlib>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include <glm/vec3.hpp>

#include "fuzz_common.h"
#include "sss/binding/texture_library.h"
#include "sss/light/light_dome.h"
#include "sss/render/image_io.h"
#include "sss/util/limits.h"
#include "sss/util/threads.h"

namespace {

constexpr std::size_t kMaxInput = 64 * 1024;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

struct Setup {
    sss::ThreadLimit threads{1};
    sss::fuzz::ScratchFolder folder{"texture", false};
    Setup() {
        ::setenv("SSS_MEMORY_LIMIT", "1G", 1);
        sss::set_limit(sss::Limit::ImagePixels, 256 * 256);
        sss::set_limit(sss::Limit::ImageSide, 4096);
    }
};

/// The extension the input is saved under: by magic, else by its first byte.
std::string extension_of(std::string_view in) {
    auto starts = [&](std::string_view magic) {
        return in.substr(0, magic.size()) == magic;
    };
    if (starts("\x89PNG")) return ".png";
    if (starts("\xff\xd8")) return ".jpg";
    if (starts(std::string_view("v/1\x01", 4))) return ".exr";
    if (starts("#?")) return ".hdr";
    if (starts(std::string_view("II*\0", 4)) || starts(std::string_view("MM\0*", 4)))
        return in.size() % 2 ? ".tif" : ".tx";
    static const char* const kAny[] = {".png", ".jpg", ".exr", ".hdr", ".tx"};
    return in.empty() ? ".tx" : kAny[static_cast<uint8_t>(in[0]) % 5];
}

/// The lookup points: inside, on the edges, outside, huge and NaN.
struct Points {
    std::vector<float> s{0.5f, 0.0f, 1.0f, 0.25f, -0.5f, 1.75f, 1e9f, kNaN, 0.999f};
    std::vector<float> t{0.5f, 0.0f, 1.0f, 0.75f, 2.5f, -3.0f, -1e9f, 0.5f, kNaN};
    std::size_t size() const { return s.size(); }
};

class Checker {
public:
    explicit Checker(bool finite) : m_finite(finite) {}
    void values(const std::vector<float>& out, const char* what) const {
        if (!m_finite) return;
        for (float v : out)
            if (!std::isfinite(v))
                sss::fuzz::finding(std::string("non-finite value from ") + what);
    }

private:
    bool m_finite;
};

void texture_lookups(sss::TextureLibrary& lib, const std::string& file,
                     const Checker& check) {
    const Points p;
    const std::size_t n = p.size();
    std::vector<float> ds(n, 0.01f), dt(n, 0.02f), zero(n, 0.0f), huge(n, 1e6f);
    std::string error;
    sss::TextureOptions options[4];
    options[1].sblur = options[1].tblur = 0.1f;
    options[1].filter = "gaussian";
    options[2].swidth = options[2].twidth = 0;
    options[2].filter = "none";
    options[2].lerp = 0;
    options[3].swidth = 1e4f;
    options[3].lerp = 1;
    options[3].fill = 0.5f;
    for (const sss::TextureOptions& o : options) {
        for (int nch : {1, 3}) {
            std::vector<float> out(n * nch, 0.0f);
            lib.texture(file, nch == 1 ? 2 : 0, nch, o, n, p.s.data(), p.t.data(),
                        ds.data(), zero.data(), zero.data(), dt.data(), nullptr,
                        out.data(), &error);
            check.values(out, "texture()");
            // Footprints OpenImageIO asserts on unless the library bounds
            // them (regressions/texture/).
            lib.texture(file, 0, nch, o, n, p.s.data(), p.t.data(), huge.data(),
                        huge.data(), nullptr, nullptr, nullptr, out.data(), &error);
            check.values(out, "texture() with a huge, degenerate footprint");
        }
    }
    std::vector<float> s2(p.s), t2(p.t);
    for (float& v : s2) v += 0.1f;
    for (float& v : t2) v += 0.1f;
    const float* st[8] = {p.s.data(), p.t.data(), s2.data(), p.t.data(),
                          p.s.data(), t2.data(),  s2.data(), t2.data()};
    std::vector<float> out(n * 3, 0.0f);
    lib.texture_quad(file, 0, 3, options[1], n, st, nullptr, out.data(), &error);
    check.values(out, "texture() of 4 points");
}

void other_lookups(sss::TextureLibrary& lib, const std::string& file,
                   const Checker& check) {
    const std::vector<glm::vec3> dirs{{0, 0, 1},  {1, 0, 0},    {0, 1, 0},
                                      {0, -1, 0}, {-1, 0, 0},   {0, 0, -1},
                                      {0, 0, 0},  {kNaN, 0, 1}, {1e30f, 1, -1e-30f}};
    const std::vector<glm::vec3> ddir(dirs.size(), glm::vec3(0.01f, 0.0f, 0.0f));
    std::string error;
    sss::TextureOptions options;
    options.sblur = 0.05f;
    std::vector<float> out(dirs.size() * 3, 0.0f);
    lib.environment(file, 0, 3, options, dirs.size(), dirs.data(), ddir.data(),
                    ddir.data(), nullptr, out.data(), &error);
    check.values(out, "environment()");

    // A depth map: the fraction in shadow is finite whatever the file.
    options.bias = 0.01f;
    options.samples = 4;
    std::vector<float> shadowed(dirs.size(), 0.0f);
    if (lib.shadow(file, options, dirs.size(), dirs.data(), ddir.data(), nullptr, nullptr,
                   shadowed.data(), &error)) {
        for (float v : shadowed)
            sss::fuzz::require(std::isnan(v) == false, "NaN from shadow()");
    }

    float numbers[16];
    std::string text;
    lib.texture_info(file, "resolution", 2, numbers, &text);
    lib.texture_info(file, "channels", 1, numbers, &text);
    lib.texture_info(file, "type", 0, numbers, &text);
    lib.texture_info(file, "viewingmatrix", 16, numbers, &text);
    lib.texture_info(file, "projectionmatrix", 16, numbers, &text);
    lib.texture_info(file, "unknown", 1, numbers, &text);
}

/// envdome's reading of a probe: read_image, then the median cut of a
/// lat-long picture. True when the picture read and every value is finite.
bool probe(const std::string& file) {
    bool finite = false;
    sss::fuzz::run_expecting_errors([&] {
        const sss::Image img = sss::read_image(file);
        sss::fuzz::require(img.width >= 0 && img.height >= 0 &&
                               img.pixels.size() == std::size_t(img.width) * img.height *
                                                        img.channels.size(),
                           "read_image: size and pixels disagree");
        finite = true;
        for (float v : img.pixels) finite = finite && std::isfinite(v);
        if (!finite || img.height <= 0 || img.width != 2 * img.height ||
            img.channel_count() == 0)
            return;
        sss::LatLongImage ll(img.width, img.height);
        for (int y = 0; y < img.height; ++y)
            for (int x = 0; x < img.width; ++x)
                for (int c = 0; c < 3; ++c)
                    ll.pixel(x, y)[c] = img.pixel(x, y)[c % img.channel_count()];
        for (const sss::DomeLight& light : sss::median_cut(ll, 8))
            sss::fuzz::require(std::isfinite(light.color.r) &&
                                   std::isfinite(light.color.g) &&
                                   std::isfinite(light.color.b),
                               "median cut of a finite probe gave a non-finite light");
    });
    return finite;
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const Setup setup;
    static unsigned counter = 0;
    if (size > kMaxInput) return 0;
    const std::string_view in(reinterpret_cast<const char*>(data), size);
    const std::string ext = extension_of(in);
    // A new name each time: nothing the last input left cached is reused.
    const std::string file = setup.folder.file("image" + std::to_string(counter++) + ext);
    sss::fuzz::write_file(file, data, size);
    const bool finite = probe(file) && (ext == ".png" || ext == ".jpg");
    const Checker check(finite);
    sss::fuzz::run_expecting_errors([&] {
        sss::TextureLibrary lib;
        texture_lookups(lib, file, check);
        other_lookups(lib, file, check);
    });
    setup.folder.clear();
    return 0;
}
