// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file synthetic.cpp
/// Synthetic lit point clouds (sphere, plane, box) with exact per-point areas.

#include "sss/cloud/synthetic.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "sss/util/error.h"
#include "sss/util/hash.h"

namespace sss {

namespace {

/// One surface sample before it goes into the cloud.
struct Sample {
    glm::dvec3 p;
    glm::dvec3 n;
    double area;
    double radius;
};

/// Uniform number in [0, 1) keyed by (seed, point index, dimension): the same
/// point gets the same jitter whatever order points are generated in.
double hash_uniform(uint64_t seed, uint64_t index, uint64_t dim) {
    uint64_t x =
        detail::splitmix64(detail::splitmix64(seed) ^ (index * 0xd1b54a32d192ed03ull));
    x = detail::splitmix64(x + dim);
    return static_cast<double>(x >> 11) * 0x1.0p-53;
}

bool finite3(const glm::dvec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

void validate(const SyntheticParams& p) {
    if (p.count < 1) throw ValueError("synthetic cloud: count must be at least 1");
    if (!std::isfinite(p.size) || !(p.size > 0.0))
        throw ValueError("synthetic cloud: size must be a finite number > 0");
    if (p.shape == SyntheticShape::Box &&
        (!std::isfinite(p.thickness) || !(p.thickness > 0.0)))
        throw ValueError("synthetic cloud: thickness must be a finite number > 0");
    if (!std::isfinite(p.jitter) || p.jitter < 0.0 || p.jitter > 1.0)
        throw ValueError("synthetic cloud: jitter must be in [0, 1]");
    if (!finite3(p.light_dir) || glm::length(p.light_dir) <= 0.0)
        throw ValueError("synthetic cloud: light direction must be finite and non-zero");
    if (!finite3(p.light_color))
        throw ValueError("synthetic cloud: light colour must be finite");
    if (!std::isfinite(p.ambient))
        throw ValueError("synthetic cloud: ambient must be finite");
}

/// Fibonacci lattice: equal-area latitude bands (z uniform), golden-angle
/// longitudes, so every point owns the same share of the sphere.
std::vector<Sample> make_sphere(const SyntheticParams& p) {
    const std::size_t n = p.count;
    const double r = p.size;
    const double area = 4.0 * std::numbers::pi * r * r / static_cast<double>(n);
    const double radius = std::sqrt(2.0 * area) / 2.0;
    const double golden_angle = std::numbers::pi * (3.0 - std::sqrt(5.0));
    std::vector<Sample> out(n);
    for (std::size_t i = 0; i < n; ++i) {
        double z = 1.0 - (2.0 * static_cast<double>(i) + 1.0) / static_cast<double>(n);
        double s = std::sqrt(std::max(0.0, 1.0 - z * z));
        double phi = golden_angle * static_cast<double>(i);
        glm::dvec3 dir(s * std::cos(phi), s * std::sin(phi), z);
        dir = glm::normalize(dir);
        out[i] = Sample{r * dir, dir, area, radius};
    }
    return out;
}

/// Appends an nu x nv grid of cell centres on a rectangle centred at `centre`
/// spanning du along axis_u and dv along axis_v.
void add_grid(std::vector<Sample>& out, const SyntheticParams& p, glm::dvec3 centre,
              glm::dvec3 normal, glm::dvec3 axis_u, glm::dvec3 axis_v, double du,
              double dv, std::size_t nu, std::size_t nv) {
    const double hu = du / static_cast<double>(nu);
    const double hv = dv / static_cast<double>(nv);
    const double area = hu * hv;
    const double radius = std::sqrt(hu * hu + hv * hv) / 2.0; // half the cell diagonal
    out.reserve(out.size() + nu * nv);
    for (std::size_t j = 0; j < nv; ++j) {
        for (std::size_t i = 0; i < nu; ++i) {
            double u = -0.5 * du + (static_cast<double>(i) + 0.5) * hu;
            double v = -0.5 * dv + (static_cast<double>(j) + 0.5) * hv;
            if (p.jitter > 0.0) {
                // Offsets stay inside the cell for jitter <= 1.
                const uint64_t index = out.size();
                u += (hash_uniform(p.seed, index, 0) - 0.5) * p.jitter * hu;
                v += (hash_uniform(p.seed, index, 1) - 0.5) * p.jitter * hv;
            }
            out.push_back(Sample{centre + u * axis_u + v * axis_v, normal, area, radius});
        }
    }
}

std::vector<Sample> make_plane(const SyntheticParams& p) {
    const auto n = static_cast<std::size_t>(
        std::max(1.0, std::round(std::sqrt(static_cast<double>(p.count)))));
    std::vector<Sample> out;
    add_grid(out, p, glm::dvec3(0.0), glm::dvec3(0, 0, 1), glm::dvec3(1, 0, 0),
             glm::dvec3(0, 1, 0), p.size, p.size, n, n);
    return out;
}

std::vector<Sample> make_box(const SyntheticParams& p) {
    const glm::dvec3 extent(p.size, p.size, p.thickness);
    const double total_area =
        2.0 * (extent.x * extent.y + extent.y * extent.z + extent.z * extent.x);
    // One spacing for all faces so the density is uniform over the box.
    const double spacing = std::sqrt(total_area / static_cast<double>(p.count));
    auto cells = [&](double length) {
        return static_cast<std::size_t>(std::max(1.0, std::round(length / spacing)));
    };
    std::vector<Sample> out;
    for (int axis = 0; axis < 3; ++axis) {
        const int a_u = (axis + 1) % 3;
        const int a_v = (axis + 2) % 3;
        for (double sign : {1.0, -1.0}) {
            glm::dvec3 normal(0.0), axis_u(0.0), axis_v(0.0);
            normal[axis] = sign;
            axis_u[a_u] = 1.0;
            axis_v[a_v] = 1.0;
            glm::dvec3 centre = normal * (0.5 * extent[axis]);
            add_grid(out, p, centre, normal, axis_u, axis_v, extent[a_u], extent[a_v],
                     cells(extent[a_u]), cells(extent[a_v]));
        }
    }
    return out;
}

} // namespace

PointCloud make_synthetic_cloud(const SyntheticParams& params) {
    validate(params);
    std::vector<Sample> samples;
    switch (params.shape) {
    case SyntheticShape::Sphere:
        samples = make_sphere(params);
        break;
    case SyntheticShape::Plane:
        samples = make_plane(params);
        break;
    case SyntheticShape::Box:
        samples = make_box(params);
        break;
    }

    const std::size_t n = samples.size();
    const glm::dvec3 light = glm::normalize(params.light_dir);
    PointCloud cloud;
    cloud.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        cloud.positions[i] = glm::vec3(samples[i].p);
        cloud.normals[i] = glm::vec3(samples[i].n);
        cloud.radii[i] = static_cast<float>(samples[i].radius);
    }

    // Channels are filled one at a time: add_channel may reallocate the
    // channel list and invalidate earlier references.
    {
        Channel& area = cloud.add_channel("_area", ChannelType::Float);
        area.data.resize(n);
        for (std::size_t i = 0; i < n; ++i)
            area.data[i] = static_cast<float>(samples[i].area);
    }
    {
        Channel& radiance = cloud.add_channel("_radiance_t", ChannelType::Color);
        radiance.data.resize(3 * n);
        for (std::size_t i = 0; i < n; ++i) {
            double cosine = std::max(0.0, glm::dot(samples[i].n, light));
            glm::dvec3 c = params.light_color * cosine + glm::dvec3(params.ambient);
            for (int k = 0; k < 3; ++k)
                radiance.data[3 * i + k] = static_cast<float>(c[k]);
        }
    }
    return cloud;
}

} // namespace sss
