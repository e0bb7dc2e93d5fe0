// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file exact.cpp
/// The exact evaluation: all pairs in double precision, with the same point
/// model as the hierarchical path (exact self disk, disk quadrature of close
/// sources). The reference the tests and benchmarks measure against.

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <string>

#include <oneapi/tbb/parallel_for.h>

#include <glm/geometric.hpp>

#include "sss/diffusion/diffusion.h"
#include "sss/util/error.h"
#include "sss/util/math.h"
#include "sss/util/progress.h"

#include "disk_quadrature.h"
#include "profile_tables.h"

namespace sss {

using diffusion_detail::disk_frame;
using diffusion_detail::for_disk_points;
using diffusion_detail::kNearKappa2;

std::vector<glm::dvec3>
evaluate_diffusion_exact(const DiffusionProblem& pb,
                         const std::vector<std::size_t>& receivers, Progress* progress,
                         ExactDisks disks) {
    const std::size_t n = pb.positions.size();
    if (!pb.receiver_gain.empty() && pb.receiver_gain.size() != n)
        throw ValueError("diffusion: " + std::to_string(pb.receiver_gain.size()) +
                         " receiver gains for " + std::to_string(n) + " points");
    std::vector<std::size_t> rec = receivers;
    if (rec.empty()) {
        rec.resize(n);
        for (std::size_t i = 0; i < n; ++i) rec[i] = i;
    }
    std::vector<glm::dvec3> out(rec.size(), glm::dvec3(0.0));
    std::atomic<std::size_t> done{0};
    if (progress) progress->set_unit("points");
    oneapi::tbb::parallel_for(std::size_t(0), rec.size(), [&](std::size_t r) {
        const std::size_t i = rec[r];
        glm::u32vec3 idx =
            pb.profile_index.empty() ? glm::u32vec3(0, 1, 2) : pb.profile_index[i];
        const Profile* prof[3] = {&pb.profiles[idx[0]], &pb.profiles[idx[1]],
                                  &pb.profiles[idx[2]]};
        double core2 = std::numeric_limits<double>::max();
        for (int ch = 0; ch < 3; ++ch)
            core2 = std::min(core2, prof[ch]->core_length() * prof[ch]->core_length());
        const bool disk_means =
            disks == ExactDisks::All || diffusion_detail::uses_disk_means(prof);
        glm::dvec3 x(pb.positions[i]);
        double acc[3] = {0, 0, 0};
        // Coincident sources usually share their area: keep the last disk.
        double memo_rho = -1.0, memo_disk[3] = {0, 0, 0};
        for (std::size_t j = 0; j < n; ++j) {
            double a = pb.areas[j];
            glm::dvec3 e(pb.irradiance[j]);
            double rho = std::sqrt(a / kPi);
            glm::dvec3 w = x - glm::dvec3(pb.positions[j]);
            double q = glm::dot(w, w);
            if (j == i || q == 0.0) {
                if (rho != memo_rho) {
                    memo_rho = rho;
                    for (int ch = 0; ch < 3; ++ch) memo_disk[ch] = prof[ch]->disk(rho);
                }
                for (int ch = 0; ch < 3; ++ch) acc[ch] += e[ch] * memo_disk[ch];
                continue;
            }
            // Same rule as the hierarchical path (in float there). The
            // sampled profiles (1/r at the source) take every disk that is not
            // tiny against its distance as a disk: the reference for the
            // hierarchical path's disk means.
            const bool disk = disk_means
                                  ? a / kPi > diffusion_detail::kExactDisk2 * q
                                  : float(a / kPi) > float(kNearKappa2 * (q + core2));
            if (disk) {
                glm::dvec3 u, v;
                glm::dvec3 nj =
                    pb.normals.empty() ? glm::dvec3(0) : glm::dvec3(pb.normals[j]);
                disk_frame(nj, w, u, v);
                double sum[3] = {0, 0, 0};
                for_disk_points(rho, u, v, [&](const glm::dvec3& off, double wt) {
                    double r = glm::length(w - off);
                    for (int ch = 0; ch < 3; ++ch) sum[ch] += wt * prof[ch]->eval(r);
                });
                for (int ch = 0; ch < 3; ++ch) acc[ch] += sum[ch] * a * e[ch];
                continue;
            }
            double r = std::sqrt(q);
            for (int ch = 0; ch < 3; ++ch) acc[ch] += prof[ch]->eval(r) * a * e[ch];
        }
        out[r] = glm::dvec3(acc[0], acc[1], acc[2]);
        if (!pb.receiver_gain.empty()) out[r] *= glm::dvec3(pb.receiver_gain[i]);
        if (progress) progress->update(done.fetch_add(1) + 1, rec.size());
    });
    return out;
}

} // namespace sss
