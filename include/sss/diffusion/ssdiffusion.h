#pragma once
/// \file ssdiffusion.h
/// The ptfilter -ssdiffusion job as one library call: channels in, material
/// resolved, diffusion evaluated, output cloud built.

#include <string>
#include <vector>

#include "sss/cloud/point_cloud.h"
#include "sss/diffusion/diffusion.h"
#include "sss/diffusion/material.h"
#include "sss/diffusion/profile.h"
#include "sss/util/error.h"

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

/// A channel the diffusion reads is missing from the input. role() says what
/// the channel is for, so a command line can name the option that sets it.
class MissingChannelError : public ValueError {
public:
    enum class Role {
        Radiance, ///< the irradiance to diffuse (radiance_channel)
        Albedo,   ///< per-point albedo (albedo_from_file)
        Dmfp      ///< per-point diffuse mean free path (dmfp_from_file)
    };
    MissingChannelError(Role role, std::string channel, std::string present);
    Role role() const { return m_role; }
    const std::string& channel() const { return m_channel; }
    /// "type name, ..." of the channels the input has, or "none".
    const std::string& present() const { return m_present; }

private:
    Role m_role;
    std::string m_channel;
    std::string m_present;
};

/// Runs the diffusion on a (merged) cloud. The output holds P, N, radius and
/// `color <output_channel>` (plus the input channels with keep_channels), and
/// the input's header matrices. Throws ValueError/FormatError on missing
/// channels, negative areas or impossible per-point material values.
PointCloud ssdiffusion(const PointCloud& input, const SsDiffusionOptions& options,
                       SsDiffusionReport* report = nullptr);

/// Part `part` (0-based) of `parts` of a ptfilter run split across machines
/// (ptfilter -part K/N): the output records of the part's receivers.
struct SsDiffusionPart {
    std::size_t total = 0; ///< points of the whole output
    std::size_t first = 0; ///< the part's first point in the space-filling order
    /// indices[k]: the index in the whole output of points' point k.
    std::vector<uint64_t> indices;
    /// The part's points, exactly as the whole output holds them (same
    /// channels, same header).
    PointCloud points;
};

/// Runs the diffusion of part `part` of `parts` of the receivers (a
/// contiguous range of the space-filling order, see evaluate_diffusion_part())
/// against the whole cloud. The part's records are bit for bit those of
/// ssdiffusion() for the same options, at any thread count (with -exact too).
/// Throws as ssdiffusion(), and ValueError for part >= parts. The input is
/// taken by value and freed once the part's records are out of it: pass it
/// with std::move to keep the peak memory of a part below the whole run's.
SsDiffusionPart ssdiffusion_part(PointCloud input, const SsDiffusionOptions& options,
                                 std::size_t part, std::size_t parts,
                                 SsDiffusionReport* report = nullptr);

/// A text naming every option that can change the output's values (the
/// resolved material and how it was given, profile, criterion, maxsolidangle,
/// exact, channel names, keep_channels), numbers written exactly: the parts of
/// one split job record a fingerprint of it, so parts made with other options
/// are refused when joined.
std::string ssdiffusion_signature(const SsDiffusionOptions& options);

} // namespace sss
