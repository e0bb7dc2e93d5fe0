// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file main.cpp
/// ssprofile: a material's diffusion profiles held against the Monte-Carlo
/// random walk on a half-space (docs/accuracy.md), and the writer of the
/// Monte-Carlo profile table (-maketable).

#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "sss/cli/args.h"
#include "sss/cli/job.h"
#include "sss/cli/options.h"
#include "sss/cli/tool.h"
#include "sss/cloud/point_cloud_io.h"
#include "sss/truth/profile_report.h"
#include "sss/truth/scene_walk.h"
#include "sss/util/atomic_output.h"
#include "sss/util/error.h"

namespace {

const char* const kTool = "ssprofile";

std::string usage() {
    return std::string(R"(usage: ssprofile [options]
       ssprofile -scene scene.rib [options] baked.ptc truth.ptc
       ssprofile -maketable out.tbl [-photons N] [-seed S] [-threads N] [-progress 1]

Holds the diffusion profiles of a material against a Monte-Carlo random walk
of the light on a half-space (reduced isotropic medium, exact Fresnel boundary,
normal pencil beam), channel by channel: L1w, the L1 error of r R(r) over
r in [0, 10 l] (l = 1 / sigma_t'), dRd, the total reflectance against the
walk's, and the flux ratios by range of r. The walk's own noise is printed.

Material (as ptfilter; lengths in mm):
  -material NAME            )") +
           sss::material_names() + R"( (default marble)
  -scattering R G B         reduced scattering sigma_s' (1/mm)
  -absorption R G B         absorption sigma_a (1/mm)
  -albedo R G B, -diffusemeanfreepath R G B
                            the medium the classic dipole infers from them
  -ior N                    relative index of refraction
Comparison:
  -profile LIST             comma-separated: classic, better, burley, pbd, mc
                            or all (default)
  -photons N                paths of the walk, all channels together
                            (default 1000000)
  -seed S                   the walk's seed (default 1001; the shipped
                            Monte-Carlo table was made with seeds 1-7)
  -csv FILE                 per annulus: walk flux and error, each profile's
  -svg FILE                 r R(r) of the walk and each profile, per channel
  -tsv FILE                 the table, one row per channel and profile
In a scene's own geometry (-scene):
  -scene FILE               the RIB whose objects bound the medium; the walk is
                            lit by baked.ptc's _radiance_t and writes truth.ptc
                            with _ssdiffusion and _ssdiffusion_error (per point,
                            ptfilter's scale); -photons counts per channel
  -unitlength U             scene units per mm (as ptfilter)
  -blocker NAME             an object (Attribute "identifier" "name") that
                            absorbs what reaches it, e.g. a bone; repeatable
  -spacing S                edge length the objects are diced to (scene units;
                            default 1/500 of the cloud's diagonal)
  -compare FILE             a ptfilter result on the same points: prints its
                            flux-weighted L1 error (and the walk's own noise in
                            it) and total against the walk;
                            repeatable (a cloud of other points: regions only)
  -region NAME X0 Y0 Z0 X1 Y1 Z1
                            prints the area-weighted mean exitance of the walk
                            and of each -compare cloud over the points inside
                            the box (e.g. a slab's lit face); repeatable
  -incidence normal|diffuse light enters refracted straight in, or diffuse
                            (cosine-weighted outside; the default)
  -scattered 0|1            1: light that leaves without a collision is not
                            tallied (the part a diffusion model describes)
Table:
  -maketable FILE           walk every (ior, albedo) node of the Monte-Carlo
                            profile table and write it (scripts/make-mc-table)
Running:
  -threads N                0 = all usable cores (default), <0 = all but N
  -progress 0|1             ALF_PROGRESS lines (-maketable)
  -check                    check the command line only, reading and writing
                            no file: exit 0 if it would run, 2 if not
  --help, --version

Exit codes: 0 ok, 1 error, 2 bad command line.
)";
}

uint64_t count_value(sss::ArgScanner& args, const std::string& opt) {
    const std::string v = args.value(opt);
    std::size_t used = 0;
    unsigned long long n = 0;
    try {
        n = std::stoull(v, &used);
    } catch (const std::exception&) {
        used = 0;
    }
    if (used != v.size() || n == 0 || v[0] == '-')
        throw sss::UsageError("option -" + opt + ": expected a positive integer, got '" +
                              v + "'");
    return n;
}

std::vector<sss::ProfileKind> profile_list(const std::string& text) {
    std::vector<sss::ProfileKind> out;
    if (text == "all")
        return {sss::ProfileKind::Classic, sss::ProfileKind::Better,
                sss::ProfileKind::Burley, sss::ProfileKind::Pbd, sss::ProfileKind::Mc};
    std::stringstream in(text);
    std::string name;
    while (std::getline(in, name, ',')) {
        sss::ProfileKind k;
        if (!sss::parse_profile_kind(name, k))
            throw sss::UsageError("option -profile: unknown profile '" + name +
                                  "' (classic, better, burley, pbd, mc, all)");
        out.push_back(k);
    }
    if (out.empty()) throw sss::UsageError("option -profile: no profile given");
    return out;
}

/// A box whose points' mean exitance -region prints.
struct Region {
    std::string name;
    glm::dvec3 lo{0.0}, hi{0.0};
};

/// What -scene is told besides the material.
struct SceneArgs {
    std::string scene;
    std::vector<std::string> blockers, compare;
    std::vector<Region> regions;
    double spacing = 0.0;
    bool normal_incidence = false, scattered_only = false;
};

Region region_value(sss::ArgScanner& args, const std::string& o) {
    Region r;
    r.name = args.value(o);
    for (int a = 0; a < 3; ++a) r.lo[a] = args.number(o);
    for (int a = 0; a < 3; ++a) r.hi[a] = args.number(o);
    for (int a = 0; a < 3; ++a)
        if (!(r.lo[a] <= r.hi[a]))
            throw sss::UsageError("option -region " + r.name +
                                  ": the box's low corner "
                                  "is above its high corner");
    return r;
}

/// -scene: the walk in the scene's geometry, lit by the baked cloud.
int run_scene(const SceneArgs& sa, const sss::ProfileReportOptions& report,
              const std::vector<std::string>& files, bool photons_given, uint64_t photons,
              bool seed_given, uint64_t seed, sss::Job& job) {
    sss::SceneWalkOptions w;
    w.scene = sa.scene;
    w.blockers = sa.blockers;
    w.material = report.material;
    w.spacing = sa.spacing;
    w.normal_incidence = sa.normal_incidence;
    w.scattered_only = sa.scattered_only;
    if (photons_given) w.photons = photons;
    if (seed_given) w.seed = seed;
    const sss::PointCloud baked = sss::read_point_cloud(files[0]);
    // The clouds compared are read first: a wrong name fails before the walk.
    std::vector<sss::PointCloud> others;
    for (const std::string& c : sa.compare) others.push_back(sss::read_point_cloud(c));
    sss::SceneWalkReport rep;
    const sss::PointCloud truth = sss::walk_scene(w, baked, &rep);
    for (const std::string& warning : rep.warnings) sss::warn(kTool, warning);
    sss::write_point_cloud(truth, files[1]);
    const sss::MeshWalkResult& r = rep.walk;
    std::printf(
        "ssprofile: %zu points, %zu medium and %zu blocker triangles (spacing %g), "
        "%llu paths per channel, %.1f s\n",
        baked.size(), rep.medium_triangles, rep.blocker_triangles, rep.spacing,
        static_cast<unsigned long long>(r.photons), job.seconds());
    const char* names = "rgb";
    for (int c = 0; c < 3; ++c) {
        const double in = r.flux_in[c] > 0.0 ? r.flux_in[c] : 1.0;
        std::printf(
            "ssprofile: %c: flux in %.6g; out %.4f +- %.4f, blocked %.4f, absorbed "
            "%.4f of it",
            names[c], r.flux_in[c], r.flux_out[c] / in, r.flux_out_error[c] / in,
            r.flux_blocked[c] / in, r.flux_absorbed[c] / in);
        if (sa.scattered_only)
            std::printf(", unscattered %.4f", r.flux_unscattered[c] / in);
        std::printf("\n");
    }
    const std::vector<float> areas = sss::cloud_areas(baked, w.area_channel);
    for (std::size_t k = 0; k < others.size(); ++k) {
        if (others[k].size() != truth.size()) {
            std::printf("ssprofile: %s has other points than the walk's: regions only\n",
                        sa.compare[k].c_str());
            continue;
        }
        const sss::CloudComparison cmp = sss::compare_with_truth(others[k], truth, areas);
        for (int c = 0; c < 3; ++c)
            std::printf(
                "ssprofile: %s %c: flux-weighted L1 %.1f%% (walk noise %.1f%%), total "
                "x%.3f of the walk's\n",
                sa.compare[k].c_str(), names[c], 100.0 * cmp.l1[c], 100.0 * cmp.noise[c],
                cmp.total_ratio[c]);
    }
    for (const Region& g : sa.regions) {
        const sss::RegionMean t = sss::region_mean(truth, areas, g.lo, g.hi);
        if (t.points == 0)
            throw sss::ValueError("region " + g.name + ": no point with area inside it");
        std::printf("ssprofile: region %s: %zu points, walk %.6g %.6g %.6g\n",
                    g.name.c_str(), t.points, t.mean.x, t.mean.y, t.mean.z);
        for (std::size_t k = 0; k < others.size(); ++k) {
            const sss::RegionMean m = sss::region_mean(
                others[k], sss::cloud_areas(others[k], "_area"), g.lo, g.hi);
            glm::dvec3 ratio(0.0);
            for (int c = 0; c < 3; ++c)
                ratio[c] = t.mean[c] > 0 ? m.mean[c] / t.mean[c] : 0.0;
            std::printf(
                "ssprofile: region %s: %s %.6g %.6g %.6g, x%.3f x%.3f x%.3f of the "
                "walk's\n",
                g.name.c_str(), sa.compare[k].c_str(), m.mean.x, m.mean.y, m.mean.z,
                ratio.x, ratio.y, ratio.z);
        }
    }
    sss::flush_standard_output();
    return 0;
}

/// The options that go together: -scene's with -scene, -maketable alone, the
/// plots and tables with the comparison (UsageError otherwise).
void check_modes(const SceneArgs& sa, const std::vector<std::string>& positional,
                 const std::string& table_path, bool plots) {
    if (!sa.scene.empty()) {
        if (positional.size() != 2)
            throw sss::UsageError("-scene needs the baked cloud and the output cloud");
        if (!table_path.empty() || plots)
            throw sss::UsageError(
                "-scene writes a cloud (no -maketable, -csv, -svg or -tsv)");
        return;
    }
    if (!sa.blockers.empty() || sa.spacing > 0.0 || !sa.compare.empty() ||
        !sa.regions.empty() || sa.normal_incidence || sa.scattered_only)
        throw sss::UsageError(
            "-blocker, -spacing, -compare, -region, -incidence and -scattered belong to "
            "-scene");
    if (!positional.empty())
        throw sss::UsageError("unexpected argument '" + positional.front() + "'");
    if (!table_path.empty() && plots)
        throw sss::UsageError("-maketable writes only the table (no -csv, -svg or -tsv)");
}

int run(const std::vector<std::string>& argv) {
    sss::ArgScanner args(argv);
    sss::ProfileReportOptions report;
    sss::McTableOptions table = sss::default_mc_table_options();
    sss::RunOptions running;
    std::string csv, svg, tsv, table_path, o;
    SceneArgs sa;
    std::vector<std::string> positional;
    bool photons_given = false, seed_given = false;
    uint64_t photons = 0, seed = 0;
    while (args.next_option(o, positional)) {
        if (sss::standard_option(kTool, o, usage())) return 0;
        if (sss::material_option(args, o, report.material, false) ||
            sss::run_option(args, o, running))
            continue;
        if (o == "profile")
            report.profiles = profile_list(args.value(o));
        else if (o == "photons")
            photons = count_value(args, o), photons_given = true;
        else if (o == "seed")
            seed = count_value(args, o), seed_given = true;
        else if (o == "csv")
            csv = args.value(o);
        else if (o == "svg")
            svg = args.value(o);
        else if (o == "tsv")
            tsv = args.value(o);
        else if (o == "maketable")
            table_path = args.value(o);
        else if (o == "scene")
            sa.scene = args.value(o);
        else if (o == "blocker")
            sa.blockers.push_back(args.value(o));
        else if (o == "spacing")
            sa.spacing = args.positive(o);
        else if (o == "compare")
            sa.compare.push_back(args.value(o));
        else if (o == "region")
            sa.regions.push_back(region_value(args, o));
        else if (o == "incidence") {
            const std::string v = args.value(o);
            if (v != "normal" && v != "diffuse")
                throw sss::UsageError("option -incidence: 'normal' or 'diffuse', not '" +
                                      v + "'");
            sa.normal_incidence = v == "normal";
        } else if (o == "scattered")
            sa.scattered_only = args.integer(o, 0, 1) == 1;
        else
            throw sss::unknown_option(o, usage());
    }
    check_modes(sa, positional, table_path, !csv.empty() || !svg.empty() || !tsv.empty());
    // The table has no material; the comparisons and the walk check theirs.
    if (table_path.empty()) report.material.validate();
    if (sss::check_only()) return 0;
    sss::Job job(kTool, running);
    if (!sa.scene.empty())
        return run_scene(sa, report, positional, photons_given, photons, seed_given, seed,
                         job);
    if (!table_path.empty()) {
        if (photons_given) table.photons = photons;
        if (seed_given) table.seed = seed;
        sss::Progress* progress = job.progress();
        const std::string text = sss::make_mc_table(table, [&](double done) {
            if (progress) progress->update(uint64_t(done * 1000.0), 1000);
        });
        sss::write_text_file(table_path, text);
        if (progress) progress->finish();
        std::printf(
            "ssprofile: wrote %s (%zu ior x %zu albedo nodes, %llu photons each ior, "
            "%.1f s)\n",
            table_path.c_str(), table.eta.size(), table.albedo.size(),
            static_cast<unsigned long long>(table.photons), job.seconds());
        return 0;
    }
    if (photons_given) report.photons = photons;
    if (seed_given) report.seed = seed;
    const sss::ProfileReport r = sss::profile_report(report);
    std::fputs(sss::format_profile_report(r).c_str(), stdout);
    if (!csv.empty()) sss::write_text_file(csv, sss::profile_report_csv(r));
    if (!svg.empty()) sss::write_text_file(svg, sss::profile_report_svg(r));
    if (!tsv.empty()) sss::write_text_file(tsv, sss::profile_report_tsv(r));
    sss::flush_standard_output();
    return 0;
}

} // namespace

int main(int argc, char** argv) {
    return sss::run_tool(kTool, argc, argv, run);
}
