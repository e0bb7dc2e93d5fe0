// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#include "sss/diffusion/volume.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>

#include <glm/geometric.hpp>
#include <glm/vector_relational.hpp>
#include <oneapi/tbb/parallel_for.h>

#include "sss/diffusion/slab_transport.h"
#include "sss/util/error.h"
#include "sss/util/limits.h"
#include "sss/util/progress.h"
#include "volume_grid.h"

namespace sss {

using namespace volume_detail;

namespace {

// One channel's medium in the diffusion approximation.
struct Medium {
    double sigma_t = 0; // sigma_t' = sigma_s' + sigma_a
    double alpha = 0;   // sigma_s' / sigma_t'
    double sigma_a = 0;
    double D = 0;    // sigma_a / (k sigma_t')^2, about 1 / (3 sigma_t')
    double A = 1;    // boundary mismatch (1 + F_dr) / (1 - F_dr)
    double dmfp = 0; // 1 / sigma_tr (inf without absorption)
    double eta = 1;  // relative index of refraction
    // Diffuse light: the share of the first collisions above depth i
    // kShareStep (in l), and the depth (in l) above which the share i /
    // (kQuantiles - 1) of them lies. Empty: straight light (exponential).
    std::vector<double> share, quantile;
};

constexpr double kShareStep = 0.01;
constexpr int kShareSteps = 1000, kQuantiles = 1025;

Medium medium_of(const ChannelCoefficients& c, bool diffuse) {
    Medium m;
    m.sigma_t = c.sigma_s_prime + c.sigma_a;
    if (!(c.sigma_s_prime > 0) || !std::isfinite(m.sigma_t))
        throw ValueError("volume diffusion needs a scattering medium (sigma_s' > 0)");
    m.alpha = c.sigma_s_prime / m.sigma_t;
    m.sigma_a = c.sigma_a;
    m.D = 1.0 / (3.0 * m.sigma_t);
    if (m.alpha < 1.0 - 1e-6) {
        // Light decays with transport theory's asymptotic rate k sigma_t
        // (alpha atanh(k) / k = 1), not diffusion's sqrt(3 (1 - alpha)):
        // the same in a nearly white medium, 15 % slower in skin's blue, so
        // that light reaches the far sides of small and thin parts.
        double lo = 0.0, hi = 1.0;
        for (int i = 0; i < 60; ++i) {
            const double k = 0.5 * (lo + hi);
            (m.alpha * std::atanh(k) / k < 1.0 ? lo : hi) = k;
        }
        const double k = 0.5 * (lo + hi);
        m.D = (1.0 - m.alpha) / (k * k * m.sigma_t);
    }
    const double fdr = fresnel_diffuse_reflectance(c.ior);
    m.A = (1.0 + fdr) / (1.0 - fdr);
    m.eta = c.ior;
    const double sigma_tr = std::sqrt(3.0 * c.sigma_a * m.sigma_t);
    m.dmfp = sigma_tr > 0 ? 1.0 / sigma_tr : std::numeric_limits<double>::infinity();
    if (diffuse) {
        for (int i = 0; i <= kShareSteps; ++i)
            m.share.push_back(first_collision_share(m.eta, i * kShareStep, true));
        std::size_t i = 0;
        for (int k = 0; k < kQuantiles; ++k) {
            const double u = std::min(double(k) / (kQuantiles - 1), m.share.back());
            while (i + 1 < m.share.size() && m.share[i + 1] < u) ++i;
            const double span =
                i + 1 < m.share.size() ? m.share[i + 1] - m.share[i] : 0.0;
            const double f =
                span > 0 ? std::clamp((u - m.share[i]) / span, 0.0, 1.0) : 0.0;
            m.quantile.push_back((double(i) + f) * kShareStep);
        }
    }
    return m;
}

// Depths of the first collisions of the light entering at a point: the
// midpoint quantiles of their distribution (the exponential free path along
// the normal for straight light), within the share `inside` of them that
// lies before the light leaves the medium (so that the source, and what a
// thin part transmits, changes smoothly with the thickness).
constexpr int kBeamSamples = 8;
double beam_depth(int k, const Medium& m, double inside = 1.0) {
    const double u = inside * (k + 0.5) / kBeamSamples;
    if (m.quantile.empty()) return -std::log(1.0 - u) / m.sigma_t;
    const double t = u * (kQuantiles - 1);
    const std::size_t i = std::min(std::size_t(t), std::size_t(kQuantiles - 2));
    const double f = t - double(i);
    return ((1 - f) * m.quantile[i] + f * m.quantile[i + 1]) / m.sigma_t;
}

// Past this many mean free paths the remaining collisions are negligible
// (e^-8): light that meets no exit within them is not cut.
constexpr double kBeamReach = 8.0;

// The share of the first collisions above depth z.
double collided_above(const Medium& m, double z) {
    if (m.share.empty()) return -std::expm1(-m.sigma_t * z);
    const double t = std::max(0.0, z * m.sigma_t / kShareStep);
    if (t >= kShareSteps) return m.share.back();
    const std::size_t i = std::size_t(t);
    const double f = t - double(i);
    return (1 - f) * m.share[i] + f * m.share[i + 1];
}

// The share of the first collisions before the light leaves the medium at
// depth `exit` (at `limit`: none found).
double beam_inside(double exit, double limit, const Medium& m) {
    return exit >= limit ? 1.0 : collided_above(m, exit);
}

// The surface at the resolution of voxels of edge h: the points of one voxel
// that face one way (the sign of their normal's largest component) merged
// into one sample, with their summed area and flux and area-weighted position
// and normal. The volume's cost then follows its voxels, not the density of
// the cloud.
struct Surfels {
    SurfaceSamples samples;
    std::vector<glm::dvec3> flux;   // sum of A E per channel
    std::vector<uint32_t> of_point; // the surfel each input point went into
};

// Points whose disk is wider than a voxel, split into squares of about a
// voxel on their tangent plane (the square of the disk's area), so that a
// coarse cloud lets light out and in all over its surface, not through one
// voxel per point. owner: the input point of each sample.
struct Split {
    SurfaceSamples samples;
    std::vector<glm::vec3> irradiance;
    std::vector<uint32_t> owner;
};

Split split_large(const SurfaceSamples& in, const std::vector<glm::vec3>* irradiance,
                  double h) {
    Split out;
    const std::size_t n = in.positions.size();
    // Bounded for any areas: past this many samples points stay whole.
    const std::size_t cap = std::max<std::size_t>(4 * n, std::size_t(1) << 25);
    std::size_t total = 0;
    for (std::size_t j = 0; j < n; ++j) {
        const double area = std::max(0.0, double(in.areas[j]));
        const double side = std::sqrt(area);
        int k = std::clamp(int(std::ceil(side / h)), 1, 64);
        if (total + std::size_t(k * k) + (n - j) > cap) k = 1;
        total += std::size_t(k * k);
        const glm::vec3 e = irradiance ? (*irradiance)[j] : glm::vec3(0.0f);
        if (k == 1) {
            out.samples.positions.push_back(in.positions[j]);
            out.samples.normals.push_back(in.normals[j]);
            out.samples.areas.push_back(in.areas[j]);
            out.irradiance.push_back(e);
            out.owner.push_back(uint32_t(j));
            continue;
        }
        const glm::dvec3 nr = glm::normalize(glm::dvec3(in.normals[j]));
        const glm::dvec3 helper =
            std::abs(nr.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
        const glm::dvec3 t1 = glm::normalize(glm::cross(nr, helper)),
                         t2 = glm::cross(nr, t1);
        for (int v = 0; v < k; ++v)
            for (int u = 0; u < k; ++u) {
                const double a = ((u + 0.5) / k - 0.5) * side,
                             b = ((v + 0.5) / k - 0.5) * side;
                out.samples.positions.push_back(
                    glm::vec3(glm::dvec3(in.positions[j]) + a * t1 + b * t2));
                out.samples.normals.push_back(in.normals[j]);
                out.samples.areas.push_back(float(area / double(k * k)));
                out.irradiance.push_back(e);
                out.owner.push_back(uint32_t(j));
            }
    }
    return out;
}

Surfels make_surfels(const SurfaceSamples& original,
                     const std::vector<glm::vec3>* original_irradiance,
                     const VoxelGrid& grid) {
    const Split split = split_large(original, original_irradiance, grid.h);
    const SurfaceSamples& in = split.samples;
    const std::vector<glm::vec3>* irradiance =
        original_irradiance ? &split.irradiance : nullptr;
    const std::size_t n = in.positions.size();
    std::vector<uint64_t> key(n);
    oneapi::tbb::parallel_for(std::size_t(0), n, [&](std::size_t j) {
        const glm::vec3& nr = in.normals[j];
        const glm::vec3 a = glm::abs(nr);
        const int axis = a.x >= a.y && a.x >= a.z ? 0 : (a.y >= a.z ? 1 : 2);
        const int face = 2 * axis + (nr[axis] < 0.0f ? 1 : 0);
        const glm::ivec3 c = grid.cell_of(glm::dvec3(in.positions[j]));
        key[j] = uint64_t(grid.voxel(c.x, c.y, c.z)) * 6u + uint64_t(face);
    });
    // Points in key order, each key's points in index order: a counting
    // sort when the keys are few against the points, else a sort.
    std::vector<uint32_t> order(n);
    const std::size_t keys = grid.count() * 6;
    if (keys <= std::max<std::size_t>(4 * n, std::size_t(1) << 22)) {
        std::vector<uint32_t> start(keys + 1, 0);
        for (std::size_t j = 0; j < n; ++j) ++start[key[j] + 1];
        for (std::size_t k = 0; k < keys; ++k) start[k + 1] += start[k];
        for (std::size_t j = 0; j < n; ++j) order[start[key[j]]++] = uint32_t(j);
    } else {
        for (std::size_t j = 0; j < n; ++j) order[j] = uint32_t(j);
        std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
            return key[a] != key[b] ? key[a] < key[b] : a < b;
        });
    }
    Surfels s;
    s.of_point.assign(original.positions.size(), ~uint32_t(0));
    for (std::size_t k = 0; k < n;) {
        std::size_t e = k;
        glm::dvec3 p(0.0), nr(0.0), flux(0.0), mean(0.0);
        double area = 0;
        for (; e < n && key[order[e]] == key[order[k]]; ++e) {
            const uint32_t j = order[e];
            const double a = double(in.areas[j]);
            p += a * glm::dvec3(in.positions[j]);
            mean += glm::dvec3(in.positions[j]);
            nr += std::max(a, 1e-30) * glm::normalize(glm::dvec3(in.normals[j]));
            area += a;
            if (irradiance) flux += a * glm::dvec3((*irradiance)[j]);
            uint32_t& of = s.of_point[split.owner[j]];
            of = std::min(of, uint32_t(s.flux.size()));
        }
        const double count = double(e - k);
        s.samples.positions.push_back(glm::vec3(area > 0 ? p / area : mean / count));
        const double len = glm::length(nr);
        s.samples.normals.push_back(len > 0 ? glm::vec3(nr / len) : in.normals[order[k]]);
        s.samples.areas.push_back(float(area));
        s.flux.push_back(flux);
        k = e;
    }
    return s;
}

// One grid of the cascade with what the system needs of it.
struct Level {
    VoxelGrid grid;
    Unknowns u;
    // Per surface point: the medium voxel it leaks through (-1: none) and
    // that voxel centre's depth below the point's tangent plane.
    std::vector<int32_t> leak_voxel;
    std::vector<double> leak_depth;
    // Per surface point: where its beam leaves the medium or meets a blocker
    // (at most the deepest collision the source samples).
    std::vector<double> beam_exit;
    double beam_limit = 0; // beam_exit's value where no exit was found
};

Level make_level(const glm::dvec3& lo, const glm::dvec3& hi, double h,
                 const SurfaceSamples& surface,
                 const std::vector<SurfaceSamples>& blockers, double beam_limit) {
    Level l;
    l.grid = make_grid(lo, hi, h, 2);
    // What a level holds per voxel of its grid with the solve's vectors
    // (measured: a whole run peaks at 73-80 bytes per voxel of its finest grid,
    // slabs of 5M and 18M voxels; the coarser levels are resident by then).
    constexpr uint64_t kBytesPerVoxel = 72;
    check_memory(uint64_t(l.grid.count()) * kBytesPerVoxel,
                 "the volume diffusion's grid of " + std::to_string(l.grid.dim.x) + "x" +
                     std::to_string(l.grid.dim.y) + "x" + std::to_string(l.grid.dim.z) +
                     " voxels",
                 "run it where more memory is available (the grid holds at most 12M "
                 "voxels in the object's box)");
    std::vector<int8_t> in = inside_voxels(l.grid, surface);
    l.grid.label.assign(l.grid.count(), kOutside);
    for (std::size_t v = 0; v < in.size(); ++v)
        if (in[v] == 1) l.grid.label[v] = kMedium;
    for (const SurfaceSamples& b : blockers) {
        const std::vector<int8_t> bin = inside_voxels(l.grid, b);
        for (std::size_t v = 0; v < bin.size(); ++v)
            if (bin[v] == 1 && l.grid.label[v] == kMedium) l.grid.label[v] = kBlocker;
    }
    l.u = number_unknowns(l.grid);
    // Without a limit the beams are cut later (beam_exits), if at all.
    if (beam_limit > 0)
        l.beam_exit = ray_thickness(l.grid, surface, blockers, beam_limit);
    l.beam_limit = beam_limit;
    const std::size_t n = surface.positions.size();
    l.leak_voxel.assign(n, -1);
    l.leak_depth.assign(n, 0.0);
    oneapi::tbb::parallel_for(std::size_t(0), n, [&](std::size_t j) {
        const glm::dvec3 p(surface.positions[j]);
        const glm::dvec3 nrm = glm::normalize(glm::dvec3(surface.normals[j]));
        // The medium voxel nearest to the point half a voxel below it.
        const glm::dvec3 q = p - 0.5 * h * nrm;
        const glm::ivec3 c = l.grid.cell_of(q);
        double best = std::numeric_limits<double>::infinity();
        for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const glm::ivec3 e = c + glm::ivec3(dx, dy, dz);
                    if (glm::any(glm::lessThan(e, glm::ivec3(0))) ||
                        glm::any(glm::greaterThanEqual(e, l.grid.dim)))
                        continue;
                    const int32_t k = l.u.index[l.grid.voxel(e.x, e.y, e.z)];
                    if (k < 0) continue;
                    const glm::dvec3 d = l.grid.centre(e.x, e.y, e.z) - q;
                    const double d2 = glm::dot(d, d);
                    if (d2 < best) {
                        best = d2;
                        l.leak_voxel[j] = k;
                        l.leak_depth[j] = std::max(
                            0.0, glm::dot(p - l.grid.centre(e.x, e.y, e.z), nrm));
                    }
                }
    });
    return l;
}

