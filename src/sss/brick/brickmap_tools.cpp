// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file brickmap_tools.cpp
/// The work of the brickmake and brickinfo tools around the brick-map core:
/// building from files, the -newer check, brickinfo's report and evaluating a
/// map over a cloud. The pictures are in brickmap_picture.cpp, so that a
/// program that does not draw them (brickmake, the Python module) does not
/// link OpenImageIO and load the libraries behind it.

#include "sss/brick/brickmap_tools.h"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <optional>
#include <sstream>

#include <glm/geometric.hpp>
#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>

#include "sss/cloud/point_cloud_io.h"
#include "sss/util/atomic_output.h"
#include "sss/util/error.h"
#include "sss/util/job_files.h"
#include "sss/util/limits.h"
#include "sss/util/parse.h"
#include "sss/util/progress.h"
#include "sss/util/version.h"

namespace sss {

namespace {

std::string triple_text(const glm::dvec3& v) {
    return short_float(v.x) + " " + short_float(v.y) + " " + short_float(v.z);
}

} // namespace

/// Tree names in the order of brickmap.h: 0 = no normal, then +x -x +y -y +z -z
/// (brickinfo's report here, its pictures in brickmap_picture.cpp).
extern const char* const kBrickMapTreeNames[7];
const char* const kBrickMapTreeNames[7] = {"none", "+x", "-x", "+y", "-y", "+z", "-z"};

// ---------------------------------------------------------------------------
// brickmake
// ---------------------------------------------------------------------------

BrickMapBuildReport make_brick_map_from_files(const std::vector<std::string>& inputs,
                                              const BrickMapBuildOptions& options,
                                              const std::string& output) {
    if (inputs.empty()) throw ValueError("no input point cloud");
    {
        // Before any work: a folder, or an output that is one of the clouds.
        JobFiles files;
        for (const std::string& in : inputs)
            files.input(in, "the input cloud \"" + in + "\"");
        files.output(output, "the output brick map \"" + output + "\"");
        check_output_target(output);
    }
    std::vector<PointCloud> clouds;
    clouds.reserve(inputs.size());
    for (const std::string& in : inputs) clouds.push_back(read_point_cloud(in));
    const ScopedStage stage("building " + output);
    // The library only sees clouds; name the files they came from.
    try {
        return build_brick_map(clouds, options, output);
    } catch (const ValueError& e) {
        throw ValueError(join(inputs) + ": " + e.what());
    } catch (const LimitError& e) {
        throw LimitError(e.which(), join(inputs) + ": " + e.what());
    } catch (const OutOfMemoryError& e) {
        throw OutOfMemoryError(join(inputs) + ": " + e.what());
    }
}

std::string brick_map_problem(const std::string& path) {
    try {
        const BrickMap map(path, 0);
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

// ---------------------------------------------------------------------------
// brickinfo: report
// ---------------------------------------------------------------------------

namespace {

/// Free text on one report line: control characters as \n, \t or \xNN.
std::string one_line(const std::string& text) {
    std::string out;
    for (unsigned char c : text) {
        if (c == '\n') {
            out += "\\n";
        } else if (c == '\t') {
            out += "\\t";
        } else if (c < 0x20 || c == 0x7f) {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\x%02x", c);
            out += buf;
        } else {
            out += char(c);
        }
    }
    return out;
}

} // namespace

std::string describe_brick_map(const std::string& path, const BrickMap& map,
                               std::optional<std::size_t> bricks_verified) {
    const BrickMapInfo& info = map.info();
    std::ostringstream out;
    out << "file: " << path << "\n";
    out << "format: bkm version " << info.version << "\n";
    out << "file size: " << info.file_size << " bytes\n";
    out << "channels: " << info.channels.size() << " (datasize " << info.data_size
        << ")\n";
    for (const auto& [name, type] : info.channels)
        out << "  " << channel_type_name(type) << " " << name << "\n";
    out << "bbox: min " << triple_text(info.bbox_min) << "  max "
        << triple_text(info.bbox_max) << "\n";
    out << "root cube: min " << triple_text(info.cube_min) << "  side "
        << short_float(info.cube_side) << "\n";
    out << "maxdepth: " << info.max_depth << "\n";
    out << "maxerror: " << short_float(info.max_error) << "\n";
    out << "ignorenormals: " << (info.ignore_normals ? 1 : 0) << "\n";
    out << "omitgeometry: " << (info.omit_geometry ? 1 : 0) << "\n";
    if (!is_identity(info.world_to_eye))
        out << "world2eye:" << matrix_text(info.world_to_eye) << "\n";
    if (!is_identity(info.world_to_ndc))
        out << "world2ndc:" << matrix_text(info.world_to_ndc) << "\n";
    if (info.format != std::array<float, 3>{0.0f, 0.0f, 1.0f})
        out << "image format: " << short_float(info.format[0]) << " "
            << short_float(info.format[1]) << " " << short_float(info.format[2]) << "\n";
    out << "provenance: "
        << (info.provenance.empty() ? "(none)" : one_line(info.provenance)) << "\n";

    // Bricks per tree (normal direction).
    std::string trees;
    for (int t = 0; t < 7; ++t) {
        std::size_t n = 0;
        for (std::size_t d = 0; d < info.levels.size(); ++d)
            n += map.bricks_at(t, int(d)).size();
        if (n > 0)
            trees += std::string(trees.empty() ? "" : ", ") + kBrickMapTreeNames[t] +
                     " " + std::to_string(n);
    }
    out << "trees: " << info.trees_used << " used"
        << (trees.empty() ? std::string() : " (bricks: " + trees + ")") << "\n";

    out << "levels: " << info.levels.size() << "\n";
    char line[160];
    std::snprintf(line, sizeof line, "  %5s %10s %12s %8s %10s %12s\n", "depth", "bricks",
                  "samples", "filled", "occupancy", "spacing");
    out << line;
    for (const BrickMapLevel& l : info.levels) {
        const double spacing = info.cube_side / std::ldexp(1.0, l.depth) / 7.0;
        const double filled =
            l.bricks > 0 ? 100.0 * double(l.samples) / (512.0 * double(l.bricks)) : 0.0;
        std::snprintf(line, sizeof line, "  %5d %10zu %12zu %7.1f%% %10zu %12s\n",
                      l.depth, l.bricks, l.samples, filled, l.occupancy_nodes,
                      short_float(spacing).c_str());
        out << line;
    }
    out << "total: " << info.total_bricks << " bricks, " << info.total_samples
        << " samples, " << info.occupancy_nodes << " occupancy-only nodes\n";
    if (bricks_verified)
        out << "checked: header, tables and " << *bricks_verified
            << (*bricks_verified == 1 ? " brick" : " bricks")
            << " (CRC-32, presence masks, finite values)\n";
    else
        out << "checked: header and tables (CRC-32); bricks not read (-verify 0)\n";
    return out.str();
}

// ---------------------------------------------------------------------------
// brickinfo: lookups over a cloud
// ---------------------------------------------------------------------------

PointCloud lookup_brick_map_cloud(const BrickMap& map, const PointCloud& cloud,
                                  const BrickMapCloudLookupOptions& options,
                                  BrickMapCloudLookupReport* report) {
    const BrickMapInfo& info = map.info();
    const std::size_t n = cloud.size();
    const int ds = info.data_size;
    PointCloud out = cloud.points_only();
    for (const auto& [name, type] : info.channels) out.add_channel(name, type);
    // Pointers only once every channel exists (adding one may move the others).
    std::vector<Channel*> channels;
    for (const auto& [name, type] : info.channels)
        channels.push_back(out.find_channel(name));

    std::vector<uint8_t> hit(n, 0);
    std::atomic<uint64_t> done{0};
    if (options.progress) options.progress->set_unit("lookups");
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, n, 1024),
        [&](const tbb::blocked_range<std::size_t>& range) {
            std::vector<float> buf(std::size_t(std::max(ds, 1)));
            for (std::size_t i = range.begin(); i != range.end(); ++i) {
                const float radius = options.filter_radius >= 0.0f
                                         ? options.filter_radius
                                         : cloud.radii[i] * options.filter_scale;
                hit[i] =
                    map.lookup(cloud.positions[i], cloud.normals[i], radius, buf.data());
                const float* src = buf.data();
                for (Channel* ch : channels) {
                    const int c = ch->components();
                    std::copy(src, src + c,
                              ch->data.begin() + std::ptrdiff_t(i * std::size_t(c)));
                    src += c;
                }
            }
            if (options.progress)
                options.progress->update(done.fetch_add(range.size()) + range.size(), n);
        });
    if (options.progress) options.progress->finish();

    if (report) {
        report->points = n;
        report->misses = std::size_t(std::count(hit.begin(), hit.end(), uint8_t(0)));
        report->differences.clear();
        report->not_compared.clear();
        if (options.compare) {
            for (const Channel* ch : channels) {
                const Channel* ref = cloud.find_channel(ch->name);
                if (!ref || ref->type != ch->type) {
                    report->not_compared.push_back(ch->name);
                    continue;
                }
                // Sequential sums: the figures do not depend on the thread count.
                ChannelDifference d;
                d.name = ch->name;
                double sum2 = 0.0, ref2 = 0.0;
                for (std::size_t k = 0; k < ch->data.size(); ++k) {
                    const double diff = double(ch->data[k]) - double(ref->data[k]);
                    sum2 += diff * diff;
                    ref2 += double(ref->data[k]) * ref->data[k];
                    d.max_abs = std::max(d.max_abs, std::fabs(diff));
                }
                const double count = double(std::max<std::size_t>(ch->data.size(), 1));
                d.rms = std::sqrt(sum2 / count);
                d.reference_rms = std::sqrt(ref2 / count);
                report->differences.push_back(d);
            }
        }
    }
    return out;
}

} // namespace sss
