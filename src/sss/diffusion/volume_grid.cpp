// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#include "volume_grid.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <deque>
#include <limits>

#include <glm/geometric.hpp>
#include <glm/vector_relational.hpp>
#include <oneapi/tbb/parallel_for.h>

#include "sss/util/error.h"

namespace sss::volume_detail {

glm::ivec3 VoxelGrid::cell_of(const glm::dvec3& p) const {
    glm::ivec3 c;
    for (int a = 0; a < 3; ++a) {
        const double t = std::floor((p[a] - origin[a]) / h + 0.5);
        c[a] = int(std::clamp(t, 0.0, double(dim[a] - 1)));
    }
    return c;
}

int8_t VoxelGrid::label_at(const glm::dvec3& p) const {
    const glm::ivec3 c = cell_of(p);
    return label[voxel(c.x, c.y, c.z)];
}

VoxelGrid make_grid(const glm::dvec3& lo, const glm::dvec3& hi, double h, int pad) {
    VoxelGrid g;
    g.h = h;
    for (int a = 0; a < 3; ++a) {
        const double cells = std::ceil((hi[a] - lo[a]) / h);
        if (!(cells < 1e6)) throw ValueError("volume diffusion: the grid is too large");
        g.dim[a] = int(cells) + 1 + 2 * pad;
    }
    g.origin = lo - double(pad) * h;
    return g;
}

namespace {

// A voxel's nearest sample so far, as one ordered key: the squared distance's
// float bits (monotonic for non-negative floats) above the sample's index, so
// that concurrent minimums give the same winner at any thread count.
uint64_t sample_key(float d2, uint32_t j) {
    uint32_t bits;
    std::memcpy(&bits, &d2, sizeof bits);
    return (uint64_t(bits) << 32) | j;
}

void atomic_min(std::atomic<uint64_t>& a, uint64_t v) {
    uint64_t cur = a.load(std::memory_order_relaxed);
    while (v < cur && !a.compare_exchange_weak(cur, v, std::memory_order_relaxed)) {
    }
}

} // namespace

std::vector<int8_t> inside_voxels(const VoxelGrid& g, const SurfaceSamples& s) {
    const std::size_t nv = g.count();
    constexpr uint64_t kEmpty = ~uint64_t(0);
    std::vector<std::atomic<uint64_t>> nearest(nv);
    for (auto& a : nearest) a.store(kEmpty, std::memory_order_relaxed);
    const std::size_t n = s.positions.size();
    // Each sample claims the voxels within its reach; the reach covers the
    // gaps between neighbouring samples and the voxel diagonal, so the
    // claimed band is a closed shell the flood fill cannot cross.
    oneapi::tbb::parallel_for(std::size_t(0), n, [&](std::size_t j) {
        const glm::dvec3 p(s.positions[j]);
        const double r = std::sqrt(std::max(0.0, double(s.areas[j])) / M_PI);
        const double reach = std::max(2.0 * r, g.h) + g.h;
        glm::ivec3 lo, hi;
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::max(0, int(std::ceil((p[a] - reach - g.origin[a]) / g.h)));
            hi[a] = std::min(g.dim[a] - 1,
                             int(std::floor((p[a] + reach - g.origin[a]) / g.h)));
        }
        for (int z = lo.z; z <= hi.z; ++z)
            for (int y = lo.y; y <= hi.y; ++y)
                for (int x = lo.x; x <= hi.x; ++x) {
                    const glm::dvec3 d = g.centre(x, y, z) - p;
                    const double d2 = d.x * d.x + d.y * d.y + d.z * d.z;
                    if (d2 > reach * reach) continue;
                    atomic_min(nearest[g.voxel(x, y, z)],
                               sample_key(float(d2), uint32_t(j)));
                }
    });
    std::vector<int8_t> inside(nv, -1);
    for (int z = 0; z < g.dim.z; ++z)
        for (int y = 0; y < g.dim.y; ++y)
            for (int x = 0; x < g.dim.x; ++x) {
                const std::size_t v = g.voxel(x, y, z);
                const uint64_t key = nearest[v].load(std::memory_order_relaxed);
                if (key == kEmpty) continue;
                const uint32_t j = uint32_t(key & 0xffffffffu);
                const glm::dvec3 d = g.centre(x, y, z) - glm::dvec3(s.positions[j]);
                inside[v] = glm::dot(d, glm::dvec3(s.normals[j])) < 0.0 ? 1 : 0;
            }
    std::vector<std::atomic<uint64_t>>().swap(nearest);
    // The grid's border is outside; the rest takes the side of the claimed
    // voxels it is connected to (breadth first, in voxel order).
    std::deque<std::size_t> queue;
    for (int z = 0; z < g.dim.z; ++z)
        for (int y = 0; y < g.dim.y; ++y)
            for (int x = 0; x < g.dim.x; ++x) {
                const std::size_t v = g.voxel(x, y, z);
                const bool border = x == 0 || y == 0 || z == 0 || x == g.dim.x - 1 ||
                                    y == g.dim.y - 1 || z == g.dim.z - 1;
                if (inside[v] < 0 && border) inside[v] = 0;
                if (inside[v] >= 0) queue.push_back(v);
            }
    const std::ptrdiff_t step[3] = {1, g.dim.x, std::ptrdiff_t(g.dim.x) * g.dim.y};
    while (!queue.empty()) {
        const std::size_t v = queue.front();
        queue.pop_front();
        const std::size_t x = v % std::size_t(g.dim.x);
        const std::size_t y = (v / std::size_t(g.dim.x)) % std::size_t(g.dim.y);
        const std::size_t z = v / (std::size_t(g.dim.x) * std::size_t(g.dim.y));
        const std::size_t c[3] = {x, y, z};
        for (int a = 0; a < 3; ++a)
            for (int sgn = -1; sgn <= 1; sgn += 2) {
                if ((sgn < 0 && c[a] == 0) ||
                    (sgn > 0 && c[a] + 1 >= std::size_t(g.dim[a])))
                    continue;
                const std::size_t w = std::size_t(std::ptrdiff_t(v) + sgn * step[a]);
                if (inside[w] < 0) {
                    inside[w] = inside[v];
                    queue.push_back(w);
                }
            }
    }
    return inside;
}

