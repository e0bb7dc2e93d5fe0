// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file turntable.cpp
/// Turntables of `ptview -serve`: the frames of an orbit drawn with ptview's
/// own renderer (each frame is the picture `ptview -orbit AZ EL` makes of
/// the same files), and a video through ffmpeg when it is there.

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>

#include <glm/common.hpp>
#include <sys/stat.h>

#include "serve_internal.h"
#include "sss/serve/view_session.h"
#include "sss/util/atomic_output.h"
#include "sss/util/messages.h"
#include "sss/util/subprocess.h"
#include "sss/view/point_view.h"

namespace sss {

namespace {

constexpr int kMaxFrames = 3600;
constexpr int kFramesPerSecond = 24;

std::string frame_name(const std::string& name, int frame) {
    char buf[16];
    std::snprintf(buf, sizeof buf, ".%04d.png", frame);
    return name + buf;
}

/// Makes the turntable's folder; UsageError when it exists and may not be
/// replaced, IoError when it cannot be made.
void make_folder(const std::string& folder, bool overwrite) {
    struct stat st {};
    if (::stat(folder.c_str(), &st) == 0) {
        if (!S_ISDIR(st.st_mode))
            throw UsageError(quoted(folder) + " exists and is not a folder");
        if (!overwrite)
            throw UsageError(quoted(folder) + " exists; export with overwrite to replace "
                                              "its pictures");
        return;
    }
    if (::mkdir(folder.c_str(), 0777) != 0)
        throw IoError(folder,
                      std::string("cannot make the folder: ") + std::strerror(errno),
                      errno);
}

/// Encodes the frames into `video` (atomically) with ffmpeg.
void encode_video(const std::string& ffmpeg, const std::string& folder,
                  const std::string& name, const std::string& format,
                  const std::string& video) {
    AtomicOutput out(video);
    std::vector<std::string> argv = {
        ffmpeg, "-nostdin", "-loglevel", "error", "-y", "-framerate",
        std::to_string(kFramesPerSecond), "-i", folder + "/" + name + ".%04d.png",
        // Even sizes, as yuv420p needs.
        "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-pix_fmt", "yuv420p"};
    if (format == "webm")
        argv.insert(argv.end(),
                    {"-c:v", "libvpx-vp9", "-b:v", "0", "-crf", "32", "-f", "webm"});
    else
        argv.insert(argv.end(), {"-c:v", "libx264", "-crf", "18", "-f", "mp4"});
    argv.push_back(out.temp_path());
    FilterLimits limits;
    limits.timeout_seconds = 600.0;
    run_filter(argv, "", -1, limits, "ffmpeg");
    out.commit();
}

} // namespace

TurntableResult ViewSession::turntable(const TurntableRequest& r) {
    if (!is_plain_file_name(r.name))
        throw UsageError(quoted(r.name) +
                         " is not a turntable name: a plain file name (letters, digits, "
                         "._-+@)");
    if (r.frames < 1 || r.frames > kMaxFrames)
        throw UsageError("frames: " + std::to_string(r.frames) + " is out of range [1, " +
                         std::to_string(kMaxFrames) + "]");
    if (r.width < 1 || r.height < 1 || r.width > 4096 || r.height > 4096)
        throw UsageError("the frame size must lie in [1, 4096]");
    if (!(r.elevation >= -90.0 && r.elevation <= 90.0) ||
        !(r.fov > 0.0 && r.fov < 170.0) || r.up_axis < 0 || r.up_axis > 2 ||
        !std::isfinite(r.start_azimuth) || !(r.radius_scale > 0.0f) ||
        !std::isfinite(r.radius_scale))
        throw UsageError(
            "elevation in [-90, 90], fov in (0, 170), up 0..2, radius scale > 0");
    if (r.video != "mp4" && r.video != "webm" && r.video != "none")
        throw UsageError("video: " + quoted(r.video) + " is not mp4, webm or none");
    if (r.tiles.empty()) throw UsageError("a turntable needs at least one tile");

    // The tiles' clouds (each once) and the channels listed: ptview's rule,
    // each cloud shows each listed channel it has.
    std::vector<std::shared_ptr<const PointCloud>> kept;
    std::vector<LabelledCloud> clouds;
    std::vector<std::string> sources;
    PointViewOptions view;
    view.false_color = r.false_color;
    view.radius_scale = r.radius_scale;
    bool default_channels = false;
    for (const TurntableRequest::Tile& t : r.tiles) {
        const ViewSourceId id = ViewSourceId::parse(t.source);
        if (std::find(sources.begin(), sources.end(), id.text()) == sources.end()) {
            kept.push_back(source_cloud(id));
            sources.push_back(id.text());
            std::string label = input_path(id.input);
            if (id.kind == ViewSourceId::Kind::Live) label += " (live diffusion)";
            if (id.kind == ViewSourceId::Kind::BrickLevel)
                label += " depth " + std::to_string(id.depth);
            clouds.push_back({kept.back().get(), label});
        }
        if (t.channel.empty()) {
            default_channels = true;
            continue;
        }
        ViewChannel c = parse_view_channel(t.channel);
        bool listed = false;
        for (const ViewChannel& v : view.channels)
            listed = listed || (v.name == c.name && v.luminance == c.luminance);
        if (!listed) view.channels.push_back(c);
    }
    if (default_channels) view.channels.clear();
    Bounds3 box;
    bool any = false;
    for (const LabelledCloud& c : clouds) {
        if (c.cloud->size() == 0) continue;
        const Bounds3 b = c.cloud->bounds();
        box.lo = any ? glm::min(box.lo, b.lo) : b.lo;
        box.hi = any ? glm::max(box.hi, b.hi) : b.hi;
        any = true;
    }

    TurntableResult result;
    const std::size_t first_input = ViewSourceId::parse(r.tiles.front().source).input;
    const std::string base = save_folder(first_input);
    result.folder = base == "." ? r.name : base + "/" + r.name;
    make_folder(result.folder, r.overwrite);
    view.exposure = r.exposure;
    for (int f = 0; f < r.frames; ++f) {
        const double azimuth = r.start_azimuth + 360.0 * double(f) / double(r.frames);
        const ViewCamera camera =
            orbit_camera(box, azimuth, r.elevation, r.up_axis, r.fov, r.width, r.height);
        const PointViewImage image = render_point_view(clouds, camera, view);
        // One exposure for every frame: the first frame's automatic one.
        if (!view.exposure) view.exposure = image.exposure;
        result.frames.push_back(frame_name(r.name, f + 1));
        write_point_view_image(image, result.folder + "/" + result.frames.back(),
                               m_options.software);
    }
    result.exposure = *view.exposure;
    if (r.video == "none") {
        result.video_note = "no video asked for";
    } else if (m_options.ffmpeg.empty() || find_program(m_options.ffmpeg).empty()) {
        result.video_note = "no ffmpeg on this machine: the frames only";
    } else {
        const std::string video = r.name + "." + r.video;
        encode_video(find_program(m_options.ffmpeg), result.folder, r.name, r.video,
                     result.folder + "/" + video);
        result.video = video;
    }
    return result;
}

} // namespace sss
