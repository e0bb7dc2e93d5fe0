// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file main.cpp
/// ptview: pictures of point clouds (PRMan's ptviewer need): a channel of
/// each cloud splatted as discs through the cloud's camera or an orbit
/// camera, several clouds or channels as a contact sheet, PNG or EXR:
///   ptview [options] cloud.ptc... out.png
///   ptview -serve [options] cloud.ptc|map.bkm...
/// Option parsing around sss::render_point_view and write_point_view_image,
/// or, with -serve, around the interactive view's server (sss/serve).

#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <fcntl.h>
#include <unistd.h>

#include "sss/cli/tool.h"
#include "sss/cloud/point_cloud_io.h"
#include "sss/serve/serve.h"
#include "sss/util/error.h"
#include "sss/util/frame_pattern.h"
#include "sss/util/isa.h"
#include "sss/util/job_files.h"
#include "sss/util/limits.h"
#include "sss/util/messages.h"
#include "sss/view/point_view.h"

namespace {

const char* const kTool = "ptview";

const char* const kUsage = R"(usage: ptview [options] cloud.ptc... out.png|out.exr|-
       ptview [options] -o out.png|out.exr|- cloud.ptc...
       ptview -serve [-port N] [-bind ADDR] [options] cloud.ptc|map.bkm...

Draws point clouds (.ptc or .ply): each point a disc of its radius facing
its normal, the nearest one in front, coloured by a channel. Several clouds
or channels make a contact sheet, one tile per cloud and channel, with one
camera and one exposure. With -serve, an interactive view of the clouds
and brick maps in a web browser, with the live diffusion of a baked cloud
(docs/ptview.md, "Interactive view").

options:
  -o FILE                the picture: .png (8-bit sRGB) or .exr (float,
                         linear); default: the last file argument; - or
                         /dev/stdout: a PNG on standard output (the report
                         then goes to standard error)
  -channel LIST          comma-separated channels shown, each NAME or
                         NAME:lum (a colour's luminance); N = the normals,
                         radius = the radii (default: each cloud's first
                         colour channel). Each cloud shows those it has.
  -camera auto|file|orbit  file: the camera the first cloud was baked with
                         (its world2eye and world2ndc); orbit: around the
                         clouds; auto (default): file when it has one
  -orbit AZ EL           orbit camera at azimuth AZ and elevation EL degrees
                         (default 30 20; implies -camera orbit)
  -up x|y|z              the orbit's up axis (default y)
  -fov DEGREES           the orbit's field of view, over the shorter side
                         (default 30)
  -res W H               size of each tile (default: 512 on the longer side,
                         the file camera's aspect, square for orbits)
  -exposure STOPS|auto|tile  multiply values by 2^STOPS; auto (default): the
                         99.5th percentile of the drawn values becomes 1, one
                         exposure for the sheet; tile: chosen for each tile
  -falsecolor 0|1        1 (default): negative values (blockers) in blue
  -background R G B      linear colour where no point is (default 0.05 0.05 0.05)
  -radiusscale S         multiply every point's radius (default 1)
  -columns N             contact sheet columns (default: one row up to 4 tiles)
  -gap N                 pixels between tiles (default 2)
  -frame N               frame number: expands %04d, #### and $F4 in file names
  -threads N             worker threads, 0 = all usable cores (default 0)
  -progress 0|1|2        ALF_PROGRESS lines, the exposure and per-tile counts
  -check                 check the command line only, reading and writing
                         no file: exit 0 if it would run, 2 if not
interactive view:
  -serve                 serve the page on http://127.0.0.1:PORT/ until
                         stopped (Ctrl-C); the options above set its first view
  -port N                the port (default 0: a free one, printed)
  -bind ADDR             the address listened on (default 127.0.0.1: this
                         machine only; 0.0.0.0: every network)
  -savedir DIR           where Save and turntables write (default: the
                         folder of the input)
  -livepoints N          points of the live diffusion while a slider moves
                         (default 50000; the whole cloud when it is let go)
  -h, --help             this help
  --version              version information

Exit codes: 0 ok, 1 unreadable or corrupt cloud, missing channel, failed
output, 2 bad command line.
)";

enum class CameraChoice { Auto, File, Orbit };

/// What the command line asks for.
struct Request {
    std::vector<std::string> inputs;
    std::string output;
    CameraChoice camera = CameraChoice::Auto;
    double azimuth = 30.0, elevation = 20.0;
    int up = 1;
    double fov = 30.0;
    int width = 0, height = 0; ///< 0: default
    sss::PointViewOptions view;
    sss::RunOptions running;
    bool serve = false;
    sss::ServeOptions server;
    std::string fragment; ///< the page's first view (URL fragment)
};

/// The ptfilter options the live view offers: the material and the profile.
/// Not -blocker (a file named by the page), nor -exact (all pairs: minutes),
/// nor those that rename channels or change the output's layout.
const std::set<std::string> kLiveOptions = {
    "material", "unitlength",          "scattering", "absorption",
    "albedo",   "diffusemeanfreepath", "ior",        "maxsolidangle",
    "profile",  "criterion",           "volume",     "incidence"};

/// The page's option words, parsed by ptfilter's own parser: the command
/// line shown reproduces the result exactly. Errors in the options' words.
sss::SsDiffusionOptions live_diffusion_options(const std::vector<std::string>& words) {
    sss::ArgScanner args(words);
    sss::SsDiffusionOptions options;
    std::vector<std::string> stray;
    std::string o;
    while (args.next_option(o, stray)) {
        if (!kLiveOptions.count(o) || !sss::ssdiffusion_option(args, o, options))
            throw sss::UsageError("option -" + sss::escape_control(o) +
                                  " is not one the live view offers");
    }
    if (!stray.empty())
        throw sss::UsageError("unexpected word " + sss::quoted(stray.front()) +
                              " among the options");
    options.diffusion.isa = sss::resolve_isa(options.diffusion.isa);
    try {
        sss::describe_material(options);
    } catch (const std::exception& e) {
        if (const std::optional<std::string> worded = sss::option_wording(e))
            throw sss::UsageError(*worded);
        throw;
    }
    return options;
}

/// `ptfilter -ssdiffusion WORDS input output`, quoted for a shell.
std::string live_diffusion_command(const std::vector<std::string>& words,
                                   const std::string& input, const std::string& output) {
    std::vector<std::string> args = {"-ssdiffusion"};
    args.insert(args.end(), words.begin(), words.end());
    args.push_back(input);
    args.push_back(output);
    return sss::quoted_command_line("ptfilter", args);
}

/// A number for the page's URL fragment (a float with the digits it has).
std::string fragment_number(double v, int digits = 9) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.*g", digits, v);
    return buf;
}

/// The -serve request: every file argument is an input (clouds and brick
/// maps); the picture's options set the page's first view.
Request serve_request(Request r, const std::vector<std::string>& files,
                      const std::vector<std::string>& sheet_only, bool have_orbit) {
    if (!sheet_only.empty())
        throw sss::UsageError("-" + sheet_only.front() +
                              " is for pictures; -serve shows the files in a browser");
    if (files.empty())
        throw sss::UsageError("no file to show (usage: ptview -serve cloud.ptc)");
    if (have_orbit && r.camera == CameraChoice::File)
        throw sss::UsageError("-orbit and -camera file exclude each other");
    for (const std::string& f : files)
        r.inputs.push_back(sss::expand_frame_pattern(f, r.running.frame, "input"));
    // The first view, in the page's URL fragment (docs/ptview.md).
    std::string& h = r.fragment;
    const auto add = [&h](const std::string& key, const std::string& value) {
        h += (h.empty() ? "#" : "&") + key + "=";
        for (unsigned char c : value) {
            if (std::isalnum(c) || std::strchr("_-.,:", c)) {
                h += char(c);
            } else {
                char buf[4];
                std::snprintf(buf, sizeof buf, "%%%02X", c);
                h += buf;
            }
        }
    };
    if (!r.view.channels.empty()) {
        std::string list;
        for (const sss::ViewChannel& c : r.view.channels) {
            if (!list.empty()) list += ',';
            list += sss::view_channel_text(c);
        }
        add("channel", list);
    }
    if (r.camera != CameraChoice::Auto || have_orbit)
        add("camera", r.camera == CameraChoice::File ? "file" : "orbit");
    if (have_orbit) {
        add("az", fragment_number(r.azimuth));
        add("el", fragment_number(r.elevation));
    }
    add("up", std::string(1, char('x' + r.up)));
    add("fov", fragment_number(r.fov));
    if (r.width > 0) add("res", std::to_string(r.width) + "x" + std::to_string(r.height));
    if (r.view.exposure)
        add("exposure", fragment_number(*r.view.exposure));
    else if (r.view.exposure_per_tile)
        add("exposure", "tile");
    add("falsecolor", r.view.false_color ? "1" : "0");
    add("radiusscale", fragment_number(r.view.radius_scale));
    const glm::vec3& b = r.view.background;
    add("background",
        fragment_number(b.x) + "," + fragment_number(b.y) + "," + fragment_number(b.z));
    return r;
}

/// Parses and checks the command line; nullopt after --help or --version.
std::optional<Request> parse_request(const std::vector<std::string>& argv) {
    sss::ArgScanner args(argv);
    Request r;
    std::vector<std::string> files;
    bool have_orbit = false, have_orbit_option = false;
    std::vector<std::string> sheet_only; // options of pictures, refused with -serve
    std::string o;
    while (args.next_option(o, files)) {
        if (sss::standard_option(kTool, o, kUsage)) {
            return std::nullopt;
        } else if (o == "serve") {
            r.serve = true;
        } else if (o == "port") {
            r.server.port = args.integer(o, 0, 65535);
        } else if (o == "bind") {
            r.server.bind_address = args.value(o);
        } else if (o == "savedir") {
            r.server.save_dir = args.value(o);
        } else if (o == "livepoints") {
            r.server.live_points = std::size_t(args.integer(o, 1, 100000000));
        } else if (o == "o") {
            sheet_only.push_back(o);
            r.output = args.value(o);
        } else if (o == "channel") {
            for (const std::string& spec : sss::split_channel_list(args.value(o), o)) {
                try {
                    r.view.channels.push_back(sss::parse_view_channel(spec));
                } catch (const sss::ValueError& e) {
                    throw sss::UsageError("option -channel: " + std::string(e.what()));
                }
            }
        } else if (o == "camera") {
            const std::string v = args.value(o);
            if (v == "auto")
                r.camera = CameraChoice::Auto;
            else if (v == "file")
                r.camera = CameraChoice::File;
            else if (v == "orbit")
                r.camera = CameraChoice::Orbit;
            else
                throw sss::UsageError("option -camera: '" + v +
                                      "' is not auto, file or orbit");
        } else if (o == "orbit") {
            r.azimuth = args.number(o);
            r.elevation = args.number(o);
            if (r.elevation < -90.0 || r.elevation > 90.0)
                throw sss::UsageError("option -orbit: elevation " +
                                      sss::short_float(r.elevation) +
                                      " is out of range [-90, 90]");
            have_orbit = true;
        } else if (o == "up") {
            const std::string v = args.value(o);
            if (v != "x" && v != "y" && v != "z")
                throw sss::UsageError("option -up: '" + v + "' is not x, y or z");
            r.up = v[0] - 'x';
            have_orbit_option = true;
        } else if (o == "fov") {
            r.fov = args.positive(o);
            if (r.fov >= 170.0)
                throw sss::UsageError("option -fov: must be < 170 (got " +
                                      sss::short_float(r.fov) + ")");
            have_orbit_option = true;
        } else if (o == "res") {
            r.width = args.integer(o, 1, 16384);
            r.height = args.integer(o, 1, 16384);
        } else if (o == "exposure") {
            if (args.peek() == "auto" || args.peek() == "tile") {
                r.view.exposure.reset();
                r.view.exposure_per_tile = args.value(o) == "tile";
                continue;
            }
            r.view.exposure_per_tile = false;
            const double e = args.number(o);
            if (e < -256.0 || e > 256.0)
                throw sss::UsageError("option -exposure: " + sss::short_float(e) +
                                      " is out of range [-256, 256]");
            r.view.exposure = e;
        } else if (o == "falsecolor") {
            r.view.false_color = args.integer(o, 0, 1) != 0;
        } else if (o == "background") {
            const glm::dvec3 b = args.triple(o);
            if (b.x < 0.0 || b.y < 0.0 || b.z < 0.0)
                throw sss::UsageError("option -background: must be >= 0");
            r.view.background = glm::vec3(b);
        } else if (o == "radiusscale") {
            r.view.radius_scale = float(args.positive(o));
        } else if (o == "columns") {
            sheet_only.push_back(o);
            r.view.columns = args.integer(o, 1, 4096);
        } else if (o == "gap") {
            sheet_only.push_back(o);
            r.view.gap = args.integer(o, 0, 256);
        } else if (sss::run_option(args, o, r.running)) {
            continue;
        } else {
            throw sss::unknown_option(o, kUsage);
        }
    }
    if (r.serve) return serve_request(std::move(r), files, sheet_only, have_orbit);
    if (r.output.empty()) {
        if (files.size() < 2)
            throw sss::UsageError(files.empty()
                                      ? "no point cloud given (usage: ptview cloud.ptc "
                                        "out.png)"
                                      : "no output picture given (the last file argument "
                                        "or -o out.png)");
        r.output = files.back();
        files.pop_back();
    }
    if (files.empty()) throw sss::UsageError("no point cloud given");
    if (have_orbit) {
        if (r.camera == CameraChoice::File)
            throw sss::UsageError("-orbit and -camera file exclude each other");
        r.camera = CameraChoice::Orbit;
    }
    if (have_orbit_option && r.camera == CameraChoice::File)
        throw sss::UsageError("-up and -fov are for the orbit camera, not -camera file");
    if (!sss::is_png_path(r.output) && !sss::is_exr_path(r.output) &&
        !sss::writes_into_existing(r.output) && r.output != "-" &&
        !sss::is_standard_output(r.output))
        throw sss::UsageError("'" + r.output +
                              "' does not end in .png or .exr (the picture's format)");
    for (const std::string& f : files)
        r.inputs.push_back(sss::expand_frame_pattern(f, r.running.frame, "point cloud"));
    r.output = sss::expand_frame_pattern(r.output, r.running.frame, "output picture");
    return r;
}

/// Hands standard output to the picture ("-", /dev/stdout, or the file
/// stdout is redirected to): the picture must be the only thing in that
/// stream, so what the tool prints there (its report, ALF_PROGRESS lines)
/// goes to standard error from now on. Returns the name the picture is
/// written to (the original stdout, as /dev/fd/N: a pipe is written into, a
/// file replaced as any output is).
std::string picture_on_standard_output() {
    if (::isatty(STDOUT_FILENO))
        throw sss::UsageError("the picture would go to a terminal (standard output); "
                              "redirect it to a file or a pipe");
    sss::flush_standard_output();
    const int fd = ::fcntl(STDOUT_FILENO, F_DUPFD_CLOEXEC, 3);
    if (fd < 0 || ::dup2(STDERR_FILENO, STDOUT_FILENO) < 0)
        throw sss::IoError("standard output",
                           std::string("cannot hand it to the picture: ") +
                               std::strerror(errno));
    return "/dev/fd/" + std::to_string(fd);
}

/// printf into a string.
template <typename... Args>
void append(std::string& text, const char* format, Args... args) {
    char buf[4096];
    std::snprintf(buf, sizeof buf, format, args...);
    text += buf;
}

/// ptview -serve: reads the inputs (their errors are the readers', before
/// anything is served), then serves the page until the process is stopped.
int serve(Request& r) {
    sss::JobFiles files;
    for (const std::string& in : r.inputs) files.input(in, "the file \"" + in + "\"");
    if (sss::check_only()) return 0;
    sss::Job job(kTool, r.running);
    sss::ServeOptions& o = r.server;
    o.inputs = r.inputs;
    o.parse_diffusion = live_diffusion_options;
    o.diffusion_command = live_diffusion_command;
    o.software = std::string("sss ptview ") + sss::version_string();
    if (job.verbose())
        o.log = [](const std::string& line) {
            std::printf("ptview: %s\n", line.c_str());
            sss::flush_standard_output();
        };
    sss::ViewSession session(o);
    sss::ViewServer server(session);
    if (o.bind_address != "127.0.0.1" && o.bind_address != "localhost" &&
        o.bind_address != "::1")
        sss::warn(kTool, "-bind " + o.bind_address +
                             ": whoever reaches this machine there sees these files and "
                             "can save results next to them");
    std::printf("ptview: serving %zu file%s at %s%s (stop with Ctrl-C)\n",
                r.inputs.size(), r.inputs.size() == 1 ? "" : "s", server.url().c_str(),
                r.fragment.c_str());
    sss::flush_standard_output();
    server.run();
    return 0;
}

int run(const std::vector<std::string>& argv) {
    std::optional<Request> request = parse_request(argv);
    if (!request) return 0;
    Request& r = *request;
    if (r.serve) return serve(r);
    // The file written: the output named, or standard output's file or pipe.
    std::string target = r.output;
    if (r.output == "-" || sss::is_standard_output(r.output)) {
        target = picture_on_standard_output();
        r.output = "standard output";
    }
    sss::JobFiles files;
    for (const std::string& in : r.inputs)
        files.input(in, "the point cloud \"" + in + "\"");
    files.output(target, "the picture \"" + r.output + "\"");
    if (sss::check_only()) return 0;
    sss::check_output_target(target);
    sss::Job job(kTool, r.running);

    std::vector<sss::PointCloud> clouds;
    clouds.reserve(r.inputs.size());
    for (const std::string& in : r.inputs) {
        const sss::ScopedStage stage("reading " + in);
        clouds.push_back(sss::read_point_cloud(in));
    }
    std::vector<sss::LabelledCloud> labelled;
    for (std::size_t i = 0; i < clouds.size(); ++i)
        labelled.push_back({&clouds[i], r.inputs[i]});

    // The camera: the first cloud's own, or an orbit around all of them.
    const bool has_camera = sss::has_file_camera(clouds.front());
    if (r.camera == CameraChoice::File && !has_camera)
        throw sss::ValueError("-camera file: " + r.inputs.front() +
                              " has no camera (its world2ndc is the identity); use "
                              "-camera orbit");
    const bool use_file =
        r.camera == CameraChoice::File || (r.camera == CameraChoice::Auto && has_camera);
    int width = r.width, height = r.height;
    if (width == 0) {
        const double aspect = use_file ? sss::file_camera_aspect(clouds.front()) : 1.0;
        width = aspect >= 1.0 ? 512 : std::max(1, int(std::lround(512.0 * aspect)));
        height = aspect >= 1.0 ? std::max(1, int(std::lround(512.0 / aspect))) : 512;
    }
    sss::ViewCamera camera;
    if (use_file) {
        camera = sss::file_camera(clouds.front(), width, height, r.inputs.front());
    } else {
        bool any = false;
        sss::Bounds3 box;
        for (const sss::PointCloud& c : clouds) {
            if (c.size() == 0) continue;
            const sss::Bounds3 b = c.bounds();
            box.lo = any ? glm::min(box.lo, b.lo) : b.lo;
            box.hi = any ? glm::max(box.hi, b.hi) : b.hi;
            any = true;
        }
        camera =
            sss::orbit_camera(box, r.azimuth, r.elevation, r.up, r.fov, width, height);
    }

    r.view.progress = job.progress();
    const sss::Stopwatch watch;
    const sss::ScopedStage drawing("drawing " + r.output);
    const sss::PointViewImage image = sss::render_point_view(labelled, camera, r.view);
    const double seconds = watch.seconds();

    std::string out;
    append(out, "ptview: wrote %s: %d x %d, %zu tile%s (%d x %d), %s, ", r.output.c_str(),
           image.width, image.height, image.tiles.size(),
           image.tiles.size() == 1 ? "" : "s", camera.width, camera.height,
           camera.description.c_str());
    if (r.view.exposure_per_tile && image.auto_exposure) {
        out += "exposure per tile";
        for (std::size_t t = 0; t < image.tiles.size(); ++t)
            append(out, "%s%.4g", t ? ", " : " ", image.tiles[t].exposure);
        out += " stops (auto: the 99.5th percentile of each tile shown as 1)";
    } else {
        append(out, "exposure %.4g stops", image.exposure);
        if (image.auto_exposure)
            append(out, " (auto: %.6g shown as 1; fix it with -exposure %.4g)",
                   image.exposure_reference, image.exposure);
    }
    out += "\n";
    if (job.verbose()) {
        for (std::size_t t = 0; t < image.tiles.size(); ++t) {
            const sss::PointViewTileInfo& info = image.tiles[t];
            append(out,
                   "ptview: tile %zu: %s %s: %zu of %zu points drawn, %zu pixels, "
                   "exposure %.4g stops\n",
                   t + 1, r.inputs[info.cloud].c_str(),
                   sss::view_channel_text(info.channel).c_str(), info.points_drawn,
                   clouds[info.cloud].size(), info.pixels_covered, info.exposure);
        }
        append(out, "ptview: drawn in %.3f s\n", seconds);
    }
    {
        const sss::ScopedStage stage("writing " + r.output);
        sss::OutputSet outputs;
        sss::write_point_view_image(image, target,
                                    std::string("sss ptview ") + sss::version_string());
        // The report goes out before the picture is put in place: a report that
        // cannot be written fails the job with the picture unchanged.
        std::fputs(out.c_str(), stdout);
        sss::flush_standard_output();
        outputs.commit();
    }
    for (std::size_t t = 0; t < image.tiles.size(); ++t)
        if (image.tiles[t].pixels_covered == 0)
            sss::warn(kTool, r.inputs[image.tiles[t].cloud] + " " +
                                 sss::view_channel_text(image.tiles[t].channel) +
                                 ": no point in view");
    return 0;
}

} // namespace

int main(int argc, char** argv) {
    return sss::run_tool(kTool, argc, argv, run);
}