// Up to three sums of a pass over [0, n) in fixed chunks, added in order:
// parallel, and the same at any thread count.
struct Sums {
    double a = 0, b = 0, c = 0;
};
template <class F>
Sums chunked_pass(std::size_t n, F f) {
    constexpr std::size_t kChunk = 8192;
    const std::size_t chunks = (n + kChunk - 1) / kChunk;
    std::vector<Sums> part(chunks);
    oneapi::tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
        part[c] = f(c * kChunk, std::min(n, (c + 1) * kChunk));
    });
    Sums t;
    for (const Sums& q : part) {
        t.a += q.a;
        t.b += q.b;
        t.c += q.c;
    }
    return t;
}

// The deterministic parallel sum of f(i) over [0, n) (chunked_pass()).
template <class F>
double chunked_sum(std::size_t n, F f) {
    return chunked_pass(n,
                        [&](std::size_t b, std::size_t e) {
                            Sums q;
                            for (std::size_t i = b; i < e; ++i) q.a += f(i);
                            return q;
                        })
        .a;
}

// The diffusion system of one channel on one level:
// diag_k phi_k - D h sum_{medium neighbours} phi_n = source_k, where diag
// holds the absorption, the exchange with the neighbours, the black
// blocker faces and the Robin leaks of the surface points.
struct System {
    const Level* level = nullptr;
    double off = 0;   // D h
    double black = 0; // conductance of a blocker face
    std::vector<double> diag;
    std::vector<double> leak; // per unknown: sum of its points' leak conductances
    std::vector<double> source;
};

