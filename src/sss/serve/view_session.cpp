// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file view_session.cpp
/// The files of `ptview -serve` and the page's requests on them: sources as
/// float arrays, the live diffusion with cancellation, Save.

#include "sss/serve/view_session.h"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <map>

#include <sys/stat.h>
#include <unistd.h>

#include "serve_internal.h"
#include "sss/brick/brickmap.h"
#include "sss/brick/brickmap_voxels.h"
#include "sss/cloud/point_cloud_io.h"
#include "sss/diffusion/material.h"
#include "sss/diffusion/profile.h"
#include "sss/util/job_files.h"
#include "sss/util/messages.h"
#include "sss/util/progress.h"
#include "sss/util/version.h"

namespace sss {

/// One input file and what was computed from it.
struct ViewSession::Input {
    std::string path;
    bool brick = false;
    std::shared_ptr<const PointCloud> cloud; ///< a point cloud's points
    std::unique_ptr<BrickMap> map;           ///< a brick map
    bool diffusable = false;                 ///< a baked cloud: _radiance_t and _area
    // Under ViewSession::m_mutex:
    mutable std::map<int, std::shared_ptr<const PointCloud>> levels;
    std::shared_ptr<const PointCloud> subsample;
    std::size_t stride = 1;
    std::shared_ptr<const PointCloud> whole; ///< the last whole live result
    std::vector<std::string> whole_words;
    LiveResult whole_result; ///< its description (values left empty)
};

namespace {

/// The voxels of a depth are refused beyond this many (a deep level of a
/// large map would take gigabytes on the page).
constexpr std::size_t kMaxLevelVoxels = std::size_t(16) << 20;

bool is_brick_map_path(const std::string& path) {
    return has_extension_in(path, {".bkm"});
}

std::string folder_of(const std::string& path) {
    const std::size_t slash = path.rfind('/');
    if (slash == std::string::npos) return ".";
    if (slash == 0) return "/";
    return path.substr(0, slash);
}

std::string join_path(const std::string& folder, const std::string& name) {
    if (folder == ".") return name;
    return folder.back() == '/' ? folder + name : folder + "/" + name;
}

/// Every stride-th point of a cloud, each standing for stride points: its
/// area multiplied by the stride and its radius by the square root, so that
/// the light it carries and the disc it covers are those of the points it
/// stands for.
PointCloud subsample_cloud(const PointCloud& cloud, std::size_t stride,
                           const std::string& area_channel) {
    PointCloud out = cloud.points_only();
    const std::size_t n = (cloud.size() + stride - 1) / stride;
    out.resize(0);
    for (const Channel& c : cloud.channels) out.add_channel(c.name, c.type);
    out.resize(n);
    const float grow = float(std::sqrt(double(stride)));
    for (std::size_t j = 0; j < n; ++j) {
        const std::size_t i = j * stride;
        out.positions[j] = cloud.positions[i];
        out.normals[j] = cloud.normals[i];
        out.radii[j] = cloud.radii[i] * grow;
    }
    for (std::size_t c = 0; c < cloud.channels.size(); ++c) {
        const Channel& from = cloud.channels[c];
        Channel& to = out.channels[c];
        const std::size_t k = std::size_t(from.components());
        for (std::size_t j = 0; j < n; ++j)
            std::copy_n(from.data.begin() + std::ptrdiff_t(j * stride * k), k,
                        to.data.begin() + std::ptrdiff_t(j * k));
        if (from.name == area_channel)
            for (float& a : to.data) a *= float(stride);
    }
    return out;
}

/// A brick map's voxels of one depth as a cloud: a point per lattice point,
/// no normal (drawn as a sphere or a square), radius half the spacing, the
/// map's channels; the map's camera.
PointCloud level_cloud(const BrickMap& map, int depth) {
    const BrickMapInfo& info = map.info();
    const BrickMapVoxels v = brick_map_voxels(map, depth);
    PointCloud out;
    out.world_to_eye = info.world_to_eye;
    out.world_to_ndc = info.world_to_ndc;
    out.format = info.format;
    for (const auto& [name, type] : info.channels) out.add_channel(name, type);
    const std::size_t n = v.coords.size();
    out.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        const glm::dvec3 p =
            v.origin +
            v.spacing * glm::dvec3(v.coords[i][0], v.coords[i][1], v.coords[i][2]);
        out.positions[i] = glm::vec3(p);
        out.normals[i] = glm::vec3(0.0f);
        out.radii[i] = float(0.5 * v.spacing);
    }
    const std::size_t stride = std::size_t(info.data_size);
    for (Channel& c : out.channels) {
        const std::size_t offset = std::size_t(map.channel_offset(c.name));
        const std::size_t k = std::size_t(c.components());
        for (std::size_t i = 0; i < n; ++i)
            std::copy_n(v.values.begin() + std::ptrdiff_t(i * stride + offset), k,
                        c.data.begin() + std::ptrdiff_t(i * k));
    }
    return out;
}

void json_camera(JsonWriter& j, const std::array<float, 16>& w2e,
                 const std::array<float, 16>& w2n, const std::array<float, 3>& format) {
    j.key("camera").begin_object();
    j.key("world2eye").numbers(w2e.data(), 16);
    j.key("world2ndc").numbers(w2n.data(), 16);
    j.key("format").numbers(format.data(), 3);
    j.end_object();
}

void json_bounds(JsonWriter& j, const glm::dvec3& lo, const glm::dvec3& hi) {
    const double b[6] = {lo.x, lo.y, lo.z, hi.x, hi.y, hi.z};
    j.key("bounds").numbers(b, 6);
}

void json_channels(JsonWriter& j, const PointCloud& cloud) {
    j.key("channels").begin_array();
    for (const Channel& c : cloud.channels) {
        j.begin_object();
        j.key("name").string(c.name);
        j.key("type").string(channel_type_name(c.type));
        j.key("components").number(double(c.components()));
        j.end_object();
    }
    j.end_array();
}

void json_materials(JsonWriter& j) {
    j.key("materials").begin_array();
    for (const NamedMaterial& m : material_table()) {
        MaterialSpec spec;
        spec.preset = m.name;
        glm::dvec3 albedo, dmfp;
        spec.resolve_albedo_dmfp(albedo, dmfp);
        j.begin_object();
        j.key("name").string(m.name);
        const double a[3] = {albedo.x, albedo.y, albedo.z};
        const double d[3] = {dmfp.x, dmfp.y, dmfp.z};
        j.key("albedo").numbers(a, 3);
        j.key("dmfp").numbers(d, 3);
        j.key("ior").number(m.ior);
        j.end_object();
    }
    j.end_array();
    j.key("profiles").begin_array();
    for (ProfileKind k : {ProfileKind::Classic, ProfileKind::Better, ProfileKind::Burley,
                          ProfileKind::Pbd, ProfileKind::Mc})
        j.string(profile_kind_name(k));
    j.end_array();
}

} // namespace

