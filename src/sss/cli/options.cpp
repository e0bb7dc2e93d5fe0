// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file options.cpp
/// Shared option groups: materials and point-cloud output.

#include "sss/cli/options.h"

#include "sss/brick/brickmap.h"
#include "sss/cloud/point_cloud_io.h"
#include "sss/diffusion/material.h"
#include "sss/diffusion/ssdiffusion.h"
#include "sss/util/error.h"
#include "sss/util/isa.h"

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

/// A channel name option's value: one a cloud can hold (a name no reader
/// accepts can never be found, and is never written).
std::string channel_option(ArgScanner& args, const std::string& opt, ChannelType type) {
    std::string name = args.value(opt);
    try {
        check_channel_name(name, type);
    } catch (const ValueError& e) {
        throw UsageError("option -" + opt + ": " + e.what());
    }
    return name;
}

} // namespace

bool material_option(ArgScanner& args, const std::string& o, MaterialSpec& m,
                     bool allow_fromfile) {
    if (o == "material") {
        m.preset = args.value(o);
        if (!find_material(m.preset))
            throw UsageError("option -material: " + unknown_material_message(m.preset));
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

bool ssdiffusion_option(ArgScanner& args, const std::string& o, SsDiffusionOptions& opt) {
    if (material_option(args, o, opt.material)) {
        return true;
    } else if (o == "maxsolidangle") {
        opt.diffusion.max_solid_angle = args.positive(o);
    } else if (o == "profile") {
        std::string p = args.value(o);
        if (!parse_profile_kind(p, opt.profile))
            throw UsageError("option -profile: unknown profile '" + p +
                             "' (classic, better, burley, pbd, mc)");
    } else if (o == "volume") {
        opt.volume = args.integer(o, 0, 1) == 1;
    } else if (o == "blocker") {
        opt.blockers.push_back(args.value(o));
    } else if (o == "incidence") {
        const std::string v = args.value(o);
        if (v != "normal" && v != "diffuse")
            throw UsageError("option -incidence: '" + v + "' is not normal or diffuse");
        opt.volume_options.diffuse_light = v == "diffuse";
    } else if (o == "criterion") {
        std::string c = args.value(o);
        if (!parse_criterion(c.c_str(), opt.diffusion.criterion))
            throw UsageError("option -criterion: unknown criterion '" + c +
                             "' (error, bbox, centroid)");
    } else if (o == "isa") {
        opt.diffusion.isa = parse_isa(args.value(o), "option -isa");
    } else if (o == "exact") {
        opt.exact = true;
    } else if (o == "areachannel") {
        opt.area_channel = channel_option(args, o, ChannelType::Float);
    } else if (o == "radiancechannel") {
        opt.radiance_channel = channel_option(args, o, ChannelType::Color);
    } else if (o == "keepchannels") {
        opt.keep_channels = args.integer(o, 0, 1) != 0;
    } else {
        return false;
    }
    return true;
}

bool brickmake_option(ArgScanner& args, const std::string& o, BrickMapBuildOptions& opt) {
    if (o == "maxerror") {
        opt.max_error = args.non_negative(o);
    } else if (o == "maxdepth") {
        opt.max_depth = args.integer(o, 0, 20);
    } else if (o == "radiusscale") {
        opt.radius_scale = args.positive(o);
    } else if (o == "ignorenormals") {
        opt.ignore_normals = args.integer(o, 0, 1) != 0;
    } else if (o == "omitgeometry") {
        opt.omit_geometry = args.integer(o, 0, 1) != 0;
    } else if (o == "channels") {
        opt.channels = split_channel_list(args.value(o), o);
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