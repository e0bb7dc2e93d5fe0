// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file brickmap_build.cpp
/// brickmake's core: splats the points of one or more clouds into per-depth
/// sample lattices of 7 normal-direction trees, prunes bricks that their
/// parent reproduces within -maxerror, and writes the .bkm file
/// (docs/bkm-format.md).
///
/// Determinism: points are put in Morton order (ties broken by index); the
/// lattice of each (tree, depth) is accumulated by exactly one task, in that
/// order; pruning decisions are pure functions of the lattices. The file is
/// therefore byte-identical whatever the number of threads.

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <set>
#include <string>
#include <vector>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "brickmap_format.h"
#include "sss/brick/brickmap.h"
#include "sss/util/atomic_output.h"
#include "sss/util/byte_io.h"
#include "sss/util/error.h"
#include "sss/util/hash.h"
#include "sss/util/limits.h"
#include "sss/util/progress.h"
#include "sss/util/threads.h"

namespace sss {

namespace {

using namespace detail;

/// A point goes into every tree whose axis is within 55 degrees of its
/// normal: every unit vector has a component of at least 1/sqrt(3) = 0.577,
/// so the tree of the dominant axis always gets it, and lookups whose normal
/// is near the boundary between two dominant axes find data in both trees.
constexpr double kCos55 = 0.57357643635104609611;
/// Extra room around the points' footprints so that none touches the root
/// cube's faces.
constexpr double kCubePadding = 0.01;
constexpr int kTileEdge = 7; ///< lattice samples per tile edge (node-aligned)
constexpr int kTileSamples = kTileEdge * kTileEdge * kTileEdge;
/// Progress units of the three phases (splatting, pruning, writing).
constexpr uint64_t kProgressSplat = 600, kProgressPrune = 150, kProgressWrite = 250;
constexpr uint64_t kProgressTotal = kProgressSplat + kProgressPrune + kProgressWrite;

// ---------------------------------------------------------------------------
// Input
// ---------------------------------------------------------------------------

struct Selected {
    const Channel* channel;
    std::string name;
    ChannelType type;
};

std::vector<Selected> select_channels(const PointCloud& cloud,
                                      const std::vector<std::string>& wanted) {
    std::vector<Selected> out;
    if (wanted.empty()) {
        for (const Channel& c : cloud.channels) {
            if (c.type == ChannelType::Float || c.type == ChannelType::Color)
                out.push_back({&c, c.name, c.type});
        }
        if (out.empty())
            throw ValueError(
                "brick map: the input has no float or color channel to store");
        return out;
    }
    std::set<std::string> seen;
    for (const std::string& name : wanted) {
        if (!seen.insert(name).second)
            throw ValueError("brick map: channel '" + name + "' is named twice");
        const Channel* c = cloud.find_channel(name);
        if (!c) throw ValueError("brick map: no channel '" + name + "' in the input");
        if (c->type != ChannelType::Float && c->type != ChannelType::Color) {
            throw ValueError("brick map: channel '" + name + "' is a " +
                             channel_type_name(c->type) +
                             "; only float and color channels can be stored");
        }
        out.push_back({c, name, c->type});
    }
    return out;
}

void check_options(const BrickMapBuildOptions& o) {
    if (!std::isfinite(o.max_error) || o.max_error < 0.0)
        throw ValueError("brick map: max error must be a finite number >= 0");
    if (o.max_depth < 0 || o.max_depth > kBkmMaxDepth)
        throw ValueError("brick map: max depth must be in [0, " +
                         std::to_string(kBkmMaxDepth) + "] (got " +
                         std::to_string(o.max_depth) + ")");
    if (!std::isfinite(o.radius_scale) || !(o.radius_scale > 0.0))
        throw ValueError("brick map: radius scale must be a finite number > 0");
    if (o.provenance.size() > kBkmMaxProvenance)
        throw ValueError("brick map: provenance text too long");
    if (o.provenance.find('\0') != std::string::npos)
        throw ValueError("brick map: provenance text contains a NUL byte");
}

void check_arrays(const PointCloud& cloud) {
    const std::size_t n = cloud.size();
    if (cloud.normals.size() != n || cloud.radii.size() != n)
        throw ValueError("brick map: the cloud's position, normal and radius arrays "
                         "have different lengths");
    for (const Channel& c : cloud.channels) {
        if (c.data.size() != n * static_cast<std::size_t>(c.components()))
            throw ValueError("brick map: channel '" + c.name + "' has " +
                             std::to_string(c.data.size()) + " floats for " +
                             std::to_string(n) + " points");
    }
}

bool finite3(const glm::vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

/// The points, prepared for splatting and put in Morton order.
struct Points {
    int data_size = 0;
    std::vector<double> u;      ///< 3 per point: position in root-cube units, [0, 1)
    std::vector<double> ru;     ///< footprint half-size in root-cube units
    std::vector<double> area;   ///< surface area the point stands for
    std::vector<float> values;  ///< data_size per point
    std::vector<uint8_t> level; ///< the point's own depth
    std::vector<uint64_t> key;  ///< Morton code of u, 21 bits per axis (the sort key)
    std::array<std::vector<uint32_t>, kBkmTrees> tree_points; ///< sorted indices
    std::array<int, kBkmTrees>
        tree_depth{}; ///< deepest own level in each tree (-1: empty)
};

/// Footprint radius and area of point i; throws ValueError naming the point.
void point_size(const PointCloud& cloud, const Channel* area_channel, double scale,
                std::size_t i, double& r, double& area) {
    const double radius = cloud.radii[i];
    const double a = area_channel ? area_channel->data[i] : 0.0;
    if (!std::isfinite(radius) || radius < 0.0)
        throw ValueError("brick map: invalid radius (point " + std::to_string(i) + ")");
    if (!std::isfinite(a) || a < 0.0)
        throw ValueError("brick map: invalid _area (point " + std::to_string(i) + ")");
    if (radius > 0.0) {
        r = radius;
    } else if (a > 0.0) {
        r = std::sqrt(a / std::numbers::pi); // the disk of that area
    } else {
        throw ValueError("brick map: point " + std::to_string(i) +
                         " has neither a radius nor an _area");
    }
    area = a > 0.0 ? a
                   : 4.0 * r * r; // surface coverage: the area, else the footprint's face
    r *= scale;
}

// ---------------------------------------------------------------------------
// Sample lattices
// ---------------------------------------------------------------------------

/// The samples of one (tree, depth): a sparse lattice of 7 * 2^depth + 1
/// samples per axis, spacing side / (7 * 2^depth). It is split into
/// node-aligned tiles of 7^3 samples (tile t holds lattice coordinates
/// 7t .. 7t + 6), found through a hash of the tile coordinates; each tile maps
/// its samples to slots in first-touch order. Node (ix, iy, iz)'s brick is the
/// 8^3 window 7 * ix .. 7 * ix + 7, i.e. its tile plus a face of the next.
class SampleLattice {
public:
    SampleLattice(int depth, int data_size)
        : m_depth(depth), m_ds(data_size),
          m_stride(static_cast<std::size_t>(data_size) + 1) {
        m_keys.assign(64, kEmpty);
        m_vals.assign(64, 0);
    }

    int depth() const { return m_depth; }
    std::size_t samples() const { return m_count; }
    std::size_t tiles() const { return m_coords.size(); }
    const std::array<uint32_t, 3>& tile_coords(std::size_t t) const {
        return m_coords[t];
    }
    const int32_t* tile_slots(std::size_t t) const { return &m_slots[t * kTileSamples]; }

    /// Adds weight w and values v (data_size floats) to sample g.
    void add(uint32_t gx, uint32_t gy, uint32_t gz, double w, const float* v) {
        const uint32_t tx = gx / kTileEdge, ty = gy / kTileEdge, tz = gz / kTileEdge;
        const uint64_t key = pack(tx, ty, tz);
        if (key != m_last_key) {
            m_last_tile = find_or_add(key, tx, ty, tz);
            m_last_key = key;
        }
        const std::size_t local = (gx - kTileEdge * tx) +
                                  kTileEdge * (gy - kTileEdge * ty) +
                                  kTileEdge * kTileEdge * (gz - kTileEdge * tz);
        int32_t& slot = m_slots[m_last_tile * kTileSamples + local];
        if (slot < 0) {
            slot = static_cast<int32_t>(m_count++);
            m_acc.resize(m_acc.size() + m_stride, 0.0);
        }
        double* a = &m_acc[static_cast<std::size_t>(slot) * m_stride];
        a[0] += w;
        for (int c = 0; c < m_ds; ++c) a[1 + c] += w * v[c];
    }

    /// Turns the sums into weighted means (float) and frees the sums.
    void finalize() {
        m_values.resize(m_count * static_cast<std::size_t>(m_ds));
        for (std::size_t s = 0; s < m_count; ++s) {
            const double* a = &m_acc[s * m_stride];
            for (int c = 0; c < m_ds; ++c)
                m_values[s * m_ds + c] = static_cast<float>(a[1 + c] / a[0]);
        }
        std::vector<double>().swap(m_acc);
    }

    const float* value(int32_t slot) const {
        return &m_values[static_cast<std::size_t>(slot) * m_ds];
    }

    /// Slots (-1: absent) of the 512 samples of node (ix, iy, iz)'s brick,
    /// index i + 8 j + 64 k.
    void gather(uint32_t ix, uint32_t iy, uint32_t iz, int32_t out[kBrickSamples]) const {
        const int32_t* tiles[8];
        for (int o = 0; o < 8; ++o) {
            const int64_t t =
                find(pack(ix + (o & 1), iy + ((o >> 1) & 1), iz + ((o >> 2) & 1)));
            tiles[o] =
                t < 0 ? nullptr : &m_slots[static_cast<std::size_t>(t) * kTileSamples];
        }
        for (int k = 0; k < 8; ++k) {
            for (int j = 0; j < 8; ++j) {
                for (int i = 0; i < 8; ++i) {
                    const int o = (i == 7) | ((j == 7) << 1) | ((k == 7) << 2);
                    const int local = (i == 7 ? 0 : i) + kTileEdge * (j == 7 ? 0 : j) +
                                      kTileEdge * kTileEdge * (k == 7 ? 0 : k);
                    out[i + 8 * j + 64 * k] = tiles[o] ? tiles[o][local] : -1;
                }
            }
        }
    }

private:
    static constexpr uint64_t kEmpty = ~uint64_t(0);

    static uint64_t pack(uint32_t x, uint32_t y, uint32_t z) {
        return uint64_t(x) | (uint64_t(y) << 21) | (uint64_t(z) << 42);
    }

    int64_t find(uint64_t key) const {
        const std::size_t mask = m_keys.size() - 1;
        for (std::size_t h = splitmix64(key) & mask;; h = (h + 1) & mask) {
            if (m_keys[h] == key) return m_vals[h];
            if (m_keys[h] == kEmpty) return -1;
        }
    }

    std::size_t find_or_add(uint64_t key, uint32_t tx, uint32_t ty, uint32_t tz) {
        std::size_t mask = m_keys.size() - 1;
        std::size_t h = splitmix64(key) & mask;
        for (; m_keys[h] != kEmpty; h = (h + 1) & mask) {
            if (m_keys[h] == key) return m_vals[h];
        }
        const uint32_t index = static_cast<uint32_t>(m_coords.size());
        m_coords.push_back({tx, ty, tz});
        m_slots.resize(m_slots.size() + kTileSamples, -1);
        m_keys[h] = key;
        m_vals[h] = index;
        if (2 * m_coords.size() > m_keys.size()) grow();
        return index;
    }

    void grow() {
        std::vector<uint64_t> keys(m_keys.size() * 2, kEmpty);
        std::vector<uint32_t> vals(keys.size(), 0);
        const std::size_t mask = keys.size() - 1;
        for (std::size_t i = 0; i < m_keys.size(); ++i) {
            if (m_keys[i] == kEmpty) continue;
            std::size_t h = splitmix64(m_keys[i]) & mask;
            while (keys[h] != kEmpty) h = (h + 1) & mask;
            keys[h] = m_keys[i];
            vals[h] = m_vals[i];
        }
        m_keys.swap(keys);
        m_vals.swap(vals);
    }

    int m_depth;
    int m_ds;
    std::size_t m_stride;
    std::vector<uint64_t> m_keys;                  ///< open addressing, linear probing
    std::vector<uint32_t> m_vals;                  ///< tile index of each key
    std::vector<std::array<uint32_t, 3>> m_coords; ///< per tile
    std::vector<int32_t> m_slots;                  ///< kTileSamples per tile
    std::vector<double> m_acc;                     ///< weight + weighted sums per sample
    std::vector<float> m_values;                   ///< data_size per sample
    std::size_t m_count = 0;
    uint64_t m_last_key = kEmpty;
    std::size_t m_last_tile = 0;
};

/// The lattice cells one point's footprint [c - rr, c + rr] overlaps along an
/// axis (cell of sample g: [g - 1/2, g + 1/2], lattice units), with the
/// fraction of the footprint's width inside each (fractions, not lengths, so
/// that tiny footprints cannot overflow the weights). Returns the count (at
/// most 8: see splat_level).
int axis_cells(double c, double rr, uint32_t gmax, uint32_t* g, double* w) {
    const double lo = c - rr, hi = c + rr;
    int64_t g0 = static_cast<int64_t>(std::floor(lo + 0.5));
    int64_t g1 = static_cast<int64_t>(std::floor(hi + 0.5));
    g0 = std::max<int64_t>(g0, 0);
    g1 = std::min<int64_t>(g1, gmax);
    int n = 0;
    for (int64_t k = g0; k <= g1 && n < 16; ++k) {
        const double o = std::min(hi, k + 0.5) - std::max(lo, k - 0.5);
        if (o > 0.0) {
            g[n] = static_cast<uint32_t>(k);
            w[n] = o / (2.0 * rr);
            ++n;
        }
    }
    return n;
}

/// Splats every point of a tree whose own level is at least the lattice's
/// depth. Weight of a sample: the fraction of the point's footprint cube
/// inside the sample's cell, times the point's area, so that a sample's
/// value is a surface-area-weighted mean. The own level makes the footprint
/// at most about one cell wide (or 7 cells for points clamped to depth 0),
/// so at most 8 cells per axis are touched.
void splat_level(const Points& pts, int tree, SampleLattice& lattice) {
    const int d = lattice.depth();
    const double scale = kTileEdge * std::ldexp(1.0, d);
    const uint32_t gmax = static_cast<uint32_t>(kTileEdge) << d;
    const int ds = pts.data_size;
    uint32_t gx[16], gy[16], gz[16];
    double wx[16], wy[16], wz[16];
    for (uint32_t i : pts.tree_points[tree]) {
        if (pts.level[i] < d) continue;
        const double rr = pts.ru[i] * scale;
        const int nx = axis_cells(pts.u[3 * i] * scale, rr, gmax, gx, wx);
        const int ny = axis_cells(pts.u[3 * i + 1] * scale, rr, gmax, gy, wy);
        const int nz = axis_cells(pts.u[3 * i + 2] * scale, rr, gmax, gz, wz);
        const double area = pts.area[i];
        const float* v = &pts.values[static_cast<std::size_t>(i) * ds];
        for (int c = 0; c < nz; ++c) {
            for (int b = 0; b < ny; ++b) {
                const double wzy = wz[c] * wy[b] * area;
                for (int a = 0; a < nx; ++a) {
                    const double w = wzy * wx[a];
                    if (w > 0.0) lattice.add(gx[a], gy[b], gz[c], w, v);
                }
            }
        }
    }
}

/// Morton keys of the nodes whose brick has at least one present sample,
/// sorted. A sample with lattice coordinate 7t on an axis is also the last
/// sample (index 7) of node t - 1 along that axis.
std::vector<uint64_t> nodes_with_data(const SampleLattice& lattice) {
    const uint32_t n = 1u << lattice.depth();
    std::vector<uint64_t> keys;
    keys.reserve(lattice.tiles() * 2);
    for (std::size_t t = 0; t < lattice.tiles(); ++t) {
        const int32_t* slots = lattice.tile_slots(t);
        unsigned subsets = 0; // bit s: some sample lies on the low faces named by s
        for (int k = 0; k < kTileEdge; ++k) {
            for (int j = 0; j < kTileEdge; ++j) {
                for (int i = 0; i < kTileEdge; ++i) {
                    if (slots[i + kTileEdge * j + kTileEdge * kTileEdge * k] < 0)
                        continue;
                    const unsigned faces = (i == 0) | ((j == 0) << 1) | ((k == 0) << 2);
                    for (unsigned s = 0; s < 8; ++s) {
                        if ((s & faces) == s) subsets |= 1u << s;
                    }
                }
            }
        }
        const auto& tc = lattice.tile_coords(t);
        for (unsigned s = 0; s < 8; ++s) {
            if (!((subsets >> s) & 1)) continue;
            const uint32_t dx = s & 1, dy = (s >> 1) & 1, dz = (s >> 2) & 1;
            if (tc[0] < dx || tc[1] < dy || tc[2] < dz) continue;
            const uint32_t x = tc[0] - dx, y = tc[1] - dy, z = tc[2] - dz;
            if (x >= n || y >= n || z >= n) continue; // the far boundary tile
            keys.push_back(bkm_morton(x, y, z));
        }
    }
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    return keys;
}

// ---------------------------------------------------------------------------
// Pruning
// ---------------------------------------------------------------------------

/// The nodes of one (tree, depth) and the pruning results.
struct LevelNodes {
    std::vector<uint64_t> keys;    ///< Morton order
    std::vector<uint16_t> samples; ///< present samples in each brick
    std::vector<uint8_t> kept;     ///< the brick keeps its data
    std::vector<double> err;       ///< dropped: bound of the error this drop causes
};

/// Per-axis parent positions of a child's 8 samples: child sample i of a
/// node with parity p (ix & 1) sits at parent-lattice coordinate
/// (7 p + i) / 2 inside the parent's brick: one parent sample (weight 1) or
/// the midpoint of two (weights 1/2).
struct AxisMap {
    int count[2][8];
    int index[2][8][2];
    double weight[2][8][2];
    AxisMap() {
        for (int p = 0; p < 2; ++p) {
            for (int i = 0; i < 8; ++i) {
                const int x2 = 7 * p + i;
                if (x2 % 2 == 0) {
                    count[p][i] = 1;
                    index[p][i][0] = x2 / 2;
                    weight[p][i][0] = 1.0;
                } else {
                    count[p][i] = 2;
                    index[p][i][0] = x2 / 2;
                    index[p][i][1] = x2 / 2 + 1;
                    weight[p][i][0] = weight[p][i][1] = 0.5;
                }
            }
        }
    }
};

/// Largest difference, over the child's present samples and all channels,
/// between a sample and the parent's trilinear interpolation at its position
/// (renormalised over the parent samples present); +inf as soon as it
/// exceeds budget or a sample has no parent data around it.
double reproduction_error(const SampleLattice& child, const int32_t* child_slots,
                          const SampleLattice& parent, const int32_t* parent_slots,
                          uint32_t ix, uint32_t iy, uint32_t iz, double budget,
                          const AxisMap& map, std::vector<double>& acc) {
    const int ds = static_cast<int>(acc.size());
    const int px = ix & 1, py = iy & 1, pz = iz & 1;
    double worst = 0.0;
    for (int k = 0; k < 8; ++k) {
        for (int j = 0; j < 8; ++j) {
            for (int i = 0; i < 8; ++i) {
                const int32_t slot = child_slots[i + 8 * j + 64 * k];
                if (slot < 0) continue;
                std::fill(acc.begin(), acc.end(), 0.0);
                double sum = 0.0;
                for (int c = 0; c < map.count[pz][k]; ++c) {
                    for (int b = 0; b < map.count[py][j]; ++b) {
                        for (int a = 0; a < map.count[px][i]; ++a) {
                            const int s = map.index[px][i][a] + 8 * map.index[py][j][b] +
                                          64 * map.index[pz][k][c];
                            const int32_t ps = parent_slots[s];
                            if (ps < 0) continue;
                            const double w = map.weight[px][i][a] * map.weight[py][j][b] *
                                             map.weight[pz][k][c];
                            const float* pv = parent.value(ps);
                            for (int q = 0; q < ds; ++q) acc[q] += w * pv[q];
                            sum += w;
                        }
                    }
                }
                if (!(sum > 0.0)) return std::numeric_limits<double>::infinity();
                const float* v = child.value(slot);
                for (int q = 0; q < ds; ++q) {
                    const double e = std::abs(double(v[q]) - acc[q] / sum);
                    if (e > budget) return std::numeric_limits<double>::infinity();
                    worst = std::max(worst, e);
                }
            }
        }
    }
    return worst;
}

/// Bottom-up pruning of one tree. A brick is dropped when none of its
/// children keeps data and its parent reproduces every present sample within
/// max_error minus the error its dropped descendants already cause (so the
/// error of every dropped sample against the brick that serves lookups stays
/// within about max_error). Depth-0 bricks are always kept.
void prune_tree(const std::vector<std::unique_ptr<SampleLattice>>& lattices,
                std::vector<LevelNodes>& levels, double max_error, int ds,
                Progress* progress, std::atomic<uint64_t>& done, uint64_t total,
                uint64_t base) {
    static const AxisMap map;
    for (int d = static_cast<int>(levels.size()) - 1; d >= 0; --d) {
        LevelNodes& L = levels[d];
        const LevelNodes* C =
            d + 1 < static_cast<int>(levels.size()) ? &levels[d + 1] : nullptr;
        const std::size_t n = L.keys.size();
        L.samples.assign(n, 0);
        L.kept.assign(n, 1);
        L.err.assign(n, 0.0);
        tbb::parallel_for(
            tbb::blocked_range<std::size_t>(0, n, 64), [&](const auto& range) {
                std::vector<int32_t> child_slots(kBrickSamples),
                    parent_slots(kBrickSamples);
                std::vector<double> acc(static_cast<std::size_t>(ds));
                uint64_t parent_key = ~uint64_t(0);
                for (std::size_t i = range.begin(); i != range.end(); ++i) {
                    const uint64_t key = L.keys[i];
                    const uint32_t ix = bkm_compact3(key), iy = bkm_compact3(key >> 1),
                                   iz = bkm_compact3(key >> 2);
                    lattices[d]->gather(ix, iy, iz, child_slots.data());
                    int count = 0;
                    for (int32_t s : child_slots) count += s >= 0 ? 1 : 0;
                    L.samples[i] = static_cast<uint16_t>(count);
                    if (d == 0) continue;
                    bool kept_child = false;
                    double below = 0.0; // error already caused by dropped descendants
                    if (C) {
                        auto it =
                            std::lower_bound(C->keys.begin(), C->keys.end(), key << 3);
                        for (; it != C->keys.end() && (*it >> 3) == key; ++it) {
                            const std::size_t c =
                                static_cast<std::size_t>(it - C->keys.begin());
                            if (C->kept[c])
                                kept_child = true;
                            else
                                below = std::max(below, C->err[c]);
                        }
                    }
                    if (kept_child || below > max_error) continue;
                    if (parent_key != key >> 3) {
                        parent_key = key >> 3;
                        lattices[d - 1]->gather(ix >> 1, iy >> 1, iz >> 1,
                                                parent_slots.data());
                    }
                    const double e = reproduction_error(
                        *lattices[d], child_slots.data(), *lattices[d - 1],
                        parent_slots.data(), ix, iy, iz, max_error - below, map, acc);
                    if (below + e <= max_error) {
                        L.kept[i] = 0;
                        L.err[i] = below + e;
                    }
                }
                if (progress) {
                    const uint64_t now = done.fetch_add(range.size()) + range.size();
                    progress->update(base + kProgressPrune * now /
                                                std::max<uint64_t>(total, 1),
                                     kProgressTotal);
                }
            });
    }
}

// ---------------------------------------------------------------------------
// Writing
// ---------------------------------------------------------------------------

/// Writes one brick: the presence mask of node's window, then (data bricks)
/// its present samples in index order.
void encode_brick(const SampleLattice& lattice, const BkmNode& node, int ds,
                  int32_t* slots, unsigned char* out) {
    lattice.gather(node.ix, node.iy, node.iz, slots);
    uint64_t mask[8] = {};
    for (int s = 0; s < kBrickSamples; ++s) {
        if (slots[s] >= 0) mask[s >> 6] |= uint64_t(1) << (s & 63);
    }
    for (int w = 0; w < 8; ++w) store_u64(out + 8 * w, mask[w]);
    if (!node.has_data()) return;
    unsigned char* p = out + kBkmMaskBytes;
    for (int s = 0; s < kBrickSamples; ++s) {
        if (slots[s] < 0) continue;
        const float* v = lattice.value(slots[s]);
        for (int c = 0; c < ds; ++c, p += 4) store_f32(p, v[c]);
    }
}

// ---------------------------------------------------------------------------
// The phases of build_brick_map
// ---------------------------------------------------------------------------

/// The merged input and what the build derives from it before splatting.
struct Input {
    const PointCloud* cloud = nullptr;
    std::vector<Selected> selected;
    int data_size = 0;
    const Channel* area = nullptr; ///< float `_area`, if any
    glm::dvec3 lo{0.0}, hi{0.0};   ///< bounds of the positions
    glm::dvec3 cube_min{0.0};
    double side = 0.0;
};

/// Checks every point (the first bad one is reported, whatever the thread
/// count) and finds the bounds and the root cube.
void scan_points(Input& in, const BrickMapBuildOptions& options) {
    const PointCloud& cloud = *in.cloud;
    const std::size_t n = cloud.size();
    std::atomic<std::size_t> first_bad{n};
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, n, 4096), [&](const auto& range) {
            for (std::size_t i = range.begin(); i != range.end(); ++i) {
                bool ok = finite3(cloud.positions[i]) && finite3(cloud.normals[i]);
                for (const Selected& s : in.selected) {
                    const int k = s.channel->components();
                    for (int c = 0; c < k && ok; ++c)
                        ok = std::isfinite(s.channel->data[i * k + c]);
                }
                double r, a;
                try {
                    point_size(cloud, in.area, options.radius_scale, i, r, a);
                } catch (const ValueError&) {
                    ok = false;
                }
                if (!ok) { // the first bad point of this range
                    lower_to(first_bad, i);
                    return;
                }
            }
        });
    if (const std::size_t i = first_bad.load(); i < n) {
        const std::string which = " (point " + std::to_string(i) + ")";
        if (!finite3(cloud.positions[i]))
            throw ValueError("brick map: non-finite position" + which);
        if (!finite3(cloud.normals[i]))
            throw ValueError("brick map: non-finite normal" + which);
        double r, a;
        point_size(cloud, in.area, options.radius_scale, i, r, a); // throws if it is that
        throw ValueError("brick map: non-finite channel value" + which);
    }
    in.lo = glm::dvec3(std::numeric_limits<double>::infinity());
    in.hi = -in.lo;
    double max_r = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
        const glm::dvec3 p(cloud.positions[i]);
        in.lo = glm::min(in.lo, p);
        in.hi = glm::max(in.hi, p);
        double r, a;
        point_size(cloud, in.area, options.radius_scale, i, r, a);
        max_r = std::max(max_r, r);
    }
    // The bounds grown by the largest footprint, made cubic (edge = the
    // largest extent) around their centre, and padded.
    const glm::dvec3 centre = 0.5 * (in.lo + in.hi);
    const glm::dvec3 size = in.hi - in.lo;
    in.side = (std::max({size.x, size.y, size.z}) + 2.0 * max_r) * (1.0 + kCubePadding);
    if (!(in.side > 0.0) || !std::isfinite(in.side))
        throw ValueError("brick map: the points span no volume");
    in.cube_min = centre - glm::dvec3(0.5 * in.side);
}

