// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file half_space.h
/// Module truth: the Monte-Carlo reference of light in a scattering medium,
/// the truth the diffusion profiles are measured against
/// (docs/accuracy.md). The medium is the reduced one a point-based tool
/// models: Jensen's sigma_s' and sigma_a with an isotropic phase function
/// (the similarity relation), so results near the entry point (r below one
/// transport mean free path) hold for that medium, not for the material's
/// real phase function.
/// May use: diffusion, dice, light, cloud, scene, util.
///
/// Units: lengths in transport mean free paths l = 1 / sigma_t'
/// (sigma_t' = sigma_s' + sigma_a), fluxes per unit flux transmitted into
/// the medium, as ptfilter's `_radiance_t` (in) and `_ssdiffusion` (out).

#include <cstdint>
#include <vector>

namespace sss {

/// How light enters the half-space z > 0 through its surface z = 0.
enum class Incidence {
    /// A normal pencil beam entering at the origin.
    Pencil,
    /// Uniform diffuse light (cosine-weighted outside), refracted in at the
    /// origin with the Fresnel transmission of each direction.
    Diffuse
};

/// A random walk in the half-space.
struct HalfSpaceOptions {
    double albedo = 0.99; ///< alpha' = sigma_s' / sigma_t', in [0, 1]
    double eta = 1.0;     ///< relative index of the medium (> 0)
    Incidence incidence = Incidence::Pencil;
    uint64_t photons = 1'000'000;
    /// Independent batches for the standard errors (and the unit of work
    /// of the threads); each is seeded from (seed, batch index), so results
    /// do not depend on the thread count.
    int batches = 64;
    uint64_t seed = 1;
    /// Radii (units of l) bounding the tallied annuli: increasing, the first
    /// 0. Empty: 0 to 10 in steps of 0.05.
    std::vector<double> edges;
    /// A path is stopped after this many collisions; its weight is counted
    /// as `truncated` (a half-space walk without absorption ends only at the
    /// boundary, after arbitrarily many steps).
    long max_collisions = 1'000'000;
};

/// Flux leaving through the surface per unit flux that entered, with
/// standard errors from the batch means.
struct HalfSpaceResult {
    std::vector<double> edges; ///< as used (n + 1 radii for n annuli)
    /// Per annulus: flux of light that scattered once / more than once.
    std::vector<double> single, multiple;
    std::vector<double> single_error, multiple_error; ///< standard errors
    /// Everything leaving beyond the last edge, all orders.
    double beyond = 0.0;
    /// Totals over all radii (the annuli and beyond).
    double total_single = 0.0, total_multiple = 0.0, total = 0.0;
    double total_single_error = 0.0, total_multiple_error = 0.0, total_error = 0.0;
    /// Weight absorbed in the medium (implicit capture; expected value under
    /// Russian roulette) and weight of paths stopped at max_collisions.
    double absorbed = 0.0, truncated = 0.0;
    uint64_t photons = 0;
    long collisions = 0; ///< all paths' collisions
};

/// Walks options.photons paths (multi-threaded through oneTBB, within the
/// caller's ThreadLimit). Free paths from sigma_t' = 1; at each collision
/// the weight is multiplied by the albedo (implicit capture) and a new
/// direction drawn uniformly on the sphere; Russian roulette below weight
/// 1e-4 (survival 1/10). At the surface the exact unpolarised Fresnel
/// reflectance decides between reflection and exit (total internal
/// reflection past the critical angle). Throws ValueError for options out
/// of range.
HalfSpaceResult walk_half_space(const HalfSpaceOptions& options);

/// The largest albedo a sweep accepts: its paths end after ln(floor) /
/// ln(albedo) collisions, which grows without bound towards 1.
constexpr double kMaxSweepAlbedo = 0.99999;

/// Many albedos from one set of paths ("white" Monte Carlo): the paths are
/// walked without absorption and a path that leaves after n collisions
/// counts albedo^n for each albedo. The results of neighbouring albedos
/// share their noise, which keeps a table over albedo smooth.
struct HalfSpaceSweepOptions {
    std::vector<double> albedos; ///< each in [0, kMaxSweepAlbedo]
    double eta = 1.0;
    Incidence incidence = Incidence::Pencil;
    uint64_t photons = 1'000'000;
    int batches = 64;
    uint64_t seed = 1;
    std::vector<double> edges; ///< as HalfSpaceOptions::edges
    /// A path ends when the largest albedo's weight albedo^n falls below
    /// this; the rest of its weight is counted as `truncated`.
    double weight_floor = 1e-12;
};

/// One result per albedo, in the order given (`absorbed` is what neither
/// left nor was truncated). Deterministic for any thread count.
std::vector<HalfSpaceResult> walk_half_space_sweep(const HalfSpaceSweepOptions& options);

/// Unpolarised Fresnel reflectance for light arriving at cosine `cos_in`
/// (in (0, 1]) from a medium of index n_in onto one of index n_out; 1 past
/// the critical angle.
double fresnel_reflectance(double cos_in, double n_in, double n_out);

/// Light scattered exactly once under a normal pencil beam that leaves
/// through the annulus r0 <= r < r1 (units of l; r1 may be infinity), per
/// unit flux entering: the first collision at depth z (density e^-z), an
/// isotropic scattering, no collision on the way back, the exit Fresnel
/// transmission. Computed by quadrature (relative error below 1e-6).
double single_scattering_flux(double albedo, double eta, double r0, double r1);

} // namespace sss
