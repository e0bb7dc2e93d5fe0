// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#include "ssdiffusion_volume.h"

#include <cmath>

#include <glm/geometric.hpp>

#include "sss/cloud/point_cloud_io.h"
#include "sss/diffusion/profile.h"
#include "sss/util/error.h"
#include "sss/util/limits.h"
#include "sss/util/math.h"

namespace sss::diffusion_detail {

namespace {

bool volume_on(const SsDiffusionOptions& o) {
    return o.volume || !o.blockers.empty();
}

// The constant material's coefficients in mm^-1. Albedo and dmfp mean the
// medium the classic dipole infers from them, as for the Monte-Carlo
// reference, whatever the profile.
void coefficients_mm(const MaterialSpec& m, ChannelCoefficients (&out)[3]) {
    const double ior = m.resolved_ior();
    if (m.uses_albedo_form()) {
        glm::dvec3 albedo, dmfp;
        m.resolve_albedo_dmfp(albedo, dmfp);
        for (int c = 0; c < 3; ++c)
            out[c] = coefficients_from_albedo_dmfp(std::min(albedo[c], 0.999999), dmfp[c],
                                                   ior);
    } else {
        glm::dvec3 ss, sa;
        m.resolve_coefficients(ss, sa);
        for (int c = 0; c < 3; ++c) out[c] = {ss[c], sa[c], ior};
    }
}

// A blocker cloud's points in mm: positions, outward normals, areas (the
// area channel, else pi r^2).
SurfaceSamples read_blocker(const std::string& path, const SsDiffusionOptions& o) {
    const PointCloud cloud = read_point_cloud(path);
    if (cloud.size() == 0)
        throw ValueError("blocker " + path + ": the cloud has no points");
    const double to_mm = 1.0 / o.material.unitlength;
    const Channel* area = cloud.find_channel(o.area_channel);
    if (area && area->components() != 1) area = nullptr;
    SurfaceSamples s;
    const std::size_t n = cloud.size();
    s.positions.resize(n);
    s.normals = cloud.normals;
    s.areas.resize(n);
    for (std::size_t j = 0; j < n; ++j) {
        const glm::vec3& p = cloud.positions[j];
        const glm::vec3& nr = cloud.normals[j];
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) ||
            !std::isfinite(nr.x) || !std::isfinite(nr.y) || !std::isfinite(nr.z) ||
            glm::dot(nr, nr) == 0.0f)
            throw ValueError("blocker " + path + ": point " + std::to_string(j) +
                             " has no finite position or normal");
        s.positions[j] = glm::vec3(glm::dvec3(p) * to_mm);
        const double a = area ? double(area->data[j])
                              : kPi * double(cloud.radii[j]) * double(cloud.radii[j]);
        if (!(a >= 0.0) || !std::isfinite(a))
            throw ValueError("blocker " + path + ": negative or invalid area at point " +
                             std::to_string(j));
        s.areas[j] = float(a * to_mm * to_mm);
    }
    return s;
}

} // namespace

VolumeInput volume_input(const DiffusionProblem& pb, const SsDiffusionOptions& o) {
    VolumeInput in;
    if (!volume_on(o)) return in;
    in.surface.positions = pb.positions;
    in.surface.normals = pb.normals;
    in.surface.areas = pb.areas;
    in.irradiance = pb.irradiance;
    return in;
}

void check_volume_options(const SsDiffusionOptions& o) {
    if (!volume_on(o) && o.volume_options.diffuse_light)
        throw UsageError("-incidence applies to the volume diffusion: add -volume 1");
    if (!volume_on(o)) return;
    if (o.material.albedo_from_file || o.material.dmfp_from_file)
        throw ValueError(
            "-volume needs one material for the whole cloud (fromfile is not "
            "supported with the volume diffusion)");
    ChannelCoefficients c[3];
    coefficients_mm(o.material, c);
    for (int k = 0; k < 3; ++k)
        if (!(c[k].sigma_s_prime > 0))
            throw ValueError("-volume needs a scattering medium (sigma_s' > 0 in every "
                             "channel)");
    // The blockers' headers now, so that a missing or broken file stops the
    // job before the diffusion, not after it.
    for (const std::string& path : o.blockers) {
        const PointCloudReader reader(path);
        if (reader.size() == 0)
            throw ValueError("blocker " + path + ": the cloud has no points");
    }
}

void apply_volume(const SsDiffusionOptions& o, VolumeInput&& in,
                  std::vector<glm::vec3>& result, SsDiffusionReport& rep) {
    if (!volume_on(o)) return;
    ScopedStage stage("solving the diffusion in the volume");
    ChannelCoefficients c[3];
    coefficients_mm(o.material, c);
    std::vector<SurfaceSamples> blockers;
    for (const std::string& path : o.blockers) blockers.push_back(read_blocker(path, o));
    const VolumeOptions& vo = o.volume_options;
    rep.volume = VolumeReport{};
    // The profile's half-space reflectance: the albedo itself when the
    // material is given so (each profile inverts its own), else the profile's.
    glm::dvec3 reflectance(0.0);
    if (o.material.uses_albedo_form()) {
        glm::dvec3 albedo, dmfp;
        o.material.resolve_albedo_dmfp(albedo, dmfp);
        reflectance = albedo;
    } else {
        for (int k = 0; k < 3; ++k)
            reflectance[k] = Profile::from_coefficients(o.profile, c[k]).total();
    }
    result = volume_diffusion(in.surface, in.irradiance, c, reflectance, blockers, result,
                              vo, &rep.volume);
    for (const std::string& w : rep.volume.warnings)
        rep.warnings.push_back("volume: " + w);
    in = VolumeInput{};
}

} // namespace sss::diffusion_detail
