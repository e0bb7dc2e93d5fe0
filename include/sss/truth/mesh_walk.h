// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file mesh_walk.h
/// The Monte-Carlo random walk of light inside real geometry: the reduced
/// isotropic medium (as half_space.h) bounded by closed triangle meshes, lit
/// by a baked point cloud's transmitted irradiance, with the exact Fresnel
/// boundary. Its per-point exitance is the truth ptfilter's `_ssdiffusion`
/// is measured against on curved and thin shapes, where the half-space
/// assumption of the diffusion profiles does not hold.
///
/// Units: lengths in scene units, coefficients per scene unit, fluxes in the
/// source's units (irradiance times area).

#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

namespace sss {

/// A triangle mesh: 3 vertex indices per triangle. Its orientation does not
/// matter.
struct TriangleMesh {
    std::vector<glm::vec3> vertices;
    std::vector<uint32_t> triangles;
};

/// The light entering the medium: a baked point cloud's points as ptfilter
/// reads them. Every array has one entry per point.
struct MeshWalkSource {
    std::vector<glm::vec3> positions; ///< on the medium's surface
    std::vector<glm::vec3> normals;   ///< outward (any length but zero)
    std::vector<float> areas;         ///< the surface each point stands for (>= 0)
    /// Irradiance transmitted into the surface (ptfilter's `_radiance_t`),
    /// per channel, >= 0.
    std::vector<glm::vec3> irradiance;
};

/// A walk in the medium bounded by `medium`.
struct MeshWalkOptions {
    /// Closed surfaces bounding the scattering medium (at least one; they
    /// must not overlap).
    std::vector<TriangleMesh> medium;
    /// Closed absorbing inclusions inside the medium (bones): light that
    /// reaches them is absorbed there (`flux_blocked`).
    std::vector<TriangleMesh> blockers;
    /// Reduced scattering and absorption per channel, per scene unit (>= 0).
    glm::dvec3 sigma_s_prime{1.0}, sigma_a{0.0};
    double eta = 1.3; ///< relative index of the medium (> 0)
    /// Paths per channel (each channel is walked on its own).
    uint64_t photons = 1'000'000;
    /// Independent batches for the standard errors (and the unit of work of
    /// the threads); each is seeded from (seed, channel, batch index), so
    /// results do not depend on the thread count.
    int batches = 64;
    uint64_t seed = 1;
    /// A path is stopped after this many collisions; its weight is counted
    /// as `flux_truncated`.
    long max_collisions = 1'000'000;
    /// Light entering at normal incidence (refracted straight in), else
    /// diffuse (cosine-weighted outside times the Fresnel transmission).
    bool normal_incidence = false;
    /// Light that leaves without a single collision (through a thin part)
    /// is not tallied at the points but as `flux_unscattered`: the
    /// scattered light a diffusion model describes.
    bool scattered_only = false;
};

/// Fluxes per channel, with standard errors from the batch means.
struct MeshWalkResult {
    /// Per source point: the flux leaving the surface nearest to it (each
    /// point with an area stands for the surface around it), divided by its
    /// area; comparable to ptfilter's `_ssdiffusion`. 0 for points without
    /// area.
    std::vector<glm::dvec3> exitance;
    std::vector<glm::dvec3> exitance_error; ///< standard errors
    /// Flux entering (the sum of area times irradiance), leaving through the
    /// surface, absorbed by the blockers, absorbed in the medium (implicit
    /// capture; expected value under Russian roulette), of paths stopped at
    /// max_collisions, and of paths lost to numerical escapes (cracks in a
    /// mesh that is not closed, a path found outside the medium's bounding
    /// box; 0 for a closed mesh).
    glm::dvec3 flux_in{0.0}, flux_out{0.0}, flux_blocked{0.0}, flux_absorbed{0.0},
        flux_truncated{0.0}, flux_lost{0.0};
    /// With scattered_only: the light that left without a collision.
    glm::dvec3 flux_unscattered{0.0};
    /// Standard errors of the totals.
    glm::dvec3 flux_out_error{0.0}, flux_blocked_error{0.0}, flux_absorbed_error{0.0},
        flux_truncated_error{0.0};
    uint64_t photons = 0;    ///< per channel walked (channels without flux are not)
    uint64_t collisions = 0; ///< all paths' collisions, all channels
};

/// Walks options.photons paths per channel with flux (multi-threaded through
/// oneTBB, within the caller's ThreadLimit; deterministic for any thread
/// count).
///
/// Each path starts at a source point chosen with probability proportional
/// to its flux (every path carries the same weight, so `flux_in` is exact),
/// uniformly within the point's disk (radius sqrt(area / pi)) projected
/// onto the surface, just inside it. Its direction is cosine-weighted
/// outside times the Fresnel transmission, refracted in by Snell's law (the
/// irradiance given is already the transmitted one). Free paths from
/// sigma_t' = sigma_s' + sigma_a; at each collision the weight is
/// multiplied by the albedo sigma_s' / sigma_t' (implicit capture) and a new
/// direction drawn uniformly on the sphere; Russian roulette below weight
/// 1e-4 of a path's start (survival 1/10). At a medium mesh the exact
/// unpolarised Fresnel reflectance decides between reflection and exit;
/// an exit is tallied at the source point nearest to it.
///
/// Throws ValueError for options out of range, meshes the ray tracer
/// refuses, source arrays of different sizes, a source point that is not
/// finite, a negative area or irradiance, and a source without flux.
MeshWalkResult walk_mesh(const MeshWalkOptions& options, const MeshWalkSource& source);

} // namespace sss
