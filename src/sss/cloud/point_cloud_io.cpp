// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file point_cloud_io.cpp
/// Format dispatch, write-time checks, channel statistics and the ptinfo
/// report. The formats themselves live in ptc_io.cpp and ply_io.cpp, the byte
/// streams they use in util/byte_io.cpp.

#include "sss/cloud/point_cloud_io.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <limits>
#include <set>
#include <sstream>

#include "point_cloud_io_detail.h"
#include "sss/util/error.h"
#include "sss/util/limits.h"
#include "sss/util/messages.h"

namespace sss {

void check_channel_name(const std::string& name, ChannelType type) {
    if (name.empty()) throw ValueError("channel with an empty name");
    for (char ch : name) {
        // isspace/iscntrl of the "C" locale: ASCII only, UTF-8 names pass.
        if (ch == '\0' || std::isspace(static_cast<unsigned char>(ch)) ||
            std::iscntrl(static_cast<unsigned char>(ch))) {
            throw ValueError("channel name " + sss::quoted(name) +
                             " contains whitespace or control characters");
        }
    }
    const std::string_view type_name = channel_type_name(type);
    if (type_name.size() + 1 + name.size() > kMaxChannelSpecLine) {
        throw ValueError("channel name " + sss::quoted(name) + " is " +
                         std::to_string(name.size()) + " bytes long: a " +
                         std::string(type_name) + " channel's name may have at most " +
                         std::to_string(kMaxChannelSpecLine - 1 - type_name.size()) +
                         " (a .ptc header line \"<type> <name>\" at most " +
                         std::to_string(kMaxChannelSpecLine) + ")");
    }
}

namespace detail {

namespace {

bool all_finite(const float* v, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) {
        if (!std::isfinite(v[i])) return false;
    }
    return true;
}

} // namespace

void check_channel_names(const PointCloud& cloud) {
    std::set<std::string> names;
    for (const Channel& c : cloud.channels) {
        check_channel_name(c.name, c.type);
        if (!names.insert(c.name).second)
            throw ValueError("duplicate channel " + sss::quoted(c.name));
    }
}

void check_writable(const PointCloud& cloud) {
    const std::size_t n = cloud.size();
    if (cloud.normals.size() != n || cloud.radii.size() != n) {
        throw ValueError("inconsistent point cloud: " + std::to_string(n) +
                         " positions, " + std::to_string(cloud.normals.size()) +
                         " normals, " + std::to_string(cloud.radii.size()) + " radii");
    }
    if (!all_finite(cloud.world_to_eye.data(), 16) ||
        !all_finite(cloud.world_to_ndc.data(), 16) ||
        !all_finite(cloud.format.data(), 3)) {
        throw ValueError("non-finite value in the header matrices or image format");
    }
    check_channel_names(cloud);
    for (const Channel& c : cloud.channels) {
        const std::size_t k = static_cast<std::size_t>(c.components());
        if (c.data.size() != n * k) {
            throw ValueError("inconsistent point cloud: channel " + sss::quoted(c.name) +
                             " holds " + std::to_string(c.data.size()) +
                             " floats, expected " + std::to_string(n * k));
        }
    }
    for (std::size_t i = 0; i < n; ++i) {
        const std::string at = " at point " + std::to_string(i);
        if (!all_finite(&cloud.positions[i].x, 3))
            throw ValueError("non-finite position" + at);
        if (!all_finite(&cloud.normals[i].x, 3))
            throw ValueError("non-finite normal" + at);
        if (!std::isfinite(cloud.radii[i])) throw ValueError("non-finite radius" + at);
        if (cloud.radii[i] < 0.0f) throw ValueError("negative radius" + at);
    }
    for (const Channel& c : cloud.channels) {
        const std::size_t k = static_cast<std::size_t>(c.components());
        for (std::size_t i = 0; i < c.data.size(); ++i) {
            if (!std::isfinite(c.data[i])) {
                throw ValueError("non-finite value in channel " + sss::quoted(c.name) +
                                 " at point " + std::to_string(i / k));
            }
        }
    }
}

namespace {

// Points reserved at first when the count is unverified: about 1 MB of arrays.
constexpr uint64_t kFirstReserveBytes = 1 << 20;
// Reservations smaller than this are not checked against the memory budget
// (reading /proc and the cgroup files for every small cloud is wasted work).
constexpr uint64_t kCheckedReserveBytes = 4 << 20;

} // namespace

CloudReserve::CloudReserve(PointCloud& cloud, const std::string& path, uint64_t claimed,
                           bool verified)
    : m_cloud(cloud), m_path(path), m_claimed(claimed),
      m_point_bytes(sizeof(glm::vec3) * 2 + sizeof(float) +
                    sizeof(float) * static_cast<uint64_t>(cloud.data_size())) {
    if (verified) reserve(claimed);
}

void CloudReserve::grow(uint64_t needed) {
    if (needed > m_claimed) {
        // The readers never append more than the header's count.
        throw FormatError(m_path, "more points than the header's count " +
                                      std::to_string(m_claimed));
    }
    const uint64_t first = std::max<uint64_t>(1, kFirstReserveBytes / m_point_bytes);
    reserve(std::min(m_claimed, std::max({needed, 2 * m_capacity, first})));
}

void CloudReserve::reserve(uint64_t capacity) {
    if (capacity <= m_capacity) return;
    const uint64_t points = capacity - m_cloud.size();
    const uint64_t more = points > std::numeric_limits<uint64_t>::max() / m_point_bytes
                              ? std::numeric_limits<uint64_t>::max()
                              : points * m_point_bytes;
    if (more >= kCheckedReserveBytes) {
        const std::string what =
            capacity == m_claimed
                ? m_path + ": reading its " + std::to_string(m_claimed) + " points"
                : m_path + ": holding " + std::to_string(capacity) + " of the " +
                      std::to_string(m_claimed) + " points its header claims";
        check_memory(more, what,
                     "read it where more memory is available, or check that the file "
                     "is not damaged");
    }
    const std::size_t n = static_cast<std::size_t>(capacity);
    m_cloud.positions.reserve(n);
    m_cloud.normals.reserve(n);
    m_cloud.radii.reserve(n);
    for (Channel& c : m_cloud.channels)
        c.data.reserve(n * static_cast<std::size_t>(c.components()));
    m_capacity = capacity;
}

bool has_extension(const std::string& path, const std::string& ext) {
    if (path.size() < ext.size()) return false;
    const std::string tail = path.substr(path.size() - ext.size());
    return std::equal(tail.begin(), tail.end(), ext.begin(), ext.end(),
                      [](char a, char b) {
                          return std::tolower(static_cast<unsigned char>(a)) ==
                                 std::tolower(static_cast<unsigned char>(b));
                      });
}

std::string format_float(double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.9g", v);
    return buf;
}

} // namespace detail

