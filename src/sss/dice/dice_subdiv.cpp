// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file dice_subdiv.cpp
/// Dicing of Catmull–Clark subdivision meshes (the subdivision itself is in
/// subdivision.cpp): the mesh is refined until its control edges are at most
/// twice the dicing length, pushed to the limit surface, and every refined
/// quad is diced as a bilinear patch.

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <vector>

#include <glm/geometric.hpp>

#include "dice_common.h"
#include "mesh_common.h"
#include "subdivision.h"

namespace sss::detail {

namespace {

/// Refinement stops before a level would exceed this many faces (memory);
/// the bilinear dicing of the last level still reaches the dicing length.
constexpr std::size_t kMaxRefinedFaces = std::size_t(1) << 20;
constexpr int kMaxLevels = 8;

} // namespace

DicedSurface dice_subdivision(const Primitive& prim, const DiceControl& control,
                              DiceEstimate* estimate) {
    const Attributes& attr = attributes_of(prim);
    const Matrix4& m = prim.object_to_world;
    const NormalTransform normals(prim);
    // "N" is not used: the limit surface has exact normals of its own.
    SubdivMesh mesh = build_subdiv_mesh(prim);

    std::vector<glm::dvec3> world;
    std::vector<double> edge;
    auto measure = [&](const std::vector<glm::dvec3>& points) {
        world.resize(points.size());
        edge.resize(points.size());
        for (std::size_t i = 0; i < points.size(); ++i) {
            world[i] = to_world(m, points[i]);
            check_world_point(prim, world[i]);
            edge[i] = control.note(
                edge_length(prim, control, world[i], attr.shading_rate), prim);
        }
    };
    if (estimate) {
        // The cage's faces: the limit surface lies inside the cage, with
        // about its area. A face of n != 4 corners becomes n quads.
        measure(mesh.points);
        for (int f = 0; f < mesh.face_count(); ++f) {
            if (mesh.face_hole[f]) continue;
            const int c0 = mesh.face_start[f], c1 = mesh.face_start[f + 1];
            const auto at = [&](int c) -> const glm::dvec3& {
                return world[mesh.corner_vertex[c]];
            };
            glm::dvec3 newell(0.0);
            double perimeter = 0.0, e = std::numeric_limits<double>::infinity();
            for (int c = c0; c < c1; ++c) {
                const int next = c + 1 < c1 ? c + 1 : c0;
                newell += glm::cross(at(c) - at(c0), at(next) - at(c0));
                perimeter += glm::length(at(next) - at(c));
                e = std::min(e, edge[mesh.corner_vertex[c]]);
            }
            const int n = c1 - c0;
            *estimate += estimate_flat_face(0.5 * glm::length(newell), perimeter, e,
                                            n == 4 ? 1.0 : static_cast<double>(n));
        }
        return {};
    }
    // Uniform refinement until every control edge is at most twice the dicing
    // length at its ends; the first step is forced when faces are not quads.
    const std::size_t face_budget = std::min(kMaxRefinedFaces, control.max_micropolygons);
    for (int level = 0;; ++level) {
        if (mesh.all_quads()) {
            if (level >= kMaxLevels ||
                static_cast<std::size_t>(mesh.corner_count()) > face_budget)
                break;
            measure(mesh.points);
            bool fine = true;
            for (const auto& [a, b] : mesh.edge_vertices)
                if (glm::length(world[a] - world[b]) > 2.0 * std::min(edge[a], edge[b])) {
                    fine = false;
                    break;
                }
            if (control.note(fine ? 1.0 : 0.0, prim) > 0.5) break;
        }
        mesh = refine_subdiv_mesh(mesh);
    }

    const SubdivLimit limit = subdiv_limit(mesh);
    measure(limit.points);
    std::vector<glm::dvec3> corner_normal(limit.corner_normals.size());
    for (std::size_t c = 0; c < corner_normal.size(); ++c)
        corner_normal[c] = normals.geometric(limit.corner_normals[c]);

    // Sub-quad counts per face, then exact output sizes.
    const int nf = mesh.face_count();
    std::vector<std::array<uint32_t, 2>> pieces(nf, {0, 0});
    std::size_t total_mp = 0, total_vertices = 0;
    for (int f = 0; f < nf; ++f) {
        if (mesh.face_hole[f]) continue;
        const int* v = &mesh.corner_vertex[4 * f];
        const double e = std::min({edge[v[0]], edge[v[1]], edge[v[2]], edge[v[3]]});
        const double lu = std::max(glm::length(world[v[1]] - world[v[0]]),
                                   glm::length(world[v[2]] - world[v[3]]));
        const double lv = std::max(glm::length(world[v[3]] - world[v[0]]),
                                   glm::length(world[v[2]] - world[v[1]]));
        const std::size_t nu = piece_count(prim, control, lu, e);
        const std::size_t nv = piece_count(prim, control, lv, e);
        pieces[f] = {static_cast<uint32_t>(nu), static_cast<uint32_t>(nv)};
        total_mp += nu * nv;
        total_vertices += (nu + 1) * (nv + 1);
        check_budget(prim, control, total_mp);
    }

    const bool with_colors = !mesh.corner_colors.empty();
    DicedSurface out;
    allocate(prim, out, total_mp, total_vertices, 2 * total_mp, with_colors);
    SurfaceWriter writer{out, with_colors, control.grids};
    if (control.displace) {
        writer.displace = &control.displace;
        writer.prim = &prim;
    }
    if (control.grids) out.resize_parametric(total_mp, total_vertices);
    QuadDicer dicer;
    QuadCorners q;
    for (int f = 0; f < nf; ++f) {
        if (pieces[f][0] == 0) continue;
        for (int k = 0; k < 4; ++k) {
            const std::size_t c = 4 * static_cast<std::size_t>(f) + k;
            q.p[k] = world[mesh.corner_vertex[c]];
            q.normal[k] = corner_normal[c];
            if (with_colors) q.color[k] = glm::dvec3(mesh.corner_colors[c]);
        }
        q.fallback_normal = normals.geometric_from_world_cross(
            glm::cross(q.p[2] - q.p[0], q.p[3] - q.p[1]));
        dicer.dice(q, pieces[f][0], pieces[f][1], writer);
    }
    writer.finish();
    return out;
}

} // namespace sss::detail
