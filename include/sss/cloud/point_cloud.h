// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file point_cloud.h
/// Module cloud: point clouds in memory, .ptc/.ply I/O, channel statistics,
/// point-cloud lookups and synthetic clouds.
/// May use: util.
///
/// In-memory point cloud: positions, normals, radii and named typed channels,
/// stored as a structure of arrays.

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <glm/vec3.hpp>

namespace sss {

/// The channel types of RenderMan point clouds.
enum class ChannelType { Float, Color, Point, Vector, Normal, Matrix };

/// Number of floats per point of a channel type (1, 3 or 16).
int channel_type_size(ChannelType type);
/// RenderMan spelling of a channel type ("float", "color", ...).
const char* channel_type_name(ChannelType type);
/// Parses a RenderMan type name; nullopt if unknown.
std::optional<ChannelType> parse_channel_type(std::string_view name);

/// One named channel; data holds size() * components() floats, point-major.
struct Channel {
    std::string name;
    ChannelType type = ChannelType::Float;
    std::vector<float> data;

    int components() const { return channel_type_size(type); }
};

/// Axis-aligned bounding box.
struct Bounds3 {
    glm::vec3 lo{0.0f};
    glm::vec3 hi{0.0f};
};

/// A point cloud. All per-point arrays have the same length size().
struct PointCloud {
    std::vector<glm::vec3> positions;
    std::vector<glm::vec3> normals; ///< zero vector = no normal (a sphere, not a disk)
    std::vector<float> radii;
    std::vector<Channel> channels;

    /// Header matrices and image format kept from RenderMan files (row-major 4x4).
    std::array<float, 16> world_to_eye{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    std::array<float, 16> world_to_ndc{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    std::array<float, 3> format{0.0f, 0.0f, 1.0f}; ///< x res, y res, pixel aspect
    int file_version = 0;         ///< .ptc version the cloud was read from (0 otherwise)
    bool file_compressed = false; ///< the file it was read from was gzip-compressed

    std::size_t size() const { return positions.size(); }
    /// Resizes every per-point array, channels included.
    void resize(std::size_t n);
    /// The same points (positions, normals, radii) and header, without
    /// channels: what a tool's output cloud starts from.
    PointCloud points_only() const;
    /// Channel by name, or nullptr.
    const Channel* find_channel(std::string_view name) const;
    Channel* find_channel(std::string_view name);
    /// Adds a zero-filled channel (or returns the existing one of the same type).
    /// Throws ValueError if a channel of that name exists with another type.
    /// Adding a channel invalidates references to the others (a vector).
    Channel& add_channel(const std::string& name, ChannelType type);
    /// Total floats per point over all channels (the PTC "datasize").
    int data_size() const;
    /// Bounding box of the positions (zero box when empty).
    Bounds3 bounds() const;
    /// Appends all points of other. Channels are matched by name and type;
    /// channels missing on one side are zero-filled. Header data of *this wins.
    void append(const PointCloud& other);
};

} // namespace sss