/// Trees of a point (bit t: tree t): every axis within 55 degrees of its
/// normal; tree 0 for zero normals or ignore_normals.
uint8_t tree_mask(const glm::vec3& normal, bool ignore_normals) {
    const glm::dvec3 n(normal);
    const double len = std::sqrt(glm::dot(n, n));
    if (ignore_normals || len == 0.0) return 1;
    uint8_t mask = 0;
    for (int axis = 0; axis < 3; ++axis) {
        const double c = n[axis] / len;
        if (c >= kCos55) mask |= uint8_t(1u << (1 + 2 * axis));
        if (-c >= kCos55) mask |= uint8_t(1u << (2 + 2 * axis));
    }
    if (mask ==
        0) { // only by rounding (|component| >= 0.577 > cos 55): the dominant axis
        int axis = 0;
        for (int a = 1; a < 3; ++a)
            if (std::abs(n[a]) > std::abs(n[axis])) axis = a;
        mask = uint8_t(1u << (1 + 2 * axis + (n[axis] < 0.0 ? 1 : 0)));
    }
    return mask;
}

/// The points in Morton order (ties by index, so the order is unique), with
/// their footprints, own levels, values and trees.
Points prepare_points(const Input& in, const BrickMapBuildOptions& options) {
    const PointCloud& cloud = *in.cloud;
    const std::size_t n = cloud.size();
    const int ds = in.data_size;
    std::vector<std::pair<uint64_t, uint32_t>> order(n);
    tbb::parallel_for(std::size_t(0), n, [&](std::size_t i) {
        const glm::dvec3 u = (glm::dvec3(cloud.positions[i]) - in.cube_min) / in.side;
        uint32_t q[3];
        for (int a = 0; a < 3; ++a)
            q[a] = static_cast<uint32_t>(std::clamp(u[a] * 2097152.0, 0.0, 2097151.0));
        order[i] = {bkm_morton(q[0], q[1], q[2]), static_cast<uint32_t>(i)};
    });
    tbb::parallel_sort(order.begin(), order.end());

    Points pts;
    pts.data_size = ds;
    pts.u.resize(3 * n);
    pts.ru.resize(n);
    pts.area.resize(n);
    pts.values.resize(n * static_cast<std::size_t>(ds));
    pts.level.resize(n);
    pts.key.resize(n);
    std::vector<uint8_t> trees(n);
    tbb::parallel_for(std::size_t(0), n, [&](std::size_t k) {
        const std::size_t i = order[k].second;
        pts.key[k] = order[k].first;
        double r, a;
        point_size(cloud, in.area, options.radius_scale, i, r, a);
        const glm::dvec3 u = (glm::dvec3(cloud.positions[i]) - in.cube_min) / in.side;
        for (int c = 0; c < 3; ++c) pts.u[3 * k + c] = u[c];
        pts.ru[k] = r / in.side;
        pts.area[k] = a;
        // Own level: the sample spacing side / (7 * 2^d) closest (in log
        // scale) to the footprint's width 2r.
        const double natural = std::round(std::log2(in.side / (kTileEdge * 2.0 * r)));
        pts.level[k] = static_cast<uint8_t>(
            std::clamp(natural, 0.0, static_cast<double>(options.max_depth)));
        float* v = &pts.values[k * static_cast<std::size_t>(ds)];
        for (const Selected& s : in.selected) {
            const int comps = s.channel->components();
            for (int c = 0; c < comps; ++c) *v++ = s.channel->data[i * comps + c];
        }
        trees[k] = tree_mask(cloud.normals[i], options.ignore_normals);
    });
    for (int t = 0; t < kBkmTrees; ++t) {
        pts.tree_depth[t] = -1;
        for (std::size_t k = 0; k < n; ++k) {
            if ((trees[k] >> t) & 1) {
                pts.tree_points[t].push_back(static_cast<uint32_t>(k));
                pts.tree_depth[t] = std::max<int>(pts.tree_depth[t], pts.level[k]);
            }
        }
    }
    return pts;
}

