// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#include "sss/diffusion/profile.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <optional>

#include "sss/util/error.h"
#include "sss/util/math.h"
#include "sss/util/name_table.h"

#include "beam_diffusion.h"
#include "fresnel.h"
#include "mc_table.h"
#include "radial_curve.h"

namespace sss {

using diffusion_detail::fresnel_moments;
using diffusion_detail::FresnelMoments;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// (exp(-sigma a) - exp(-sigma b)) / sigma for b >= a, given delta = b - a
// computed without cancellation; the sigma -> 0 limit is delta.
double exp_diff_over_sigma(double sigma, double a, double delta) {
    if (sigma == 0.0) return delta;
    if (delta == kInf) return std::exp(-sigma * a) / sigma;
    return std::exp(-sigma * a) * (-std::expm1(-sigma * delta)) / sigma;
}

// e^{-sigma d0}/d0 - e^{-sigma d}/d for d >= d0 > 0, d - d0 = delta.
double exp_over_d_diff(double sigma, double d0, double d, double delta) {
    if (d == kInf) return std::exp(-sigma * d0) / d0;
    // = e^{-s d0} [ 1/d0 - e^{-s delta}/d ] = e^{-s d0} [ delta/(d0 d) + (1 - e^{-s
    // delta})/d ]
    return std::exp(-sigma * d0) * (delta / (d0 * d) - std::expm1(-sigma * delta) / d);
}

double burley_shape(double albedo) {
    double t = albedo - 0.33;
    return 3.5 + 100.0 * t * t * t * t;
}

// The first name of a kind is the one written; the others are accepted aliases.
constexpr NameTable<ProfileKind, 10> kProfileKindNames({{
    {ProfileKind::Classic, "classic"},
    {ProfileKind::Classic, "dipole"},
    {ProfileKind::Better, "better"},
    {ProfileKind::Better, "betterdipole"},
    {ProfileKind::Burley, "burley"},
    {ProfileKind::Burley, "normalized"},
    {ProfileKind::Pbd, "pbd"},
    {ProfileKind::Pbd, "beam"},
    {ProfileKind::Mc, "mc"},
    {ProfileKind::Mc, "montecarlo"},
}});

bool is_curve(ProfileKind kind) {
    return kind == ProfileKind::Pbd || kind == ProfileKind::Mc;
}

// The curve of a sampled profile for reduced albedo alpha in (0, 1].
std::shared_ptr<const RadialCurve> curve_of(ProfileKind kind, double alpha, double eta) {
    using namespace diffusion_detail;
    if (kind == ProfileKind::Mc) {
        check_mc_range(eta);
        return cached_curve(1, mc_curve_value, alpha, eta);
    }
    return cached_curve(0, beam_curve_value, alpha, eta);
}

// Reduced albedo whose curve's total reflectance is `albedo` (sigma_t' = 1):
// regula falsi (Illinois) in u = sqrt(1 - alpha'), where the total is
// smooth and falls monotonically.
double curve_alpha_for_total(ProfileKind kind, double albedo, double eta) {
    auto total_of_u = [&](double u) {
        double alpha = 1.0 - u * u;
        return alpha <= 0.0 ? 0.0 : 2.0 * kPi * curve_of(kind, alpha, eta)->total();
    };
    double lo = 1e-4, hi = 1.0; // u
    double flo = total_of_u(lo) - albedo, fhi = -albedo;
    if (flo <= 0.0) return 1.0 - lo * lo;
    int side = 0;
    for (int it = 0; it < 60 && hi - lo > 1e-12; ++it) {
        double u = (lo * fhi - hi * flo) / (fhi - flo);
        if (!(u > lo && u < hi)) u = 0.5 * (lo + hi);
        double f = total_of_u(u) - albedo;
        if (std::abs(f) < 1e-10) return 1.0 - u * u;
        if (f > 0.0) {
            lo = u, flo = f;
            if (side == 1) fhi *= 0.5;
            side = 1;
        } else {
            hi = u, fhi = f;
            if (side == -1) flo *= 0.5;
            side = -1;
        }
    }
    double u = 0.5 * (lo + hi);
    return 1.0 - u * u;
}

} // namespace

