// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file slab_transport.h
/// The light a plane slab of a reduced isotropic medium sends back and
/// through, from transport theory rather than diffusion: the reference the
/// volume's thin parts are corrected to.

namespace sss {

/// Scattered light leaving a slab per unit flux entering it through the top
/// face (light that crosses without a collision is not counted).
struct SlabLight {
    double reflectance = 0;   ///< out through the lit face
    double transmittance = 0; ///< out through the far face
};

/// The slab of `thickness` transport mean free paths, single-scattering
/// albedo `alpha` (reduced), relative index `eta` on both faces (exact
/// Fresnel, total internal reflection), lit at normal incidence or by
/// diffuse (cosine-weighted) light. Solved as the integral equation of the
/// collision density: cells of at most 0.15 mean free paths, kernels
/// integrated over each cell exactly and over the direction cosine by Gauss
/// rules on both sides of the critical angle, every Fresnel reflection
/// summed. Agrees with the Monte-Carlo walk to its noise (about 1 %).
/// Throws ValueError for arguments outside alpha in [0, 1), eta >= 1,
/// thickness > 0.
SlabLight slab_transport(double alpha, double eta, double thickness, bool diffuse);

/// The share of the light entering a medium (straight or diffuse, refracted
/// at relative index eta) whose first collision lies above `depth` transport
/// mean free paths.
double first_collision_share(double eta, double depth, bool diffuse);

/// How much more light a deep slab (30 transport mean free paths) sends back
/// under diffuse light than under light entering straight: what the
/// surface profiles, which assume the latter, miss under a dome.
double diffuse_reflectance_ratio(double alpha, double eta);

} // namespace sss
