// ptfilter: PRMan-compatible point-cloud filter. Only ssdiffusion is offered:
//   ptfilter -ssdiffusion [options] in.ptc [more.ptc ...] out.ptc
//   ptfilter -ssdiffusion [options] -part K/N in.ptc [more.ptc ...] out.ptpart
//   ptfilter -merge part.ptpart ... out.ptc
// Option parsing only; the work is sss::ssdiffusion(), sss::ssdiffusion_part()
// and sss::merge_cloud_parts().

#include <algorithm>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "sss/cli/tool.h"
#include "sss/cloud/cloud_part.h"
#include "sss/cloud/point_cloud_io.h"
#include "sss/diffusion/ssdiffusion.h"
#include "sss/util/atomic_output.h"
#include "sss/util/error.h"
#include "sss/util/frame_pattern.h"
#include "sss/util/hash.h"
#include "sss/util/isa.h"
#include "sss/util/job_files.h"
#include "sss/util/limits.h"
#include "sss/util/parse.h"

namespace {

const char* kTool = "ptfilter";

std::string usage() {
    char buf[4096];
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
        "  -profile NAME             classic (default), better, burley\n"
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
        "  --help, --version\n",
        sss::material_names().c_str());
    return buf;
}

/// The option that names a channel of each role.
const char* channel_option(sss::MissingChannelError::Role role) {
    switch (role) {
    case sss::MissingChannelError::Role::Radiance:
        return "-radiancechannel";
    case sss::MissingChannelError::Role::Albedo:
        return "-albedo fromfile";
    case sss::MissingChannelError::Role::Dmfp:
        return "-diffusemeanfreepath fromfile";
    }
    return "?";
}

/// "K/N" with 1 <= K <= N.
std::pair<uint32_t, uint32_t> parse_part(const std::string& text) {
    constexpr unsigned long kMaxParts = 1000000;
    auto bad = [&]() {
        return sss::UsageError("option -part: expected K/N with 1 <= K <= N <= " +
                               std::to_string(kMaxParts) + " (e.g. 2/4), got '" + text +
                               "'");
    };
    const std::size_t slash = text.find('/');
    if (slash == std::string::npos) throw bad();
    auto number = [&](const std::string& digits) {
        if (digits.empty() || digits.size() > 7 ||
            digits.find_first_not_of("0123456789") != std::string::npos)
            throw bad();
        return std::stoul(digits);
    };
    const unsigned long k = number(text.substr(0, slash));
    const unsigned long n = number(text.substr(slash + 1));
    if (k < 1 || n > kMaxParts || k > n) throw bad();
    return {uint32_t(k), uint32_t(n)};
}

/// What ties the parts of one job together: the input cloud's content, every
/// option that changes the output and the number of parts.
uint64_t part_fingerprint(const sss::PointCloud& cloud,
                          const sss::SsDiffusionOptions& opt,
                          const sss::PointCloudWriteOptions& wopt, uint32_t parts) {
    const std::string job = sss::ssdiffusion_signature(opt) +
                            "; compress=" + std::to_string(wopt.compress) +
                            "; ptcversion=" + std::to_string(wopt.ptc_version) +
                            "; parts=" + std::to_string(parts);
    return sss::cloud_fingerprint(cloud, sss::detail::hash_bytes(job.data(), job.size()));
}

/// Expands the frame patterns of every file name and takes the last one (the
/// output) off `files`.
std::string take_output(std::vector<std::string>& files, const sss::RunOptions& running) {
    for (std::string& f : files)
        f = sss::expand_frame_pattern(f, running.frame, "file name");
    std::string out = files.back();
    files.pop_back();
    return out;
}

/// UsageError unless `out` names a point cloud (or an existing device or FIFO).
void require_cloud_output(const std::string& out) {
    if (!sss::has_extension_in(out, sss::point_cloud_extensions()) &&
        !sss::writes_into_existing(out))
        throw sss::UsageError("output " +
                              sss::unknown_extension_text(out, "a point cloud file",
                                                          sss::point_cloud_extensions()));
}

