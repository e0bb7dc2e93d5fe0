// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// The 2-D texture plugin's file makers and readers besides maketx's:
// depth maps (zfiles written by render, shadow maps by MakeShadow) and
// cube-face environments (MakeCubeFaceEnvironment). The formats are in
// docs/scene.md ("Depth maps", "Cube-face environments").

#include "texture2d_makers.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <vector>

#include <OpenImageIO/filter.h>
#include <OpenImageIO/imageio.h>

namespace sss::detail {

namespace {

constexpr double kPi = 3.14159265358979323846;

/// "file: reason" from OpenImageIO's first line.
std::string oiio_error(const std::string& file, std::string reason) {
    reason = reason.substr(0, reason.find('\n'));
    if (reason.empty()) reason = "cannot be read";
    return file + ": " + reason;
}

std::unique_ptr<OIIO::ImageInput> open_image(const std::string& file,
                                             std::string* error) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(file, ec)) {
        *error = file + ": " +
                 (std::filesystem::exists(file, ec)
                      ? "not a regular file"
                      : "cannot open: No such file or directory");
        return nullptr;
    }
    auto in = OIIO::ImageInput::open(file);
    if (!in) *error = oiio_error(file, OIIO::geterror());
    return in;
}

/// Writes a float image as scanline OpenEXR into `path` (whatever its
/// name: the caller's temporary), with the attributes already in `spec`.
bool write_exr(const std::string& path, OIIO::ImageSpec spec, const float* pixels,
               std::string* error) {
    auto out = OIIO::ImageOutput::create("openexr");
    if (!out) {
        *error = "no OpenEXR writer: " + OIIO::geterror();
        return false;
    }
    spec.attribute("compression", "zip");
    if (!out->open(path, spec) || !out->write_image(OIIO::TypeDesc::FLOAT, pixels) ||
        !out->close()) {
        *error = oiio_error(path, out->geterror());
        return false;
    }
    return true;
}

} // namespace

bool known_filter(const std::string& name) {
    for (int i = 0, n = OIIO::Filter2D::num_filters(); i < n; ++i) {
        OIIO::FilterDesc d;
        OIIO::Filter2D::get_filterdesc(i, &d);
        if (name == d.name) return true;
    }
    return false;
}

// --- depth maps -------------------------------------------------------------------

bool read_depth_map_file(const std::string& file, DepthMapData& out, std::string* error) {
    auto in = open_image(file, error);
    if (!in) return false;
    const OIIO::ImageSpec spec = in->spec();
    int channel = spec.channelindex("Z");
    if (channel < 0 && spec.nchannels == 1) channel = 0;
    if (channel < 0) {
        *error = file + ": not a depth map: no Z channel (a zfile or shadow map has one: "
                        "Display \"zfile\"/\"shadow\" or MakeShadow)";
        return false;
    }
    const bool matrices =
        spec.getattribute("worldtocamera", OIIO::TypeMatrix,
                          out.world_to_camera.data()) &&
        spec.getattribute("worldtoscreen", OIIO::TypeMatrix, out.world_to_screen.data());
    if (!matrices) {
        *error = file + ": not a depth map: no worldtocamera and worldtoscreen matrices "
                        "(a zfile or shadow map has them: Display \"zfile\"/\"shadow\" "
                        "or MakeShadow)";
        return false;
    }
    out.width = spec.width;
    out.height = spec.height;
    out.z.assign(std::size_t(spec.width) * std::size_t(spec.height), 0.0f);
    if (!in->read_image(0, 0, channel, channel + 1, OIIO::TypeDesc::FLOAT,
                        out.z.data())) {
        *error = oiio_error(file, in->geterror());
        return false;
    }
    // No NaN reaches a comparison: an unreadable depth shadows nothing.
    for (float& z : out.z)
        if (!std::isfinite(z)) z = 1e30f;
    return true;
}

bool make_shadow_file(const std::string& input, const std::string& output,
                      std::string* error) {
    DepthMapData map;
    if (!read_depth_map_file(input, map, error)) return false;
    OIIO::ImageSpec spec(map.width, map.height, 1, OIIO::TypeDesc::FLOAT);
    spec.channelnames = {"Z"};
    spec.z_channel = 0;
    spec.attribute("worldtocamera", OIIO::TypeMatrix, map.world_to_camera.data());
    spec.attribute("worldtoscreen", OIIO::TypeMatrix, map.world_to_screen.data());
    spec.attribute("textureformat", "Shadow");
    spec.attribute("sss:textureformat", "Shadow");
    spec.attribute("sss:source", input);
    return write_exr(output, spec, map.z.data(), error);
}

// --- cube-face environments ---------------------------------------------------------

namespace {

/// A picture as floats, nchannels per pixel.
struct Picture {
    int width = 0, height = 0, channels = 0;
    std::vector<float> pixels;

