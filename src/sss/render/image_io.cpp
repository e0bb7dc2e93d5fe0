// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file image_io.cpp
/// Images out and in through OpenImageIO: resolving RenderMan Display lines
/// (type, mode, parameters) into files and channels, writing them atomically
/// with provenance metadata, and reading images back. docs/images.md has the
/// user-facing rules.

#include "sss/render/image_io.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <string_view>

#include <OpenImageIO/imageio.h>

#include "sss/image/image_check.h"
#include "sss/image/image_file.h"
#include "sss/light/shadow_map.h"
#include "sss/util/atomic_output.h"
#include "sss/util/byte_io.h"
#include "sss/util/error.h"
#include "sss/util/hash.h"
#include "sss/util/job_files.h"
#include "sss/util/limits.h"

namespace sss {

// ---------------------------------------------------------------------------
// Image
// ---------------------------------------------------------------------------

Image::Image(int w, int h, std::vector<std::string> names)
    : width(w), height(h), channels(std::move(names)) {
    if (w < 0 || h < 0)
        throw ValueError("image size " + std::to_string(w) + " x " + std::to_string(h) +
                         " is negative");
    std::set<std::string> seen;
    for (const auto& name : channels) {
        if (name.empty()) throw ValueError("image channel with an empty name");
        if (!seen.insert(name).second)
            throw ValueError("image channel '" + name + "' is given twice");
    }
    pixels.assign(std::size_t(w) * std::size_t(h) * channels.size(), 0.0f);
}

int Image::channel_index(const std::string& name) const {
    for (std::size_t i = 0; i < channels.size(); ++i)
        if (channels[i] == name) return static_cast<int>(i);
    return -1;
}

namespace {

// ---------------------------------------------------------------------------
// Resolving a Display
// ---------------------------------------------------------------------------

std::string lower(std::string_view s) {
    std::string out(s);
    for (char& c : out) c = char(std::tolower(static_cast<unsigned char>(c)));
    return out;
}

std::string trim(std::string_view s) {
    std::size_t b = s.find_first_not_of(" \t\r\n");
    if (b == std::string_view::npos) return {};
    std::size_t e = s.find_last_not_of(" \t\r\n");
    return std::string(s.substr(b, e - b + 1));
}

/// OIIO format name for a file extension ("" when the extension is unknown).
std::string format_from_extension(const std::string& path) {
    std::string ext = lower(std::filesystem::path(path).extension().string());
    if (ext == ".exr") return "openexr";
    if (ext == ".tif" || ext == ".tiff") return "tiff";
    if (ext == ".png") return "png";
    if (ext == ".jpg" || ext == ".jpeg") return "jpeg";
    return {};
}

/// OIIO format name for a display type that names a format ("" otherwise).
std::string format_from_type(const std::string& type) {
    if (type == "openexr" || type == "exr") return "openexr";
    if (type == "tiff" || type == "tif") return "tiff";
    if (type == "png") return "png";
    if (type == "jpeg" || type == "jpg") return "jpeg";
    return {};
}

/// The RenderMan standard modes (and "ci", the beauty colour of "Ci,a" lists).
const std::vector<std::string>* standard_mode(const std::string& item) {
    static const std::vector<std::pair<std::string, std::vector<std::string>>> modes = {
        {"rgba", {"R", "G", "B", "A"}},
        {"rgb", {"R", "G", "B"}},
        {"a", {"A"}},
        {"z", {"Z"}},
        {"rgbz", {"R", "G", "B", "Z"}},
        {"rgbaz", {"R", "G", "B", "A", "Z"}},
        {"ci", {"R", "G", "B"}},
    };
    std::string key = lower(item);
    for (const auto& [name, channels] : modes)
        if (name == key) return &channels;
    return nullptr;
}

/// "beauty R G B A, layers diffuse specular" for error messages.
std::string describe_channels(const Image& image) {
    std::string plain, layers;
    std::set<std::string> seen;
    for (const auto& c : image.channels) {
        std::size_t dot = c.rfind('.');
        if (dot == std::string::npos) {
            plain += (plain.empty() ? "" : " ") + c;
        } else if (seen.insert(c.substr(0, dot)).second) {
            layers += (layers.empty() ? "" : " ") + c.substr(0, dot);
        }
    }
    std::string text = "the image has channels " + (plain.empty() ? "(none)" : plain);
    if (!layers.empty()) text += " and layers " + layers;
    return text;
}

/// One channel chosen by a mode, and the name it takes in a file of its own.
struct ModeChannel {
    std::string channel;
    std::string short_name;
};

/// Channels of one item of a mode ("rgba", "Ci", "diffuse", "color diffuse").
void add_mode_item(const std::string& item_text, const Image& image,
                   const std::string& label, const std::string& mode,
                   std::vector<ModeChannel>& out) {
    std::string item = trim(item_text);
    if (item.empty())
        throw ValueError(label + ": mode '" + mode + "' has an empty channel name");
    // An inline declaration ("color diffuse", "varying float occ") names the
    // AOV by its last word; the type is the renderer's business.
    std::size_t space = item.find_last_of(" \t");
    if (space != std::string::npos) item = item.substr(space + 1);

    if (const auto* channels = standard_mode(item)) {
        for (const auto& c : *channels) {
            if (image.channel_index(c) < 0)
                throw ValueError(label + ": mode '" + mode + "' needs channel " + c +
                                 ", which the image does not have (" +
                                 describe_channels(image) + ")");
            out.push_back({c, c});
        }
        return;
    }
    // An AOV: a plain channel of that name, or the layer "item.*".
    if (image.channel_index(item) >= 0) {
        out.push_back({item, item});
        return;
    }
    std::string prefix = item + ".";
    std::size_t before = out.size();
    for (const auto& c : image.channels)
        if (c.size() > prefix.size() && c.compare(0, prefix.size(), prefix) == 0)
            out.push_back({c, c.substr(prefix.size())});
    if (out.size() == before)
        throw ValueError(label + ": mode '" + mode + "' names '" + item +
                         "', which the image does not have (" + describe_channels(image) +
                         ")");
}

bool contains(const std::vector<std::string>& list, const std::string& s) {
    return std::find(list.begin(), list.end(), s) != list.end();
}

const std::vector<std::string>& exr_compressions() {
    static const std::vector<std::string> names = {
        "none", "rle", "zips", "zip", "piz", "pxr24", "b44", "b44a", "dwaa", "dwab"};
    return names;
}

std::string join(const std::vector<std::string>& list, const char* sep) {
    std::string s;
    for (const auto& item : list) s += (s.empty() ? "" : sep) + item;
    return s;
}

/// PRMan's zfile and shadow drivers: the depth, nothing else.
void depth_map_target(const DisplaySpec& display, const Image& image,
                      const std::string& label, DisplayTarget& target) {
    if (lower(trim(display.mode)) != "z")
        throw ValueError(label + ": a \"" + display.type +
                         "\" display writes depth: its mode is \"z\", not '" +
                         display.mode + "'");
    if (image.channel_index("Z") < 0)
        throw ValueError(label + ": the image has no depth (" + describe_channels(image) +
                         ")");
    target.channels = target.names = {"Z"};
    target.half = false;
    target.depth_map = true;
    target.shadow_map = lower(display.type) == "shadow";
}

} // namespace

const std::vector<std::string>& image_extensions() {
    static const std::vector<std::string> extensions = {".exr", ".tif", ".tiff",
                                                        ".png", ".jpg", ".jpeg"};
    return extensions;
}

bool display_is_depth_map(const DisplaySpec& display) {
    const std::string type = lower(display.type);
    return type == "zfile" || type == "shadow";
}

std::string display_format(const DisplaySpec& display) {
    const std::string type = lower(display.type);
    // Depth maps are OpenEXR files whatever their name (".z", ".shd", ".tex").
    if (display_is_depth_map(display)) return "openexr";
    std::string format = format_from_type(type);
    if (!format.empty()) return format;
    const std::string path = display_file(display);
    // "file" and other drivers: the name decides, and must say something
    // (a device or FIFO, which has no extension, gets OpenEXR).
    format = format_from_extension(path);
    if (format.empty() && writes_into_existing(path)) return "openexr";
    if (format.empty())
        throw ValueError(
            "Display \"" + std::string(display.additional ? "+" : "") + display.name +
            "\"" + (display.where.empty() ? "" : " (" + display.where + ")") + ": " +
            unknown_extension_text(path, "an image file", image_extensions()) +
            "; name the format in the display type (\"openexr\", "
            "\"tiff\", \"png\", \"jpeg\") or use one of these extensions");
    return format;
}

bool display_writes_nothing(const DisplaySpec& display) {
    return lower(display.type) == "null";
}

bool display_is_window(const DisplaySpec& display) {
    const std::string type = lower(display.type);
    return type == "it" || type == "framebuffer" || type == "x11" || type == "windows";
}

std::string display_file(const DisplaySpec& display) {
    // There is no window here: "it"/"framebuffer" write an OpenEXR file, and a
    // name without an image extension ("view", "shot.0042") gets ".exr".
    if (display_is_window(display) && format_from_extension(display.name).empty())
        return display.name + ".exr";
    return display.name;
}

DisplayTarget resolve_display(const DisplaySpec& display, const Image& image,
                              bool primary, const DisplayDefaults& defaults) {
    const std::string label = "display '" + std::string(display.additional ? "+" : "") +
                              display.name + "'" +
                              (display.where.empty() ? "" : " (" + display.where + ")");
    if (display.name.empty()) throw ValueError("display with an empty file name");

    DisplayTarget target;
    target.exposure_gain = defaults.exposure_gain;
    target.exposure_gamma = defaults.exposure_gamma;
    target.path = display_file(display);
    target.format = display_format(display);
    const bool exr = target.format == "openexr";
    if (display_is_depth_map(display)) {
        depth_map_target(display, image, label, target);
        return target;
    }

    // Channels from the mode: a comma-separated list of items.
    if (trim(display.mode).empty()) throw ValueError(label + ": empty display mode");
    std::vector<ModeChannel> chosen;
    std::size_t start = 0;
    while (true) {
        std::size_t comma = display.mode.find(',', start);
        add_mode_item(display.mode.substr(start, comma == std::string::npos
                                                     ? std::string::npos
                                                     : comma - start),
                      image, label, display.mode, chosen);
        if (comma == std::string::npos) break;
        start = comma + 1;
    }
    // "rgba,a" or "Ci,rgb" name a channel twice: it is written once.
    for (const auto& m : chosen) {
        if (contains(target.channels, m.channel)) continue;
        target.channels.push_back(m.channel);
        target.names.push_back(m.short_name);
    }

    if (exr && primary) {
        // The primary EXR holds everything: full layer names, and every AOV.
        target.names = target.channels;
        static const std::vector<std::string> beauty = {"R", "G", "B", "A", "Z"};
        for (const auto& c : image.channels)
            if (!contains(beauty, c) && !contains(target.channels, c)) {
                target.channels.push_back(c);
                target.names.push_back(c);
            }
    } else {
        // A file of its own: AOV channels take their short names (diffuse.R
        // -> R) unless two channels would then share a name.
        std::set<std::string> unique(target.names.begin(), target.names.end());
        if (unique.size() != target.names.size()) target.names = target.channels;
    }

    // Pixel type and compression.
    std::string pixel_type = lower(display.params.get_string("type", ""));
    if (exr) {
        if (pixel_type == "float")
            target.half = false;
        else if (pixel_type.empty() || pixel_type == "half")
            target.half = true;
        else
            throw ValueError(label + ": \"string type\" '" + pixel_type +
                             "' is not half or float");
        target.compression = lower(display.params.get_string("compression", "zip"));
        if (!contains(exr_compressions(), target.compression))
            throw ValueError(label + ": unknown OpenEXR compression '" +
                             target.compression + "' (one of " +
                             join(exr_compressions(), ", ") + ")");
        return target;
    }

    // Integer formats: quantisation.
    target.half = false;
    if (defaults.quantize) target.quantize = *defaults.quantize;
    if (const Param* q = display.params.find("quantize")) {
        if ((q->type != ParamType::Float && q->type != ParamType::Integer) ||
            q->numbers.size() != 4)
            throw ValueError(label + ": \"quantize\" needs 4 numbers [zero one min max]");
        target.quantize.zero = q->numbers[0];
        target.quantize.one = q->numbers[1];
        target.quantize.min = q->numbers[2];
        target.quantize.max = q->numbers[3];
    }
    if (const Param* d = display.params.find("dither")) {
        if ((d->type != ParamType::Float && d->type != ParamType::Integer) ||
            d->numbers.size() != 1)
            throw ValueError(label + ": \"dither\" needs one number [amplitude]");
        target.quantize.dither = d->numbers[0];
    }
    const QuantizeSpec& q = target.quantize;
    for (double v : {q.zero, q.one, q.min, q.max, q.dither})
        if (!std::isfinite(v))
            throw ValueError(label + ": quantize values must be finite numbers");
    if (q.one < 0.0 || q.dither < 0.0 || q.min < 0.0 || q.min > q.max)
        throw ValueError(label +
                         ": quantize needs one >= 0, 0 <= min <= max and dither >= 0");
    if (q.one == 0.0) {
        if (target.format != "tiff")
            throw ValueError(label + ": quantize one = 0 asks for float pixels, which " +
                             target.format +
                             " files cannot hold; use a TIFF or OpenEXR display");
        target.bits = 32;
    } else if (q.max > 65535.0) {
        throw ValueError(label + ": quantize max " + std::to_string(q.max) +
                         " does not fit in 16 bits");
    } else {
        target.bits = q.max > 255.0 ? 16 : 8;
        if (target.bits == 16 && target.format == "jpeg")
            throw ValueError(
                label + ": JPEG files hold 8 bits; quantize max must be at most 255");
    }
    if (!pixel_type.empty() && pixel_type != "uint8" && pixel_type != "byte")
        throw ValueError(label + ": " + target.format +
                         " files take their pixel type from \"quantize\"; " +
                         "\"string type\" '" + pixel_type + "' needs an OpenEXR display");
    for (const auto& c : target.channels)
        if (c == "Z")
            throw ValueError(label + ": depth (Z) cannot be stored in an 8-bit " +
                             target.format + " file; use an OpenEXR display");
    if (target.format == "jpeg" && target.channels.size() > 1) {
        // JPEG has no alpha: the colour stays premultiplied (over black).
        for (std::size_t i = 0; i < target.names.size(); ++i)
            if (target.names[i] == "A") {
                target.channels.erase(target.channels.begin() + std::ptrdiff_t(i));
                target.names.erase(target.names.begin() + std::ptrdiff_t(i));
                break;
            }
    }
    std::size_t n = target.channels.size();
    if (target.format == "png" && n > 4)
        throw ValueError(label + ": PNG holds at most 4 channels, mode '" + display.mode +
                         "' gives " + std::to_string(n) + " (" + join(target.names, " ") +
                         "); use an OpenEXR display");
    if (target.format == "jpeg" && n != 1 && n != 3)
        throw ValueError(label + ": JPEG holds 1 or 3 channels, mode '" + display.mode +
                         "' gives " + std::to_string(n) + " (" + join(target.names, " ") +
                         ")");
    return target;
}

void check_display_size(const DisplaySpec& display, const DisplayTarget& target,
                        int width, int height) {
    constexpr int kJpegMaxSide = 65500;
    if (target.format != "jpeg" || std::max(width, height) <= kJpegMaxSide) return;
    throw ValueError("display '" + std::string(display.additional ? "+" : "") +
                     display.name + "'" +
                     (display.where.empty() ? "" : " (" + display.where + ")") +
                     ": a JPEG file holds at most " + std::to_string(kJpegMaxSide) +
                     " pixels a side, the image is " + std::to_string(width) + " x " +
                     std::to_string(height) + "; use a TIFF, PNG or OpenEXR display");
}

// ---------------------------------------------------------------------------
// Writing
// ---------------------------------------------------------------------------

namespace {

/// Largest finite half: larger values would become infinite in the file.
constexpr float kHalfMax = 65504.0f;

/// Depth, positions and normals keep full precision even in a half file.
bool needs_float(const std::string& channel) {
    return channel == "Z" || channel.rfind("P.", 0) == 0 || channel.rfind("N.", 0) == 0;
}

/// Whether Exposure changes a channel: colour (R, G, B, layer.R/G/B), not
/// alpha, depth, one-channel AOVs or the P and N layers.
bool exposed(const std::string& channel) {
    if (channel == "R" || channel == "G" || channel == "B") return true;
    if (needs_float(channel) || channel.size() < 3) return false;
    const std::string tail = channel.substr(channel.size() - 2);
    return tail == ".R" || tail == ".G" || tail == ".B";
}

/// (gain * v)^(1/gamma); gain * v where that is not positive.
double expose(double v, double gain, double gamma) {
    const double x = gain * v;
    return gamma == 1.0 || !(x > 0.0) ? x : std::pow(x, 1.0 / gamma);
}

/// round(zero + one * v + dither * r) clamped to [min, max].
double quantize_value(double v, const QuantizeSpec& q, double r) {
    const double x = std::floor(q.zero + q.one * v + q.dither * r + 0.5);
    return std::clamp(x, q.min, q.max);
}

/// "YYYY:MM:DD hh:mm:ss" local time and EXR's utcOffset (UTC = local +
/// utcOffset, in seconds). SOURCE_DATE_EPOCH fixes the time (in UTC) for
/// reproducible files.
struct CaptureTime {
    std::string date;
    float utc_offset = 0.0f;
};

CaptureTime capture_time() {
    std::time_t now = std::time(nullptr);
    std::tm tm{};
    CaptureTime result;
    if (const char* epoch = std::getenv("SOURCE_DATE_EPOCH"); epoch && *epoch) {
        errno = 0;
        char* end = nullptr;
        long long value = std::strtoll(epoch, &end, 10);
        if (errno != 0 || *end != '\0' || value < 0)
            throw ValueError("SOURCE_DATE_EPOCH '" + std::string(epoch) +
                             "' is not a number of seconds since 1970");
        now = static_cast<std::time_t>(value);
        gmtime_r(&now, &tm);
    } else {
        tzset(); // localtime_r need not notice a changed TZ by itself
        localtime_r(&now, &tm);
        result.utc_offset = static_cast<float>(-tm.tm_gmtoff);
    }
    char text[32];
    std::strftime(text, sizeof text, "%Y:%m:%d %H:%M:%S", &tm);
    result.date = text;
    return result;
}

/// glm stores a column-vector matrix column by column; read in that order
/// the 16 numbers are the row-vector (Imath, RenderMan) matrix row by row:
/// the transpose, which is what the EXR attribute holds.
std::array<float, 16> row_vector_matrix(const Matrix4& m) {
    std::array<float, 16> out{};
    for (int col = 0; col < 4; ++col)
        for (int row = 0; row < 4; ++row)
            out[std::size_t(col * 4 + row)] = float(m[col][row]);
    return out;
}

void add_metadata(std::vector<ImageAttribute>& attributes, const ImageMetadata& metadata,
                  bool exr) {
    auto add = [&](std::string name, auto value) {
        attributes.push_back({std::move(name), std::move(value)});
    };
    if (!metadata.software.empty()) add("Software", metadata.software);
    // OIIO writes DateTime as EXR's capDate (a capDate of our own would be
    // replaced by the current time).
    CaptureTime when = capture_time();
    add("DateTime", when.date);
    if (!metadata.command_line.empty()) {
        add("sss:commandLine", metadata.command_line);
        if (!exr) add("ImageDescription", metadata.command_line);
    }
    for (const auto& [name, value] : metadata.extra) add(name, value);
    if (!exr) return;
    add("utcOffset", when.utc_offset);
    add("renderTimeSeconds", static_cast<float>(metadata.render_seconds));
    add("worldToCamera", row_vector_matrix(metadata.world_to_camera));
    add("worldToNDC", row_vector_matrix(metadata.world_to_ndc));
}

/// A depth map's own attributes (docs/scene.md, "Depth maps"): OIIO's
/// names, which textureinfo's "viewingmatrix" and "projectionmatrix" read.
void add_depth_map_metadata(std::vector<ImageAttribute>& attributes,
                            const ImageMetadata& metadata, bool shadow) {
    attributes.push_back({"worldtocamera", row_vector_matrix(metadata.world_to_camera)});
    attributes.push_back({"worldtoscreen", row_vector_matrix(metadata.world_to_screen)});
    if (shadow) {
        attributes.push_back({"textureformat", std::string("Shadow")});
        attributes.push_back({"sss:textureformat", std::string("Shadow")});
    }
}

int index_of(const std::vector<std::string>& list, const std::string& s) {
    auto it = std::find(list.begin(), list.end(), s);
    return it == list.end() ? -1 : int(it - list.begin());
}

} // namespace

double dither_noise(int x, int y, int k) {
    const uint64_t pixel =
        detail::splitmix64((uint64_t(uint32_t(y)) << 32) | uint32_t(x)) ^
        0x646974686572ull;
    const uint64_t h = detail::splitmix64(pixel + uint64_t(uint32_t(k) + 1) *
                                                      detail::kSplitMixIncrement);
    return 2.0 * detail::unit_double(h) - 1.0;
}

namespace {

/// Checks the image and the display against each other; the image channel of
/// each of the display's channels.
std::vector<int> display_sources(const Image& image, const DisplayTarget& target) {
    const std::string& path = target.path;
    if (path.empty()) throw ValueError("image output with an empty file name");
    if (image.width <= 0 || image.height <= 0)
        throw ValueError(path + ": cannot write an empty image (" +
                         std::to_string(image.width) + " x " +
                         std::to_string(image.height) + ")");
    const std::size_t pixel_count = std::size_t(image.width) * std::size_t(image.height);
    if (image.pixels.size() != pixel_count * image.channels.size())
        throw ValueError(path + ": image has " + std::to_string(image.pixels.size()) +
                         " values, expected " + std::to_string(image.width) + " x " +
                         std::to_string(image.height) + " x " +
                         std::to_string(image.channels.size()));
    if (target.channels.empty() || target.channels.size() != target.names.size())
        throw ValueError(path + ": display has " +
                         std::to_string(target.channels.size()) + " channels and " +
                         std::to_string(target.names.size()) + " channel names");
    const std::size_t n = target.channels.size();
    std::vector<int> source(n);
    for (std::size_t k = 0; k < n; ++k) {
        source[k] = image.channel_index(target.channels[k]);
        if (source[k] < 0)
            throw ValueError(path + ": the image has no channel '" + target.channels[k] +
                             "' (" + describe_channels(image) + ")");
        if (index_of(target.names, target.names[k]) != int(k))
            throw ValueError(path + ": channel name '" + target.names[k] +
                             "' is used twice");
    }
    return source;
}

/// The written channels, pixel by pixel; any NaN/Inf stops here, before a
/// file exists.
std::vector<float> display_values(const Image& image, const DisplayTarget& target,
                                  const std::vector<int>& source) {
    const std::string& path = target.path;
    const std::size_t pixel_count = std::size_t(image.width) * std::size_t(image.height);
    const std::size_t n = target.channels.size();
    std::vector<float> values(pixel_count * n);
    std::size_t bad = 0, first_bad = 0;
    const std::size_t stride = image.channels.size();
    for (std::size_t p = 0; p < pixel_count; ++p)
        for (std::size_t k = 0; k < n; ++k) {
            float v = image.pixels[p * stride + std::size_t(source[k])];
            if (!std::isfinite(v) && bad++ == 0) first_bad = p * n + k;
            values[p * n + k] = v;
        }
    if (bad > 0) {
        std::size_t p = first_bad / n, k = first_bad % n;
        float v = values[first_bad];
        throw ValueError(
            path + ": " + std::to_string(bad) + " non-finite value" +
            (bad > 1 ? "s" : "") + " in the image, the first " +
            (std::isnan(v) ? "NaN" : "infinite") + " in channel " + target.channels[k] +
            " at pixel (" + std::to_string(p % std::size_t(image.width)) + ", " +
            std::to_string(p / std::size_t(image.width)) + "); nothing was written");
    }
    return values;
}

/// The pixels of an integer (or TIFF float) file, one of `floats`, `words`
/// or `bytes` by the display's bits.
struct IntegerPixels {
    std::vector<uint8_t> bytes;
    std::vector<uint16_t> words;
    std::vector<float> floats;
};

/// Integer (or TIFF float): straight alpha (colour divided by coverage), the
/// exposure, then quantize: round(zero + one * v + dither * r) clamped to
/// [min, max]. No sRGB curve: the values are linear unless the exposure's
/// gamma encodes them.
IntegerPixels integer_pixels(const std::vector<float>& values, int width,
                             const DisplayTarget& target, ImageFileSpec& spec,
                             const std::vector<char>& exposed_channel) {
    const std::size_t n = target.channels.size();
    const std::size_t pixel_count = values.size() / n;
    const double gamma = target.exposure_gamma;
    if (gamma == 1.0) {
        spec.attributes.push_back({"oiio:ColorSpace", std::string("Linear")});
    } else {
        spec.attributes.push_back({"oiio:ColorSpace", "Gamma" + std::to_string(gamma)});
        spec.attributes.push_back({"oiio:Gamma", static_cast<float>(gamma)});
    }
    // Our data is already unassociated: OIIO must not divide again (PNG)
    // and TIFF marks its alpha as unassociated.
    spec.attributes.push_back({"oiio:UnassociatedAlpha", 1});
    spec.stored = target.bits == 32   ? PixelType::Float
                  : target.bits == 16 ? PixelType::UInt16
                                      : PixelType::UInt8;
    const int alpha = spec.alpha_channel;
    IntegerPixels px;
    if (target.bits == 32)
        px.floats.resize(values.size());
    else if (target.bits == 16)
        px.words.resize(values.size());
    else
        px.bytes.resize(values.size());
    for (std::size_t p = 0; p < pixel_count; ++p) {
        const float* in = &values[p * n];
        const double a = alpha >= 0 ? double(in[alpha]) : 1.0;
        const int x = int(p % std::size_t(width));
        const int y = int(p / std::size_t(width));
        for (std::size_t k = 0; k < n; ++k) {
            double v = in[k];
            if (int(k) != alpha && alpha >= 0 && a > 0.0) v /= a;
            if (exposed_channel[k])
                v = expose(v, target.exposure_gain, target.exposure_gamma);
            if (target.bits == 32) {
                px.floats[p * n + k] = static_cast<float>(v);
                continue;
            }
            const double q =
                quantize_value(v, target.quantize, dither_noise(x, y, int(k)));
            if (target.bits == 16)
                px.words[p * n + k] = uint16_t(std::clamp(q, 0.0, 65535.0));
            else
                px.bytes[p * n + k] = uint8_t(std::clamp(q, 0.0, 255.0));
        }
    }
    return px;
}

} // namespace

void write_display(const Image& image, const DisplayTarget& target,
                   const ImageMetadata& metadata) {
    const std::vector<int> source = display_sources(image, target);
    const bool exr = target.format == "openexr";
    const std::size_t n = target.channels.size();
    std::vector<float> values = display_values(image, target, source);
    if (target.depth_map)
        for (float& z : values) // no hit (0): nothing there to cast a shadow
            if (!(z > 0.0f)) z = kNoSurfaceDepth;

    ImageFileSpec spec;
    spec.format = target.format;
    spec.width = image.width;
    spec.height = image.height;
    spec.stored =
        exr ? (target.half ? PixelType::Half : PixelType::Float) : PixelType::UInt8;
    spec.channel_names = target.names;
    spec.alpha_channel = index_of(target.names, "A");
    spec.z_channel = exr ? index_of(target.names, "Z") : -1;
    spec.what = target.format + " image";
    add_metadata(spec.attributes, metadata, exr);
    if (target.depth_map)
        add_depth_map_metadata(spec.attributes, metadata, target.shadow_map);

    // Exposure (a no-op at gain 1, gamma 1). Integer files apply it after
    // dividing by alpha, in integer_pixels.
    const bool exposure = target.exposure_gain != 1.0 || target.exposure_gamma != 1.0;
    std::vector<char> exposed_channel(n);
    for (std::size_t k = 0; k < n; ++k) exposed_channel[k] = exposed(target.channels[k]);
    if (exr && exposure)
        for (std::size_t i = 0; i < values.size(); ++i)
            if (exposed_channel[i % n])
                values[i] = static_cast<float>(
                    expose(values[i], target.exposure_gain, target.exposure_gamma));

    IntegerPixels px;
    if (exr) {
        spec.attributes.push_back({"compression", target.compression});
        if (target.half) {
            bool mixed = false;
            std::vector<PixelType> formats(n, PixelType::Half);
            for (std::size_t k = 0; k < n; ++k)
                if (needs_float(target.channels[k])) {
                    formats[k] = PixelType::Float;
                    mixed = true;
                }
            if (mixed) spec.channel_stored = formats;
            // Beyond the half range a value would be stored as infinity.
            for (std::size_t i = 0; i < values.size(); ++i)
                if (formats[i % n] == PixelType::Half)
                    values[i] = std::clamp(values[i], -kHalfMax, kHalfMax);
        }
    } else {
        px = integer_pixels(values, image.width, target, spec, exposed_channel);
    }
    // The file through a temporary (write_image_file()).
    if (exr)
        write_image_file(target.path, spec, PixelType::Float, values.data());
    else if (target.bits == 32)
        write_image_file(target.path, spec, PixelType::Float, px.floats.data());
    else if (target.bits == 16)
        write_image_file(target.path, spec, PixelType::UInt16, px.words.data());
    else
        write_image_file(target.path, spec, PixelType::UInt8, px.bytes.data());
}

// ---------------------------------------------------------------------------
// Reading
// ---------------------------------------------------------------------------

namespace {

/// An image that is not there, in the words of the other readers
/// ("cannot open: No such file or directory"); ec: why exists() could not tell.
IoError missing_image(const std::string& path, const std::error_code& ec) {
    return IoError(path, "cannot open: " + (ec ? ec.message() : std::strerror(ENOENT)),
                   ec ? ec.value() : ENOENT);
}

/// Opens an image for reading with alpha left as stored (no premultiplying).
std::unique_ptr<OIIO::ImageInput> open_input(const std::string& path) {
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) throw missing_image(path, ec);
    detail::require_regular_file(path); // a FIFO would block OpenImageIO
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    auto in = OIIO::ImageInput::open(path, &config);
    if (!in)
        throw FormatError(path, "not an image OpenImageIO can read: " + OIIO::geterror());
    return in;
}

} // namespace

