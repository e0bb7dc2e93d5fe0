// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file shadow_map.h
/// Module light: depth-map shadows. A ShadowMap is the depth a light's
/// camera saw (a zfile or shadow map, docs/scene.md), and shadow_fraction()
/// the percentage-closer filtered lookup of RSL's shadow() and of the
/// standard lights' "shadowname". Reading the files is binding's business
/// (TextureLibrary); this is the arithmetic both the shaders and the C++
/// lights share.

#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "sss/scene/scene.h"

namespace sss {

/// The depth stored where a shadow camera saw no surface: farther than any
/// point, so such texels shadow nothing (finite, so no file holds Inf).
inline constexpr float kNoSurfaceDepth = 1e30f;

/// PRMan's default shadow bias (camera-space units of the map's camera),
/// used when neither the call nor `Option "shadow" "bias"` gives one.
inline constexpr float kDefaultShadowBias = 0.225f;

/// A depth map as a light's camera saw it.
struct ShadowMap {
    int width = 0, height = 0;
    /// Camera-space z of the nearest surface per texel, rows top to bottom
    /// (kNoSurfaceDepth where there is none).
    std::vector<float> depth;
    /// World to the map camera's space (RenderMan's: z away from the eye).
    Matrix4 world_to_camera{1.0};
    /// World to the map's screen: after the division by w the map covers
    /// x, y in [-1, 1], x to the right, y up (column-vector matrices, as
    /// every sss Matrix4).
    Matrix4 world_to_screen{1.0};

    float at(int x, int y) const { return depth[std::size_t(y) * width + x]; }
};

/// How one shadow lookup filters (the token-value options of shadow()).
struct ShadowLookup {
    /// Depth offset (map camera units): a point is shadowed where its depth
    /// minus bias lies behind the stored depth.
    float bias = kDefaultShadowBias;
    /// Blur in map units (1 = the whole map), added to the footprint.
    float sblur = 0.0f, tblur = 0.0f;
    /// Multipliers of the footprint (the point's own extent on the map).
    float swidth = 1.0f, twidth = 1.0f;
    /// Depth comparisons over the filter region (stratified, jittered).
    int samples = 1;
    /// "gaussian" weights the samples by their distance from the centre;
    /// any other name ("box", the default) weighs them alike.
    bool gaussian = false;
};

/// The fraction of world point `p` in shadow (0 = lit, 1 = in shadow) on
/// `map`, percentage-closer filtered: `lookup.samples` depth comparisons
/// over the box of the point's footprint (its world differences dp_du,
/// dp_dv projected on the map, times swidth/twidth) plus the blur, at least
/// one texel wide. Each sample falls on one texel; outside the map it is
/// lit. Points behind the map's camera (camera z <= 0) or projecting outside
/// the map are lit. The jitter is a hash of p and `seed`: the same answer
/// for the same point whatever the thread or batch. Non-finite input gives 0.
float shadow_fraction(const ShadowMap& map, const glm::dvec3& p, const glm::dvec3& dp_du,
                      const glm::dvec3& dp_dv, const ShadowLookup& lookup,
                      uint64_t seed = 0);

/// The bias a scene gives shadow lookups that name none: `Option "shadow"
/// "bias"`, else the mean of "bias0" and "bias1" (PRMan's older pair; one
/// of them alone counts as given), else kDefaultShadowBias.
float scene_shadow_bias(const Scene& scene);

} // namespace sss
