// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// The random walk in a medium bounded by triangle meshes (mesh_walk.h).

#include "sss/truth/mesh_walk.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <unordered_map>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include "sss/light/ray_tracer.h"
#include "sss/truth/half_space.h"
#include "sss/util/error.h"

#include "random.h"

namespace sss {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kRouletteBelow = 1e-4;
constexpr double kRouletteSurvival = 0.1;
/// Start points, reflected paths and collisions just short of the surface
/// keep this far inside it, relative to the medium's bounding-box diagonal:
/// far above the float rays' rounding, far below a mean free path.
constexpr double kOffset = 1e-5;
/// A path found this far outside the medium's bounding box (relative to its
/// diagonal) has escaped through a crack.
constexpr double kLostMargin = 1e-3;
/// Jittered start points tried before a source point's own position is used
/// (a disk that overhangs an edge of the surface projects onto nothing).
constexpr int kJitterTries = 8;
/// Batches walked at once: a batch's exit tallies are held until it is
/// combined, so this bounds their memory.
constexpr std::size_t kWave = 32;
/// So that the channels' batches draw different numbers.
constexpr uint64_t kChannelSalt[3] = {0x6a09e667f3bcc909ull, 0xbb67ae8584caa73bull,
                                      0x3c6ef372fe94f82bull};
/// photons * batch must not overflow.
constexpr uint64_t kMaxPhotons = uint64_t(1) << 48;

std::string point_text(std::size_t i) {
    return "mesh walk: source point " + std::to_string(i);
}

bool finite3(const glm::vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

/// An orthonormal basis (t1, t2) around the unit vector n (Duff et al. 2017).
void basis(const glm::dvec3& n, glm::dvec3& t1, glm::dvec3& t2) {
    const double sign = std::copysign(1.0, n.z);
    const double a = -1.0 / (sign + n.z), b = n.x * n.y * a;
    t1 = {1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x};
    t2 = {b, sign + n.y * n.y * a, -n.y};
}

/// The source point nearest to a place, among those with an area: a k-d tree
/// stored implicitly (each range's median at its middle, split on the
/// range's widest axis).
class NearestPoint {
public:
    explicit NearestPoint(const MeshWalkSource& s) {
        for (std::size_t i = 0; i < s.positions.size(); ++i)
            if (s.areas[i] > 0.0f)
                m_nodes.push_back({glm::dvec3(s.positions[i]), uint32_t(i), 0});
        build(0, m_nodes.size());
    }

    /// The index of the nearest point (ties: the lowest index); the tree
    /// must not be empty.
    uint32_t nearest(const glm::dvec3& p) const {
        std::size_t best = 0;
        double d2 = kInf;
        search(0, m_nodes.size(), p, best, d2);
        return m_nodes[best].index;
    }

private:
    struct Node {
        glm::dvec3 p;
        uint32_t index;
        int axis; ///< the split of the range whose middle this is
    };
    std::vector<Node> m_nodes;

    void build(std::size_t lo, std::size_t hi) {
        if (hi - lo < 2) return;
        glm::dvec3 lower(kInf), upper(-kInf);
        for (std::size_t k = lo; k < hi; ++k) {
            lower = glm::min(lower, m_nodes[k].p);
            upper = glm::max(upper, m_nodes[k].p);
        }
        const glm::dvec3 e = upper - lower;
        const int axis = e.x >= e.y && e.x >= e.z ? 0 : e.y >= e.z ? 1 : 2;
        const std::size_t mid = lo + (hi - lo) / 2;
        std::nth_element(m_nodes.begin() + long(lo), m_nodes.begin() + long(mid),
                         m_nodes.begin() + long(hi),
                         [axis](const Node& a, const Node& b) {
                             return a.p[axis] < b.p[axis] ||
                                    (a.p[axis] == b.p[axis] && a.index < b.index);
                         });
        m_nodes[mid].axis = axis;
        build(lo, mid);
        build(mid + 1, hi);
    }

    void search(std::size_t lo, std::size_t hi, const glm::dvec3& p, std::size_t& best,
                double& d2) const {
        if (lo >= hi) return;
        const std::size_t mid = lo + (hi - lo) / 2;
        const Node& q = m_nodes[mid];
        const glm::dvec3 v = p - q.p;
        const double d = glm::dot(v, v);
        if (d < d2 || (d == d2 && q.index < m_nodes[best].index)) {
            d2 = d;
            best = mid;
        }
        if (hi - lo == 1) return;
        const double delta = p[q.axis] - q.p[q.axis];
        if (delta < 0.0) {
            search(lo, mid, p, best, d2);
            if (delta * delta <= d2) search(mid + 1, hi, p, best, d2);
        } else {
            search(mid + 1, hi, p, best, d2);
            if (delta * delta <= d2) search(lo, mid, p, best, d2);
        }
    }
};

/// The meshes in one ray tracer: the medium's first, then the blockers.
struct Scene {
    RayTracer tracer;
    uint32_t medium_meshes = 0;
    double offset = 0.0;
    glm::dvec3 lower{kInf}, upper{-kInf}; ///< the medium's box with the lost margin

    /// False also for NaN.
    bool inside_box(const glm::dvec3& p) const {
        return p.x >= lower.x && p.x <= upper.x && p.y >= lower.y && p.y <= upper.y &&
               p.z >= lower.z && p.z <= upper.z;
    }
};

void add_meshes(Scene& scene, const std::vector<TriangleMesh>& meshes, const char* what) {
    for (std::size_t k = 0; k < meshes.size(); ++k) {
        try {
            scene.tracer.add_mesh(meshes[k].vertices, meshes[k].triangles);
        } catch (const ValueError& e) {
            throw ValueError("mesh walk: " + std::string(what) + " mesh " +
                             std::to_string(k) + ": " + e.what());
        }
    }
}

void build_scene(const MeshWalkOptions& o, Scene& scene) {
    for (std::size_t k = 0; k < o.medium.size(); ++k) {
        if (o.medium[k].triangles.empty())
            throw ValueError("mesh walk: medium mesh " + std::to_string(k) +
                             " has no triangles");
    }
    add_meshes(scene, o.medium, "medium");
    add_meshes(scene, o.blockers, "blocker");
    scene.medium_meshes = uint32_t(o.medium.size());
    for (const TriangleMesh& m : o.medium)
        for (uint32_t v : m.triangles) {
            scene.lower = glm::min(scene.lower, glm::dvec3(m.vertices[v]));
            scene.upper = glm::max(scene.upper, glm::dvec3(m.vertices[v]));
        }
    const double diagonal = glm::length(scene.upper - scene.lower);
    if (!(diagonal > 0.0))
        throw ValueError("mesh walk: the medium's meshes have no extent");
    scene.offset = kOffset * diagonal;
    scene.lower -= glm::dvec3(kLostMargin * diagonal);
    scene.upper += glm::dvec3(kLostMargin * diagonal);
    scene.tracer.commit();
}

void check_options(const MeshWalkOptions& o) {
    if (o.medium.empty()) throw ValueError("mesh walk: no medium meshes");
    for (int c = 0; c < 3; ++c) {
        if (!(o.sigma_s_prime[c] >= 0.0 && std::isfinite(o.sigma_s_prime[c])) ||
            !(o.sigma_a[c] >= 0.0 && std::isfinite(o.sigma_a[c])))
            throw ValueError("mesh walk: channel " + std::to_string(c) + ": sigma_s' " +
                             std::to_string(o.sigma_s_prime[c]) + " and sigma_a " +
                             std::to_string(o.sigma_a[c]) +
                             " must be finite and not negative");
    }
    if (!(o.eta > 0.0 && std::isfinite(o.eta)))
        throw ValueError("mesh walk: eta " + std::to_string(o.eta) +
                         " must be positive and finite");
    if (o.photons == 0 || o.photons > kMaxPhotons || o.batches < 1 ||
        uint64_t(o.batches) > o.photons)
        throw ValueError("mesh walk: " + std::to_string(o.photons) + " photons in " +
                         std::to_string(o.batches) + " batches");
    if (o.max_collisions < 1)
        throw ValueError("mesh walk: max_collisions must be at least 1");
}

void check_source(const MeshWalkSource& s) {
    const std::size_t n = s.positions.size();
    if (s.normals.size() != n || s.areas.size() != n || s.irradiance.size() != n)
        throw ValueError("mesh walk: the source has " + std::to_string(n) +
                         " positions, " + std::to_string(s.normals.size()) +
                         " normals, " + std::to_string(s.areas.size()) + " areas and " +
                         std::to_string(s.irradiance.size()) + " irradiances");
    if (n == 0) throw ValueError("mesh walk: the source has no points");
    if (n > std::numeric_limits<uint32_t>::max())
        throw ValueError("mesh walk: the source has too many points");
    double flux = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
        if (!finite3(s.positions[i]))
            throw ValueError(point_text(i) + ": position not finite");
        if (!finite3(s.normals[i]) || glm::dot(s.normals[i], s.normals[i]) == 0.0f)
            throw ValueError(point_text(i) + ": normal zero or not finite");
        if (!(s.areas[i] >= 0.0f && std::isfinite(s.areas[i])))
            throw ValueError(point_text(i) + ": area " + std::to_string(s.areas[i]) +
                             " negative or not finite");
        for (int c = 0; c < 3; ++c) {
            if (!(s.irradiance[i][c] >= 0.0f && std::isfinite(s.irradiance[i][c])))
                throw ValueError(point_text(i) + ": irradiance " +
                                 std::to_string(s.irradiance[i][c]) + " (channel " +
                                 std::to_string(c) + ") negative or not finite");
            flux += double(s.areas[i]) * double(s.irradiance[i][c]);
        }
    }
    if (!(flux > 0.0)) throw ValueError("mesh walk: the source has no flux");
}

/// One channel's medium and the light entering it.
struct Channel {
    std::size_t index = 0;
    double sigma_t = 0.0, albedo = 0.0;
    std::vector<double> cdf; ///< cumulative flux in point order
    double flux = 0.0;
    std::size_t last = 0; ///< the last point with flux
};

Channel make_channel(const MeshWalkOptions& o, const MeshWalkSource& s, std::size_t c) {
    Channel ch;
    ch.index = c;
    ch.sigma_t = o.sigma_s_prime[int(c)] + o.sigma_a[int(c)];
    // A medium that neither scatters nor absorbs keeps its light.
    ch.albedo = ch.sigma_t > 0.0 ? o.sigma_s_prime[int(c)] / ch.sigma_t : 1.0;
    ch.cdf.resize(s.positions.size());
    for (std::size_t i = 0; i < s.positions.size(); ++i) {
        const double f = double(s.areas[i]) * double(s.irradiance[i][int(c)]);
        if (f > 0.0) ch.last = i;
        ch.flux += f;
        ch.cdf[i] = ch.flux;
    }
    return ch;
}

/// What one walk shares between its paths.
struct Walk {
    const MeshWalkOptions& options;
    const MeshWalkSource& source;
    const Scene& scene;
    const NearestPoint& nearest;
    const Channel& channel;
};

/// One batch's tallies, in units of a path's starting weight.
struct BatchTally {
    std::unordered_map<uint32_t, double> exits; ///< weight leaving nearest each point
    double out = 0.0, blocked = 0.0, absorbed = 0.0, truncated = 0.0, lost = 0.0,
           unscattered = 0.0;
    uint64_t collisions = 0;
};

/// A path's start just inside the surface and its direction in the medium.
void start(const Walk& w, Uniform& u, glm::dvec3& p, glm::dvec3& d) {
    const Channel& ch = w.channel;
    // The first point whose cumulative flux passes the draw has flux.
    const auto it = std::upper_bound(ch.cdf.begin(), ch.cdf.end(), u() * ch.flux);
    const std::size_t i = it == ch.cdf.end() ? ch.last : std::size_t(it - ch.cdf.begin());
    const glm::dvec3 centre(w.source.positions[i]);
    const glm::dvec3 n = glm::normalize(glm::dvec3(w.source.normals[i]));
    glm::dvec3 t1, t2;
    basis(n, t1, t2);
    const double radius = std::sqrt(double(w.source.areas[i]) / std::numbers::pi);
    const double off = w.scene.offset;
    p = centre - n * off;
    for (int k = 0; k < kJitterTries; ++k) {
        // Uniform in the disk, then along -n onto the surface: a curved
        // surface leaves the tangent plane, and a start outside would leave
        // at once.
        const double r = radius * std::sqrt(u()), phi = 2.0 * std::numbers::pi * u();
        const double h = radius + off;
        const glm::dvec3 above =
            centre + r * (std::cos(phi) * t1 + std::sin(phi) * t2) + h * n;
        const ShadowRay ray{glm::vec3(above), glm::vec3(-n), 0.0f, float(2.0 * h)};
        const RayHit hit = w.scene.tracer.intersect(ray);
        if (hit.hit && hit.mesh < w.scene.medium_meshes) {
            p = above - n * (double(hit.t) + off);
            break;
        }
    }
    // Cosine-weighted outside times the Fresnel transmission, by rejection so
    // that every path carries the same weight; then refracted in.
    const double eta = w.options.eta;
    if (w.options.normal_incidence) {
        d = -n;
        return;
    }
    double cos_out = 0.0;
    do {
        cos_out = std::sqrt(u());
    } while (u() >= 1.0 - fresnel_reflectance(cos_out, 1.0, eta));
    const double sin_out = std::sqrt(std::max(0.0, 1.0 - cos_out * cos_out));
    const double phi = 2.0 * std::numbers::pi * u();
    const double sin_in = std::min(1.0, sin_out / eta);
    const double cos_in = std::sqrt(std::max(0.0, 1.0 - sin_in * sin_in));
    d = glm::normalize(-cos_in * n + sin_in * (std::cos(phi) * t1 + std::sin(phi) * t2));
}

/// A path meeting a surface at `hit` along the segment from p in direction
/// d: true if it is reflected back into the medium (p and d updated), false
/// if it ends there (absorbed by a blocker, or out through the surface).
bool at_surface(const Walk& w, Uniform& u, const RayHit& hit, glm::dvec3& p,
                glm::dvec3& d, double weight, bool unscattered, BatchTally& t) {
    const glm::dvec3 h = p + d * double(hit.t);
    if (hit.mesh >= w.scene.medium_meshes) {
        t.blocked += weight;
        return false;
    }
    const glm::dvec3 n = glm::normalize(glm::dvec3(hit.geometric_normal));
    const double c = glm::dot(d, n);
    if (!std::isfinite(c)) {
        t.lost += weight;
        return false;
    }
    if (u() < fresnel_reflectance(std::abs(c), w.options.eta, 1.0)) {
        d = glm::normalize(d - 2.0 * c * n);
        // Back off the surface on the side the path came from, whichever
        // way the mesh is oriented.
        p = h - std::copysign(w.scene.offset, c) * n;
        return true;
    }
    if (unscattered && w.options.scattered_only) {
        t.unscattered += weight;
        return false;
    }
    t.out += weight;
    t.exits[w.nearest.nearest(h)] += weight;
    return false;
}

/// One path of unit weight from its start to its end, tallied in `t`.
void walk_path(const Walk& w, Uniform& u, BatchTally& t) {
    const Channel& ch = w.channel;
    const double off = w.scene.offset;
    glm::dvec3 p, d;
    start(w, u, p, d);
    double weight = 1.0;
    long collisions = 0;
    for (;;) {
        const double x = u();
        const double s = ch.sigma_t > 0.0 ? -std::log1p(-x) / ch.sigma_t : kInf;
        // The ray reaches one offset past the collision: a surface just
        // beyond it pulls the collision back inside rather than the float
        // rays' rounding leaving it outside.
        const ShadowRay ray{glm::vec3(p), glm::vec3(d), 0.0f, float(s + off)};
        const RayHit hit = w.scene.tracer.intersect(ray);
        if (hit.hit && double(hit.t) <= s) {
            if (!at_surface(w, u, hit, p, d, weight, collisions == 0, t)) return;
            continue;
        }
        // No surface along an endless ray: the path is outside the medium.
        if (!std::isfinite(s)) {
            t.lost += weight;
            return;
        }
        p += d * (hit.hit ? std::clamp(double(hit.t) - off, 0.0, s) : s);
        if (!w.scene.inside_box(p)) {
            t.lost += weight;
            return;
        }
        ++collisions;
        ++t.collisions;
        t.absorbed += weight * (1.0 - ch.albedo);
        weight *= ch.albedo;
        if (!(weight > 0.0)) return;
        if (weight < kRouletteBelow) {
            // Unbiased: survivors carry the expected weight of the rest.
            if (u() >= kRouletteSurvival) return;
            weight /= kRouletteSurvival;
        }
        if (collisions >= w.options.max_collisions) {
            t.truncated += weight;
            return;
        }
        d = uniform_direction(u);
    }
}

/// Sums of per-batch estimates, for the standard error of their mean.
struct Moments {
    double sum = 0.0, sum2 = 0.0;
    void add(double e) {
        sum += e;
        sum2 += e * e;
    }
    double error(std::size_t batches) const {
        if (batches < 2) return 0.0;
        const double b = double(batches), mean = sum / b;
        return std::sqrt(std::max(0.0, sum2 - b * mean * mean) / (b * (b - 1.0)));
    }
};

/// Walks one channel's batches and fills its part of the result.
void walk_channel(const Walk& w, MeshWalkResult& r) {
    const std::size_t c = w.channel.index;
    const uint64_t photons = w.options.photons;
    const std::size_t batches = std::size_t(w.options.batches);
    const std::size_t points = w.source.positions.size();
    const double weight = w.channel.flux / double(photons); // each path's flux
    const auto batch_begin = [&](std::size_t b) { return photons * b / batches; };
    std::vector<BatchTally> tallies(batches);
    std::vector<double> exits(points, 0.0);
    std::vector<Moments> point_moments(points);
    for (std::size_t first = 0; first < batches; first += kWave) {
        const std::size_t end = std::min(batches, first + kWave);
        tbb::parallel_for(first, end, [&](std::size_t b) {
            Uniform u(batch_seed(w.options.seed ^ kChannelSalt[c], b));
            for (uint64_t i = batch_begin(b); i < batch_begin(b + 1); ++i)
                walk_path(w, u, tallies[b]);
        });
        // In batch order, whichever thread walked them; each point occurs
        // once per batch, so the order within a batch does not matter.
        for (std::size_t b = first; b < end; ++b) {
            const double scale =
                weight * double(photons) / double(batch_begin(b + 1) - batch_begin(b));
            for (const auto& [i, x] : tallies[b].exits) {
                exits[i] += x;
                point_moments[i].add(x * scale / double(w.source.areas[i]));
            }
            std::unordered_map<uint32_t, double>().swap(tallies[b].exits);
        }
    }
    for (std::size_t i = 0; i < points; ++i) {
        if (exits[i] == 0.0) continue;
        r.exitance[i][int(c)] = exits[i] * weight / double(w.source.areas[i]);
        r.exitance_error[i][int(c)] = point_moments[i].error(batches);
    }
    const auto total = [&](double BatchTally::*field, double& value, double* error) {
        Moments m;
        double sum = 0.0;
        for (std::size_t b = 0; b < batches; ++b) {
            sum += tallies[b].*field;
            m.add(tallies[b].*field * weight * double(photons) /
                  double(batch_begin(b + 1) - batch_begin(b)));
        }
        value = sum * weight;
        if (error) *error = m.error(batches);
    };
    const int k = int(c);
    r.flux_in[k] = w.channel.flux;
    total(&BatchTally::out, r.flux_out[k], &r.flux_out_error[k]);
    total(&BatchTally::blocked, r.flux_blocked[k], &r.flux_blocked_error[k]);
    total(&BatchTally::absorbed, r.flux_absorbed[k], &r.flux_absorbed_error[k]);
    total(&BatchTally::truncated, r.flux_truncated[k], &r.flux_truncated_error[k]);
    total(&BatchTally::lost, r.flux_lost[k], nullptr);
    total(&BatchTally::unscattered, r.flux_unscattered[k], nullptr);
    for (const BatchTally& t : tallies) r.collisions += t.collisions;
}

} // namespace

MeshWalkResult walk_mesh(const MeshWalkOptions& options, const MeshWalkSource& source) {
    check_options(options);
    check_source(source);
    Scene scene;
    build_scene(options, scene);
    const NearestPoint nearest(source);
    MeshWalkResult r;
    r.exitance.assign(source.positions.size(), glm::dvec3(0.0));
    r.exitance_error.assign(source.positions.size(), glm::dvec3(0.0));
    r.photons = options.photons;
    for (std::size_t c = 0; c < 3; ++c) {
        const Channel channel = make_channel(options, source, c);
        if (!(channel.flux > 0.0)) continue; // nothing enters in this channel
        walk_channel(Walk{options, source, scene, nearest, channel}, r);
    }
    return r;
}

} // namespace sss
