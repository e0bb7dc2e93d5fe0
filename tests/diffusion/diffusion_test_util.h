// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
// Helpers shared by the diffusion unit tests (diffusion_test.cpp,
// stability_test.cpp).

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "sss/cloud/point_cloud.h"
#include "sss/cloud/synthetic.h"
#include "sss/diffusion/diffusion.h"
#include "sss/diffusion/material.h"
#include "sss/diffusion/profile.h"

namespace sss::test {

/// Unpolarised Fresnel reflectance seen from inside a medium of relative
/// index eta at cosine mu, written independently of the library (total
/// internal reflection past the critical angle).
inline double fresnel_inside(double mu, double eta) {
    double sin_t2 = eta * eta * (1.0 - mu * mu);
    if (sin_t2 >= 1.0) return 1.0;
    double ct = std::sqrt(1.0 - sin_t2);
    double rs = (eta * mu - ct) / (eta * mu + ct);
    double rp = (mu - eta * ct) / (mu + eta * ct);
    return 0.5 * (rs * rs + rp * rp);
}

/// The three channel profiles of a table material (Jensen 2001), lengths
/// scaled by `unitlength` (scene units per mm).
inline std::vector<Profile> material_profiles(const char* name, double unitlength = 1.0,
                                              ProfileKind kind = ProfileKind::Classic) {
    const NamedMaterial* m = find_material(name);
    if (!m) throw std::runtime_error(std::string("test needs material ") + name);
    std::vector<Profile> out;
    for (int ch = 0; ch < 3; ++ch)
        out.push_back(
            Profile::from_coefficients(kind, {m->sigma_s_prime[ch] / unitlength,
                                              m->sigma_a[ch] / unitlength, m->ior}));
    return out;
}

/// A DiffusionProblem from a cloud with `_area` and `_radiance_t`.
inline DiffusionProblem problem_from(const PointCloud& cloud,
                                     std::vector<Profile> profiles) {
    DiffusionProblem pb;
    pb.positions = cloud.positions;
    pb.normals = cloud.normals;
    const Channel* area = cloud.find_channel("_area");
    const Channel* rad = cloud.find_channel("_radiance_t");
    if (!area || !rad) throw std::runtime_error("cloud lacks _area or _radiance_t");
    pb.areas = area->data;
    pb.irradiance.resize(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i)
        pb.irradiance[i] = {rad->data[3 * i], rad->data[3 * i + 1], rad->data[3 * i + 2]};
    pb.profiles = std::move(profiles);
    return pb;
}

/// A synthetic lit cloud (ptsynth's shapes): thickness 2 for boxes, light
/// from (1, 0.5, 2).
inline PointCloud synthetic(SyntheticShape shape, std::size_t n, double size,
                            double ambient = 0.0) {
    SyntheticParams sp;
    sp.shape = shape;
    sp.count = n;
    sp.size = size;
    sp.thickness = 2.0;
    sp.light_dir = {1, 0.5, 2};
    sp.ambient = ambient;
    return make_synthetic_cloud(sp);
}

} // namespace sss::test
