// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file cloud_part.cpp
/// The .ptpart file: a little-endian header (counts, fingerprint, the whole
/// cloud's header and channel table, CRC-32), then the part's arrays and their
/// CRC-32. Layout in docs/file-formats.md ("Part files").

#include "sss/cloud/cloud_part.h"

#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <optional>

#include "sss/util/atomic_output.h"
#include "sss/util/byte_io.h"
#include "sss/util/error.h"
#include "sss/util/hash.h"
#include "sss/util/limits.h"

namespace sss {

namespace {

using namespace detail;

constexpr std::array<unsigned char, 8> kMagic = {'S', 'S', 'S', 'P', 'A', 'R', 'T', 0x1a};
constexpr uint32_t kVersion = 1;
constexpr std::size_t kFixedHeader = 204; // up to the channel table
constexpr uint32_t kMaxChannels = 4096;
constexpr uint32_t kMaxNameLength = 4096;
constexpr std::size_t kChunk = 1 << 16; // bytes converted at a time

// A channel of the table: name and type.
struct ChannelSpec {
    std::string name;
    ChannelType type;
};

// Floats per point of the records after the indices: position, normal,
// radius, channels.
uint64_t floats_per_point(const std::vector<ChannelSpec>& channels) {
    uint64_t w = 7;
    for (const ChannelSpec& c : channels) w += uint64_t(channel_type_size(c.type));
    return w;
}

void store_le(unsigned char* p, float v) {
    store_f32(p, v);
}
void store_le(unsigned char* p, uint64_t v) {
    store_u64(p, v);
}
void load_le(const unsigned char* p, float& v) {
    v = load_f32(p);
}
void load_le(const unsigned char* p, uint64_t& v) {
    v = load_u64(p);
}

// Writes arrays through a sink, counting their CRC.
class CrcSink {
public:
    explicit CrcSink(ByteSink& sink) : m_sink(sink) {}
    void bytes(const void* p, std::size_t n) {
        m_crc = crc32(m_crc, p, n);
        m_sink.write(p, n);
    }
    void u32(uint32_t v) {
        unsigned char b[4];
        store_u32(b, v);
        bytes(b, 4);
    }
    // Arrays of floats or u64, little-endian, through a chunk buffer.
    template <class T>
    void values(const T* v, std::size_t n) {
        unsigned char buf[kChunk];
        while (n > 0) {
            std::size_t k = std::min(n, kChunk / sizeof(T));
            for (std::size_t i = 0; i < k; ++i) store_le(buf + sizeof(T) * i, v[i]);
            bytes(buf, sizeof(T) * k);
            v += k, n -= k;
        }
    }
    uint32_t crc() const { return m_crc; }
    void restart() { m_crc = 0; }

private:
    ByteSink& m_sink;
    uint32_t m_crc = 0;
};

// Reads arrays from a source, counting their CRC; FormatError at the end of
// the data.
class CrcSource {
public:
    explicit CrcSource(ByteSource& src) : m_src(src) {}
    void bytes(void* p, std::size_t n) {
        if (!m_src.read_exact(p, n))
            throw FormatError(m_src.path(), "part file is truncated");
        m_crc = crc32(m_crc, p, n);
    }
    uint32_t u32() {
        unsigned char b[4];
        bytes(b, 4);
        return load_u32(b);
    }
    template <class T>
    void values(T* v, std::size_t n) {
        unsigned char buf[kChunk];
        while (n > 0) {
            std::size_t k = std::min(n, kChunk / sizeof(T));
            bytes(buf, sizeof(T) * k);
            for (std::size_t i = 0; i < k; ++i) load_le(buf + sizeof(T) * i, v[i]);
            v += k, n -= k;
        }
    }
    uint32_t crc() const { return m_crc; }
    void restart(uint32_t crc = 0) { m_crc = crc; }
    // A word read outside the CRC (the stored CRC itself).
    uint32_t raw_u32() {
        unsigned char b[4];
        if (!m_src.read_exact(b, 4))
            throw FormatError(m_src.path(), "part file is truncated");
        return load_u32(b);
    }

private:
    ByteSource& m_src;
    uint32_t m_crc = 0;
};

// A part's header as read: what the file says, the cloud header and the
// channel table.
struct PartHeader {
    CloudPartInfo info;
    PointCloud shape; // no points: matrices, format, empty channels
    std::vector<ChannelSpec> channels;
    uint64_t header_bytes = 0; // up to and including the header CRC
};

std::string hex(uint64_t v) {
    char buf[20];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
    return buf;
}

std::string part_name(const CloudPartInfo& info) {
    return "part " + std::to_string(info.part) + "/" + std::to_string(info.parts);
}

// Reads the header from src and checks it (its CRC, the counts, and against
// the file's size when known).
PartHeader read_header(ByteSource& src) {
    const std::string& path = src.path();
    CrcSource in(src);
    unsigned char h[kFixedHeader];
    if (!src.read_exact(h, kFixedHeader) || !std::equal(kMagic.begin(), kMagic.end(), h))
        throw FormatError(path, "not a part file (ptfilter -part writes them)");
    // The header CRC covers the fixed part and the channel table.
    in.restart(crc32(0, h, kFixedHeader));
    PartHeader ph;
    CloudPartInfo& info = ph.info;
    const uint32_t version = load_u32(h + 8);
    if (version != kVersion)
        throw FormatError(path, "part file version " + std::to_string(version) +
                                    " is not supported (this build reads version " +
                                    std::to_string(kVersion) + ")");
    info.part = load_u32(h + 12);
    info.parts = load_u32(h + 16);
    const uint32_t flags = load_u32(h + 20);
    const uint32_t ptc_version = load_u32(h + 24);
    const uint32_t nchannels = load_u32(h + 28);
    info.fingerprint = load_u64(h + 32);
    info.total = load_u64(h + 40);
    info.first = load_u64(h + 48);
    info.count = load_u64(h + 56);
    for (int i = 0; i < 16; ++i) {
        ph.shape.world_to_eye[i] = load_f32(h + 64 + 4 * i);
        ph.shape.world_to_ndc[i] = load_f32(h + 128 + 4 * i);
    }
    for (int i = 0; i < 3; ++i) ph.shape.format[i] = load_f32(h + 192 + 4 * i);
    if (nchannels > kMaxChannels)
        throw FormatError(path, "part file header: " + std::to_string(nchannels) +
                                    " channels (at most " + std::to_string(kMaxChannels) +
                                    ")");
    for (uint32_t c = 0; c < nchannels; ++c) {
        std::string text[2];
        for (std::string& t : text) {
            const uint32_t len = in.u32();
            if (len == 0 || len > kMaxNameLength)
                throw FormatError(path, "part file header: bad channel name length " +
                                            std::to_string(len));
            t.resize(len);
            in.bytes(t.data(), len);
        }
        std::optional<ChannelType> type = parse_channel_type(text[1]);
        if (!type)
            throw FormatError(path,
                              "part file header: unknown channel type '" + text[1] + "'");
        ph.channels.push_back({text[0], *type});
    }
    if (in.raw_u32() != in.crc())
        throw FormatError(path, "part file header is damaged (checksum)");
    ph.header_bytes = src.consumed();
    // Checked after the CRC: a damaged count is reported as damage.
    if (info.parts == 0 || info.part == 0 || info.part > info.parts)
        throw FormatError(path, "part file header: part " + std::to_string(info.part) +
                                    " of " + std::to_string(info.parts));
    if ((flags & ~1u) != 0 || ptc_version > 2)
        throw FormatError(path, "part file header: bad write options");
    info.write_options.compress = (flags & 1u) != 0;
    info.write_options.ptc_version = int(ptc_version);
    if (info.first > info.total || info.count > info.total - info.first)
        throw FormatError(path, "part file header: points " + std::to_string(info.first) +
                                    " + " + std::to_string(info.count) + " of " +
                                    std::to_string(info.total));
    for (const ChannelSpec& c : ph.channels) ph.shape.add_channel(c.name, c.type);
    // The data's size follows from the header: a short file is truncated.
    const uint64_t per_point = 8 + 4 * floats_per_point(ph.channels);
    const uint64_t expected = ph.header_bytes + per_point * info.count + 4;
    if (std::optional<uint64_t> bound = src.remaining_bound();
        bound && (info.count > *bound / per_point))
        throw FormatError(path, "part file is truncated (" + std::to_string(info.count) +
                                    " points announced)");
    if (!src.compressed()) {
        struct stat st {};
        if (::stat(path.c_str(), &st) == 0 && uint64_t(st.st_size) != expected)
            throw FormatError(
                path, uint64_t(st.st_size) < expected
                          ? "part file is truncated (" + std::to_string(st.st_size) +
                                " bytes of " + std::to_string(expected) + ")"
                          : "part file has " +
                                std::to_string(uint64_t(st.st_size) - expected) +
                                " bytes after its end");
    }
    return ph;
}

// Reads the data that follows a header into part (sized and checked).
void read_data(ByteSource& src, const PartHeader& ph, CloudPart& part) {
    const std::size_t m = std::size_t(ph.info.count);
    CrcSource in(src);
    part.info = ph.info;
    part.indices.resize(m);
    in.values(part.indices.data(), m);
    PointCloud& pts = part.points;
    pts = ph.shape;
    pts.resize(m);
    in.values(reinterpret_cast<float*>(pts.positions.data()), 3 * m);
    in.values(reinterpret_cast<float*>(pts.normals.data()), 3 * m);
    in.values(pts.radii.data(), m);
    for (Channel& c : pts.channels) in.values(c.data.data(), c.data.size());
    if (in.raw_u32() != in.crc())
        throw FormatError(src.path(), "part file data is damaged (checksum)");
    src.finish();
    for (std::size_t k = 0; k < m; ++k) {
        if (part.indices[k] >= ph.info.total)
            throw FormatError(src.path(),
                              "point index " + std::to_string(part.indices[k]) +
                                  " out of range (" + std::to_string(ph.info.total) +
                                  " points)",
                              int64_t(k));
    }
}

bool same_shape(const PartHeader& a, const PartHeader& b) {
    if (a.channels.size() != b.channels.size()) return false;
    for (std::size_t c = 0; c < a.channels.size(); ++c)
        if (a.channels[c].name != b.channels[c].name ||
            a.channels[c].type != b.channels[c].type)
            return false;
    return a.shape.world_to_eye == b.shape.world_to_eye &&
           a.shape.world_to_ndc == b.shape.world_to_ndc &&
           a.shape.format == b.shape.format;
}

} // namespace

void write_cloud_part(const CloudPart& part, const std::string& path) {
    const CloudPartInfo& info = part.info;
    const PointCloud& pts = part.points;
    const std::size_t m = pts.size();
    if (info.parts == 0 || info.part == 0 || info.part > info.parts ||
        part.indices.size() != m || info.count != m || info.first > info.total ||
        info.count > info.total - info.first || pts.normals.size() != m ||
        pts.radii.size() != m)
        throw ValueError(path + ": inconsistent part (" + part_name(info) + ", " +
                         std::to_string(m) + " points)");
    for (const Channel& c : pts.channels)
        if (c.data.size() != m * std::size_t(c.components()))
            throw ValueError(path + ": channel '" + c.name + "' has the wrong size");
    for (uint64_t i : part.indices)
        if (i >= info.total)
            throw ValueError(path + ": point index " + std::to_string(i) +
                             " out of range");

    unsigned char h[kFixedHeader] = {};
    std::copy(kMagic.begin(), kMagic.end(), h);
    store_u32(h + 8, kVersion);
    store_u32(h + 12, info.part);
    store_u32(h + 16, info.parts);
    store_u32(h + 20, info.write_options.compress ? 1u : 0u);
    store_u32(h + 24, uint32_t(info.write_options.ptc_version));
    store_u32(h + 28, uint32_t(pts.channels.size()));
    store_u64(h + 32, info.fingerprint);
    store_u64(h + 40, info.total);
    store_u64(h + 48, info.first);
    store_u64(h + 56, info.count);
    for (int i = 0; i < 16; ++i) {
        store_f32(h + 64 + 4 * i, pts.world_to_eye[i]);
        store_f32(h + 128 + 4 * i, pts.world_to_ndc[i]);
    }
    for (int i = 0; i < 3; ++i) store_f32(h + 192 + 4 * i, pts.format[i]);

    AtomicOutput out(path);
    ByteSink sink(out.temp_path(), path, false);
    CrcSink o(sink);
    o.bytes(h, kFixedHeader);
    for (const Channel& c : pts.channels)
        for (const std::string& t : {c.name, std::string(channel_type_name(c.type))}) {
            o.u32(uint32_t(t.size()));
            o.bytes(t.data(), t.size());
        }
    const uint32_t header_crc = o.crc();
    unsigned char b[4];
    store_u32(b, header_crc);
    sink.write(b, 4);
    o.restart();
    o.values(part.indices.data(), m);
    o.values(reinterpret_cast<const float*>(pts.positions.data()), 3 * m);
    o.values(reinterpret_cast<const float*>(pts.normals.data()), 3 * m);
    o.values(pts.radii.data(), m);
    for (const Channel& c : pts.channels) o.values(c.data.data(), c.data.size());
    store_u32(b, o.crc());
    sink.write(b, 4);
    sink.close();
    out.commit();
}

CloudPartInfo read_cloud_part_info(const std::string& path) {
    ByteSource src(path);
    return read_header(src).info;
}

CloudPart read_cloud_part(const std::string& path) {
    ByteSource src(path);
    PartHeader ph = read_header(src);
    CloudPart part;
    read_data(src, ph, part);
    return part;
}

PointCloud merge_cloud_parts(const std::vector<std::string>& paths,
                             PointCloudWriteOptions& write_options) {
    if (paths.empty()) throw ValueError("no part files to join");
    // Every header first: a missing or foreign part is found before any data
    // is read.
    std::vector<PartHeader> headers;
    for (const std::string& p : paths) {
        ByteSource src(p);
        headers.push_back(read_header(src));
    }
    const PartHeader& h0 = headers[0];
    const uint32_t parts = h0.info.parts;
    std::map<uint32_t, std::size_t> by_part; // K -> which file
    for (std::size_t i = 0; i < headers.size(); ++i) {
        const CloudPartInfo& info = headers[i].info;
        if (info.fingerprint != h0.info.fingerprint || info.parts != parts ||
            info.total != h0.info.total)
            throw ValueError(
                paths[i] + " (" + part_name(info) + ") is not from the job of " +
                paths[0] + " (" + part_name(h0.info) +
                "): other input, options or number of parts (fingerprint " +
                hex(info.fingerprint) + ", not " + hex(h0.info.fingerprint) + ")");
        if (!same_shape(headers[i], h0))
            throw ValueError(paths[i] + ": channels or header differ from " + paths[0]);
        auto [it, fresh] = by_part.try_emplace(info.part, i);
        if (!fresh)
            throw ValueError(part_name(info) + " given twice: " + paths[it->second] +
                             " and " + paths[i]);
    }
    if (by_part.size() != parts) {
        std::string missing;
        for (uint32_t k = 1; k <= parts; ++k)
            if (!by_part.count(k)) {
                if (!missing.empty()) missing += ", ";
                if (missing.size() > 200) {
                    missing += "...";
                    break;
                }
                missing += std::to_string(k);
            }
        throw ValueError("missing part" +
                         std::string(parts - by_part.size() > 1 ? "s " : " ") + missing +
                         " of " + std::to_string(parts) +
                         " (given: " + std::to_string(by_part.size()) + ")");
    }
    uint64_t next = 0;
    for (auto [k, i] : by_part) {
        const CloudPartInfo& info = headers[i].info;
        if (info.first != next)
            throw FormatError(paths[i], part_name(info) + " starts at point " +
                                            std::to_string(info.first) + ", expected " +
                                            std::to_string(next));
        next += info.count;
    }
    if (next != h0.info.total)
        throw FormatError(paths[by_part.rbegin()->second],
                          "the parts hold " + std::to_string(next) + " points, not " +
                              std::to_string(h0.info.total));

    // The whole cloud and the largest part held at once: their sizes are
    // backed by the files' (read_header), the budget still decides.
    const uint64_t per_point = 8 + 4 * floats_per_point(h0.channels);
    uint64_t largest = 0;
    for (const PartHeader& h : headers) largest = std::max(largest, h.info.count);
    check_memory((h0.info.total + largest) * per_point + h0.info.total,
                 "joining the " + std::to_string(h0.info.total) + " points of " +
                     std::to_string(parts) + " parts",
                 "join them where more memory is available");
    PointCloud whole = h0.shape;
    const std::size_t n = std::size_t(h0.info.total);
    whole.resize(n);
    std::vector<uint8_t> seen(n, 0);
    for (auto [k, i] : by_part) {
        ByteSource src(paths[i]);
        PartHeader ph = read_header(src);
        if (ph.info.fingerprint != h0.info.fingerprint || ph.info.part != k)
            throw FormatError(paths[i], "changed while the parts were joined");
        CloudPart part;
        read_data(src, ph, part);
        for (std::size_t j = 0; j < part.indices.size(); ++j) {
            const std::size_t at = std::size_t(part.indices[j]);
            if (seen[at])
                throw FormatError(paths[i],
                                  "point " + std::to_string(at) + " is in two parts",
                                  int64_t(j));
            seen[at] = 1;
            whole.positions[at] = part.points.positions[j];
            whole.normals[at] = part.points.normals[j];
            whole.radii[at] = part.points.radii[j];
            for (std::size_t c = 0; c < whole.channels.size(); ++c) {
                const std::size_t w = std::size_t(whole.channels[c].components());
                std::copy_n(part.points.channels[c].data.begin() + std::ptrdiff_t(w * j),
                            w, whole.channels[c].data.begin() + std::ptrdiff_t(w * at));
            }
        }
    }
    write_options = h0.info.write_options;
    return whole;
}

uint64_t cloud_fingerprint(const PointCloud& cloud, uint64_t seed) {
    uint64_t h = hash_bytes(&seed, sizeof seed, cloud.size());
    auto add = [&](const void* p, std::size_t n) { h = hash_bytes(p, n, h); };
    if (!cloud.positions.empty()) {
        add(cloud.positions.data(), cloud.positions.size() * sizeof(glm::vec3));
        add(cloud.normals.data(), cloud.normals.size() * sizeof(glm::vec3));
    }
    add(cloud.radii.data(), cloud.radii.size() * sizeof(float));
    for (const Channel& c : cloud.channels) {
        add(c.name.data(), c.name.size());
        const int type = int(c.type);
        add(&type, sizeof type);
        add(c.data.data(), c.data.size() * sizeof(float));
    }
    add(cloud.world_to_eye.data(), sizeof cloud.world_to_eye);
    add(cloud.world_to_ndc.data(), sizeof cloud.world_to_ndc);
    add(cloud.format.data(), sizeof cloud.format);
    return h;
}

} // namespace sss