System make_system(const Level& l, const Medium& m, const SurfaceSamples& surface,
                   const std::vector<glm::dvec3>& flux_in, int channel) {
    System s;
    s.level = &l;
    const double h = l.grid.h;
    s.off = m.D * h;
    s.black = h * h * m.D / (0.5 * h + 2.0 * m.D);
    const std::size_t nu = l.u.voxels.size();
    s.leak.assign(nu, 0.0);
    s.source.assign(nu, 0.0);
    const std::size_t n = surface.positions.size();
    // Sequential: each point adds into shared voxels in a fixed order.
    for (std::size_t j = 0; j < n; ++j) {
        const int32_t k = l.leak_voxel[j];
        if (k < 0) continue;
        s.leak[std::size_t(k)] +=
            double(surface.areas[j]) / (2.0 * m.A + l.leak_depth[j] / m.D);
    }
    for (std::size_t j = 0; j < n; ++j) {
        const double flux = flux_in[j][channel];
        if (flux == 0.0) continue;
        const glm::dvec3 p(surface.positions[j]);
        const glm::dvec3 nrm = glm::normalize(glm::dvec3(surface.normals[j]));
        // Light that crosses unscattered or reaches a blocker first is no
        // source.
        const double inside = beam_inside(l.beam_exit[j], l.beam_limit, m);
        for (int b = 0; b < kBeamSamples; ++b) {
            const glm::dvec3 q = p - beam_depth(b, m, inside) * nrm;
            Stencil st;
            if (!medium_stencil(l.grid, l.u, q, st)) continue;
            const double q_flux = m.alpha * flux * inside / kBeamSamples;
            for (int i = 0; i < st.n; ++i)
                s.source[std::size_t(st.unknown[i])] += q_flux * st.weight[i];
        }
    }
    s.diag.assign(nu, 0.0);
    oneapi::tbb::parallel_for(std::size_t(0), nu, [&](std::size_t k) {
        double d = m.sigma_a * h * h * h + s.leak[k];
        for (int32_t nbk : l.u.neighbours[k]) {
            if (nbk >= 0) d += s.off;
            if (nbk == Unknowns::kBlack) d += s.black;
        }
        s.diag[k] = d;
    });
    return s;
}

