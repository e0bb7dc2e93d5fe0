// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// The file side of bake3d: records merged into point clouds and written.

#include "sss/binding/bake3d_file.h"

#include <array>

#include <algorithm>
#include <map>

#include "sss/util/atomic_output.h"
#include "sss/util/error.h"
#include "sss/util/job_files.h"
#include "sss/util/messages.h"

namespace sss {

namespace {

ChannelType channel_type_of(const std::string& name, int floats,
                            const ChannelDeclarations& declared) {
    for (const auto& [declared_name, type_name] : declared) {
        if (declared_name != name) continue;
        const std::optional<ChannelType> type = parse_channel_type(type_name);
        if (!type)
            throw ValueError("channel '" + name + "' is declared with unknown type '" +
                             type_name + "'");
        if (channel_type_size(*type) != floats)
            throw ValueError("channel '" + name + "' is declared " + type_name +
                             " but baked with " + std::to_string(floats) +
                             " floats per point");
        return *type;
    }
    switch (floats) {
    case 1:
        return ChannelType::Float;
    case 3:
        return ChannelType::Color;
    case 16:
        return ChannelType::Matrix;
    default:
        throw ValueError("channel '" + name + "' has " + std::to_string(floats) +
                         " floats per point (1, 3 or 16 expected)");
    }
}

} // namespace

PointCloud bake3d_point_cloud(std::span<const Bake3dRecord> records,
                              const ChannelDeclarations& declared) {
    // The channels, in the order first baked, with their sizes.
    std::vector<std::pair<std::string, int>> channels;
    std::size_t total = 0;
    for (const Bake3dRecord& r : records) {
        const std::size_t n = r.P.size();
        if (r.channels.size() != r.channel_floats.size())
            throw ValueError("bake3d record with " + std::to_string(r.channels.size()) +
                             " channel names but " +
                             std::to_string(r.channel_floats.size()) + " channel sizes");
        if ((!r.N.empty() && r.N.size() != n) ||
            (!r.radius.empty() && r.radius.size() != n))
            throw ValueError("bake3d record with " + std::to_string(n) + " points but " +
                             std::to_string(r.N.size()) + " normals and " +
                             std::to_string(r.radius.size()) + " radii");
        std::size_t stride = 0;
        for (std::size_t k = 0; k < r.channels.size(); ++k) {
            const int floats = r.channel_floats[k];
            stride += std::size_t(std::max(floats, 0));
            auto it = std::find_if(channels.begin(), channels.end(), [&](const auto& c) {
                return c.first == r.channels[k];
            });
            if (it == channels.end())
                channels.emplace_back(r.channels[k], floats);
            else if (it->second != floats)
                throw ValueError("channel '" + r.channels[k] + "' is baked with " +
                                 std::to_string(it->second) + " and with " +
                                 std::to_string(floats) + " floats per point");
        }
        if (r.values.size() != n * stride)
            throw ValueError("bake3d record with " + std::to_string(n) + " points of " +
                             std::to_string(stride) + " floats but " +
                             std::to_string(r.values.size()) + " values");
        total += n;
    }

    PointCloud cloud;
    for (const auto& [name, floats] : channels)
        cloud.add_channel(name, channel_type_of(name, floats, declared));
    cloud.resize(total);
    std::size_t at = 0;
    for (const Bake3dRecord& r : records) {
        const std::size_t n = r.P.size();
        std::copy(r.P.begin(), r.P.end(), cloud.positions.begin() + at);
        if (!r.N.empty()) std::copy(r.N.begin(), r.N.end(), cloud.normals.begin() + at);
        if (!r.radius.empty())
            std::copy(r.radius.begin(), r.radius.end(), cloud.radii.begin() + at);
        // Where each of the record's channels goes.
        std::vector<Channel*> targets;
        std::size_t stride = 0;
        for (std::size_t k = 0; k < r.channels.size(); ++k) {
            targets.push_back(cloud.find_channel(r.channels[k]));
            stride += std::size_t(r.channel_floats[k]);
        }
        for (std::size_t i = 0; i < n; ++i) {
            const float* src = r.values.data() + i * stride;
            for (std::size_t k = 0; k < targets.size(); ++k) {
                const int floats = r.channel_floats[k];
                std::copy_n(src, floats, targets[k]->data.data() + (at + i) * floats);
                src += floats;
            }
        }
        at += n;
    }
    return cloud;
}

namespace {

/// `r` with a float "_area" channel first (its own, else its areas).
Bake3dRecord with_area_first(const Bake3dRecord& r) {
    int offset = 0, at = -1;
    for (std::size_t k = 0; k < r.channels.size(); ++k) {
        if (r.channels[k] == "_area" && r.channel_floats[k] == 1) at = offset;
        offset += r.channel_floats[k];
    }
    const std::size_t stride = static_cast<std::size_t>(offset);
    const std::size_t n = r.P.size();
    Bake3dRecord out = r;
    out.channels.assign(1, "_area");
    out.channel_floats.assign(1, 1);
    for (std::size_t k = 0; k < r.channels.size(); ++k)
        if (!(r.channels[k] == "_area" && r.channel_floats[k] == 1)) {
            out.channels.push_back(r.channels[k]);
            out.channel_floats.push_back(r.channel_floats[k]);
        }
    out.values.clear();
    out.values.reserve(n * (stride + (at < 0 ? 1 : 0)));
    for (std::size_t i = 0; i < n; ++i) {
        const float* v = r.values.data() + i * stride;
        out.values.push_back(at >= 0 ? v[at] : (i < r.area.size() ? r.area[i] : 0.0f));
        int o = 0;
        for (std::size_t k = 0; k < r.channels.size(); ++k) {
            if (o != at)
                out.values.insert(out.values.end(), v + o, v + o + r.channel_floats[k]);
            o += r.channel_floats[k];
        }
    }
    return out;
}

void store_matrix(const glm::dmat4& m, std::array<float, 16>& out) {
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) out[c * 4 + r] = static_cast<float>(m[c][r]);
}

} // namespace