using Lattices = std::array<std::vector<std::unique_ptr<SampleLattice>>, kBkmTrees>;

/// Limit::Bricks counts node records (data bricks and occupancy-only nodes),
/// what a reader holds in memory. before_pruning: the estimate from the
/// points (fail before building); otherwise the nodes about to be written.
void check_brick_count(uint64_t nodes, const BrickMapBuildOptions& options,
                       bool before_pruning) {
    if (nodes <= limit(Limit::Bricks)) return;
    std::string remedy;
    if (before_pruning)
        remedy = "; counted from the points before pruning: lower -maxdepth (now " +
                 std::to_string(options.max_depth) + ") or raise -radiusscale";
    else if (options.omit_geometry)
        remedy = "; raise -maxerror, lower -maxdepth or raise -radiusscale";
    else
        remedy = "; lower -maxdepth, raise -radiusscale, or leave out the "
                 "occupancy-only nodes with -omitgeometry 1 and raise -maxerror";
    try {
        check_limit(Limit::Bricks, nodes, "brick map");
    } catch (const LimitError& e) {
        throw LimitError(Limit::Bricks, e.what() + remedy);
    }
}

/// What the build will hold before pruning, counted from the points alone.
struct BuildEstimate {
    uint64_t nodes = 0; ///< at least this many nodes (bricks before pruning)
    uint64_t bytes = 0; ///< about this much memory for lattices and tables
};

