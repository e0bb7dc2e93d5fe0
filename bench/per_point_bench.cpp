// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// Per-point materials against one material: ptfilter's -albedo fromfile
// -diffusemeanfreepath fromfile (the ssdiffusion() library call) on a lit
// sphere whose albedo and mean free path vary smoothly over the surface, and
// the same sphere with one material: the per-point values' mean, and in turn
// -materials of its points' own materials (timing only). Prints,
// for both, the time of the call and the error against the exact all-pairs
// evaluation (each receiver with its own exact material, not the quantised
// one) at -samples random points: RMS and max of |h - e| / mean|e|, worst
// channel; then the time ratios (wall clock, and the CPU time of every
// thread, which other jobs on the machine disturb less). docs/ptfilter.md
// quotes it.
//
//   per_point_bench [-n 1000000] [-samples 300] [-threads 2] [-repeat 3]
//                   [-materials 8]

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <sys/resource.h>

#include "bench_util.h"
#include "sss/cli/args.h"
#include "sss/cli/tool.h"
#include "sss/cloud/synthetic.h"
#include "sss/diffusion/diffusion.h"
#include "sss/diffusion/ssdiffusion.h"
#include "sss/util/error.h"
#include "sss/util/progress.h"
#include "sss/util/threads.h"

namespace {

constexpr double kIor = 1.5;

// The per-point material at p (mm), in patches a few mm to 10 mm across (a
// painted map's scale against a 50 mm sphere): albedo and mean free path
// vary between the corners kLow and kHigh of each channel's range.
constexpr double kAlbedoLow[3] = {0.6, 0.5, 0.4}, kAlbedoHigh[3] = {0.8, 0.7, 0.6};
constexpr double kDmfpLow[3] = {3.0, 2.0, 1.5}, kDmfpHigh[3] = {8.0, 5.5, 4.0};

glm::dvec3 albedo_at(const glm::vec3& p) {
    const double u = 0.5 + 0.5 * std::sin(p.x / 7.0) * std::cos(p.y / 9.0 + p.z / 11.0);
    glm::dvec3 a;
    for (int ch = 0; ch < 3; ++ch)
        a[ch] = kAlbedoLow[ch] + u * (kAlbedoHigh[ch] - kAlbedoLow[ch]);
    return a;
}
glm::dvec3 dmfp_at(const glm::vec3& p) {
    const double v = 0.5 + 0.5 * std::cos(p.z / 6.0) * std::sin(p.x / 13.0 + 1.0);
    glm::dvec3 d;
    for (int ch = 0; ch < 3; ++ch)
        d[ch] = kDmfpLow[ch] + v * (kDmfpHigh[ch] - kDmfpLow[ch]);
    return d;
}

sss::PointCloud varying_sphere(std::size_t n, glm::dvec3& mean_albedo,
                               glm::dvec3& mean_dmfp) {
    sss::SyntheticParams sp;
    sp.shape = sss::SyntheticShape::Sphere;
    sp.count = n;
    sp.size = 50.0;
    sp.light_dir = {1, 1, 1};
    sss::PointCloud c = sss::make_synthetic_cloud(sp);
    sss::Channel& a = c.add_channel("_albedo", sss::ChannelType::Color);
    sss::Channel& d = c.add_channel("_diffusemeanfreepath", sss::ChannelType::Color);
    a.data.resize(3 * c.size());
    d.data.resize(3 * c.size());
    mean_albedo = mean_dmfp = glm::dvec3(0.0);
    for (std::size_t i = 0; i < c.size(); ++i) {
        const glm::dvec3 al = albedo_at(c.positions[i]), dm = dmfp_at(c.positions[i]);
        for (int ch = 0; ch < 3; ++ch) {
            a.data[3 * i + ch] = float(al[ch]);
            d.data[3 * i + ch] = float(dm[ch]);
        }
        mean_albedo += al / double(c.size());
        mean_dmfp += dm / double(c.size());
    }
    return c;
}

// The exact evaluation at the samples, each sampled receiver with its own
// material (per_point) or every one with the mean material.
std::vector<glm::dvec3> exact_at(const sss::PointCloud& c,
                                 const std::vector<std::size_t>& samples, bool per_point,
                                 const glm::dvec3& albedo, const glm::dvec3& dmfp) {
    sss::DiffusionProblem pb = sss_bench::cloud_problem(c);
    for (int ch = 0; ch < 3; ++ch)
        pb.profiles.push_back(sss::Profile::from_albedo_dmfp(sss::ProfileKind::Classic,
                                                             albedo[ch], dmfp[ch], kIor));
    if (per_point) {
        // Only a receiver's own material matters: the others keep profile 0-2.
        pb.profile_index.assign(c.size(), glm::u32vec3(0, 1, 2));
        const sss::Channel* a = c.find_channel("_albedo");
        const sss::Channel* d = c.find_channel("_diffusemeanfreepath");
        for (std::size_t i : samples) {
            glm::u32vec3 idx;
            for (int ch = 0; ch < 3; ++ch) {
                idx[ch] = uint32_t(pb.profiles.size());
                pb.profiles.push_back(sss::Profile::from_albedo_dmfp(
                    sss::ProfileKind::Classic, a->data[3 * i + ch], d->data[3 * i + ch],
                    kIor));
            }
            pb.profile_index[i] = idx;
        }
    }
    return sss::evaluate_diffusion_exact(pb, samples);
}

struct Row {
    double seconds = 0, cpu = 0, rms = 0, max = 0;
    std::size_t profiles = 0;
};

// The process's CPU time so far (every thread, user and system).
double cpu_seconds() {
    rusage ru{};
    getrusage(RUSAGE_SELF, &ru);
    return double(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
           1e-6 * double(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
}

Row measure(const sss::PointCloud& c, const sss::SsDiffusionOptions& o, int repeat,
            const std::vector<std::size_t>& samples, const std::vector<glm::dvec3>& e) {
    Row row;
    row.seconds = row.cpu = 1e300;
    sss::PointCloud out;
    for (int k = 0; k < repeat; ++k) {
        const double cpu0 = cpu_seconds();
        sss::Stopwatch w;
        sss::SsDiffusionReport rep;
        out = sss::ssdiffusion(c, o, &rep);
        row.profiles = rep.distinct_profiles;
        row.seconds = std::min(row.seconds, w.seconds());
        row.cpu = std::min(row.cpu, cpu_seconds() - cpu0);
    }
    const sss::Channel* h = out.find_channel("_ssdiffusion");
    for (int ch = 0; ch < 3 && !e.empty(); ++ch) {
        double mean = 0, sq = 0, mx = 0;
        for (const glm::dvec3& v : e) mean += std::abs(v[ch]) / double(e.size());
        for (std::size_t k = 0; k < samples.size(); ++k) {
            const double d = (double(h->data[3 * samples[k] + ch]) - e[k][ch]) / mean;
            sq += d * d / double(samples.size());
            mx = std::max(mx, std::abs(d));
        }
        row.rms = std::max(row.rms, std::sqrt(sq));
        row.max = std::max(row.max, mx);
    }
    return row;
}

int run(const std::vector<std::string>& argv) {
    sss::ArgScanner args(argv);
    std::size_t n = 1000000, sample_count = 300;
    int threads = 2, repeat = 3, picked = 8;
    while (!args.done()) {
        std::string o = args.option();
        if (o == "n")
            n = std::size_t(args.positive(o));
        else if (o == "samples")
            sample_count = std::size_t(args.positive(o));
        else if (o == "threads")
            threads = args.integer(o, 0, 1024);
        else if (o == "repeat")
            repeat = args.integer(o, 1, 100);
        else if (o == "materials")
            picked = args.integer(o, 1, 100);
        else
            throw sss::UsageError("unknown option -" + o);
    }
    sss::ThreadLimit limit(sss::resolve_thread_count(threads));
    glm::dvec3 albedo, dmfp;
    const sss::PointCloud c = varying_sphere(n, albedo, dmfp);
    const std::vector<std::size_t> samples =
        sss_bench::random_samples(c.size(), sample_count, 12345);

    sss::SsDiffusionOptions uniform;
    uniform.material.albedo = albedo;
    uniform.material.dmfp = dmfp;
    uniform.material.ior = kIor;
    sss::SsDiffusionOptions per_point;
    per_point.material.albedo_from_file = per_point.material.dmfp_from_file = true;
    per_point.material.ior = kIor;

    const Row u =
        measure(c, uniform, repeat, samples, exact_at(c, samples, false, albedo, dmfp));
    const Row p =
        measure(c, per_point, repeat, samples, exact_at(c, samples, true, albedo, dmfp));
    // The same cloud with one material taken from it, for several of its
    // points: a material's cost depends on it (how coarse the points are
    // against its near field, where close disks need the quadrature), so the
    // cost a per-point cloud should match is the mean over its own materials,
    // not the cost of their mean (timing only).
    const std::vector<std::size_t> picks =
        sss_bench::random_samples(c.size(), std::size_t(picked), 12345);
    std::vector<Row> taken;
    for (std::size_t i : picks) {
        sss::SsDiffusionOptions o = uniform;
        o.material.albedo = albedo_at(c.positions[i]);
        o.material.dmfp = dmfp_at(c.positions[i]);
        taken.push_back(measure(c, o, repeat, {}, {}));
    }
    std::printf("per_point_bench: %zu points, %d threads, best of %d, error against the "
                "exact evaluation at %zu points (fraction of mean|e|, worst channel)\n",
                c.size(), sss::resolve_thread_count(threads), repeat, samples.size());
    std::printf("%-22s %9s %9s %9s %9s %9s\n", "material", "profiles", "seconds", "cpu_s",
                "rms", "max");
    std::printf("%-22s %9zu %9.3f %9.3f %9.5f %9.5f\n", "uniform (the mean)", u.profiles,
                u.seconds, u.cpu, u.rms, u.max);
    std::printf("%-22s %9zu %9.3f %9.3f %9.5f %9.5f\n", "fromfile", p.profiles, p.seconds,
                p.cpu, p.rms, p.max);
    double taken_cpu = 0, lo = 1e300, hi = 0;
    for (const Row& r : taken) {
        taken_cpu += r.cpu / double(taken.size());
        lo = std::min(lo, r.cpu);
        hi = std::max(hi, r.cpu);
    }
    std::printf("%-22s %9d %9s %9.3f   (%zu of the cloud's materials, one at a time: "
                "%.3f to %.3f)\n",
                "uniform (its own)", 3, "", taken_cpu, taken.size(), lo, hi);
    std::printf("fromfile / uniform (the mean): %.2fx (wall), %.2fx (cpu)\n",
                p.seconds / u.seconds, p.cpu / u.cpu);
    std::printf("fromfile / uniform (its own, mean cpu): %.2fx\n", p.cpu / taken_cpu);
    return 0;
}

} // namespace

int main(int argc, char** argv) {
    return sss::run_tool("per_point_bench", argc, argv, run);
}