std::vector<std::pair<std::string, PointCloud>>
bake3d_clouds(std::span<const Bake3dRecord> records, const ChannelDeclarations& declared,
              const Camera* camera) {
    std::vector<std::string> files;
    std::map<std::string, std::vector<Bake3dRecord>> by_file;
    for (const Bake3dRecord& r : records) {
        auto [it, added] = by_file.try_emplace(r.file);
        if (added) files.push_back(r.file);
        it->second.push_back(with_area_first(r));
    }
    std::vector<std::pair<std::string, PointCloud>> out;
    for (const std::string& file : files) {
        PointCloud cloud;
        try {
            cloud = bake3d_point_cloud(by_file[file], declared);
        } catch (const ValueError& e) {
            throw ValueError(escape_control(truncated(file, kMaxEcho)) + ": " + e.what());
        }
        by_file[file].clear();
        // Names the readers would refuse fail here, before any file is written.
        for (const Channel& c : cloud.channels) {
            try {
                check_channel_name(c.name, c.type);
            } catch (const ValueError& e) {
                throw ValueError("bake3d file " + sss::quoted(file) + ": " + e.what());
            }
        }
        if (camera) {
            store_matrix(camera->world_to_camera, cloud.world_to_eye);
            store_matrix(camera->world_to_ndc(), cloud.world_to_ndc);
            cloud.format = {float(camera->xres), float(camera->yres),
                            float(camera->pixel_aspect)};
        }
        out.emplace_back(file, std::move(cloud));
    }
    return out;
}

std::vector<std::string> write_bake3d_files(std::span<const Bake3dRecord> records,
                                            const ChannelDeclarations& declared,
                                            const PointCloudWriteOptions& options,
                                            const Camera* camera) {
    std::vector<std::pair<std::string, PointCloud>> clouds =
        bake3d_clouds(records, declared, camera);
    // Every name is checked before any file is written.
    JobFiles* job = JobFiles::current();
    for (const auto& [file, cloud] : clouds) {
        const std::string use = "bake3d file " + sss::quoted(file);
        check_file_name(file, use);
        if (job) job->output(file, use);
        if (!has_extension_in(file, point_cloud_extensions()) &&
            !writes_into_existing(file))
            throw ValueError(use + ": " +
                             unknown_extension_text(file, "a point cloud file",
                                                    point_cloud_extensions()));
        check_output_target(file);
    }
    std::vector<std::string> files;
    for (auto& [file, cloud] : clouds) {
        write_point_cloud(cloud, file, options);
        files.push_back(file);
    }
    return files;
}

} // namespace sss
