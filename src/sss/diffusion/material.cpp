// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#include "sss/diffusion/material.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sss/util/error.h"
#include "sss/util/messages.h"

namespace sss {

const std::vector<NamedMaterial>& material_table() {
    // Jensen et al. 2001 measured coefficients (mm^-1). Chicken sigma_a(red) is
    // 0.015 / 0.018 and marble's ior 1.5 (docs/algorithms.md explains why).
    static const std::vector<NamedMaterial> table = {
        {"apple", {2.29, 2.39, 1.97}, {0.0030, 0.0034, 0.046}, 1.3},
        {"chicken1", {0.15, 0.21, 0.38}, {0.015, 0.077, 0.19}, 1.3},
        {"chicken2", {0.19, 0.25, 0.32}, {0.018, 0.088, 0.20}, 1.3},
        {"cream", {7.38, 5.47, 3.15}, {0.0002, 0.0028, 0.0163}, 1.3},
        {"ketchup", {0.18, 0.07, 0.03}, {0.061, 0.97, 1.45}, 1.3},
        {"marble", {2.19, 2.62, 3.00}, {0.0021, 0.0041, 0.0071}, 1.5},
        {"potato", {0.68, 0.70, 0.55}, {0.0024, 0.0090, 0.12}, 1.3},
        {"skimmilk", {0.70, 1.22, 1.90}, {0.0014, 0.0025, 0.0142}, 1.3},
        {"skin1", {0.74, 0.88, 1.01}, {0.032, 0.17, 0.48}, 1.3},
        {"skin2", {1.09, 1.59, 1.79}, {0.013, 0.070, 0.145}, 1.3},
        {"spectralon", {11.6, 20.4, 14.9}, {0.0, 0.0, 0.0}, 1.3},
        {"wholemilk", {2.55, 3.21, 3.77}, {0.0011, 0.0024, 0.014}, 1.3},
    };
    return table;
}

const NamedMaterial* find_material(std::string_view name) {
    for (const NamedMaterial& m : material_table())
        if (name == m.name) return &m;
    return nullptr;
}

std::string material_names() {
    std::string out;
    for (const NamedMaterial& m : material_table()) {
        if (!out.empty()) out += ", ";
        out += m.name;
    }
    return out;
}

std::string unknown_material_message(const std::string& name) {
    std::vector<std::string> names;
    for (const NamedMaterial& m : material_table()) names.emplace_back(m.name);
    const std::string guess = closest_match(name, names);
    if (!guess.empty())
        return "unknown material '" + name + "'; did you mean '" + guess + "'?";
    return "unknown material '" + name + "' (known: " + material_names() + ")";
}

double fresnel_diffuse_reflectance(double eta) {
    if (eta >= 1.0) return -1.440 / (eta * eta) + 0.710 / eta + 0.668 + 0.0636 * eta;
    // Egan-Hilgeman fit for eta < 1.
    return -0.4399 + 0.7099 / eta - 0.3319 / (eta * eta) + 0.0636 / (eta * eta * eta);
}

namespace {

double boundary_a(double eta) {
    double f = fresnel_diffuse_reflectance(eta);
    return (1.0 + f) / (1.0 - f);
}

// Total reflectance as a function of s = sqrt(3(1 - alpha')); k = 4A/3.
double total_of_s(double s, double k) {
    return 0.5 * (1.0 - s * s / 3.0) * (std::exp(-s) + std::exp(-(1.0 + k) * s));
}

double total_of_s_derivative(double s, double k) {
    double e1 = std::exp(-s), e2 = std::exp(-(1.0 + k) * s);
    return 0.5 *
           (-(2.0 * s / 3.0) * (e1 + e2) - (1.0 - s * s / 3.0) * (e1 + (1.0 + k) * e2));
}

} // namespace

double classic_total_reflectance(double alpha_prime, double eta) {
    double s = std::sqrt(std::max(0.0, 3.0 * (1.0 - alpha_prime)));
    return total_of_s(s, 4.0 * boundary_a(eta) / 3.0);
}

double classic_s_from_albedo(double albedo, double eta) {
    if (!(albedo >= 0.0 && albedo < 1.0))
        throw ValueError("albedo " + std::to_string(albedo) + " is outside [0, 1)");
    const double k = 4.0 * boundary_a(eta) / 3.0;
    const double smax = std::sqrt(3.0);
    if (albedo == 0.0) return smax;
    // total_of_s falls monotonically from 1 at s = 0 to 0 at sqrt(3): Newton
    // steps kept inside a shrinking bisection bracket.
    double lo = 0.0, hi = smax;
    // Small-s expansion R ~ 1 - (1 + 2A/3) s as the first guess.
    double s = std::clamp((1.0 - albedo) / (1.0 + 0.5 * k), lo, hi);
    for (int it = 0; it < 100; ++it) {
        double g = total_of_s(s, k) - albedo;
        if (g > 0)
            lo = s;
        else
            hi = s;
        double dg = total_of_s_derivative(s, k);
        double next = s - g / dg;
        if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
        if (std::abs(next - s) <= 1e-15 * std::max(1e-300, s) || hi - lo < 1e-300) {
            s = next;
            break;
        }
        s = next;
    }
    return s;
}

AlbedoDmfp albedo_dmfp_from_coefficients(const ChannelCoefficients& c) {
    AlbedoDmfp out;
    double st = c.sigma_s_prime + c.sigma_a;
    if (!(st > 0.0)) return out;
    // s = sqrt(3 sigma_a / sigma_t') avoids forming 1 - alpha'.
    double s = std::sqrt(3.0 * c.sigma_a / st);
    double k = 4.0 * boundary_a(c.ior) / 3.0;
    out.albedo = 0.5 * (c.sigma_s_prime / st) * (std::exp(-s) + std::exp(-(1.0 + k) * s));
    double str = std::sqrt(3.0 * c.sigma_a * st);
    out.dmfp = str > 0.0 ? 1.0 / str : std::numeric_limits<double>::infinity();
    return out;
}

ChannelCoefficients coefficients_from_albedo_dmfp(double albedo, double dmfp,
                                                  double ior) {
    ChannelCoefficients c;
    c.ior = ior;
    double s = classic_s_from_albedo(albedo, ior);
    // sigma_t' = 1/(l_d s), sigma_a = s/(3 l_d): no subtraction near alpha' -> 1.
    double st = 1.0 / (dmfp * s);
    c.sigma_a = s / (3.0 * dmfp);
    // Albedo 0 is exactly no scattering (st - sigma_a leaves ~1e-17 here).
    c.sigma_s_prime = albedo == 0.0 ? 0.0 : st - c.sigma_a;
    return c;
}

MaterialValueError::MaterialValueError(std::string field, double value)
    : ValueError("impossible " + field + " value " + std::to_string(value)),
      m_field(std::move(field)), m_value(value) {}

MaterialFormError::MaterialFormError()
    : UsageError("the material is given both as scattering/absorption coefficients and "
                 "as albedo/diffuse mean free path; give one form") {}

void check_unitlength(double unitlength) {
    if (!(std::isfinite(unitlength) && unitlength > 0.0))
        throw MaterialValueError("unitlength", unitlength);
}

void MaterialSpec::validate() const {
    if (!find_material(preset)) throw UsageError(unknown_material_message(preset));
    if ((scattering || absorption) && uses_albedo_form()) throw MaterialFormError();
    auto check = [](const std::optional<glm::dvec3>& v, const char* what, bool positive,
                    double maxv) {
        if (!v) return;
        for (int i = 0; i < 3; ++i) {
            double x = (*v)[i];
            if (!std::isfinite(x) || x < 0.0 || (positive && x <= 0.0) || x > maxv)
                throw MaterialValueError(what, x);
        }
    };
    const double inf = std::numeric_limits<double>::infinity();
    check(scattering, "scattering", false, inf);
    check(absorption, "absorption", false, inf);
    check(albedo, "albedo", false, 1.0);
    check(dmfp, "diffusemeanfreepath", true, inf);
    if (ior && !(std::isfinite(*ior) && *ior > 0.0))
        throw MaterialValueError("ior", *ior);
    check_unitlength(unitlength);
}

double MaterialSpec::resolved_ior() const {
    if (ior) return *ior;
    return find_material(preset)->ior;
}

void MaterialSpec::resolve_coefficients(glm::dvec3& sigma_s_prime,
                                        glm::dvec3& sigma_a) const {
    const NamedMaterial* m = find_material(preset);
    sigma_s_prime = scattering ? *scattering : m->sigma_s_prime;
    sigma_a = absorption ? *absorption : m->sigma_a;
}

void MaterialSpec::resolve_albedo_dmfp(glm::dvec3& albedo_out,
                                       glm::dvec3& dmfp_mm_out) const {
    glm::dvec3 ss, sa;
    resolve_coefficients(ss, sa);
    for (int i = 0; i < 3; ++i) {
        AlbedoDmfp ad = albedo_dmfp_from_coefficients({ss[i], sa[i], resolved_ior()});
        albedo_out[i] = ad.albedo;
        dmfp_mm_out[i] = ad.dmfp;
    }
    if (albedo) albedo_out = *albedo;
    if (dmfp) dmfp_mm_out = *dmfp;
}

} // namespace sss
