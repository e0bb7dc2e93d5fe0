// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file material.h
/// Subsurface materials: Jensen et al. 2001 measured table, the three
/// PRMan-equivalent ways of giving a material, and unit handling.
///
/// Conventions (see docs/algorithms.md): sigma_s' and sigma_a are in mm^-1,
/// dmfp in mm; a scene length = mm length x unitlength, so a coefficient in
/// scene units^-1 = its mm^-1 value / unitlength.

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <glm/vec3.hpp>

#include "sss/util/error.h"

namespace sss {

/// One entry of the measured-material table.
struct NamedMaterial {
    const char* name;
    glm::dvec3 sigma_s_prime; ///< reduced scattering, mm^-1
    glm::dvec3 sigma_a;       ///< absorption, mm^-1
    double ior;               ///< relative index of refraction
};

/// The 12 Jensen 2001 materials, in alphabetical order as PRMan lists them.
const std::vector<NamedMaterial>& material_table();
/// Material by (case-sensitive) name, or nullptr.
const NamedMaterial* find_material(std::string_view name);
/// "apple, chicken1, ..." for error messages and --help.
std::string material_names();
/// The message for a material name not in the table: "unknown material
/// 'skin11'; did you mean 'skin1'?" when a name is close (closest_match in
/// sss/util/messages.h), else "unknown material 'x' (known: apple, ...)".
std::string unknown_material_message(const std::string& name);

/// JMLH01 fit of the internal diffuse Fresnel reflectance F_dr(eta), with the
/// Egan-Hilgeman fit below eta = 1.
double fresnel_diffuse_reflectance(double eta);

/// Total diffuse reflectance of the classic dipole for reduced albedo alpha'.
double classic_total_reflectance(double alpha_prime, double eta);

/// Classic dipole inversion solved in s = sqrt(3(1 - alpha')) in double
/// precision: returns s such that classic_total_reflectance = albedo.
/// albedo must be in [0, 1).
double classic_s_from_albedo(double albedo, double eta);

/// One channel's physical coefficients in scene units.
struct ChannelCoefficients {
    double sigma_s_prime = 0; ///< scene units^-1
    double sigma_a = 0;       ///< scene units^-1
    double ior = 1.3;
};

/// Classic-dipole albedo (total diffuse reflectance) and dmfp = 1/sigma_tr
/// (infinite when sigma_a = 0) of coefficients.
struct AlbedoDmfp {
    double albedo = 0;
    double dmfp = 0;
};
AlbedoDmfp albedo_dmfp_from_coefficients(const ChannelCoefficients& c);
/// The classic inversion: coefficients whose classic albedo and dmfp are the
/// given ones (lengths in whatever unit dmfp is in).
ChannelCoefficients coefficients_from_albedo_dmfp(double albedo, double dmfp, double ior);

/// An impossible material value (negative or NaN coefficient, albedo above 1,
/// non-positive mean free path, ior or unitlength). field() is the setting's
/// PRMan name ("scattering", "absorption", "albedo", "diffusemeanfreepath",
/// "ior", "unitlength"), so a command line can name its option.
class MaterialValueError : public ValueError {
public:
    MaterialValueError(std::string field, double value);
    const std::string& field() const { return m_field; }
    double value() const { return m_value; }

private:
    std::string m_field;
    double m_value;
};

/// A material given both as scattering/absorption coefficients and as
/// albedo/diffuse mean free path. A UsageError: the caller must pick one form.
class MaterialFormError : public UsageError {
public:
    MaterialFormError();
};

/// MaterialValueError unless unitlength (the scene length of one mm) is finite
/// and > 0. The one check of it, for materials and for bakes.
void check_unitlength(double unitlength);

/// How the user gave the material: what ptfilter's options fill in.
/// Starts as the named preset (default marble); -scattering/-absorption or
/// -albedo/-diffusemeanfreepath replace parts of it.
struct MaterialSpec {
    std::string preset = "marble";
    std::optional<glm::dvec3> scattering; ///< sigma_s', mm^-1
    std::optional<glm::dvec3> absorption; ///< sigma_a, mm^-1
    std::optional<glm::dvec3> albedo;     ///< total diffuse reflectance
    std::optional<glm::dvec3> dmfp;       ///< diffuse mean free path, mm
    bool albedo_from_file = false;        ///< per-point _albedo channel
    bool dmfp_from_file = false;          ///< per-point _diffusemeanfreepath channel
    std::optional<double> ior;            ///< default: the preset's
    double unitlength = 1.0;              ///< scene length of one mm

    /// True when the material is given as albedo + dmfp (either part).
    bool uses_albedo_form() const {
        return albedo || dmfp || albedo_from_file || dmfp_from_file;
    }
    /// Checks consistency and values: UsageError for an unknown preset,
    /// MaterialFormError, MaterialValueError.
    void validate() const;
    /// Resolved ior.
    double resolved_ior() const;
    /// Albedo and dmfp (mm) in effect for the constant parts of the material.
    void resolve_albedo_dmfp(glm::dvec3& albedo_out, glm::dvec3& dmfp_mm_out) const;
    /// Coefficients (mm^-1) in effect when the coefficient form is used.
    void resolve_coefficients(glm::dvec3& sigma_s_prime, glm::dvec3& sigma_a) const;
};

} // namespace sss