    /// Bilinear at pixel-centre coordinates (x, y), clamped to the edges.
    void sample(double x, double y, float* out) const {
        x = std::clamp(x, 0.0, double(width - 1));
        y = std::clamp(y, 0.0, double(height - 1));
        const int x0 = static_cast<int>(std::floor(x)),
                  y0 = static_cast<int>(std::floor(y));
        const int x1 = std::min(x0 + 1, width - 1), y1 = std::min(y0 + 1, height - 1);
        const double fx = x - x0, fy = y - y0;
        for (int c = 0; c < channels; ++c) {
            const auto at = [&](int px, int py) {
                return double(pixels[(std::size_t(py) * width + px) * channels + c]);
            };
            const double top = at(x0, y0) * (1 - fx) + at(x1, y0) * fx;
            const double bottom = at(x0, y1) * (1 - fx) + at(x1, y1) * fx;
            out[c] = static_cast<float>(top * (1 - fy) + bottom * fy);
        }
    }
};

bool read_picture(const std::string& file, Picture& p, std::string* error) {
    auto in = open_image(file, error);
    if (!in) return false;
    const OIIO::ImageSpec& spec = in->spec();
    p.width = spec.width;
    p.height = spec.height;
    p.channels = spec.nchannels;
    p.pixels.assign(std::size_t(p.width) * p.height * p.channels, 0.0f);
    if (p.pixels.empty() ||
        !in->read_image(0, 0, 0, p.channels, OIIO::TypeDesc::FLOAT, p.pixels.data())) {
        *error = oiio_error(file, in->geterror());
        return false;
    }
    for (float& v : p.pixels)
        if (!std::isfinite(v)) v = 0.0f;
    return true;
}

} // namespace

bool make_cube_environment_file(const std::array<std::string, 6>& faces,
                                const std::string& output, double fov,
                                const std::string& filter, std::string* error) {
    if (!known_filter(filter)) {
        *error = "unknown filter \"" + filter + "\"";
        return false;
    }
    if (!(fov > 0.0 && fov < 180.0)) {
        *error = "field of view " + std::to_string(fov) + " is not in (0, 180) degrees";
        return false;
    }
    std::array<Picture, 6> pic;
    for (int f = 0; f < 6; ++f) {
        if (!read_picture(faces[f], pic[f], error)) return false;
        if (pic[f].width != pic[0].width || pic[f].height != pic[0].height ||
            pic[f].channels != pic[0].channels) {
            *error = faces[f] + ": " + std::to_string(pic[f].width) + " x " +
                     std::to_string(pic[f].height) + " with " +
                     std::to_string(pic[f].channels) + " channels; the first face, " +
                     faces[0] + ", is " + std::to_string(pic[0].width) + " x " +
                     std::to_string(pic[0].height) + " with " +
                     std::to_string(pic[0].channels) + ": the six faces must match";
            return false;
        }
    }
    const int n = pic[0].width, h = pic[0].height, nc = pic[0].channels;
    // The face's [-1, 1] on the picture: a wider view than 90 degrees
    // holds the face in its middle.
    const double k = 1.0 / std::tan(0.5 * fov * kPi / 180.0);
    std::vector<float> cube(std::size_t(n) * 6 * n * nc, 0.0f);
    for (int f = 0; f < 6; ++f) {
        // OpenEXR's faces are seen as a right-handed viewer sees them,
        // RenderMan's pictures as its left-handed camera does: the side
        // faces are mirrored left to right, the top and bottom ones upside
        // down (docs/scene.md, "Cube-face environments").
        const bool top_or_bottom = f == 2 || f == 3;
        for (int j = 0; j < n; ++j) {
            for (int i = 0; i < n; ++i) {
                // OpenEXR: pixel centres 0 and n - 1 on the cube's edges.
                const double a = n > 1 ? -1.0 + 2.0 * i / (n - 1) : 0.0;
                const double b = n > 1 ? -1.0 + 2.0 * j / (n - 1) : 0.0;
                const double u = (top_or_bottom ? a : -a) * k;
                const double v = (top_or_bottom ? -b : b) * k;
                const double x = 0.5 * (u + 1.0) * n - 0.5;
                const double y = 0.5 * (v + 1.0) * h - 0.5;
                float* dst = &cube[((std::size_t(f) * n + j) * n + i) * nc];
                pic[f].sample(x, y, dst);
            }
        }
    }
    OIIO::ImageSpec spec(n, 6 * n, nc, OIIO::TypeDesc::FLOAT);
    OIIO::ImageSpec first;
    if (auto in = OIIO::ImageInput::open(faces[0])) first = in->spec();
    if (int(first.channelnames.size()) == nc) spec.channelnames = first.channelnames;
    spec.alpha_channel = first.alpha_channel;
    spec.attribute("textureformat", "CubeFace Environment");
    spec.attribute("sss:fov", static_cast<float>(fov));
    return write_exr(output, spec, cube.data(), error);
}

} // namespace sss::detail
