// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file profile.h
/// Radial diffusion profiles R(r): diffuse reflectance per unit area at
/// distance r from a unit-power point source on a flat surface. Each profile
/// knows its closed-form disk integral, used for exact self and near terms.

#include <memory>
#include <string>
#include <string_view>

#include "sss/diffusion/material.h"

namespace sss {

/// The profiles ptfilter offers (-profile).
enum class ProfileKind {
    Classic, ///< Jensen et al. 2001 dipole (default; PRMan's)
    Better,  ///< d'Eon 2012 "better dipole" (Grosjean D, moment boundary)
    Burley,  ///< Christensen-Burley 2015 normalized diffusion (dmfp fit)
    /// Photon beam diffusion (Habel, Christensen, Jarosz 2013) with the exact
    /// single scattering.
    Pbd,
    /// Tabulated from the project's half-space random walk
    /// (data/profiles/mc_halfspace.tbl).
    Mc
};

class RadialCurve;

/// Parses "classic" / "dipole", "better" / "betterdipole", "burley" /
/// "normalized", "pbd" / "beam", "mc" / "montecarlo".
bool parse_profile_kind(std::string_view name, ProfileKind& out);
const char* profile_kind_name(ProfileKind kind);

/// One colour channel's profile, all lengths in scene units.
class Profile {
public:
    Profile() = default;

    /// From physical coefficients (scene units). Burley uses the classic
    /// albedo and dmfp of those coefficients.
    static Profile from_coefficients(ProfileKind kind, const ChannelCoefficients& c);
    /// From total diffuse reflectance and dmfp (scene units). Each profile
    /// inverts its own total reflectance, so a uniformly lit plane gives
    /// albedo x E whatever the profile. albedo in [0, 1).
    static Profile from_albedo_dmfp(ProfileKind kind, double albedo, double dmfp,
                                    double ior);

    ProfileKind kind() const { return m_kind; }
    /// R(r), per unit area (scene units^-2). Finite at r = 0 for the dipoles,
    /// +inf for Burley, pbd and mc (their single scattering peaks as 1/r).
    double eval(double r) const;
    /// Integral of R over a disk of radius rho centred on the source:
    /// 2 pi \int_0^rho r R(r) dr (closed form).
    double disk(double rho) const;
    /// Total diffuse reflectance, disk(infinity).
    double total() const { return m_total; }
    /// Length below which R stops growing like a power law (z_r for the
    /// dipoles, 0 for Burley, pbd and mc): the scale the near field must
    /// resolve.
    double core_length() const { return m_core; }
    /// Diffuse mean free path 1/sigma_tr (inf when sigma_a = 0).
    double dmfp() const { return m_dmfp; }
    /// sigma_tr, the exponential decay rate of the far tail.
    double sigma_tr() const { return m_sigma_tr; }
    /// Distance beyond which the remaining reflectance is below
    /// fraction * total (used to size tables and cut far nodes).
    double cutoff_radius(double fraction) const;

    /// Physical quantities for -progress reports.
    double alpha_prime() const { return m_alpha; }
    double sigma_t_prime() const { return m_sigma_t; }
    double ior() const { return m_ior; }

private:
    ProfileKind m_kind = ProfileKind::Classic;
    double m_alpha = 0;        // reduced albedo (dipoles)
    double m_sigma_t = 0;      // sigma_t' (dipoles)
    double m_sigma_tr = 0;     // effective transport coefficient
    double m_zr = 0, m_zv = 0; // dipole depths (zv signed for Better)
    double m_D = 0;            // diffusion coefficient (Better)
    double m_ce = 0, m_cphi = 0;
    double m_scale = 0; // alpha'/(4 pi) or alpha'^2/(4 pi); Burley: A
    double m_d = 0;     // Burley shape length
    double m_total = 0;
    double m_core = 0;
    double m_dmfp = 0;
    double m_ior = 1.3;
    std::shared_ptr<const RadialCurve> m_curve; // pbd, mc: rho R(rho), rho = r sigma_t'
};

/// Three channels (r, g, b).
struct RgbProfile {
    Profile channel[3];
};

} // namespace sss
