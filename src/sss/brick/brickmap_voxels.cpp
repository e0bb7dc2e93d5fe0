// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file brickmap_voxels.cpp
/// A brick map's samples on the lattice of one depth (brickmap_voxels.h), for
/// the grids of a .vdb file.

#include "sss/brick/brickmap_voxels.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>

#include "brickmap_format.h"
#include "sss/brick/brickmap.h"

namespace sss {

namespace {

using detail::kBkmTrees;
using detail::kBrickSamples;

constexpr int kBrickEdge = 7; ///< sample steps per brick edge

/// One tree's sample at a lattice point; `slot` indexes a value buffer.
struct Entry {
    std::array<int32_t, 3> c;
    int tree;
    std::size_t slot;
};

bool entry_less(const Entry& a, const Entry& b) {
    return std::tie(a.c, a.tree) < std::tie(b.c, b.tree);
}

/// The normal whose lookups read tree t: its axis (none for tree 0).
glm::vec3 tree_normal(int tree) {
    glm::vec3 n(0.0f);
    if (tree > 0) n[(tree - 1) / 2] = (tree - 1) % 2 ? -1.0f : 1.0f;
    return n;
}

BrickMapVoxels empty_voxels(const BrickMap& map, int depth) {
    const BrickMapInfo& info = map.info();
    BrickMapVoxels v;
    v.depth = depth;
    v.spacing = info.cube_side / (kBrickEdge * std::ldexp(1.0, depth));
    v.origin = info.cube_min;
    return v;
}

/// Appends the lattice points of the samples flagged in `present` of node
/// `node` (at the depth) to `out`, with slots from `slot` on.
void add_samples(const std::array<uint32_t, 3>& node, int tree,
                 const std::vector<uint8_t>& present, std::vector<Entry>& out,
                 std::size_t& slot) {
    for (int s = 0; s < kBrickSamples; ++s) {
        if (!present[static_cast<std::size_t>(s)]) continue;
        const int ijk[3] = {s % 8, (s / 8) % 8, s / 64};
        Entry e;
        for (int a = 0; a < 3; ++a)
            e.c[a] = static_cast<int32_t>(node[a]) * kBrickEdge + ijk[a];
        e.tree = tree;
        e.slot = slot++;
        out.push_back(e);
    }
}

/// Sorts the entries by lattice point and tree and drops the repeats of a
/// point within one tree (the faces neighbouring bricks share); returns the
/// start of each lattice point's run, and its end as the last element.
std::vector<std::size_t> group_entries(std::vector<Entry>& entries) {
    std::stable_sort(entries.begin(), entries.end(), entry_less);
    entries.erase(std::unique(entries.begin(), entries.end(),
                              [](const Entry& a, const Entry& b) {
                                  return a.c == b.c && a.tree == b.tree;
                              }),
                  entries.end());
    std::vector<std::size_t> starts;
    for (std::size_t i = 0; i < entries.size(); ++i)
        if (i == 0 || entries[i].c != entries[i - 1].c) starts.push_back(i);
    starts.push_back(entries.size());
    return starts;
}

/// The world point of a lattice point as a float inside the root cube (a
/// point on the cube's far faces must not round to just outside it).
glm::vec3 lattice_point(const BrickMapVoxels& v, const std::array<int32_t, 3>& c,
                        const BrickMapInfo& info) {
    glm::vec3 p;
    for (int a = 0; a < 3; ++a) {
        const double lo = info.cube_min[a], hi = lo + info.cube_side;
        const double x = v.origin[a] + v.spacing * c[a];
        float f = static_cast<float>(x);
        while (double(f) > hi)
            f = std::nextafter(f, -std::numeric_limits<float>::infinity());
        while (double(f) < lo)
            f = std::nextafter(f, std::numeric_limits<float>::infinity());
        p[a] = f;
    }
    return p;
}

} // namespace

int brick_map_surface_depth(const BrickMap& map) {
    std::size_t above = 0;
    for (int t = 0; t < kBkmTrees; ++t) above += map.nodes_at(t, 0).size();
    if (above == 0) return 0;
    double share = 1.0;
    int best = 0;
    for (int d = 1; d <= detail::kBkmMaxDepth; ++d) {
        std::size_t nodes = 0, parents = 0;
        for (int t = 0; t < kBkmTrees; ++t) {
            std::vector<std::array<uint32_t, 3>> here = map.nodes_at(t, d);
            nodes += here.size();
            for (auto& c : here)
                for (uint32_t& x : c) x >>= 1;
            std::sort(here.begin(), here.end());
            parents += static_cast<std::size_t>(std::unique(here.begin(), here.end()) -
                                                here.begin());
        }
        if (nodes == 0) break;
        share *= double(parents) / double(above);
        if (share < 0.9) break;
        best = d;
        above = nodes;
    }
    return best;
}

BrickMapVoxels brick_map_voxels(const BrickMap& map, int depth) {
    const BrickMapInfo& info = map.info();
    const int ds = info.data_size;
    BrickMapVoxels v = empty_voxels(map, depth);
    std::vector<Entry> entries;
    std::size_t slot = 0;
    std::vector<uint8_t> present;
    for (int t = 0; t < kBkmTrees; ++t) {
        for (const std::array<uint32_t, 3>& node : map.nodes_at(t, depth)) {
            if (map.read_occupancy(t, depth, node[0], node[1], node[2], present))
                add_samples(node, t, present, entries, slot);
        }
    }
    const std::vector<std::size_t> starts = group_entries(entries);
    const std::size_t groups = starts.size() - 1;
    std::vector<float> values(groups * static_cast<std::size_t>(ds), 0.0f);
    std::vector<uint8_t> found(groups, 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, groups), [&](const auto& range) {
        std::vector<float> one(static_cast<std::size_t>(ds));
        std::vector<double> sum(static_cast<std::size_t>(ds));
        for (std::size_t g = range.begin(); g != range.end(); ++g) {
            const glm::vec3 p = lattice_point(v, entries[starts[g]].c, info);
            std::fill(sum.begin(), sum.end(), 0.0);
            int count = 0;
            for (std::size_t i = starts[g]; i < starts[g + 1]; ++i) {
                if (!map.lookup_depth(p, tree_normal(entries[i].tree), depth, one.data()))
                    continue;
                for (int k = 0; k < ds; ++k) sum[k] += one[k];
                ++count;
            }
            if (count == 0) continue;
            found[g] = 1;
            for (int k = 0; k < ds; ++k)
                values[g * static_cast<std::size_t>(ds) + k] =
                    static_cast<float>(sum[k] / count);
        }
    });
    for (std::size_t g = 0; g < groups; ++g) {
        if (!found[g]) continue;
        v.coords.push_back(entries[starts[g]].c);
        v.values.insert(v.values.end(),
                        values.begin() + static_cast<std::ptrdiff_t>(g * ds),
                        values.begin() + static_cast<std::ptrdiff_t>((g + 1) * ds));
    }
    return v;
}

} // namespace sss