std::vector<double> nearest_source_distance(const VoxelGrid& g,
                                            const std::vector<glm::dvec3>& sources,
                                            const std::vector<glm::vec3>& queries) {
    std::vector<double> out(queries.size(), std::numeric_limits<double>::infinity());
    if (sources.empty()) return out;
    std::vector<int32_t> nearest(g.count(), -1);
    std::vector<double> best(g.count(), std::numeric_limits<double>::infinity());
    std::deque<glm::ivec3> queue;
    const auto offer = [&](const glm::ivec3& c, int32_t s) {
        const std::size_t v = g.voxel(c.x, c.y, c.z);
        const glm::dvec3 d = g.centre(c.x, c.y, c.z) - sources[std::size_t(s)];
        const double d2 = glm::dot(d, d);
        if (d2 >= best[v]) return;
        if (nearest[v] < 0 || d2 < best[v]) queue.push_back(c);
        best[v] = d2;
        nearest[v] = s;
    };
    for (std::size_t s = 0; s < sources.size(); ++s)
        offer(g.cell_of(sources[s]), int32_t(s));
    const glm::ivec3 step[6] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};
    while (!queue.empty()) {
        const glm::ivec3 c = queue.front();
        queue.pop_front();
        const int32_t s = nearest[g.voxel(c.x, c.y, c.z)];
        for (const glm::ivec3& d : step) {
            const glm::ivec3 n = c + d;
            if (glm::any(glm::lessThan(n, glm::ivec3(0))) ||
                glm::any(glm::greaterThanEqual(n, g.dim)))
                continue;
            offer(n, s);
        }
    }
    for (std::size_t j = 0; j < queries.size(); ++j) {
        const glm::dvec3 q(queries[j]);
        const glm::ivec3 c = g.cell_of(q);
        const int32_t s = nearest[g.voxel(c.x, c.y, c.z)];
        if (s >= 0) out[j] = glm::length(q - sources[std::size_t(s)]);
    }
    return out;
}