/// ptfilter -merge part... out: joins the parts of one -part job.
int run_merge(std::vector<std::string> files, const sss::RunOptions& running) {
    if (files.size() < 2)
        throw sss::UsageError("-merge needs the part files and an output file");
    const std::string out_path = take_output(files, running);
    require_cloud_output(out_path);
    sss::Job job(kTool, running);
    if (job.up_to_date({out_path}, files)) return 0;
    sss::check_output_target(out_path);
    sss::PointCloudWriteOptions wopt;
    sss::PointCloud whole;
    {
        sss::ScopedStage stage("joining " + std::to_string(files.size()) + " parts");
        whole = sss::merge_cloud_parts(files, wopt);
    }
    double join_s = job.seconds();
    {
        sss::ScopedStage stage("writing " + out_path);
        sss::write_point_cloud(whole, out_path, wopt);
    }
    if (job.progress()) job.progress()->finish();
    if (job.verbose()) {
        std::printf("ptfilter: joined %zu parts, %zu points: read %.3f s, write %.3f s\n",
                    files.size(), whole.size(), join_s, job.seconds() - join_s);
        sss::flush_standard_output();
    }
    return 0;
}

// -progress 2: the computed values at a glance, as PRMan's ptfilter prints a
// sample of them (docs/ptfilter.md#progress).
void print_values(const sss::ValueSummary& v, const std::string& channel) {
    if (v.count == 0) return;
    std::printf("ptfilter: %s of %zu points: min %.6g %.6g %.6g, mean %.6g %.6g %.6g, "
                "max %.6g %.6g %.6g\n",
                channel.c_str(), v.count, v.min.x, v.min.y, v.min.z, v.mean.x, v.mean.y,
                v.mean.z, v.max.x, v.max.y, v.max.z);
    for (const auto& [index, value] : v.sample)
        std::printf("ptfilter: %s of point %llu: %.6g %.6g %.6g\n", channel.c_str(),
                    (unsigned long long)index, double(value.x), double(value.y),
                    double(value.z));
}

