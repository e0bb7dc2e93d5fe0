// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file main.cpp
/// ptbake: reads a RIB scene and bakes the point clouds ptfilter reads
/// (_area, _radiance_t and optionally _albedo, _diffusemeanfreepath).
/// Option parsing around sss::read_rib and sss::bake_scene.

#include <cstdio>
#include <string>
#include <vector>

#include "sss/bake/bake.h"
#include "sss/cli/tool.h"
#include "sss/diffusion/material.h"
#include "sss/scene/rib.h"
#include "sss/util/atomic_output.h"
#include "sss/util/error.h"
#include "sss/util/frame_pattern.h"
#include "sss/util/job_files.h"
#include "sss/util/limits.h"
#include "sss/util/parse.h"

namespace {

const char* const kTool = "ptbake";

std::string usage() {
    char buf[4096];
    std::snprintf(
        buf, sizeof buf,
        "usage: ptbake [options] scene.rib\n"
        "\n"
        "Dices every surface that has a bake shader (bake_radiance_t, bake_sss_params,\n"
        "bake_constant) into micropolygons, independent of the view and with nothing\n"
        "culled, lights them (ambient + diffuse, ray-traced shadows) and writes the\n"
        "point clouds named by the shaders' \"filename\". Other surfaces only cast\n"
        "shadows. The scene may be gzip-compressed; \"-\" reads it from standard\n"
        "input. See docs/ptbake.md.\n"
        "\n"
        "options:\n"
        "  -o FILE                write every bake into FILE (.ptc or .ply) instead\n"
        "  -frame N               frame number: selects FrameBegin N and expands\n"
        "                         %%04d, #### and $F4 in file names\n"
        "  -spacing LEN|mfp       micropolygon edge in scene units (default: the\n"
        "                         scene's ShadingRate in raster pixels); mfp: the\n"
        "                         material's smallest mean free path\n"
        "  -mfpfraction F         with -spacing mfp: F x mean free path (default 1)\n"
        "  -material NAME, -unitlength U, -scattering, -absorption, -albedo,\n"
        "  -diffusemeanfreepath, -ior\n"
        "                         the material the bake is for, as in ptfilter (%s):\n"
        "                         warns when points are farther apart than its mean\n"
        "                         free path\n"
        "  -compress 0|1          gzip the .ptc (default 0)\n"
        "  -ptcversion 0|1|2      .ptc version written (default 0)\n"
        "  -lenient               skip what the scene asks for that is not\n"
        "                         implemented (CSG, unknown requests...) with a\n"
        "                         warning; by default it is an error\n"
        "  -newer 0|1             1: do nothing when every cloud the scene bakes is\n"
        "                         newer than the RIB, every archive, texture and\n"
        "                         shader it reads\n"
        "  -threads N             worker threads, 0 = all usable cores (default 0)\n"
        "  -p:N, -t:N             the same as -threads N (prman's spelling)\n"
        "  -p, -t, -t:all         all usable cores (-threads 0)\n"
        "  -progress 0|1|2        1: counts and timings, and ALF_PROGRESS lines\n"
        "  -check                 check the command line only, reading and writing\n"
        "                         no file: exit 0 if it would run, 2 if not\n"
        "  -h, --help             this help\n"
        "  --version              version information\n"
        "\n"
        "Exit codes: 0 ok, 1 bad scene or failed bake, 2 bad command line.\n",
        sss::material_names().c_str());
    return buf;
}

int run_job(const std::vector<std::string>& argv) {
    sss::ArgScanner args(argv);
    sss::BakeOptions opt;
    sss::MaterialSpec material;
    bool have_material = false;
    std::vector<std::string> files;
    sss::RunOptions running;
    sss::RibReadOptions read;
    std::string o;
    while (args.next_option(o, files)) {
        if (sss::standard_option(kTool, o, usage())) {
            return 0;
        } else if (sss::material_option(args, o, material, false)) {
            // -unitlength and -ior alone describe units, not a material.
            have_material = have_material || (o != "unitlength" && o != "ior");
            opt.unitlength = material.unitlength;
        } else if (o == "o") {
            opt.output = args.value(o);
        } else if (o == "spacing") {
            if (args.peek() == "mfp") {
                args.value(o);
                opt.spacing_from_material = true;
            } else {
                opt.spacing = args.positive(o);
            }
        } else if (o == "mfpfraction") {
            opt.mfp_fraction = args.positive(o);
        } else if (o == "lenient") {
            read.lenient = true;
        } else if (sss::prman_thread_option(o, running)) {
            continue;
        } else if (sss::newer_option(args, o, running)) {
            continue;
        } else if (sss::write_option(args, o, opt.write)) {
            continue;
        } else if (sss::run_option(args, o, running)) {
            continue;
        } else {
            throw sss::unknown_option(o, usage());
        }
    }
    if (files.size() != 1)
        throw sss::UsageError(files.empty() ? "no scene given (usage: ptbake scene.rib)"
                                            : "more than one scene given");
    if (have_material) {
        material.validate();
        opt.material = material;
    }
    opt.frame = running.frame;
    const std::string rib = sss::expand_frame_pattern(files[0], opt.frame, "scene");
    if (!opt.output.empty()) {
        opt.output = sss::expand_frame_pattern(opt.output, opt.frame, "option -o");
        // -o over the scene is refused by name before its extension.
        if (sss::JobFiles::same_file(opt.output, rib))
            throw sss::OutputConflictError(
                "option -o \"" + opt.output +
                "\" is an input of this job (the scene file \"" + rib + "\")");
        if (!sss::has_extension_in(opt.output, sss::point_cloud_extensions()) &&
            !sss::writes_into_existing(opt.output))
            throw sss::UsageError("option -o: " + sss::unknown_extension_text(
                                                      opt.output, "a point cloud file",
                                                      sss::point_cloud_extensions()));
    }
    if (sss::check_only()) return 0;

    sss::Job job(kTool, running);
    opt.progress = job.progress();

    sss::RibReadOptions ropt = read;
    ropt.frame = opt.frame;
    sss::Scene scene = [&] {
        sss::ScopedStage stage("reading " + rib);
        return sss::read_rib(rib, ropt);
    }();
    sss::warn_all(kTool, scene.warnings);
    const double read_s = job.seconds();
    // One plan for the whole job: the shaders are loaded and bound once.
    const sss::BakeJob bake(scene, opt);
    // A scene on standard input has no date: always baked.
    if (job.newer() && rib != sss::kRibStandardInput &&
        job.up_to_date(bake.output_files(), bake.input_files()))
        return 0;

    sss::BakeReport report = bake.run();
    sss::warn_all(kTool, report.warnings);
    if (job.verbose()) {
        std::printf("ptbake: %s: %zu primitives, %zu lights, %zu baked, %zu occluders "
                    "(%zu triangles, %zu shadowed lights)\n",
                    rib.c_str(), scene.primitives.size(), scene.lights.size(),
                    report.baked_primitives, report.occluder_primitives,
                    report.occluder_triangles, report.shadow_lights);
        std::printf(
            "ptbake: estimated %.4g micropolygons, %s before dicing\n",
            report.estimated_micropolygons,
            sss::format_bytes(static_cast<uint64_t>(report.estimated_bytes)).c_str());
        std::printf("ptbake: micropolygon size %.4g to %.4g scene units\n",
                    report.min_spacing, report.max_spacing);
        for (const sss::BakeFileReport& f : report.files) {
            std::printf("ptbake: wrote %s: %zu points, area %.6g, channels %s\n",
                        f.path.c_str(), f.points, f.area, sss::join(f.channels).c_str());
        }
        std::printf("ptbake: read %.3f s, dice %.3f s, occluders %.3f s, light %.3f s, "
                    "write %.3f s, total %.3f s, threads %d\n",
                    read_s, report.dice_seconds, report.trace_build_seconds,
                    report.light_seconds, report.write_seconds, job.seconds(),
                    job.threads());
        sss::flush_standard_output();
    }
    return 0;
}

/// run_job, with the bake's errors about what the command line sets told in
/// the options' words.
int run(const std::vector<std::string>& argv) {
    try {
        return run_job(argv);
    } catch (const sss::MissingBakeFileError& e) {
        throw sss::ValueError(std::string(e.what()) + " (give one, or ptbake -o FILE)");
    } catch (const sss::SpacingMaterialError& e) {
        throw sss::UsageError(e.source() +
                              ": -spacing mfp needs a material (-material NAME ...) "
                              "for objects baked without bake_sss_params");
    }
}

} // namespace

int main(int argc, char** argv) {
    return sss::run_tool(kTool, argc, argv, run);
}