// ---------------------------------------------------------------------------

ViewSourceId ViewSourceId::parse(const std::string& text) {
    const auto digits = [&](std::size_t from, std::size_t to, std::size_t& out) {
        if (to <= from || to - from > 9) return false;
        out = 0;
        for (std::size_t i = from; i < to; ++i) {
            if (!std::isdigit(static_cast<unsigned char>(text[i]))) return false;
            out = out * 10 + std::size_t(text[i] - '0');
        }
        return true;
    };
    ViewSourceId id;
    std::size_t depth = 0;
    if (text.size() >= 2 && (text[0] == 'c' || text[0] == 'l') &&
        digits(1, text.size(), id.input)) {
        id.kind = text[0] == 'c' ? Kind::Cloud : Kind::Live;
        return id;
    }
    const std::size_t dot = text.find('.');
    if (text.size() >= 4 && text[0] == 'b' && dot != std::string::npos &&
        digits(1, dot, id.input) && digits(dot + 1, text.size(), depth) && depth < 64) {
        id.kind = Kind::BrickLevel;
        id.depth = int(depth);
        return id;
    }
    throw NotFoundError("no source " + quoted(text, 40) +
                        " (sources: c<i>, l<i>, b<i>.<depth>)");
}

std::string ViewSourceId::text() const {
    switch (kind) {
    case Kind::Cloud:
        return "c" + std::to_string(input);
    case Kind::Live:
        return "l" + std::to_string(input);
    case Kind::BrickLevel:
        break;
    }
    return "b" + std::to_string(input) + "." + std::to_string(depth);
}

