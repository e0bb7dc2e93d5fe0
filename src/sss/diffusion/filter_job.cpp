// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file filter_job.cpp
/// ptfilter's job: checks, reading or streaming, parts, the merge, writing.

#include "sss/diffusion/filter_job.h"

#include <cstdio>
#include <utility>

#include "sss/cloud/cloud_part.h"
#include "sss/util/atomic_output.h"
#include "sss/util/frame_pattern.h"
#include "sss/util/hash.h"
#include "sss/util/isa.h"
#include "sss/util/job_files.h"
#include "sss/util/limits.h"
#include "sss/util/parse.h"
#include "sss/util/progress.h"

namespace sss {

namespace {

/// UsageError unless `out` names a point cloud (or an existing device or FIFO).
void require_cloud_output(const std::string& out) {
    if (!has_extension_in(out, point_cloud_extensions()) && !writes_into_existing(out))
        throw UsageError("output " + unknown_extension_text(out, "a point cloud file",
                                                            point_cloud_extensions()));
}

/// What ties the parts of one job together: the input cloud's content, every
/// option that changes the output and the number of parts.
uint64_t part_fingerprint(const PointCloud& cloud, const SsDiffusionOptions& opt,
                          const PointCloudWriteOptions& wopt, uint32_t parts) {
    const std::string job = ssdiffusion_signature(opt) +
                            "; compress=" + std::to_string(wopt.compress) +
                            "; ptcversion=" + std::to_string(wopt.ptc_version) +
                            "; parts=" + std::to_string(parts);
    return cloud_fingerprint(cloud, detail::hash_bytes(job.data(), job.size()));
}

/// Runs f (the diffusion) with its input errors naming the input files: the
/// library below only sees the merged cloud.
template <class F>
void naming_inputs(const std::vector<std::string>& inputs, F&& f) {
    try {
        f();
    } catch (const MissingChannelError& e) {
        throw MissingChannelError(e.role(), e.channel(), e.present(), join(inputs));
    } catch (const ValueError& e) {
        throw ValueError(join(inputs) + ": " + e.what());
    }
}

FilterJobReport run_merge(const FilterJob& job) {
    FilterJobReport report;
    Stopwatch clock;
    PointCloudWriteOptions wopt;
    PointCloud whole;
    {
        ScopedStage stage("joining " + std::to_string(job.inputs.size()) + " parts");
        whole = merge_cloud_parts(job.inputs, wopt);
    }
    report.points = whole.size();
    report.read_seconds = clock.seconds();
    {
        ScopedStage stage("writing " + job.output);
        write_point_cloud(whole, job.output, wopt);
    }
    report.write_seconds = clock.seconds() - report.read_seconds;
    return report;
}

FilterJobReport run_part(const FilterJob& job) {
    FilterJobReport report;
    Stopwatch clock;
    PointCloud cloud;
    for (std::size_t i = 0; i < job.inputs.size(); ++i) {
        ScopedStage stage("reading " + job.inputs[i]);
        if (i == 0)
            cloud = read_point_cloud(job.inputs[i]);
        else
            cloud.append(read_point_cloud(job.inputs[i]));
    }
    report.read_seconds = clock.seconds();
    report.points = cloud.size();
    CloudPart piece;
    {
        ScopedStage stage("filtering " + join(job.inputs));
        naming_inputs(job.inputs, [&] {
            piece.info.fingerprint =
                part_fingerprint(cloud, job.options, job.write, job.parts);
            // The cloud is moved in: the part frees it early (less memory).
            SsDiffusionPart p =
                ssdiffusion_part(std::move(cloud), job.options, job.part - 1, job.parts,
                                 &report.diffusion);
            piece.info.part = job.part;
            piece.info.parts = job.parts;
            piece.info.total = p.total;
            piece.info.first = p.first;
            piece.info.count = p.points.size();
            piece.info.write_options = job.write;
            piece.indices = std::move(p.indices);
            piece.points = std::move(p.points);
        });
    }
    report.part_first = piece.info.first;
    report.part_count = piece.info.count;
    report.filter_seconds = clock.seconds() - report.read_seconds;
    {
        ScopedStage stage("writing " + job.output);
        write_cloud_part(piece, job.output);
    }
    report.write_seconds = clock.seconds() - report.read_seconds - report.filter_seconds;
    return report;
}

FilterJobReport run_streamed(const FilterJob& job) {
    FilterJobReport report;
    Stopwatch clock;
    // The inputs are read for the channels the filter needs, and again while
    // the output is written, so that no whole cloud is held next to the octree.
    SsDiffusionFiles files(job.inputs, job.options); // the headers
    double read_s = clock.seconds();
    {
        ScopedStage stage("filtering " + join(job.inputs));
        naming_inputs(job.inputs, [&] { files.filter(&report.diffusion); });
    }
    report.read_seconds = read_s + files.read_seconds();
    report.points = files.size();
    report.filter_seconds = clock.seconds() - report.read_seconds;
    {
        ScopedStage stage("writing " + job.output);
        files.write(job.output, job.write);
    }
    report.write_seconds = clock.seconds() - report.read_seconds - report.filter_seconds;
    return report;
}

} // namespace

std::pair<uint32_t, uint32_t> parse_filter_part(const std::string& text) {
    constexpr unsigned long kMaxParts = 1000000;
    auto bad = [&]() {
        return UsageError("option -part: expected K/N with 1 <= K <= N <= " +
                          std::to_string(kMaxParts) + " (e.g. 2/4), got '" + text + "'");
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

std::vector<std::string> prepare_filter_job(FilterJob& job, std::optional<int> frame,
                                            bool this_machine) {
    if (job.mode != FilterJob::Mode::Merge) {
        // The kernels' path: a farm that asked for one must get it or stop.
        Isa& isa = job.options.diffusion.isa;
        isa = this_machine ? resolve_isa(isa) : requested_isa(isa);
    }
    // The whole material before reading anything.
    std::vector<std::string> material;
    if (job.mode != FilterJob::Mode::Merge) material = describe_material(job.options);
    for (std::string& f : job.inputs) f = expand_frame_pattern(f, frame, "file name");
    for (std::string& f : job.options.blockers)
        f = expand_frame_pattern(f, frame, "file name");
    if (job.mode == FilterJob::Mode::Part &&
        (job.options.volume || !job.options.blockers.empty()))
        throw UsageError("-volume and -blocker cannot run in parts (-part): the volume "
                         "couples every point with every other");
    job.output = expand_frame_pattern(job.output, frame, "file name");
    if (job.mode == FilterJob::Mode::Part) {
        if (!has_extension_in(job.output, {kCloudPartExtension}) &&
            !writes_into_existing(job.output))
            throw UsageError("with -part the output is a part file: name it *" +
                             std::string(kCloudPartExtension) + ", not " + job.output);
    } else {
        require_cloud_output(job.output);
    }
    return material;
}

std::vector<std::string> describe_values(const ValueSummary& v,
                                         const std::string& channel) {
    std::vector<std::string> lines;
    if (v.count == 0) return lines;
    char buf[512];
    std::snprintf(buf, sizeof buf,
                  "%s of %zu points: min %.6g %.6g %.6g, mean %.6g %.6g %.6g, "
                  "max %.6g %.6g %.6g",
                  channel.c_str(), v.count, v.min.x, v.min.y, v.min.z, v.mean.x, v.mean.y,
                  v.mean.z, v.max.x, v.max.y, v.max.z);
    lines.emplace_back(buf);
    for (const auto& [index, value] : v.sample) {
        std::snprintf(buf, sizeof buf, "%s of point %llu: %.6g %.6g %.6g",
                      channel.c_str(), (unsigned long long)index, double(value.x),
                      double(value.y), double(value.z));
        lines.emplace_back(buf);
    }
    return lines;
}

FilterJobReport run_filter_job(const FilterJob& job) {
    check_output_target(job.output);
    switch (job.mode) {
    case FilterJob::Mode::Merge:
        return run_merge(job);
    case FilterJob::Mode::Part:
        return run_part(job);
    case FilterJob::Mode::Diffusion:
        break;
    }
    return run_streamed(job);
}

} // namespace sss