/// A lower bound of the nodes the build creates: per tree and depth, the
/// nodes that contain the centre of a point splatted there (each gets the
/// sample nearest to that centre). The points are in Morton order, so the
/// nodes of one depth are runs of equal key prefixes: one pass per tree.
BuildEstimate estimate_build(const Points& pts) {
    std::array<std::array<uint64_t, kBkmMaxDepth + 1>, kBkmTrees> counts{};
    std::array<uint64_t, kBkmTrees> splats{};
    tbb::parallel_for(0, kBkmTrees, [&](int t) {
        uint64_t last[kBkmMaxDepth + 1];
        std::fill(std::begin(last), std::end(last), ~uint64_t(0));
        for (uint32_t k : pts.tree_points[t]) {
            const uint64_t key = pts.key[k];
            splats[t] += pts.level[k] + 1u;
            for (int d = 0; d <= pts.level[k]; ++d) {
                const uint64_t prefix = key >> (3 * (21 - d));
                if (prefix != last[d]) {
                    last[d] = prefix;
                    ++counts[t][d];
                }
            }
        }
    });
    BuildEstimate e;
    uint64_t splatted = 0;
    for (int t = 0; t < kBkmTrees; ++t) {
        splatted += splats[t];
        for (uint64_t c : counts[t]) e.nodes += c;
    }
    // Per node: its tile of sample slots (343 int32), the tile hash and
    // coordinates, the pruning state and the node record. Per sample: the
    // double-precision sums and the float values. Samples: about 64 a node
    // on surfaces (measured: 64 for ptsynth spheres and boxes), but at most
    // about 8 per point and depth where the points are sparse.
    const uint64_t per_node = kTileSamples * 4 + 40 + 19 + 40;
    const uint64_t per_sample =
        8 * uint64_t(pts.data_size + 1) + 4 * uint64_t(pts.data_size);
    const uint64_t samples = std::min(e.nodes * 64, splatted * 8);
    e.bytes = e.nodes * per_node + samples * per_sample;
    return e;
}

