// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file ply_io.cpp
/// PLY point clouds. We write binary little-endian PLY with one `vertex`
/// element (x y z nx ny nz radius, the display colour as uchar red green
/// blue, then every channel component as a float) and record the real
/// channel types in "comment sss_channel <type> <name>" lines, and the
/// channel the colour shows in "comment sss_display_color <name>". We read
/// our own files exactly (the colour bytes, derived data, are skipped) and
/// other tools' files leniently: x/y/z required, nx/ny/nz and radius
/// optional, every other scalar property becomes a float channel.

#include <algorithm>
#include <charconv>
#include <cmath>
#include <map>
#include <set>
#include <sstream>

#include "point_cloud_io_detail.h"
#include "sss/cloud/point_cloud_io.h"
#include "sss/util/atomic_output.h"
#include "sss/util/error.h"
#include "sss/util/srgb.h"
#include "sss/util/version.h"

namespace sss {

namespace {

using namespace detail;

constexpr std::size_t kMaxHeaderLine = 1 << 16;
constexpr std::size_t kMaxHeaderBytes = 1 << 24;
// Position, normal and radius, then at most 16 floats per channel.
constexpr std::size_t kMaxProperties = 7 + 16 * static_cast<std::size_t>(kMaxChannels);
constexpr const char* kChannelComment = "sss_channel";
constexpr const char* kDisplayColorComment = "sss_display_color";
/// The vertex colour properties MeshLab and CloudCompare show.
constexpr const char* kColorProperties[3] = {"red", "green", "blue"};

enum class PlyScalar { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

std::optional<PlyScalar> parse_scalar(const std::string& s) {
    static const std::map<std::string, PlyScalar> names = {
        {"char", PlyScalar::Int8},      {"int8", PlyScalar::Int8},
        {"uchar", PlyScalar::UInt8},    {"uint8", PlyScalar::UInt8},
        {"short", PlyScalar::Int16},    {"int16", PlyScalar::Int16},
        {"ushort", PlyScalar::UInt16},  {"uint16", PlyScalar::UInt16},
        {"int", PlyScalar::Int32},      {"int32", PlyScalar::Int32},
        {"uint", PlyScalar::UInt32},    {"uint32", PlyScalar::UInt32},
        {"float", PlyScalar::Float32},  {"float32", PlyScalar::Float32},
        {"double", PlyScalar::Float64}, {"float64", PlyScalar::Float64}};
    const auto it = names.find(s);
    if (it == names.end()) return std::nullopt;
    return it->second;
}

std::size_t scalar_size(PlyScalar t) {
    switch (t) {
    case PlyScalar::Int8:
    case PlyScalar::UInt8:
        return 1;
    case PlyScalar::Int16:
    case PlyScalar::UInt16:
        return 2;
    case PlyScalar::Int32:
    case PlyScalar::UInt32:
    case PlyScalar::Float32:
        return 4;
    case PlyScalar::Float64:
        return 8;
    }
    return 4;
}

double load_scalar(PlyScalar t, const unsigned char* p) {
    switch (t) {
    case PlyScalar::Int8:
        return static_cast<int8_t>(p[0]);
    case PlyScalar::UInt8:
        return p[0];
    case PlyScalar::Int16:
        return static_cast<int16_t>(load_u16(p));
    case PlyScalar::UInt16:
        return load_u16(p);
    case PlyScalar::Int32:
        return load_i32(p);
    case PlyScalar::UInt32:
        return load_u32(p);
    case PlyScalar::Float32:
        return load_f32(p);
    case PlyScalar::Float64:
        return load_f64(p);
    }
    return 0.0;
}

struct PlyProperty {
    std::string name;
    PlyScalar type = PlyScalar::Float32;
    std::size_t offset = 0; ///< byte offset in a binary vertex record
};

/// Channel declared by an sss_channel comment.
struct DeclaredChannel {
    ChannelType type;
    std::string name;
};

struct PlyHeader {
    bool ascii = false;
    uint64_t count = 0;
    std::vector<PlyProperty> props;
    std::size_t stride = 0;
    std::vector<DeclaredChannel> declared;
    /// The channel red/green/blue were made from (sss_display_color).
    std::optional<std::string> display_color;
    std::optional<std::array<float, 16>> world_to_eye, world_to_ndc;
    std::optional<std::array<float, 3>> format;
};

/// Component property names of a channel in our PLY naming.
std::vector<std::string> component_names(const std::string& name, ChannelType type) {
    switch (type) {
    case ChannelType::Float:
        return {name};
    case ChannelType::Color:
        return {name + "_r", name + "_g", name + "_b"};
    case ChannelType::Point:
    case ChannelType::Vector:
    case ChannelType::Normal:
        return {name + "_x", name + "_y", name + "_z"};
    case ChannelType::Matrix: {
        std::vector<std::string> out;
        for (int i = 0; i < 16; ++i) out.push_back(name + "_" + std::to_string(i));
        return out;
    }
    }
    return {name};
}

std::vector<std::string> split_words(const std::string& line) {
    std::vector<std::string> words;
    std::istringstream ss(line);
    std::string w;
    while (ss >> w) words.push_back(w);
    return words;
}

bool parse_float(const std::string& s, float& out) {
    const char* b = s.data();
    const char* e = b + s.size();
    if (b != e && *b == '+') ++b;
    double v = 0.0;
    const auto [ptr, ec] = std::from_chars(b, e, v);
    if (ec != std::errc() || ptr != e) return false;
    out = static_cast<float>(v);
    return true;
}

template <std::size_t N>
std::array<float, N> parse_float_list(const std::string& path,
                                      const std::vector<std::string>& words,
                                      const std::string& what) {
    std::array<float, N> out{};
    if (words.size() != N + 2) {
        throw FormatError(path, "malformed '" + what + "' comment: expected " +
                                    std::to_string(N) + " numbers");
    }
    for (std::size_t i = 0; i < N; ++i) {
        if (!parse_float(words[i + 2], out[i]) || !std::isfinite(out[i])) {
            throw FormatError(path, "malformed '" + what + "' comment: bad number '" +
                                        words[i + 2] + "'");
        }
    }
    return out;
}

/// Property and channel names become channel names, which may hold no
/// control characters (blanks cannot occur: the header is split on them).
bool has_control_character(const std::string& name) {
    return std::any_of(name.begin(), name.end(), [](char ch) {
        return static_cast<unsigned char>(ch) < 0x20 || ch == 0x7f;
    });
}

std::string read_header_line(ByteSource& in, std::size_t& header_bytes) {
    std::string line;
    for (;;) {
        const int c = in.get();
        if (c < 0) throw FormatError(in.path(), "truncated PLY header (no end_header)");
        if (++header_bytes > kMaxHeaderBytes)
            throw FormatError(in.path(), "PLY header too large");
        if (c == '\n') break;
        if (line.size() >= kMaxHeaderLine)
            throw FormatError(in.path(), "PLY header line too long");
        line.push_back(static_cast<char>(c));
    }
    if (!line.empty() && line.back() == '\r') line.pop_back();
    return line;
}

PlyHeader read_header(ByteSource& in) {
    const std::string& path = in.path();
    auto fail = [&](const std::string& what) { return FormatError(path, what); };
    std::size_t header_bytes = 0;
    if (read_header_line(in, header_bytes) != "ply")
        throw fail("not a PLY file (no 'ply' line)");

    PlyHeader h;
    bool have_format = false;
    // 0: no element yet, 1: inside vertex, 2: past vertex (ignored).
    int state = 0;
    std::set<std::string> prop_names;
    for (;;) {
        const std::string line = read_header_line(in, header_bytes);
        const std::vector<std::string> w = split_words(line);
        if (w.empty()) continue;
        const std::string& key = w[0];
        if (key == "end_header") break;
        if (key == "format") {
            if (w.size() != 3) throw fail("malformed PLY format line '" + line + "'");
            if (w[1] == "binary_big_endian")
                throw fail("binary_big_endian PLY is not supported");
            if (w[1] != "binary_little_endian" && w[1] != "ascii") {
                throw fail("unknown PLY format '" + w[1] + "'");
            }
            if (w[2] != "1.0") throw fail("unsupported PLY version '" + w[2] + "'");
            h.ascii = w[1] == "ascii";
            have_format = true;
        } else if (key == "comment") {
            if (w.size() >= 2 && w[1] == kChannelComment) {
                if (w.size() != 4)
                    throw fail("malformed sss_channel comment '" + line + "'");
                const std::optional<ChannelType> t = parse_channel_type(w[2]);
                if (!t)
                    throw fail("unknown channel type '" + w[2] +
                               "' in sss_channel comment");
                if (has_control_character(w[3]))
                    throw fail("control character in the channel name of sss_channel "
                               "comment '" +
                               line + "'");
                h.declared.push_back({*t, w[3]});
            } else if (w.size() >= 2 && w[1] == kDisplayColorComment) {
                if (w.size() != 3 || h.display_color)
                    throw fail("malformed or repeated sss_display_color comment '" +
                               line + "'");
                h.display_color = w[2];
            } else if (w.size() >= 2 && w[1] == "sss_world_to_eye") {
                h.world_to_eye = parse_float_list<16>(path, w, w[1]);
            } else if (w.size() >= 2 && w[1] == "sss_world_to_ndc") {
                h.world_to_ndc = parse_float_list<16>(path, w, w[1]);
            } else if (w.size() >= 2 && w[1] == "sss_format") {
                h.format = parse_float_list<3>(path, w, w[1]);
            }
        } else if (key == "obj_info") {
            // free text, ignored
        } else if (key == "element") {
            if (w.size() != 3) throw fail("malformed PLY element line '" + line + "'");
            if (state == 0) {
                if (w[1] != "vertex") {
                    throw fail(
                        "PLY element '" + w[1] +
                        "' comes before 'vertex' (vertex must be the first element)");
                }
                uint64_t count = 0;
                const auto [ptr, ec] =
                    std::from_chars(w[2].data(), w[2].data() + w[2].size(), count);
                if (ec != std::errc() || ptr != w[2].data() + w[2].size() ||
                    count > (uint64_t{1} << 53)) {
                    throw fail("invalid vertex count '" + w[2] + "'");
                }
                h.count = count;
                state = 1;
            } else {
                state = 2;
            }
        } else if (key == "property") {
            if (state == 0) throw fail("PLY property before any element");
            if (state == 2) continue;
            if (w.size() >= 2 && w[1] == "list") {
                throw fail("list properties not supported (vertex property '" + w.back() +
                           "')");
            }
            if (w.size() != 3) throw fail("malformed PLY property line '" + line + "'");
            const std::optional<PlyScalar> t = parse_scalar(w[1]);
            if (!t) throw fail("unknown PLY property type '" + w[1] + "'");
            if (has_control_character(w[2]))
                throw fail("control character in the vertex property name '" + w[2] +
                           "'");
            if (!prop_names.insert(w[2]).second) {
                throw fail("duplicate vertex property '" + w[2] + "'");
            }
            if (h.props.size() >= kMaxProperties) {
                throw fail("more than " + std::to_string(kMaxProperties) +
                           " vertex properties");
            }
            h.props.push_back({w[2], *t, h.stride});
            h.stride += scalar_size(*t);
        } else {
            throw fail("unknown PLY header keyword '" + key + "'");
        }
    }
    if (!have_format) throw fail("PLY header has no format line");
    if (state == 0) throw fail("PLY file has no vertex element");
    return h;
}

/// Where each output value comes from: property index per target slot.
struct Mapping {
    int pos[3] = {-1, -1, -1};
    int nrm[3] = {-1, -1, -1};
    int radius = -1;
    std::vector<std::vector<int>> channel_props; ///< per channel, per component
};

Mapping map_properties(const std::string& path, const PlyHeader& h, PointCloud& cloud) {
    std::map<std::string, int> index;
    for (std::size_t i = 0; i < h.props.size(); ++i)
        index[h.props[i].name] = static_cast<int>(i);
    std::vector<bool> used(h.props.size(), false);
    auto find = [&](const std::string& name) {
        const auto it = index.find(name);
        return it == index.end() ? -1 : it->second;
    };
    Mapping m;
    static const char* const pos_names[] = {"x", "y", "z"};
    static const char* const nrm_names[] = {"nx", "ny", "nz"};
    for (int a = 0; a < 3; ++a) {
        m.pos[a] = find(pos_names[a]);
        if (m.pos[a] < 0)
            throw FormatError(path, std::string("PLY vertex has no '") + pos_names[a] +
                                        "' property");
        used[m.pos[a]] = true;
        m.nrm[a] = find(nrm_names[a]);
    }
    // A normal needs all three components; a partial one is left to become channels.
    if (m.nrm[0] >= 0 && m.nrm[1] >= 0 && m.nrm[2] >= 0) {
        for (int a : m.nrm) used[a] = true;
    } else {
        m.nrm[0] = m.nrm[1] = m.nrm[2] = -1;
    }
    m.radius = find("radius");
    if (m.radius >= 0) used[m.radius] = true;
    // Our display colour is derived from a channel: reading it back as
    // channels of its own would duplicate that channel.
    if (h.display_color) {
        for (const char* name : kColorProperties) {
            const int i = find(name);
            if (i < 0) {
                throw FormatError(path,
                                  std::string("sss_display_color comment but no '") +
                                      name + "' property");
            }
            used[i] = true;
        }
    }

    // Channels paired with the property index of their first component, so the
    // cloud lists them in file order whether declared or not.
    struct Pending {
        int first;
        Channel channel;
        std::vector<int> props;
    };
    std::vector<Pending> pending;
    std::set<std::string> names;
    for (const DeclaredChannel& d : h.declared) {
        if (!names.insert(d.name).second) {
            throw FormatError(path, "duplicate sss_channel comment for '" + d.name + "'");
        }
        Pending p;
        p.channel.name = d.name;
        p.channel.type = d.type;
        for (const std::string& comp : component_names(d.name, d.type)) {
            const int i = find(comp);
            if (i < 0) {
                throw FormatError(path, "channel '" + d.name +
                                            "' is declared in a comment "
                                            "but property '" +
                                            comp + "' is missing");
            }
            if (used[i]) {
                throw FormatError(path, "property '" + comp + "' is claimed twice");
            }
            used[i] = true;
            p.props.push_back(i);
        }
        p.first = p.props.front();
        pending.push_back(std::move(p));
    }
    for (std::size_t i = 0; i < h.props.size(); ++i) {
        if (used[i]) continue;
        if (!names.insert(h.props[i].name).second) {
            throw FormatError(path, "property '" + h.props[i].name +
                                        "' clashes with a declared channel name");
        }
        Pending p;
        p.channel.name = h.props[i].name;
        p.channel.type = ChannelType::Float;
        p.props.push_back(static_cast<int>(i));
        p.first = static_cast<int>(i);
        pending.push_back(std::move(p));
    }
    std::stable_sort(
        pending.begin(), pending.end(),
        [](const Pending& a, const Pending& b) { return a.first < b.first; });
    if (pending.size() > static_cast<std::size_t>(kMaxChannels)) {
        throw FormatError(path,
                          std::to_string(pending.size()) + " channels, more than the " +
                              std::to_string(kMaxChannels) + " a point cloud may have");
    }
    for (Pending& p : pending) {
        cloud.channels.push_back(std::move(p.channel));
        m.channel_props.push_back(std::move(p.props));
    }
    return m;
}

/// Reads the next whitespace-separated word of an ASCII body; empty at the end.
std::string next_word(ByteSource& in) {
    std::string w;
    int c = in.get();
    while (c == ' ' || c == '\t' || c == '\n' || c == '\r') c = in.get();
    while (c >= 0 && c != ' ' && c != '\t' && c != '\n' && c != '\r') {
        if (w.size() > 512) throw FormatError(in.path(), "malformed ASCII PLY value");
        w.push_back(static_cast<char>(c));
        c = in.get();
    }
    return w;
}

} // namespace

PointCloud read_ply(const std::string& path) {
    ByteSource in(path);
    const PlyHeader h = read_header(in);
    PointCloud cloud;
    cloud.file_compressed = in.compressed();
    if (h.world_to_eye) cloud.world_to_eye = *h.world_to_eye;
    if (h.world_to_ndc) cloud.world_to_ndc = *h.world_to_ndc;
    if (h.format) cloud.format = *h.format;
    const Mapping m = map_properties(path, h, cloud);

    const std::size_t nprops = h.props.size();
    // Minimum bytes per vertex: binary stride, or one character and one
    // separator per ASCII value.
    const uint64_t min_vertex_bytes = h.ascii ? 2 * nprops : h.stride;
    const std::optional<uint64_t> left = in.remaining_bound();
    // The last ASCII value needs no separator after it, hence the slack of 1.
    const uint64_t slack = h.ascii ? 1 : 0;
    if (left && min_vertex_bytes > 0 && h.count > (*left + slack) / min_vertex_bytes) {
        const std::string what = "header claims " + std::to_string(h.count) +
                                 " vertices but the file is too short for them";
        if (h.ascii || in.compressed()) throw FormatError(path, what);
        // Exact for binary in a plain file: name the first incomplete vertex.
        throw FormatError(path, "truncated vertex data: " + what,
                          static_cast<int64_t>(*left / min_vertex_bytes));
    }
    // A binary plain file has been checked exactly; otherwise (gzip, or ASCII,
    // whose values may be far longer than the minimum) grow as data arrives.
    CloudReserve reserve(cloud, path, h.count,
                         left.has_value() && !in.compressed() && !h.ascii);
    const auto truncated = [&](uint64_t i) {
        return FormatError(path,
                           "truncated vertex data: header claims " +
                               std::to_string(h.count) + " vertices, data ends after " +
                               std::to_string(i),
                           static_cast<int64_t>(i));
    };
    std::vector<double> values(nprops);
    std::vector<unsigned char> rec(h.stride);
    for (uint64_t i = 0; i < h.count; ++i) {
        const int64_t index = static_cast<int64_t>(i);
        reserve.room_for(1);
        if (h.ascii) {
            for (std::size_t q = 0; q < nprops; ++q) {
                const std::string word = next_word(in);
                if (word.empty()) throw truncated(i);
                float v = 0.0f;
                if (!parse_float(word, v)) {
                    throw FormatError(
                        path, "malformed number '" + word + "' in vertex data", index);
                }
                values[q] = v;
            }
        } else {
            if (!in.read_exact(rec.data(), rec.size())) throw truncated(i);
            for (std::size_t q = 0; q < nprops; ++q) {
                values[q] = load_scalar(h.props[q].type, rec.data() + h.props[q].offset);
            }
        }
        auto value = [&](int prop, const char* what) {
            const float v = static_cast<float>(values[static_cast<std::size_t>(prop)]);
            if (!std::isfinite(v)) {
                throw FormatError(path,
                                  std::string("non-finite ") + what + " ('" +
                                      h.props[static_cast<std::size_t>(prop)].name + "')",
                                  index);
            }
            return v;
        };
        cloud.positions.emplace_back(value(m.pos[0], "position"),
                                     value(m.pos[1], "position"),
                                     value(m.pos[2], "position"));
        if (m.nrm[0] >= 0) {
            cloud.normals.emplace_back(value(m.nrm[0], "normal"),
                                       value(m.nrm[1], "normal"),
                                       value(m.nrm[2], "normal"));
        } else {
            cloud.normals.emplace_back(0.0f);
        }
        const float radius = m.radius >= 0 ? value(m.radius, "radius") : 0.0f;
        if (radius < 0.0f) throw FormatError(path, "negative radius", index);
        cloud.radii.push_back(radius);
        for (std::size_t c = 0; c < cloud.channels.size(); ++c) {
            for (int prop : m.channel_props[c]) {
                cloud.channels[c].data.push_back(value(prop, "channel value"));
            }
        }
    }
    in.finish();
    return cloud;
}

const Channel* ply_display_channel(const PointCloud& cloud) {
    // A cloud with its own float channels red, green or blue (a foreign PLY
    // read in) keeps them and gets no display colour: the names would clash.
    for (const char* name : kColorProperties) {
        const Channel* c = cloud.find_channel(name);
        if (c && c->type == ChannelType::Float) return nullptr;
    }
    const Channel* diffusion = cloud.find_channel("_ssdiffusion");
    if (diffusion && diffusion->type == ChannelType::Color) return diffusion;
    for (const Channel& c : cloud.channels)
        if (c.type == ChannelType::Color) return &c;
    return nullptr;
}

uint8_t ply_display_byte(float value) {
    const double v = std::clamp(static_cast<double>(value), 0.0, 1.0);
    return static_cast<uint8_t>(std::lround(255.0 * srgb_encode(v)));
}

void write_ply(const PointCloud& cloud, const std::string& path) {
    check_writable(cloud);
    // Every property name must be unique, or the file cannot be read back.
    std::set<std::string> props = {"x", "y", "z", "nx", "ny", "nz", "radius"};
    std::ostringstream channel_props;
    for (const Channel& c : cloud.channels) {
        for (const std::string& comp : component_names(c.name, c.type)) {
            if (!props.insert(comp).second) {
                throw ValueError("cannot write channel '" + c.name +
                                 "' to PLY: property '" + comp + "' already exists");
            }
            channel_props << "property float " << comp << "\n";
        }
    }
    const Channel* shown = ply_display_channel(cloud);
    std::ostringstream head;
    head << "ply\nformat binary_little_endian 1.0\n";
    head << "comment written by sss " << version_string() << "\n";
    auto matrix_comment = [&](const char* key, const float* v, int n) {
        head << "comment " << key;
        for (int i = 0; i < n; ++i) head << " " << format_float(v[i]);
        head << "\n";
    };
    const PointCloud defaults;
    if (cloud.world_to_eye != defaults.world_to_eye) {
        matrix_comment("sss_world_to_eye", cloud.world_to_eye.data(), 16);
    }
    if (cloud.world_to_ndc != defaults.world_to_ndc) {
        matrix_comment("sss_world_to_ndc", cloud.world_to_ndc.data(), 16);
    }
    if (cloud.format != defaults.format)
        matrix_comment("sss_format", cloud.format.data(), 3);
    for (const Channel& c : cloud.channels) {
        head << "comment " << kChannelComment << " " << channel_type_name(c.type) << " "
             << c.name << "\n";
    }
    if (shown) head << "comment " << kDisplayColorComment << " " << shown->name << "\n";
    head << "element vertex " << cloud.size() << "\n";
    for (const char* p : {"x", "y", "z", "nx", "ny", "nz", "radius"}) {
        head << "property float " << p << "\n";
    }
    if (shown) {
        for (const char* p : kColorProperties) head << "property uchar " << p << "\n";
    }
    head << channel_props.str() << "end_header\n";

    const std::size_t floats = 7 + static_cast<std::size_t>(cloud.data_size());
    AtomicOutput out(path);
    ByteSink sink(out.temp_path(), path, false);
    sink.write(head.str());
    std::vector<unsigned char> rec(4 * floats + (shown ? 3 : 0));
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        unsigned char* r = rec.data();
        auto put = [&r](float v) {
            store_f32(r, v);
            r += 4;
        };
        for (int a = 0; a < 3; ++a) put(cloud.positions[i][a]);
        for (int a = 0; a < 3; ++a) put(cloud.normals[i][a]);
        put(cloud.radii[i]);
        if (shown) {
            for (std::size_t q = 0; q < 3; ++q)
                *r++ = ply_display_byte(shown->data[3 * i + q]);
        }
        for (const Channel& c : cloud.channels) {
            const std::size_t k = static_cast<std::size_t>(c.components());
            for (std::size_t q = 0; q < k; ++q) put(c.data[i * k + q]);
        }
        sink.write(rec.data(), rec.size());
    }
    sink.close();
    out.commit();
}

} // namespace sss