std::vector<double> ray_thickness(const VoxelGrid& g, const SurfaceSamples& surface,
                                  const std::vector<SurfaceSamples>& blockers,
                                  double limit) {
    std::vector<const SurfaceSamples*> sets = {&surface};
    for (const SurfaceSamples& b : blockers) sets.push_back(&b);
    const auto reach = [&](const SurfaceSamples& s, std::size_t k) {
        return 1.5 *
               std::max(std::sqrt(std::max(0.0, double(s.areas[k])) / M_PI), 0.5 * g.h);
    };
    // Every voxel lists the disks that reach into it (set, sample).
    const std::size_t nv = g.count();
    std::vector<uint32_t> start(nv + 1, 0);
    std::vector<std::pair<uint32_t, uint32_t>> refs;
    for (int pass = 0; pass < 2; ++pass) {
        for (uint32_t set = 0; set < sets.size(); ++set) {
            const SurfaceSamples& s = *sets[set];
            for (std::size_t k = 0; k < s.positions.size(); ++k) {
                const glm::dvec3 p(s.positions[k]);
                const double r = reach(s, k);
                const glm::ivec3 lo = g.cell_of(p - glm::dvec3(r)),
                                 hi = g.cell_of(p + glm::dvec3(r));
                for (int z = lo.z; z <= hi.z; ++z)
                    for (int y = lo.y; y <= hi.y; ++y)
                        for (int x = lo.x; x <= hi.x; ++x) {
                            const std::size_t v = g.voxel(x, y, z);
                            if (pass == 0)
                                ++start[v + 1];
                            else
                                refs[start[v]++] = {set, uint32_t(k)};
                        }
            }
        }
        if (pass == 0) {
            for (std::size_t v = 0; v < nv; ++v) start[v + 1] += start[v];
            refs.resize(start[nv]);
        } else {
            for (std::size_t v = nv; v > 0; --v) start[v] = start[v - 1];
            start[0] = 0;
        }
    }
    const std::size_t n = surface.positions.size();
    std::vector<double> t(n, limit);
    oneapi::tbb::parallel_for(std::size_t(0), n, [&](std::size_t j) {
        const glm::dvec3 p(surface.positions[j]);
        const glm::dvec3 dir = -glm::normalize(glm::dvec3(surface.normals[j]));
        // Amanatides and Woo's walk through the voxels, in voxel units.
        const glm::dvec3 q = (p - g.origin) / g.h + 0.5;
        glm::ivec3 c, step;
        glm::dvec3 next, delta;
        for (int a = 0; a < 3; ++a) {
            c[a] = int(std::floor(q[a]));
            step[a] = dir[a] > 0 ? 1 : -1;
            delta[a] = dir[a] != 0 ? std::abs(1.0 / dir[a]) : 1e300;
            const double edge =
                dir[a] > 0 ? std::floor(q[a]) + 1 - q[a] : q[a] - std::floor(q[a]);
            next[a] = dir[a] != 0 ? edge * delta[a] : 1e300;
        }
        double best = limit;
        double travelled = 0; // voxel units
        while (travelled * g.h < best) {
            if (glm::any(glm::lessThan(c, glm::ivec3(0))) ||
                glm::any(glm::greaterThanEqual(c, g.dim)))
                break;
            const std::size_t v = g.voxel(c.x, c.y, c.z);
            for (uint32_t i = start[v]; i < start[v + 1]; ++i) {
                const auto [set, k] = refs[i];
                if (set == 0 && k == j) continue;
                const SurfaceSamples& s = *sets[set];
                const glm::dvec3 nq = glm::normalize(glm::dvec3(s.normals[k]));
                const double denom = glm::dot(dir, nq);
                // Out of the medium through a surface facing along the ray,
                // into a blocker through one facing against it.
                if (set == 0 ? denom < 0.2 : denom > -0.2) continue;
                const glm::dvec3 pq(s.positions[k]);
                const double tk = glm::dot(pq - p, nq) / denom;
                if (!(tk > 0.05 * g.h) || tk >= best) continue;
                const glm::dvec3 hit = p + tk * dir - pq;
                const double r = reach(s, k);
                if (glm::dot(hit, hit) <= r * r) best = tk;
            }
            const int a =
                next.x < next.y ? (next.x < next.z ? 0 : 2) : (next.y < next.z ? 1 : 2);
            travelled = next[a];
            next[a] += delta[a];
            c[a] += step[a];
        }
        t[j] = best;
    });
    return t;
}