int run(const std::vector<std::string>& argv) {
    sss::ArgScanner args(argv);
    sss::SsDiffusionOptions opt;
    sss::PointCloudWriteOptions wopt;
    std::vector<std::string> files;
    bool have_filter = false;
    sss::RunOptions running;
    bool merge = false;
    std::optional<std::pair<uint32_t, uint32_t>> part; // K, N
    std::string filter_option;                         // the first one given
    std::string o;
    while (args.next_option(o, files)) {
        if (o != "merge" && o != "part" && o != "newer" && o != "threads" &&
            o != "progress" && o != "Progress" && o != "frame" && o != "isa" &&
            filter_option.empty())
            filter_option = o;
        if (sss::standard_option(kTool, o, usage())) {
            return 0;
        } else if (o == "merge") {
            merge = true;
        } else if (o == "part") {
            part = parse_part(args.value(o));
        } else if (o == "ssdiffusion") {
            have_filter = true;
        } else if (o == "filter") {
            std::string f = args.value(o);
            if (f != "ssdiffusion")
                throw sss::UsageError("filter '" + f +
                                      "' is not supported (only ssdiffusion)");
            have_filter = true;
        } else if (sss::ssdiffusion_option(args, o, opt)) {
            continue;
        } else if (sss::write_option(args, o, wopt)) {
            continue;
        } else if (sss::run_option(args, o, running)) {
            continue;
        } else if (sss::newer_option(args, o, running)) {
            continue;
        } else if (o == "organize") {
            args.integer(o, 0, 1);
        } else {
            throw sss::UsageError("unknown option -" + o);
        }
    }
    if (merge) {
        if (!filter_option.empty() || part)
            throw sss::UsageError("-merge joins part files and takes no -" +
                                  (part ? std::string("part") : filter_option) +
                                  ": filter options belong to the -part runs");
        return run_merge(files, running);
    }
    if (!have_filter)
        throw sss::UsageError(
            "no filter given (use -ssdiffusion or -filter ssdiffusion)");
    if (files.size() < 2)
        throw sss::UsageError("need at least one input file and an output file");
    // The kernels' path: a farm that asked for one must get it or stop.
    opt.diffusion.isa = sss::resolve_isa(opt.diffusion.isa);
    // Check the whole material before reading anything.
    std::vector<std::string> material = sss::describe_material(opt);

    const std::string out_path = take_output(files, running);
    // The output may be one of the inputs (in place): every input is read
    // whole before the output replaces it.
    if (part) {
        if (!sss::has_extension_in(out_path, {sss::kCloudPartExtension}) &&
            !sss::writes_into_existing(out_path))
            throw sss::UsageError("with -part the output is a part file: name it *" +
                                  std::string(sss::kCloudPartExtension) + ", not " +
                                  out_path);
    } else {
        require_cloud_output(out_path);
    }
    sss::Job job(kTool, running);
    if (job.up_to_date({out_path}, files)) return 0;
    opt.diffusion.progress = job.progress();
    sss::check_output_target(out_path);
    if (job.verbose()) {
        for (const std::string& line : material)
            std::printf("ptfilter: %s\n", line.c_str());
        sss::flush_standard_output();
    }

    // Without -part the inputs are streamed (sss::SsDiffusionFiles: read for
    // the channels the filter needs, read again while the output is written),
    // so that no whole cloud is held next to the octree. A part needs the
    // whole cloud for its fingerprint.
    sss::PointCloud cloud;
    std::optional<sss::SsDiffusionFiles> streamed;
    for (std::size_t i = 0; i < files.size() && part; ++i) {
        sss::ScopedStage stage("reading " + files[i]);
        if (i == 0)
            cloud = sss::read_point_cloud(files[i]);
        else
            cloud.append(sss::read_point_cloud(files[i]));
    }
    if (!part) streamed.emplace(files, opt); // the headers
    double read_s = job.seconds();
    std::size_t points = cloud.size();

    sss::SsDiffusionReport report;
    sss::CloudPart piece;
    try {
        sss::ScopedStage stage("filtering " + sss::join(files));
        if (part) {
            piece.info.fingerprint = part_fingerprint(cloud, opt, wopt, part->second);
            // The cloud is moved in: the part frees it early (less memory).
            sss::SsDiffusionPart p = sss::ssdiffusion_part(
                std::move(cloud), opt, part->first - 1, part->second, &report);
            piece.info.part = part->first;
            piece.info.parts = part->second;
            piece.info.total = p.total;
            piece.info.first = p.first;
            piece.info.count = p.points.size();
            piece.info.write_options = wopt;
            piece.indices = std::move(p.indices);
            piece.points = std::move(p.points);
        } else {
            streamed->filter(&report);
            read_s += streamed->read_seconds();
            points = streamed->size();
        }
    } catch (const sss::MissingChannelError& e) {
        throw sss::ValueError(sss::join(files) + ": input has no channel '" +
                              e.channel() + "' (set it with " + channel_option(e.role()) +
                              "; channels present: " + e.present() + ")");
    } catch (const sss::ValueError& e) {
        // Name the input files: the library only sees the merged cloud.
        throw sss::ValueError(sss::join(files) + ": " + e.what());
    }
    for (const std::string& w : report.warnings) sss::warn(kTool, w);
    double filter_s = job.seconds() - read_s;

    {
        sss::ScopedStage stage("writing " + out_path);
        if (part)
            sss::write_cloud_part(piece, out_path);
        else
            streamed->write(out_path, wopt);
    }
    if (job.verbose()) {
        if (part)
            std::printf("ptfilter: part %u/%u: points %llu to %llu of %zu\n", part->first,
                        part->second, (unsigned long long)piece.info.first,
                        (unsigned long long)(piece.info.first + piece.info.count),
                        points);
        std::printf("ptfilter: %zu points, threads %d, maxsolidangle %g, criterion %s%s, "
                    "kernels %s\n",
                    points, job.threads(), opt.diffusion.max_solid_angle,
                    sss::criterion_name(opt.diffusion.criterion),
                    opt.exact ? " (exact)" : "", sss::isa_name(opt.diffusion.isa));
        if (job.detailed() && !opt.exact)
            std::printf(
                "ptfilter: octree %zu nodes (built in %.3f s, evaluated in %.3f s), per "
                "point %.1f shared node terms, %.1f node terms, %.1f point terms, %.2f "
                "disk integrals\n",
                report.stats.nodes, report.stats.build_seconds, report.stats.eval_seconds,
                double(report.stats.local_terms) / std::max<std::size_t>(1, points),
                double(report.stats.far_terms) / std::max<std::size_t>(1, points),
                double(report.stats.near_terms) / std::max<std::size_t>(1, points),
                double(report.stats.quadrature_terms) / std::max<std::size_t>(1, points));
        if (job.detailed()) print_values(report.values, opt.output_channel);
        std::printf(
            "ptfilter: read %.3f s, diffusion %.3f s, write %.3f s, total %.3f s\n",
            read_s, filter_s, job.seconds() - read_s - filter_s, job.seconds());
        if (job.detailed()) {
            // The peak resident memory of this program so far (VmHWM: not
            // the pages of a large parent that started it, as ru_maxrss).
            const double peak = double(sss::peak_resident_memory());
            std::printf("ptfilter: peak memory %.1f MB, %.1f bytes per point\n",
                        peak / 1e6, peak / double(std::max<std::size_t>(1, points)));
        }
        sss::flush_standard_output();
    }
    return 0;
}

} // namespace

int main(int argc, char** argv) {
    return sss::run_tool(kTool, argc, argv, run);
}
