// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file ptc_io.cpp
/// Pixar .ptc point clouds, versions 0-2, plain or gzip. The layout follows
/// docs/file-formats.md: a little-endian binary header whose field offsets
/// depend on the version, "<type> <name>\n" channel spec lines, then fixed-size
/// records (position, packed normal, radius, channel data).

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <set>

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>

#include "point_cloud_io_detail.h"
#include "sss/cloud/point_cloud_io.h"
#include "sss/util/atomic_output.h"
#include "sss/util/error.h"
#include "sss/util/threads.h"

namespace sss {

namespace {

using namespace detail;

constexpr int32_t kPtcMagic = 0x63747070; // bytes on disk: "pptc"
constexpr int kMaxVersion = 2;
constexpr std::size_t kMaxSpecLine = kMaxChannelSpecLine + 1; // with the newline
constexpr std::size_t kRecordBase = 20; // 3 f32 position + 2 u16 normal + f32 radius
constexpr uint16_t kZeroNormalCode = 65535;
constexpr uint32_t kPadWord = 0xDEADBEEFu;
constexpr int kV2PadWords = 32;

/// Byte offsets of the header fields that move between versions.
struct PtcLayout {
    std::size_t max_radius; ///< v >= 2, followed by 32 pad words; 0 = absent
    std::size_t world2eye;
    std::size_t world2ndc;
    std::size_t format;
    std::size_t nvars; ///< followed by datasize
    std::size_t specs; ///< = size of the fixed binary header
};

PtcLayout layout_for(int version) {
    // Each optional block shifts everything after it: 16 bytes for the four
    // unknown floats of v1 (at offset 40), 4 + 32 * 4 = 132 bytes for the v2
    // max radius and padding (at offset 56).
    const std::size_t v1 = version >= 1 ? 16 : 0;
    const std::size_t v2 = version >= 2 ? 4 + 4 * kV2PadWords : 0;
    const std::size_t w2e = 40 + v1 + v2;
    const std::size_t max_radius = version >= 2 ? 56 : 0;
    return {max_radius, w2e, w2e + 64, w2e + 128, w2e + 140, w2e + 148};
}

glm::vec3 decode_normal(uint16_t phi_code, uint16_t z_code) {
    if (phi_code == kZeroNormalCode && z_code == kZeroNormalCode) return glm::vec3(0.0f);
    const double nz = 2.0 * z_code / 65535.0 - 1.0;
    const double phi = 2.0 * std::numbers::pi * (phi_code / 65535.0 - 0.5);
    const double s = std::sqrt(std::max(0.0, 1.0 - nz * nz));
    return glm::vec3(static_cast<float>(s * std::sin(phi)),
                     static_cast<float>(s * std::cos(phi)), static_cast<float>(nz));
}

/// Inverse of decode_normal with round-to-nearest (halves away from zero) on
/// both codes. The input is normalised first; a zero vector gets the
/// (65535, 65535) "no normal" code.
std::array<uint16_t, 2> encode_normal(const glm::vec3& n) {
    const double x = n.x, y = n.y, z = n.z;
    const double len = std::sqrt(x * x + y * y + z * z);
    if (len == 0.0) return {kZeroNormalCode, kZeroNormalCode};
    const double nz = std::clamp(z / len, -1.0, 1.0);
    const double phi = std::atan2(x, y); // x = s sin(phi), y = s cos(phi); in [-pi, pi]
    auto quantise = [](double unit) {
        return static_cast<uint16_t>(std::clamp(std::lround(unit * 65535.0), 0L, 65535L));
    };
    const uint16_t z_code = quantise((nz + 1.0) * 0.5);
    uint16_t phi_code = quantise(phi / (2.0 * std::numbers::pi) + 0.5);
    // (65535, 65535) would read back as "no normal". It arises only for a
    // normal within half a z step of +z with phi ~ pi, where sqrt(1 - nz^2) is
    // 0 once decoded, so phi = 0 gives back the same vector.
    if (phi_code == kZeroNormalCode && z_code == kZeroNormalCode) phi_code = 0;
    return {phi_code, z_code};
}

/// Reads one "<type> <name>" spec line (without the newline).
std::string read_spec_line(ByteSource& in, int index) {
    std::string line;
    for (;;) {
        const int c = in.get();
        if (c < 0) {
            throw FormatError(in.path(), "truncated channel specs (in spec line " +
                                             std::to_string(index + 1) + ")");
        }
        if (c == '\n') break;
        if (line.size() >= kMaxSpecLine) {
            throw FormatError(in.path(), "malformed channel spec line " +
                                             std::to_string(index + 1) + " (too long)");
        }
        line.push_back(static_cast<char>(c));
    }
    if (!line.empty() && line.back() == '\r') line.pop_back();
    return line;
}

Channel parse_spec_line(const std::string& path, const std::string& line, int index) {
    auto malformed = [&](const std::string& why) {
        return FormatError(path, "malformed channel spec line " +
                                     std::to_string(index + 1) + " '" + line +
                                     "': " + why);
    };
    for (char ch : line) {
        if ((static_cast<unsigned char>(ch) < 0x20 && ch != '\t') || ch == 0x7f) {
            throw malformed("control character");
        }
    }
    // Split on blanks; exactly two words are expected.
    std::vector<std::string> words;
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
        std::size_t j = i;
        while (j < line.size() && line[j] != ' ' && line[j] != '\t') ++j;
        if (j > i) words.push_back(line.substr(i, j - i));
        i = j;
    }
    if (words.size() != 2) throw malformed("expected '<type> <name>'");
    const std::optional<ChannelType> type = parse_channel_type(words[0]);
    if (!type) {
        throw FormatError(path, "unknown channel type '" + words[0] + "' in spec line " +
                                    std::to_string(index + 1));
    }
    Channel c;
    c.type = *type;
    c.name = words[1];
    return c;
}

} // namespace