PointCloud read_point_cloud(const std::string& path) {
    return detail::has_extension(path, ".ply") ? read_ply(path) : read_ptc(path);
}

void write_point_cloud(const PointCloud& cloud, const std::string& path,
                       const PointCloudWriteOptions& options) {
    if (detail::has_extension(path, ".ply")) {
        write_ply(cloud, path);
    } else {
        write_ptc(cloud, path, options);
    }
}

struct PointCloudReader::Impl {
    std::unique_ptr<detail::PtcReader> ptc;
    PointCloud whole; // .ply: the whole cloud, handed out in chunks
    PointCloud header;
    uint64_t next = 0;
};

PointCloudReader::PointCloudReader(const std::string& path)
    : m_impl(std::make_unique<Impl>()) {
    if (detail::has_extension(path, ".ply")) {
        m_impl->whole = read_ply(path);
        m_impl->header = m_impl->whole;
        m_impl->header.resize(0);
    } else {
        m_impl->ptc = std::make_unique<detail::PtcReader>(path);
        m_impl->header = m_impl->ptc->header();
    }
}

PointCloudReader::~PointCloudReader() = default;

const PointCloud& PointCloudReader::header() const {
    return m_impl->header;
}

uint64_t PointCloudReader::size() const {
    return m_impl->ptc ? m_impl->ptc->size() : m_impl->whole.size();
}

bool PointCloudReader::size_verified() const {
    return m_impl->ptc ? m_impl->ptc->verified() : true;
}

