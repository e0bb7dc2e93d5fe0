// The file side of bake3d: records merged into point clouds and written.

#include "sss/shading/bake3d_file.h"

#include <algorithm>
#include <map>

#include "sss/util/error.h"

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

std::vector<std::string> write_bake3d_files(std::span<const Bake3dRecord> records,
                                            const ChannelDeclarations& declared,
                                            const PointCloudWriteOptions& options) {
    std::vector<std::string> files;
    std::map<std::string, std::vector<std::size_t>> by_file; // record indices
    for (std::size_t i = 0; i < records.size(); ++i) {
        auto [it, added] = by_file.try_emplace(records[i].file);
        if (added) files.push_back(records[i].file);
        it->second.push_back(i);
    }
    for (const std::string& file : files) {
        PointCloud cloud;
        try {
            if (files.size() == 1) {
                cloud = bake3d_point_cloud(records, declared);
            } else {
                // Records of several files: this file's, copied together.
                std::vector<Bake3dRecord> mine;
                for (std::size_t i : by_file[file]) mine.push_back(records[i]);
                cloud = bake3d_point_cloud(mine, declared);
            }
        } catch (const ValueError& e) {
            throw ValueError(file + ": " + e.what());
        }
        write_point_cloud(cloud, file, options);
    }
    return files;
}

} // namespace sss