uint32_t value_hash(const std::vector<float>& values) {
    uint32_t h = 2166136261u;
    const auto* bytes = reinterpret_cast<const unsigned char*>(values.data());
    for (std::size_t i = 0; i < values.size() * sizeof(float); ++i) {
        h ^= bytes[i];
        h *= 16777619u;
    }
    return h;
}

bool is_plain_file_name(const std::string& name) {
    if (name.empty() || name.size() > 200 || name == "." || name == ".." ||
        name[0] == '.' || name[0] == '-')
        return false;
    for (char c : name)
        if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '_' &&
            c != '-' && c != '+' && c != '@')
            return false;
    return true;
}

// ---------------------------------------------------------------------------

ViewSession::ViewSession(ServeOptions options) : m_options(std::move(options)) {
    if (m_options.inputs.empty()) throw UsageError("no file to show");
    for (const std::string& path : m_options.inputs) {
        auto in = std::make_unique<Input>();
        in->path = path;
        if (is_brick_map_path(path)) {
            in->brick = true;
            in->map = std::make_unique<BrickMap>(path);
        } else {
            auto cloud = std::make_shared<PointCloud>(read_point_cloud(path));
            const Channel* area = cloud->find_channel("_area");
            const Channel* radiance = cloud->find_channel("_radiance_t");
            in->diffusable = area && area->type == ChannelType::Float && radiance &&
                             radiance->type == ChannelType::Color && cloud->size() > 0;
            in->cloud = std::move(cloud);
        }
        m_inputs.push_back(std::move(in));
    }
}

ViewSession::~ViewSession() = default;

const ViewSession::Input& ViewSession::input(std::size_t i) const {
    if (i >= m_inputs.size())
        throw NotFoundError("no input " + std::to_string(i) + " (there are " +
                            std::to_string(m_inputs.size()) + ")");
    return *m_inputs[i];
}

const std::string& ViewSession::input_path(std::size_t i) const {
    return input(i).path;
}

std::string ViewSession::save_folder(std::size_t i) const {
    if (!m_options.save_dir.empty()) return m_options.save_dir;
    return folder_of(input(i).path);
}

std::string ViewSession::scene_json() const {
    JsonWriter j;
    j.begin_object();
    j.key("software").string(m_options.software);
    j.key("live_points").number(double(m_options.live_points));
    j.key("video").begin_array();
    if (!m_options.ffmpeg.empty() && !find_program(m_options.ffmpeg).empty()) {
        j.string("mp4");
        j.string("webm");
    }
    j.end_array();
    j.key("inputs").begin_array();
    for (std::size_t i = 0; i < m_inputs.size(); ++i) {
        const Input& in = *m_inputs[i];
        j.begin_object();
        j.key("index").number(double(i));
        j.key("label").string(in.path);
        j.key("save_folder").string(save_folder(i));
        if (in.brick) {
            const BrickMapInfo& info = in.map->info();
            j.key("kind").string("brickmap");
            PointCloud header;
            for (const auto& [name, type] : info.channels) header.add_channel(name, type);
            json_channels(j, header);
            json_bounds(j, info.bbox_min, info.bbox_max);
            if (!is_identity(info.world_to_ndc))
                json_camera(j, info.world_to_eye, info.world_to_ndc, info.format);
            j.key("surface_depth").number(double(brick_map_surface_depth(*in.map)));
            j.key("levels").begin_array();
            for (const BrickMapLevel& level : info.levels) {
                j.begin_object();
                j.key("depth").number(double(level.depth));
                j.key("bricks").number(double(level.bricks));
                j.key("samples").number(double(level.samples));
                j.end_object();
            }
            j.end_array();
        } else {
            const PointCloud& c = *in.cloud;
            j.key("kind").string("cloud");
            j.key("points").number(double(c.size()));
            json_channels(j, c);
            const Bounds3 b = c.bounds();
            json_bounds(j, glm::dvec3(b.lo), glm::dvec3(b.hi));
            if (!is_identity(c.world_to_ndc))
                json_camera(j, c.world_to_eye, c.world_to_ndc, c.format);
            j.key("live").boolean(in.diffusable);
            if (in.diffusable) {
                const std::size_t limit = std::max<std::size_t>(1, m_options.live_points);
                j.key("live_stride").number(double((c.size() + limit - 1) / limit));
            }
        }
        j.end_object();
    }
    j.end_array();
    json_materials(j);
    j.end_object();
    return j.text();
}

