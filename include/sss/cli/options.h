#pragma once
/// \file options.h
/// Option groups shared by several tools (materials, runs, point-cloud
/// output) and the -newer test.

#include <optional>
#include <string>
#include <vector>

#include "sss/cli/args.h"

namespace sss {

struct MaterialSpec;
/// Parses the PRMan material options shared by ptfilter and ptbake
/// (-material, -unitlength, -scattering, -absorption, -albedo r g b|fromfile,
/// -diffusemeanfreepath r g b|fromfile, -ior) into spec. Returns false when
/// opt is not one of them; allow_fromfile = false rejects `fromfile`.
bool material_option(ArgScanner& args, const std::string& opt, MaterialSpec& spec,
                     bool allow_fromfile = true);

/// The options of every tool that runs a job: -threads N, -progress 0|1|2
/// and its alias -Progress (= 1), and -frame N for frame patterns in paths
/// (frame_pattern.h).
struct RunOptions {
    int threads = 0;
    int progress = 0;
    std::optional<int> frame;
};
/// Parses one of them into run; false when opt is not one of them.
bool run_option(ArgScanner& args, const std::string& opt, RunOptions& run);

/// The `-newer 1` test of ptfilter, brickmake, ptbake and render: true when
/// every output exists and was modified strictly after every input (file
/// system time, full resolution). Then it prints "<tool>: OUT is newer than
/// its inputs; nothing to do" on stdout and the tool exits 0 without work.
/// False when an output or an input is missing (the job then runs and
/// reports a missing input itself), or when there are no outputs.
bool outputs_up_to_date(const std::string& tool, const std::vector<std::string>& outputs,
                        const std::vector<std::string>& inputs);

struct PointCloudWriteOptions;
/// Parses the point-cloud output options (-compress 0|1, -ptcversion 0|1|2);
/// false when opt is not one of them.
bool write_option(ArgScanner& args, const std::string& opt,
                  PointCloudWriteOptions& write);

} // namespace sss
