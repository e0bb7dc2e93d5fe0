// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
// Shared by the benches: a latitude-longitude mesh (north pole, rings-1 rings
// of `segments` vertices, south pole) written as one RIB PointsPolygons with
// vertex normals: triangle fans at the poles, quads between rings.

#include <sstream>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

namespace bench {

/// v and n hold 2 + (rings - 1) * segments vertices in the layout above.
inline std::string latlong_points_polygons(const std::vector<glm::dvec3>& v,
                                           const std::vector<glm::dvec3>& n, int rings,
                                           int segments) {
    auto ring = [&](int j, int i) { return 1 + (j - 1) * segments + (i % segments); };
    std::ostringstream nverts, verts, rib;
    rib.precision(9);
    for (int i = 0; i < segments; ++i) {
        nverts << "3 ";
        verts << 0 << ' ' << ring(1, i + 1) << ' ' << ring(1, i) << ' ';
    }
    for (int j = 1; j < rings - 1; ++j)
        for (int i = 0; i < segments; ++i) {
            nverts << "4 ";
            verts << ring(j, i) << ' ' << ring(j, i + 1) << ' ' << ring(j + 1, i + 1)
                  << ' ' << ring(j + 1, i) << ' ';
        }
    const int south = static_cast<int>(v.size()) - 1;
    for (int i = 0; i < segments; ++i) {
        nverts << "3 ";
        verts << south << ' ' << ring(rings - 1, i) << ' ' << ring(rings - 1, i + 1)
              << ' ';
    }
    rib << "PointsPolygons [" << nverts.str() << "] [" << verts.str() << "] \"P\" [";
    for (const glm::dvec3& p : v) rib << p.x << ' ' << p.y << ' ' << p.z << ' ';
    rib << "] \"N\" [";
    for (const glm::dvec3& p : n) rib << p.x << ' ' << p.y << ' ' << p.z << ' ';
    rib << "]\n";
    return rib.str();
}

} // namespace bench