std::shared_ptr<const PointCloud>
ViewSession::source_cloud(const ViewSourceId& id) const {
    const Input& in = input(id.input);
    switch (id.kind) {
    case ViewSourceId::Kind::Cloud:
        if (in.brick)
            throw NotFoundError("input " + std::to_string(id.input) +
                                " is a brick map (ask for b" + std::to_string(id.input) +
                                ".<depth>)");
        return in.cloud;
    case ViewSourceId::Kind::Live: {
        const std::lock_guard<std::mutex> lock(m_mutex);
        if (!in.whole)
            throw NotFoundError("no live diffusion of input " + std::to_string(id.input) +
                                " yet");
        return in.whole;
    }
    case ViewSourceId::Kind::BrickLevel:
        break;
    }
    if (!in.brick)
        throw NotFoundError("input " + std::to_string(id.input) + " is not a brick map");
    const BrickMapInfo& info = in.map->info();
    if (id.depth >= int(info.levels.size()))
        throw NotFoundError(in.path + " has no depth " + std::to_string(id.depth) +
                            " (its depths: 0 to " +
                            std::to_string(int(info.levels.size()) - 1) + ")");
    {
        const std::lock_guard<std::mutex> lock(m_mutex);
        const auto it = in.levels.find(id.depth);
        if (it != in.levels.end()) return it->second;
    }
    if (info.levels[std::size_t(id.depth)].samples > kMaxLevelVoxels)
        throw ValueError(in.path + ": depth " + std::to_string(id.depth) + " has " +
                         std::to_string(info.levels[std::size_t(id.depth)].samples) +
                         " samples; the view takes at most " +
                         std::to_string(kMaxLevelVoxels));
    auto cloud = std::make_shared<const PointCloud>(level_cloud(*in.map, id.depth));
    const std::lock_guard<std::mutex> lock(m_mutex);
    return in.levels.emplace(id.depth, std::move(cloud)).first->second;
}

std::vector<float> ViewSession::geometry(const std::string& source) const {
    const std::shared_ptr<const PointCloud> c = source_cloud(ViewSourceId::parse(source));
    const std::size_t n = c->size();
    std::vector<float> out(7 * n);
    for (std::size_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) {
            out[3 * i + std::size_t(k)] = c->positions[i][k];
            out[3 * n + 3 * i + std::size_t(k)] = c->normals[i][k];
        }
    std::copy(c->radii.begin(), c->radii.end(), out.begin() + std::ptrdiff_t(6 * n));
    return out;
}

std::vector<float> ViewSession::channel(const std::string& source, std::size_t k) const {
    const std::shared_ptr<const PointCloud> c = source_cloud(ViewSourceId::parse(source));
    if (k >= c->channels.size())
        throw NotFoundError("source " + source + " has no channel " + std::to_string(k) +
                            " (it has " + std::to_string(c->channels.size()) + ")");
    return c->channels[k].data;
}

// ---------------------------------------------------------------------------
// Live diffusion
// ---------------------------------------------------------------------------

std::shared_ptr<const PointCloud> ViewSession::live_subsample(std::size_t cloud,
                                                              std::size_t& stride) {
    Input& in = *m_inputs[cloud];
    const std::lock_guard<std::mutex> lock(m_mutex);
    if (!in.subsample) {
        const std::size_t limit = std::max<std::size_t>(1, m_options.live_points);
        in.stride = (in.cloud->size() + limit - 1) / limit;
        in.subsample = std::make_shared<const PointCloud>(
            subsample_cloud(*in.cloud, in.stride, "_area"));
    }
    stride = in.stride;
    return in.subsample;
}

LiveResult ViewSession::diffuse(const LiveRequest& request) {
    const Input& in = input(request.cloud);
    if (!in.diffusable)
        throw NotFoundError(in.path + " is not a baked cloud (a float _area and a color "
                                      "_radiance_t channel): it has no live diffusion");
    uint64_t ticket;
    {
        const std::lock_guard<std::mutex> lock(m_mutex);
        ticket = ++m_ticket;
    }
    return compute(request.cloud, request, ticket);
}

