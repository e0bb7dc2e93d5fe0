// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// Speed against error of ptfilter -ssdiffusion on a lit sphere.
//
//   build/bin/ssdiffusion_bench [-n 1000000] [-samples 1000] [-material marble]
//                               [-profile classic] [-threads 0] [-criteria 1]
//                               [-eps 0.25,0.5,1,2,4] [-isa all|auto|NAME]
//                               [-alldisks 0|1]
//
// Makes a sphere of radius 50 mm (unitlength 1) with N points lit by
// E = max(0, N.L), writes it as .ptc, then for each -maxsolidangle (and each
// criterion) times read + diffusion + write exactly as ptfilter does, and
// compares with the exact all-pairs evaluation at `samples` random points:
// RMS, 99th percentile and max of |h - e| / mean(e), worst colour channel.
// -isa all repeats the error criterion on every instruction-set path this CPU
// has (the comparison of the paths; their results are identical). -alldisks 1
// makes the reference integrate every source disk (ExactDisks::All), which
// also measures the point model's near field, equally for every profile.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "sss/cli/tool.h"
#include "sss/cloud/point_cloud_io.h"
#include "sss/cloud/synthetic.h"
#include "sss/diffusion/ssdiffusion.h"
#include "sss/util/error.h"
#include "sss/util/isa.h"
#include "sss/util/parse.h"

