// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file main.cpp
/// render: ray traces a RIB scene with the built-in surface shaders (brick-map
/// and point-cloud _ssdiffusion lookups included) and writes its Displays,
/// beauty and AOVs. Option parsing around sss::read_rib and sss::RenderJob.

#include <algorithm>
#include <climits>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "sss/cli/tool.h"
#include "sss/render/render.h"
#include "sss/scene/rib.h"
#include "sss/util/atomic_output.h"
#include "sss/util/error.h"
#include "sss/util/frame_pattern.h"
#include "sss/util/job_files.h"
#include "sss/util/limits.h"

namespace {

const char* const kTool = "render";

std::string usage() {
    return "usage: render [options] scene.rib\n"
           "\n"
           "Ray traces the scene (Embree) with its RSL shaders (the standard ones:\n"
           "constant, matte, plastic, read_ssdiffusion, skin...) and lights, and\n"
           "writes every Display: the beauty in R, G, B, A and the AOVs its modes\n"
           "name (shader output variables, or the built-in ambient, diffuse,\n"
           "specular, sss, occlusion). A bake RIB (shaders that call bake3d) also\n"
           "bakes its point clouds, as ptbake does. The scene may be gzip-compressed;\n"
           "\"-\" reads it from standard input. See docs/render.md.\n"
           "\n"
           "options:\n"
           "  -o IMAGE               write the primary Display into IMAGE instead\n"
           "  -frame N               frame number: selects FrameBegin N and expands\n"
           "                         %04d, #### and $F4 in file names (without it\n"
           "                         every frame of the file is rendered, in order)\n"
           "  -res X Y               image size instead of Format (quick previews)\n"
           "  -samples N             N x N pixel samples instead of PixelSamples\n"
           "  -pixelshading 0|1      1: shade every pixel sample on its own instead\n"
           "                         of at the ShadingRate (default 0)\n"
           "  -lenient               skip what the scene asks for that is not\n"
           "                         implemented (CSG, unknown requests...) with a\n"
           "                         warning; by default it is an error\n"
           "  -newer 0|1             1: do nothing when every image is newer than the\n"
           "                         RIB, its archives and the maps its shaders read\n"
           "  -threads N             worker threads, 0 = all usable cores (default 0)\n"
           "  -p:N, -t:N             the same as -threads N (prman's spelling)\n"
           "  -p, -t, -t:all         all usable cores (-threads 0)\n"
           "  -progress 0|1|2        1: counts and timings, and ALF_PROGRESS lines\n"
           "  -check                 check the command line only, reading and writing\n"
           "                         no file: exit 0 if it would run, 2 if not\n"
           "  -h, --help             this help\n"
           "  --version              version information\n"
           "\n"
           "Exit codes: 0 ok, 1 bad scene or failed render, 2 bad command line.\n";
}

/// Renders one frame of the scene (RenderJob) and prints its summary.
void render_frame(const sss::Scene& scene, const std::string& rib,
                  const sss::RenderJobOptions& opt, sss::Job& job, double read_s) {
    sss::warn_all(kTool, scene.warnings);
    // One plan for the whole job: the shaders are loaded and bound once.
    const sss::RenderJob render(scene, opt);
    // A scene on standard input has no date: always rendered.
    if (job.newer() && rib != sss::kRibStandardInput) {
        const sss::RenderFiles io = render.files();
        if (job.up_to_date(io.outputs, io.inputs)) return;
    }

    const sss::RenderReport report = render.run();
    sss::warn_all(kTool, report.warnings);
    if (job.verbose()) {
        const int xres = opt.xres > 0 ? opt.xres : scene.options.camera.xres;
        const int yres = opt.yres > 0 ? opt.yres : scene.options.camera.yres;
        const int nx =
            opt.pixel_samples > 0 ? opt.pixel_samples : scene.options.pixel_samples[0];
        const int ny =
            opt.pixel_samples > 0 ? opt.pixel_samples : scene.options.pixel_samples[1];
        for (std::size_t i = 0; i < report.baked_files.size(); ++i)
            std::printf("render: baked %s: %zu points, total area %.6g\n",
                        report.baked_files[i].c_str(), report.baked_points[i],
                        report.baked_areas[i]);
        if (report.files.empty()) {
            std::printf("render: every Display is \"null\": no image rendered\n");
        } else {
            std::printf(
                "render: %s: %zu primitives, %zu lights, %zu triangles, %dx%d pixels, "
                "%dx%d samples\n",
                rib.c_str(), scene.primitives.size(), scene.lights.size(),
                report.triangles, xres, yres, nx, ny);
            std::printf("render: %zu camera rays, %zu shadow and occlusion rays, %zu "
                        "secondary rays, %zu shading points\n",
                        report.camera_rays, report.shadow_rays, report.secondary_rays,
                        report.shading_points);
        }
        for (const std::string& f : report.files)
            std::printf("render: wrote %s\n", f.c_str());
        std::printf("render: read %.3f s, bake %.3f s, setup %.3f s, render %.3f s, "
                    "write %.3f s, total %.3f s, threads %d\n",
                    read_s, report.bake_seconds, report.setup_seconds,
                    report.render_seconds, report.write_seconds, job.seconds(),
                    job.threads());
        sss::flush_standard_output();
    }
}

int run(const std::vector<std::string>& argv) {
    sss::ArgScanner args(argv);
    sss::RenderJobOptions opt;
    sss::RunOptions running;
    sss::RibReadOptions read;
    std::vector<std::string> files;
    std::string o;
    while (args.next_option(o, files)) {
        if (sss::standard_option(kTool, o, usage())) {
            return 0;
        } else if (o == "o") {
            opt.output = args.value(o);
            opt.output_label = "option -o";
        } else if (o == "res") {
            // Any size: the image limits below say how far it may go.
            opt.xres = args.integer(o, 1, INT_MAX);
            opt.yres = args.integer(o, 1, INT_MAX);
        } else if (o == "samples") {
            opt.pixel_samples = args.integer(o, 1, 64);
        } else if (o == "pixelshading") {
            opt.pixel_shading = args.integer(o, 0, 1) != 0;
        } else if (o == "lenient") {
            read.lenient = true;
        } else if (sss::prman_thread_option(o, running)) {
            continue;
        } else if (sss::newer_option(args, o, running)) {
            continue;
        } else if (sss::run_option(args, o, running)) {
            continue;
        } else {
            throw sss::unknown_option(o, usage());
        }
    }
    if (files.size() != 1)
        throw sss::UsageError(files.empty() ? "no scene given (usage: render scene.rib)"
                                            : "more than one scene given");
    if (opt.xres > 0) {
        const std::string at =
            "option -res " + std::to_string(opt.xres) + " " + std::to_string(opt.yres);
        sss::check_limit(sss::Limit::ImageSide, uint64_t(std::max(opt.xres, opt.yres)),
                         at);
        sss::check_limit(sss::Limit::ImagePixels, uint64_t(opt.xres) * uint64_t(opt.yres),
                         at);
    }
    opt.frame = running.frame;
    opt.command_line = sss::quoted_command_line(kTool, argv);
    const std::string rib = sss::expand_frame_pattern(files[0], opt.frame, "scene");
    if (!opt.output.empty()) {
        // -o over the scene is refused by name before its extension.
        const std::string out =
            sss::expand_frame_pattern(opt.output, opt.frame, "option -o");
        if (sss::JobFiles::same_file(out, rib))
            throw sss::OutputConflictError(
                "option -o \"" + out + "\" is an input of this job (the scene file \"" +
                rib + "\")");
        if (!sss::has_extension_in(out, sss::image_extensions()) &&
            !sss::writes_into_existing(out))
            throw sss::UsageError("option -o: " +
                                  sss::unknown_extension_text(out, "an image file",
                                                              sss::image_extensions()));
    }
    if (sss::check_only()) return 0;

    sss::Job job(kTool, running);
    opt.progress = job.progress();

    sss::RibReadOptions ropt = read;
    ropt.frame = opt.frame;
    const sss::Scene scene = [&] {
        sss::ScopedStage stage("reading " + rib);
        return sss::read_rib(rib, ropt);
    }();
    render_frame(scene, rib, opt, job, job.seconds());
    // Without -frame (and -o, which names one image) every frame of the
    // file, in order, as prman renders them: a shadow pass's frame, then
    // the frames that read its maps.
    if (opt.frame || !opt.output.empty() || rib == sss::kRibStandardInput) return 0;
    std::vector<int> done = {scene.options.frame.value_or(0)};
    for (int number : scene.frame_numbers) {
        if (std::find(done.begin(), done.end(), number) != done.end()) continue;
        done.push_back(number);
        const double start = job.seconds();
        ropt.frame = number;
        const sss::Scene next = [&] {
            sss::ScopedStage stage("reading frame " + std::to_string(number) + " of " +
                                   rib);
            return sss::read_rib(rib, ropt);
        }();
        render_frame(next, rib, opt, job, job.seconds() - start);
    }
    return 0;
}

} // namespace

int main(int argc, char** argv) {
    return sss::run_tool(kTool, argc, argv, run);
}
