// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file brickmap_picture.cpp
/// brickinfo's pictures of a brick map: levels seen down an axis and slices
/// of lookups, auto-exposed and written as 8-bit sRGB PNG through
/// OpenImageIO. A file of its own: only the programs that draw pictures link
/// OpenImageIO (brickmap_tools.cpp).

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>

#include "sss/brick/brickmap_tools.h"
#include "sss/cloud/point_cloud_io.h"
#include "sss/image/image_file.h"
#include "sss/util/atomic_output.h"
#include "sss/util/error.h"
#include "sss/util/parse.h"
#include "sss/util/srgb.h"
#include "sss/util/version.h"

namespace sss {

/// brickmap_tools.cpp: tree names in the order of brickmap.h.
extern const char* const kBrickMapTreeNames[7];

namespace {

/// The query normal that selects a tree (zero for tree 0).
glm::vec3 tree_normal(int tree) {
    glm::vec3 n(0.0f);
    if (tree >= 1 && tree <= 6) n[(tree - 1) / 2] = (tree % 2 == 1) ? 1.0f : -1.0f;
    return n;
}

std::string channel_list(const BrickMapInfo& info) {
    std::string s;
    for (const auto& [name, type] : info.channels) s += (s.empty() ? "" : ", ") + name;
    return s;
}

/// The deepest level that has bricks, or -1.
int deepest_level(const BrickMapInfo& info) {
    for (int d = int(info.levels.size()) - 1; d >= 0; --d)
        if (info.levels[std::size_t(d)].bricks > 0) return d;
    return -1;
}

bool ends_with_png(const std::string& path) {
    if (path.size() < 4) return false;
    std::string ext = path.substr(path.size() - 4);
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return ext == ".png";
}

} // namespace

// ---------------------------------------------------------------------------
// brickinfo: pictures
// ---------------------------------------------------------------------------

namespace {

/// An orthographic view: screen axes right/up (signed world axes), the
/// direction towards the viewer, and the pixel grid.
struct View {
    glm::dvec3 right{1, 0, 0};
    glm::dvec3 up{0, 1, 0};
    glm::dvec3 toward{0, 0, 1};
    double u0 = 0.0; ///< left edge (along right)
    double v1 = 0.0; ///< top edge (along up)
    double pixel = 1.0;
    int width = 1;
    int height = 1;
};

View make_view(int axis, bool from_negative, const glm::dvec3& lo, const glm::dvec3& hi,
               int size) {
    View v;
    v.toward = glm::dvec3(0.0);
    v.toward[axis] = from_negative ? -1.0 : 1.0;
    glm::dvec3 world_up(0.0);
    world_up[axis == 2 ? 1 : 2] = 1.0;
    v.up = world_up;
    // Left-handed, as RenderMan's camera: right = up x forward, so a view from
    // -z (a default camera's side) has +x to the right and +y up.
    v.right = glm::cross(v.up, -v.toward);
    // The box's extent on the screen axes (they are signed world axes).
    double umin = std::numeric_limits<double>::max(), umax = -umin;
    double vmin = umin, vmax = -umin;
    for (int c = 0; c < 8; ++c) {
        glm::dvec3 p((c & 1) ? hi.x : lo.x, (c & 2) ? hi.y : lo.y, (c & 4) ? hi.z : lo.z);
        umin = std::min(umin, glm::dot(p, v.right));
        umax = std::max(umax, glm::dot(p, v.right));
        vmin = std::min(vmin, glm::dot(p, v.up));
        vmax = std::max(vmax, glm::dot(p, v.up));
    }
    double ext = std::max(umax - umin, vmax - vmin);
    if (!(ext > 0.0)) ext = 1.0;
    v.pixel = ext / size;
    v.width = std::clamp(int(std::lround((umax - umin) / v.pixel)), 1, size);
    v.height = std::clamp(int(std::lround((vmax - vmin) / v.pixel)), 1, size);
    // Centre the box in the pixel grid.
    v.u0 = 0.5 * (umin + umax) - 0.5 * v.width * v.pixel;
    v.v1 = 0.5 * (vmin + vmax) + 0.5 * v.height * v.pixel;
    return v;
}

const char* axis_name(int axis) {
    static const char* const names[] = {"x", "y", "z"};
    return names[axis];
}

/// Value at quantile q of the values (0 when empty); reorders them.
double quantile(std::vector<float>& values, double q) {
    if (values.empty()) return 0.0;
    std::size_t k =
        std::min(values.size() - 1, std::size_t(q * double(values.size() - 1) + 0.5));
    std::nth_element(values.begin(), values.begin() + std::ptrdiff_t(k), values.end());
    return values[k];
}

/// The picture being drawn: up to 3 components per pixel and a "has data" flag.
struct Canvas {
    int width = 0, height = 0, components = 1;
    std::vector<float> value;
    std::vector<uint8_t> filled;
    // Level pictures: z-buffer (larger = nearer the viewer), the depth of
    // the level that wrote each pixel (-1: none) and its sample spacing.
    std::vector<float> depth;
    std::vector<int8_t> level;
    std::vector<float> slack;