LiveResult ViewSession::compute(std::size_t index, const LiveRequest& request,
                                uint64_t ticket,
                                std::shared_ptr<const PointCloud>* kept) {
    Input& in = *m_inputs[index];
    if (!m_options.parse_diffusion)
        throw UsageError("this view computes no diffusion (no option parser)");
    SsDiffusionOptions options = m_options.parse_diffusion(request.words);
    LiveResult result;
    try {
        result.material = describe_material(options);
    } catch (const ValueError& e) {
        throw UsageError(e.what());
    }
    const bool whole = !request.preview || in.cloud->size() <= m_options.live_points;
    std::shared_ptr<const PointCloud> cloud = in.cloud;
    if (!whole) cloud = live_subsample(index, result.stride);

    // A newer request (of any cloud) cancels this one at its next progress
    // step: ssdiffusion() then throws Cancelled.
    Progress progress(false);
    progress.set_callback([this, ticket](uint64_t, uint64_t) {
        const std::lock_guard<std::mutex> lock(m_mutex);
        return ticket == 0 || ticket == m_ticket;
    });
    options.diffusion.progress = &progress;
    SsDiffusionReport report;
    PointCloud out;
    try {
        out = ssdiffusion(*cloud, options, &report);
    } catch (const MissingChannelError& e) {
        throw ValueError(in.path + ": no channel \"" + e.channel() +
                         "\" (its channels: " + e.present() + ")");
    } catch (const ValueError& e) {
        throw ValueError(in.path + ": " + e.what());
    }
    result.seconds = report.seconds;
    result.warnings = report.warnings;
    result.points = out.size();
    const Channel* values = out.find_channel(options.output_channel);
    if (!values)
        throw ValueError(in.path + ": the diffusion wrote no " + options.output_channel);
    result.values = values->data;
    result.hash = value_hash(result.values);
    const std::string name =
        is_plain_file_name(request.output_name) &&
                has_extension_in(request.output_name, point_cloud_extensions())
            ? request.output_name
            : default_result_name(in.path);
    if (m_options.diffusion_command)
        result.command = m_options.diffusion_command(request.words, in.path,
                                                     join_path(save_folder(index), name));
    if (whole) {
        auto cloud_kept = std::make_shared<const PointCloud>(std::move(out));
        if (kept) *kept = cloud_kept;
        const std::lock_guard<std::mutex> lock(m_mutex);
        in.whole = std::move(cloud_kept);
        in.whole_words = request.words;
        in.whole_result = result;
        in.whole_result.values.clear();
    }
    return result;
}

std::pair<std::string, LiveResult>
ViewSession::save(std::size_t cloud, const std::vector<std::string>& words,
                  const std::string& name, bool overwrite) {
    const Input& in = input(cloud);
    if (!in.diffusable)
        throw NotFoundError(in.path +
                            " is not a baked cloud: it has no diffusion to save");
    if (!is_plain_file_name(name) || !has_extension_in(name, point_cloud_extensions()))
        throw UsageError(quoted(name) +
                         " is not a name a result is saved under: a plain file name "
                         "(letters, digits, ._-+@) ending in .ptc or .ply");
    const std::string path = join_path(save_folder(cloud), name);
    for (const std::string& other : m_options.inputs)
        if (JobFiles::same_file(path, other))
            throw UsageError(quoted(path) +
                             " is an input of this view; choose another name");
    struct stat st {};
    if (::stat(path.c_str(), &st) == 0 && !overwrite)
        throw UsageError(quoted(path) + " exists; save with overwrite to replace it");

    std::shared_ptr<const PointCloud> result;
    LiveResult described;
    {
        const std::lock_guard<std::mutex> lock(m_mutex);
        if (in.whole && in.whole_words == words) {
            result = in.whole;
            described = in.whole_result;
        }
    }
    if (!result)
        described = compute(cloud, LiveRequest{cloud, words, false, name}, 0, &result);
    write_point_cloud(*result, path);
    if (m_options.diffusion_command)
        described.command = m_options.diffusion_command(words, in.path, path);
    return {path, described};
}

std::string default_result_name(const std::string& input) {
    std::string name = input.substr(input.rfind('/') + 1);
    const std::size_t dot = name.rfind('.');
    if (dot != std::string::npos && dot > 0) name.resize(dot);
    std::string plain;
    for (char c : name)
        plain += std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' ||
                         c == '.' || c == '+' || c == '@'
                     ? c
                     : '_';
    while (!plain.empty() && (plain[0] == '.' || plain[0] == '-')) plain.erase(0, 1);
    return (plain.empty() ? std::string("cloud") : plain) + "_ssd.ptc";
}

} // namespace sss
