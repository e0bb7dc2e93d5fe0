// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file main.cpp
/// brickinfo: what is in a brick map (.bkm), pictures of it, and lookups
/// over a point cloud to measure its error:
///   brickinfo [options] file.bkm
///   brickinfo file.vdb
/// Option parsing around sss::describe_brick_map, write_brick_map_picture
/// and lookup_brick_map_cloud (sss::describe_vdb_file for OpenVDB files).

#include <cctype>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "sss/brick/brickmap.h"
#include "sss/brick/brickmap_tools.h"
#include "sss/cli/tool.h"
#include "sss/cloud/point_cloud_io.h"
#include "sss/util/error.h"
#include "sss/util/frame_pattern.h"
#include "sss/util/job_files.h"
#include "sss/util/limits.h"
#include "sss/util/messages.h"
#include "sss/vdb/vdb.h"

namespace {

const char* const kTool = "brickinfo";

const char* const kUsage = R"(usage: brickinfo [options] file.bkm
       brickinfo [-info 0|1] [-verify 0|1] file.vdb

Prints the map's format version, channels, bounding box and root cube, build
settings, provenance and, per level, the bricks and samples with data, after
checking the whole file (checksums, masks, values). See docs/brickinfo.md.
For an OpenVDB file (brickmake ... out.vdb, or any other): its metadata and
grids (type, active voxels, voxel size, box, metadata), after reading every
grid (-verify 0: the descriptions only).

options:
  -info 0|1                print the report (default 1)
  -verify 0|1              1 (default): read and check every brick first; 0:
                           check the header and tables only (bricks are still
                           checked when a picture or lookup reads them)
  -picture out.png         write a PNG picture of the map:
    -level D|all           the samples of depth D, seen down an axis; per
                           pixel the front-most sample; all (default): every
                           depth, each pixel showing the finest data there
    -axis x|y|z|-x|-y|-z   the side the viewer is on (default z: from +z)
    -slice x|y|z VALUE     instead: lookups on the plane x|y|z = VALUE
    -channel NAME          the channel shown (default: the map's first)
    -tree T|all            one octree, 0 (no normal) or 1..6 (+x -x +y -y +z
                           -z), or all of them (default all)
    -size PIXELS           the picture's longer side, 16..4096 (default 512)
  -lookup in.ptc out.ptc   evaluate the map at every point of a cloud (with
                           its normals) and write P, N, radius and the map's
                           channels to out.ptc (.ptc or .ply)
    -filterradius R        lookup filter radius (default: each point's radius
                           for -lookup, 0 = the finest data for -slice)
    -filterscale S         -lookup: multiplies the point radius (default 1)
    -compare 0|1           also print the RMS and largest difference to the
                           input's channels of the same name (default 0)
    -compress 0|1, -ptcversion 0|1|2   .ptc output options
  -frame N                 frame number: expands %04d, #### and $F4 in file names
  -threads N               worker threads, 0 = all usable cores (default 0)
  -progress 0|1|2          ALF_PROGRESS lines during -lookup
  -check                   check the command line only, reading and writing
                           no file: exit 0 if it would run, 2 if not
  -h, --help               this help
  --version                version information

Exit codes: 0 ok, 1 unreadable or corrupt map or cloud, failed output, 2 bad
command line.
)";

int axis_index(const std::string& opt, const std::string& word) {
    if (word == "x") return 0;
    if (word == "y") return 1;
    if (word == "z") return 2;
    throw sss::UsageError("option -" + opt + ": '" + word + "' is not x, y or z");
}

bool ends_with_png(const std::string& path) {
    if (path.size() < 4) return false;
    std::string ext = path.substr(path.size() - 4);
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    return ext == ".png";
}

/// What the command line asks for.
struct Request {
    std::string map_path;
    bool info = true;
    bool verify = true;
    std::string picture_path; ///< empty: no picture
    sss::BrickMapPictureOptions picture;
    bool have_slice = false;
    std::string lookup_in, lookup_out; ///< empty: no lookup
    sss::BrickMapCloudLookupOptions lookup;
    sss::PointCloudWriteOptions wopt;
    sss::RunOptions running;
};

/// Parses and checks the command line; nullopt after --help or --version.
std::optional<Request> parse_request(const std::vector<std::string>& argv) {
    sss::ArgScanner args(argv);
    Request r;
    std::vector<std::string> files;
    bool have_level = false, have_axis = false;
    bool picture_option = false; // an option that only makes sense with -picture
    std::optional<float> filter_radius;
    bool have_filterscale = false, have_compare = false;
    std::string o;
    while (args.next_option(o, files)) {
        if (sss::standard_option(kTool, o, kUsage)) {
            return std::nullopt;
        } else if (o == "info") {
            r.info = args.integer(o, 0, 1) != 0;
        } else if (o == "verify") {
            r.verify = args.integer(o, 0, 1) != 0;
        } else if (o == "picture") {
            r.picture_path = args.value(o);
        } else if (o == "level") {
            if (args.peek() == "all") {
                args.value(o);
                r.picture.level = -1;
            } else {
                r.picture.level = args.integer(o, 0, 30);
            }
            have_level = picture_option = true;
        } else if (o == "axis") {
            // "-z" is a value here, not an option.
            if (args.done()) throw sss::UsageError("option -axis needs a value");
            const std::string word = args.positional();
            const bool signed_word =
                word.size() == 2 && (word[0] == '-' || word[0] == '+');
            r.picture.view_from_negative = signed_word && word[0] == '-';
            const std::string a = signed_word ? word.substr(1) : word;
            if (a != "x" && a != "y" && a != "z")
                throw sss::UsageError("option -axis: '" + word +
                                      "' is not x, y, z, -x, -y or -z");
            r.picture.axis = axis_index(o, a);
            have_axis = picture_option = true;
        } else if (o == "slice") {
            r.picture.mode = sss::BrickMapPictureMode::Slice;
            r.picture.axis = axis_index(o, args.value(o));
            r.picture.slice = args.number(o);
            r.have_slice = picture_option = true;
        } else if (o == "channel") {
            r.picture.channel = args.value(o);
            picture_option = true;
        } else if (o == "tree") {
            if (args.peek() == "all") {
                args.value(o);
                r.picture.tree = -1;
            } else {
                r.picture.tree = args.integer(o, 0, 6);
            }
            picture_option = true;
        } else if (o == "size") {
            r.picture.size = args.integer(o, 16, 4096);
            picture_option = true;
        } else if (o == "lookup") {
            r.lookup_in = args.value(o);
            r.lookup_out = args.value(o);
        } else if (o == "filterradius") {
            filter_radius = float(args.non_negative(o));
        } else if (o == "filterscale") {
            r.lookup.filter_scale = float(args.positive(o));
            have_filterscale = true;
        } else if (o == "compare") {
            r.lookup.compare = args.integer(o, 0, 1) != 0;
            have_compare = true;
        } else if (sss::write_option(args, o, r.wopt)) {
            continue;
        } else if (sss::run_option(args, o, r.running)) {
            continue;
        } else {
            throw sss::unknown_option(o, kUsage);
        }
    }
    if (files.size() != 1)
        throw sss::UsageError(files.empty()
                                  ? "no brick map given (usage: brickinfo file.bkm)"
                                  : "more than one brick map given");
    if (picture_option && r.picture_path.empty())
        throw sss::UsageError(
            "-level, -axis, -slice, -channel, -tree and -size need -picture");
    if (have_level && r.have_slice)
        throw sss::UsageError("-level and -slice exclude each other");
    if (have_axis && r.have_slice)
        throw sss::UsageError("-axis is for -level pictures; -slice names its own axis");
    if ((have_filterscale || have_compare) && r.lookup_in.empty())
        throw sss::UsageError("-filterscale and -compare need -lookup");
    if (filter_radius && r.lookup_in.empty() && !r.have_slice)
        throw sss::UsageError("-filterradius needs -lookup or -slice");
    if (!r.picture_path.empty() && !ends_with_png(r.picture_path) &&
        !sss::writes_into_existing(r.picture_path))
        throw sss::UsageError("option -picture: '" + r.picture_path +
                              "' does not end in .png (pictures are PNG files)");

    r.map_path = sss::expand_frame_pattern(files[0], r.running.frame, "brick map");
    if (!r.picture_path.empty())
        r.picture_path =
            sss::expand_frame_pattern(r.picture_path, r.running.frame, "option -picture");
    if (!r.lookup_in.empty()) {
        r.lookup_in =
            sss::expand_frame_pattern(r.lookup_in, r.running.frame, "option -lookup");
        r.lookup_out =
            sss::expand_frame_pattern(r.lookup_out, r.running.frame, "option -lookup");
        if (!sss::has_extension_in(r.lookup_out, sss::point_cloud_extensions()) &&
            !sss::writes_into_existing(r.lookup_out))
            throw sss::UsageError(
                "option -lookup: " +
                sss::unknown_extension_text(r.lookup_out, "a point cloud file",
                                            sss::point_cloud_extensions()));
    }
    if (filter_radius) {
        r.lookup.filter_radius = *filter_radius;
        r.picture.filter_radius = *filter_radius;
    }
    return r;
}

/// What to print once every output is in place: stdout lines, warnings.
struct Messages {
    std::string out;
    std::vector<std::string> warnings;
};

/// printf into a string.
template <typename... Args>
void append(std::string& text, const char* format, Args... args) {
    char buf[4096];
    std::snprintf(buf, sizeof buf, format, args...);
    text += buf;
}

/// -picture: draws the map and says what was drawn.
void write_picture(const sss::BrickMap& map, const Request& request, Messages& m) {
    const sss::BrickMapPictureReport r =
        sss::write_brick_map_picture(map, request.picture, request.picture_path);
    append(m.out, "brickinfo: wrote %s: %d x %d, %s; %zu pixels with data",
           request.picture_path.c_str(), r.width, r.height, r.description.c_str(),
           r.pixels_with_data);
    if (request.picture.mode == sss::BrickMapPictureMode::Level)
        append(m.out, ", %zu samples drawn", r.samples_drawn);
    m.out += "\n";
    if (r.pixels_with_data == 0)
        m.warnings.push_back(
            request.picture_path + ": no data in the picture (" +
            (request.have_slice ? "does the plane cross the map? " : "") +
            "does the tree hold data?)");
}

/// -lookup: evaluates the map at every point of a cloud, writes the result and
/// reports the differences to the input.
void lookup_cloud(const sss::BrickMap& map, Request& r, sss::Job& job, Messages& m) {
    const sss::PointCloud cloud = sss::read_point_cloud(r.lookup_in);
    r.lookup.progress = job.progress();
    const sss::Stopwatch watch;
    sss::BrickMapCloudLookupReport report;
    const sss::PointCloud out =
        sss::lookup_brick_map_cloud(map, cloud, r.lookup, &report);
    const double seconds = watch.seconds();
    sss::write_point_cloud(out, r.lookup_out, r.wopt);
    char radius[64];
    if (r.lookup.filter_radius >= 0.0f)
        std::snprintf(radius, sizeof radius, "%g", double(r.lookup.filter_radius));
    else
        std::snprintf(radius, sizeof radius, "point radius x %g",
                      double(r.lookup.filter_scale));
    append(m.out,
           "brickinfo: lookup %s -> %s: %zu points, %zu without data, filter radius "
           "%s, %.3f s\n",
           r.lookup_in.c_str(), r.lookup_out.c_str(), report.points, report.misses,
           radius, seconds);
    for (const sss::ChannelDifference& d : report.differences)
        append(m.out,
               "brickinfo: compare %s: rms %.6g max %.6g (input rms %.6g, relative "
               "rms %.4g%%)\n",
               d.name.c_str(), d.rms, d.max_abs, d.reference_rms,
               d.reference_rms > 0.0 ? 100.0 * d.rms / d.reference_rms : 0.0);
    for (const std::string& name : report.not_compared)
        append(m.out, "brickinfo: compare %s: not in %s (or another type)\n",
               name.c_str(), r.lookup_in.c_str());
    if (report.misses > 0)
        m.warnings.push_back(r.lookup_in + ": " + std::to_string(report.misses) +
                             " points have no map data around them (written as 0)");
}

/// brickinfo file.vdb: the report of an OpenVDB file, after reading every
/// grid unless -verify 0.
int describe_vdb(const Request& request) {
    if (!request.picture_path.empty() || !request.lookup_in.empty())
        throw sss::UsageError(request.map_path +
                              " is an OpenVDB file: brickinfo only describes it "
                              "(-picture and -lookup read .bkm brick maps)");
    const sss::Job job(kTool, request.running);
    std::size_t voxels = 0, grids = 0;
    if (request.verify) {
        const sss::ScopedStage stage("reading " + request.map_path);
        for (const sss::VdbGrid& g : sss::read_vdb_grids(request.map_path)) {
            voxels += g.coords.size();
            ++grids;
        }
    }
    std::string text = sss::describe_vdb_file(request.map_path);
    if (request.verify)
        append(text, "checked: %zu float and vec3s grids read, %zu voxels\n", grids,
               voxels);
    else
        text += "checked: grid descriptions only (-verify 0)\n";
    if (request.info) {
        std::fputs(text.c_str(), stdout);
        sss::flush_standard_output();
    }
    return 0;
}

int run(const std::vector<std::string>& argv) {
    std::optional<Request> request = parse_request(argv);
    if (!request) return 0;
    if (sss::is_vdb_path(request->map_path)) return describe_vdb(*request);
    // No output replaces the map, the lookup's cloud or the other output.
    sss::JobFiles files;
    files.input(request->map_path, "the brick map \"" + request->map_path + "\"");
    if (!request->lookup_in.empty())
        files.input(request->lookup_in,
                    "the -lookup input \"" + request->lookup_in + "\"");
    if (!request->picture_path.empty())
        files.output(request->picture_path,
                     "option -picture \"" + request->picture_path + "\"");
    if (!request->lookup_in.empty())
        files.output(request->lookup_out,
                     "the -lookup output \"" + request->lookup_out + "\"");
    if (sss::check_only()) return 0;
    if (!request->picture_path.empty()) sss::check_output_target(request->picture_path);
    if (!request->lookup_in.empty()) sss::check_output_target(request->lookup_out);
    sss::Job job(kTool, request->running);
    const sss::BrickMap map(request->map_path);
    // Everything is checked before anything is reported: a corrupt map gives
    // one ERROR line, not a report followed by one.
    std::optional<std::size_t> verified;
    if (request->verify) {
        const sss::ScopedStage stage("checking " + request->map_path);
        verified = map.verify();
    }
    if (request->info) {
        std::fputs(sss::describe_brick_map(request->map_path, map, verified).c_str(),
                   stdout);
        sss::flush_standard_output();
    }
    // The picture and the lookup's cloud are put in place together, or neither.
    Messages messages;
    sss::OutputSet outputs;
    if (!request->picture_path.empty()) write_picture(map, *request, messages);
    if (!request->lookup_in.empty()) lookup_cloud(map, *request, job, messages);
    // The report goes out before the outputs are put in place: a report that
    // cannot be written fails the job with its outputs unchanged.
    std::fputs(messages.out.c_str(), stdout);
    sss::flush_standard_output();
    outputs.commit();
    for (const std::string& w : messages.warnings) sss::warn(kTool, w);
    return 0;
}

} // namespace

int main(int argc, char** argv) {
    return sss::run_tool(kTool, argc, argv, run);
}
