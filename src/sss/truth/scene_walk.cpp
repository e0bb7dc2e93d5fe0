// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// The walk in a scene's own geometry, lit by a baked cloud.

#include "sss/truth/scene_walk.h"

#include <algorithm>
#include <cmath>
#include <set>

#include "sss/dice/dice.h"
#include "sss/scene/rib.h"
#include "sss/util/error.h"
#include "sss/util/math.h"

namespace sss {

namespace {

const Channel& color_channel(const PointCloud& c, const std::string& name) {
    const Channel* ch = c.find_channel(name);
    if (!ch) throw ValueError("the cloud has no channel '" + name + "'");
    if (ch->components() != 3)
        throw ValueError("channel '" + name + "' is " + channel_type_name(ch->type) +
                         ", expected color");
    return *ch;
}

/// The medium's coefficients per scene unit.
void coefficients(const MaterialSpec& m, glm::dvec3& ss, glm::dvec3& sa) {
    m.validate();
    if (m.albedo_from_file || m.dmfp_from_file)
        throw ValueError(
            "the walk needs one medium: per-point materials (fromfile) are not "
            "supported");
    if (m.uses_albedo_form()) {
        glm::dvec3 albedo, dmfp;
        m.resolve_albedo_dmfp(albedo, dmfp);
        for (int ch = 0; ch < 3; ++ch) {
            const ChannelCoefficients c =
                coefficients_from_albedo_dmfp(albedo[ch], dmfp[ch], m.resolved_ior());
            ss[ch] = c.sigma_s_prime;
            sa[ch] = c.sigma_a;
        }
    } else {
        m.resolve_coefficients(ss, sa);
    }
    ss /= m.unitlength;
    sa /= m.unitlength;
}

} // namespace

std::vector<float> cloud_areas(const PointCloud& cloud, const std::string& area_channel) {
    std::vector<float> a(cloud.size());
    const Channel* ch = cloud.find_channel(area_channel);
    if (ch && ch->components() != 1)
        throw ValueError("channel '" + area_channel + "' is " +
                         channel_type_name(ch->type) + ", expected float");
    for (std::size_t i = 0; i < cloud.size(); ++i)
        a[i] = ch ? ch->data[i] : float(kPi) * cloud.radii[i] * cloud.radii[i];
    return a;
}

PointCloud walk_scene(const SceneWalkOptions& o, const PointCloud& baked,
                      SceneWalkReport* report) {
    SceneWalkReport local;
    SceneWalkReport& rep = report ? *report : local;
    MeshWalkOptions w;
    coefficients(o.material, w.sigma_s_prime, w.sigma_a);
    w.eta = o.material.resolved_ior();
    w.photons = o.photons;
    w.seed = o.seed;
    w.normal_incidence = o.normal_incidence;
    w.scattered_only = o.scattered_only;
    w.batches = o.batches;

    MeshWalkSource src;
    src.positions = baked.positions;
    src.normals = baked.normals;
    src.areas = cloud_areas(baked, o.area_channel);
    if (!baked.find_channel(o.area_channel))
        rep.warnings.push_back("no '" + o.area_channel +
                               "' channel: using pi * radius^2 as each point's area");
    const Channel& e = color_channel(baked, o.radiance_channel);
    src.irradiance.resize(baked.size());
    for (std::size_t i = 0; i < baked.size(); ++i)
        src.irradiance[i] = {e.data[3 * i], e.data[3 * i + 1], e.data[3 * i + 2]};

    const Scene scene = read_rib(o.scene);
    // The shape only: dice every object to one edge length.
    glm::dvec3 lo(1e300), hi(-1e300);
    for (const glm::vec3& p : baked.positions) {
        lo = glm::min(lo, glm::dvec3(p));
        hi = glm::max(hi, glm::dvec3(p));
    }
    double diagonal = baked.size() ? glm::length(hi - lo) : 0.0;
    rep.spacing = o.spacing > 0.0 ? o.spacing : std::max(diagonal, 1e-6) / 500.0;
    std::vector<DiceRequest> requests;
    for (std::size_t i = 0; i < scene.primitives.size(); ++i) {
        DiceControl control;
        control.spacing = rep.spacing;
        requests.push_back({i, control, {}});
    }
    const std::vector<DicedSurface> diced = dice_all(scene, requests);
    std::set<std::string> found;
    for (std::size_t i = 0; i < scene.primitives.size(); ++i) {
        if (diced[i].triangles.empty()) continue;
        const std::string name = scene.primitives[i].attributes->name();
        const bool blocker =
            std::find(o.blockers.begin(), o.blockers.end(), name) != o.blockers.end();
        if (blocker) found.insert(name);
        TriangleMesh m{diced[i].vertices, diced[i].triangles};
        (blocker ? rep.blocker_triangles : rep.medium_triangles) +=
            m.triangles.size() / 3;
        (blocker ? w.blockers : w.medium).push_back(std::move(m));
    }
    for (const std::string& b : o.blockers)
        if (!found.count(b))
            throw ValueError(o.scene + ": no object named '" + b +
                             "' (Attribute \"identifier\" \"name\") for -blocker");
    if (w.medium.empty()) throw ValueError(o.scene + ": no geometry bounds the medium");

    rep.walk = walk_mesh(w, src);
    if (glm::length(rep.walk.flux_lost) > 1e-3 * glm::length(rep.walk.flux_in))
        rep.warnings.push_back(
            "light escaped through the geometry (is every object closed?)");

    PointCloud out = baked.points_only();
    Channel& value = out.add_channel("_ssdiffusion", ChannelType::Color);
    for (std::size_t i = 0; i < out.size(); ++i)
        for (int c = 0; c < 3; ++c)
            value.data[3 * i + c] = float(rep.walk.exitance[i][c]);
    Channel& error = out.add_channel("_ssdiffusion_error", ChannelType::Color);
    for (std::size_t i = 0; i < out.size(); ++i)
        for (int c = 0; c < 3; ++c)
            error.data[3 * i + c] = float(rep.walk.exitance_error[i][c]);
    return out;
}

CloudComparison compare_with_truth(const PointCloud& result, const PointCloud& truth,
                                   const std::vector<float>& areas) {
    if (result.size() != truth.size() || areas.size() != truth.size())
        throw ValueError("the clouds compared have " + std::to_string(result.size()) +
                         " and " + std::to_string(truth.size()) + " points");
    const Channel& a = color_channel(result, "_ssdiffusion");
    const Channel& t = color_channel(truth, "_ssdiffusion");
    const Channel* err = truth.find_channel("_ssdiffusion_error");
    if (err && err->components() != 3) err = nullptr;
    glm::dvec3 diff(0.0), sum_a(0.0), sum_t(0.0), sum_e(0.0);
    for (std::size_t i = 0; i < truth.size(); ++i) {
        if (!(areas[i] > 0.0f)) continue;
        if (glm::length(result.positions[i] - truth.positions[i]) >
            1e-4f * (1.0f + glm::length(truth.positions[i])))
            throw ValueError("the clouds compared differ at point " + std::to_string(i) +
                             ": not the same points");
        for (int c = 0; c < 3; ++c) {
            diff[c] += std::abs(double(a.data[3 * i + c]) - t.data[3 * i + c]) * areas[i];
            sum_a[c] += double(a.data[3 * i + c]) * areas[i];
            sum_t[c] += double(t.data[3 * i + c]) * areas[i];
            if (err) sum_e[c] += double(err->data[3 * i + c]) * areas[i];
        }
    }
    CloudComparison r;
    for (int c = 0; c < 3; ++c) {
        r.l1[c] = sum_t[c] > 0.0 ? diff[c] / sum_t[c] : 0.0;
        r.total_ratio[c] = sum_t[c] > 0.0 ? sum_a[c] / sum_t[c] : 0.0;
        r.noise[c] = sum_t[c] > 0.0 ? std::sqrt(2.0 / kPi) * sum_e[c] / sum_t[c] : 0.0;
    }
    return r;
}

RegionMean region_mean(const PointCloud& cloud, const std::vector<float>& areas,
                       const glm::dvec3& lo, const glm::dvec3& hi) {
    if (areas.size() != cloud.size())
        throw ValueError("region mean: " + std::to_string(areas.size()) + " areas for " +
                         std::to_string(cloud.size()) + " points");
    const Channel& v = color_channel(cloud, "_ssdiffusion");
    RegionMean r;
    double area = 0.0;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const glm::dvec3 p(cloud.positions[i]);
        if (!(areas[i] > 0.0f) || glm::any(glm::lessThan(p, lo)) ||
            glm::any(glm::greaterThan(p, hi)))
            continue;
        ++r.points;
        area += areas[i];
        for (int c = 0; c < 3; ++c) r.mean[c] += double(v.data[3 * i + c]) * areas[i];
    }
    if (area > 0.0) r.mean /= area;
    return r;
}

} // namespace sss