Unknowns number_unknowns(const VoxelGrid& g) {
    Unknowns u;
    u.index.assign(g.count(), -1);
    for (std::size_t v = 0; v < g.count(); ++v)
        if (g.label[v] == kMedium) {
            u.index[v] = int32_t(u.voxels.size());
            u.voxels.push_back(uint32_t(v));
        }
    u.neighbours.resize(u.voxels.size());
    const std::ptrdiff_t step[3] = {1, g.dim.x, std::ptrdiff_t(g.dim.x) * g.dim.y};
    oneapi::tbb::parallel_for(std::size_t(0), u.voxels.size(), [&](std::size_t k) {
        const std::size_t v = u.voxels[k];
        const std::size_t c[3] = {v % std::size_t(g.dim.x),
                                  (v / std::size_t(g.dim.x)) % std::size_t(g.dim.y),
                                  v / (std::size_t(g.dim.x) * std::size_t(g.dim.y))};
        for (int a = 0; a < 3; ++a)
            for (int side = 0; side < 2; ++side) {
                int32_t& nb = u.neighbours[k][std::size_t(2 * a + side)];
                nb = Unknowns::kNone;
                if ((side == 0 && c[a] == 0) ||
                    (side == 1 && c[a] + 1 >= std::size_t(g.dim[a])))
                    continue;
                const std::size_t w =
                    std::size_t(std::ptrdiff_t(v) + (side == 0 ? -step[a] : step[a]));
                if (g.label[w] == kMedium)
                    nb = u.index[w];
                else if (g.label[w] == kBlocker)
                    nb = Unknowns::kBlack;
            }
    });
    return u;
}

bool medium_stencil(const VoxelGrid& g, const Unknowns& u, const glm::dvec3& p,
                    Stencil& out) {
    const glm::dvec3 t = (p - g.origin) / g.h;
    glm::ivec3 base;
    glm::dvec3 f;
    for (int a = 0; a < 3; ++a) {
        const double fl = std::floor(t[a]);
        base[a] = int(fl);
        f[a] = t[a] - fl;
    }
    out.n = 0;
    double total = 0;
    for (int corner = 0; corner < 8; ++corner) {
        const glm::ivec3 c =
            base + glm::ivec3(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
        if (c.x < 0 || c.y < 0 || c.z < 0 || c.x >= g.dim.x || c.y >= g.dim.y ||
            c.z >= g.dim.z)
            continue;
        const int32_t k = u.index[g.voxel(c.x, c.y, c.z)];
        if (k < 0) continue;
        const double w = ((corner & 1) ? f.x : 1 - f.x) *
                         (((corner >> 1) & 1) ? f.y : 1 - f.y) *
                         (((corner >> 2) & 1) ? f.z : 1 - f.z);
        if (w <= 0) continue;
        out.unknown[out.n] = k;
        out.weight[out.n] = w;
        ++out.n;
        total += w;
    }
    if (out.n == 0 || !(total > 0)) {
        out.n = 0;
        return false;
    }
    for (int i = 0; i < out.n; ++i) out.weight[i] /= total;
    return true;
}

} // namespace sss::volume_detail