/// Splats into one lattice per (tree, depth), each filled by one task,
/// finest depths first (they are the largest).
Lattices splat_all(const Points& pts, Progress* progress) {
    struct Task {
        int tree, depth;
        uint64_t weight;
    };
    std::vector<Task> tasks;
    uint64_t total_weight = 0;
    Lattices lattices;
    for (int t = 0; t < kBkmTrees; ++t) {
        for (int d = 0; d <= pts.tree_depth[t]; ++d) {
            lattices[t].push_back(std::make_unique<SampleLattice>(d, pts.data_size));
            tasks.push_back({t, d, pts.tree_points[t].size() + 1});
            total_weight += tasks.back().weight;
        }
    }
    std::stable_sort(tasks.begin(), tasks.end(),
                     [](const Task& a, const Task& b) { return a.depth > b.depth; });
    std::atomic<uint64_t> done{0};
    tbb::parallel_for(
        std::size_t(0), tasks.size(),
        [&](std::size_t k) {
            const Task& task = tasks[k];
            SampleLattice& lattice = *lattices[task.tree][task.depth];
            splat_level(pts, task.tree, lattice);
            lattice.finalize();
            if (progress) {
                const uint64_t now = done.fetch_add(task.weight) + task.weight;
                progress->update(kProgressSplat * now / total_weight, kProgressTotal);
            }
        },
        tbb::simple_partitioner());
    return lattices;
}

