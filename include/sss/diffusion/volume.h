// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file volume.h
/// Diffusion in the volume a point cloud encloses (ptfilter -volume 1): the
/// cloud is taken as the closed, outward-oriented surface of the medium, the
/// diffusion equation is solved on a voxel grid of the enclosed volume with
/// the surface irradiance as source and Robin (partial-current) boundaries,
/// and absorbing blockers (bones) as black inclusions. Thin parts transmit,
/// small objects keep their light, and the light that leaves is never more
/// than the light that entered. See docs/volume.md.

#include <cstddef>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "sss/diffusion/material.h"

namespace sss {

class Progress;

/// Oriented samples of a closed surface: positions, outward normals and the
/// area each point stands for, all lengths in one unit.
struct SurfaceSamples {
    std::vector<glm::vec3> positions;
    std::vector<glm::vec3> normals;
    std::vector<float> areas;
};

/// How finely and how long the volume is solved.
struct VolumeOptions {
    /// Voxels per transport mean free path l = 1 / sigma_t' of the channel
    /// with the shortest one: the voxel size is l / this.
    double voxels_per_mfp = 2.0;
    /// At most this many voxels in the finest grid's box; a larger object
    /// gets larger voxels (and a warning when they exceed l).
    std::size_t max_voxels = 12'000'000;
    /// A point whose medium is thicker than thick_dmfp spread lengths below
    /// it keeps the surface profile's result; one thinner than thin_dmfp
    /// takes the volume's; in between the two are blended. A channel's
    /// spread length is its diffuse mean free path, but at least spread_mfp
    /// transport mean free paths.
    double thin_dmfp = 4.0, thick_dmfp = 6.0, spread_mfp = 5.0;
    /// Stop when the residual is below this fraction of the source.
    double tolerance = 1e-3;
    /// How the light entered, which decides how deep it first scatters and so
    /// how much a thin part transmits: a straight beam along the normal (a
    /// distant light overhead; the dipole's assumption) or diffuse light
    /// (cosine-weighted, a dome or an overcast sky). The irradiance alone
    /// does not say. Diffuse light also raises the profile's result (and the
    /// reflectance the volume is corrected to) by diffuse_reflectance_ratio().
    bool diffuse_light = false;
    Progress* progress = nullptr;
};

/// What the volume solve did, per channel.
struct VolumeReport {
    bool needed = false;           ///< some point is thin or a blocker was given
    double voxel = 0;              ///< finest voxel edge (the problem's unit)
    int dims[3] = {0, 0, 0};       ///< finest grid
    std::size_t unknowns = 0;      ///< medium voxels of the finest grid
    std::size_t thin_points = 0;   ///< points whose result is (partly) the volume's
    int levels = 0;                ///< grids of the cascade
    int iterations[3] = {0, 0, 0}; ///< conjugate-gradient steps, all levels
    /// Fluxes of the volume solve: scattered light entering, leaving through
    /// the surface, absorbed in the medium, absorbed by the blockers.
    glm::dvec3 flux_in{0.0}, flux_out{0.0}, flux_absorbed{0.0}, flux_blocked{0.0};
    /// The profile's half-space reflectance less the grid's, per channel.
    glm::dvec3 reflectance_correction{0.0};
    /// Under diffuse light: the factor the profile's result and reflectance
    /// were raised by (diffuse_reflectance_ratio()); 1 under straight light.
    glm::dvec3 diffuse_ratio{1.0};
    /// The range of the factors that bring the grid's transmission through a
    /// slab to transport theory's, over the thicknesses present, per channel.
    glm::dvec3 transmission_min{1.0}, transmission_max{1.0};
    double seconds = 0;
    std::vector<std::string> warnings;
};

/// The exitance at every surface point (the problem's positions, normals,
/// areas, transmitted irradiance, lengths in the unit of `channels`'
/// coefficients), blended with `profile_result` (the surface profile's
/// exitance at the same points) by each point's thickness. Points the volume
/// does not concern keep profile_result bit for bit (under straight light).
/// `profile_reflectance`: the profile's total diffuse reflectance per channel
/// (Profile::total()); the volume's own half-space reflectance is corrected to it at each
/// point in proportion to the point's irradiance (a negative value: no correction).
/// Throws ValueError for arrays of different sizes or a medium without scattering.
std::vector<glm::vec3> volume_diffusion(const SurfaceSamples& surface,
                                        const std::vector<glm::vec3>& irradiance,
                                        const ChannelCoefficients (&channels)[3],
                                        const glm::dvec3& profile_reflectance,
                                        const std::vector<SurfaceSamples>& blockers,
                                        const std::vector<glm::vec3>& profile_result,
                                        const VolumeOptions& options,
                                        VolumeReport* report = nullptr);

} // namespace sss
