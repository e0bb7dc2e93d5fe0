// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// A material's profiles against the walk: the report, its CSV and its plot.

#include "sss/truth/profile_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "sss/util/error.h"

namespace sss {

namespace {

std::string fmt(const char* f, double a) {
    char buf[64];
    std::snprintf(buf, sizeof buf, f, a);
    return buf;
}

std::string percent(double x) {
    return fmt("%+.1f%%", 100.0 * x);
}

} // namespace

ProfileReport profile_report(const ProfileReportOptions& o) {
    const MaterialSpec& m = o.material;
    m.validate();
    if (m.albedo_from_file || m.dmfp_from_file)
        throw ValueError(
            "profile report: a per-point material has no single medium; give "
            "its values");
    if (o.profiles.empty()) throw ValueError("profile report: no profiles");
    ProfileReport rep;
    rep.kinds = o.profiles;
    const double eta = m.resolved_ior();
    glm::dvec3 ss, sa;
    if (m.uses_albedo_form()) {
        glm::dvec3 albedo, dmfp;
        m.resolve_albedo_dmfp(albedo, dmfp);
        for (int ch = 0; ch < 3; ++ch) {
            const ChannelCoefficients c =
                coefficients_from_albedo_dmfp(albedo[ch], dmfp[ch], eta);
            ss[ch] = c.sigma_s_prime;
            sa[ch] = c.sigma_a;
        }
        rep.material =
            "albedo/diffusemeanfreepath (the medium the classic dipole infers)";
    } else {
        m.resolve_coefficients(ss, sa);
        rep.material = m.scattering || m.absorption ? "scattering/absorption"
                                                    : "material " + m.preset;
    }
    HalfSpaceSweepOptions s;
    s.eta = eta;
    s.photons = o.photons;
    s.seed = o.seed;
    s.batches = o.batches;
    for (int ch = 0; ch < 3; ++ch) {
        const double st = ss[ch] + sa[ch];
        if (!(st > 0.0) || !(ss[ch] > 0.0))
            throw ValueError("profile report: channel " + std::to_string(ch) +
                             " does not scatter (sigma_s' = 0)");
        rep.channel[ch].alpha = std::min(ss[ch] / st, kMaxSweepAlbedo);
        rep.channel[ch].eta = eta;
        rep.channel[ch].sigma_t_mm = st;
        s.albedos.push_back(rep.channel[ch].alpha);
    }
    std::vector<HalfSpaceResult> walks = walk_half_space_sweep(s);
    for (int ch = 0; ch < 3; ++ch) {
        ChannelReport& c = rep.channel[ch];
        c.walk = std::move(walks[std::size_t(ch)]);
        for (ProfileKind k : o.profiles) {
            c.profiles.push_back(
                Profile::from_coefficients(k, {c.alpha, 1.0 - c.alpha, eta}));
            c.accuracy.push_back(compare_with_walk(c.profiles.back(), c.walk));
        }
    }
    return rep;
}

std::string format_profile_report(const ProfileReport& r) {
    std::string out = r.material + ", ior " + fmt("%g", r.channel[0].eta) +
                      "; walk: " + std::to_string(r.channel[0].walk.photons) +
                      " photons, normal pencil beam\n";
    out += "L1w: L1 error of r R(r) over r in [0, 10 l]; dRd: total reflectance against "
           "the walk's;\nflux ratios model / walk for r/l in [0, 0.1), [0.1, 1), [1, 3), "
           "[3, 10)\n";
    const char* names = "rgb";
    for (int ch = 0; ch < 3; ++ch) {
        const ChannelReport& c = r.channel[ch];
        out +=
            "\nchannel " + std::string(1, names[ch]) + ": alpha' " +
            fmt("%.6g", c.alpha) + ", l = " + fmt("%.4g", 1.0 / c.sigma_t_mm) +
            " mm, walk Rd " + fmt("%.5f", c.walk.total) + " +- " +
            fmt("%.5f", c.walk.total_error) + " (single " +
            fmt("%.5f", c.walk.total_single) + "), L1w noise " +
            fmt("%.2f%%", 100.0 * (c.accuracy.empty() ? 0.0 : c.accuracy[0].l1w_noise)) +
            "\n";
        char line[256];
        std::snprintf(line, sizeof line, "  %-8s %8s %8s %8s %8s %8s %8s\n", "profile",
                      "L1w", "dRd", "<0.1", "0.1-1", "1-3", "3-10");
        out += line;
        for (std::size_t k = 0; k < r.kinds.size(); ++k) {
            const ProfileAccuracy& a = c.accuracy[k];
            std::snprintf(
                line, sizeof line, "  %-8s %7.1f%% %8s %8.3f %8.3f %8.3f %8.3f\n",
                profile_kind_name(r.kinds[k]), 100.0 * a.l1w, percent(a.d_rd).c_str(),
                a.range_ratio[0], a.range_ratio[1], a.range_ratio[2], a.range_ratio[3]);
            out += line;
        }
    }
    return out;
}

std::string profile_report_csv(const ProfileReport& r) {
    std::string out =
        "channel,alpha,eta,r0,r1,walk_single,walk_single_error,walk_multiple,"
        "walk_multiple_error";
    for (ProfileKind k : r.kinds) out += std::string(",") + profile_kind_name(k);
    out += "\n";
    char buf[64];
    for (int ch = 0; ch < 3; ++ch) {
        const ChannelReport& c = r.channel[ch];
        std::vector<std::vector<double>> model;
        for (const Profile& p : c.profiles)
            model.push_back(profile_annulus_flux(p, c.walk.edges));
        for (std::size_t i = 0; i + 1 < c.walk.edges.size(); ++i) {
            std::snprintf(buf, sizeof buf, "%d,%.9g,%.9g", ch, c.alpha, c.eta);
            out += buf;
            for (double v :
                 {c.walk.edges[i], c.walk.edges[i + 1], c.walk.single[i],
                  c.walk.single_error[i], c.walk.multiple[i], c.walk.multiple_error[i]}) {
                std::snprintf(buf, sizeof buf, ",%.9g", v);
                out += buf;
            }
            for (const std::vector<double>& f : model) {
                std::snprintf(buf, sizeof buf, ",%.9g", f[i]);
                out += buf;
            }
            out += "\n";
        }
    }
    return out;
}

std::string profile_report_tsv(const ProfileReport& r) {
    std::string out =
        "channel\talpha\teta\twalk_rd\twalk_rd_error\twalk_single\tprofile\t"
        "l1w\tl1w_noise\td_rd\td_rd_error\tratio_0_0.1\tratio_0.1_1\t"
        "ratio_1_3\tratio_3_10\n";
    char buf[512];
    for (int ch = 0; ch < 3; ++ch) {
        const ChannelReport& c = r.channel[ch];
        for (std::size_t k = 0; k < r.kinds.size(); ++k) {
            const ProfileAccuracy& a = c.accuracy[k];
            std::snprintf(
                buf, sizeof buf,
                "%d\t%.9g\t%.9g\t%.9g\t%.3g\t%.9g\t%s\t%.6g\t%.3g\t%.6g\t%.3g\t%.6g\t%.6g"
                "\t%.6g\t%.6g\n",
                ch, c.alpha, c.eta, c.walk.total, c.walk.total_error, c.walk.total_single,
                profile_kind_name(r.kinds[k]), a.l1w, a.l1w_noise, a.d_rd, a.d_rd_error,
                a.range_ratio[0], a.range_ratio[1], a.range_ratio[2], a.range_ratio[3]);
            out += buf;
        }
    }
    return out;
}

std::string profile_report_svg(const ProfileReport& r) {
    // Three panels of 360 x 280: x = r / l in [0, 10], y = log10 of the flux
    // per unit r (2 pi r R(r)) over five decades below the walk's peak.
    const double pw = 360, ph = 280, left = 50, top = 30, w = 290, h = 200;
    static const char* const colours[] = {"#d62728", "#ff7f0e", "#2ca02c",
                                          "#1f77b4", "#9467bd", "#8c564b"};
    std::string out = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" +
                      fmt("%g", 3 * pw) + "\" height=\"" + fmt("%g", ph + 30) +
                      "\" font-family=\"sans-serif\" font-size=\"11\">\n"
                      "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
    const char* names[] = {"red", "green", "blue"};
    for (int ch = 0; ch < 3; ++ch) {
        const ChannelReport& c = r.channel[ch];
        const std::vector<double>& e = c.walk.edges;
        const double x0 = ch * pw + left;
        std::vector<double> walk;
        double peak = 0.0;
        for (std::size_t i = 0; i + 1 < e.size(); ++i) {
            walk.push_back((c.walk.single[i] + c.walk.multiple[i]) / (e[i + 1] - e[i]));
            peak = std::max(peak, walk.back());
        }
        if (!(peak > 0.0)) continue;
        const double ytop = std::ceil(std::log10(peak)), ybot = ytop - 5.0;
        auto px = [&](double rr) { return x0 + w * std::min(rr, 10.0) / 10.0; };
        auto py = [&](double v) {
            const double lv = v > 0.0 ? std::clamp(std::log10(v), ybot, ytop) : ybot;
            return top + h * (ytop - lv) / (ytop - ybot);
        };
        out += "<rect x=\"" + fmt("%g", x0) + "\" y=\"" + fmt("%g", top) + "\" width=\"" +
               fmt("%g", w) + "\" height=\"" + fmt("%g", h) +
               "\" fill=\"none\" stroke=\"#888\"/>\n";
        out += "<text x=\"" + fmt("%g", x0) + "\" y=\"" + fmt("%g", top - 8) + "\">" +
               names[ch] + ": alpha' " + fmt("%.4g", c.alpha) + "</text>\n";
        for (int d = 0; d <= 5; ++d)
            out += "<text x=\"" + fmt("%g", x0 - 40) + "\" y=\"" +
                   fmt("%g", top + h * d / 5.0 + 4) + "\">1e" + fmt("%g", ytop - d) +
                   "</text>\n";
        for (int t = 0; t <= 10; t += 2)
            out += "<text x=\"" + fmt("%g", px(t) - 4) + "\" y=\"" +
                   fmt("%g", top + h + 14) + "\">" + std::to_string(t) + "</text>\n";
        out += "<text x=\"" + fmt("%g", x0 + w / 2 - 10) + "\" y=\"" +
               fmt("%g", top + h + 28) + "\">r / l</text>\n";
        auto polyline = [&](const std::vector<double>& v, const char* colour,
                            double width) {
            out += "<polyline fill=\"none\" stroke=\"" + std::string(colour) +
                   "\" stroke-width=\"" + fmt("%g", width) + "\" points=\"";
            for (std::size_t i = 0; i < v.size(); ++i) {
                const double mid = 0.5 * (e[i] + e[i + 1]);
                if (mid > 10.0) break;
                out += fmt("%.1f", px(mid)) + "," + fmt("%.1f", py(v[i])) + " ";
            }
            out += "\"/>\n";
        };
        polyline(walk, "black", 2.5);
        for (std::size_t k = 0; k < c.profiles.size(); ++k) {
            std::vector<double> f = profile_annulus_flux(c.profiles[k], e);
            for (std::size_t i = 0; i < f.size(); ++i) f[i] /= e[i + 1] - e[i];
            polyline(f, colours[k % 6], 1.2);
        }
        double ly = top + 14;
        out += "<text x=\"" + fmt("%g", x0 + w - 70) + "\" y=\"" + fmt("%g", ly) +
               "\">walk</text>\n";
        for (std::size_t k = 0; k < r.kinds.size(); ++k) {
            ly += 13;
            out += "<text x=\"" + fmt("%g", x0 + w - 70) + "\" y=\"" + fmt("%g", ly) +
                   "\" fill=\"" + colours[k % 6] + "\">" + profile_kind_name(r.kinds[k]) +
                   "</text>\n";
        }
    }
    out += "</svg>\n";
    return out;
}

} // namespace sss