/// The node tables: breadth first, Morton order within a depth (so the
/// children of a node are contiguous and in octant order). Without
/// omit_geometry, dropped bricks stay as occupancy-only nodes.
void make_tables(const std::array<std::vector<LevelNodes>, kBkmTrees>& levels,
                 bool omit_geometry, BkmContents& contents) {
    for (int t = 0; t < kBkmTrees; ++t) {
        std::vector<BkmNode>& table = contents.trees[t];
        const std::vector<LevelNodes>& L = levels[t];
        uint64_t next = 1; // table index of the next child
        for (std::size_t d = 0; d < L.size(); ++d) {
            const LevelNodes& here = L[d];
            const LevelNodes* below = d + 1 < L.size() ? &L[d + 1] : nullptr;
            std::size_t j = 0; // walks the next depth's nodes
            for (std::size_t i = 0; i < here.keys.size(); ++i) {
                if (omit_geometry && !here.kept[i]) continue;
                BkmNode node;
                node.depth = static_cast<uint8_t>(d);
                node.flags = here.kept[i] ? kBkmNodeHasData : 0;
                node.samples = here.samples[i];
                node.ix = bkm_compact3(here.keys[i]);
                node.iy = bkm_compact3(here.keys[i] >> 1);
                node.iz = bkm_compact3(here.keys[i] >> 2);
                if (below) {
                    const std::vector<uint64_t>& next_keys = below->keys;
                    while (j < next_keys.size() && (next_keys[j] >> 3) < here.keys[i])
                        ++j;
                    for (; j < next_keys.size() && (next_keys[j] >> 3) == here.keys[i];
                         ++j) {
                        if (omit_geometry && !below->kept[j]) continue;
                        node.child_mask |= uint8_t(1u << (next_keys[j] & 7));
                    }
                }
                if (node.child_mask) {
                    node.first_child = static_cast<uint32_t>(next);
                    next += static_cast<uint64_t>(std::popcount(node.child_mask));
                }
                table.push_back(node);
            }
        }
        if (table.size() > std::numeric_limits<uint32_t>::max())
            throw ValueError("brick map: too many nodes in tree " + std::to_string(t));
    }
    bkm_assign_offsets(contents);
}

