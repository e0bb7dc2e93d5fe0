// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file main.cpp
/// ptsynth: writes a synthetic lit point cloud (sphere, plane or box) with
/// `_area` and `_radiance_t` channels, ready for `ptfilter -ssdiffusion`.

#include <climits>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include "sss/cli/tool.h"
#include "sss/cloud/point_cloud_io.h"
#include "sss/cloud/synthetic.h"
#include "sss/util/atomic_output.h"
#include "sss/util/error.h"
#include "sss/util/job_files.h"
#include "sss/util/limits.h"

namespace {

const char* const kTool = "ptsynth";

const char* const kUsage = R"(usage: ptsynth [options] out.ptc|out.ply

Writes a synthetic lit point cloud with known geometry: P, N, radius,
`float _area` (areas add up to the surface area) and
`color _radiance_t` = lightcolor * max(0, N.L) + ambient.

options:
  -shape sphere|plane|box   shape (default sphere)
                              sphere: radius `size` at the origin, Fibonacci lattice
                              plane:  size x size square in z = 0, normal +z
                              box:    size x size x thickness, centred at the origin
  -n count                  approximate number of points (default 100000)
  -size s                   sphere radius / plane and box side (default 50)
  -thickness t              box thickness along z (default 5)
  -jitter f                 plane/box: random offset, fraction of the grid
                            spacing, 0..1 (default 0)
  -seed n                   jitter seed (default 1; output is deterministic)
  -light x y z              direction towards the distant light (default 0 0 1)
  -lightcolor r g b         light colour (default 1 1 1)
  -ambient a                constant irradiance added everywhere (default 0)
  -compress 0|1             gzip the .ptc output (default 0)
  -check                    check the command line only, reading and writing
                            no file: exit 0 if it would run, 2 if not
  -h, --help                this help
  --version                 version information

The output format follows the extension: .ply, anything else is .ptc.
Exit codes: 0 ok, 1 failure, 2 bad command line.
)";

sss::SyntheticShape parse_shape(const std::string& name) {
    if (name == "sphere") return sss::SyntheticShape::Sphere;
    if (name == "plane") return sss::SyntheticShape::Plane;
    if (name == "box") return sss::SyntheticShape::Box;
    throw sss::UsageError("option -shape: unknown shape '" + name +
                          "' (expected sphere, plane or box)");
}

int run(const std::vector<std::string>& args) {
    sss::SyntheticParams params;
    sss::PointCloudWriteOptions write_options;
    std::vector<std::string> positional;

    sss::ArgScanner scan(args);
    std::string opt;
    while (scan.next_option(opt, positional)) {
        if (sss::standard_option(kTool, opt, kUsage)) {
            return 0;
        } else if (opt == "shape") {
            params.shape = parse_shape(scan.value(opt));
        } else if (opt == "n") {
            params.count = static_cast<std::size_t>(scan.integer(opt, 1, INT_MAX));
        } else if (opt == "size") {
            params.size = scan.positive(opt);
        } else if (opt == "thickness") {
            params.thickness = scan.positive(opt);
        } else if (opt == "jitter") {
            params.jitter = scan.non_negative(opt);
            if (params.jitter > 1.0)
                throw sss::UsageError("option -jitter: must be in [0, 1]");
        } else if (opt == "seed") {
            params.seed = static_cast<uint64_t>(scan.integer(opt, 0, INT_MAX));
        } else if (opt == "light") {
            params.light_dir = scan.triple(opt);
            if (params.light_dir == glm::dvec3(0.0))
                throw sss::UsageError("option -light: the direction must not be 0 0 0");
        } else if (opt == "lightcolor") {
            params.light_color = scan.triple(opt);
            if (params.light_color.r < 0 || params.light_color.g < 0 ||
                params.light_color.b < 0)
                throw sss::UsageError("option -lightcolor: components must be >= 0");
        } else if (opt == "ambient") {
            params.ambient = scan.non_negative(opt);
        } else if (opt == "compress") {
            write_options.compress = scan.integer(opt, 0, 1) != 0;
        } else {
            throw sss::unknown_option(opt, kUsage);
        }
    }
    if (positional.empty()) throw sss::UsageError("missing output file");
    if (positional.size() > 1)
        throw sss::UsageError("expected one output file, got " +
                              std::to_string(positional.size()) + " arguments");
    const std::string& output = positional.front();
    if (!sss::has_extension_in(output, sss::point_cloud_extensions()) &&
        !sss::writes_into_existing(output))
        throw sss::UsageError("output " +
                              sss::unknown_extension_text(output, "a point cloud file",
                                                          sss::point_cloud_extensions()));
    if (sss::check_only()) return 0;
    sss::check_output_target(output);

    sss::Stopwatch watch;
    sss::PointCloud cloud;
    {
        sss::ScopedStage stage("making the point cloud");
        cloud = sss::make_synthetic_cloud(params);
    }
    // Printed before the file is committed: if standard output cannot take
    // it, the job fails and the file is left as it was.
    std::printf("%s: writing %zu points to %s (made in %.2f s)\n", kTool, cloud.size(),
                output.c_str(), watch.seconds());
    sss::flush_standard_output();
    sss::ScopedStage stage("writing " + output);
    sss::write_point_cloud(cloud, output, write_options);
    return 0;
}

} // namespace

int main(int argc, char** argv) {
    return sss::run_tool(kTool, argc, argv, run);
}
