// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file main.cpp
/// ptinfo: prints what is in point cloud files (.ptc or .ply): format,
/// point count, bounding box, header matrices, channels and per-channel
/// statistics. The counterpart of `ptviewer -info` and 3Delight `ptcview -info`.

#include <iostream>
#include <string>
#include <vector>

#include "sss/cli/tool.h"
#include "sss/cloud/point_cloud_io.h"
#include "sss/util/error.h"

namespace {

const char* const kTool = "ptinfo";

const char* const kUsage = R"(usage: ptinfo [options] file...

Prints, for each point cloud file (.ply, anything else is read as .ptc):
path, format and version, whether it is gzip-compressed, point count,
bounding box, world2eye / world2ndc / image format when they are not the
defaults, every channel as "<type> <name>" and, with -stats 1, the
min / mean / max of each channel component and of the radius.

options:
  -stats 0|1     print per-channel statistics (default 1)
  -check         check the command line only, reading and writing
                 no file: exit 0 if it would run, 2 if not
  -h, --help     this help
  --version      version information

Exit codes: 0 ok, 1 unreadable or invalid file, 2 bad command line.
)";

int run(const std::vector<std::string>& args) {
    bool stats = true;
    std::vector<std::string> files;

    sss::ArgScanner scan(args);
    std::string opt;
    while (scan.next_option(opt, files)) {
        if (sss::standard_option(kTool, opt, kUsage)) {
            return 0;
        } else if (opt == "stats") {
            stats = scan.integer(opt, 0, 1) != 0;
        } else {
            throw sss::unknown_option(opt, kUsage);
        }
    }
    if (files.empty()) throw sss::UsageError("missing input file");
    if (sss::check_only()) return 0;

    for (std::size_t i = 0; i < files.size(); ++i) {
        sss::ScopedStage stage("reading " + files[i]);
        const sss::PointCloud cloud = sss::read_point_cloud(files[i]);
        std::cout << (i > 0 ? "\n" : "")
                  << sss::describe_point_cloud(files[i], cloud, stats);
        sss::flush_standard_output();
    }
    return 0;
}

} // namespace

int main(int argc, char** argv) {
    return sss::run_tool(kTool, argc, argv, run);
}