// Jacobi-preconditioned conjugate gradients from x; returns the steps. The
// vectors are floats (the result is wanted to 1e-3), the sums doubles.
int solve(const System& s, std::vector<float>& x, double tolerance, int max_steps) {
    const std::size_t n = x.size();
    const auto& nb = s.level->u.neighbours;
    std::vector<float> r(n), z(n), p(n), ap(n), inv(n), diag(n);
    const float off = float(s.off);
    for (std::size_t k = 0; k < n; ++k) {
        diag[k] = float(s.diag[k]);
        inv[k] = float(1.0 / s.diag[k]);
    }
    // y = A v over [b, e), and sum v.y.
    const auto apply = [&](const std::vector<float>& v, std::vector<float>& y,
                           std::size_t b, std::size_t e) {
        double dot = 0;
        for (std::size_t k = b; k < e; ++k) {
            float t = diag[k] * v[k];
            for (int32_t m : nb[k])
                if (m >= 0) t -= off * v[std::size_t(m)];
            y[k] = t;
            dot += double(v[k]) * double(t);
        }
        return dot;
    };
    Sums t = chunked_pass(n, [&](std::size_t b, std::size_t e) {
        apply(x, ap, b, e);
        Sums q;
        for (std::size_t k = b; k < e; ++k) {
            r[k] = float(s.source[k]) - ap[k];
            z[k] = r[k] * inv[k];
            p[k] = z[k];
            q.a += double(r[k]) * z[k];
            q.b += double(r[k]) * r[k];
            q.c += s.source[k] * s.source[k];
        }
        return q;
    });
    const double bnorm = std::sqrt(t.c);
    if (!(bnorm > 0)) {
        std::fill(x.begin(), x.end(), 0.0f);
        return 0;
    }
    double rz = t.a, rr = t.b;
    int step = 0;
    for (; step < max_steps && std::sqrt(rr) > tolerance * bnorm; ++step) {
        const double pap = chunked_pass(n, [&](std::size_t b, std::size_t e) {
                               return Sums{apply(p, ap, b, e), 0, 0};
                           }).a;
        if (!(pap > 0)) break;
        const float alpha = float(rz / pap);
        t = chunked_pass(n, [&](std::size_t b, std::size_t e) {
            Sums q;
            for (std::size_t k = b; k < e; ++k) {
                x[k] += alpha * p[k];
                r[k] -= alpha * ap[k];
                z[k] = r[k] * inv[k];
                q.a += double(r[k]) * z[k];
                q.b += double(r[k]) * r[k];
            }
            return q;
        });
        const float beta = float(t.a / rz);
        rz = t.a;
        rr = t.b;
        oneapi::tbb::parallel_for(std::size_t(0), n,
                                  [&](std::size_t k) { p[k] = z[k] + beta * p[k]; });
    }
    return step;
}

// phi of a coarser level read at the finer level's unknowns (the cascade's
// starting guess).
std::vector<float> prolong(const Level& coarse, const std::vector<float>& phi,
                           const Level& fine) {
    std::vector<float> x(fine.u.voxels.size(), 0.0f);
    oneapi::tbb::parallel_for(std::size_t(0), x.size(), [&](std::size_t k) {
        const std::size_t v = fine.u.voxels[k];
        const VoxelGrid& g = fine.grid;
        const int xi = int(v % std::size_t(g.dim.x));
        const int yi = int((v / std::size_t(g.dim.x)) % std::size_t(g.dim.y));
        const int zi = int(v / (std::size_t(g.dim.x) * std::size_t(g.dim.y)));
        Stencil st;
        if (!medium_stencil(coarse.grid, coarse.u, g.centre(xi, yi, zi), st)) return;
        double s = 0;
        for (int i = 0; i < st.n; ++i)
            s += st.weight[i] * phi[std::size_t(st.unknown[i])];
        x[k] = float(s);
    });
    return x;
}

// Each channel's blend weights averaged over the surface within about its
// spread length (a box filter on the grid, area-weighted), so that the
// result passes from the profile's to the volume's gradually rather than at
// a seam where the thickness below the surface jumps (the edge of a bone).
void smooth_weights(const VoxelGrid& g, const SurfaceSamples& surface,
                    const double (&spread)[3], std::vector<glm::vec3>& w) {
    const std::size_t nv = g.count(), n = surface.positions.size();
    std::vector<double> num(nv), den(nv), tmp(nv);
    const std::ptrdiff_t stride[3] = {1, g.dim.x, std::ptrdiff_t(g.dim.x) * g.dim.y};
    // A running box sum of half-width r along axis a, in place.
    const auto box = [&](std::vector<double>& f, int a, int r) {
        const int len = g.dim[a];
        const int b1 = (a + 1) % 3, b2 = (a + 2) % 3;
        for (int v = 0; v < g.dim[b2]; ++v)
            for (int u = 0; u < g.dim[b1]; ++u) {
                glm::ivec3 c(0);
                c[b1] = u;
                c[b2] = v;
                const std::size_t base = g.voxel(c.x, c.y, c.z);
                double run = 0;
                for (int i = 0; i < std::min(r, len); ++i)
                    run += f[base + std::size_t(i * stride[a])];
                for (int i = 0; i < len; ++i) {
                    if (i + r < len) run += f[base + std::size_t((i + r) * stride[a])];
                    if (i - r - 1 >= 0)
                        run -= f[base + std::size_t((i - r - 1) * stride[a])];
                    tmp[base + std::size_t(i * stride[a])] = run;
                }
                for (int i = 0; i < len; ++i)
                    f[base + std::size_t(i * stride[a])] =
                        tmp[base + std::size_t(i * stride[a])];
            }
    };
    for (int c = 0; c < 3; ++c) {
        std::fill(num.begin(), num.end(), 0.0);
        std::fill(den.begin(), den.end(), 0.0);
        for (std::size_t j = 0; j < n; ++j) {
            const glm::ivec3 v = g.cell_of(glm::dvec3(surface.positions[j]));
            const std::size_t k = g.voxel(v.x, v.y, v.z);
            const double a = std::max(0.0, double(surface.areas[j]));
            num[k] += a * double(w[j][c]);
            den[k] += a;
        }
        const int r = std::clamp(int(std::lround(0.5 * spread[c] / g.h)), 1, 32);
        for (int a = 0; a < 3; ++a) {
            box(num, a, r);
            box(den, a, r);
        }
        for (std::size_t j = 0; j < n; ++j) {
            const glm::ivec3 v = g.cell_of(glm::dvec3(surface.positions[j]));
            const std::size_t k = g.voxel(v.x, v.y, v.z);
            if (den[k] > 0) w[j][c] = float(std::clamp(num[k] / den[k], 0.0, 1.0));
        }
    }
}

// A beam's first collisions (the share `inside` of them) as sources of a
// column of voxel centres h apart, the first `first` below the lit face:
// each shared between the two nearest centres.
void add_beam(const Medium& m, double h, double first, double inside,
              std::vector<double>& rhs) {
    const std::size_t k_max = rhs.size();
    for (int b = 0; b < kBeamSamples; ++b) {
        const double z = beam_depth(b, m, inside);
        const double t = std::clamp((z - first) / h, 0.0, double(k_max - 1));
        const std::size_t k = std::min(std::size_t(t), k_max - 1);
        const double f = t - double(k), q = m.alpha * inside / kBeamSamples;
        rhs[k] += (1 - f) * q;
        if (f > 0) rhs[k + 1] += f * q;
    }
}