    Canvas(int w, int h, int c)
        : width(w), height(h), components(c), value(std::size_t(w) * h * c, 0.0f),
          filled(std::size_t(w) * h, 0),
          depth(std::size_t(w) * h, -std::numeric_limits<float>::infinity()),
          level(std::size_t(w) * h, int8_t(-1)), slack(std::size_t(w) * h, 0.0f) {}
};

/// Exposes and encodes the canvas to 8-bit sRGB, background as a checkerboard.
std::vector<uint8_t> expose(const Canvas& canvas, BrickMapPictureReport& report) {
    std::vector<float> values;
    for (std::size_t i = 0; i < canvas.filled.size(); ++i)
        if (canvas.filled[i])
            for (int c = 0; c < canvas.components; ++c)
                values.push_back(canvas.value[i * canvas.components + c]);
    report.pixels_with_data = values.size() / std::size_t(canvas.components);
    std::vector<float> sorted = values;
    double lo = std::min(0.0, quantile(sorted, 0.005));
    double hi = quantile(sorted, 0.995);
    if (!(hi > lo))
        hi = lo + (lo < 0.0 ? -lo : 1.0); // flat picture: value maps to mid/black
    report.black = lo;
    report.white = hi;

    std::vector<uint8_t> rgb(std::size_t(canvas.width) * canvas.height * 3);
    for (int y = 0; y < canvas.height; ++y) {
        for (int x = 0; x < canvas.width; ++x) {
            std::size_t i = std::size_t(y) * canvas.width + x;
            uint8_t* px = rgb.data() + 3 * i;
            if (!canvas.filled[i]) {
                // 8-pixel checkerboard: never mistaken for data, even black data.
                uint8_t g = ((x / 8 + y / 8) % 2 == 0) ? 48 : 80;
                px[0] = px[1] = g;
                px[2] = uint8_t(g + 16);
                continue;
            }
            for (int c = 0; c < 3; ++c) {
                float v = canvas.value[i * canvas.components +
                                       std::min(c, canvas.components - 1)];
                double t = std::clamp((double(v) - lo) / (hi - lo), 0.0, 1.0);
                px[c] = uint8_t(std::lround(255.0 * srgb_encode(t)));
            }
        }
    }
    return rgb;
}

void write_png(const std::string& path, int width, int height,
               const std::vector<uint8_t>& rgb, const std::string& description) {
    ImageFileSpec spec;
    spec.width = width;
    spec.height = height;
    spec.channel_names = {"R", "G", "B"};
    spec.attributes = {{"ImageDescription", description},
                       {"Software", std::string("sss brickinfo ") + version_string()}};
    spec.what = "PNG";
    write_image_file(path, spec, PixelType::UInt8, rgb.data());
}

/// A signed world axis (screen axes are +-x, +-y or +-z).
struct SignedAxis {
    int axis = 0;
    double sign = 1.0;
};

SignedAxis signed_axis(const glm::dvec3& v) {
    for (int a = 0; a < 3; ++a)
        if (v[a] != 0.0) return SignedAxis{a, v[a] > 0.0 ? 1.0 : -1.0};
    return {};
}

/// Draws the samples of one depth. Within a depth the front-most sample
/// wins. When finer levels are drawn over coarser ones (all levels), a finer
/// sample replaces a coarser pixel unless it lies clearly behind it (more
/// than the coarser spacing), so pruned-away front bricks do not let the
/// back of an object show through.
void draw_level(const BrickMap& map, const BrickMapPictureOptions& options, int level,
                int offset, const View& view, Canvas& canvas, std::size_t& drawn) {
    const BrickMapInfo& info = map.info();
    const int ds = info.data_size;
    const double edge = info.cube_side / std::ldexp(1.0, level);
    const double spacing = edge / 7.0;
    const SignedAxis ra = signed_axis(view.right);
    const SignedAxis ua = signed_axis(view.up);

    struct Job {
        int tree;
        std::array<uint32_t, 3> node;
    };
    std::vector<Job> jobs;
    for (int t = 0; t < 7; ++t) {
        if (options.tree >= 0 && t != options.tree) continue;
        for (const auto& node : map.bricks_at(t, level)) jobs.push_back(Job{t, node});
    }

    // A sample with lattice coordinate g covers [g - 1/2, g + 1/2) spacings
    // along each axis. Cell boundaries are computed from the integer
    // boundary index alone, so neighbouring samples share them exactly and
    // no pixel falls between two samples.
    auto boundary = [&](int axis, int64_t k) {
        return info.cube_min[axis] + (double(k) - 0.5) * spacing;
    };
    // Pixels whose centres (index + 1/2, in pixels from origin) lie in
    // [lo, hi); at least the pixel under the centre when the cell is
    // smaller than a pixel.
    auto pixel_range = [&](double lo, double hi, int limit, int& a, int& b) {
        a = int(std::ceil(lo / view.pixel - 0.5));
        b = int(std::ceil(hi / view.pixel - 0.5)) - 1;
        if (a > b) a = b = int(std::floor(0.5 * (lo + hi) / view.pixel));
        a = std::max(a, 0);
        b = std::min(b, limit - 1);
    };

    // Bricks are read in parallel a chunk at a time and drawn in job order,
    // so ties in depth resolve the same way whatever the thread count.
    constexpr std::size_t kChunk = 256;
    std::vector<std::vector<float>> data(kChunk);
    std::vector<std::vector<uint8_t>> present(kChunk);
    std::vector<uint8_t> found(kChunk);
    for (std::size_t first = 0; first < jobs.size(); first += kChunk) {
        const std::size_t count = std::min(kChunk, jobs.size() - first);
        tbb::parallel_for(std::size_t(0), count, [&](std::size_t k) {
            const Job& job = jobs[first + k];
            found[k] = map.read_brick(job.tree, level, job.node[0], job.node[1],
                                      job.node[2], data[k], present[k]);
        });
        for (std::size_t k = 0; k < count; ++k) {
            if (!found[k]) continue;
            const Job& job = jobs[first + k];
            for (int s = 0; s < 512; ++s) {
                if (!present[k][std::size_t(s)]) continue;
                const int64_t g[3] = {7 * int64_t(job.node[0]) + s % 8,
                                      7 * int64_t(job.node[1]) + (s / 8) % 8,
                                      7 * int64_t(job.node[2]) + s / 64};
                const glm::dvec3 q =
                    info.cube_min +
                    glm::dvec3(double(g[0]), double(g[1]), double(g[2])) * spacing;
                const float depth = float(glm::dot(q, view.toward));
                // Screen intervals of the cell (signed axes flip the bounds).
                const double r0 = ra.sign * boundary(ra.axis, g[ra.axis]);
                const double r1 = ra.sign * boundary(ra.axis, g[ra.axis] + 1);
                const double u0 = std::min(r0, r1), u1 = std::max(r0, r1);
                const double w0 = ua.sign * boundary(ua.axis, g[ua.axis]);
                const double w1 = ua.sign * boundary(ua.axis, g[ua.axis] + 1);
                const double v0 = std::min(w0, w1), v1 = std::max(w0, w1);
                int x0, x1, y0, y1;
                pixel_range(u0 - view.u0, u1 - view.u0, view.width, x0, x1);
                pixel_range(view.v1 - v1, view.v1 - v0, view.height, y0, y1);
                if (x0 > x1 || y0 > y1) continue;
                ++drawn;
                const float* src = data[k].data() + std::size_t(s) * ds + offset;
                for (int y = y0; y <= y1; ++y) {
                    for (int x = x0; x <= x1; ++x) {
                        const std::size_t i = std::size_t(y) * view.width + x;
                        const bool same_level = canvas.level[i] == level;
                        const float limit = same_level
                                                ? canvas.depth[i]
                                                : canvas.depth[i] - canvas.slack[i];
                        if (!(depth > limit)) continue;
                        canvas.depth[i] = depth;
                        canvas.slack[i] = float(spacing);
                        canvas.level[i] = int8_t(level);
                        canvas.filled[i] = 1;
                        for (int c = 0; c < canvas.components; ++c)
                            canvas.value[i * canvas.components + c] = src[c];
                    }
                }
            }
        }
    }
}

void draw_slice(const BrickMap& map, const BrickMapPictureOptions& options, int offset,
                const View& view, Canvas& canvas) {
    const int ds = map.info().data_size;
    std::vector<int> trees;
    if (options.tree >= 0) {
        trees.push_back(options.tree);
    } else {
        for (int t = 0; t < 7; ++t) trees.push_back(t);
    }
    tbb::parallel_for(tbb::blocked_range<int>(0, view.height),
                      [&](const tbb::blocked_range<int>& rows) {
                          std::vector<float> buf(static_cast<std::size_t>(ds));
                          for (int y = rows.begin(); y != rows.end(); ++y) {
                              for (int x = 0; x < view.width; ++x) {
                                  const double u = view.u0 + (x + 0.5) * view.pixel;
                                  const double v = view.v1 - (y + 0.5) * view.pixel;
                                  glm::dvec3 p = u * view.right + v * view.up;
                                  p[options.axis] = options.slice;
                                  double acc[3] = {0, 0, 0};
                                  int hits = 0;
                                  for (int t : trees) {
                                      if (!map.lookup(glm::vec3(p), tree_normal(t),
                                                      options.filter_radius, buf.data()))
                                          continue;
                                      ++hits;
                                      for (int c = 0; c < canvas.components; ++c)
                                          acc[c] += buf[std::size_t(offset + c)];
                                  }
                                  if (hits == 0) continue;
                                  std::size_t i = std::size_t(y) * view.width + x;
                                  canvas.filled[i] = 1;
                                  for (int c = 0; c < canvas.components; ++c)
                                      canvas.value[i * canvas.components + c] =
                                          float(acc[c] / hits);
                              }
                          }
                      });
}

} // namespace

BrickMapPictureReport write_brick_map_picture(const BrickMap& map,
                                              const BrickMapPictureOptions& options,
                                              const std::string& path) {
    const BrickMapInfo& info = map.info();
    // A device or FIFO has no extension to check (it gets the PNG bytes).
    if (!ends_with_png(path) && !writes_into_existing(path))
        throw ValueError(path + ": pictures are PNG files (.png)");
    if (options.axis < 0 || options.axis > 2)
        throw ValueError("picture axis must be x, y or z");
    if (options.tree < -1 || options.tree > 6)
        throw ValueError("tree " + std::to_string(options.tree) +
                         " is out of range [0, 6]");
    if (options.size < 1 || options.size > 4096)
        throw ValueError("picture size " + std::to_string(options.size) +
                         " is out of range [1, 4096]");
    if (info.channels.empty()) throw ValueError("the map has no channels");
    const std::string channel =
        options.channel.empty() ? info.channels.front().first : options.channel;
    const int index = map.channel_index(channel);
    if (index < 0)
        throw ValueError("no channel '" + channel +
                         "' in the map (channels: " + channel_list(info) + ")");
    const int offset = map.channel_offset(channel);
    const int components = channel_type_size(info.channels[std::size_t(index)].second);
    const int deepest = deepest_level(info);
    if (deepest < 0) throw ValueError("the map has no bricks");

    BrickMapPictureReport report;
    const std::string tree_text =
        options.tree < 0 ? std::string("all trees")
                         : std::string("tree ") + std::to_string(options.tree) + " (" +
                               kBrickMapTreeNames[options.tree] + ")";
    std::string what;
    View view;
    std::unique_ptr<Canvas> canvas;
    if (options.mode == BrickMapPictureMode::Level) {
        if (options.level > deepest)
            throw ValueError("level " + std::to_string(options.level) +
                             " is deeper than the map (deepest level with bricks: " +
                             std::to_string(deepest) + ")");
        report.level = options.level;
        // Frame the input's bounding box plus one sample spacing of the
        // finest level drawn (splats reach the neighbouring samples), within
        // the root cube.
        const int finest = options.level < 0 ? deepest : options.level;
        const double margin = info.cube_side / std::ldexp(1.0, finest) / 7.0;
        const glm::dvec3 cube_max = info.cube_min + glm::dvec3(info.cube_side);
        const glm::dvec3 lo = glm::max(info.bbox_min - margin, info.cube_min);
        const glm::dvec3 hi = glm::min(info.bbox_max + margin, cube_max);
        view = make_view(options.axis, options.view_from_negative, lo, hi, options.size);
        canvas = std::make_unique<Canvas>(view.width, view.height, components);
        if (options.level >= 0) {
            draw_level(map, options, options.level, offset, view, *canvas,
                       report.samples_drawn);
            what = "level " + std::to_string(options.level) + " samples";
        } else {
            // Coarse to fine: each pixel ends with the finest data there.
            for (int d = 0; d <= deepest; ++d)
                draw_level(map, options, d, offset, view, *canvas, report.samples_drawn);
            what = "levels 0-" + std::to_string(deepest) + " samples (finest per pixel)";
        }
        what += std::string(" seen from ") + (options.view_from_negative ? "-" : "+") +
                axis_name(options.axis);
    } else {
        // The input's bounding box plus 2 % of its largest side.
        const glm::dvec3 ext = info.bbox_max - info.bbox_min;
        double pad = 0.02 * std::max({ext.x, ext.y, ext.z});
        if (!(pad > 0.0)) pad = 0.02 * info.cube_side;
        view = make_view(options.axis, options.view_from_negative, info.bbox_min - pad,
                         info.bbox_max + pad, options.size);
        canvas = std::make_unique<Canvas>(view.width, view.height, components);
        draw_slice(map, options, offset, view, *canvas);
        what = std::string("lookups on the plane ") + axis_name(options.axis) + " = " +
               short_float(options.slice) + ", filter radius " +
               short_float(options.filter_radius);
    }
    report.width = view.width;
    report.height = view.height;
    const std::vector<uint8_t> rgb = expose(*canvas, report);
    report.description = what + ", " + tree_text + ", channel " + channel + ", black " +
                         short_float(report.black) + ", white " +
                         short_float(report.white) +
                         ", right = " + (signed_axis(view.right).sign > 0 ? "+" : "-") +
                         axis_name(signed_axis(view.right).axis) + ", up = +" +
                         axis_name(signed_axis(view.up).axis);
    write_png(path, view.width, view.height, rgb, report.description);
    return report;
}

} // namespace sss
