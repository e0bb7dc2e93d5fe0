// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// ptbake benchmark: a ~1M-point bake of a mesh lit by 25 shadowed distant
// lights (a dome, as a light-probe conversion gives), timed by stage, with the
// irradiance error against an exact reference.
//
// Scene: a sphere of radius 1 given as a polygon mesh (PointsPolygons with
// vertex normals) resting on an 8 x 8 ground plate, both baked. The reference
// irradiance of a point is sum_l Cl max(0, N.L) V, with V = 1 on the (convex)
// sphere and, on the plate, V computed analytically against the true sphere.
// The difference measures what the bake gets wrong: the polygonal sphere's
// shadow outline, terminator self-shadowing and ray offsets.
//
// usage: bake_bench [-n POINTS] [-lights N] [-faces N] [-threads N]

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>

#include <glm/geometric.hpp>

#include "latlong_mesh.h"
#include "sss/bake/bake.h"
#include "sss/scene/rib.h"
#include "sss/util/progress.h"
#include "sss/util/threads.h"

namespace {

const double kPi = 3.14159265358979323846;

struct DomeLight {
    glm::dvec3 to_light; // unit
    double intensity;
};

std::vector<DomeLight> dome(int n) {
    // Fibonacci directions over the upper hemisphere, elevation >= ~10 degrees.
    std::vector<DomeLight> out;
    const double golden = kPi * (3.0 - std::sqrt(5.0));
    for (int i = 0; i < n; ++i) {
        double y = 0.17 + 0.83 * (i + 0.5) / n;
        double r = std::sqrt(1.0 - y * y);
        double phi = golden * i;
        out.push_back({{r * std::cos(phi), y, r * std::sin(phi)}, 2.0 / n});
    }
    return out;
}

std::string scene_text(const std::vector<DomeLight>& lights, int rings, int segments) {
    std::ostringstream rib;
    rib.precision(9);
    rib << "Format 640 480 1\nProjection \"perspective\" \"fov\" 40\n"
           "Translate 0 0 8\nWorldBegin\n";
    int handle = 1;
    for (const DomeLight& l : lights)
        rib << "LightSource \"distantlight_rts\" " << handle++ << " \"from\" ["
            << l.to_light.x << ' ' << l.to_light.y << ' ' << l.to_light.z
            << "] \"to\" [0 0 0] \"intensity\" [" << l.intensity << "]\n";
    rib << "Surface \"bake_radiance_t\" \"string filename\" [\"bench.ptc\"]\n";
    // Sphere mesh: poles + (rings - 1) rings of `segments` vertices.
    std::vector<glm::dvec3> v;
    v.push_back({0, 1, 0});
    for (int j = 1; j < rings; ++j) {
        double th = kPi * j / rings;
        for (int i = 0; i < segments; ++i) {
            double ph = 2 * kPi * i / segments;
            v.push_back(
                {std::sin(th) * std::cos(ph), std::cos(th), std::sin(th) * std::sin(ph)});
        }
    }
    v.push_back({0, -1, 0});
    rib << bench::latlong_points_polygons(v, v, rings, segments);  // unit sphere: N = P
    rib << "Polygon \"P\" [-4 -1 -4  -4 -1 4  4 -1 4  4 -1 -4]\n"; // faces +y
    rib << "WorldEnd\n";
    return rib.str();
}

// Does the ray p + t d (t > 0) hit the unit sphere at the origin?
bool hits_unit_sphere(const glm::dvec3& p, const glm::dvec3& d) {
    double b = glm::dot(p, d);
    double c = glm::dot(p, p) - 1.0;
    double disc = b * b - c;
    if (disc < 0.0) return false;
    if (c <= 0.0) return true;         // starts inside or on the sphere
    return -b - std::sqrt(disc) > 0.0; // the near intersection is ahead
}

} // namespace

