// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file main.cpp
/// envdome: an HDR lat-long light probe -> a RIB archive of distant lights
/// by Debevec's median cut (sss/light/light_dome.h), or (-sky) a procedural
/// sky probe written as OpenEXR. docs/lighting.md.

#include <cstdint>
#include <cstdio>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "sss/cli/tool.h"
#include "sss/image/image_check.h"
#include "sss/light/light_dome.h"
#include "sss/render/image_io.h"
#include "sss/util/error.h"
#include "sss/util/job_files.h"
#include "sss/util/limits.h"

namespace {

const char* const kTool = "envdome";

const char* const kUsage = R"(usage: envdome [options] probe.exr out.rib
       envdome -sky W H [-sun elevation azimuth] out.exr

Turns an HDR light probe in lat-long form (.exr, .hdr, .tx made with
maketx --envlatl, ...: any image OpenImageIO reads, twice as wide as high;
cube maps and mirror-ball probes are not supported) into a dome of distant
lights by Debevec's median cut, written as a RIB archive to ReadArchive
inside WorldBegin/WorldEnd. Each light stands for one region of the map: it
comes from the region's energy centroid with lightcolor = the region's
integral of radiance x solid angle / pi, so a white diffuse surface gets
diffuse(N) ~ the map's cosine-weighted integral / pi, what envlight.sl gives
with the same map. Directions follow environment(): top row +y, image
centre +z, a quarter from the left +x.

options:
  -n N                 number of lights, a power of two (default 64)
  -intensity s         scale of every light (default 1)
  -shadows 0|1         1: distantlight_rts lights (ray-traced shadows);
                       0: distantlight (default)
  -rotate deg          rotate the dome about +y (default 0)
  -o file              the output (else the last positional argument)
  -sky W H             write a procedural sky probe (W = 2 H) instead: a
                       blue gradient, a sun disc and a dark ground, OpenEXR
  -sun elev azim       the sky's sun: degrees above the horizon, and about
                       +y from +z towards +x (default 45 30)
  -progress 0|1        1: a summary line and ALF_PROGRESS lines
  -threads N           accepted for uniformity (the cut is serial)
  -check               check the command line only, reading and writing
                       no file: exit 0 if it would run, 2 if not
  -h, --help           this help
  --version            version information

Exit codes: 0 ok, 1 unreadable probe or unwritable output, 2 bad command line.
)";

/// What -sky holds per pixel at its peak: the sky (moved into the image
/// written) and the writer's float copy, 12 bytes each, and room for the
/// OpenEXR writer's buffers.
constexpr uint64_t kSkyBytesPerPixel = 32;
/// What the median cut holds per pixel of a probe besides the image read
/// (which read_image() checks): the RGB copy (12), energy (8), directions (24).
constexpr uint64_t kCutBytesPerPixel = 44;

/// The probe as a float RGB lat-long image (one channel: grey).
sss::LatLongImage load_probe(const std::string& path) {
    if (const std::optional<sss::ImageHeader> h = sss::check_image_file(path))
        sss::check_memory(uint64_t(h->width) * uint64_t(h->height) * kCutBytesPerPixel,
                          "placing lights on the " + std::to_string(h->width) + " x " +
                              std::to_string(h->height) + " probe " + path,
                          "use a smaller probe");
    const sss::Image img = sss::read_image(path);
    if (img.height <= 0 || img.width != 2 * img.height)
        throw sss::FormatError(
            path, "not a lat-long environment map: it is " + std::to_string(img.width) +
                      " x " + std::to_string(img.height) +
                      ", a lat-long map is twice as wide as high "
                      "(cube maps and light-probe spheres are not supported)");
    int r = img.channel_index("R"), g = img.channel_index("G"),
        b = img.channel_index("B");
    if (r < 0 || g < 0 || b < 0) {
        if (img.channel_count() >= 3) {
            r = 0;
            g = 1;
            b = 2;
        } else if (img.channel_count() >= 1) {
            r = g = b = 0;
        } else {
            throw sss::FormatError(path, "no channels");
        }
    }
    sss::LatLongImage out(img.width, img.height);
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            const float* p = img.pixel(x, y);
            float* q = out.pixel(x, y);
            q[0] = p[r];
            q[1] = p[g];
            q[2] = p[b];
        }
    return out;
}

void write_text(const std::string& path, const std::string& text) {
    sss::AtomicOutput out(path);
    {
        std::ofstream f(out.temp_path(), std::ios::binary);
        f << text;
        f.flush();
        if (!f) throw sss::IoError(path, "cannot write");
    }
    out.commit();
}

