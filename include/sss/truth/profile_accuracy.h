// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file profile_accuracy.h
/// The diffusion profiles held against the half-space random walk, and the
/// Monte-Carlo profile table made from it (docs/accuracy.md).

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "sss/diffusion/profile.h"
#include "sss/truth/half_space.h"

namespace sss {

/// Ranges of r (units of l) the report's flux ratios are given for.
inline const std::vector<double> kAccuracyRanges = {0.0, 0.1, 1.0, 3.0, 10.0};

/// One profile against one walk (normal pencil beam, per unit flux entering).
struct ProfileAccuracy {
    /// L1 error of r R(r) over r in [0, 10 l]: sum over the walk's annuli
    /// of |model flux - walk flux| / sum of the walk's flux.
    double l1w = 0.0;
    /// The walk's own share of l1w: the mean absolute noise of its annuli,
    /// sqrt(2 / pi) sum sigma / sum flux (what a perfect model would score).
    double l1w_noise = 0.0;
    /// Total reflectance: model / walk - 1, and the walk's relative error.
    double d_rd = 0.0, d_rd_error = 0.0;
    /// model / walk flux within each of kAccuracyRanges' ranges.
    std::vector<double> range_ratio;
};

/// Annulus fluxes of a profile whose lengths are in units of l
/// (sigma_t' = 1), on the walk's annuli.
std::vector<double> profile_annulus_flux(const Profile& p,
                                         const std::vector<double>& edges);

/// Compares the profile (sigma_t' = 1) with the walk; only annuli within
/// [0, 10] count for l1w (the walk's edges must reach 10).
ProfileAccuracy compare_with_walk(const Profile& p, const HalfSpaceResult& walk);

/// How the Monte-Carlo profile table is made.
struct McTableOptions {
    std::vector<double> eta;      ///< relative indices, increasing
    std::vector<double> albedo;   ///< reduced albedos, increasing, < kMaxSweepAlbedo
    uint64_t photons = 4'000'000; ///< per eta
    uint64_t seed = 1;
    int batches = 64;
    /// A ratio whose walk annulus has a relative standard error above this
    /// is replaced by its inner neighbour's (the far tail at low albedo,
    /// where there is almost no light).
    double max_relative_error = 0.03;
};

/// The default nodes (what scripts/make-mc-table uses).
McTableOptions default_mc_table_options();

/// Walks every eta (one sweep over all albedos each) and returns the
/// table's text (the format diffusion/mc_table.h reads). `progress` is called
/// after each eta with the fraction done.
std::string make_mc_table(const McTableOptions& options,
                          const std::function<void(double)>& progress = {});

} // namespace sss