bool parse_profile_kind(std::string_view name, ProfileKind& out) {
    std::optional<ProfileKind> kind = kProfileKindNames.parse(name);
    if (kind) out = *kind;
    return kind.has_value();
}

const char* profile_kind_name(ProfileKind kind) {
    return kProfileKindNames.name(kind);
}

Profile Profile::from_coefficients(ProfileKind kind, const ChannelCoefficients& c) {
    if (!(c.sigma_s_prime >= 0.0 && c.sigma_a >= 0.0 && std::isfinite(c.sigma_s_prime) &&
          std::isfinite(c.sigma_a)))
        throw ValueError("impossible scattering/absorption coefficients");
    if (!(c.ior > 0.0 && std::isfinite(c.ior))) throw ValueError("impossible ior");
    if (kind == ProfileKind::Burley) {
        AlbedoDmfp ad = albedo_dmfp_from_coefficients(c);
        return from_albedo_dmfp(kind, ad.albedo, ad.dmfp, c.ior);
    }
    Profile p;
    p.m_kind = kind;
    p.m_ior = c.ior;
    double st = c.sigma_s_prime + c.sigma_a;
    if (is_curve(kind)) {
        if (kind == ProfileKind::Mc) diffusion_detail::check_mc_range(c.ior);
        if (!(st > 0.0) || c.sigma_s_prime == 0.0) {
            p.m_dmfp = 0.0;
            return p;
        }
        p.m_sigma_t = st;
        p.m_alpha = c.sigma_s_prime / st;
        p.m_curve = curve_of(kind, p.m_alpha, c.ior);
        p.m_sigma_tr = diffusion_detail::grosjean_sigma_tr(p.m_alpha) * st;
        p.m_dmfp = p.m_sigma_tr > 0.0 ? 1.0 / p.m_sigma_tr : kInf;
        p.m_scale = 1.0;
        p.m_core = 0.0;
        p.m_total = 2.0 * kPi * p.m_curve->total();
        return p;
    }
    if (!(st > 0.0) || c.sigma_s_prime == 0.0) {
        // No scattering: nothing comes back out. Keep lengths finite.
        p.m_zr = p.m_core = 1.0;
        p.m_zv = kind == ProfileKind::Classic ? 1.0 : -1.0;
        p.m_dmfp = 0.0;
        return p;
    }
    p.m_sigma_t = st;
    p.m_alpha = c.sigma_s_prime / st;
    p.m_zr = 1.0 / st;
    p.m_core = p.m_zr;
    if (kind == ProfileKind::Classic) {
        double f = fresnel_diffuse_reflectance(c.ior);
        double a = (1.0 + f) / (1.0 - f);
        p.m_sigma_tr = std::sqrt(3.0 * c.sigma_a * st);
        p.m_zv = p.m_zr * (1.0 + 4.0 * a / 3.0);
        p.m_scale = p.m_alpha / (4.0 * kPi);
    } else {
        FresnelMoments fm = fresnel_moments(c.ior);
        double a = (1.0 + fm.three_c2) / (1.0 - fm.two_c1);
        p.m_D = (2.0 * c.sigma_a + c.sigma_s_prime) / (3.0 * st * st);
        p.m_sigma_tr = std::sqrt(c.sigma_a / p.m_D);
        p.m_zv = -p.m_zr - 4.0 * a * p.m_D;
        p.m_cphi = 0.25 * (1.0 - fm.two_c1);
        p.m_ce = 0.5 * (1.0 - fm.three_c2);
        p.m_scale = p.m_alpha * p.m_alpha / (4.0 * kPi);
    }
    p.m_dmfp = p.m_sigma_tr > 0.0 ? 1.0 / p.m_sigma_tr : kInf;
    p.m_total = 0.0;
    p.m_total = p.disk(kInf);
    return p;
}

