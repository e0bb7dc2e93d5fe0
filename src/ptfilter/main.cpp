// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// ptfilter: PRMan-compatible point-cloud filter (-ssdiffusion, -part K/N, -merge).
// Option parsing and reporting; the work is one library call, sss::run_filter_job()
// (sss/diffusion/filter_job.h), which the Python module's sss.ptfilter() makes too.

#include <algorithm>
#include <cstdio>
#include <string>
#include <tuple>
#include <vector>

#include "sss/cli/tool.h"
#include "sss/diffusion/filter_job.h"
#include "sss/util/error.h"
#include "sss/util/isa.h"
#include "sss/util/limits.h"

namespace {

const char* kTool = "ptfilter";

std::string usage() {
    char buf[5120];
    std::snprintf(
        buf, sizeof buf,
        "usage: ptfilter -ssdiffusion [options] in.ptc [more.ptc ...] out.ptc\n"
        "       ptfilter -ssdiffusion [options] -part K/N in.ptc [...] out.ptpart\n"
        "       ptfilter -merge [-newer 1] [-progress 1] p1.ptpart ... pN.ptpart "
        "out.ptc\n"
        "       (also: -filter ssdiffusion)\n"
        "Subsurface diffusion of baked irradiance (Jensen dipole, hierarchical).\n"
        "Input .ptc/.ply clouds are merged; the output holds P, N, radius and\n"
        "color _ssdiffusion. Input and output may be the same file.\n\n"
        "Material (lengths in mm, scene length = mm x unitlength):\n"
        "  -material NAME            %s (default marble)\n"
        "  -scattering R G B         reduced scattering sigma_s' (1/mm)\n"
        "  -absorption R G B         absorption sigma_a (1/mm)\n"
        "  -albedo R G B | fromfile  diffuse albedo (or per-point _albedo)\n"
        "  -diffusemeanfreepath R G B | fromfile   dmfp in mm (or per point)\n"
        "  -ior N                    relative index of refraction (default: material's)\n"
        "  -unitlength U             scene units per mm (cm scenes: 0.1; default 1)\n"
        "Evaluation:\n"
        "  -maxsolidangle E          time/quality knob, smaller = slower, more\n"
        "                            accurate (default 1)\n"
        "  -profile NAME             classic (default, PRMan's), better, burley, pbd\n"
        "                            (photon beam diffusion), mc (Monte-Carlo table)\n"
        "  -volume 0|1               1: light carried through the volume the cloud\n"
        "                            encloses (thin parts, small objects; "
        "docs/volume.md)\n"
        "  -blocker FILE             a cloud on the surface of an absorbing inclusion\n"
        "                            (bone), normals out of it; repeatable; implies\n"
        "                            -volume 1\n"
        "  -incidence normal|diffuse how the baked light entered (a distant light\n"
        "                            overhead, default; or a dome): how much thin\n"
        "                            parts transmit with -volume 1\n"
        "  -criterion NAME           error (default), bbox (PRMan), centroid (J&B)\n"
        "  -exact                    all pairs (slow reference)\n"
        "Channels and output:\n"
        "  -areachannel NAME         default _area\n"
        "  -radiancechannel NAME     default _radiance_t\n"
        "  -keepchannels 0|1         copy input channels to the output (default 0)\n"
        "  -compress 0|1             gzip the output .ptc (default 0)\n"
        "  -ptcversion 0|1|2         .ptc version written (default 0)\n"
        "Splitting one cloud across machines (docs/farm.md):\n"
        "  -part K/N                 evaluate part K of N (1 <= K <= N) of the points\n"
        "                            (a compact region) against the whole cloud;\n"
        "                            writes a part file (.ptpart)\n"
        "  -merge                    join the N part files of one job (any order)\n"
        "                            into the cloud a single run writes, byte for byte\n"
        "Running:\n"
        "  -threads N                0 = all usable cores (default), <0 = all but N\n"
        "  -isa NAME                 kernels' instruction set: auto (default: SSS_ISA,\n"
        "                            else the best this CPU has), x86-64, avx2, avx512;\n"
        "                            all give identical results\n"
        "  -frame N                  expands %%04d, #### and $F4 in the file names\n"
        "  -progress 0|1|2           1: material values and timings, ALF_PROGRESS "
        "lines;\n"
        "                            2: also octree statistics\n"
        "  -newer 0|1                1: do nothing when out.ptc is newer than every\n"
        "                            input (exit 0)\n"
        "  -organize 0|1             accepted for compatibility; output is unorganized\n"
        "  -check                    check the command line only, reading and writing\n"
        "                            no file: exit 0 if it would run, 2 if not\n"
        "  --help, --version\n",
        sss::material_names().c_str());
    return buf;
}

double share(double part, double whole) {
    return whole > 0 ? part / whole : 0.0;
}

/// The report lines of a finished run (-progress 1 and 2).
void print_report(const sss::FilterJob& fj, const sss::FilterJobReport& r,
                  const sss::Job& job) {
    const sss::SsDiffusionOptions& opt = fj.options;
    const double per_point = 1.0 / double(std::max<std::size_t>(1, r.points));
    if (fj.mode == sss::FilterJob::Mode::Merge) {
        std::printf("ptfilter: joined %zu parts, %zu points: read %.3f s, write %.3f s\n",
                    fj.inputs.size(), r.points, r.read_seconds, r.write_seconds);
        return;
    }
    if (fj.mode == sss::FilterJob::Mode::Part)
        std::printf("ptfilter: part %u/%u: points %llu to %llu of %zu\n", fj.part,
                    fj.parts, (unsigned long long)r.part_first,
                    (unsigned long long)(r.part_first + r.part_count), r.points);
    std::printf("ptfilter: %zu points, threads %d, maxsolidangle %g, criterion %s%s, "
                "kernels %s\n",
                r.points, job.threads(), opt.diffusion.max_solid_angle,
                sss::criterion_name(opt.diffusion.criterion), opt.exact ? " (exact)" : "",
                sss::isa_name(opt.diffusion.isa));
    const sss::DiffusionStats& s = r.diffusion.stats;
    if (job.detailed() && !opt.exact)
        std::printf(
            "ptfilter: octree %zu nodes (built in %.3f s, evaluated in %.3f s), per "
            "point %.1f shared node terms, %.1f node terms, %.1f point terms, %.2f "
            "disk integrals\n",
            s.nodes, s.build_seconds, s.eval_seconds, double(s.local_terms) * per_point,
            double(s.far_terms) * per_point, double(s.near_terms) * per_point,
            double(s.quadrature_terms) * per_point);
    if (job.detailed())
        for (const std::string& line :
             sss::describe_values(r.diffusion.values, opt.output_channel))
            std::printf("ptfilter: %s\n", line.c_str());
    const sss::VolumeReport& v = r.diffusion.volume;
    if (v.needed)
        std::printf(
            "ptfilter: volume: %zu of %zu points thin, voxel %.4g mm, grid %dx%dx%d, "
            "%zu medium voxels, %d levels, %d/%d/%d CG steps, %.3f s; scattered "
            "light out %.4f %.4f %.4f, blocked %.4f %.4f %.4f of what entered; "
            "transmission through thin parts x%.2f-%.2f x%.2f-%.2f x%.2f-%.2f (%s "
            "light)\n",
            v.thin_points, r.points, v.voxel, v.dims[0], v.dims[1], v.dims[2], v.unknowns,
            v.levels, v.iterations[0], v.iterations[1], v.iterations[2], v.seconds,
            share(v.flux_out.x, v.flux_in.x), share(v.flux_out.y, v.flux_in.y),
            share(v.flux_out.z, v.flux_in.z), share(v.flux_blocked.x, v.flux_in.x),
            share(v.flux_blocked.y, v.flux_in.y), share(v.flux_blocked.z, v.flux_in.z),
            v.transmission_min.x, v.transmission_max.x, v.transmission_min.y,
            v.transmission_max.y, v.transmission_min.z, v.transmission_max.z,
            opt.volume_options.diffuse_light ? "diffuse" : "normal");
    else if (opt.volume || !opt.blockers.empty())
        std::printf(
            "ptfilter: volume: every point is thick against the material (%.3f s)\n",
            v.seconds);
    std::printf("ptfilter: read %.3f s, diffusion %.3f s, write %.3f s, total %.3f s\n",
                r.read_seconds, r.filter_seconds, r.write_seconds, job.seconds());
    if (job.detailed()) {
        // VmHWM: not the pages of a large parent that started it, as ru_maxrss.
        const double peak = double(sss::peak_resident_memory());
        std::printf("ptfilter: peak memory %.1f MB, %.1f bytes per point\n", peak / 1e6,
                    peak * per_point);
    }
}

int run(const std::vector<std::string>& argv) {
    sss::ArgScanner args(argv);
    sss::FilterJob fj;
    bool have_filter = false, merge = false, part = false;
    sss::RunOptions running;
    std::string filter_option, o; // filter_option: the first one given
    while (args.next_option(o, fj.inputs)) {
        if (o != "merge" && o != "part" && o != "newer" && o != "threads" &&
            o != "progress" && o != "Progress" && o != "frame" && o != "isa" &&
            filter_option.empty())
            filter_option = o;
        if (sss::standard_option(kTool, o, usage())) {
            return 0;
        } else if (o == "merge") {
            merge = true;
        } else if (o == "part") {
            std::tie(fj.part, fj.parts) = sss::parse_filter_part(args.value(o));
            part = true;
        } else if (o == "ssdiffusion" || o == "filter") {
            const std::string f = o == "filter" ? args.value(o) : o;
            if (f != "ssdiffusion")
                throw sss::UsageError("filter '" + f +
                                      "' is not supported (only ssdiffusion)");
            have_filter = true;
        } else if (sss::ssdiffusion_option(args, o, fj.options) ||
                   sss::write_option(args, o, fj.write) ||
                   sss::run_option(args, o, running) ||
                   sss::newer_option(args, o, running)) {
            continue;
        } else if (o == "organize") {
            args.integer(o, 0, 1);
        } else {
            throw sss::unknown_option(o, usage());
        }
    }
    if (merge) {
        if (!filter_option.empty() || part)
            throw sss::UsageError("-merge joins part files and takes no -" +
                                  (part ? std::string("part") : filter_option) +
                                  ": filter options belong to the -part runs");
        fj.mode = sss::FilterJob::Mode::Merge;
    } else if (!have_filter) {
        throw sss::UsageError(
            "no filter given (use -ssdiffusion or -filter ssdiffusion)");
    } else if (part) {
        fj.mode = sss::FilterJob::Mode::Part;
    }
    if (fj.inputs.size() < 2)
        throw sss::UsageError(merge ? "-merge needs the part files and an output file"
                                    : "need at least one input file and an output file");
    fj.output = fj.inputs.back();
    fj.inputs.pop_back();
    const std::vector<std::string> material =
        sss::prepare_filter_job(fj, running.frame, !sss::check_only());
    if (sss::check_only()) return 0;

    sss::Job job(kTool, running);
    // A blocker is an input too: a newer one makes the output stale.
    std::vector<std::string> sources = fj.inputs;
    sources.insert(sources.end(), fj.options.blockers.begin(), fj.options.blockers.end());
    if (job.up_to_date({fj.output}, sources)) return 0;
    fj.options.diffusion.progress = job.progress();
    for (const std::string& line : material)
        if (job.verbose()) std::printf("ptfilter: %s\n", line.c_str());
    sss::flush_standard_output();
    const sss::FilterJobReport report = sss::run_filter_job(fj);
    for (const std::string& w : report.diffusion.warnings) sss::warn(kTool, w);
    if (fj.mode == sss::FilterJob::Mode::Merge && job.progress())
        job.progress()->finish();
    if (job.verbose()) {
        print_report(fj, report, job);
        sss::flush_standard_output();
    }
    return 0;
}

} // namespace

int main(int argc, char** argv) {
    return sss::run_tool(kTool, argc, argv, run);
}
