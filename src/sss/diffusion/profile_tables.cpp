// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file profile_tables.cpp
/// Builds the q = r^2 profile tables: finite-difference derivatives, the
/// quadrupole remainder bound and the running maxima from the far end.

#include "profile_tables.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <oneapi/tbb/parallel_for.h>

#include "sss/util/limits.h"

namespace sss::diffusion_detail {

namespace {

double q_of_bits(uint32_t bits) {
    return double(std::bit_cast<float>(bits));
}

// A class holds profiles whose transport lengths (1 / sigma_tr) fall in one
// bin of this ratio and whose totals (the albedo's effect) are within this
// ratio of its smallest: their bounds then differ little, so the class's
// largest bound is close to each of its own.
constexpr double kEnvelopeLength = 1.05, kEnvelopeTotal = 1.02;

void make_envelopes(const std::vector<Profile>& profiles, Tables& t) {
    const auto bin = [&](uint32_t i) {
        const double s = profiles[i].sigma_tr();
        return s > 0.0 && std::isfinite(s)
                   ? int64_t(std::floor(-std::log(s) / std::log(kEnvelopeLength)))
                   : INT64_MIN;
    };
    std::vector<std::pair<int64_t, uint32_t>> order;
    for (uint32_t i = 0; i < profiles.size(); ++i) order.push_back({bin(i), i});
    std::stable_sort(order.begin(), order.end(), [&](const auto& a, const auto& b) {
        return a.first != b.first
                   ? a.first < b.first
                   : profiles[a.second].total() < profiles[b.second].total();
    });
    // The classes (each a run of `order`), then their bounds, class by class.
    t.envelope_of.assign(profiles.size(), 0);
    std::vector<std::size_t> start; // each class's first position in `order`
    int64_t first_bin = 0;
    double first_total = 0.0;
    for (std::size_t o = 0; o < order.size(); ++o) {
        const auto [b, i] = order[o];
        if (start.empty() || b != first_bin ||
            !(profiles[i].total() <= kEnvelopeTotal * first_total)) {
            first_bin = b;
            first_total = profiles[i].total();
            start.push_back(o);
        }
        t.envelope_of[i] = uint32_t(start.size() - 1);
    }
    start.push_back(order.size());
    t.envelopes.resize(start.size() - 1);
    oneapi::tbb::parallel_for(std::size_t(0), t.envelopes.size(), [&](std::size_t c) {
        ChannelTable& e = t.envelopes[c];
        e.bounds.assign(t.count, TableBounds{0, 0, 0, 0});
        for (std::size_t o = start[c]; o < start[c + 1]; ++o) {
            const ChannelTable& m = t.channels[order[o].second];
            for (uint32_t k = 0; k < t.count; ++k) {
                TableBounds& eb = e.bounds[k];
                const TableBounds& mb = m.bounds[k];
                eb.error_bound = std::max(eb.error_bound, mb.error_bound);
                eb.max_value = std::max(eb.max_value, mb.max_value);
                eb.max_d1 = std::max(eb.max_d1, mb.max_d1);
                eb.max_d2 = std::max(eb.max_d2, mb.max_d2);
            }
        }
    });
}

} // namespace

std::vector<float> material_near_rows(const Tables& tables,
                                      const std::vector<glm::u32vec3>& materials) {
    const std::size_t per_material = std::size_t(tables.count) * kProfileRowFloats;
    if (tables.profile_rows.empty() ||
        uint64_t(materials.size()) * per_material * sizeof(float) > kMaterialRowBytes)
        return {};
    std::vector<float> rows(materials.size() * per_material, 0.0f);
    oneapi::tbb::parallel_for(std::size_t(0), materials.size(), [&](std::size_t m) {
        for (int ch = 0; ch < 3; ++ch) {
            const float* src =
                tables.profile_rows.data() + materials[m][ch] * per_material;
            float* dst = rows.data() + m * per_material;
            for (uint32_t k = 0; k < tables.count; ++k) {
                dst[k * kProfileRowFloats + 2 * ch] = src[k * kProfileRowFloats];
                dst[k * kProfileRowFloats + 2 * ch + 1] = src[k * kProfileRowFloats + 1];
            }
        }
    });
    return rows;
}

Tables build_tables(const std::vector<Profile>& profiles, bool per_point) {
    Tables t;
    double lmin = std::numeric_limits<double>::infinity(), rmax = 0.0;
    for (const Profile& p : profiles) {
        if (p.total() <= 0.0) continue;
        double core = p.core_length() > 0.0 ? p.core_length() : 1e-2 / p.sigma_tr();
        lmin = std::min(lmin, core);
        rmax = std::max(rmax, p.cutoff_radius(1e-7));
    }
    if (!(rmax > 0.0) || !std::isfinite(lmin)) {
        lmin = 1.0;
        rmax = 1.0;
    }
    float q0 = float(std::max(1e-30, 1e-8 * lmin * lmin));
    t.bits0 = std::bit_cast<uint32_t>(q0);
    double qend = std::min(1e36, std::max(rmax * rmax, 4.0 * double(q0)));
    uint32_t bend = std::bit_cast<uint32_t>(float(qend));
    t.count = ((bend - t.bits0) >> kShift) + 3;
    // Per profile and entry: the entry and four bounds, with per-point
    // materials its row and its class's share of the bounds at most.
    const uint64_t per_entry =
        sizeof(TableEntry) + 4 * sizeof(float) +
        (per_point ? kProfileRowFloats * sizeof(float) + 4 * sizeof(float) : 0);
    check_memory(uint64_t(profiles.size()) * t.count * per_entry,
                 "the tables of " + std::to_string(profiles.size()) + " profiles",
                 "give fewer distinct per-point materials");
    t.channels.resize(profiles.size());
    // Each profile's table on its own (per-point materials make hundreds).
    oneapi::tbb::parallel_for(std::size_t(0), profiles.size(), [&](std::size_t pi) {
        const Profile& p = profiles[pi];
        ChannelTable& ct = t.channels[pi];
        ct.entries.assign(t.count, TableEntry{0, 0, 0, 0});
        ct.bounds.assign(t.count, TableBounds{0, 0, 0, 0});
        ct.core2 = float(p.core_length() * p.core_length());
        if (p.total() <= 0.0) return;
        double rcut = p.cutoff_radius(1e-7);
        auto F = [&](double q) { return p.eval(std::sqrt(std::max(q, 0.0))); };
        std::vector<double> g(t.count, 0.0);
        for (uint32_t k = 0; k + 1 < t.count; ++k) {
            double q = q_of_bits(t.bits0 + (k << kShift));
            if (std::sqrt(q) > rcut) break;
            double h = 2e-3 * q;
            double fm2 = F(q - 2 * h), fm = F(q - h), f0 = F(q), fp = F(q + h),
                   fp2 = F(q + 2 * h);
            double d1 = (fp - fm) / (2 * h);
            double d2 = (fp - 2 * f0 + fm) / (h * h);
            double d3 = (fp2 - 2 * fp + 2 * fm - fm2) / (2 * h * h * h);
            ct.entries[k] = {float(f0), float(d1), float(d2), 0.0f};
            double w = std::sqrt(q);
            // Third-order terms dropped by the quadrupole expansion of F(|w - delta|^2):
            // 2 |F''| |w| s^3 + (4/3) |F'''| |w|^3 s^3, per unit s^3 and power.
            g[k] = 2.0 * std::abs(d2) * w + (4.0 / 3.0) * std::abs(d3) * w * w * w;
        }
        // Running maxima from the far end make both bounds valid for every q' >= q.
        double gmax = 0.0, fmax = 0.0, d1max = 0.0, d2max = 0.0;
        for (uint32_t k = t.count; k-- > 0;) {
            gmax = std::max(gmax, g[k]);
            fmax = std::max(fmax, double(ct.entries[k].f));
            d1max = std::max(d1max, std::abs(double(ct.entries[k].df)));
            d2max = std::max(d2max, std::abs(double(ct.entries[k].d2f)));
            ct.bounds[k] = {float(std::min(gmax, 1e30)), float(std::min(fmax, 1e30)),
                            float(std::min(d1max, 1e30)), float(std::min(d2max, 1e30))};
        }
    });
    if (t.channels.size() >= 3) {
        t.rows.assign(std::size_t(t.count) * kRowFloats, 0.0f);
        for (uint32_t k = 0; k < t.count; ++k) {
            float* row = t.rows.data() + std::size_t(k) * kRowFloats;
            for (int ch = 0; ch < 3; ++ch) {
                const std::vector<TableEntry>& e = t.channels[std::size_t(ch)].entries;
                const TableEntry& a = e[k];
                const TableEntry& b = k + 1 < t.count ? e[k + 1] : e[k];
                row[2 * ch] = a.f;
                row[2 * ch + 1] = b.f - a.f;
                row[8 + 2 * ch] = a.df;
                row[8 + 2 * ch + 1] = b.df - a.df;
                row[16 + 2 * ch] = a.d2f;
                row[16 + 2 * ch + 1] = b.d2f - a.d2f;
            }
        }
    }
    if (per_point) make_envelopes(profiles, t);
    // (The kernels address them with 32-bit offsets; beyond that the
    // receivers go one by one.)
    const std::size_t per_profile = std::size_t(t.count) * kProfileRowFloats;
    if (per_point && per_profile * t.channels.size() < std::size_t(INT32_MAX)) {
        t.profile_rows.assign(per_profile * t.channels.size(), 0.0f);
        oneapi::tbb::parallel_for(std::size_t(0), t.channels.size(), [&](std::size_t pi) {
            const std::vector<TableEntry>& e = t.channels[pi].entries;
            for (uint32_t k = 0; k < t.count; ++k) {
                float* row = t.profile_rows.data() + pi * per_profile +
                             std::size_t(k) * kProfileRowFloats;
                const TableEntry& a = e[k];
                const TableEntry& b = k + 1 < t.count ? e[k + 1] : e[k];
                row[0] = a.f;
                row[1] = b.f - a.f;
                row[2] = a.df;
                row[3] = b.df - a.df;
                row[4] = a.d2f;
                row[5] = b.d2f - a.d2f;
            }
        });
    }
    return t;
}

} // namespace sss::diffusion_detail