/// Every node's brick checksum (the header's checksum covers them, so they
/// are needed before anything is written): the bricks are encoded once here
/// and again when written, rather than held in memory.
void compute_brick_crcs(BkmContents& contents, const Lattices& lattices) {
    const int ds = contents.info.data_size;
    std::vector<std::pair<int, BkmNode*>> all;
    for (int t = 0; t < kBkmTrees; ++t)
        for (BkmNode& node : contents.trees[t]) all.emplace_back(t, &node);
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, all.size(), 64), [&](const auto& range) {
            std::vector<int32_t> slots(kBrickSamples);
            std::vector<unsigned char> bytes;
            for (std::size_t k = range.begin(); k != range.end(); ++k) {
                const auto [t, node] = all[k];
                bytes.resize(static_cast<std::size_t>(bkm_brick_size(*node, ds)));
                encode_brick(*lattices[t][node->depth], *node, ds, slots.data(),
                             bytes.data());
                node->crc = bkm_crc32(0, bytes.data(), bytes.size());
            }
        });
}

/// Writes the file atomically: everything before the bricks, then the
/// bricks in table order, encoded in parallel batches.
void write_file(const std::string& path, const BkmContents& contents,
                const Lattices& lattices, Progress* progress) {
    const int ds = contents.info.data_size;
    AtomicOutput output(path);
    {
        ByteSink sink(output.temp_path(), path, false);
        const std::vector<unsigned char> head = bkm_encode_head(contents);
        sink.write(head.data(), head.size());
        std::vector<std::pair<int, const BkmNode*>> all;
        for (int t = 0; t < kBkmTrees; ++t)
            for (const BkmNode& node : contents.trees[t]) all.emplace_back(t, &node);
        const uint64_t brick_bytes = contents.info.file_size - head.size();
        uint64_t written = 0;
        constexpr std::size_t kBatch = 2048;
        std::vector<unsigned char> buffer;
        std::vector<uint64_t> at;
        for (std::size_t b0 = 0; b0 < all.size(); b0 += kBatch) {
            const std::size_t b1 = std::min(all.size(), b0 + kBatch);
            at.assign(b1 - b0 + 1, 0);
            for (std::size_t k = b0; k < b1; ++k)
                at[k - b0 + 1] = at[k - b0] + bkm_brick_size(*all[k].second, ds);
            buffer.resize(at.back());
            tbb::parallel_for(
                tbb::blocked_range<std::size_t>(b0, b1, 64), [&](const auto& range) {
                    std::vector<int32_t> slots(kBrickSamples);
                    for (std::size_t k = range.begin(); k != range.end(); ++k) {
                        const auto [t, node] = all[k];
                        encode_brick(*lattices[t][node->depth], *node, ds, slots.data(),
                                     buffer.data() + at[k - b0]);
                    }
                });
            sink.write(buffer.data(), buffer.size());
            written += buffer.size();
            if (progress) {
                progress->update(kProgressSplat + kProgressPrune +
                                     kProgressWrite * written /
                                         std::max<uint64_t>(brick_bytes, 1),
                                 kProgressTotal);
            }
        }
        sink.close();
    }
    output.commit();
}

} // namespace

