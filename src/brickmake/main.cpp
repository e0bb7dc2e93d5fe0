// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file main.cpp
/// brickmake: PRMan-compatible brick map builder,
///   brickmake [options] in.ptc [more.ptc ...] out.bkm|out.vdb
/// Option parsing around sss::make_brick_map_from_files (or, for an OpenVDB
/// output, sss::make_vdb_from_files).

#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "sss/brick/brickmap.h"
#include "sss/brick/brickmap_tools.h"
#include "sss/cli/tool.h"
#include "sss/util/error.h"
#include "sss/util/frame_pattern.h"
#include "sss/util/job_files.h"
#include "sss/vdb/vdb.h"

namespace {

const char* const kTool = "brickmake";

const char* const kUsage =
    R"(usage: brickmake [options] in.ptc [more.ptc ...] out.bkm|out.vdb

Builds a brick map (sparse octrees of 8x8x8-sample bricks, see docs/brickmake.md)
from point clouds (.ptc or .ply; several are merged, channels matched by name).
An output ending in .vdb gets the map's channels as OpenVDB grids instead
(one grid per channel, named after it, and its coarser levels as
NAME_level1...), for Houdini, Blender and other volume tools. The output is
written atomically.

options:
  -maxerror E            largest error allowed when a brick is left out in favour
                         of its parent, in the channels' units (default 0.002)
  -maxdepth D            deepest octree level, 0..20 (default 15)
  -radiusscale S         multiplies the point radii: > 1 blurs and shrinks the
                         map; < 1 is not recommended (default 1)
  -ignorenormals 0|1     1: one octree, normals ignored (default 0: the two
                         sides of thin surfaces are kept apart)
  -omitgeometry 0|1      1: leave out occupancy data (default 0)
  -channels A,B,...      channels to store (default: every float and color)
  -newer 0|1             1: do nothing when the output is newer than every
                         input and a readable current-version map (or .vdb)
  -frame N               frame number: expands %04d, #### and $F4 in file names
  -splitangle DEG        PRMan 12.5 option; accepted and ignored
  -threads N             worker threads, 0 = all usable cores (default 0)
  -progress 0|1|2        1: counts, size and time, ALF_PROGRESS lines; 2: also
                         the bricks per level (-Progress = 1)
  -check                 check the command line only, reading and writing
                         no file: exit 0 if it would run, 2 if not
  -h, --help             this help
  --version              version information

Exit codes: 0 ok (or nothing to do with -newer 1), 1 bad input or failed
build, 2 bad command line.
)";

int run(const std::vector<std::string>& argv) {
    sss::ArgScanner args(argv);
    sss::BrickMapBuildOptions opt;
    sss::RunOptions running;
    std::vector<std::string> files;
    std::string o;
    while (args.next_option(o, files)) {
        if (sss::standard_option(kTool, o, kUsage)) {
            return 0;
        } else if (sss::brickmake_option(args, o, opt)) {
            continue;
        } else if (sss::newer_option(args, o, running)) {
            continue;
        } else if (o == "splitangle") {
            args.number(o);
            sss::warn(kTool, "-splitangle is ignored: the sides of a surface are always "
                             "kept apart by normal direction (see -ignorenormals)");
        } else if (sss::run_option(args, o, running)) {
            continue;
        } else {
            throw sss::unknown_option(o, kUsage);
        }
    }
    if (files.size() < 2)
        throw sss::UsageError(files.empty()
                                  ? "no input and output files given"
                                  : "need at least one input file and an output file");
    for (std::string& f : files)
        f = sss::expand_frame_pattern(f, running.frame, "file name");
    const std::string out_path = files.back();
    files.pop_back();
    if (opt.radius_scale < 1.0)
        sss::warn(kTool, "-radiusscale below 1 makes large and inefficient brick maps");

    // A brick map never replaces one of its clouds (another format).
    sss::JobFiles job_files;
    for (const std::string& f : files)
        job_files.input(f, "the input cloud \"" + f + "\"");
    job_files.output(out_path, "the output \"" + out_path + "\"");
    if (sss::check_only()) return 0;
    sss::check_output_target(out_path);

    const bool vdb = sss::is_vdb_path(out_path);
    sss::Job job(kTool, running);
    // -newer 1 keeps only a map this brickmake can read: one written by an
    // older version (no checksums) or a corrupt one is rebuilt.
    if (job.newer()) {
        std::error_code ec;
        const std::string problem = !std::filesystem::exists(out_path, ec) ? ""
                                    : vdb ? sss::vdb_file_problem(out_path)
                                          : sss::brick_map_problem(out_path);
        if (problem.empty()) {
            if (job.up_to_date({out_path}, files)) return 0;
        } else {
            sss::warn(kTool, problem + "; rebuilding it");
        }
    }
    opt.progress = job.progress();
    opt.provenance =
        sss::quoted_command_line(std::string(kTool) + " " + sss::version_string(), argv);

    if (vdb) {
        const sss::VdbMakeReport report = [&] {
            sss::ScopedStage stage("making the OpenVDB grids " + out_path);
            return sss::make_vdb_from_files(files, opt, out_path);
        }();
        if (job.verbose()) {
            std::size_t voxels = 0;
            for (const sss::VdbGridInfo& g : report.vdb.grids) voxels += g.voxels;
            std::printf("brickmake: %s: %zu points, %zu bricks, %zu grids (main grids at "
                        "depth %d), %zu voxels, %llu bytes\n",
                        out_path.c_str(), report.build.points,
                        report.build.bricks_written, report.vdb.grids.size(),
                        report.vdb.surface_depth, voxels,
                        static_cast<unsigned long long>(report.vdb.file_size));
            if (job.detailed()) {
                for (const sss::VdbGridInfo& g : report.vdb.grids)
                    std::printf("brickmake: grid %s: %s, %zu voxels, voxel size %g\n",
                                g.name.c_str(), g.value_type.c_str(), g.voxels,
                                g.voxel_size.x);
            }
            std::printf("brickmake: total %.3f s, threads %d\n", job.seconds(),
                        job.threads());
            sss::flush_standard_output();
        }
        return 0;
    }
    const sss::BrickMapBuildReport report = [&] {
        sss::ScopedStage stage("making the brick map " + out_path);
        return sss::make_brick_map_from_files(files, opt, out_path);
    }();
    if (job.verbose()) {
        std::printf(
            "brickmake: %s: %zu points, %zu bricks (%zu before pruning), %llu bytes\n",
            out_path.c_str(), report.points, report.bricks_written,
            report.bricks_before_pruning,
            static_cast<unsigned long long>(report.file_size));
        if (job.detailed()) {
            const sss::BrickMap map(out_path);
            for (const sss::BrickMapLevel& l : map.info().levels)
                std::printf("brickmake: depth %d: %zu bricks, %zu samples\n", l.depth,
                            l.bricks, l.samples);
        }
        std::printf("brickmake: build %.3f s, total %.3f s (with reading), threads %d\n",
                    report.seconds, job.seconds(), job.threads());
        sss::flush_standard_output();
    }
    return 0;
}

} // namespace

int main(int argc, char** argv) {
    return sss::run_tool(kTool, argc, argv, run);
}
