// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// Speed against error: the measurements behind docs/speed-vs-error.md.
// scripts/speed-vs-error builds, runs this program and draws the report from
// the tables it writes; see that document for what every column means.
//
//   speed_error_bench -out DIR [-sections sweep,profiles,scaling,model,brick]
//                     [-n 500000] [-samples 2000] [-scaling 100000,1000000,4000000]
//                     [-scalingsamples 200] [-scenes scenes] [-threads 0] [-quick]
//                     [-cases sphere-marble,...] [-eps 0.03,0.06,...]
//                     [-profilecases sphere-marble,sphere-skin1] [-profilesamples 1000]
//
// Sections (each writes DIR/<section>.tsv, tab separated, one header line;
// meta.tsv gets the settings and the seconds per section):
//  sweep     every cloud/material case (or -cases): ptfilter's hierarchical
//            evaluation (the ssdiffusion() library call) for each
//            -maxsolidangle and each criterion (error, bbox, centroid),
//            classic profile. Errors |h - e| / mean|e| against the exact
//            all-pairs evaluation at -samples random points of the cloud
//            (computed once per case and profile: sweep_refs.tsv), worst
//            colour channel: RMS, 99th percentile, max. Time of the library
//            call, points/s, peak memory it added. cases.tsv describes the
//            clouds.
//  profiles  the same for the better and burley profiles, error criterion,
//            on -profilecases with -profilesamples (profiles_refs.tsv).
//  scaling   the lit marble sphere at each size: the default settings and
//            PRMan's bbox criterion at 1, in the library and as the ptfilter
//            tool (child process: wall time and peak RSS); the error
//            criterion at 0.5 and 2 in the library.
//  model     model error, independent of the evaluation: a uniformly lit
//            plane (E = 1) at point spacings 0.25 ... 8 mean free paths,
//            exact evaluation at the points nearest the centre, divided by
//            the exact integral of the profile over the same square (albedo
//            x E less what lies beyond the square's edge).
//  brick     brickmake -maxerror sweep on the default _ssdiffusion clouds:
//            build time, file size, bricks, lookup error at the points.
//
// Clouds: sphere (make_synthetic_cloud, r = 50 mm, E = max(0, N.L)), the
// teapot bake (scenes/teapot/bake.rib, cm), the thin box with its blocker
// (scenes/thinbox/bake.rib, mm), a rough displaced sphere (a noise-displaced
// mesh baked under a shadowed distant light). Baked clouds get the spacing
// that gives about -n points.
//
// Peak memory: before each call the process's peak RSS is reset to its
// current RSS (Linux /proc/self/clear_refs, after malloc_trim); the figure is
// the peak reached during the call minus the RSS before it: the memory the
// call added on top of its input, which is already in memory.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <numeric>
#include <random>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include <fcntl.h>
#include <malloc.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include "bench_util.h"
#include "latlong_mesh.h"
#include "sss/bake/bake.h"
#include "sss/brick/brickmap.h"
#include "sss/cli/tool.h"
#include "sss/cloud/point_cloud_io.h"
#include "sss/cloud/synthetic.h"
#include "sss/diffusion/ssdiffusion.h"
#include "sss/light/lights.h"
#include "sss/scene/rib.h"
#include "sss/util/error.h"

extern char** environ;

