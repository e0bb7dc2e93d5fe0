// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
// Internal: Catmull–Clark subdivision of a RenderMan SubdivisionMesh, used by
// dice_subdiv.cpp. Object space throughout; dicing decisions (how many levels)
// belong to the caller.

#include <array>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "sss/scene/scene.h"

namespace sss::detail {

/// A polygon mesh with the edge topology and sharpness Catmull–Clark needs.
/// Faces are runs of corners: corners face_start[f] .. face_start[f+1]-1, in
/// the face's winding order. Corner c's edge joins its vertex to the next
/// corner's vertex.
struct SubdivMesh {
    std::vector<glm::dvec3> points;       ///< control points
    std::vector<int> face_start;          ///< face count + 1 offsets
    std::vector<int> corner_vertex;       ///< vertex of each corner
    std::vector<int> corner_edge;         ///< edge leaving each corner
    std::vector<glm::vec3> corner_colors; ///< Cs per corner; empty = none
    std::vector<std::array<int, 2>> edge_vertices;
    std::vector<std::array<int, 2>> edge_faces; ///< [1] == -1 on a boundary edge
    std::vector<float> edge_sharpness;          ///< infinite on boundary edges
    std::vector<float> vertex_sharpness;        ///< corner tags (and pinned corners)
    std::vector<uint8_t> face_hole;             ///< "hole" tag: not diced

    int face_count() const { return static_cast<int>(face_start.size()) - 1; }
    int corner_count() const { return static_cast<int>(corner_vertex.size()); }
    int edge_count() const { return static_cast<int>(edge_vertices.size()); }
    int vertex_count() const { return static_cast<int>(points.size()); }
    /// True when every face has 4 corners.
    bool all_quads() const;
};

/// Level 0 of a SubdivisionMesh primitive: validates it (ValueError naming
/// prim.source) and applies the tags.
SubdivMesh build_subdiv_mesh(const Primitive& prim);

/// One Catmull–Clark step; every face of the result is a quad.
SubdivMesh refine_subdiv_mesh(const SubdivMesh& mesh);

/// Limit surface data of an all-quad mesh.
struct SubdivLimit {
    std::vector<glm::dvec3> points;         ///< limit position of every vertex
    std::vector<glm::dvec3> corner_normals; ///< unit normal per face corner
};

/// Pushes every vertex to its limit position and gives each face corner a
/// limit normal (tangent stencils at smooth vertices, the face's own corner
/// normal at crease, corner and boundary vertices so creases stay sharp).
/// Normals follow the face winding (RenderMan's dPdu x dPdv).
SubdivLimit subdiv_limit(const SubdivMesh& mesh);

} // namespace sss::detail