// The column's fluence: diag on the diagonal, -off beside it, solved
// exactly (forward elimination and back substitution, Thomas).
std::vector<double> solve_column(const std::vector<double>& diag, double off,
                                 const std::vector<double>& rhs) {
    const std::size_t k_max = diag.size();
    std::vector<double> c(k_max, 0.0), e(k_max, 0.0), phi(k_max);
    c[0] = -off / diag[0];
    e[0] = rhs[0] / diag[0];
    for (std::size_t k = 1; k < k_max; ++k) {
        const double den = diag[k] + off * c[k - 1];
        c[k] = -off / den;
        e[k] = (rhs[k] + off * e[k - 1]) / den;
    }
    phi[k_max - 1] = e[k_max - 1];
    for (std::size_t k = k_max - 1; k-- > 0;) phi[k] = e[k] - c[k] * phi[k + 1];
    return phi;
}

// The total diffuse reflectance of a uniformly lit half-space in the same
// discretisation as the grids (voxels of edge h below the surface, the leak
// half a voxel above the first centre, the beam's collisions shared between
// the nearest centres): a column of voxels, solved exactly (Thomas).
double halfspace_reflectance(const Medium& m, double h, double first) {
    const double l = 1.0 / m.sigma_t;
    const double reach = std::max(40.0 * l, 12.0 * std::min(m.dmfp, 1e3 * l));
    const std::size_t k_max = std::size_t(std::clamp(std::ceil(reach / h), 8.0, 2e5));
    const double off = m.D / h, leak = 1.0 / (2.0 * m.A + first / m.D);
    std::vector<double> diag(k_max), rhs(k_max, 0.0);
    for (std::size_t k = 0; k < k_max; ++k)
        diag[k] =
            m.sigma_a * h + off * ((k > 0) + (k + 1 < k_max)) + (k == 0 ? leak : 0.0);
    add_beam(m, h, first, 1.0, rhs);
    return leak * solve_column(diag, off, rhs)[0];
}

// The grid's own transmission through a slab of thickness d lit uniformly
// on one face, in the same discretisation as the grids (voxel centres h
// apart, the last one `phase` h above the far face) and read as
// volume_exitance reads it: a voxel deep, scaled to what the leaks let out.
// A column of voxels, solved exactly.
double column_transmission(const Medium& m, double h, double d, double phase) {
    const double far = phase * h;
    const std::size_t k_max =
        std::size_t(std::clamp(std::floor(std::max(0.0, d - far) / h) + 1.0, 1.0, 2e5));
    const double first = std::max(0.0, d - far - double(k_max - 1) * h);
    const double off = m.D / h, leak_top = 1.0 / (2.0 * m.A + first / m.D),
                 leak_far = 1.0 / (2.0 * m.A + std::min(far, d) / m.D);
    std::vector<double> diag(k_max), rhs(k_max, 0.0);
    for (std::size_t k = 0; k < k_max; ++k)
        diag[k] = m.sigma_a * h + off * ((k > 0) + (k + 1 < k_max)) +
                  (k == 0 ? leak_top : 0.0) + (k + 1 == k_max ? leak_far : 0.0);
    add_beam(m, h, first, collided_above(m, d), rhs);
    const std::vector<double> phi = solve_column(diag, off, rhs);
    const auto at = [&](double z) { // phi at depth z, linear between centres
        const double t = std::clamp((z - first) / h, 0.0, double(k_max - 1));
        const std::size_t k = std::min(std::size_t(t), k_max - 1);
        const double f = t - double(k);
        return f > 0 ? (1 - f) * phi[k] + f * phi[k + 1] : phi[k];
    };
    const double top = at(h), bottom = at(d - h);
    const double out = leak_top * phi[0] + leak_far * phi[k_max - 1];
    return top + bottom > 0 ? out * bottom / (top + bottom) : 0.0;
}

// What a voxel diffusion gets wrong through thin parts: it carries light
// with the diffusion's decay and no transient, so an absorbing medium lets
// too much through a few mean free paths and too little through many. The
// factors that bring the grid's slab transmission to transport theory's, at
// thicknesses 1.25x apart from l/4 to d_max (at most 30 l; past the ends the
// end's factor) and for kPhases ways the far face can lie between voxel
// centres (the grid's own transmission depends on it by several percent).
constexpr int kPhases = 4;
struct SlabFactors {
    double lo = 0, log_step = std::log(1.25);
    std::vector<std::array<double, kPhases>> factor;
    // At thickness d, the nearest voxel centre `depth` below the far face;
    // from 1 at d = 0 (light from beside the point) to the first node's.
    double at(double d, double depth, double h) const {
        if (factor.empty()) return 1.0;
        if (d < lo) return 1.0 + d / lo * (at(lo, depth, h) - 1.0);
        const double t = std::clamp(std::log(std::max(d, lo) / lo) / log_step, 0.0,
                                    double(factor.size() - 1));
        const std::size_t k = std::min(std::size_t(t), factor.size() - 1);
        const double f = t - double(k);
        const double u = std::clamp(depth / h * kPhases - 0.5, 0.0, kPhases - 1.0);
        const int p = std::min(int(u), kPhases - 2);
        const double g = u - p;
        const auto in_phase = [&](std::size_t i) {
            return (1 - g) * factor[i][std::size_t(p)] +
                   g * factor[i][std::size_t(p + 1)];
        };
        return f > 0 ? (1 - f) * in_phase(k) + f * in_phase(k + 1) : in_phase(k);
    }
};

SlabFactors slab_factors(const Medium& m, double h, double d_max, bool diffuse) {
    SlabFactors s;
    const double l = 1.0 / m.sigma_t;
    s.lo = 0.25 * l;
    const double hi = std::clamp(d_max, s.lo, 30.0 * l);
    std::array<double, kPhases> last;
    last.fill(1.0);
    for (double d = s.lo;; d *= 1.25) {
        const double t =
            slab_transport(std::min(m.alpha, 1.0 - 1e-9), m.eta, d * m.sigma_t, diffuse)
                .transmittance;
        for (int p = 0; p < kPhases; ++p) {
            const double g = column_transmission(m, h, d, (p + 0.5) / kPhases);
            // Where either is too faint to compare, the thinner slab's factor.
            if (t > 1e-9 && g > 1e-9) last[std::size_t(p)] = std::clamp(t / g, 0.2, 5.0);
        }
        s.factor.push_back(last);
        if (d >= hi) break;
    }
    return s;
}

} // namespace