namespace {

struct Errors {
    double rms = 0, p99 = 0, max = 0;
    double bias = 0; ///< mean signed (h - e) / mean(e), the channel farthest from 0
};

Errors compare(const sss::PointCloud& out, const std::vector<std::size_t>& samples,
               const std::vector<glm::dvec3>& exact) {
    const sss::Channel* c = out.find_channel("_ssdiffusion");
    Errors worst;
    for (int ch = 0; ch < 3; ++ch) {
        double mean = 0;
        for (const glm::dvec3& e : exact) mean += e[ch] / double(exact.size());
        double se = 0, mx = 0, sum = 0;
        std::vector<double> all;
        for (std::size_t k = 0; k < samples.size(); ++k) {
            double signed_d =
                (double(c->data[3 * samples[k] + ch]) - exact[k][ch]) / mean;
            double d = std::abs(signed_d);
            sum += signed_d / double(samples.size());
            se += d * d / double(samples.size());
            mx = std::max(mx, d);
            all.push_back(d);
        }
        std::sort(all.begin(), all.end());
        if (!all.empty())
            worst.p99 =
                std::max(worst.p99, all[std::min(all.size() - 1, all.size() * 99 / 100)]);
        worst.rms = std::max(worst.rms, std::sqrt(se));
        worst.max = std::max(worst.max, mx);
        if (std::abs(sum) > std::abs(worst.bias)) worst.bias = sum;
    }
    return worst;
}

int run(const std::vector<std::string>& argv) {
    sss::ArgScanner args(argv);
    std::size_t n = 1000000, nsamples = 1000;
    std::string material = "marble", profile = "classic";
    int threads = 0;
    bool criteria = true, all_disks = false;
    std::vector<double> eps_list = {0.25, 0.5, 1, 2, 4};
    std::vector<sss::Isa> isas = {sss::Isa::Auto};
    while (!args.done()) {
        std::string o = args.option();
        if (o == "n")
            n = std::size_t(args.positive(o));
        else if (o == "samples")
            nsamples = std::size_t(args.positive(o));
        else if (o == "material")
            material = args.value(o);
        else if (o == "profile")
            profile = args.value(o);
        else if (o == "threads")
            threads = args.integer(o, -64, 1024);
        else if (o == "criteria")
            criteria = args.integer(o, 0, 1) != 0;
        else if (o == "alldisks")
            all_disks = args.integer(o, 0, 1) != 0;
        else if (o == "eps") {
            eps_list.clear();
            std::string v = args.value(o);
            for (std::size_t at = 0; at <= v.size();) {
                std::size_t end = std::min(v.find(',', at), v.size());
                std::optional<double> e = sss::parse_finite(v.substr(at, end - at));
                if (!e || !(*e > 0))
                    throw sss::UsageError("-eps: bad value in '" + v + "'");
                eps_list.push_back(*e);
                at = end + 1;
            }
        } else if (o == "isa") {
            std::string v = args.value(o);
            isas = v == "all" ? sss::supported_isas()
                              : std::vector<sss::Isa>{sss::parse_isa(v, "-isa")};
        } else
            throw sss::UsageError("unknown option -" + o);
    }
    sss::ThreadLimit limit(sss::resolve_thread_count(threads));

    sss::SyntheticParams sp;
    sp.shape = sss::SyntheticShape::Sphere;
    sp.count = n;
    sp.size = 50.0;
    sp.light_dir = {1, 1, 1};
    const std::string dir =
        (std::filesystem::temp_directory_path() / "sss_bench").string();
    std::filesystem::create_directories(dir);
    const std::string in_path = dir + "/sphere.ptc", out_path = dir + "/sphere_ssd.ptc";
    sss::write_point_cloud(sss::make_synthetic_cloud(sp), in_path);

    sss::SsDiffusionOptions opt;
    opt.material.preset = material;
    if (!sss::parse_profile_kind(profile, opt.profile))
        throw sss::UsageError("unknown profile " + profile);

    // Exact reference at random sample points.
    sss::PointCloud cloud = sss::read_point_cloud(in_path);
    std::mt19937_64 rng(12345);
    std::vector<std::size_t> samples(nsamples);
    for (std::size_t& s : samples) s = std::size_t(rng() % cloud.size());
    sss::DiffusionProblem pb;
    pb.positions = cloud.positions;
    pb.normals = cloud.normals;
    const sss::Channel* area = cloud.find_channel("_area");
    const sss::Channel* rad = cloud.find_channel("_radiance_t");
    pb.areas = area->data;
    for (std::size_t i = 0; i < cloud.size(); ++i)
        pb.irradiance.push_back(
            {rad->data[3 * i], rad->data[3 * i + 1], rad->data[3 * i + 2]});
    const sss::NamedMaterial* m = sss::find_material(material);
    for (int ch = 0; ch < 3; ++ch)
        pb.profiles.push_back(sss::Profile::from_coefficients(
            opt.profile, {m->sigma_s_prime[ch], m->sigma_a[ch], m->ior}));
    sss::Stopwatch exact_watch;
    std::vector<glm::dvec3> exact = sss::evaluate_diffusion_exact(
        pb, samples, nullptr, all_disks ? sss::ExactDisks::All : sss::ExactDisks::Model);
    std::printf("# %zu points, sphere r = 50 mm, %s, profile %s, %d threads\n",
                cloud.size(), material.c_str(), profile.c_str(),
                sss::resolve_thread_count(threads));
    std::printf("# exact reference at %zu points%s: %.1f s\n", nsamples,
                all_disks ? " (every disk integrated)" : "", exact_watch.seconds());
    std::printf("%-10s %8s %14s %10s %10s %10s %10s %12s %10s %12s\n", "criterion", "isa",
                "maxsolidangle", "wall_s", "diff_s", "rms_%", "p99_%", "max_%", "bias_%",
                "points/s");

    std::vector<sss::Criterion> crits = {sss::Criterion::Error};
    if (criteria) {
        crits.push_back(sss::Criterion::SolidAngleBox);
        crits.push_back(sss::Criterion::SolidAngleCentroid);
    }
    for (sss::Criterion c : crits) {
        for (sss::Isa isa : isas) {
            if (c != sss::Criterion::Error && isa != isas.front()) continue;
            opt.diffusion.isa = sss::resolve_isa(isa);
            for (double eps : eps_list) {
                opt.diffusion.criterion = c;
                opt.diffusion.max_solid_angle = eps;
                // Timed exactly as ptfilter runs: read, filter, write.
                sss::Stopwatch watch;
                sss::PointCloud in = sss::read_point_cloud(in_path);
                sss::SsDiffusionReport rep;
                sss::PointCloud out = sss::ssdiffusion(in, opt, &rep);
                sss::write_point_cloud(out, out_path);
                double wall = watch.seconds();
                Errors e = compare(out, samples, exact);
                std::printf(
                    "%-10s %8s %14g %10.3f %10.3f %10.3f %10.3f %12.3f %10.3f %12.0f\n",
                    sss::criterion_name(c), sss::isa_name(opt.diffusion.isa), eps, wall,
                    rep.seconds, 100 * e.rms, 100 * e.p99, 100 * e.max, 100 * e.bias,
                    double(in.size()) / rep.seconds);
                std::fflush(stdout);
            }
        }
    }
    std::filesystem::remove_all(dir);
    return 0;
}

} // namespace

int main(int argc, char** argv) {
    return sss::run_tool("ssdiffusion_bench", argc, argv, run);
}