std::size_t PointCloudReader::read(PointCloud& chunk, std::size_t max) {
    Impl& m = *m_impl;
    bool same = chunk.channels.size() == m.header.channels.size();
    for (std::size_t c = 0; same && c < chunk.channels.size(); ++c)
        same = chunk.channels[c].name == m.header.channels[c].name &&
               chunk.channels[c].type == m.header.channels[c].type;
    if (!same) chunk.channels = m.header.channels;
    chunk.resize(0);
    if (m.ptc) return m.ptc->read_into(chunk, max, nullptr);
    const std::size_t first = static_cast<std::size_t>(m.next);
    const std::size_t k = std::min<std::size_t>(max, m.whole.size() - first);
    const auto at = [first](auto& v, std::size_t w) {
        return v.begin() + static_cast<std::ptrdiff_t>(first * w);
    };
    chunk.positions.assign(at(m.whole.positions, 1), at(m.whole.positions, 1) + k);
    chunk.normals.assign(at(m.whole.normals, 1), at(m.whole.normals, 1) + k);
    chunk.radii.assign(at(m.whole.radii, 1), at(m.whole.radii, 1) + k);
    for (std::size_t c = 0; c < chunk.channels.size(); ++c) {
        const std::size_t w = static_cast<std::size_t>(chunk.channels[c].components());
        auto& src = m.whole.channels[c].data;
        chunk.channels[c].data.assign(at(src, w), at(src, w) + std::ptrdiff_t(k * w));
    }
    m.next += k;
    return k;
}

struct PointCloudWriter::Impl {
    std::unique_ptr<detail::PtcWriter> ptc;
    PointCloud whole; // .ply: gathered, written on commit
    std::string path;
    uint64_t count = 0;
};

PointCloudWriter::PointCloudWriter(const std::string& path, const PointCloud& header,
                                   uint64_t count, const Bounds3& bounds,
                                   float max_radius,
                                   const PointCloudWriteOptions& options)
    : m_impl(std::make_unique<Impl>()) {
    m_impl->path = path;
    m_impl->count = count;
    detail::check_channel_names(header);
    if (detail::has_extension(path, ".ply")) {
        m_impl->whole = header;
        m_impl->whole.resize(0);
    } else {
        m_impl->ptc = std::make_unique<detail::PtcWriter>(path, header, count, bounds,
                                                          max_radius, options);
    }
}

PointCloudWriter::~PointCloudWriter() = default;

void PointCloudWriter::write(const PointCloud& chunk) {
    detail::check_writable(chunk);
    if (m_impl->ptc)
        m_impl->ptc->write(chunk);
    else
        m_impl->whole.append(chunk);
}

void PointCloudWriter::commit() {
    if (m_impl->ptc) {
        m_impl->ptc->commit();
        return;
    }
    if (m_impl->whole.size() != m_impl->count)
        throw ValueError("point cloud writer: " + std::to_string(m_impl->whole.size()) +
                         " of the " + std::to_string(m_impl->count) +
                         " points announced were written");
    write_ply(m_impl->whole, m_impl->path);
}

std::vector<ChannelStats> channel_stats(const PointCloud& cloud) {
    const std::size_t n = cloud.size();
    auto compute = [n](const std::string& name, ChannelType type, const float* data,
                       std::size_t available) {
        ChannelStats s;
        s.name = name;
        s.type = type;
        const std::size_t k = static_cast<std::size_t>(channel_type_size(type));
        s.min.assign(k, 0.0);
        s.mean.assign(k, 0.0);
        s.max.assign(k, 0.0);
        const std::size_t count = std::min(n, available / k);
        if (count == 0) return s;
        for (std::size_t c = 0; c < k; ++c) {
            double lo = data[c], hi = data[c], sum = 0.0;
            for (std::size_t i = 0; i < count; ++i) {
                const double v = data[i * k + c];
                lo = std::min(lo, v);
                hi = std::max(hi, v);
                sum += v;
            }
            s.min[c] = lo;
            s.mean[c] = sum / static_cast<double>(count);
            s.max[c] = hi;
        }
        return s;
    };
    std::vector<ChannelStats> out;
    out.push_back(
        compute("radius", ChannelType::Float, cloud.radii.data(), cloud.radii.size()));
    for (const Channel& c : cloud.channels) {
        out.push_back(compute(c.name, c.type, c.data.data(), c.data.size()));
    }
    return out;
}

