// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file options.h
/// Option groups shared by several tools (and the Python module): materials,
/// ptfilter's diffusion options, brickmake's build options, point-cloud output.
/// The options of a job (threads, progress, frame, -newer) are in job.h.

#include <string>

#include "sss/cli/args.h"

namespace sss {

struct MaterialSpec;
/// Parses the PRMan material options shared by ptfilter and ptbake
/// (-material, -unitlength, -scattering, -absorption, -albedo r g b|fromfile,
/// -diffusemeanfreepath r g b|fromfile, -ior) into spec. Returns false when
/// opt is not one of them; allow_fromfile = false rejects `fromfile`.
bool material_option(ArgScanner& args, const std::string& opt, MaterialSpec& spec,
                     bool allow_fromfile = true);

struct SsDiffusionOptions;
/// Parses the options of ptfilter -ssdiffusion that fill SsDiffusionOptions:
/// the material options (material_option), -maxsolidangle, -profile,
/// -criterion, -isa, -exact, -areachannel, -radiancechannel and
/// -keepchannels. Returns false when opt is not one of them. ptfilter and
/// the Python module's ssdiffusion() (keywords turned into these words) share
/// it, so both accept and refuse the same values with the same messages.
bool ssdiffusion_option(ArgScanner& args, const std::string& opt,
                        SsDiffusionOptions& options);

struct BrickMapBuildOptions;
/// Parses brickmake's build options (-maxerror, -maxdepth, -radiusscale,
/// -ignorenormals, -omitgeometry, -channels) into options. Returns false when
/// opt is not one of them. brickmake and the Python module's make_brickmap()
/// share it.
bool brickmake_option(ArgScanner& args, const std::string& opt,
                      BrickMapBuildOptions& options);

struct PointCloudWriteOptions;
/// Parses the point-cloud output options (-compress 0|1, -ptcversion 0|1|2);
/// false when opt is not one of them.
bool write_option(ArgScanner& args, const std::string& opt,
                  PointCloudWriteOptions& write);

} // namespace sss
