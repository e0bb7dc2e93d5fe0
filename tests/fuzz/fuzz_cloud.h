#pragma once
// Checks shared by fuzz_ptc and fuzz_ply on a cloud that was read
// successfully: consistent sizes, finite values, usable statistics, and a
// write + read back that keeps every value (the readers promise that
// everything they return can be written again).

#include <cmath>
#include <cstring>
#include <string>

#include "fuzz_common.h"
#include "sss/cloud/point_cloud_io.h"

namespace sss::fuzz {

inline bool finite3(const glm::vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

/// Sizes and finiteness of everything a reader returned.
inline void check_cloud(const PointCloud& c) {
    const std::size_t n = c.size();
    require(c.normals.size() == n && c.radii.size() == n, "array sizes disagree");
    for (std::size_t i = 0; i < n; ++i) {
        require(finite3(c.positions[i]) && finite3(c.normals[i]), "non-finite vector");
        require(std::isfinite(c.radii[i]) && c.radii[i] >= 0.0f, "bad radius");
    }
    for (const Channel& ch : c.channels) {
        require(ch.data.size() == n * static_cast<std::size_t>(ch.components()),
                "channel '" + ch.name + "' has the wrong size");
        for (float v : ch.data) require(std::isfinite(v), "non-finite channel value");
    }
    for (float v : c.world_to_eye) require(std::isfinite(v), "non-finite world2eye");
    for (float v : c.world_to_ndc) require(std::isfinite(v), "non-finite world2ndc");
    for (float v : c.format) require(std::isfinite(v), "non-finite format");
}

inline bool same_bits(const void* a, const void* b, std::size_t bytes) {
    return bytes == 0 || std::memcmp(a, b, bytes) == 0;
}

/// Statistics, then a .ptc write and read back: positions, radii and channel
/// data must come back bit for bit. Writing must not refuse what was read.
inline void exercise_cloud(const PointCloud& c, const ScratchFile& out) {
    check_cloud(c);
    const std::vector<ChannelStats> stats = channel_stats(c);
    require(stats.size() == c.channels.size() + 1, "channel_stats size");
    for (const ChannelStats& s : stats) {
        for (std::size_t q = 0; q < s.mean.size(); ++q) {
            // Means of finite floats are finite in double.
            require(std::isfinite(s.mean[q]) && s.min[q] <= s.max[q], "bad statistics");
        }
    }
    PointCloudWriteOptions options;
    options.ptc_version = c.file_version;
    PointCloud back;
    try {
        write_ptc(c, out.path(), options);
        back = read_ptc(out.path());
    } catch (const std::exception& e) {
        finding(std::string("a cloud that was read cannot be written and read back: ") +
                e.what());
    }
    require(back.size() == c.size() && back.channels.size() == c.channels.size(),
            "write + read back changed the point or channel count");
    require(same_bits(back.positions.data(), c.positions.data(),
                      c.size() * sizeof(glm::vec3)) &&
                same_bits(back.radii.data(), c.radii.data(), c.size() * sizeof(float)),
            "write + read back changed positions or radii");
    for (std::size_t i = 0; i < c.channels.size(); ++i) {
        const Channel& a = c.channels[i];
        const Channel& b = back.channels[i];
        require(
            a.name == b.name && a.type == b.type &&
                same_bits(a.data.data(), b.data.data(), a.data.size() * sizeof(float)),
            "write + read back changed channel '" + a.name + "'");
    }
}

} // namespace sss::fuzz
