// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file filter_job.h
/// ptfilter's job as one library call, as maketx is one call of OpenImageIO:
/// the tool (src/ptfilter/main.cpp) and the Python module's sss.ptfilter()
/// parse their options into a FilterJob, and prepare_filter_job() and
/// run_filter_job() do the rest (checks, reading, streaming, parts and their
/// fingerprint, the merge, writing). Reporting stays with the caller.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "sss/cloud/point_cloud_io.h"
#include "sss/diffusion/ssdiffusion.h"

namespace sss {

/// One ptfilter run, as its options give it.
struct FilterJob {
    enum class Mode {
        Diffusion, ///< -ssdiffusion: the inputs' diffusion into one cloud
        Part,      ///< -ssdiffusion -part K/N: part K of N into a part file
        Merge      ///< -merge: the part files of one job into the cloud
    };
    Mode mode = Mode::Diffusion;
    /// Input files and the output, frame patterns not yet expanded (the output
    /// may be one of the inputs: every input is read before it is replaced).
    std::vector<std::string> inputs;
    std::string output;
    SsDiffusionOptions options;
    PointCloudWriteOptions write;
    uint32_t part = 0;  ///< with Mode::Part: K (1-based)
    uint32_t parts = 0; ///< with Mode::Part: N
};

/// Parses "K/N" (1 <= K <= N <= 10^6) of -part; UsageError otherwise.
std::pair<uint32_t, uint32_t> parse_filter_part(const std::string& text);

/// The checks a run makes before it reads anything, in this order: the file
/// names' frame patterns expanded with `frame` (MissingFrameError when one
/// has a pattern and there is no frame), the output's extension for the mode
/// (UsageError), the kernels' instruction set resolved (a run that asked for
/// one must get it), and the whole material validated. Returns the material's
/// description (describe_material()); nothing for Mode::Merge. With
/// `this_machine` false (a dry parse, `ptfilter -check`, maybe on a farm's
/// submit host) the instruction set's name is checked but not that this CPU
/// has it (requested_isa()).
std::vector<std::string> prepare_filter_job(FilterJob& job, std::optional<int> frame,
                                            bool this_machine = true);

/// What a run did, for its report.
struct FilterJobReport {
    SsDiffusionReport diffusion;
    std::size_t points = 0;     ///< points of the whole output
    std::size_t part_first = 0; ///< Mode::Part: the part's first point
    std::size_t part_count = 0; ///< Mode::Part: the part's points
    double read_seconds = 0;
    double filter_seconds = 0; ///< the diffusion (Merge: joining the parts)
    double write_seconds = 0;
};

/// -progress 2's lines for the computed values at a glance, as PRMan's
/// ptfilter prints a sample of them: min, mean and max per channel, then each
/// sampled point (docs/ptfilter.md#progress). None for an empty summary.
std::vector<std::string> describe_values(const ValueSummary& values,
                                         const std::string& channel);

/// Runs a prepared job: checks that the output can be written, then
/// - Diffusion: streams the inputs (SsDiffusionFiles: no whole cloud is held
///   next to the octree) and writes the output atomically;
/// - Part: reads the inputs whole (the part file records a fingerprint of the
///   cloud and of every option that changes the output), evaluates the part
///   and writes the part file;
/// - Merge: joins the part files (merge_cloud_parts()) into the cloud.
/// The filter's ValueErrors name the input files; a missing channel stays a
/// MissingChannelError (with inputs()), so that a front end can name the
/// option that sets it.
FilterJobReport run_filter_job(const FilterJob& job);

} // namespace sss