namespace {

// The state of one volume_diffusion() call, built step by step.
struct Run {
    Run(const SurfaceSamples& s, const std::vector<glm::vec3>& e,
        const std::vector<SurfaceSamples>& b, const VolumeOptions& options,
        VolumeReport& report)
        : surface(s), irradiance(e), blockers(b), o(options), rep(report) {}
    const SurfaceSamples& surface;
    const std::vector<glm::vec3>& irradiance;
    const std::vector<SurfaceSamples>& blockers;
    const VolumeOptions& o;
    VolumeReport& rep;
    std::size_t n = 0;
    Medium med[3];
    double l_min = 0, box = 0, h = 0, beam_limit = 0;
    glm::dvec3 lo{0.0}, hi{0.0}, size{0.0};
    bool over_budget = false;
    int coarse_steps = 0;
    std::vector<std::unique_ptr<Level>> levels; // coarsest first, then finest first
    std::vector<std::shared_ptr<const Surfels>> level_surfels;
    std::vector<SurfaceSamples> coarse_blockers;
    std::vector<glm::vec3> w;     // the volume's share per point and channel
    std::vector<float> thickness; // the medium below each point (capped)
    bool channel_needed[3] = {false, false, false};

    // The surface (and the blockers) merged to the voxels of a grid of edge e.
    std::pair<std::shared_ptr<Surfels>, std::vector<SurfaceSamples>>
    merged(double e) const {
        const VoxelGrid g = make_grid(lo, hi, e, 2);
        auto sf = std::make_shared<Surfels>(make_surfels(surface, &irradiance, g));
        std::vector<SurfaceSamples> bl;
        for (const SurfaceSamples& b : blockers)
            bl.push_back(make_surfels(b, nullptr, g).samples);
        return {sf, bl};
    }
};

// The media, the object's box, the finest voxel size and the coarsest grid
// of the cascade (at most 2^18 voxels in the box), built first: it decides
// which points and channels need the volume at all, so that a shape thick
// against every channel costs no more.
void plan(Run& r, const ChannelCoefficients (&channels)[3]) {
    r.l_min = std::numeric_limits<double>::infinity();
    for (int c = 0; c < 3; ++c) {
        r.med[c] = medium_of(channels[c], r.o.diffuse_light);
        r.l_min = std::min(r.l_min, 1.0 / r.med[c].sigma_t);
        r.beam_limit = std::max(r.beam_limit, kBeamReach / r.med[c].sigma_t);
    }
    r.lo = r.hi = glm::dvec3(r.surface.positions[0]);
    for (const glm::vec3& p : r.surface.positions) {
        r.lo = glm::min(r.lo, glm::dvec3(p));
        r.hi = glm::max(r.hi, glm::dvec3(p));
    }
    r.size = glm::max(r.hi - r.lo, glm::dvec3(r.l_min));
    r.box = r.size.x * r.size.y * r.size.z;
    // The finest voxels resolve the shortest transport mean free path within
    // the voxel budget.
    r.h = r.l_min / r.o.voxels_per_mfp;
    r.over_budget = r.box / (r.h * r.h * r.h) > double(r.o.max_voxels);
    if (r.over_budget) r.h = std::cbrt(r.box / double(r.o.max_voxels));
    while (r.coarse_steps < 7 &&
           r.box / std::pow(r.h * double(1 << r.coarse_steps), 3) > 262144.0)
        ++r.coarse_steps;
    const double e = r.h * double(1 << r.coarse_steps);
    auto [sf, bl] = r.merged(e);
    r.levels.push_back(
        std::make_unique<Level>(make_level(r.lo, r.hi, e, sf->samples, bl, 0.0)));
    r.level_surfels.push_back(sf);
    r.coarse_blockers = std::move(bl);
}

// How far the light a point gives off beyond its own has come at least: the
// distance to the nearest well-lit part of the surface (irradiance above a
// quarter of the lit surface's mean). Through a slab it is the thickness;
// on the dark side of a ball, near the terminator, much less than the
// chord below the point; 0 on a well-lit point (what it gives off beyond its
// own came from beside it).
std::vector<double> lit_distance(const VoxelGrid& g, const Surfels& cs,
                                 const SurfaceSamples& surface) {
    const std::size_t m = cs.flux.size();
    std::vector<double> e(m, 0.0);
    double sum = 0, area = 0;
    for (std::size_t k = 0; k < m; ++k) {
        const double a = double(cs.samples.areas[k]);
        if (!(a > 0)) continue;
        e[k] = (cs.flux[k].x + cs.flux[k].y + cs.flux[k].z) / a;
        if (e[k] > 0) {
            sum += e[k] * a;
            area += a;
        }
    }
    std::vector<glm::dvec3> lit;
    std::vector<char> is_lit(m, 0);
    for (std::size_t k = 0; k < m; ++k)
        if (area > 0 && e[k] > 0.25 * sum / area) {
            lit.push_back(glm::dvec3(cs.samples.positions[k]));
            is_lit[k] = 1;
        }
    std::vector<double> d = nearest_source_distance(g, lit, surface.positions);
    for (std::size_t j = 0; j < d.size(); ++j)
        if (is_lit[cs.of_point[j]]) d[j] = 0.0;
    return d;
}

// Each point's share of the volume per channel, from the thickness below it
// against the channel's spread length: its diffuse mean free path, but at
// least spread_mfp transport mean free paths (a small object loses light to
// its curvature even where it hardly absorbs).
void weigh(Run& r) {
    const VolumeOptions& o = r.o;
    double spread[3], spread_max = 0;
    for (int c = 0; c < 3; ++c) {
        spread[c] = std::max(r.med[c].dmfp, o.spread_mfp / r.med[c].sigma_t);
        spread_max = std::max(spread_max, spread[c]);
    }
    const double limit = o.thick_dmfp * spread_max;
    const Surfels& cs = *r.level_surfels[0];
    const std::vector<double> depth =
        ray_thickness(r.levels[0]->grid, cs.samples, r.coarse_blockers,
                      std::isfinite(limit) ? limit : 2.0 * glm::length(r.size));
    r.w.assign(r.n, glm::vec3(0.0f));
    r.thickness.assign(r.n, 0.0f);
    bool any = false;
    for (std::size_t j = 0; j < r.n; ++j) {
        const double d = depth[cs.of_point[j]];
        r.thickness[j] = float(d);
        for (int c = 0; c < 3; ++c) {
            double wc = (o.thick_dmfp - d / spread[c]) / (o.thick_dmfp - o.thin_dmfp);
            if (d >= limit) wc = 0.0; // no way out found within the limit
            r.w[j][c] = float(std::clamp(wc, 0.0, 1.0));
            any = any || r.w[j][c] > 0.0f;
        }
    }
    if (any) {
        smooth_weights(r.levels[0]->grid, r.surface, spread, r.w);
        const std::vector<double> lit = lit_distance(r.levels[0]->grid, cs, r.surface);
        for (std::size_t j = 0; j < r.n; ++j)
            r.thickness[j] = float(std::min(double(r.thickness[j]), lit[j]));
    }
    for (std::size_t j = 0; j < r.n; ++j) {
        for (int c = 0; c < 3; ++c)
            if (r.w[j][c] > 0.0f) r.channel_needed[c] = true;
        if (r.w[j] != glm::vec3(0.0f)) ++r.rep.thin_points;
    }
    r.rep.needed = r.rep.thin_points > 0;
}

// The finer grids, down to h, finest first afterwards; a grid that loses
// surface the finer one has is not a good start for it and is dropped.
void refine(Run& r) {
    // The surface area that finds a medium voxel below it.
    const auto leaking = [](const Level& l, const Surfels& sf) {
        double a = 0;
        for (std::size_t k = 0; k < l.leak_voxel.size(); ++k)
            if (l.leak_voxel[k] >= 0) a += double(sf.samples.areas[k]);
        return a;
    };
    for (int k = r.coarse_steps - 1; k >= 0; --k) {
        const double e = r.h * double(1 << k);
        auto [sf, bl] = r.merged(e);
        auto finer = std::make_unique<Level>(
            make_level(r.lo, r.hi, e, sf->samples, bl, r.beam_limit));
        if (leaking(*r.levels.back(), *r.level_surfels.back()) <
                0.95 * leaking(*finer, *sf) ||
            r.levels.back()->u.voxels.size() < 512) {
            r.levels.pop_back();
            r.level_surfels.pop_back();
        }
        r.levels.push_back(std::move(finer));
        r.level_surfels.push_back(sf);
    }
    std::reverse(r.levels.begin(), r.levels.end());
    std::reverse(r.level_surfels.begin(), r.level_surfels.end());
}

// One channel's fluence on the finest grid, solved down the cascade; the
// fluxes go to the report.
std::vector<float> solve_channel(Run& r, int c) {
    const Medium& m = r.med[c];
    VolumeReport& rep = r.rep;
    std::vector<float> phi;
    const Level* prev = nullptr;
    for (std::size_t li = r.levels.size(); li-- > 0;) {
        const Level& l = *r.levels[li];
        const Surfels& ls = *r.level_surfels[li];
        const System s = make_system(l, m, ls.samples, ls.flux, c);
        phi = prev ? prolong(*prev, phi, l) : std::vector<float>(l.u.voxels.size(), 0.0f);
        rep.iterations[c] += solve(s, phi, r.o.tolerance, 50000);
        prev = &l;
        if (li > 0) continue;
        // Fluxes: what went in, left, was absorbed in the medium and by the
        // blockers (they balance to the solver's tolerance).
        const std::size_t nu = phi.size();
        rep.flux_in[c] = chunked_sum(nu, [&](std::size_t k) { return s.source[k]; });
        rep.flux_out[c] =
            chunked_sum(nu, [&](std::size_t k) { return s.leak[k] * phi[k]; });
        const double hv = l.grid.h * l.grid.h * l.grid.h;
        rep.flux_absorbed[c] =
            chunked_sum(nu, [&](std::size_t k) { return m.sigma_a * hv * phi[k]; });
        rep.flux_blocked[c] = chunked_sum(nu, [&](std::size_t k) {
            int faces = 0;
            for (int32_t nb : l.u.neighbours[k]) faces += nb == Unknowns::kBlack;
            return faces * s.black * phi[k];
        });
    }
    return phi;
}

// How deep below the lit surface the finest grid's first voxels lie
// (flux-weighted): the column the grid's own reflectance is taken from.
double lit_depth(const Level& fine, const Surfels& surfels) {
    double sum = 0, weight = 0;
    for (std::size_t k = 0; k < surfels.flux.size(); ++k) {
        const double f =
            std::max(0.0, surfels.flux[k].x + surfels.flux[k].y + surfels.flux[k].z);
        if (fine.leak_voxel[k] < 0 || f <= 0) continue;
        sum += f * fine.leak_depth[k];
        weight += f;
    }
    return weight > 0 ? sum / weight : 0.5 * fine.grid.h;
}

// The volume's exitance at each point: the fluence read a voxel below it,
// carried to the surface by the Robin condition, scaled so that the points
// give off exactly the flux the solve lets out; plus what a voxel diffusion
// misses near where light enters (single scattering, the near field): the
// profile's half-space reflectance less the grid's own, in proportion to
// each point's irradiance.
std::vector<double> volume_exitance(Run& r, int c, const std::vector<float>& phi,
                                    double profile_reflectance) {
    const Level& fine = *r.levels.front();
    const Surfels& surfels = *r.level_surfels.front();
    const Medium& m = r.med[c];
    const std::size_t n = r.n;
    std::vector<double> exitance(n, 0.0);
    oneapi::tbb::parallel_for(std::size_t(0), n, [&](std::size_t j) {
        const int32_t leak = fine.leak_voxel[surfels.of_point[j]];
        if (leak < 0) return;
        const glm::dvec3 p(r.surface.positions[j]);
        const glm::dvec3 nrm = glm::normalize(glm::dvec3(r.surface.normals[j]));
        const double d = fine.grid.h;
        Stencil st;
        double f = phi[std::size_t(leak)];
        if (medium_stencil(fine.grid, fine.u, p - d * nrm, st)) {
            f = 0;
            for (int i = 0; i < st.n; ++i)
                f += st.weight[i] * phi[std::size_t(st.unknown[i])];
        }
        exitance[j] = std::max(0.0, f) / (2.0 * m.A + d / m.D);
    });
    const double read = chunked_sum(
        n, [&](std::size_t j) { return double(r.surface.areas[j]) * exitance[j]; });
    const double scale = read > 0 ? r.rep.flux_out[c] / read : 0.0;
    const double grid_reflectance =
        halfspace_reflectance(m, fine.grid.h, lit_depth(fine, surfels));
    const double missing =
        profile_reflectance >= 0.0 ? profile_reflectance - grid_reflectance : 0.0;
    r.rep.reflectance_correction[c] = missing;
    // The light a point gives off beyond what its own irradiance sends back
    // came through the medium below it: corrected as through a slab of the
    // point's thickness.
    double d_max = 0;
    for (std::size_t j = 0; j < n; ++j)
        if (r.w[j][c] > 0.0f) d_max = std::max(d_max, double(r.thickness[j]));
    const SlabFactors through = slab_factors(m, fine.grid.h, d_max, r.o.diffuse_light);
    r.rep.transmission_min[c] = through.factor.front()[0];
    r.rep.transmission_max[c] = through.factor.front()[0];
    for (const auto& f : through.factor)
        for (double x : f) {
            r.rep.transmission_min[c] = std::min(r.rep.transmission_min[c], x);
            r.rep.transmission_max[c] = std::max(r.rep.transmission_max[c], x);
        }
    for (std::size_t j = 0; j < n; ++j) {
        const double e = double(r.irradiance[j][c]);
        const double v = exitance[j] * scale;
        const double own = std::clamp(grid_reflectance * e, 0.0, v);
        const double depth = fine.leak_depth[surfels.of_point[j]];
        exitance[j] = std::max(
            0.0, own +
                     through.at(double(r.thickness[j]), depth, fine.grid.h) * (v - own) +
                     missing * e);
    }
    return exitance;
}

// Channel c of `out`: the volume's exitance blended with the profile's by
// each point's share. Light out never more than light in: the correction is
// local and the blend keeps some of the profile's light, so a shape small
// against the light's spread could give off more than came in; then the
// volume's points are scaled down (the others keep the profile's).
void blend_channel(const Run& r, int c, const std::vector<double>& volume,
                   const std::vector<glm::vec3>& profile_result,
                   std::vector<glm::vec3>& out) {
    const Level& fine = *r.levels.front();
    const Surfels& surfels = *r.level_surfels.front();
    const std::size_t n = r.n;
    std::vector<double> blended(n, 0.0);
    std::vector<char> mine(n, 0); // the points whose value is (partly) the volume's
    for (std::size_t j = 0; j < n; ++j) {
        if (fine.leak_voxel[surfels.of_point[j]] < 0 || r.w[j][c] == 0.0f) continue;
        mine[j] = 1;
        blended[j] = double(r.w[j][c]) * volume[j] +
                     (1.0 - double(r.w[j][c])) * double(profile_result[j][c]);
    }
    const Sums t = chunked_pass(n, [&](std::size_t b, std::size_t e) {
        Sums q;
        for (std::size_t j = b; j < e; ++j) {
            const double a = double(r.surface.areas[j]);
            q.a += a * std::max(0.0, double(r.irradiance[j][c]));
            if (mine[j])
                q.b += a * blended[j];
            else
                q.c += a * double(profile_result[j][c]);
        }
        return q;
    });
    const double cap =
        t.b + t.c > t.a && t.b > 0 ? std::max(0.0, t.a - std::max(0.0, t.c)) / t.b : 1.0;
    for (std::size_t j = 0; j < n; ++j) {
        if (!mine[j]) continue;
        const double v = blended[j] * cap;
        out[j][c] = std::isfinite(v) ? float(v) : 0.0f;
    }
}

} // namespace