BrickMapBuildReport build_brick_map(const std::vector<PointCloud>& clouds,
                                    const BrickMapBuildOptions& options,
                                    const std::string& path) {
    const Stopwatch clock;
    check_options(options);
    Progress* progress = options.progress;

    // Merge (channels matched by name and type; the first cloud's header wins).
    Input in;
    PointCloud merged;
    if (clouds.size() == 1) {
        in.cloud = &clouds[0];
    } else if (!clouds.empty()) {
        merged = clouds[0];
        for (std::size_t i = 1; i < clouds.size(); ++i) merged.append(clouds[i]);
        in.cloud = &merged;
    }
    if (!in.cloud || in.cloud->size() == 0)
        throw ValueError("brick map: no points to build a brick map from");
    const PointCloud& cloud = *in.cloud;
    check_arrays(cloud);
    if (cloud.size() > std::numeric_limits<uint32_t>::max())
        throw ValueError("brick map: too many points");
    in.selected = select_channels(cloud, options.channels);
    for (const Selected& s : in.selected) in.data_size += channel_type_size(s.type);
    if (in.data_size > kBkmMaxDataSize)
        throw ValueError("brick map: " + std::to_string(in.data_size) +
                         " floats per sample; at most " +
                         std::to_string(kBkmMaxDataSize) + " are supported");
    in.area = cloud.find_channel("_area");
    if (in.area && in.area->type != ChannelType::Float) in.area = nullptr;
    scan_points(in, options);

    Lattices lattices;
    {
        // Sort keys, positions, footprints, values, levels and tree lists.
        check_memory(uint64_t(cloud.size()) * (80 + 4 * uint64_t(in.data_size)),
                     "brick map: preparing " + std::to_string(cloud.size()) + " points",
                     "build the map from fewer points");
        const Points pts = prepare_points(in, options);
        const BuildEstimate estimate = estimate_build(pts);
        check_brick_count(estimate.nodes, options, true);
        check_memory(estimate.bytes,
                     "brick map: building at least " + std::to_string(estimate.nodes) +
                         " bricks (-maxdepth " + std::to_string(options.max_depth) + ")",
                     "lower -maxdepth or raise -radiusscale for fewer bricks");
        lattices = splat_all(pts, progress);
    } // the lattices hold everything from here on

    // Nodes with data, then pruning.
    std::array<std::vector<LevelNodes>, kBkmTrees> levels;
    for (int t = 0; t < kBkmTrees; ++t) levels[t].resize(lattices[t].size());
    tbb::parallel_for(
        std::size_t(0), std::size_t(kBkmTrees) * (kBkmMaxDepth + 1), [&](std::size_t k) {
            const std::size_t t = k / (kBkmMaxDepth + 1), d = k % (kBkmMaxDepth + 1);
            if (d < lattices[t].size())
                levels[t][d].keys = nodes_with_data(*lattices[t][d]);
        });
    uint64_t total_nodes = 0;
    for (int t = 0; t < kBkmTrees; ++t)
        for (const LevelNodes& L : levels[t]) total_nodes += L.keys.size();
    std::atomic<uint64_t> prune_done{0};
    for (int t = 0; t < kBkmTrees; ++t) {
        prune_tree(lattices[t], levels[t], options.max_error, in.data_size, progress,
                   prune_done, total_nodes, kProgressSplat);
    }

    BkmContents contents;
    BrickMapInfo& info = contents.info;
    info.version = kBkmVersion;
    for (const Selected& s : in.selected) info.channels.emplace_back(s.name, s.type);
    info.data_size = in.data_size;
    info.bbox_min = in.lo;
    info.bbox_max = in.hi;
    info.cube_min = in.cube_min;
    info.cube_side = in.side;
    info.max_depth = options.max_depth;
    info.max_error = options.max_error;
    info.ignore_normals = options.ignore_normals;
    info.omit_geometry = options.omit_geometry;
    info.world_to_eye = cloud.world_to_eye;
    info.world_to_ndc = cloud.world_to_ndc;
    info.format = cloud.format;
    info.provenance = options.provenance;
    make_tables(levels, options.omit_geometry, contents);
    uint64_t written = 0;
    for (const auto& table : contents.trees) written += table.size();
    check_brick_count(written, options, false);
    compute_brick_crcs(contents, lattices);
    write_file(path, contents, lattices, progress);
    if (progress) progress->finish();

    BrickMapBuildReport report;
    report.points = cloud.size();
    report.bricks_before_pruning = total_nodes;
    for (const auto& table : contents.trees)
        for (const BkmNode& node : table)
            report.bricks_written += node.has_data() ? 1 : 0;
    report.file_size = info.file_size;
    report.seconds = clock.seconds();
    return report;
}

} // namespace sss
