/// \file options.cpp
/// Shared option groups and the -newer test.

#include "sss/cli/options.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "sss/cloud/point_cloud_io.h"
#include "sss/diffusion/material.h"
#include "sss/util/error.h"

namespace sss {

namespace {

std::optional<glm::dvec3> triple_or_fromfile(ArgScanner& args, const std::string& opt,
                                             bool& fromfile, bool allow) {
    if (args.peek() == "fromfile") {
        if (!allow)
            throw UsageError("option -" + opt + ": fromfile is not available here");
        args.value(opt);
        fromfile = true;
        return std::nullopt;
    }
    return args.triple(opt);
}

} // namespace

bool material_option(ArgScanner& args, const std::string& o, MaterialSpec& m,
                     bool allow_fromfile) {
    if (o == "material") {
        m.preset = args.value(o);
        if (!find_material(m.preset))
            throw UsageError("option -material: unknown material '" + m.preset +
                             "' (known: " + material_names() + ")");
    } else if (o == "unitlength") {
        m.unitlength = args.positive(o);
    } else if (o == "scattering") {
        m.scattering = args.triple(o);
    } else if (o == "absorption") {
        m.absorption = args.triple(o);
    } else if (o == "albedo") {
        m.albedo = triple_or_fromfile(args, o, m.albedo_from_file, allow_fromfile);
    } else if (o == "diffusemeanfreepath") {
        m.dmfp = triple_or_fromfile(args, o, m.dmfp_from_file, allow_fromfile);
    } else if (o == "ior") {
        m.ior = args.positive(o);
    } else {
        return false;
    }
    return true;
}

bool run_option(ArgScanner& args, const std::string& o, RunOptions& run) {
    if (o == "threads") {
        run.threads = args.integer(o, -1024, 1024);
    } else if (o == "progress") {
        run.progress = args.integer(o, 0, 2);
    } else if (o == "Progress") {
        run.progress = std::max(run.progress, 1);
    } else if (o == "frame") {
        run.frame = args.integer(o, -1000000, 1000000);
    } else {
        return false;
    }
    return true;
}

bool outputs_up_to_date(const std::string& tool, const std::vector<std::string>& outputs,
                        const std::vector<std::string>& inputs) {
    namespace fs = std::filesystem;
    if (outputs.empty()) return false;
    std::error_code ec;
    std::optional<fs::file_time_type> newest_input;
    for (const std::string& in : inputs) {
        const fs::file_time_type t = fs::last_write_time(in, ec);
        if (ec) return false;
        if (!newest_input || t > *newest_input) newest_input = t;
    }
    for (const std::string& out : outputs) {
        if (!fs::is_regular_file(out, ec) || ec) return false;
        const fs::file_time_type t = fs::last_write_time(out, ec);
        if (ec || (newest_input && !(t > *newest_input))) return false;
    }
    std::string names;
    for (const std::string& out : outputs) names += (names.empty() ? "" : ", ") + out;
    std::printf("%s: %s %s newer than %s inputs; nothing to do\n", tool.c_str(),
                names.c_str(), outputs.size() == 1 ? "is" : "are",
                outputs.size() == 1 ? "its" : "their");
    std::fflush(stdout);
    return true;
}

bool write_option(ArgScanner& args, const std::string& o, PointCloudWriteOptions& write) {
    if (o == "compress") {
        write.compress = args.integer(o, 0, 1) != 0;
    } else if (o == "ptcversion") {
        write.ptc_version = args.integer(o, 0, 2);
    } else {
        return false;
    }
    return true;
}

} // namespace sss