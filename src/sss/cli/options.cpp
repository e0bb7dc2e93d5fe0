/// \file options.cpp
/// Shared option groups: materials and point-cloud output.

#include "sss/cli/options.h"

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