// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file profile_report.h
/// A material's profiles against the random walk, channel by channel: what
/// `ssprofile` prints and scripts/accuracy-report collects.

#include <cstdint>
#include <string>
#include <vector>

#include "sss/diffusion/material.h"
#include "sss/diffusion/profile.h"
#include "sss/truth/half_space.h"
#include "sss/truth/profile_accuracy.h"

namespace sss {

struct ProfileReportOptions {
    /// The medium: a preset or coefficients (sigma_s', sigma_a, ior). A
    /// material given as albedo and dmfp is the medium the classic dipole
    /// infers from them (PRMan's reading).
    MaterialSpec material;
    std::vector<ProfileKind> profiles = {ProfileKind::Classic, ProfileKind::Better,
                                         ProfileKind::Burley, ProfileKind::Pbd,
                                         ProfileKind::Mc};
    uint64_t photons = 1'000'000; ///< for the three channels together
    /// Not a seed the Monte-Carlo table was made with (1-7), so that the mc
    /// profile is checked against an independent walk.
    uint64_t seed = 1001;
    int batches = 64;
};

struct ChannelReport {
    double alpha = 0.0;                    ///< reduced albedo alpha'
    double eta = 1.0;                      ///< relative index
    double sigma_t_mm = 0.0;               ///< sigma_t' (1/mm): l = 1 / sigma_t'
    HalfSpaceResult walk;                  ///< normal pencil beam, radii in l
    std::vector<Profile> profiles;         ///< sigma_t' = 1
    std::vector<ProfileAccuracy> accuracy; ///< per profile
};

struct ProfileReport {
    std::string material; ///< how the material was given
    std::vector<ProfileKind> kinds;
    ChannelReport channel[3];
};

/// Walks the three channels (one sweep: the same paths for all three) and
/// compares each profile. Throws ValueError for a medium that does not
/// scatter.
ProfileReport profile_report(const ProfileReportOptions& options);

/// The text table: per channel and profile L1w, dRd, the ratios by range of r,
/// and the walk's own noise.
std::string format_profile_report(const ProfileReport& report);

/// Per channel and annulus: r0, r1, the walk's flux and standard error
/// (single, multiple), each profile's flux.
std::string profile_report_csv(const ProfileReport& report);

/// One row per channel and profile (with a header): channel, alpha, eta,
/// walk_rd, walk_rd_error, walk_single, profile, l1w, l1w_noise, d_rd,
/// d_rd_error and the four range ratios; what scripts/accuracy-report reads.
std::string profile_report_tsv(const ProfileReport& report);

/// r R(r) of the walk and each profile, one panel per channel (log scale), as
/// an SVG picture.
std::string profile_report_svg(const ProfileReport& report);

} // namespace sss
