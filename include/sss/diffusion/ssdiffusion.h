// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file ssdiffusion.h
/// The ptfilter -ssdiffusion job as one library call: channels in, material
/// resolved, diffusion evaluated, output cloud built.

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "sss/cloud/point_cloud.h"
#include "sss/cloud/point_cloud_io.h"
#include "sss/diffusion/diffusion.h"
#include "sss/diffusion/material.h"
#include "sss/diffusion/profile.h"
#include "sss/diffusion/volume.h"
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
    /// Light carried through the volume the cloud encloses (volume.h):
    /// thin parts, small objects, blockers. Off: the surface profile alone.
    bool volume = false;
    /// Clouds sampling absorbing inclusions (bones), normals pointing out of
    /// them; any blocker turns the volume diffusion on.
    std::vector<std::string> blockers;
    VolumeOptions volume_options;
};

/// The computed values at a glance (ptfilter -progress 2): per channel over
/// every point, and a few points spread evenly over the output.
struct ValueSummary {
    std::size_t count = 0; ///< points summarised
    glm::dvec3 min{0.0}, mean{0.0}, max{0.0};
    /// (index in the whole output, value), indices in increasing order.
    std::vector<std::pair<uint64_t, glm::vec3>> sample;
};

/// What happened, for -progress reports.
struct SsDiffusionReport {
    std::vector<std::string> material_lines; ///< material values in scene units
    std::vector<std::string> warnings;
    std::size_t distinct_profiles = 0;
    DiffusionStats stats;
    double seconds = 0;
    ValueSummary values; ///< the output channel's values (a part's: the part's)
    VolumeReport volume; ///< the volume diffusion's (volume or blockers)
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
    /// `inputs`: the files the channel is missing from ("" when not known).
    MissingChannelError(Role role, std::string channel, std::string present,
                        std::string inputs = "");
    Role role() const { return m_role; }
    /// The input files, as run_filter_job() names them ("" when not known).
    const std::string& inputs() const { return m_inputs; }
    const std::string& channel() const { return m_channel; }
    /// "type name, ..." of the channels the input has, or "none".
    const std::string& present() const { return m_present; }

private:
    Role m_role;
    std::string m_channel;
    std::string m_present;
    std::string m_inputs;
};

/// Runs the diffusion on a (merged) cloud. The output holds P, N, radius and
/// `color <output_channel>` (plus the input channels with keep_channels), and
/// the input's header matrices. Throws ValueError/FormatError on missing
/// channels, negative areas or impossible per-point material values.
PointCloud ssdiffusion(const PointCloud& input, const SsDiffusionOptions& options,
                       SsDiffusionReport* report = nullptr);

/// ptfilter -ssdiffusion from files to a file, in little memory: the inputs
/// are read a chunk at a time for the channels the diffusion reads, the
/// evaluation consumes its problem (evaluate_diffusion(DiffusionProblem&&)),
/// and the output is written from the results while the inputs are read a
/// second time for the channels it copies, so that no whole cloud is held
/// (about 130 bytes per point at the peak, the octree's). The output is byte
/// for byte what ssdiffusion() of the merged inputs, written with
/// write_point_cloud(), gives. Three steps, so that a caller can tell errors
/// of the inputs from errors of the filter.
class SsDiffusionFiles {
public:
    /// Opens the inputs and reads their headers. Throws as read_point_cloud(),
    /// and ValueError when two inputs have a channel of one name and two types.
    SsDiffusionFiles(std::vector<std::string> inputs, SsDiffusionOptions options);
    ~SsDiffusionFiles();
    SsDiffusionFiles(const SsDiffusionFiles&) = delete;
    SsDiffusionFiles& operator=(const SsDiffusionFiles&) = delete;

    /// Reads the points (FormatError, IoError as read_point_cloud()) and then
    /// evaluates the diffusion (throws as ssdiffusion()). Timings and
    /// statistics go to the report; read_seconds() is the reading's share.
    void filter(SsDiffusionReport* report = nullptr);
    /// Writes the output atomically (extension as write_point_cloud()).
    /// Throws IoError when an input changed since filter() read it.
    void write(const std::string& path, const PointCloudWriteOptions& options = {});

    /// Points of the merged inputs (known after filter()).
    std::size_t size() const { return m_points; }
    /// Seconds filter() spent reading the inputs.
    double read_seconds() const { return m_read_seconds; }

private:
    struct Input;
    std::vector<std::string> m_paths;
    SsDiffusionOptions m_options;
    std::vector<Input> m_inputs;
    PointCloud m_merged; ///< the merged inputs' header: channels without data
    std::vector<glm::vec3> m_result;
    Bounds3 m_bounds;
    float m_max_radius = 0.0f;
    std::size_t m_points = 0;
    double m_read_seconds = 0;
    bool m_filtered = false;
};

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
