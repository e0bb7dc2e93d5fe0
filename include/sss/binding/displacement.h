// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file displacement.h
/// Displacement shaders for the dicer: a Displacer gives each primitive with
/// a `Displacement` shader a DiceControl::displace hook that runs the shader
/// (ShadingContext::execute, BatchLayout::Grid on diced grids, Points on the
/// points the dicer adds between grids) and hands back the displaced
/// positions and normals. Shared by ptbake and render, which dice before they
/// build their ray tracers, so the traced triangles are the displaced ones.
///
/// `Attribute "displacementbound" "sphere" [r] "coordinatesystem" [space]`
/// only matters to renderers that bound primitives before displacing them
/// (PRMan clips displacement there); here it is a check: points moved
/// farther than the bound give one warning per primitive. Spaces: "object"
/// (the default) and "shader" scale r by the primitive's transform, others
/// ("world", "camera", "current") take it as a world length.

#include <atomic>
#include <cstddef>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <tbb/enumerable_thread_specific.h>

#include "sss/binding/scene_shaders.h"
#include "sss/dice/dice.h"
#include "sss/scene/scene.h"
#include "sss/shading/engine.h"

namespace sss {

/// Runs the scene's displacement shaders for dice_all. Thread-safe: one
/// ShadingContext per thread. Must outlive the dicing.
class Displacer {
public:
    Displacer(const Scene& scene, const SceneShaders& shaders,
              const ShadingResources& resources, ShadingServices& services);
    ~Displacer();
    Displacer(const Displacer&) = delete;
    Displacer& operator=(const Displacer&) = delete;

    /// The hook for primitive `primitive` (an index into scene.primitives),
    /// or an empty one when it has no displacement shader.
    DisplaceHook hook(std::size_t primitive);

    /// After dicing: one warning per primitive displaced beyond its
    /// displacementbound, and the count of points whose shader results were
    /// not finite (those points stay where they were), in primitive order.
    std::vector<std::string> warnings() const;

    /// The farthest any point of `primitive` moved (world units), so far.
    double max_displacement(std::size_t primitive) const;

private:
    void displace(std::size_t primitive, DisplaceGrid& grid);

    const Scene& m_scene;
    const SceneShaders& m_shaders;
    const ShadingResources& m_resources;
    ShadingServices& m_services;
    tbb::enumerable_thread_specific<std::unique_ptr<ShadingContext>> m_contexts;
    mutable std::mutex m_mutex;
    std::vector<double> m_max_moved;      ///< per primitive, world units
    std::vector<std::size_t> m_nonfinite; ///< per primitive
};

} // namespace sss
