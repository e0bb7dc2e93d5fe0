// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file mc_table.cpp
/// Reading and interpolating the Monte-Carlo profile table.

#include "mc_table.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>
#include <sstream>

#include "sss/util/error.h"
#include "sss/util/math.h"

#include "beam_diffusion.h"

namespace sss::diffusion_detail {

extern const char* const kMcTableText; // generated from data/profiles/mc_halfspace.tbl

namespace {

// Index i and weight t of x between sorted nodes (clamped at the ends).
std::pair<std::size_t, double> bracket(const std::vector<double>& nodes, double x) {
    if (nodes.size() < 2 || x <= nodes.front()) return {0, 0.0};
    if (x >= nodes.back()) return {nodes.size() - 2, 1.0};
    std::size_t i =
        std::size_t(std::upper_bound(nodes.begin(), nodes.end(), x) - nodes.begin()) - 1;
    return {i, (x - nodes[i]) / (nodes[i + 1] - nodes[i])};
}

} // namespace

McTable parse_mc_table(const std::string& text) {
    McTable t;
    std::istringstream in(text);
    std::string line;
    int line_no = 0;
    auto fail = [&](const std::string& what) {
        throw FormatError("mc_halfspace.tbl",
                          "line " + std::to_string(line_no) + ": " + what);
    };
    auto numbers = [&](std::istringstream& ls) {
        std::vector<double> v;
        double x;
        while (ls >> x) {
            if (!std::isfinite(x)) fail("a value that is not finite");
            v.push_back(x);
        }
        if (!ls.eof()) fail("a value that is not a number");
        return v;
    };
    while (std::getline(in, line)) {
        ++line_no;
        if (line.empty()) continue;
        if (line[0] == '#') {
            if (t.source.empty() && line.size() > 2) t.source = line.substr(2);
            continue;
        }
        std::istringstream ls(line);
        std::string key;
        ls >> key;
        if (key == "eta")
            t.eta = numbers(ls);
        else if (key == "albedo")
            t.albedo = numbers(ls);
        else if (key == "rho")
            t.rho = numbers(ls);
        else if (key == "ratio") {
            std::size_t e, a;
            if (!(ls >> e >> a)) fail("ratio without its eta and albedo index");
            if (t.eta.empty() || t.albedo.empty() || t.rho.empty())
                fail("ratio before the eta, albedo and rho lines");
            if (e >= t.eta.size() || a >= t.albedo.size()) fail("index out of range");
            std::vector<double> v = numbers(ls);
            if (v.size() != t.rho.size()) fail("wrong number of ratios");
            if (t.ratio.empty())
                t.ratio.assign(t.eta.size() * t.albedo.size() * t.rho.size(), -1.0);
            for (double x : v)
                if (!(x > 0.0)) fail("a ratio that is not positive");
            std::copy(v.begin(), v.end(),
                      t.ratio.begin() +
                          std::ptrdiff_t((e * t.albedo.size() + a) * t.rho.size()));
        } else
            fail("unknown key '" + key + "'");
    }
    for (const std::vector<double>* v : {&t.eta, &t.albedo, &t.rho})
        for (std::size_t i = 1; i < v->size(); ++i)
            if (!((*v)[i] > (*v)[i - 1])) fail("nodes must increase");
    if (t.eta.empty() || t.albedo.empty() || t.rho.empty()) fail("missing nodes");
    if (std::find(t.ratio.begin(), t.ratio.end(), -1.0) != t.ratio.end() ||
        t.ratio.size() != t.eta.size() * t.albedo.size() * t.rho.size())
        fail("ratios missing for some (eta, albedo)");
    return t;
}

const McTable& mc_table() {
    static const McTable table = [] {
        std::string text = kMcTableText;
        if (text.find_first_not_of(" \t\r\n") == std::string::npos)
            throw ValueError("profile mc: this build has no Monte-Carlo table "
                             "(data/profiles/mc_halfspace.tbl; scripts/make-mc-table "
                             "writes it)");
        return parse_mc_table(text);
    }();
    return table;
}

void check_mc_range(double eta) {
    const McTable& t = mc_table();
    if (!(eta >= t.eta.front() - 1e-9 && eta <= t.eta.back() + 1e-9))
        throw ValueError("profile mc: ior " + std::to_string(eta) +
                         " is outside the Monte-Carlo table's range [" +
                         std::to_string(t.eta.front()) + ", " +
                         std::to_string(t.eta.back()) + "] (use -profile pbd)");
}

double mc_ratio(const McTable& t, double alpha, double eta, double rho) {
    // Albedo nodes are increasing in alpha; interpolate in v = sqrt(1 - alpha),
    // where the profiles change smoothly up to alpha = 1.
    // (Plain variables, not structured bindings: a lambda below uses them.)
    const std::pair<std::size_t, double> be = bracket(t.eta, eta),
                                         ba = bracket(t.albedo, alpha);
    const std::size_t e = be.first, a = ba.first;
    const double te = be.second;
    double ta = ba.second;
    if (ta > 0.0 && ta < 1.0) {
        const double v0 = std::sqrt(1.0 - t.albedo[a]),
                     v1 = std::sqrt(1.0 - t.albedo[a + 1]);
        ta = (v0 - std::sqrt(1.0 - alpha)) / (v0 - v1);
    }
    const double lrho = std::log(std::max(rho, 1e-300));
    const std::pair<std::size_t, double> bk = bracket(t.rho, rho);
    const std::size_t k = bk.first;
    double tk = bk.second;
    if (tk > 0.0 && tk < 1.0)
        tk = (lrho - std::log(t.rho[k])) / (std::log(t.rho[k + 1]) - std::log(t.rho[k]));
    const std::size_t na = t.albedo.size(), nr = t.rho.size();
    auto at = [&](std::size_t ei, std::size_t ai) {
        const double* r = t.ratio.data() + (ei * na + ai) * nr;
        return r[k] + tk * (r[std::min(k + 1, nr - 1)] - r[k]);
    };
    const std::size_t e1 = std::min(e + 1, t.eta.size() - 1),
                      a1 = std::min(a + 1, na - 1);
    const double lo = at(e, a) + ta * (at(e, a1) - at(e, a));
    const double hi = at(e1, a) + ta * (at(e1, a1) - at(e1, a));
    return lo + te * (hi - lo);
}

namespace {

// The ratio past the table's last annulus for alpha' -> 1, such that no light
// is lost without absorption (total 1, as the walk has it): what matters
// only for alpha' above the last node, whose light leaves mostly beyond the
// table's last annulus. Cached per eta.
double tail_ratio(double eta) {
    static std::mutex mutex;
    static std::map<double, double> cache;
    std::lock_guard<std::mutex> lock(mutex);
    auto it = cache.find(eta);
    if (it != cache.end()) return it->second;
    const McTable& t = mc_table();
    const double top = t.albedo.back(), last = t.rho.back();
    // \int_0^last f_pbd ratio, by the midpoint rule in ln rho.
    const int n = 4000;
    const double lo = std::log(1e-6), hi = std::log(last), h = (hi - lo) / n;
    double inner = beam_curve_value(1.0, eta, 1e-6) * 1e-6; // f is flat below
    for (int i = 0; i < n; ++i) {
        const double rho = std::exp(lo + (i + 0.5) * h);
        inner += beam_curve_value(1.0, eta, rho) * mc_ratio(t, top, eta, rho) * rho * h;
    }
    std::shared_ptr<const RadialCurve> pbd = cached_curve(0, beam_curve_value, 1.0, eta);
    const double outer = pbd->total() - pbd->integral(last);
    double r = outer > 0.0 ? (1.0 / (2.0 * kPi) - inner) / outer : 1.0;
    if (!(r > 0.0) || !std::isfinite(r)) r = 1.0;
    cache.emplace(eta, r);
    return r;
}

} // namespace

double mc_curve_value(double alpha, double eta, double rho) {
    const McTable& t = mc_table();
    double ratio = mc_ratio(t, alpha, eta, rho);
    const double last = t.rho.back();
    if (rho > last) {
        // Towards the energy-conserving tail over one decade.
        const double w = std::min(1.0, std::log(rho / last) / std::log(10.0));
        ratio += w * (tail_ratio(eta) - ratio);
    }
    return beam_curve_value(alpha, eta, rho) * ratio;
}

} // namespace sss::diffusion_detail