int main(int argc, char** argv) {
    double target = 1e6;
    int nlights = 25, threads = 0, segments = 160;
    for (int i = 1; i + 1 < argc; i += 2) {
        std::string o = argv[i];
        if (o == "-n")
            target = std::atof(argv[i + 1]);
        else if (o == "-lights")
            nlights = std::atoi(argv[i + 1]);
        else if (o == "-faces")
            segments = std::max(8, int(std::sqrt(std::atof(argv[i + 1]) * 2)));
        else if (o == "-threads")
            threads = std::atoi(argv[i + 1]);
        else {
            std::fprintf(
                stderr,
                "usage: bake_bench [-n POINTS] [-lights N] [-faces N] [-threads N]\n");
            return 2;
        }
    }
    const int rings = segments / 2;
    sss::ThreadLimit limit(sss::resolve_thread_count(threads));
    const std::vector<DomeLight> lights = dome(nlights);

    sss::Stopwatch parse_watch;
    sss::Scene scene = sss::parse_rib(scene_text(lights, rings, segments), "bench.rib");
    const double parse_s = parse_watch.seconds();

    sss::BakeOptions opt;
    const double area = 4 * kPi + 64.0; // about: the mesh sphere is a little smaller
    opt.spacing = std::sqrt(area / target);
    sss::BakeReport report;
    sss::Stopwatch watch;
    auto files = sss::bake_clouds(scene, opt, &report);
    const double bake_s = watch.seconds();
    const sss::PointCloud& cloud = files.at(0).second;

    sss::Stopwatch write_watch;
    sss::write_point_cloud(cloud, "/tmp/sss_bake_bench.ptc");
    const double write_s = write_watch.seconds();
    std::remove("/tmp/sss_bake_bench.ptc");

    // Reference and error.
    const sss::Channel* rad = cloud.find_channel("_radiance_t");
    double sum2 = 0, sum_ref = 0, worst = 0;
    std::size_t rays = 0, mismatched = 0;
    std::size_t plate_points = 0, plate_bad = 0, sphere_bad = 0;
    double plate_sum2 = 0, sphere_sum2 = 0;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        glm::dvec3 p(cloud.positions[i]), n(cloud.normals[i]);
        bool plate = p.y < -0.999 && std::abs(n.y - 1.0) < 1e-6;
        double ref = 0;
        for (const DomeLight& l : lights) {
            double c = glm::dot(n, l.to_light);
            if (c <= 0) continue;
            ++rays;
            bool visible = !plate || !hits_unit_sphere(p, l.to_light);
            ref += visible ? l.intensity * c : 0.0;
        }
        double got = rad->data[3 * i];
        double e = got - ref;
        sum2 += e * e;
        sum_ref += ref;
        const bool bad = std::abs(e) > 0.05 * 2.0 / nlights; // off by > 5% of one light
        mismatched += bad;
        if (plate) {
            ++plate_points;
            plate_bad += bad;
            plate_sum2 += e * e;
        } else {
            sphere_bad += bad;
            sphere_sum2 += e * e;
        }
        worst = std::max(worst, std::abs(e));
    }
    const double mean_ref = sum_ref / cloud.size();
    std::printf(
        "bake_bench: %zu points, %d shadowed distant lights, %zu triangles, %d threads\n",
        cloud.size(), nlights, report.occluder_triangles,
        sss::resolve_thread_count(threads));
    std::printf("  parse %.3f s, dice %.3f s, embree build %.3f s, light %.3f s "
                "(%.1f M shadow rays, %.1f M rays/s), write %.3f s\n",
                parse_s, report.dice_seconds, report.trace_build_seconds,
                report.light_seconds, rays * 1e-6, rays * 1e-6 / report.light_seconds,
                write_s);
    std::printf("  bake total %.3f s (parse + bake + write %.3f s)\n", bake_s,
                parse_s + bake_s + write_s);
    std::printf(
        "  irradiance error vs exact: RMS %.3f %% of mean, max %.3f of mean %.3f; "
        "%.3f %% of points off by more than 5 %% of one light\n",
        100.0 * std::sqrt(sum2 / cloud.size()) / mean_ref, worst, mean_ref,
        100.0 * mismatched / cloud.size());
    const std::size_t sphere_points = cloud.size() - plate_points;
    std::printf(
        "  plate %zu points: RMS %.3f %%, %.3f %% off; sphere %zu points: RMS %.3f %%, "
        "%.3f %% off\n",
        plate_points, 100.0 * std::sqrt(plate_sum2 / plate_points) / mean_ref,
        100.0 * plate_bad / plate_points, sphere_points,
        100.0 * std::sqrt(sphere_sum2 / std::max<std::size_t>(1, sphere_points)) /
            mean_ref,
        100.0 * sphere_bad / std::max<std::size_t>(1, sphere_points));
    return 0;
}
