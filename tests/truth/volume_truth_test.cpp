// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file volume_truth_test.cpp
/// The volume diffusion (ptfilter -volume 1) against the project's random
/// walk in the same geometry: a 2 mm marble slab lit on top, where the
/// surface profiles give 1.2-1.3x the reflected light, and a 5 mm skin1 slab
/// lit straight on, through which a diffusion alone carries half the blue
/// light it should (and 1.4x under diffuse light); the walk counts the
/// scattered light only, what a diffusion model describes.

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include <glm/geometric.hpp>

#include "sss/diffusion/material.h"
#include "sss/diffusion/profile.h"
#include "sss/diffusion/volume.h"
#include "sss/truth/mesh_walk.h"

namespace {

using namespace sss;

void add_face(MeshWalkSource& s, glm::vec3 corner, glm::vec3 eu, glm::vec3 ev, int nu,
              int nv, float e) {
    const glm::vec3 n = glm::cross(eu, ev);
    const float area = glm::length(n) / float(nu * nv);
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
            s.positions.push_back(corner + (float(i) + 0.5f) / float(nu) * eu +
                                  (float(j) + 0.5f) / float(nv) * ev);
            s.normals.push_back(glm::normalize(n));
            s.areas.push_back(area);
            s.irradiance.push_back(glm::vec3(e));
        }
}

TriangleMesh box_mesh(glm::vec3 lo, glm::vec3 hi) {
    TriangleMesh m;
    for (int k = 0; k < 8; ++k)
        m.vertices.push_back(
            {k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z});
    m.triangles = {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                   2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
    return m;
}

void check_slab(const char* material, float d, ProfileKind kind, bool diffuse) {
    const float w = 20.0f, s = 0.4f;
    const int n = int(w / s), nd = int(d / s);
    MeshWalkSource src;
    const glm::vec3 lo(-w / 2, -w / 2, -d), hi(w / 2, w / 2, 0.0f);
    const glm::vec3 X(w, 0, 0), Y(0, w, 0), Z(0, 0, d);
    add_face(src, {lo.x, lo.y, hi.z}, X, Y, n, n, 1.0f);
    add_face(src, lo, Y, X, n, n, 0.0f);
    add_face(src, lo, X, Z, n, nd, 0.0f);
    add_face(src, {lo.x, hi.y, lo.z}, Z, X, nd, n, 0.0f);
    add_face(src, lo, Z, Y, nd, n, 0.0f);
    add_face(src, {hi.x, lo.y, lo.z}, Y, Z, n, nd, 0.0f);

    const NamedMaterial* m = find_material(material);
    MeshWalkOptions wo;
    wo.medium = {box_mesh(lo, hi)};
    wo.sigma_s_prime = m->sigma_s_prime;
    wo.sigma_a = m->sigma_a;
    wo.eta = m->ior;
    wo.photons = 300'000;
    wo.batches = 16;
    wo.scattered_only = true;
    wo.normal_incidence = !diffuse;
    const MeshWalkResult truth = walk_mesh(wo, src);

    SurfaceSamples surface{src.positions, src.normals, src.areas};
    ChannelCoefficients ch[3];
    glm::dvec3 reflectance;
    for (int k = 0; k < 3; ++k) {
        ch[k] = {m->sigma_s_prime[k], m->sigma_a[k], m->ior};
        reflectance[k] = Profile::from_coefficients(kind, ch[k]).total();
    }
    const std::vector<glm::vec3> zero(src.positions.size(), glm::vec3(0.0f));
    VolumeReport rep;
    VolumeOptions vo;
    vo.diffuse_light = diffuse;
    const std::vector<glm::vec3> vol =
        volume_diffusion(surface, src.irradiance, ch, reflectance, {}, zero, vo, &rep);
    ASSERT_EQ(rep.thin_points, src.positions.size());

    // The middle of the lit face (R) and of the back face (T).
    for (float z : {0.0f, -d}) {
        glm::dvec3 a(0.0), t(0.0);
        for (std::size_t j = 0; j < src.positions.size(); ++j) {
            const glm::vec3& p = src.positions[j];
            if (std::abs(p.z - z) > 1e-4f || std::abs(p.x) > 4.0f || std::abs(p.y) > 4.0f)
                continue;
            a += glm::dvec3(vol[j]);
            t += truth.exitance[j];
        }
        for (int c = 0; c < 3; ++c) {
            SCOPED_TRACE(testing::Message()
                         << material << " " << d << " mm, z " << z << " channel " << c
                         << (diffuse ? " diffuse" : " normal"));
            EXPECT_NEAR(a[c] / t[c], 1.0, 0.10);
        }
    }
    // The light out never exceeds what went in (the walk's scattered part).
    for (int c = 0; c < 3; ++c) EXPECT_LE(rep.flux_out[c], truth.flux_in[c]);
}

TEST(VolumeTruth, SlabReflectanceAndTransmittanceMatchTheWalk) {
    check_slab("marble", 2.0f, ProfileKind::Pbd, true);
}

TEST(VolumeTruth, AnAbsorbingSlabTransmitsWhatTransportTheorySays) {
    check_slab("skin1", 5.0f, ProfileKind::Mc, false);
    check_slab("skin1", 5.0f, ProfileKind::Mc, true);
}

} // namespace