namespace {

constexpr double kPi = 3.14159265358979323846;
const double kNaN = std::nan("");

// ---------------------------------------------------------------------------
// Small helpers
// ---------------------------------------------------------------------------

/// A tab-separated table written row by row (flushed, so a partial run
/// leaves the rows done so far).
class Table {
public:
    Table(const std::string& path, const std::vector<std::string>& columns)
        : m_out(path), m_columns(columns.size()) {
        if (!m_out) throw sss::IoError("cannot write " + path, path);
        for (std::size_t i = 0; i < columns.size(); ++i)
            m_out << (i ? "\t" : "") << columns[i];
        m_out << "\n" << std::flush;
    }
    Table& operator<<(const std::string& s) {
        m_row.push_back(s);
        return *this;
    }
    Table& operator<<(double v) {
        char buf[64];
        if (std::isnan(v))
            std::snprintf(buf, sizeof buf, "nan");
        else
            std::snprintf(buf, sizeof buf, "%.6g", v);
        m_row.push_back(buf);
        return *this;
    }
    Table& operator<<(std::size_t v) {
        m_row.push_back(std::to_string(v));
        return *this;
    }
    void end_row() {
        if (m_row.size() != m_columns)
            throw std::logic_error("table row has the wrong number of columns");
        for (std::size_t i = 0; i < m_row.size(); ++i)
            m_out << (i ? "\t" : "") << m_row[i];
        m_out << "\n" << std::flush;
        m_row.clear();
    }

private:
    std::ofstream m_out;
    std::size_t m_columns;
    std::vector<std::string> m_row;
};

/// A value from /proc/self/status in kB ("VmRSS:", "VmHWM:"), or -1.
long status_kb(const char* key) {
    std::ifstream in("/proc/self/status");
    std::string line;
    const std::size_t n = std::char_traits<char>::length(key);
    while (std::getline(in, line))
        if (line.compare(0, n, key) == 0) return std::atol(line.c_str() + n);
    return -1;
}

/// Peak memory added by a piece of code (see the file comment).
class PeakProbe {
public:
    void start() {
        malloc_trim(0);
        std::ofstream clear("/proc/self/clear_refs");
        clear << "5" << std::flush;
        m_ok = bool(clear);
        m_before = status_kb("VmRSS:");
    }
    double added_mb() const {
        const long hwm = status_kb("VmHWM:");
        if (!m_ok || hwm < 0 || m_before < 0) return kNaN;
        return double(hwm - m_before) / 1024.0;
    }

private:
    bool m_ok = false;
    long m_before = -1;
};

std::vector<std::string> split(const std::string& s, char sep) {
    std::vector<std::string> out;
    std::stringstream ss(s);
    std::string item;
    while (std::getline(ss, item, sep))
        if (!item.empty()) out.push_back(item);
    return out;
}

// ---------------------------------------------------------------------------
// Clouds
// ---------------------------------------------------------------------------

sss::PointCloud lit_sphere(std::size_t n) {
    sss::SyntheticParams sp;
    sp.shape = sss::SyntheticShape::Sphere;
    sp.count = n;
    sp.size = 50.0;
    sp.light_dir = {1, 1, 1};
    return sss::make_synthetic_cloud(sp);
}

sss::PointCloud merged(std::vector<std::pair<std::string, sss::PointCloud>> files) {
    if (files.empty()) throw sss::ValueError("the bake produced no cloud");
    sss::PointCloud out = std::move(files[0].second);
    for (std::size_t i = 1; i < files.size(); ++i) out.append(files[i].second);
    return out;
}

/// Bakes a scene at the spacing that gives about `target` points (within 3 %;
/// trial bakes starting at spacing s0 measure the density).
sss::PointCloud bake_to_count(const sss::Scene& scene, std::size_t target, double s0) {
    sss::BakeOptions o;
    o.spacing = s0;
    sss::BakeReport rep;
    sss::PointCloud cloud = merged(sss::bake_clouds(scene, o, &rep));
    for (int trial = 0; trial < 3; ++trial) {
        const double ratio = double(cloud.size()) / double(target);
        if (std::abs(ratio - 1.0) < 0.03) break;
        o.spacing *= std::sqrt(ratio);
        cloud = merged(sss::bake_clouds(scene, o, &rep));
    }
    return cloud;
}

/// A rough surface: a sphere of radius 50 mm displaced along its normal by
/// three octaves of noise (amplitude 2 mm, wavelengths 12, 6 and 3 mm), as a
/// polygon mesh with vertex normals, lit by a shadowed distant light and a
/// little ambient light.
std::string rough_scene_text() {
    const int rings = 300, segments = 600;
    const double radius = 50.0, amplitude = 2.0;
    auto height = [&](const glm::dvec3& d) {
        const glm::dvec3 p = d * radius;
        double h = 0, a = 1, total = 0;
        for (double wavelength : {12.0, 6.0, 3.0}) {
            h += a * (2.0 * sss::noise3(p / wavelength + glm::dvec3(17.0 * a)) - 1.0);
            total += a;
            a *= 0.5;
        }
        return amplitude * h / total;
    };
    auto dir = [&](int j, int i) {
        const double th = kPi * j / rings, ph = 2 * kPi * i / segments;
        return glm::dvec3(std::sin(th) * std::cos(ph), std::cos(th),
                          std::sin(th) * std::sin(ph));
    };
    auto point = [&](int j, int i) {
        const glm::dvec3 d = dir(j, i);
        return d * (radius + height(d));
    };
    // Vertices: north pole, rings 1..rings-1, south pole.
    std::vector<glm::dvec3> v, n;
    auto add = [&](int j, int i) {
        v.push_back(point(j, i));
        if (j == 0 || j == rings) {
            n.push_back(dir(j, i));
            return;
        }
        // Normal from central differences on the grid (outward).
        const glm::dvec3 du = point(j, i + 1) - point(j, i - 1);
        const glm::dvec3 dv = point(j + 1, i) - point(j - 1, i);
        glm::dvec3 nn = glm::normalize(glm::cross(dv, du));
        if (glm::dot(nn, dir(j, i)) < 0) nn = -nn;
        n.push_back(nn);
    };
    add(0, 0);
    for (int j = 1; j < rings; ++j)
        for (int i = 0; i < segments; ++i) add(j, i);
    add(rings, 0);
    std::ostringstream rib;
    rib.precision(8);
    rib << "Format 512 512 1\nProjection \"perspective\" \"fov\" 40\n"
           "Translate 0 0 200\nWorldBegin\n"
           "LightSource \"ambientlight\" 1 \"intensity\" [0.05]\n"
           "LightSource \"distantlight\" 2 \"from\" [1 1 1] \"to\" [0 0 0] "
           "\"intensity\" [1] \"string shadowname\" [\"raytrace\"]\n"
           "Surface \"bake_radiance_t\" \"string filename\" [\"rough.ptc\"]\n";
    rib << bench::latlong_points_polygons(v, n, rings, segments);
    rib << "WorldEnd\n";
    return rib.str();
}

/// One cloud with one material.
struct Case {
    std::string name;     ///< "sphere-marble"
    std::string cloud;    ///< "sphere"
    std::string material; ///< preset name
    double unitlength = 1.0;
    std::string units; ///< "mm" / "cm"
    std::string description;
};

const std::vector<Case>& all_cases() {
    static const std::vector<Case> cases = {
        {"sphere-marble", "sphere", "marble", 1.0, "mm",
         "sphere r = 50 mm, E = max(0, N.L)"},
        {"sphere-skin1", "sphere", "skin1", 1.0, "mm",
         "the same sphere with skin1 (short mean free path)"},
        {"teapot-marble", "teapot", "marble", 0.1, "cm",
         "scenes/teapot/bake.rib: two point lights, one ray-traced shadow, soft "
         "back light"},
        {"thinbox-skin1", "thinbox", "skin1", 1.0, "mm",
         "scenes/thinbox/bake.rib: 30 x 4 x 30 mm slab, shadowed distant light, "
         "torus blocker baked with E = -1"},
        {"rough-marble", "rough", "marble", 1.0, "mm",
         "sphere r = 50 mm displaced by 3 octaves of noise (2 mm, 3-12 mm "
         "wavelengths), shadowed distant light + 0.05 ambient"},
    };
    return cases;
}

class Clouds {
public:
    Clouds(std::string scenes, std::size_t n) : m_scenes(std::move(scenes)), m_n(n) {}
    const sss::PointCloud& get(const std::string& name) {
        auto it = m_clouds.find(name);
        if (it != m_clouds.end()) return *it->second;
        sss::Stopwatch w;
        auto cloud = std::make_unique<sss::PointCloud>(make(name));
        m_seconds[name] = w.seconds();
        std::fprintf(stderr, "  cloud %s: %zu points in %.1f s\n", name.c_str(),
                     cloud->size(), m_seconds[name]);
        return *(m_clouds[name] = std::move(cloud));
    }
    /// Seconds it took to make (or bake) a cloud.
    double seconds(const std::string& name) const { return m_seconds.at(name); }
    void drop(const std::string& name) { m_clouds.erase(name); }

private:
    sss::PointCloud make(const std::string& name) {
        if (name == "sphere") return lit_sphere(m_n);
        if (name == "teapot")
            return bake_to_count(sss::read_rib(m_scenes + "/teapot/bake.rib"), m_n, 0.05);
        if (name == "thinbox")
            return bake_to_count(sss::read_rib(m_scenes + "/thinbox/bake.rib"), m_n, 0.5);
        if (name == "rough")
            return bake_to_count(sss::parse_rib(rough_scene_text(), "rough.rib"), m_n,
                                 0.25);
        throw sss::UsageError("unknown cloud " + name);
    }
    std::string m_scenes;
    std::size_t m_n;
    std::map<std::string, std::unique_ptr<sss::PointCloud>> m_clouds;
    std::map<std::string, double> m_seconds;
};

// ---------------------------------------------------------------------------
// Evaluation, reference and errors
// ---------------------------------------------------------------------------

sss::SsDiffusionOptions options_for(const std::string& material, double unitlength,
                                    sss::ProfileKind profile, sss::Criterion criterion,
                                    double eps) {
    sss::SsDiffusionOptions o;
    o.material.preset = material;
    o.material.unitlength = unitlength;
    o.profile = profile;
    o.diffusion.criterion = criterion;
    o.diffusion.max_solid_angle = eps;
    return o;
}

/// The problem ssdiffusion() solves for a constant preset material (the same
/// channels, areas and profiles), for the exact reference.
sss::DiffusionProblem make_problem(const sss::PointCloud& c,
                                   const sss::SsDiffusionOptions& o) {
    sss::DiffusionProblem pb = sss_bench::cloud_problem(c);
    glm::dvec3 ss, sa;
    o.material.resolve_coefficients(ss, sa);
    const double u = o.material.unitlength, ior = o.material.resolved_ior();
    for (int ch = 0; ch < 3; ++ch)
        pb.profiles.push_back(
            sss::Profile::from_coefficients(o.profile, {ss[ch] / u, sa[ch] / u, ior}));
    return pb;
}

struct Reference {
    std::vector<std::size_t> samples;
    std::vector<glm::dvec3> exact;
    glm::dvec3 mean_abs{0.0};
    double seconds = 0;
};

Reference reference(const sss::PointCloud& cloud, const sss::SsDiffusionOptions& o,
                    std::size_t count) {
    Reference r;
    r.samples = sss_bench::random_samples(cloud.size(), count, 12345);
    sss::DiffusionProblem pb = make_problem(cloud, o);
    sss::Stopwatch w;
    r.exact = sss::evaluate_diffusion_exact(pb, r.samples);
    r.seconds = w.seconds();
    for (const glm::dvec3& e : r.exact)
        r.mean_abs += glm::abs(e) / double(r.exact.size());
    return r;
}

struct Errors {
    double rms = 0, p99 = 0, max = 0; ///< fractions of mean|e|, worst channel
    double bias = 0; ///< mean signed (h - e) / mean|e|, the channel farthest from 0
};

Errors compare(const sss::PointCloud& out, const Reference& ref) {
    const sss::Channel* c = out.find_channel("_ssdiffusion");
    Errors worst;
    std::vector<double> d(ref.samples.size());
    for (int ch = 0; ch < 3; ++ch) {
        double se = 0, sum = 0;
        for (std::size_t k = 0; k < ref.samples.size(); ++k) {
            const double signed_d =
                (double(c->data[3 * ref.samples[k] + ch]) - ref.exact[k][ch]) /
                ref.mean_abs[ch];
            d[k] = std::abs(signed_d);
            sum += signed_d;
            se += d[k] * d[k];
        }
        const double bias = sum / double(d.size());
        if (std::abs(bias) > std::abs(worst.bias)) worst.bias = bias;
        std::sort(d.begin(), d.end());
        worst.rms = std::max(worst.rms, std::sqrt(se / double(d.size())));
        worst.p99 =
            std::max(worst.p99, d[std::size_t(std::ceil(0.99 * double(d.size()))) - 1]);
        worst.max = std::max(worst.max, d.back());
    }
    return worst;
}

struct Timed {
    double seconds = 0;
    double peak_mb = 0;
    sss::SsDiffusionReport report;
    sss::PointCloud out;
};

/// One library call, timed (the fastest of 3 when a call takes under 0.5 s)
/// with the memory it added.
Timed run_ssdiffusion(const sss::PointCloud& in, const sss::SsDiffusionOptions& o) {
    Timed t;
    PeakProbe probe;
    probe.start();
    sss::Stopwatch w;
    t.out = sss::ssdiffusion(in, o, &t.report);
    t.seconds = w.seconds();
    t.peak_mb = probe.added_mb();
    for (int rep = 1; rep < 3 && t.seconds < 0.5; ++rep) {
        t.out = sss::PointCloud();
        sss::Stopwatch w2;
        t.out = sss::ssdiffusion(in, o, &t.report);
        t.seconds = std::min(t.seconds, w2.seconds());
    }
    return t;
}

// ---------------------------------------------------------------------------
// Sections
// ---------------------------------------------------------------------------

struct Settings {
    std::string out_dir;
    std::string scenes = "scenes";
    std::size_t n = 500000;
    std::size_t samples = 2000;
    std::vector<std::size_t> scaling = {100000, 1000000, 4000000};
    std::size_t scaling_samples = 200;
    std::vector<double> eps = {0.03, 0.06, 0.125, 0.25, 0.5, 1, 2, 4, 8, 16};
    std::vector<double> model_spacings = {0.25, 0.5, 1, 2, 4, 8};
    std::vector<double> max_errors = {0.0005, 0.001, 0.002, 0.005, 0.01, 0.02, 0.05};
    std::vector<std::string> cases; ///< empty: all
    /// The profile sweep runs on these cases, with this many samples.
    std::vector<std::string> profile_cases = {"sphere-marble", "sphere-skin1"};
    std::size_t profile_samples = 1000;
    int threads = 1;
};

const std::vector<std::string> kSweepColumns = {"case",
                                                "profile",
                                                "criterion",
                                                "maxsolidangle",
                                                "points",
                                                "seconds",
                                                "points_per_s",
                                                "rms_pct",
                                                "p99_pct",
                                                "max_pct",
                                                "peak_mb",
                                                "far_terms_per_point",
                                                "near_terms_per_point",
                                                "bias_pct"};

void sweep_row(Table& t, const Case& c, sss::ProfileKind profile, sss::Criterion crit,
               double eps, const sss::PointCloud& cloud, const Timed& r,
               const Errors& e) {
    const double n = double(cloud.size());
    t << c.name << sss::profile_kind_name(profile) << sss::criterion_name(crit) << eps
      << cloud.size() << r.seconds << n / r.seconds << 100 * e.rms << 100 * e.p99
      << 100 * e.max << r.peak_mb << double(r.report.stats.far_terms) / n
      << double(r.report.stats.near_terms) / n << 100 * e.bias;
    t.end_row();
}

/// The maxsolidangle sweep of one case for the given profiles and criteria;
/// one exact reference per profile.
void sweep_case(const Settings& s, Clouds& clouds, const Case& c,
                const std::vector<sss::ProfileKind>& profiles,
                const std::vector<sss::Criterion>& criteria, Table& out, Table& refs) {
    const sss::PointCloud& cloud = clouds.get(c.cloud);
    for (sss::ProfileKind p : profiles) {
        Reference ref = reference(
            cloud, options_for(c.material, c.unitlength, p, sss::Criterion::Error, 1),
            p == sss::ProfileKind::Classic ? s.samples : s.profile_samples);
        std::fprintf(stderr, "  %s %s: exact at %zu points in %.1f s\n", c.name.c_str(),
                     sss::profile_kind_name(p), ref.samples.size(), ref.seconds);
        refs << c.name << sss::profile_kind_name(p) << ref.samples.size() << cloud.size()
             << ref.seconds << ref.mean_abs.x << ref.mean_abs.y << ref.mean_abs.z;
        refs.end_row();
        for (sss::Criterion crit : criteria)
            for (double eps : s.eps) {
                Timed r = run_ssdiffusion(
                    cloud, options_for(c.material, c.unitlength, p, crit, eps));
                Errors e = compare(r.out, ref);
                std::fprintf(stderr,
                             "    %-8s %-8s %6g  %8.3f s  rms %7.3f %%  max %8.3f %%\n",
                             sss::profile_kind_name(p), sss::criterion_name(crit), eps,
                             r.seconds, 100 * e.rms, 100 * e.max);
                sweep_row(out, c, p, crit, eps, cloud, r, e);
            }
    }
}

const std::vector<std::string> kCaseColumns = {
    "case",   "cloud",  "material", "unitlength",    "units",
    "points", "area",   "spacing",  "bbox_diagonal", "dmfp_r",
    "dmfp_g", "dmfp_b", "mfp_min",  "cloud_seconds", "description"};

/// One row of cases.tsv: the cloud and the material's lengths in scene units.
void case_row(Table& t, const Case& c, const sss::PointCloud& cloud, double cloud_s) {
    double area = 0;
    for (float a : cloud.find_channel("_area")->data) area += a;
    const sss::Bounds3 b = cloud.bounds();
    sss::SsDiffusionOptions o = options_for(
        c.material, c.unitlength, sss::ProfileKind::Classic, sss::Criterion::Error, 1);
    glm::dvec3 ss, sa;
    o.material.resolve_coefficients(ss, sa);
    double mfp_min = 1e300;
    glm::dvec3 dmfp;
    for (int ch = 0; ch < 3; ++ch) {
        sss::Profile p = sss::Profile::from_coefficients(
            o.profile,
            {ss[ch] / c.unitlength, sa[ch] / c.unitlength, o.material.resolved_ior()});
        dmfp[ch] = p.dmfp();
        mfp_min = std::min(mfp_min, c.unitlength / (ss[ch] + sa[ch]));
    }
    t << c.name << c.cloud << c.material << c.unitlength << c.units << cloud.size()
      << area << std::sqrt(area / double(cloud.size()))
      << double(glm::length(b.hi - b.lo)) << dmfp.x << dmfp.y << dmfp.z << mfp_min
      << cloud_s << c.description;
    t.end_row();
}

void section_sweep(const Settings& s, Clouds& clouds, bool profiles) {
    Table out(s.out_dir + (profiles ? "/profiles.tsv" : "/sweep.tsv"), kSweepColumns);
    Table refs(s.out_dir + (profiles ? "/profiles_refs.tsv" : "/sweep_refs.tsv"),
               {"case", "profile", "samples", "points", "exact_seconds", "mean_abs_r",
                "mean_abs_g", "mean_abs_b"});
    std::unique_ptr<Table> cases;
    if (!profiles)
        cases = std::make_unique<Table>(s.out_dir + "/cases.tsv", kCaseColumns);
    std::string last_cloud;
    const std::vector<std::string>& only = profiles ? s.profile_cases : s.cases;
    for (const Case& c : all_cases()) {
        if (!only.empty() && std::find(only.begin(), only.end(), c.name) == only.end())
            continue;
        if (!last_cloud.empty() && last_cloud != c.cloud) clouds.drop(last_cloud);
        last_cloud = c.cloud;
        std::fprintf(stderr, "%s %s\n", profiles ? "profiles" : "sweep", c.name.c_str());
        if (cases) {
            const sss::PointCloud& cloud = clouds.get(c.cloud);
            case_row(*cases, c, cloud, clouds.seconds(c.cloud));
        }
        if (profiles)
            sweep_case(s, clouds, c, {sss::ProfileKind::Better, sss::ProfileKind::Burley},
                       {sss::Criterion::Error}, out, refs);
        else
            sweep_case(s, clouds, c, {sss::ProfileKind::Classic},
                       {sss::Criterion::Error, sss::Criterion::SolidAngleBox,
                        sss::Criterion::SolidAngleCentroid},
                       out, refs);
    }
    if (!last_cloud.empty()) clouds.drop(last_cloud);
}

/// Runs ptfilter as a child process with -progress 2: wall seconds and the
/// peak RSS (MB) it reports itself, or NaN. (Not wait4's ru_maxrss: a child
/// spawned from this bench starts with the bench's own pages counted.)
std::pair<double, double> run_tool_child(std::vector<std::string> argv,
                                         const std::string& log) {
    argv.insert(argv.begin() + 1, {"-progress", "2"});
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, log.c_str(),
                                     O_WRONLY | O_CREAT | O_TRUNC, 0644);
    sss::Stopwatch w;
    pid_t pid = 0;
    const int spawned =
        posix_spawn(&pid, args[0], &actions, nullptr, args.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (spawned != 0) return {kNaN, kNaN};
    int status = 0;
    if (waitpid(pid, &status, 0) != pid || !WIFEXITED(status) || WEXITSTATUS(status) != 0)
        return {kNaN, kNaN};
    const double seconds = w.seconds();
    std::ifstream in(log);
    std::string line;
    double mb = kNaN; // the tool prints 10^6 bytes; this table is in 2^20
    while (std::getline(in, line))
        if (std::sscanf(line.c_str(), "ptfilter: peak memory %lf MB", &mb) == 1)
            mb = mb * 1e6 / 1048576.0;
    return {seconds, mb};
}

void section_scaling(const Settings& s) {
    Table t(s.out_dir + "/scaling.tsv",
            {"points", "criterion", "maxsolidangle", "seconds", "points_per_s", "rms_pct",
             "p99_pct", "max_pct", "peak_mb", "far_terms_per_point", "tool_seconds",
             "tool_peak_mb"});
    const std::string bin =
        std::filesystem::canonical("/proc/self/exe").parent_path().string();
    const std::string dir =
        (std::filesystem::temp_directory_path() / "sss_speed_error").string();
    std::filesystem::create_directories(dir);
    // The default and PRMan's default also as the ptfilter tool; the default
    // criterion's neighbours in the library only.
    const std::vector<std::tuple<sss::Criterion, double, bool>> runs = {
        {sss::Criterion::Error, 1.0, true},
        {sss::Criterion::SolidAngleBox, 1.0, true},
        {sss::Criterion::Error, 0.5, false},
        {sss::Criterion::Error, 2.0, false}};
    for (std::size_t n : s.scaling) {
        std::fprintf(stderr, "scaling %zu\n", n);
        sss::PointCloud cloud = lit_sphere(n);
        const std::string in = dir + "/sphere.ptc", out = dir + "/sphere_ssd.ptc";
        sss::write_point_cloud(cloud, in);
        Reference ref = reference(
            cloud,
            options_for("marble", 1, sss::ProfileKind::Classic, sss::Criterion::Error, 1),
            s.scaling_samples);
        for (auto [crit, eps, tool] : runs) {
            Timed r = run_ssdiffusion(
                cloud, options_for("marble", 1, sss::ProfileKind::Classic, crit, eps));
            Errors e = compare(r.out, ref);
            r.out = sss::PointCloud();
            double tool_s = kNaN, tool_mb = kNaN;
            if (tool) {
                char eps_text[32];
                std::snprintf(eps_text, sizeof eps_text, "%g", eps);
                std::tie(tool_s, tool_mb) =
                    run_tool_child({bin + "/ptfilter", "-ssdiffusion", "-material",
                                    "marble", "-criterion", sss::criterion_name(crit),
                                    "-maxsolidangle", eps_text, in, out},
                                   dir + "/ptfilter.log");
            }
            std::fprintf(
                stderr, "  %-8s %4g %8.3f s (tool %.3f s, %.0f MB)  rms %.3f %%\n",
                sss::criterion_name(crit), eps, r.seconds, tool_s, tool_mb, 100 * e.rms);
            t << cloud.size() << sss::criterion_name(crit) << eps << r.seconds
              << double(n) / r.seconds << 100 * e.rms << 100 * e.p99 << 100 * e.max
              << r.peak_mb << double(r.report.stats.far_terms) / double(n) << tool_s
              << tool_mb;
            t.end_row();
        }
    }
    std::filesystem::remove_all(dir);
}

/// Exact integral of a profile over the square [-L/2, L/2]^2 seen from x
/// (E = 1): (1 / 2 pi) int disk(rho(theta)) dtheta, rho the distance to the
/// square's edge along theta.
double square_integral(const sss::Profile& p, double side, glm::dvec2 x) {
    const int steps = 8192;
    const double h = 0.5 * side;
    double sum = 0;
    for (int k = 0; k < steps; ++k) {
        const double th = 2 * kPi * (k + 0.5) / steps;
        const double c = std::cos(th), sn = std::sin(th);
        double rho = 1e300;
        if (c > 0) rho = std::min(rho, (h - x.x) / c);
        if (c < 0) rho = std::min(rho, (-h - x.x) / c);
        if (sn > 0) rho = std::min(rho, (h - x.y) / sn);
        if (sn < 0) rho = std::min(rho, (-h - x.y) / sn);
        sum += p.disk(rho);
    }
    return sum / steps;
}

void section_model(const Settings& s) {
    Table t(s.out_dir + "/model.tsv",
            {"material", "profile", "jitter", "spacing_over_mfp", "spacing_mm", "points",
             "side_mm", "receivers", "channel", "spacing_over_zr", "dmfp_over_spacing",
             "ratio_median", "ratio_min", "ratio_max", "square_over_albedo"});
    const int kReceivers = 25;
    for (const char* material : {"marble", "skin1"}) {
        const sss::NamedMaterial* m = sss::find_material(material);
        double mfp_min = 1e300, dmfp_max = 0;
        for (int ch = 0; ch < 3; ++ch) {
            mfp_min = std::min(mfp_min, 1.0 / (m->sigma_s_prime[ch] + m->sigma_a[ch]));
            dmfp_max =
                std::max(dmfp_max, sss::albedo_dmfp_from_coefficients(
                                       {m->sigma_s_prime[ch], m->sigma_a[ch], m->ior})
                                       .dmfp);
        }
        const double target_side = 16.0 * dmfp_max;
        for (double f : s.model_spacings) {
            const double h = f * mfp_min;
            const std::size_t per_side =
                std::max<std::size_t>(8, std::size_t(std::round(target_side / h)));
            const double side = double(per_side) * h;
            for (double jitter : {0.0, 0.5}) {
                sss::SyntheticParams sp;
                sp.shape = sss::SyntheticShape::Plane;
                sp.count = per_side * per_side;
                sp.size = side;
                sp.jitter = jitter;
                sp.light_dir = {0, 0, 1};
                sss::PointCloud cloud = sss::make_synthetic_cloud(sp);
                // The points nearest the centre.
                std::vector<std::size_t> idx(cloud.size());
                std::iota(idx.begin(), idx.end(), std::size_t(0));
                const std::size_t k = std::min<std::size_t>(kReceivers, idx.size());
                std::partial_sort(
                    idx.begin(), idx.begin() + k, idx.end(),
                    [&](std::size_t a, std::size_t b) {
                        return glm::dot(cloud.positions[a], cloud.positions[a]) <
                               glm::dot(cloud.positions[b], cloud.positions[b]);
                    });
                idx.resize(k);
                for (sss::ProfileKind prof :
                     {sss::ProfileKind::Classic, sss::ProfileKind::Better,
                      sss::ProfileKind::Burley}) {
                    sss::DiffusionProblem pb = make_problem(
                        cloud, options_for(material, 1, prof, sss::Criterion::Error, 1));
                    std::vector<glm::dvec3> exact =
                        sss::evaluate_diffusion_exact(pb, idx);
                    for (int ch = 0; ch < 3; ++ch) {
                        const sss::Profile& p = pb.profiles[ch];
                        std::vector<double> ratio;
                        for (std::size_t r = 0; r < k; ++r) {
                            const glm::vec3 x = cloud.positions[idx[r]];
                            ratio.push_back(exact[r][ch] /
                                            square_integral(p, side, {x.x, x.y}));
                        }
                        std::sort(ratio.begin(), ratio.end());
                        const double zr = 1.0 / (m->sigma_s_prime[ch] + m->sigma_a[ch]);
                        t << std::string(material) << sss::profile_kind_name(prof)
                          << jitter << f << h << cloud.size() << side << k
                          << std::string(1, "rgb"[ch]) << h / zr << p.dmfp() / h
                          << ratio[k / 2] << ratio.front() << ratio.back()
                          << square_integral(p, side, {0, 0}) / p.total();
                        t.end_row();
                    }
                    if (prof == sss::ProfileKind::Classic && jitter == 0.0)
                        std::fprintf(stderr, "model %s h = %g mfp (%zu points)\n",
                                     material, f, cloud.size());
                }
            }
        }
    }
}

void section_brick(const Settings& s, Clouds& clouds) {
    Table t(s.out_dir + "/brick.tsv",
            {"case", "points", "maxerror", "build_seconds", "peak_mb", "file_mb",
             "bricks", "rms_abs", "p99_abs", "max_abs", "rms_pct", "p99_pct", "max_pct",
             "misses", "mean_value"});
    const std::string path =
        (std::filesystem::temp_directory_path() / "sss_speed_error.bkm").string();
    for (const char* name : {"sphere-marble", "teapot-marble"}) {
        const Case& c = *std::find_if(all_cases().begin(), all_cases().end(),
                                      [&](const Case& x) { return x.name == name; });
        std::fprintf(stderr, "brick %s\n", name);
        sss::PointCloud cloud =
            sss::ssdiffusion(clouds.get(c.cloud), options_for(c.material, c.unitlength,
                                                              sss::ProfileKind::Classic,
                                                              sss::Criterion::Error, 1));
        clouds.drop(c.cloud);
        const sss::Channel* ssd = cloud.find_channel("_ssdiffusion");
        const std::size_t n = cloud.size();
        glm::dvec3 mean(0.0);
        for (std::size_t i = 0; i < n; ++i)
            for (int ch = 0; ch < 3; ++ch) mean[ch] += std::abs(ssd->data[3 * i + ch]);
        mean /= double(n);
        for (double me : s.max_errors) {
            sss::BrickMapBuildOptions bo;
            bo.max_error = me;
            PeakProbe probe;
            probe.start();
            sss::Stopwatch w;
            sss::BrickMapBuildReport rep = sss::build_brick_map({cloud}, bo, path);
            const double build_s = w.seconds();
            const double peak = probe.added_mb();
            sss::BrickMap map(path);
            const int off = map.channel_offset("_ssdiffusion");
            const int ds = map.info().data_size;
            std::vector<glm::vec3> got(n);
            std::vector<uint8_t> ok(n);
            tbb::parallel_for(std::size_t(0), n, [&](std::size_t i) {
                std::vector<float> v(ds);
                ok[i] = map.lookup(cloud.positions[i], cloud.normals[i], 0.0f, v.data());
                got[i] = {v[off], v[off + 1], v[off + 2]};
            });
            double rms_abs = 0, p99_abs = 0, max_abs = 0, rms = 0, p99 = 0, mx = 0;
            std::size_t misses = 0;
            for (std::size_t i = 0; i < n; ++i) misses += !ok[i];
            std::vector<double> d(n);
            for (int ch = 0; ch < 3; ++ch) {
                double se = 0;
                for (std::size_t i = 0; i < n; ++i) {
                    d[i] = std::abs(double(got[i][ch]) - ssd->data[3 * i + ch]);
                    se += d[i] * d[i];
                }
                std::sort(d.begin(), d.end());
                const double r = std::sqrt(se / double(n));
                const double q = d[std::size_t(std::ceil(0.99 * double(n))) - 1];
                rms_abs = std::max(rms_abs, r);
                p99_abs = std::max(p99_abs, q);
                max_abs = std::max(max_abs, d.back());
                rms = std::max(rms, r / mean[ch]);
                p99 = std::max(p99, q / mean[ch]);
                mx = std::max(mx, d.back() / mean[ch]);
            }
            std::fprintf(stderr, "  maxerror %g: %.2f s, %.1f MB, rms %.5f\n", me,
                         build_s, double(rep.file_size) / 1048576.0, rms_abs);
            t << c.name << n << me << build_s << peak << double(rep.file_size) / 1048576.0
              << rep.bricks_written << rms_abs << p99_abs << max_abs << 100 * rms
              << 100 * p99 << 100 * mx << misses << mean.x;
            t.end_row();
        }
    }
    std::filesystem::remove(path);
}

std::vector<std::size_t> parse_sizes(const std::string& s) {
    std::vector<std::size_t> out;
    for (const std::string& w : split(s, ',')) out.push_back(std::stoull(w));
    return out;
}

int run(const std::vector<std::string>& argv) {
    sss::ArgScanner args(argv);
    Settings s;
    std::string sections = "sweep,profiles,scaling,model,brick";
    int threads = 0;
    bool quick = false;
    while (!args.done()) {
        std::string o = args.option();
        if (o == "out")
            s.out_dir = args.value(o);
        else if (o == "sections")
            sections = args.value(o);
        else if (o == "n")
            s.n = std::size_t(args.positive(o));
        else if (o == "samples")
            s.samples = std::size_t(args.positive(o));
        else if (o == "scaling")
            s.scaling = parse_sizes(args.value(o));
        else if (o == "scalingsamples")
            s.scaling_samples = std::size_t(args.positive(o));
        else if (o == "scenes")
            s.scenes = args.value(o);
        else if (o == "threads")
            threads = args.integer(o, -64, 1024);
        else if (o == "cases")
            s.cases = split(args.value(o), ',');
        else if (o == "profilecases")
            s.profile_cases = split(args.value(o), ',');
        else if (o == "profilesamples")
            s.profile_samples = std::size_t(args.positive(o));
        else if (o == "eps") {
            s.eps.clear();
            for (const std::string& w : split(args.value(o), ','))
                s.eps.push_back(std::stod(w));
        } else if (o == "quick")
            quick = true;
        else
            throw sss::UsageError("unknown option -" + o);
    }
    if (s.out_dir.empty()) throw sss::UsageError("-out DIR is required");
    if (quick) {
        s.n = 30000;
        s.samples = 300;
        s.profile_samples = 300;
        s.scaling = {10000, 30000, 100000};
        s.scaling_samples = 100;
        s.model_spacings = {0.5, 2, 8};
        s.max_errors = {0.002, 0.02};
    }
    std::filesystem::create_directories(s.out_dir);
    s.threads = sss::resolve_thread_count(threads);
    sss::ThreadLimit limit(s.threads);
    sss::Stopwatch total;
    Clouds clouds(s.scenes, s.n);

    std::map<std::string, double> seconds;
    for (const std::string& sec : split(sections, ',')) {
        sss::Stopwatch w;
        if (sec == "sweep")
            section_sweep(s, clouds, false);
        else if (sec == "profiles")
            section_sweep(s, clouds, true);
        else if (sec == "scaling")
            section_scaling(s);
        else if (sec == "model")
            section_model(s);
        else if (sec == "brick")
            section_brick(s, clouds);
        else
            throw sss::UsageError("unknown section " + sec);
        seconds[sec] = w.seconds();
        std::fprintf(stderr, "section %s: %.1f s\n", sec.c_str(), seconds[sec]);
    }
    Table meta(s.out_dir + "/meta.tsv", {"key", "value"});
    auto kv = [&](const std::string& k, const std::string& v) {
        meta << k << v;
        meta.end_row();
    };
    kv("threads", std::to_string(s.threads));
    kv("points", std::to_string(s.n));
    kv("samples", std::to_string(s.samples));
    kv("profile_samples", std::to_string(s.profile_samples));
    kv("scaling_samples", std::to_string(s.scaling_samples));
    for (auto& [k, v] : seconds) kv("seconds_" + k, std::to_string(v));
    kv("seconds_total", std::to_string(total.seconds()));
    return 0;
}

} // namespace

int main(int argc, char** argv) {
    return sss::run_tool("speed_error_bench", argc, argv, run);
}
