// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file point_cloud.cpp
/// PointCloud container operations and channel type helpers.

#include "sss/cloud/point_cloud.h"

#include <algorithm>
#include <cctype>

#include <glm/common.hpp>

#include "sss/util/error.h"
#include "sss/util/name_table.h"

namespace sss {

int channel_type_size(ChannelType type) {
    switch (type) {
    case ChannelType::Float:
        return 1;
    case ChannelType::Color:
    case ChannelType::Point:
    case ChannelType::Vector:
    case ChannelType::Normal:
        return 3;
    case ChannelType::Matrix:
        return 16;
    }
    return 1; // unreachable for valid enum values
}

namespace {

constexpr NameTable<ChannelType, 6> kChannelTypes({{{ChannelType::Float, "float"},
                                                    {ChannelType::Color, "color"},
                                                    {ChannelType::Point, "point"},
                                                    {ChannelType::Vector, "vector"},
                                                    {ChannelType::Normal, "normal"},
                                                    {ChannelType::Matrix, "matrix"}}},
                                                  "float");

} // namespace

const char* channel_type_name(ChannelType type) {
    return kChannelTypes.name(type);
}

std::optional<ChannelType> parse_channel_type(std::string_view name) {
    return kChannelTypes.parse(name);
}

PointCloud PointCloud::points_only() const {
    PointCloud out;
    out.positions = positions;
    out.normals = normals;
    out.radii = radii;
    out.world_to_eye = world_to_eye;
    out.world_to_ndc = world_to_ndc;
    out.format = format;
    return out;
}

void PointCloud::resize(std::size_t n) {
    positions.resize(n, glm::vec3(0.0f));
    normals.resize(n, glm::vec3(0.0f));
    radii.resize(n, 0.0f);
    for (Channel& c : channels)
        c.data.resize(n * static_cast<std::size_t>(c.components()));
}

const Channel* PointCloud::find_channel(std::string_view name) const {
    for (const Channel& c : channels) {
        if (c.name == name) return &c;
    }
    return nullptr;
}

Channel* PointCloud::find_channel(std::string_view name) {
    for (Channel& c : channels) {
        if (c.name == name) return &c;
    }
    return nullptr;
}

Channel& PointCloud::add_channel(const std::string& name, ChannelType type) {
    // Names end up in "<type> <name>\n" header lines, so they must be one word.
    if (name.empty()) throw ValueError("channel name must not be empty");
    for (char ch : name) {
        if (std::isspace(static_cast<unsigned char>(ch)) ||
            std::iscntrl(static_cast<unsigned char>(ch))) {
            throw ValueError("channel name '" + name +
                             "' contains whitespace or control characters");
        }
    }
    if (Channel* existing = find_channel(name)) {
        if (existing->type != type) {
            throw ValueError("channel '" + name + "' already exists as " +
                             channel_type_name(existing->type) + ", not " +
                             channel_type_name(type));
        }
        return *existing;
    }
    Channel c;
    c.name = name;
    c.type = type;
    c.data.assign(size() * static_cast<std::size_t>(c.components()), 0.0f);
    channels.push_back(std::move(c));
    return channels.back();
}

int PointCloud::data_size() const {
    int total = 0;
    for (const Channel& c : channels) total += c.components();
    return total;
}

Bounds3 PointCloud::bounds() const {
    Bounds3 b;
    if (positions.empty()) return b;
    b.lo = b.hi = positions.front();
    for (const glm::vec3& p : positions) {
        b.lo = glm::min(b.lo, p);
        b.hi = glm::max(b.hi, p);
    }
    return b;
}

void PointCloud::append(const PointCloud& other) {
    if (&other == this) {
        const PointCloud copy = other; // appending to itself would read what it writes
        append(copy);
        return;
    }
    // Check every type conflict before changing anything (all-or-nothing).
    for (const Channel& oc : other.channels) {
        const Channel* mine = find_channel(oc.name);
        if (mine && mine->type != oc.type) {
            throw ValueError("cannot merge channel '" + oc.name +
                             "': " + channel_type_name(mine->type) + " here, " +
                             channel_type_name(oc.type) + " in the appended cloud");
        }
    }
    const std::size_t n0 = size();
    const std::size_t n1 = other.size();
    for (const Channel& oc : other.channels) add_channel(oc.name, oc.type);
    resize(n0 + n1); // zero-fills channels the other cloud lacks

    std::copy_n(other.positions.begin(), std::min(n1, other.positions.size()),
                positions.begin() + static_cast<std::ptrdiff_t>(n0));
    std::copy_n(other.normals.begin(), std::min(n1, other.normals.size()),
                normals.begin() + static_cast<std::ptrdiff_t>(n0));
    std::copy_n(other.radii.begin(), std::min(n1, other.radii.size()),
                radii.begin() + static_cast<std::ptrdiff_t>(n0));
    for (const Channel& oc : other.channels) {
        Channel* mine = find_channel(oc.name);
        const std::size_t k = static_cast<std::size_t>(oc.components());
        const std::size_t count = std::min(n1 * k, oc.data.size());
        std::copy_n(oc.data.begin(), count,
                    mine->data.begin() + static_cast<std::ptrdiff_t>(n0 * k));
    }
}

} // namespace sss
