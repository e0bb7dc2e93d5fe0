// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
// ptfilter -volume / -blocker inside the -ssdiffusion job: the points the
// volume diffusion needs, kept before the octree consumes the problem, and
// the step that blends its result into the profile's.

#include <vector>

#include <glm/vec3.hpp>

#include "sss/diffusion/diffusion.h"
#include "sss/diffusion/ssdiffusion.h"
#include "sss/diffusion/volume.h"

namespace sss::diffusion_detail {

/// What the volume solve reads of a problem (in mm, as the problem).
struct VolumeInput {
    SurfaceSamples surface;
    std::vector<glm::vec3> irradiance;
};

/// A copy of the problem's points when options ask for the volume, else empty.
VolumeInput volume_input(const DiffusionProblem& pb, const SsDiffusionOptions& options);

/// Checks that the options' volume settings can run (a constant material,
/// blockers whose headers read and that hold points): throws ValueError,
/// IoError, FormatError before any work.
void check_volume_options(const SsDiffusionOptions& options);

/// Replaces `result` (the profile's exitance, the problem's order) by the
/// volume diffusion's where the shape asks for it; reports into rep.volume.
void apply_volume(const SsDiffusionOptions& options, VolumeInput&& input,
                  std::vector<glm::vec3>& result, SsDiffusionReport& rep);

} // namespace sss::diffusion_detail