Image read_image(const std::string& path) {
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) throw missing_image(path, ec);
    detail::require_regular_file(path);
    if (const std::optional<ImageHeader> h = check_image_file(path))
        check_memory(uint64_t(h->width) * uint64_t(h->height) * uint64_t(h->channels) * 4,
                     "reading " + path + " (" + std::to_string(h->width) + " x " +
                         std::to_string(h->height) + ", " + std::to_string(h->channels) +
                         " channels)",
                     "use a smaller image");
    auto in = open_input(path);
    const OIIO::ImageSpec& spec = in->spec();
    Image image;
    try {
        image = Image(spec.width, spec.height, spec.channelnames);
    } catch (const ValueError& e) {
        throw FormatError(path, e.what());
    }
    if (!image.pixels.empty() &&
        !in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT,
                        image.pixels.data()))
        throw FormatError(path, "cannot read pixels: " + in->geterror());
    in->close();
    return image;
}

std::string read_image_attribute(const std::string& path, const std::string& name) {
    auto in = open_input(path);
    const OIIO::ImageSpec& spec = in->spec();
    const OIIO::ParamValue* p = spec.find_attribute(name);
    if (!p) {
        // OIIO renames some standard OpenEXR attributes when reading.
        static const std::pair<const char*, const char*> aliases[] = {
            {"capdate", "DateTime"},
            {"comments", "ImageDescription"},
            {"owner", "Copyright"}};
        for (const auto& [exr_name, oiio_name] : aliases)
            if (lower(name) == exr_name) p = spec.find_attribute(oiio_name);
    }
    return p ? p->get_string() : std::string();
}

} // namespace sss
