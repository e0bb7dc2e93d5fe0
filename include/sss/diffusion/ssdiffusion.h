#pragma once
/// \file ssdiffusion.h
/// The ptfilter -ssdiffusion job as one library call: channels in, material
/// resolved, diffusion evaluated, output cloud built.

#include <string>
#include <vector>

#include "sss/diffusion/diffusion.h"
#include "sss/diffusion/material.h"
#include "sss/cloud/point_cloud.h"
#include "sss/diffusion/profile.h"

namespace sss {

/// Everything ptfilter -ssdiffusion can be told.
struct SsDiffusionOptions {
    MaterialSpec material;
    ProfileKind profile = ProfileKind::Classic;
    DiffusionOptions diffusion; ///< -maxsolidangle, criterion, progress
    bool exact = false;         ///< all pairs instead of the octree
    std::string area_channel = "_area";
    std::string radiance_channel = "_radiance_t";
    std::string albedo_channel = "_albedo";
    std::string dmfp_channel = "_diffusemeanfreepath";
    std::string output_channel = "_ssdiffusion";
    bool keep_channels = false; ///< copy the input channels to the output
};

/// What happened, for -progress reports.
struct SsDiffusionReport {
    std::vector<std::string> material_lines; ///< material values in scene units
    std::vector<std::string> warnings;
    std::size_t distinct_profiles = 0;
    DiffusionStats stats;
    double seconds = 0;
};

/// Describes the constant material (albedo, dmfp, sigma_s', sigma_a, ior in
/// scene units) as text lines; validates it (throws ValueError/UsageError).
std::vector<std::string> describe_material(const SsDiffusionOptions& options);

/// Runs the diffusion on a (merged) cloud. The output holds P, N, radius and
/// `color <output_channel>` (plus the input channels with keep_channels), and
/// the input's header matrices. Throws ValueError/FormatError on missing
/// channels, negative areas or impossible per-point material values.
PointCloud ssdiffusion(const PointCloud& input, const SsDiffusionOptions& options,
                       SsDiffusionReport* report = nullptr);

} // namespace sss