int run(const std::vector<std::string>& args) {
    int count = 64;
    sss::DomeRibOptions rib;
    std::string output;
    bool sky = false;
    int sky_w = 0, sky_h = 0;
    sss::SkyOptions sky_opt;
    sss::RunOptions running;
    std::vector<std::string> files;

    sss::ArgScanner scan(args);
    std::string opt;
    while (scan.next_option(opt, files)) {
        if (sss::standard_option(kTool, opt, kUsage)) {
            return 0;
        } else if (opt == "n") {
            count = scan.integer(opt, 1, 65536);
            if ((count & (count - 1)) != 0)
                throw sss::UsageError("-n must be a power of two, not " +
                                      std::to_string(count));
        } else if (opt == "intensity") {
            rib.intensity = scan.non_negative(opt);
        } else if (opt == "shadows") {
            rib.shadows = scan.integer(opt, 0, 1) != 0;
        } else if (opt == "rotate") {
            rib.rotate_degrees = scan.number(opt);
        } else if (opt == "o") {
            output = scan.value(opt);
        } else if (opt == "sky") {
            sky = true;
            sky_w = scan.integer(opt, 2, 65536);
            sky_h = scan.integer(opt, 1, 32768);
            if (sky_w != 2 * sky_h)
                throw sss::UsageError(
                    "-sky W H: W must be twice H (a lat-long map), not " +
                    std::to_string(sky_w) + " x " + std::to_string(sky_h));
        } else if (opt == "sun") {
            sky_opt.sun_elevation = scan.number(opt);
            sky_opt.sun_azimuth = scan.number(opt);
            if (sky_opt.sun_elevation < -90.0 || sky_opt.sun_elevation > 90.0)
                throw sss::UsageError("-sun: the elevation must be in [-90, 90] degrees");
        } else if (sss::run_option(scan, opt, running)) {
            continue;
        } else {
            throw sss::unknown_option(opt, kUsage);
        }
    }
    if (output.empty() && !files.empty()) {
        output = files.back();
        files.pop_back();
    }
    if (output.empty()) throw sss::UsageError("no output file given");
    // The sky is OpenEXR whatever the name: the name must say so.
    if (sky && !sss::has_extension_in(output, {".exr"}) &&
        !sss::writes_into_existing(output))
        throw sss::UsageError(
            "-sky writes OpenEXR: " +
            sss::unknown_extension_text(output, "an OpenEXR file", {".exr"}));
    if (sky && !files.empty())
        throw sss::UsageError("-sky takes no probe, only an output file");
    if (!sky && files.empty()) throw sss::UsageError("no probe file given");
    if (!sky && files.size() > 1) throw sss::UsageError("more than one probe given");
    // The dome never replaces its probe.
    sss::JobFiles job_files;
    if (!sky)
        for (const std::string& f : files) job_files.input(f, "the probe \"" + f + "\"");
    job_files.output(output, "the output \"" + output + "\"");
    if (sss::check_only()) return 0;
    sss::check_output_target(output);
    sss::Job job(kTool, running);

    if (sky) {
        sss::ScopedStage stage("making the sky " + output);
        // The sky, the image it moves into and the float copy the writer
        // makes: 12 bytes a pixel each.
        sss::check_memory(uint64_t(sky_w) * uint64_t(sky_h) * kSkyBytesPerPixel,
                          "a " + std::to_string(sky_w) + " x " + std::to_string(sky_h) +
                              " sky",
                          "make a smaller sky (-sky W H)");
        sss::LatLongImage img = sss::sky_probe(sky_w, sky_h, sky_opt);
        const glm::dvec3 integral = sss::latlong_integral(img);
        job.progress()->update(1, 2);
        sss::Image out(sky_w, sky_h, {"R", "G", "B"});
        out.pixels = std::move(img.rgb);
        sss::DisplayTarget target;
        target.path = output;
        target.format = "openexr";
        target.channels = {"R", "G", "B"};
        target.names = {"R", "G", "B"};
        target.half = false;
        sss::ImageMetadata meta;
        meta.software = std::string(kTool) + " (sss) " + sss::version_string();
        meta.command_line = sss::quoted_command_line(kTool, args);
        sss::write_display(out, target, meta);
        job.progress()->finish();
        if (job.verbose())
            std::printf("envdome: %s: sky %d x %d, integral %.6g %.6g %.6g\n",
                        output.c_str(), sky_w, sky_h, integral.x, integral.y, integral.z);
        return 0;
    }

    const std::string& probe = files[0];
    std::optional<sss::ScopedStage> stage(std::in_place, "reading " + probe);
    const sss::LatLongImage img = load_probe(probe);
    job.progress()->update(1, 3);
    stage.emplace("placing the lights of " + probe);
    const std::vector<sss::DomeLight> lights = sss::median_cut(img, count);
    job.progress()->update(2, 3);
    rib.probe = probe;
    stage.emplace("writing " + output);
    write_text(output, sss::dome_rib(lights, rib));
    stage.reset();
    job.progress()->finish();
    if (job.verbose()) {
        const glm::dvec3 e = sss::latlong_integral(img);
        std::printf(
            "envdome: %s: %zu lights from %s (%d x %d), integral %.6g %.6g %.6g\n",
            output.c_str(), lights.size(), probe.c_str(), img.width, img.height, e.x, e.y,
            e.z);
    }
    return 0;
}

} // namespace

int main(int argc, char** argv) {
    return sss::run_tool(kTool, argc, argv, run);
}