namespace detail {

PtcReader::PtcReader(const std::string& path) : m_in(std::make_unique<ByteSource>(path)) {
    ByteSource& in = *m_in;
    const auto fail = [&](const std::string& what) { return FormatError(path, what); };

    unsigned char head[8];
    if (!in.read_exact(head, sizeof head)) {
        throw fail("file too short for a .ptc header (" + std::to_string(in.consumed()) +
                   " bytes)");
    }
    // OpenVDB's files start with the bytes " BD V" (0x56444220, little-endian).
    if (load_u32(head) == 0x56444220u)
        throw fail("an OpenVDB file, not a point cloud (brickinfo describes .vdb files)");
    if (load_i32(head) != kPtcMagic) {
        char buf[64];
        std::snprintf(buf, sizeof buf, "not a .ptc file (bad magic 0x%08x)",
                      load_u32(head));
        throw fail(buf);
    }
    const int32_t version = load_i32(head + 4);
    if (version < 0 || version > kMaxVersion) {
        throw fail("unsupported .ptc version " + std::to_string(version) +
                   " (versions 0, 1 and 2 are supported; organized clouds are not)");
    }
    const PtcLayout lay = layout_for(version);
    std::vector<unsigned char> header(lay.specs);
    std::copy(head, head + sizeof head, header.begin());
    if (!in.read_exact(header.data() + 8, header.size() - 8)) {
        throw fail("file too short for a version " + std::to_string(version) +
                   " .ptc header (" + std::to_string(in.consumed()) + " of " +
                   std::to_string(lay.specs) + " bytes)");
    }
    const unsigned char* h = header.data();

    const double npoints_d = load_f64(h + 8);
    // 2^53: the largest count a double holds exactly.
    if (!std::isfinite(npoints_d) || npoints_d < 0.0 ||
        npoints_d != std::floor(npoints_d) || npoints_d > 9007199254740992.0) {
        throw fail("invalid point count " + format_float(npoints_d) + " in the header");
    }
    const uint64_t npoints = static_cast<uint64_t>(npoints_d);

    PointCloud& cloud = m_header;
    cloud.file_version = version;
    cloud.file_compressed = in.compressed();
    for (int i = 0; i < 16; ++i) {
        cloud.world_to_eye[i] = load_f32(h + lay.world2eye + 4 * i);
        cloud.world_to_ndc[i] = load_f32(h + lay.world2ndc + 4 * i);
    }
    for (int i = 0; i < 3; ++i) cloud.format[i] = load_f32(h + lay.format + 4 * i);
    // Everything read is writable again, so the header must be finite too.
    for (float v : cloud.world_to_eye) {
        if (!std::isfinite(v)) throw fail("non-finite value in the world2eye matrix");
    }
    for (float v : cloud.world_to_ndc) {
        if (!std::isfinite(v)) throw fail("non-finite value in the world2ndc matrix");
    }
    for (float v : cloud.format) {
        if (!std::isfinite(v)) throw fail("non-finite value in the image format");
    }

    const int32_t nvars = load_i32(h + lay.nvars);
    const int32_t datasize = load_i32(h + lay.nvars + 4);
    if (nvars < 0 || nvars > kMaxChannels) {
        throw fail("invalid channel count nvars = " + std::to_string(nvars));
    }
    if (datasize < 0 || datasize > 16 * kMaxChannels) {
        throw fail("invalid datasize " + std::to_string(datasize));
    }

    std::set<std::string> names;
    int sum = 0;
    for (int i = 0; i < nvars; ++i) {
        Channel c = parse_spec_line(path, read_spec_line(in, i), i);
        if (!names.insert(c.name).second)
            throw fail("duplicate channel '" + c.name + "'");
        sum += c.components();
        cloud.channels.push_back(std::move(c));
    }
    if (sum != datasize) {
        throw fail("channel sizes add up to " + std::to_string(sum) +
                   " floats per point but the header datasize is " +
                   std::to_string(datasize));
    }
    if (version >= 1) {
        unsigned char extra[8]; // two floats of unknown meaning
        if (!in.read_exact(extra, sizeof extra)) {
            throw fail("truncated header after channel specs");
        }
    }

    const std::size_t record = kRecordBase + 4 * static_cast<std::size_t>(datasize);
    const std::optional<uint64_t> left = in.remaining_bound();
    if (left && npoints > *left / record) {
        if (in.compressed()) {
            throw fail("header claims " + std::to_string(npoints) + " points of " +
                       std::to_string(record) +
                       " bytes, more than the compressed file can hold");
        }
        // Exact for a plain file: name the first point whose record is missing.
        throw FormatError(path,
                          "truncated point data: header claims " +
                              std::to_string(npoints) + " points of " +
                              std::to_string(record) + " bytes but only " +
                              std::to_string(*left) + " bytes remain",
                          static_cast<int64_t>(*left / record));
    }
    m_npoints = npoints;
    m_record = record;
    m_verified = left.has_value() && !in.compressed();
}

PtcReader::~PtcReader() = default;

void PtcReader::decode_records(PointCloud& cloud, std::size_t k) {
    const std::size_t record = m_record;
    const unsigned char* buf = m_buf.data();
    // Checks one record, throwing what the reader reports for it.
    auto check = [&](std::size_t j) {
        const unsigned char* r = buf + j * record;
        const int64_t index = static_cast<int64_t>(m_done + j);
        const glm::vec3 p(load_f32(r), load_f32(r + 4), load_f32(r + 8));
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
            throw FormatError(m_in->path(), "non-finite position", index);
        const float radius = load_f32(r + 16);
        if (!std::isfinite(radius))
            throw FormatError(m_in->path(), "non-finite radius", index);
        if (radius < 0.0f) throw FormatError(m_in->path(), "negative radius", index);
        const unsigned char* d = r + kRecordBase;
        for (const Channel& c : cloud.channels)
            for (int q = 0; q < c.components(); ++q, d += 4)
                if (!std::isfinite(load_f32(d)))
                    throw FormatError(m_in->path(),
                                      "non-finite value in channel '" + c.name + "'",
                                      index);
    };
    const std::size_t first = cloud.positions.size();
    cloud.positions.resize(first + k);
    cloud.normals.resize(first + k);
    cloud.radii.resize(first + k);
    for (Channel& c : cloud.channels)
        c.data.resize((first + k) * std::size_t(c.components()));
    // Decoded in parallel (the normals' sqrt and sincos are most of it); the
    // first bad record, if any, is then checked again alone so that the error
    // names it exactly as a record-by-record read would.
    std::atomic<std::size_t> bad{k};
    oneapi::tbb::parallel_for(
        oneapi::tbb::blocked_range<std::size_t>(0, k, 4096),
        [&](const oneapi::tbb::blocked_range<std::size_t>& range) {
            for (std::size_t j = range.begin(); j != range.end(); ++j) {
                const unsigned char* r = buf + j * record;
                const glm::vec3 p(load_f32(r), load_f32(r + 4), load_f32(r + 8));
                const float radius = load_f32(r + 16);
                bool ok = std::isfinite(p.x) && std::isfinite(p.y) &&
                          std::isfinite(p.z) && std::isfinite(radius) && radius >= 0.0f;
                cloud.positions[first + j] = p;
                cloud.radii[first + j] = radius;
                cloud.normals[first + j] =
                    decode_normal(load_u16(r + 12), load_u16(r + 14));
                const unsigned char* d = r + kRecordBase;
                for (Channel& c : cloud.channels) {
                    const std::size_t n = std::size_t(c.components());
                    for (std::size_t q = 0; q < n; ++q, d += 4) {
                        const float v = load_f32(d);
                        ok = ok && std::isfinite(v);
                        c.data[(first + j) * n + q] = v;
                    }
                }
                if (!ok) lower_to(bad, j);
            }
        });
    if (bad.load() < k) check(bad.load());
}

std::size_t PtcReader::read_into(PointCloud& cloud, std::size_t max,
                                 CloudReserve* reserve) {
    const std::string& path = m_in->path();
    const std::size_t record = m_record;
    const std::size_t chunk_points = std::max<std::size_t>(1, (1 << 20) / record);
    const std::size_t want =
        static_cast<std::size_t>(std::min<uint64_t>(max, m_npoints - m_done));
    std::size_t taken = 0;
    while (taken < want) {
        const std::size_t k = std::min(chunk_points, want - taken);
        if (m_buf.size() < k * record) m_buf.resize(k * record);
        const std::size_t got = m_in->read(m_buf.data(), k * record);
        if (got < k * record) {
            const uint64_t complete = m_done + got / record;
            throw FormatError(path,
                              "truncated point data: header claims " +
                                  std::to_string(m_npoints) +
                                  " points, data ends after " + std::to_string(complete),
                              static_cast<int64_t>(complete));
        }
        if (reserve) reserve->room_for(k);
        decode_records(cloud, k);
        m_done += k;
        taken += k;
    }
    if (m_done == m_npoints && !m_finished) {
        m_in->finish();
        m_finished = true;
    }
    return taken;
}

} // namespace detail

