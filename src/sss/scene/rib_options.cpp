// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file rib_options.cpp
/// The reader's option requests: image format, camera projection and screen
/// window, displays, the imager shader, hider, `Option` and the parameter
/// declarations.

#include "rib_reader.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>

#include "rib_args.h"
#include "sss/util/limits.h"
#include "sss/util/messages.h"

namespace sss::rib {

bool Reader::option_allowed(const Statement& s) {
    if (!m_in_world) return true;
    warn(s, s.name + " inside WorldBegin/WorldEnd has no effect, ignored");
    return false;
}

void Reader::do_format(const Statement& s) {
    std::size_t i = 0;
    auto n = take_numbers(s, i, 3);
    no_more_args(s, i);
    int xres = to_int(s, n[0], "xresolution");
    int yres = to_int(s, n[1], "yresolution");
    if (xres < 1 || yres < 1) fail(s, "resolution must be positive");
    // Before anything is sized by it (render's image, ptbake's dicing rate).
    const std::string at =
        where(s) + ": Format " + std::to_string(xres) + " " + std::to_string(yres);
    check_limit(Limit::ImageSide, uint64_t(std::max(xres, yres)), at);
    check_limit(Limit::ImagePixels, uint64_t(xres) * uint64_t(yres), at);
    if (!(n[2] > 0.0)) fail(s, "pixel aspect ratio must be positive, got " + fmt(n[2]));
    if (!option_allowed(s)) return;
    m_scene.options.camera.xres = xres;
    m_scene.options.camera.yres = yres;
    m_scene.options.camera.pixel_aspect = n[2];
    m_scene.options.camera.sources.format = where(s) + ": " + s.name;
}

void Reader::do_frame_aspect(const Statement& s) {
    std::size_t i = 0;
    double a = take_number(s, i);
    no_more_args(s, i);
    if (!(a > 0.0)) fail(s, "frame aspect ratio must be positive, got " + fmt(a));
    if (!option_allowed(s)) return;
    m_frame_aspect = a;
    m_scene.options.camera.sources.frame_aspect = where(s) + ": " + s.name;
}

void Reader::do_screen_window(const Statement& s) {
    std::size_t i = 0;
    auto n = take_numbers(s, i, 4);
    no_more_args(s, i);
    if (n[0] == n[1] || n[2] == n[3]) fail(s, "empty screen window");
    if (!option_allowed(s)) return;
    m_scene.options.camera.screen_window = {n[0], n[1], n[2], n[3]};
    m_scene.options.camera.sources.screen_window = where(s) + ": " + s.name;
}

void Reader::do_crop_window(const Statement& s) {
    std::size_t i = 0;
    auto n = take_numbers(s, i, 4);
    no_more_args(s, i);
    for (double v : n)
        if (v < 0.0 || v > 1.0) fail(s, "crop window values must lie in [0,1]");
    // Only restricts which pixels are rendered: nothing to record here.
}

void Reader::do_projection(const Statement& s) {
    std::size_t i = 0;
    std::string name = take_string(s, i, "projection name");
    ParamList params = take_params(s, i, true);
    if (!option_allowed(s)) return;
    Camera& cam = m_scene.options.camera;
    if (name == "perspective") {
        double fov = params.get_float("fov", cam.fov);
        if (!(fov > 0.0 && fov < 180.0))
            fail(s, "fov must lie in (0, 180) degrees, got " + fmt(fov));
        cam.perspective = true;
        cam.fov = fov;
    } else if (name == "orthographic") {
        cam.perspective = false;
    } else {
        fail(s, "unsupported projection " + sss::quoted(name) +
                    " (perspective or orthographic)");
    }
    cam.sources.projection = where(s) + ": " + s.name;
    // RI: the projection marks camera space; the CTM restarts from identity.
    if (m_ctm != Matrix4(1.0))
        warn(s, "transformations before Projection are part of the screen "
                "transformation and are ignored");
    set_ctm(Matrix4(1.0));
}

void Reader::do_clipping(const Statement& s) {
    std::size_t i = 0;
    auto n = take_numbers(s, i, 2);
    no_more_args(s, i);
    if (!(n[0] > 0.0) || !(n[1] > n[0]))
        fail(s, "need 0 < near < far, got " + fmt(n[0]) + " " + fmt(n[1]));
    if (!option_allowed(s)) return;
    m_scene.options.camera.near_clip = n[0];
    m_scene.options.camera.far_clip = n[1];
    m_scene.options.camera.sources.clipping = where(s) + ": " + s.name;
}

void Reader::do_pixel_samples(const Statement& s) {
    std::size_t i = 0;
    auto n = take_numbers(s, i, 2);
    no_more_args(s, i);
    for (double v : n)
        if (!(v >= 1.0 && v <= 1024.0)) fail(s, "pixel samples must lie in [1, 1024]");
    if (!option_allowed(s)) return;
    m_scene.options.pixel_samples[0] = static_cast<int>(std::ceil(n[0]));
    m_scene.options.pixel_samples[1] = static_cast<int>(std::ceil(n[1]));
}

void Reader::do_depth_of_field(const Statement& s) {
    std::size_t i = 0;
    Camera& cam = m_scene.options.camera;
    if (s.args.empty()) { // no arguments: the pinhole camera
        if (!option_allowed(s)) return;
        cam.fstop = std::numeric_limits<double>::infinity();
        cam.focal_length = cam.focal_distance = 0.0;
        cam.sources.depth_of_field.clear();
        return;
    }
    auto n = take_numbers(s, i, 3);
    no_more_args(s, i);
    if (!(n[0] > 0.0)) fail(s, "fstop must be positive, got " + fmt(n[0]));
    if (!(n[1] > 0.0)) fail(s, "focallength must be positive, got " + fmt(n[1]));
    if (!(n[2] > n[1]))
        fail(s, "focaldistance " + fmt(n[2]) + " must be beyond focallength " +
                    fmt(n[1]) + " (nothing could be in focus)");
    if (!option_allowed(s)) return;
    // RI_INFINITY (1e38) or any huge fstop: a lens of no size, the pinhole.
    cam.fstop = n[0] >= 1e30 ? std::numeric_limits<double>::infinity() : n[0];
    cam.focal_length = n[1];
    cam.focal_distance = n[2];
    cam.sources.depth_of_field = where(s) + ": " + s.name;
}

void Reader::do_pixel_filter(const Statement& s) {
    std::size_t i = 0;
    std::string name = take_string(s, i, "filter name");
    auto n = take_numbers(s, i, 2);
    no_more_args(s, i);
    std::string key = lower(name);
    if (key == "catmullrom") key = "catmull-rom";
    static const char* const kNames[] = {"box", "triangle", "catmull-rom", "gaussian",
                                         "sinc"};
    if (std::find(std::begin(kNames), std::end(kNames), key) == std::end(kNames))
        fail(s, "unknown pixel filter \"" + name +
                    "\" (box, triangle, catmull-rom, gaussian or sinc)");
    for (double w : n)
        if (!(w > 0.0 && w <= 16.0))
            fail(s, "filter widths must lie in (0, 16] pixels, got " + fmt(n[0]) + " " +
                        fmt(n[1]));
    if (!option_allowed(s)) return;
    m_scene.options.pixel_filter = {key, n[0], n[1]};
}

void Reader::do_exposure(const Statement& s) {
    std::size_t i = 0;
    auto n = take_numbers(s, i, 2);
    no_more_args(s, i);
    if (!(n[0] >= 0.0) || !std::isfinite(n[0]))
        fail(s, "exposure gain must be 0 or more, got " + fmt(n[0]));
    if (!(n[1] > 0.0) || !std::isfinite(n[1]))
        fail(s, "exposure gamma must be positive, got " + fmt(n[1]));
    if (!option_allowed(s)) return;
    m_scene.options.exposure_gain = n[0];
    m_scene.options.exposure_gamma = n[1];
}

void Reader::do_quantize(const Statement& s) {
    std::size_t i = 0;
    std::string type = take_string(s, i, "quantize type");
    auto n = take_numbers(s, i, 4);
    no_more_args(s, i);
    const std::string key = lower(type);
    if (key != "rgba" && key != "rgb" && key != "z")
        fail(s, "unknown quantize type " + sss::quoted(type) + " (rgba, rgb or z)");
    if (!(n[0] >= 0.0) || !(n[1] <= n[2]) || !(n[3] >= 0.0))
        fail(s, "need one >= 0, min <= max and ditheramplitude >= 0, got " + fmt(n[0]) +
                    " " + fmt(n[1]) + " " + fmt(n[2]) + " " + fmt(n[3]));
    if (!option_allowed(s)) return;
    // Depth is always written as float: Quantize "z" has nothing to change.
    if (key == "z") return;
    QuantizeSpec q;
    q.one = n[0];
    q.min = n[1];
    q.max = n[2];
    q.dither = n[3];
    m_scene.options.quantize = q;
}

void Reader::do_display(const Statement& s) {
    std::size_t i = 0;
    DisplaySpec d;
    d.name = take_string(s, i, "display name");
    d.type = take_string(s, i, "display type");
    d.mode = take_string(s, i, "display mode");
    d.params = take_params(s, i, true);
    if (!d.name.empty() && d.name[0] == '+') {
        d.additional = true;
        d.name.erase(0, 1);
    }
    if (d.name.empty()) fail(s, "empty display name");
    d.where = where(s);
    if (!option_allowed(s)) return;
    // A primary display replaces every earlier display.
    if (!d.additional) m_scene.options.displays.clear();
    m_scene.options.displays.push_back(std::move(d));
}

void Reader::do_display_channel(const Statement& s) {
    std::size_t i = 0;
    std::string text = take_string(s, i, "channel declaration");
    take_params(s, i, true); // per-channel filter settings: not used
    Decl decl;
    std::string name, type_text;
    std::string err = parse_decl(text, true, decl, &name, &type_text);
    if (!err.empty()) fail(s, err);
    if (!option_allowed(s)) return;
    auto& chans = m_scene.options.display_channels;
    auto it = std::find_if(chans.begin(), chans.end(),
                           [&](const auto& c) { return c.first == name; });
    if (it != chans.end())
        it->second = type_text;
    else
        chans.emplace_back(name, type_text);
    m_decls[name] = decl;
}

void Reader::do_imager(const Statement& s) {
    std::size_t i = 0;
    std::string name = take_string(s, i, "shader name");
    ParamList params = take_params(s, i, true, true);
    if (!option_allowed(s)) return;
    // Imager "null" (or "") turns the imager off, as RiImager(RI_NULL).
    if (name.empty() || name == "null")
        m_scene.options.imager.reset();
    else
        m_scene.options.imager = make_shader(s, name, std::move(params));
}

void Reader::do_hider(const Statement& s) {
    std::size_t i = 0;
    std::string name = take_string(s, i, "hider name");
    take_params(s, i, true);
    if (option_allowed(s)) m_scene.options.hider = name;
}

void Reader::do_option(const Statement& s) {
    std::size_t i = 0;
    std::string group = take_string(s, i, "option name");
    ParamList params = take_params(s, i, true);
    if (group == "searchpath") set_search_paths(s, params);
    ParamList& dst = m_scene.options.groups[group];
    for (Param& p : params.items) dst.set(std::move(p));
}

void Reader::set_search_paths(const Statement& s, const ParamList& params) {
    for (const Param& p : params.items) {
        if (p.type != ParamType::String || p.strings.size() != 1)
            fail(s, "searchpath " + sss::quoted(p.name) + " needs one string");
        const std::vector<std::string> previous = search_path(m_scene, p.name);
        std::vector<std::string> path;
        const std::string& text = p.strings[0];
        std::size_t start = 0;
        while (start <= text.size()) {
            std::size_t end = text.find(':', start);
            if (end == std::string::npos) end = text.size();
            const std::string entry = text.substr(start, end - start);
            if (entry == "&")
                path.insert(path.end(), previous.begin(), previous.end());
            else if (!entry.empty())
                path.push_back(entry);
            start = end + 1;
        }
        m_scene.options.search_paths[p.name] = std::move(path);
    }
}

void Reader::do_color_samples(const Statement& s) {
    std::size_t i = 0;
    auto a = take_float_array(s, i, "nRGB matrix");
    auto b = take_float_array(s, i, "RGBn matrix");
    no_more_args(s, i);
    if (a.size() != 9 || b.size() != 9) fail(s, "only 3 color samples are supported");
}

void Reader::do_declare(const Statement& s) {
    std::size_t i = 0;
    std::string name = take_string(s, i, "name");
    std::string text = take_string(s, i, "declaration");
    no_more_args(s, i);
    if (name.empty() || name.find_first_of(" \t\n[]") != std::string::npos)
        fail(s, "bad parameter name " + sss::quoted(name));
    Decl decl;
    std::string err = parse_decl(text, false, decl, nullptr);
    if (!err.empty()) fail(s, err);
    m_decls[name] = decl;
}

} // namespace sss::rib
