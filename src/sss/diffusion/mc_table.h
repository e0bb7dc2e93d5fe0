// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file mc_table.h
/// The Monte-Carlo profile: photon beam diffusion corrected by the ratio of
/// the half-space random walk to it, tabulated over (eta, alpha', rho)
/// (data/profiles/mc_halfspace.tbl, written by scripts/make-mc-table and
/// compiled into the library).

#include <string>
#include <vector>

namespace sss::diffusion_detail {

/// The table as read: ratio[(e * albedos + a) * rhos + k] at eta[e],
/// albedo[a] and rho[k] (the annuli's mean radii, units of l).
struct McTable {
    std::vector<double> eta, albedo, rho, ratio;
    std::string source; ///< the header line naming how it was made
};

/// Parses the table's text (throws FormatError with the line).
McTable parse_mc_table(const std::string& text);

/// The table compiled into the library.
const McTable& mc_table();

/// Throws ValueError when eta is outside the table's range.
void check_mc_range(double eta);

/// The walk-to-beam-diffusion ratio at (alpha, eta, rho): linear in eta, in
/// sqrt(1 - alpha) and in ln rho between the table's nodes, constant past its
/// ends in alpha and rho.
double mc_ratio(const McTable& t, double alpha, double eta, double rho);

/// f = rho R of the Monte-Carlo profile.
double mc_curve_value(double alpha, double eta, double rho);

} // namespace sss::diffusion_detail