Profile Profile::from_albedo_dmfp(ProfileKind kind, double albedo, double dmfp,
                                  double ior) {
    // Burley's normalized profile is fine at albedo 1 (spectralon); the dipoles
    // need alpha' < 1.
    const double albedo_max =
        kind == ProfileKind::Burley ? 1.0 : std::nextafter(1.0, 0.0);
    if (!(albedo >= 0.0 && albedo <= albedo_max))
        throw ValueError("albedo " + std::to_string(albedo) + " is outside [0, 1)");
    if (!(dmfp > 0.0)) throw ValueError("diffuse mean free path must be positive");
    if (!(ior > 0.0 && std::isfinite(ior))) throw ValueError("impossible ior");
    switch (kind) {
    case ProfileKind::Classic:
        return from_coefficients(kind, coefficients_from_albedo_dmfp(albedo, dmfp, ior));
    case ProfileKind::Better: {
        if (albedo == 0.0) return from_coefficients(kind, {0.0, 1.0 / dmfp, ior});
        // Invert this profile's own total reflectance in u = sqrt(1 - alpha')
        // with sigma_t' = 1 (the total does not depend on the length scale).
        auto total_of_u = [&](double u) {
            double alpha = 1.0 - u * u;
            return from_coefficients(kind, {alpha, u * u, ior}).total();
        };
        double lo = 0.0, hi = 1.0; // total falls with u
        for (int it = 0; it < 200 && hi - lo > 1e-16; ++it) {
            double mid = 0.5 * (lo + hi);
            if (total_of_u(mid) > albedo)
                lo = mid;
            else
                hi = mid;
        }
        double u = 0.5 * (lo + hi);
        double sa1 = u * u, ss1 = 1.0 - u * u; // sigma_t' = 1 units
        double d1 = (2.0 * sa1 + ss1) / 3.0;
        double str1 = std::sqrt(sa1 / d1); // sigma_tr in units of sigma_t'
        double st = str1 > 0.0 ? 1.0 / (dmfp * str1) : kInf;
        if (!std::isfinite(st)) throw ValueError("albedo too close to 1");
        return from_coefficients(kind, {ss1 * st, sa1 * st, ior});
    }
    case ProfileKind::Pbd:
    case ProfileKind::Mc: {
        if (kind == ProfileKind::Mc) diffusion_detail::check_mc_range(ior);
        if (albedo == 0.0) return from_coefficients(kind, {0.0, 1.0 / dmfp, ior});
        double alpha = curve_alpha_for_total(kind, albedo, ior);
        double st = 1.0 / (dmfp * diffusion_detail::grosjean_sigma_tr(alpha));
        if (!std::isfinite(st)) throw ValueError("albedo too close to 1");
        return from_coefficients(kind, {alpha * st, (1.0 - alpha) * st, ior});
    }
    case ProfileKind::Burley: {
        Profile p;
        p.m_kind = kind;
        p.m_ior = ior;
        p.m_scale = albedo;
        p.m_total = albedo;
        p.m_dmfp = dmfp;
        // A spectralon-like infinite dmfp spreads the light to infinity.
        p.m_d = std::min(dmfp, 1e30) / burley_shape(albedo);
        p.m_sigma_tr = 1.0 / (3.0 * p.m_d);
        p.m_core = 0.0;
        p.m_alpha = albedo;
        return p;
    }
    }
    throw ValueError("unknown profile");
}

double Profile::eval(double r) const {
    if (m_scale == 0.0) return 0.0;
    switch (m_kind) {
    case ProfileKind::Classic: {
        double r2 = r * r;
        double dr = std::sqrt(r2 + m_zr * m_zr), dv = std::sqrt(r2 + m_zv * m_zv);
        double s = m_sigma_tr;
        return m_scale * (m_zr * (1.0 + s * dr) * std::exp(-s * dr) / (dr * dr * dr) +
                          m_zv * (1.0 + s * dv) * std::exp(-s * dv) / (dv * dv * dv));
    }
    case ProfileKind::Better: {
        double r2 = r * r;
        double dr = std::sqrt(r2 + m_zr * m_zr), dv = std::sqrt(r2 + m_zv * m_zv);
        double s = m_sigma_tr;
        double real = (m_ce * m_zr * (1.0 + s * dr) / (dr * dr)) * std::exp(-s * dr) / dr;
        double virt = (m_ce * m_zv * (1.0 + s * dv) / (dv * dv)) * std::exp(-s * dv) / dv;
        // Fluence terms: C_phi/D (e^{-s dr}/dr - e^{-s dv}/dv), a true
        // difference: computed from dv - dr without cancellation.
        double delta = (m_zv * m_zv - m_zr * m_zr) / (dv + dr);
        double fluence = exp_over_d_diff(s, dr, dv, delta);
        return m_scale * (real - virt + m_cphi / m_D * fluence);
    }
    case ProfileKind::Pbd:
    case ProfileKind::Mc: {
        if (r <= 0.0) return kInf;
        double rho = r * m_sigma_t;
        return m_sigma_t * m_sigma_t * m_curve->value(rho) / rho;
    }
    case ProfileKind::Burley: {
        if (r <= 0.0) return kInf;
        return m_scale * (std::exp(-r / m_d) + std::exp(-r / (3.0 * m_d))) /
               (8.0 * kPi * m_d * r);
    }
    }
    return 0.0;
}

