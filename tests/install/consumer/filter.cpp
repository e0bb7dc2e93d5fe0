// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// Filters a point cloud through the installed library, as
// `ptfilter -ssdiffusion -material M -unitlength U in out` does:
//   filter in.ptc out.ptc MATERIAL UNITLENGTH
#include <cstdio>
#include <exception>
#include <string>

#include <sss/cloud/point_cloud_io.h>
#include <sss/diffusion/ssdiffusion.h>

int main(int argc, char** argv) {
    if (argc != 5) {
        std::fprintf(stderr, "usage: filter in.ptc out.ptc MATERIAL UNITLENGTH\n");
        return 2;
    }
    try {
        sss::SsDiffusionOptions options;
        options.material.preset = argv[3];
        options.material.unitlength = std::stod(argv[4]);
        const sss::PointCloud out =
            sss::ssdiffusion(sss::read_point_cloud(argv[1]), options);
        sss::write_point_cloud(out, argv[2]);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "filter ERROR: %s\n", e.what());
        return 1;
    }
    return 0;
}