bool is_identity(const std::array<float, 16>& m) {
    for (int r = 0; r < 4; ++r) {
        for (int c = 0; c < 4; ++c) {
            if (m[r * 4 + c] != (r == c ? 1.0f : 0.0f)) return false;
        }
    }
    return true;
}

std::string short_float(double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.6g", v);
    return buf;
}

std::string matrix_text(const std::array<float, 16>& m) {
    std::string s;
    for (int r = 0; r < 4; ++r) {
        if (r > 0) s += " |";
        for (int c = 0; c < 4; ++c) {
            s += ' ';
            s += short_float(m[r * 4 + c]);
        }
    }
    return s;
}

namespace {

const char* component_label(ChannelType type, int c) {
    static const char* const xyz[] = {"x", "y", "z"};
    static const char* const rgb[] = {"r", "g", "b"};
    static const char* const idx[] = {"0", "1", "2",  "3",  "4",  "5",  "6",  "7",
                                      "8", "9", "10", "11", "12", "13", "14", "15"};
    switch (type) {
    case ChannelType::Float:
        return "";
    case ChannelType::Color:
        return rgb[c];
    case ChannelType::Point:
    case ChannelType::Vector:
    case ChannelType::Normal:
        return xyz[c];
    case ChannelType::Matrix:
        return idx[c];
    }
    return "";
}

std::string stats_lines(const ChannelStats& s, const std::string& indent) {
    std::string out;
    for (std::size_t c = 0; c < s.min.size(); ++c) {
        const std::string label = component_label(s.type, static_cast<int>(c));
        out += indent + (label.empty() ? "" : label + ": ") + "min " +
               short_float(s.min[c]) + "  mean " + short_float(s.mean[c]) + "  max " +
               short_float(s.max[c]) + "\n";
    }
    return out;
}

} // namespace

std::string describe_point_cloud(const std::string& path, const PointCloud& cloud,
                                 bool stats) {
    std::ostringstream out;
    out << "file: " << path << "\n";
    if (detail::has_extension(path, ".ply")) {
        out << "format: ply\n";
    } else {
        out << "format: ptc version " << cloud.file_version << "\n";
    }
    out << "compressed: " << (cloud.file_compressed ? "yes (gzip)" : "no") << "\n";
    out << "points: " << cloud.size() << "\n";
    if (cloud.size() == 0) {
        out << "bbox: empty\n";
    } else {
        const Bounds3 b = cloud.bounds();
        out << "bbox: min " << short_float(b.lo.x) << " " << short_float(b.lo.y) << " "
            << short_float(b.lo.z) << "  max " << short_float(b.hi.x) << " "
            << short_float(b.hi.y) << " " << short_float(b.hi.z) << "\n";
    }
    if (!is_identity(cloud.world_to_eye))
        out << "world2eye:" << matrix_text(cloud.world_to_eye) << "\n";
    if (!is_identity(cloud.world_to_ndc))
        out << "world2ndc:" << matrix_text(cloud.world_to_ndc) << "\n";
    if (cloud.format != std::array<float, 3>{0.0f, 0.0f, 1.0f}) {
        out << "image format: " << short_float(cloud.format[0]) << " "
            << short_float(cloud.format[1]) << " " << short_float(cloud.format[2])
            << "\n";
    }
    out << "channels: " << cloud.channels.size() << " (datasize " << cloud.data_size()
        << ")\n";
    const bool with_stats = stats && cloud.size() > 0;
    const std::vector<ChannelStats> all =
        with_stats ? channel_stats(cloud) : std::vector<ChannelStats>{};
    for (std::size_t i = 0; i < cloud.channels.size(); ++i) {
        const Channel& c = cloud.channels[i];
        out << "  " << channel_type_name(c.type) << " " << c.name << "\n";
        if (with_stats) out << stats_lines(all[i + 1], "    ");
    }
    if (with_stats) out << "radius: " << stats_lines(all[0], "");
    return out.str();
}

} // namespace sss
