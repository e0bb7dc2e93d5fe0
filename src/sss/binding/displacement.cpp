// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file displacement.cpp
/// Displacement shaders run for the dicer (displacement.h).

#include "sss/binding/displacement.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>
#include <glm/vec4.hpp>

namespace sss {

namespace {

/// splitmix64: the seed of a primitive's n-th hook call.
uint64_t mix(uint64_t x) {
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

/// The displacement bound of a primitive in world units, or a negative
/// number when it has none.
double world_bound(const Primitive& prim, const Scene& scene) {
    const Attributes& attr = attributes_of(prim);
    const auto it = attr.groups.find("displacementbound");
    if (it == attr.groups.end() || !it->second.has("sphere")) return -1.0;
    const double r = it->second.get_float("sphere", 0.0);
    const std::string space = it->second.get_string("coordinatesystem", "object");
    Matrix4 m(1.0);
    if (space == "object")
        m = prim.object_to_world;
    else if (space == "shader" && attr.displacement)
        m = attr.displacement->shader_to_world;
    else if (space == "shader" && attr.surface) // a class's displacement method
        m = attr.surface->shader_to_world;
    else if (auto cs = scene.coordinate_systems.find(space);
             cs != scene.coordinate_systems.end())
        m = cs->second;
    // The largest stretch of the space's axes.
    const glm::dmat3 l(m);
    const double scale =
        std::max({glm::length(l[0]), glm::length(l[1]), glm::length(l[2])});
    return std::abs(r) * scale;
}

} // namespace

Displacer::Displacer(const Scene& scene, const SceneShaders& shaders,
                     const ShadingResources& resources, ShadingServices& services)
    : m_scene(scene), m_shaders(shaders), m_resources(resources), m_services(services),
      m_contexts(
          [this] { return std::make_unique<ShadingContext>(m_resources, m_services); }),
      m_max_moved(scene.primitives.size(), 0.0), m_nonfinite(scene.primitives.size(), 0) {
}

Displacer::~Displacer() = default;

DisplaceHook Displacer::hook(std::size_t primitive) {
    if (primitive >= m_shaders.displacement_of.size() ||
        !m_shaders.displacement_of[primitive])
        return {};
    return [this, primitive](DisplaceGrid& grid) { displace(primitive, grid); };
}

void Displacer::displace(std::size_t primitive, DisplaceGrid& grid) {
    const Primitive& prim = m_scene.primitives[primitive];
    const ShaderInstance& shader = *m_shaders.displacement_of[primitive];
    const Camera& camera = m_scene.options.camera;
    const glm::dmat4& to_camera = camera.world_to_camera;
    const glm::dmat4 to_world = glm::inverse(to_camera);
    const glm::dmat3 vector_to_camera(to_camera);
    const glm::dmat3 normal_to_camera = glm::transpose(glm::inverse(vector_to_camera));
    const glm::dmat3 normal_to_world = glm::transpose(vector_to_camera);
    const std::size_t n = grid.size();
    if (n == 0) return;

    ShadingBatch batch;
    batch.size = n;
    // A grid one point wide has no differences across it: as unrelated
    // points its derivatives come from dPdu and dPdv instead of being 0.
    batch.layout =
        grid.grid && grid.nu > 1 && grid.nv > 1 ? BatchLayout::Grid : BatchLayout::Points;
    batch.nu = grid.nu;
    batch.nv = grid.nv;
    batch.primitive = &prim;
    batch.seed = mix(mix(primitive) ^ grid.sequence);
    batch.P.resize(n);
    batch.N.resize(n);
    batch.Ng.resize(n);
    batch.I.resize(n);
    batch.dPdu.resize(n);
    batch.dPdv.resize(n);
    for (std::size_t k = 0; k < n; ++k) {
        const glm::dvec3 pc(to_camera * glm::dvec4(glm::dvec3(grid.P[k]), 1.0));
        batch.P[k] = glm::vec3(pc);
        batch.I[k] = camera.perspective ? glm::vec3(pc) : glm::vec3(0.0f, 0.0f, 1.0f);
        const auto unit = [&](const glm::vec3& v) {
            const glm::dvec3 c = normal_to_camera * glm::dvec3(v);
            const double len = glm::length(c);
            return glm::vec3(len > 0.0 ? c / len : c);
        };
        batch.N[k] = unit(grid.N[k]);
        batch.Ng[k] = unit(grid.Ng[k]);
        batch.dPdu[k] = glm::vec3(vector_to_camera * glm::dvec3(grid.dPdu[k]));
        batch.dPdv[k] = glm::vec3(vector_to_camera * glm::dvec3(grid.dPdv[k]));
    }
    batch.u = grid.u;
    batch.v = grid.v;
    batch.du = grid.du;
    batch.dv = grid.dv;
    batch.s = grid.s;
    batch.t = grid.t;

    ShadingContext& context = *m_contexts.local();
    // A class shader bound by Surface runs its displacement method here.
    context.execute_as(ShaderKind::Displacement, shader, batch);
    const std::size_t nonfinite = context.nonfinite_points();

    double moved = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
        // The engine writes non-finite results as 0: such points stay put.
        if (nonfinite > 0 && batch.P[k] == glm::vec3(0.0f)) {
            grid.N[k] = glm::vec3(0.0f); // the dicer keeps its own normal
            continue;
        }
        const glm::dvec3 pw(to_world * glm::dvec4(glm::dvec3(batch.P[k]), 1.0));
        const glm::dvec3 nw = normal_to_world * glm::dvec3(batch.N[k]);
        moved = std::max(moved, glm::length(pw - glm::dvec3(grid.P[k])));
        grid.P[k] = glm::vec3(pw);
        const double len = glm::length(nw);
        grid.N[k] =
            len > 0.0 && std::isfinite(len) ? glm::vec3(nw / len) : glm::vec3(0.0f);
    }
    std::lock_guard<std::mutex> lock(m_mutex);
    m_max_moved[primitive] = std::max(m_max_moved[primitive], moved);
    m_nonfinite[primitive] += nonfinite;
}

double Displacer::max_displacement(std::size_t primitive) const {
    std::lock_guard<std::mutex> lock(m_mutex);
    return primitive < m_max_moved.size() ? m_max_moved[primitive] : 0.0;
}

std::vector<std::string> Displacer::warnings() const {
    std::lock_guard<std::mutex> lock(m_mutex);
    std::vector<std::string> out;
    for (std::size_t i = 0; i < m_max_moved.size(); ++i) {
        if (!m_shaders.displacement_of[i]) continue;
        const Primitive& prim = m_scene.primitives[i];
        const std::string where =
            prim.source + ": " + m_shaders.displacement_of[i]->program().name;
        const double bound = world_bound(prim, m_scene);
        // A little slack for rounding (points are floats).
        if (m_max_moved[i] > 1.001 * std::max(bound, 0.0) + 1e-6) {
            char buf[256];
            if (bound < 0.0)
                std::snprintf(buf, sizeof buf,
                              " moves points up to %.4g without a displacementbound "
                              "(PRMan would clip them; give Attribute "
                              "\"displacementbound\" \"sphere\" [r])",
                              m_max_moved[i]);
            else
                std::snprintf(buf, sizeof buf,
                              " moves points up to %.4g, beyond its displacementbound "
                              "%.4g (world units; PRMan clips there)",
                              m_max_moved[i], bound);
            out.push_back(where + buf);
        }
        if (m_nonfinite[i] > 0)
            out.push_back(where + ": " + std::to_string(m_nonfinite[i]) +
                          " points gave NaN or infinity and were written as 0");
    }
    return out;
}

} // namespace sss