PointCloud read_ptc(const std::string& path) {
    PtcReader reader(path);
    PointCloud cloud = reader.header();
    // A plain file has been checked exactly; otherwise grow as data arrives.
    CloudReserve reserve(cloud, path, reader.size(), reader.verified());
    while (reader.read_into(cloud, std::size_t(1) << 20, &reserve) > 0) {
    }
    return cloud;
}

namespace detail {

PtcWriter::PtcWriter(const std::string& path, const PointCloud& header, uint64_t count,
                     const Bounds3& bounds, float max_radius,
                     const PointCloudWriteOptions& options) {
    if (options.ptc_version < 0 || options.ptc_version > kMaxVersion) {
        throw ValueError("cannot write .ptc version " +
                         std::to_string(options.ptc_version) + " (0, 1 or 2)");
    }
    if (header.channels.size() > static_cast<std::size_t>(kMaxChannels)) {
        throw ValueError("too many channels for a .ptc file (" +
                         std::to_string(header.channels.size()) + ")");
    }
    const int version = options.ptc_version;
    const PtcLayout lay = layout_for(version);

    std::vector<unsigned char> head(lay.specs, 0);
    unsigned char* h = head.data();
    store_i32(h, kPtcMagic);
    store_i32(h + 4, version);
    store_f64(h + 8, static_cast<double>(count));
    const Bounds3& b = bounds;
    const float box[6] = {b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z};
    for (int i = 0; i < 6; ++i) store_f32(h + 16 + 4 * i, box[i]);
    // v1's four unknown floats stay zero.
    if (version >= 2) {
        store_f32(h + lay.max_radius, max_radius);
        for (int i = 0; i < kV2PadWords; ++i) {
            store_u32(h + lay.max_radius + 4 + 4 * i, kPadWord);
        }
    }
    for (int i = 0; i < 16; ++i) {
        store_f32(h + lay.world2eye + 4 * i, header.world_to_eye[i]);
        store_f32(h + lay.world2ndc + 4 * i, header.world_to_ndc[i]);
    }
    for (int i = 0; i < 3; ++i) store_f32(h + lay.format + 4 * i, header.format[i]);
    store_i32(h + lay.nvars, static_cast<int32_t>(header.channels.size()));
    store_i32(h + lay.nvars + 4, header.data_size());

    m_out = std::make_unique<AtomicOutput>(path);
    m_sink = std::make_unique<ByteSink>(m_out->temp_path(), path, options.compress);
    m_sink->write(head.data(), head.size());
    for (const Channel& c : header.channels) {
        m_sink->write(std::string(channel_type_name(c.type)) + " " + c.name + "\n");
    }
    if (version >= 1) {
        const unsigned char zeros[8] = {};
        m_sink->write(zeros, sizeof zeros);
    }
    m_count = count;
    m_record = kRecordBase + 4 * static_cast<std::size_t>(header.data_size());
    m_data_size = header.data_size();
}

PtcWriter::~PtcWriter() = default;

void PtcWriter::write(const PointCloud& cloud) {
    const std::size_t n = cloud.size();
    if (cloud.data_size() != m_data_size)
        throw ValueError("point cloud writer: chunk of " +
                         std::to_string(cloud.data_size()) + " floats per point, not " +
                         std::to_string(m_data_size));
    if (m_written + n > m_count)
        throw ValueError("point cloud writer: more than the " + std::to_string(m_count) +
                         " points announced");
    // Records go to the sink a batch at a time (about 1 MB), each batch
    // encoded in parallel (the normals' atan2 is most of the work).
    const std::size_t batch = std::max<std::size_t>(1, (std::size_t(1) << 20) / m_record);
    if (m_rec.size() < std::min(batch, n) * m_record)
        m_rec.resize(std::min(batch, n) * m_record);
    for (std::size_t b = 0; b < n; b += batch) {
        const std::size_t e = std::min(n, b + batch);
        oneapi::tbb::parallel_for(
            oneapi::tbb::blocked_range<std::size_t>(b, e, 4096),
            [&](const oneapi::tbb::blocked_range<std::size_t>& range) {
                for (std::size_t i = range.begin(); i != range.end(); ++i) {
                    unsigned char* r = m_rec.data() + (i - b) * m_record;
                    store_f32(r, cloud.positions[i].x);
                    store_f32(r + 4, cloud.positions[i].y);
                    store_f32(r + 8, cloud.positions[i].z);
                    const std::array<uint16_t, 2> code = encode_normal(cloud.normals[i]);
                    store_u16(r + 12, code[0]);
                    store_u16(r + 14, code[1]);
                    store_f32(r + 16, cloud.radii[i]);
                    unsigned char* d = r + kRecordBase;
                    for (const Channel& c : cloud.channels) {
                        const std::size_t k = static_cast<std::size_t>(c.components());
                        for (std::size_t q = 0; q < k; ++q, d += 4)
                            store_f32(d, c.data[i * k + q]);
                    }
                }
            });
        m_sink->write(m_rec.data(), (e - b) * m_record);
    }
    m_written += n;
}

void PtcWriter::commit() {
    if (m_written != m_count)
        throw ValueError("point cloud writer: " + std::to_string(m_written) + " of the " +
                         std::to_string(m_count) + " points announced were written");
    m_sink->close();
    m_out->commit();
}

} // namespace detail

void write_ptc(const PointCloud& cloud, const std::string& path,
               const PointCloudWriteOptions& options) {
    if (options.ptc_version < 0 || options.ptc_version > kMaxVersion) {
        throw ValueError("cannot write .ptc version " +
                         std::to_string(options.ptc_version) + " (0, 1 or 2)");
    }
    check_writable(cloud);
    float max_radius = 0.0f;
    for (float r : cloud.radii) max_radius = std::max(max_radius, r);
    PtcWriter writer(path, cloud, cloud.size(), cloud.bounds(), max_radius, options);
    writer.write(cloud);
    writer.commit();
}

} // namespace sss