double Profile::disk(double rho) const {
    if (m_scale == 0.0 || !(rho > 0.0)) return 0.0;
    switch (m_kind) {
    case ProfileKind::Classic: {
        // (alpha'/2) sum_z [e^{-s z} - z e^{-s d}/d] = (alpha'/2) sum_z z I(z).
        double s = m_sigma_tr, total = 0.0;
        for (double z : {m_zr, m_zv}) {
            double d = rho == kInf ? kInf : std::sqrt(rho * rho + z * z);
            double delta = rho == kInf ? kInf : rho * rho / (d + z);
            total += z * exp_over_d_diff(s, z, d, delta);
        }
        return 2.0 * kPi * m_scale * total;
    }
    case ProfileKind::Better: {
        double s = m_sigma_tr;
        double zr = m_zr, zv = std::abs(m_zv);
        double dr = rho == kInf ? kInf : std::sqrt(rho * rho + zr * zr);
        double dv = rho == kInf ? kInf : std::sqrt(rho * rho + zv * zv);
        double er = rho == kInf ? kInf : rho * rho / (dr + zr);
        double ev = rho == kInf ? kInf : rho * rho / (dv + zv);
        // C_E terms: z * (e^{-s|z|}/|z| - e^{-s d}/d); the virtual one is subtracted with
        // z < 0.
        double ce = m_ce * (zr * exp_over_d_diff(s, zr, dr, er) +
                            zv * exp_over_d_diff(s, zv, dv, ev));
        // Fluence terms: [ (e^{-s zr} - e^{-s dr}) - (e^{-s zv} - e^{-s dv}) ] / s
        //              = [ (e^{-s zr} - e^{-s zv}) - (e^{-s dr} - e^{-s dv}) ] / s.
        // The first form for small disks (each bracket ~ rho^2; the second
        // cancels to ~1e-16 absolute, which dominated, and could turn negative,
        // for tiny areas), the second for large ones (no growing brackets).
        double fluence;
        if (rho < zr) {
            fluence = exp_diff_over_sigma(s, zr, er) - exp_diff_over_sigma(s, zv, ev);
        } else {
            double near = exp_diff_over_sigma(s, zr, zv - zr);
            double far = 0.0;
            if (rho != kInf)
                far = exp_diff_over_sigma(s, dr, (zv * zv - zr * zr) / (dv + dr));
            fluence = near - far;
        }
        double phi = m_cphi / m_D * fluence;
        return 2.0 * kPi * m_scale * (ce + phi);
    }
    case ProfileKind::Pbd:
    case ProfileKind::Mc:
        return 2.0 * kPi * m_curve->integral(rho == kInf ? kInf : rho * m_sigma_t);
    case ProfileKind::Burley: {
        if (rho == kInf) return m_scale;
        return m_scale *
               -(0.25 * std::expm1(-rho / m_d) + 0.75 * std::expm1(-rho / (3.0 * m_d)));
    }
    }
    return 0.0;
}

double Profile::cutoff_radius(double fraction) const {
    if (m_total <= 0.0) return 0.0;
    double target = fraction * m_total;
    double lo = 0.0, hi = std::max(m_core, 1e-12);
    while (m_total - disk(hi) > target && hi < 1e300) hi *= 2.0;
    for (int it = 0; it < 200 && hi - lo > 1e-12 * hi; ++it) {
        double mid = 0.5 * (lo + hi);
        if (m_total - disk(mid) > target)
            lo = mid;
        else
            hi = mid;
    }
    return hi;
}

} // namespace sss
