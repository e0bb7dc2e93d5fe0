// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// Profiles against the half-space walk, and the Monte-Carlo profile table.

#include "sss/truth/profile_accuracy.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "sss/util/error.h"

namespace sss {

std::vector<double> profile_annulus_flux(const Profile& p,
                                         const std::vector<double>& edges) {
    std::vector<double> out;
    double inner = 0.0;
    for (std::size_t i = 0; i + 1 < edges.size(); ++i) {
        const double outer = p.disk(edges[i + 1]);
        out.push_back(i == 0 ? outer - p.disk(edges[0]) : outer - inner);
        inner = outer;
    }
    return out;
}

ProfileAccuracy compare_with_walk(const Profile& p, const HalfSpaceResult& walk) {
    const std::vector<double>& e = walk.edges;
    if (e.size() < 2 || e.back() < 10.0 - 1e-9)
        throw ValueError("profile accuracy: the walk's annuli must reach 10 l");
    const std::vector<double> model = profile_annulus_flux(p, e);
    ProfileAccuracy a;
    double diff = 0.0, sum = 0.0, noise = 0.0;
    const std::size_t ranges = kAccuracyRanges.size() - 1;
    std::vector<double> in_model(ranges, 0.0), in_walk(ranges, 0.0);
    for (std::size_t i = 0; i + 1 < e.size(); ++i) {
        const double mid = 0.5 * (e[i] + e[i + 1]);
        if (mid > 10.0) break;
        const double w = walk.single[i] + walk.multiple[i];
        diff += std::abs(model[i] - w);
        sum += w;
        noise += std::hypot(walk.single_error[i], walk.multiple_error[i]);
        for (std::size_t r = 0; r < ranges; ++r)
            if (mid >= kAccuracyRanges[r] && mid < kAccuracyRanges[r + 1]) {
                in_model[r] += model[i];
                in_walk[r] += w;
            }
    }
    a.l1w = sum > 0.0 ? diff / sum : 0.0;
    a.l1w_noise = sum > 0.0 ? std::sqrt(2.0 / std::numbers::pi) * noise / sum : 0.0;
    a.d_rd = walk.total > 0.0 ? p.total() / walk.total - 1.0 : 0.0;
    a.d_rd_error = walk.total > 0.0 ? walk.total_error / walk.total : 0.0;
    for (std::size_t r = 0; r < ranges; ++r)
        a.range_ratio.push_back(in_walk[r] > 0.0 ? in_model[r] / in_walk[r] : 0.0);
    return a;
}

McTableOptions default_mc_table_options() {
    McTableOptions o;
    o.eta = {1.0, 1.1, 1.2, 1.3, 1.4, 1.5, 1.6};
    // Nodes even in v = sqrt(1 - alpha') (the table interpolates in v), denser
    // towards alpha' = 1 where most materials are.
    for (double v : {0.01, 0.014, 0.02, 0.028, 0.04, 0.056, 0.08, 0.11, 0.15, 0.2,
                     0.26, 0.33,  0.41, 0.5,   0.6,  0.7,   0.8,  0.9,  0.95, 0.99})
        o.albedo.push_back(1.0 - v * v);
    std::reverse(o.albedo.begin(), o.albedo.end());
    return o;
}

namespace {

// The table's annuli: [0, 1e-3], then eight per decade out to 10^2.5 l.
std::vector<double> table_edges() {
    std::vector<double> e{0.0};
    for (int k = 0; k <= 44; ++k) e.push_back(std::pow(10.0, -3.0 + k / 8.0));
    return e;
}

} // namespace

std::string make_mc_table(const McTableOptions& o,
                          const std::function<void(double)>& progress) {
    if (o.eta.empty() || o.albedo.empty())
        throw ValueError("mc table: no eta or albedo nodes");
    for (double a : o.albedo)
        if (!(a > 0.0)) throw ValueError("mc table: albedo nodes must be positive");
    const std::vector<double> edges = table_edges();
    std::vector<double> rho;
    for (std::size_t i = 0; i + 1 < edges.size(); ++i)
        rho.push_back(i == 0 ? 0.5 * edges[1] : std::sqrt(edges[i] * edges[i + 1]));
    std::string text;
    char buf[64];
    auto line = [&](const char* key, const std::vector<double>& v) {
        text += key;
        for (double x : v) {
            std::snprintf(buf, sizeof buf, " %.9g", x);
            text += buf;
        }
        text += "\n";
    };
    std::snprintf(buf, sizeof buf, "%llu", static_cast<unsigned long long>(o.photons));
    text += "# sss Monte-Carlo half-space profile table: " + std::string(buf) +
            " photons per eta, seed " + std::to_string(o.seed) + "\n";
    text +=
        "# Written by scripts/make-mc-table. Each ratio is the random walk's flux\n"
        "# leaving through an annulus (normal pencil beam, reduced isotropic medium,\n"
        "# exact Fresnel boundary) over photon beam diffusion's; rho is the annulus's\n"
        "# mean radius in transport mean free paths.\n";
    line("eta", o.eta);
    line("albedo", o.albedo);
    line("rho", rho);
    for (std::size_t e = 0; e < o.eta.size(); ++e) {
        HalfSpaceSweepOptions s;
        s.albedos = o.albedo;
        s.eta = o.eta[e];
        s.photons = o.photons;
        s.batches = o.batches;
        s.seed = o.seed + e;
        s.edges = edges;
        s.weight_floor = 1e-10;
        const std::vector<HalfSpaceResult> walks = walk_half_space_sweep(s);
        for (std::size_t a = 0; a < o.albedo.size(); ++a) {
            const HalfSpaceResult& w = walks[a];
            const Profile pbd = Profile::from_coefficients(
                ProfileKind::Pbd, {o.albedo[a], 1.0 - o.albedo[a], o.eta[e]});
            const std::vector<double> model = profile_annulus_flux(pbd, edges);
            // Annuli with too little light for a ratio take their nearest
            // reliable neighbour's (outwards first: the far tail).
            std::vector<double> ratio(rho.size(), 0.0);
            for (std::size_t k = 0; k < rho.size(); ++k) {
                const double flux = w.single[k] + w.multiple[k];
                const double err = std::hypot(w.single_error[k], w.multiple_error[k]);
                if (flux > 1e-12 && model[k] > 1e-12 &&
                    err <= o.max_relative_error * flux)
                    ratio[k] = flux / model[k];
            }
            double last = 0.0;
            for (double& r : ratio) r = r > 0.0 ? (last = r) : last;
            last = 0.0;
            for (std::size_t k = rho.size(); k-- > 0;)
                ratio[k] = ratio[k] > 0.0 ? (last = ratio[k]) : last;
            for (double& r : ratio)
                if (!(r > 0.0)) r = 1.0; // no reliable annulus at all
            std::snprintf(buf, sizeof buf, "ratio %zu %zu", e, a);
            text += buf;
            for (double r : ratio) {
                std::snprintf(buf, sizeof buf, " %.6g", r);
                text += buf;
            }
            text += "\n";
        }
        if (progress) progress(double(e + 1) / double(o.eta.size()));
    }
    return text;
}

} // namespace sss