std::vector<glm::vec3> volume_diffusion(const SurfaceSamples& surface,
                                        const std::vector<glm::vec3>& irradiance,
                                        const ChannelCoefficients (&channels)[3],
                                        const glm::dvec3& profile_reflectance,
                                        const std::vector<SurfaceSamples>& blockers,
                                        const std::vector<glm::vec3>& profile_result,
                                        const VolumeOptions& o, VolumeReport* report) {
    VolumeReport local;
    VolumeReport& rep = report ? *report : local;
    struct Timer {
        VolumeReport& rep;
        std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
        ~Timer() {
            rep.seconds =
                std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
                    .count();
        }
    } timer{rep};
    const std::size_t n = surface.positions.size();
    if (surface.normals.size() != n || surface.areas.size() != n ||
        irradiance.size() != n || profile_result.size() != n)
        throw ValueError("volume diffusion: arrays of different sizes");
    for (const SurfaceSamples& b : blockers)
        if (b.normals.size() != b.positions.size() ||
            b.areas.size() != b.positions.size())
            throw ValueError("volume diffusion: blocker arrays of different sizes");
    std::vector<glm::vec3> out = profile_result;
    if (n == 0) return out;
    Run r(surface, irradiance, blockers, o, rep);
    r.n = n;
    plan(r, channels);
    // The profiles describe light entering straight; diffuse light first
    // scatters shallower and more of it comes back, by transport theory's
    // ratio for a deep slab.
    glm::dvec3 reflectance = profile_reflectance;
    if (o.diffuse_light)
        for (int c = 0; c < 3; ++c) {
            const double ratio = diffuse_reflectance_ratio(r.med[c].alpha, r.med[c].eta);
            rep.diffuse_ratio[c] = ratio;
            if (reflectance[c] >= 0.0) reflectance[c] *= ratio;
            for (glm::vec3& v : out) v[c] = float(double(v[c]) * ratio);
        }
    const std::vector<glm::vec3> profile = out;
    weigh(r);
    if (!rep.needed) return out;
    if (r.over_budget && r.h > r.l_min)
        rep.warnings.push_back(
            "the object is large against the mean free path: voxels of " +
            std::to_string(r.h) + " (" + std::to_string(r.h / r.l_min) +
            " mean free paths)");
    // The coarse grid's beams, now that the volume is needed.
    Level& coarse = *r.levels.front();
    coarse.beam_exit = ray_thickness(coarse.grid, r.level_surfels.front()->samples,
                                     r.coarse_blockers, r.beam_limit);
    coarse.beam_limit = r.beam_limit;
    refine(r);
    const Level& fine = *r.levels.front();
    const Surfels& surfels = *r.level_surfels.front();
    rep.voxel = fine.grid.h;
    for (int a = 0; a < 3; ++a) rep.dims[a] = fine.grid.dim[a];
    rep.unknowns = fine.u.voxels.size();
    rep.levels = int(r.levels.size());
    if (rep.unknowns == 0) {
        rep.warnings.push_back(
            "the cloud encloses no volume: the profile's result is kept");
        rep.needed = false;
        rep.thin_points = 0;
        return out;
    }
    std::size_t unused = 0;
    for (std::size_t j = 0; j < n; ++j)
        unused += fine.leak_voxel[surfels.of_point[j]] < 0;
    if (unused > 0)
        rep.warnings.push_back(std::to_string(unused) +
                               " points have no medium voxel below them: they keep the "
                               "profile's result");
    for (int c = 0; c < 3; ++c) {
        if (!r.channel_needed[c]) continue;
        const std::vector<float> phi = solve_channel(r, c);
        if (o.progress) o.progress->update(uint64_t(c + 1), 3);
        blend_channel(r, c, volume_exitance(r, c, phi, reflectance[c]), profile, out);
    }
    return out;
}

} // namespace sss
