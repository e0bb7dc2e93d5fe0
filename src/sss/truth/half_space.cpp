// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// The half-space random walk (half_space.h) and the closed-form single
// scattering it is checked against.

#include "sss/truth/half_space.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <string>

#include <tbb/parallel_for.h>

#include "sss/util/error.h"
#include "sss/util/hash.h"

#include "random.h"

namespace sss {

namespace {

constexpr double kRouletteBelow = 1e-4;
constexpr double kRouletteSurvival = 0.1;

/// One batch's tallies, normalised later by the weight that entered.
struct Tally {
    std::vector<double> single, multiple;
    double beyond_single = 0.0, beyond_multiple = 0.0;
    double entered = 0.0, absorbed = 0.0, truncated = 0.0;
    long collisions = 0;
};

struct Vec {
    double x, y, z;
};

Vec isotropic(Uniform& u) {
    const glm::dvec3 d = uniform_direction(u);
    return {d.x, d.y, d.z};
}

/// The annulus of radius r (edges increasing from 0), or -1 beyond.
long annulus_of(const std::vector<double>& edges, double r) {
    const auto it = std::upper_bound(edges.begin(), edges.end(), r);
    if (it == edges.end()) return -1;
    return long(it - edges.begin()) - 1;
}

/// The direction a photon has once inside, and its weight (the Fresnel
/// transmission of diffuse light; 1 for the pencil beam).
std::pair<Vec, double> entering(Incidence incidence, double eta, Uniform& u) {
    if (incidence == Incidence::Pencil) return {{0.0, 0.0, 1.0}, 1.0};
    // Cosine-weighted outside, refracted by Snell's law.
    const double cos_out = std::sqrt(u());
    const double sin_out = std::sqrt(std::max(0.0, 1.0 - cos_out * cos_out));
    const double phi = 2.0 * std::numbers::pi * u();
    const double sin_in = sin_out / eta;
    const double cos_in = std::sqrt(std::max(0.0, 1.0 - sin_in * sin_in));
    const double t = 1.0 - fresnel_reflectance(cos_out, 1.0, eta);
    return {{sin_in * std::cos(phi), sin_in * std::sin(phi), cos_in}, t};
}

/// One path from its entry. `collide(order, w)` is called at each collision
/// (weight before it) and returns the weight after it, or a negative value to
/// end the path; `leave(order, r, w)` when it leaves at radius r.
template <class Collide, class Leave>
void walk_path(double eta, Incidence incidence, Uniform& u, double& entered,
               Collide&& collide, Leave&& leave) {
    auto [d, w] = entering(incidence, eta, u);
    entered += w;
    Vec p{0.0, 0.0, 0.0};
    long order = 0;
    for (;;) {
        const double s = -std::log1p(-u());
        if (d.z < 0.0 && s >= -p.z / d.z) {
            // Reaches the surface first; a new free flight after a
            // reflection is as good as the rest of this one (memoryless).
            const double t = -p.z / d.z;
            p = {p.x + d.x * t, p.y + d.y * t, 0.0};
            if (u() < fresnel_reflectance(-d.z, eta, 1.0)) {
                d.z = -d.z;
                continue;
            }
            leave(order, std::hypot(p.x, p.y), w);
            return;
        }
        p = {p.x + d.x * s, p.y + d.y * s, p.z + d.z * s};
        ++order;
        w = collide(order, w);
        if (!(w > 0.0)) return;
        d = isotropic(u);
    }
}

void walk_one(const HalfSpaceOptions& o, Uniform& u, Tally& tally) {
    walk_path(
        o.eta, o.incidence, u, tally.entered,
        [&](long order, double w) {
            ++tally.collisions;
            tally.absorbed += w * (1.0 - o.albedo);
            w *= o.albedo;
            if (w <= 0.0) return -1.0;
            if (w < kRouletteBelow) {
                // Unbiased: survivors carry the expected weight of the rest.
                if (u() >= kRouletteSurvival) return -1.0;
                w /= kRouletteSurvival;
            }
            if (order >= o.max_collisions) {
                tally.truncated += w;
                return -1.0;
            }
            return w;
        },
        [&](long order, double r, double w) {
            const long a = annulus_of(o.edges, r);
            const bool once = order == 1;
            if (a < 0)
                (once ? tally.beyond_single : tally.beyond_multiple) += w;
            else
                (once ? tally.single : tally.multiple)[std::size_t(a)] += w;
        });
}

void check(const HalfSpaceOptions& o) {
    if (!(o.albedo >= 0.0 && o.albedo <= 1.0))
        throw ValueError("half-space walk: albedo " + std::to_string(o.albedo) +
                         " is outside [0, 1]");
    if (!(o.eta > 0.0 && std::isfinite(o.eta)))
        throw ValueError("half-space walk: eta " + std::to_string(o.eta) +
                         " must be positive and finite");
    if (o.photons == 0 || o.batches < 1 || uint64_t(o.batches) > o.photons)
        throw ValueError("half-space walk: " + std::to_string(o.photons) +
                         " photons in " + std::to_string(o.batches) + " batches");
    if (o.max_collisions < 1)
        throw ValueError("half-space walk: max_collisions must be at least 1");
    if (o.edges.size() < 2 || o.edges.front() != 0.0)
        throw ValueError("half-space walk: the annuli's radii must start at 0");
    for (std::size_t i = 1; i < o.edges.size(); ++i)
        if (!(o.edges[i] > o.edges[i - 1]) || !std::isfinite(o.edges[i]))
            throw ValueError("half-space walk: the annuli's radii must increase");
}

/// Mean and standard error of per-batch values.
std::pair<double, double> mean_error(const std::vector<double>& v) {
    double mean = 0.0;
    for (double x : v) mean += x;
    mean /= double(v.size());
    if (v.size() < 2) return {mean, 0.0};
    double ss = 0.0;
    for (double x : v) ss += (x - mean) * (x - mean);
    return {mean, std::sqrt(ss / double(v.size() - 1) / double(v.size()))};
}

/// Adaptive Simpson on [a, b] to absolute tolerance `tol`.
double simpson(const std::function<double(double)>& f, double a, double b, double fa,
               double fm, double fb, double whole, double tol, int depth) {
    const double m = 0.5 * (a + b);
    const double lm = 0.5 * (a + m), rm = 0.5 * (m + b);
    const double flm = f(lm), frm = f(rm);
    const double left = (m - a) / 6.0 * (fa + 4.0 * flm + fm);
    const double right = (b - m) / 6.0 * (fm + 4.0 * frm + fb);
    const double diff = left + right - whole;
    if (depth <= 0 || std::abs(diff) <= 15.0 * tol) return left + right + diff / 15.0;
    return simpson(f, a, m, fa, flm, fm, left, 0.5 * tol, depth - 1) +
           simpson(f, m, b, fm, frm, fb, right, 0.5 * tol, depth - 1);
}

double integrate(const std::function<double(double)>& f, double a, double b, double tol) {
    if (!(b > a)) return 0.0;
    // A few panels first, so that narrow features are not stepped over.
    constexpr int kPanels = 16;
    double sum = 0.0;
    for (int k = 0; k < kPanels; ++k) {
        const double lo = a + (b - a) * k / kPanels, hi = a + (b - a) * (k + 1) / kPanels;
        const double fa = f(lo), fm = f(0.5 * (lo + hi)), fb = f(hi);
        sum += simpson(f, lo, hi, fa, fm, fb, (hi - lo) / 6.0 * (fa + 4.0 * fm + fb),
                       tol / kPanels, 40);
    }
    return sum;
}

} // namespace

double fresnel_reflectance(double cos_in, double n_in, double n_out) {
    if (n_in == n_out) return 0.0; // index-matched: no interface
    cos_in = std::clamp(cos_in, 0.0, 1.0);
    const double sin_out = n_in / n_out * std::sqrt(std::max(0.0, 1.0 - cos_in * cos_in));
    if (sin_out >= 1.0) return 1.0;
    const double cos_out = std::sqrt(1.0 - sin_out * sin_out);
    const double rs =
        (n_in * cos_in - n_out * cos_out) / (n_in * cos_in + n_out * cos_out);
    const double rp =
        (n_out * cos_in - n_in * cos_out) / (n_out * cos_in + n_in * cos_out);
    return 0.5 * (rs * rs + rp * rp);
}

namespace {

/// The result from the batches' tallies: fluxes per unit flux that entered,
/// standard errors from the batch means.
HalfSpaceResult summarise_tallies(const std::vector<Tally>& tallies,
                                  const std::vector<double>& edges, uint64_t photons) {
    const std::size_t n = edges.size() - 1;
    const std::size_t batches = tallies.size();
    HalfSpaceResult r;
    r.edges = edges;
    r.photons = photons;
    r.single.assign(n, 0.0);
    r.multiple.assign(n, 0.0);
    r.single_error.assign(n, 0.0);
    r.multiple_error.assign(n, 0.0);
    double entered = 0.0, beyond = 0.0;
    for (const Tally& t : tallies) {
        entered += t.entered;
        beyond += t.beyond_single + t.beyond_multiple;
        r.absorbed += t.absorbed;
        r.truncated += t.truncated;
        r.collisions += t.collisions;
    }
    // Each batch's fluxes per unit flux it let in; the result is their
    // mean weighted by what entered (every photon counts once).
    std::vector<double> per(batches);
    const auto summarise = [&](const std::function<double(const Tally&)>& value,
                               double& mean, double& error) {
        double sum = 0.0;
        for (std::size_t b = 0; b < batches; ++b) {
            sum += value(tallies[b]);
            per[b] =
                tallies[b].entered > 0.0 ? value(tallies[b]) / tallies[b].entered : 0.0;
        }
        mean = entered > 0.0 ? sum / entered : 0.0;
        error = mean_error(per).second;
    };
    for (std::size_t a = 0; a < n; ++a) {
        summarise([a](const Tally& t) { return t.single[a]; }, r.single[a],
                  r.single_error[a]);
        summarise([a](const Tally& t) { return t.multiple[a]; }, r.multiple[a],
                  r.multiple_error[a]);
    }
    const auto sum_of = [](const std::vector<double>& v) {
        double s = 0.0;
        for (double x : v) s += x;
        return s;
    };
    summarise([&](const Tally& t) { return sum_of(t.single) + t.beyond_single; },
              r.total_single, r.total_single_error);
    summarise([&](const Tally& t) { return sum_of(t.multiple) + t.beyond_multiple; },
              r.total_multiple, r.total_multiple_error);
    summarise(
        [&](const Tally& t) {
            return sum_of(t.single) + sum_of(t.multiple) + t.beyond_single +
                   t.beyond_multiple;
        },
        r.total, r.total_error);
    if (entered > 0.0) {
        r.beyond = beyond / entered;
        r.absorbed /= entered;
        r.truncated /= entered;
    }
    return r;
}

std::vector<double> default_edges(std::vector<double> edges) {
    if (edges.empty())
        for (int i = 0; i <= 200; ++i) edges.push_back(0.05 * i);
    return edges;
}

Uniform batch_generator(uint64_t seed, std::size_t batch) {
    return Uniform(batch_seed(seed, batch));
}

} // namespace

HalfSpaceResult walk_half_space(const HalfSpaceOptions& options) {
    HalfSpaceOptions o = options;
    o.edges = default_edges(o.edges);
    check(o);
    const std::size_t n = o.edges.size() - 1;
    const std::size_t batches = std::size_t(o.batches);
    std::vector<Tally> tallies(batches);
    tbb::parallel_for(std::size_t(0), batches, [&](std::size_t b) {
        Tally& t = tallies[b];
        t.single.assign(n, 0.0);
        t.multiple.assign(n, 0.0);
        const uint64_t first = o.photons * b / batches,
                       end = o.photons * (b + 1) / batches;
        Uniform u = batch_generator(o.seed, b);
        for (uint64_t i = first; i < end; ++i) walk_one(o, u, t);
    });
    return summarise_tallies(tallies, o.edges, o.photons);
}

std::vector<HalfSpaceResult> walk_half_space_sweep(const HalfSpaceSweepOptions& options) {
    HalfSpaceOptions o;
    o.eta = options.eta;
    o.incidence = options.incidence;
    o.photons = options.photons;
    o.batches = options.batches;
    o.seed = options.seed;
    o.edges = default_edges(options.edges);
    check(o);
    const std::vector<double>& albedos = options.albedos;
    if (albedos.empty()) throw ValueError("half-space sweep: no albedos");
    double top = 0.0;
    for (double a : albedos) {
        if (!(a >= 0.0 && a <= kMaxSweepAlbedo))
            throw ValueError("half-space sweep: albedo " + std::to_string(a) +
                             " is outside [0, " + std::to_string(kMaxSweepAlbedo) + "]");
        top = std::max(top, a);
    }
    if (!(options.weight_floor > 0.0 && options.weight_floor < 1.0))
        throw ValueError("half-space sweep: weight_floor must be in (0, 1)");
    // Past this many collisions even the largest albedo's weight is below
    // the floor: the path ends there and that weight counts as truncated.
    const long last =
        top > 0.0 ? long(std::ceil(std::log(options.weight_floor) / std::log(top))) : 1;
    std::vector<double> log_albedo;
    for (double a : albedos)
        log_albedo.push_back(a > 0.0 ? std::log(a)
                                     : -std::numeric_limits<double>::infinity());
    const std::size_t n = o.edges.size() - 1, na = albedos.size();
    const std::size_t batches = std::size_t(o.batches);
    // tallies[b * na + k]: batch b, albedo k.
    std::vector<Tally> tallies(batches * na);
    tbb::parallel_for(std::size_t(0), batches, [&](std::size_t b) {
        Tally* t = &tallies[b * na];
        for (std::size_t k = 0; k < na; ++k) {
            t[k].single.assign(n, 0.0);
            t[k].multiple.assign(n, 0.0);
        }
        const uint64_t first = o.photons * b / batches,
                       end = o.photons * (b + 1) / batches;
        Uniform u = batch_generator(o.seed, b);
        double entered = 0.0;
        long collisions = 0;
        for (uint64_t i = first; i < end; ++i) {
            walk_path(
                o.eta, o.incidence, u, entered,
                [&](long order, double w) {
                    ++collisions;
                    if (order < last) return w;
                    for (std::size_t k = 0; k < na; ++k)
                        t[k].truncated += w * std::exp(double(order) * log_albedo[k]);
                    return -1.0;
                },
                [&](long order, double r, double w) {
                    const long a = annulus_of(o.edges, r);
                    for (std::size_t k = 0; k < na; ++k) {
                        // albedo^order; 0^0 = 1 (light that never scattered).
                        const double wk =
                            order == 0 ? w : w * std::exp(double(order) * log_albedo[k]);
                        Tally& tk = t[k];
                        const bool once = order == 1;
                        if (a < 0)
                            (once ? tk.beyond_single : tk.beyond_multiple) += wk;
                        else
                            (once ? tk.single : tk.multiple)[std::size_t(a)] += wk;
                    }
                });
        }
        for (std::size_t k = 0; k < na; ++k) {
            t[k].entered = entered;
            t[k].collisions = collisions;
        }
    });
    std::vector<HalfSpaceResult> out;
    std::vector<Tally> one(batches);
    for (std::size_t k = 0; k < na; ++k) {
        for (std::size_t b = 0; b < batches; ++b) one[b] = std::move(tallies[b * na + k]);
        HalfSpaceResult r = summarise_tallies(one, o.edges, o.photons);
        // What neither left nor was truncated was absorbed.
        r.absorbed = std::max(0.0, 1.0 - r.total - r.truncated);
        out.push_back(std::move(r));
    }
    return out;
}

double single_scattering_flux(double albedo, double eta, double r0, double r1) {
    if (!(r1 > r0) || r0 < 0.0) return 0.0;
    // Depth z = -ln(1 - x): e^-z dz = dx on [0, 1). From depth z the
    // annulus is seen between the cosines mu(r1) and mu(r0), mu(r) =
    // z / sqrt(r^2 + z^2); the path back is z / mu long.
    const auto mu_of = [](double z, double r) {
        return std::isinf(r) ? 0.0 : r == 0.0 ? 1.0 : z / std::hypot(r, z);
    };
    const auto inner = [&](double x) {
        if (x >= 1.0) return 0.0;
        const double z = -std::log1p(-x);
        return integrate(
            [&](double mu) {
                return mu <= 0.0 ? 0.0
                                 : std::exp(-z / mu) *
                                       (1.0 - fresnel_reflectance(mu, eta, 1.0));
            },
            mu_of(z, r1), mu_of(z, r0), 1e-10);
    };
    return 0.5 * albedo * integrate(inner, 0.0, 1.0, 1e-9);
}

} // namespace sss
