// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file point_view.cpp
/// Pictures of point clouds: cameras, disc splatting with a z-buffer,
/// exposure and false colour, contact sheets, PNG/EXR output (OpenImageIO).

#include "sss/view/point_view.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>

#include <glm/geometric.hpp>
#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>

#include "sss/cloud/point_cloud_io.h"
#include "sss/image/image_file.h"
#include "sss/util/atomic_output.h"
#include "sss/util/error.h"
#include "sss/util/math.h"
#include "sss/util/progress.h"
#include "sss/util/srgb.h"

namespace sss {

namespace {

/// Every disc is widened by this variance (pixels^2): a point a fraction of a
/// pixel across still covers the pixel nearest to its centre (a pixel centre
/// is at most sqrt(0.5) pixels away).
constexpr double kMinVariance = 0.5;
/// Points per parallel task and per progress update.
constexpr std::size_t kGrain = 16384;

std::string lower(std::string s) {
    for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

bool ends_with(const std::string& path, const char* ext) {
    const std::string e(ext);
    return path.size() >= e.size() && lower(path.substr(path.size() - e.size())) == e;
}

glm::dmat4 stored_matrix(const std::array<float, 16>& a) {
    // Stored as RenderMan's row-major row-vector matrix, which is glm's
    // column-major layout for column vectors (bake3d_file.cpp writes it so).
    glm::dmat4 m(1.0);
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) m[c][r] = double(a[std::size_t(c * 4 + r)]);
    return m;
}

std::string number_text(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", v);
    return buf;
}

/// A depth as an unsigned key with the same order (negative depths too).
uint32_t ordered_bits(float depth) {
    const uint32_t bits = std::bit_cast<uint32_t>(depth);
    return (bits & 0x80000000u) ? ~bits : (bits | 0x80000000u);
}

/// Two unit vectors perpendicular to the unit vector n (Duff et al. 2017).
void tangent_basis(const glm::dvec3& n, glm::dvec3& t1, glm::dvec3& t2) {
    const double sign = std::copysign(1.0, n.z);
    const double a = -1.0 / (sign + n.z);
    const double b = n.x * n.y * a;
    t1 = glm::dvec3(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    t2 = glm::dvec3(b, sign + n.y * n.y * a, -n.y);
}

float luminance(const glm::vec3& v) {
    return 0.2126f * v.x + 0.7152f * v.y + 0.0722f * v.z;
}

std::string channel_names(const PointCloud& cloud) {
    std::string s;
    for (const Channel& c : cloud.channels) s += (s.empty() ? "" : ", ") + c.name;
    return s.empty() ? std::string("none") : s;
}

/// Where a tile's per-point values come from.
struct ValueSource {
    enum class From { Channel, Normals, Radius } from = From::Channel;
    const Channel* channel = nullptr;
    ViewValueKind kind = ViewValueKind::Grey;
    bool luminance = false;

    glm::vec3 at(const PointCloud& cloud, std::size_t i) const {
        switch (from) {
        case From::Normals: {
            const glm::vec3 n = cloud.normals[i];
            const float len = glm::length(n);
            return len > 0.0f ? n / len : glm::vec3(0.0f);
        }
        case From::Radius:
            return glm::vec3(cloud.radii[i]);
        case From::Channel:
            break;
        }
        const int k = channel->components();
        const float* d = channel->data.data() + i * std::size_t(k);
        if (k == 1) return glm::vec3(d[0]);
        glm::vec3 v(d[0], d[1], d[2]);
        if (luminance) return glm::vec3(sss::luminance(v));
        if (kind == ViewValueKind::Direction) {
            const float len = glm::length(v);
            return len > 0.0f ? v / len : glm::vec3(0.0f);
        }
        return v;
    }
};

/// Whether the cloud has something to show under this name.
bool cloud_has(const PointCloud& cloud, const ViewChannel& channel) {
    return channel.name == "N" || channel.name == "radius" ||
           cloud.find_channel(channel.name) != nullptr;
}

ValueSource value_source(const PointCloud& cloud, const ViewChannel& channel,
                         const std::string& label) {
    ValueSource s;
    s.luminance = channel.luminance;
    if (const Channel* c = cloud.find_channel(channel.name)) {
        s.channel = c;
        switch (c->type) {
        case ChannelType::Float:
            s.kind = ViewValueKind::Grey;
            break;
        case ChannelType::Color:
        case ChannelType::Point:
        case ChannelType::Vector:
            s.kind = channel.luminance ? ViewValueKind::Grey : ViewValueKind::Colour;
            break;
        case ChannelType::Normal:
            s.kind = channel.luminance ? ViewValueKind::Grey : ViewValueKind::Direction;
            break;
        case ChannelType::Matrix:
            throw ValueError(label + ": channel \"" + channel.name +
                             "\" is a matrix, which cannot be shown");
        }
        return s;
    }
    if (channel.name == "N") {
        if (channel.luminance)
            throw ValueError(label + ": N (the normals) has no luminance");
        s.from = ValueSource::From::Normals;
        s.kind = ViewValueKind::Direction;
        return s;
    }
    if (channel.name == "radius") {
        s.from = ValueSource::From::Radius;
        s.kind = ViewValueKind::Grey;
        return s;
    }
    throw ValueError(label + ": no channel \"" + channel.name + "\" (its channels: " +
                     channel_names(cloud) + "; every cloud also has N and radius)");
}

/// The default channel of a cloud: its first colour channel, else its first
/// channel that can be shown, else its normals.
ViewChannel default_channel(const PointCloud& cloud) {
    for (const Channel& c : cloud.channels)
        if (c.type == ChannelType::Color) return {c.name, false};
    for (const Channel& c : cloud.channels)
        if (c.type != ChannelType::Matrix) return {c.name, false};
    return {"N", false};
}

/// The automatic exposure's reference: the 99.5th percentile of the largest
/// |component| of the covered pixels of the tiles (normals excluded); 0 when
/// there are none.
double exposure_reference(const std::vector<const ViewTile*>& tiles) {
    std::vector<float> magnitudes;
    for (const ViewTile* t : tiles) {
        if (t->kind == ViewValueKind::Direction) continue;
        for (std::size_t k = 0; k < t->value.size(); ++k)
            if (t->covered(k))
                magnitudes.push_back(
                    std::max({std::abs(t->value[k].x), std::abs(t->value[k].y),
                              std::abs(t->value[k].z)}));
    }
    if (magnitudes.empty()) return 0.0;
    const std::size_t q = std::min(
        magnitudes.size() - 1, std::size_t(0.995 * double(magnitudes.size() - 1) + 0.5));
    std::nth_element(magnitudes.begin(), magnitudes.begin() + std::ptrdiff_t(q),
                     magnitudes.end());
    return magnitudes[q];
}

/// The stops that show `reference` as 1 (0 for no reference; never -0).
double stops_for(double reference) {
    return reference > 0.0 ? 0.0 - std::log2(reference) : 0.0;
}

} // namespace

// ---------------------------------------------------------------------------
// Cameras
// ---------------------------------------------------------------------------

bool has_file_camera(const PointCloud& cloud) {
    return !is_identity(cloud.world_to_ndc);
}

double file_camera_aspect(const PointCloud& cloud) {
    const double x = cloud.format[0], y = cloud.format[1];
    const double pixel = cloud.format[2] > 0.0f ? double(cloud.format[2]) : 1.0;
    if (!(x > 0.0) || !(y > 0.0)) return 1.0;
    return x * pixel / y;
}

ViewCamera file_camera(const PointCloud& cloud, int width, int height,
                       const std::string& label) {
    if (!has_file_camera(cloud))
        throw ValueError(label +
                         ": the cloud has no camera (its world2ndc is the identity)");
    ViewCamera cam;
    cam.width = width;
    cam.height = height;
    cam.world_to_eye = stored_matrix(cloud.world_to_eye);
    // NDC [0,1]^2 spans the frame; fit the frame into the image, centred.
    const double aspect = file_camera_aspect(cloud);
    double fw = width, fh = height;
    if (double(width) / double(height) > aspect)
        fw = fh * aspect;
    else
        fh = fw / aspect;
    glm::dmat4 ndc_to_raster(1.0);
    ndc_to_raster[0][0] = fw;
    ndc_to_raster[1][1] = fh;
    ndc_to_raster[3][0] = 0.5 * (width - fw);
    ndc_to_raster[3][1] = 0.5 * (height - fh);
    cam.world_to_raster = ndc_to_raster * stored_matrix(cloud.world_to_ndc);
    cam.min_w = 0.0;
    cam.description = "camera of " + label;
    return cam;
}

ViewCamera orbit_camera(const Bounds3& bounds, double azimuth_deg, double elevation_deg,
                        int up_axis, double fov_deg, int width, int height) {
    if (up_axis < 0 || up_axis > 2)
        throw ValueError("orbit camera: up axis must be 0, 1 or 2");
    if (!(fov_deg > 0.0 && fov_deg < 180.0))
        throw ValueError("orbit camera: field of view must lie in (0, 180) degrees");
    const glm::dvec3 lo(bounds.lo), hi(bounds.hi);
    const glm::dvec3 centre = 0.5 * (lo + hi);
    double radius = 0.5 * glm::length(hi - lo);
    if (!(radius > 0.0)) radius = 1.0; // one point, or none: a unit sphere around it
    // Horizontal axes (e1 right at azimuth 0, e2 towards the viewer) and up.
    glm::dvec3 up(0.0), e1(0.0), e2(0.0);
    up[up_axis] = 1.0;
    if (up_axis == 2) {
        e1 = {1, 0, 0};
        e2 = {0, -1, 0};
    } else if (up_axis == 1) {
        e1 = {1, 0, 0};
        e2 = {0, 0, 1};
    } else {
        e1 = {0, 1, 0};
        e2 = {0, 0, 1};
    }
    const double az = azimuth_deg * kPi / 180.0, el = elevation_deg * kPi / 180.0;
    const glm::dvec3 dir =
        std::cos(el) * (std::sin(az) * e1 + std::cos(az) * e2) + std::sin(el) * up;
    const double half = 0.5 * fov_deg * kPi / 180.0;
    const glm::dvec3 forward = -dir;
    glm::dvec3 right = glm::cross(forward, up);
    if (glm::length(right) < 1e-9) // looking straight up or down
        right = glm::cross(forward, std::sin(el) > 0.0 ? -e2 : e2);
    right = glm::normalize(right);
    const glm::dvec3 cam_up = glm::cross(right, forward);
    // The nearest distance at which the box's 8 corners fit in 95 % of the
    // frame; the bounding sphere's distance always does (it holds the box).
    const double tan_half = std::tan(half);
    const double fit_x = 0.95 * tan_half * double(width) / std::min(width, height);
    const double fit_y = 0.95 * tan_half * double(height) / std::min(width, height);
    const auto fits = [&](double d) {
        for (int k = 0; k < 8; ++k) {
            const glm::dvec3 corner((k & 1) ? hi.x : lo.x, (k & 2) ? hi.y : lo.y,
                                    (k & 4) ? hi.z : lo.z);
            const glm::dvec3 v = corner - (centre + d * dir);
            const double z = glm::dot(v, forward);
            if (!(z > 0.0) || std::abs(glm::dot(v, right)) > fit_x * z ||
                std::abs(glm::dot(v, cam_up)) > fit_y * z)
                return false;
        }
        return true;
    };
    double far = radius / std::sin(half) / 0.95, near = 0.0;
    for (int it = 0; it < 60; ++it) {
        const double mid = 0.5 * (near + far);
        (fits(mid) ? far : near) = mid;
    }
    const double distance = far;
    const glm::dvec3 eye = centre + distance * dir;

    ViewCamera cam;
    cam.width = width;
    cam.height = height;
    glm::dmat4 w2e(1.0);
    for (int j = 0; j < 3; ++j) {
        w2e[j][0] = right[j];
        w2e[j][1] = cam_up[j];
        w2e[j][2] = forward[j];
    }
    w2e[3][0] = -glm::dot(right, eye);
    w2e[3][1] = -glm::dot(cam_up, eye);
    w2e[3][2] = -glm::dot(forward, eye);
    cam.world_to_eye = w2e;
    // Eye to raster: x = W/2 + f x/z, y = H/2 - f y/z; w = z.
    const double f = 0.5 * std::min(width, height) / std::tan(half);
    glm::dmat4 proj(0.0);
    proj[0][0] = f;
    proj[2][0] = 0.5 * width;
    proj[1][1] = -f;
    proj[2][1] = 0.5 * height;
    proj[2][2] = 1.0;
    proj[2][3] = 1.0;
    cam.world_to_raster = proj * w2e;
    cam.min_w = 1e-6 * distance;
    cam.description = "orbit az " + number_text(azimuth_deg) + " el " +
                      number_text(elevation_deg) + " up " + "xyz"[up_axis] + " fov " +
                      number_text(fov_deg);
    return cam;
}

// ---------------------------------------------------------------------------
// Channels and tiles
// ---------------------------------------------------------------------------

ViewChannel parse_view_channel(const std::string& spec) {
    ViewChannel c;
    const std::size_t colon = spec.rfind(':');
    c.name = spec;
    if (colon != std::string::npos) {
        const std::string suffix = spec.substr(colon + 1);
        if (suffix != "lum")
            throw ValueError("channel \"" + spec + "\": unknown suffix \":" + suffix +
                             "\" (only :lum, the luminance, is known)");
        c.name = spec.substr(0, colon);
        c.luminance = true;
    }
    if (c.name.empty()) throw ValueError("channel \"" + spec + "\": empty name");
    return c;
}

std::string view_channel_text(const ViewChannel& channel) {
    return channel.name + (channel.luminance ? ":lum" : "");
}

std::vector<std::pair<std::size_t, ViewChannel>>
view_tiles(const std::vector<LabelledCloud>& clouds,
           const std::vector<ViewChannel>& channels) {
    // A channel no cloud has is named first, with the channels they have.
    for (const ViewChannel& c : channels) {
        bool found = false;
        for (const LabelledCloud& l : clouds) found = found || cloud_has(*l.cloud, c);
        if (found) continue;
        if (clouds.size() == 1)
            value_source(*clouds.front().cloud, c, clouds.front().label);
        std::string have;
        for (const LabelledCloud& l : clouds)
            have += (have.empty() ? "" : "; ") + l.label + ": " + channel_names(*l.cloud);
        throw ValueError("no cloud has a channel \"" + c.name + "\" (" + have +
                         "; every cloud also has N and radius)");
    }
    std::vector<std::pair<std::size_t, ViewChannel>> tiles;
    for (std::size_t i = 0; i < clouds.size(); ++i) {
        const PointCloud& cloud = *clouds[i].cloud;
        if (channels.empty()) {
            tiles.emplace_back(i, default_channel(cloud));
            continue;
        }
        const std::size_t before = tiles.size();
        for (const ViewChannel& c : channels)
            if (cloud_has(cloud, c)) tiles.emplace_back(i, c);
        if (tiles.size() == before) {
            std::string asked;
            for (const ViewChannel& c : channels)
                asked += (asked.empty() ? "" : ", ") + c.name;
            throw ValueError(clouds[i].label + ": none of the channels " + asked +
                             " (its channels: " + channel_names(cloud) +
                             "; every cloud also has N and radius)");
        }
    }
    return tiles;
}

ViewTile render_view_tile(const PointCloud& cloud, const ViewChannel& channel,
                          const ViewCamera& camera, float radius_scale,
                          const std::string& label, Progress* progress,
                          uint64_t progress_done, uint64_t progress_total) {
    const ValueSource source = value_source(cloud, channel, label);
    if (cloud.size() >= std::size_t(ViewTile::kNoPoint))
        throw ValueError(label + ": " + std::to_string(cloud.size()) +
                         " points; pictures take fewer than 2^32");
    if (camera.width <= 0 || camera.height <= 0)
        throw ValueError("picture size must be positive");
    const int W = camera.width, H = camera.height;
    const std::size_t pixels = std::size_t(W) * std::size_t(H);
    // Per pixel: (ordered depth << 32 | point index); the smallest wins, so the
    // result is the same whatever order the threads draw in.
    std::vector<uint64_t> keys(pixels, std::numeric_limits<uint64_t>::max());
    const glm::dmat4& M = camera.world_to_raster;
    const glm::dmat4& E = camera.world_to_eye;
    const glm::dvec3 gz(E[0][2], E[1][2], E[2][2]); // d(eye z)/d(world)
    const double gz_len = glm::length(gz);
    const double scale = double(radius_scale);
    std::atomic<std::size_t> drawn{0};
    std::atomic<uint64_t> done{0};

    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, cloud.size(), kGrain),
        [&](const tbb::blocked_range<std::size_t>& range) {
            std::size_t local_drawn = 0;
            for (std::size_t i = range.begin(); i != range.end(); ++i) {
                const glm::dvec3 p(cloud.positions[i]);
                const glm::dvec4 h = M * glm::dvec4(p, 1.0);
                if (!(h.w > camera.min_w)) continue;
                const double cx = h.x / h.w, cy = h.y / h.w;
                // Screen Jacobian d(raster)/d(world) at the point.
                glm::dvec3 jx, jy;
                for (int j = 0; j < 3; ++j) {
                    jx[j] = (M[j][0] - cx * M[j][3]) / h.w;
                    jy[j] = (M[j][1] - cy * M[j][3]) / h.w;
                }
                const double r = double(cloud.radii[i]) * scale;
                const double depth = (E * glm::dvec4(p, 1.0)).z;
                if (!(depth > 0.0)) continue; // behind the eye (orthographic cameras too)
                double sxx, sxy, syy;
                double gx = 0.0, gy = 0.0; // depth gradient over the raster
                glm::dvec3 n(cloud.normals[i]);
                const double nlen = glm::length(n);
                if (nlen > 0.0) {
                    n /= nlen;
                    glm::dvec3 t1, t2;
                    tangent_basis(n, t1, t2);
                    const glm::dvec2 a1(glm::dot(jx, t1), glm::dot(jy, t1));
                    const glm::dvec2 a2(glm::dot(jx, t2), glm::dot(jy, t2));
                    sxx = r * r * (a1.x * a1.x + a2.x * a2.x);
                    sxy = r * r * (a1.x * a1.y + a2.x * a2.y);
                    syy = r * r * (a1.y * a1.y + a2.y * a2.y);
                    // The disc's plane: depth = depth + g . (pixel - centre).
                    const double det = a1.x * a2.y - a2.x * a1.y;
                    if (std::abs(det) * r * r > 0.01) {
                        const double b1 = glm::dot(gz, t1), b2 = glm::dot(gz, t2);
                        gx = (b1 * a2.y - b2 * a1.y) / det;
                        gy = (b2 * a1.x - b1 * a2.x) / det;
                    }
                } else {
                    // A sphere: its outline, about r times the Jacobian.
                    sxx = r * r * glm::dot(jx, jx);
                    sxy = r * r * glm::dot(jx, jy);
                    syy = r * r * glm::dot(jy, jy);
                }
                sxx += kMinVariance;
                syy += kMinVariance;
                const double det_s = sxx * syy - sxy * sxy;
                if (!(det_s > 0.0) || !std::isfinite(det_s)) continue;
                const double ex = std::sqrt(sxx), ey = std::sqrt(syy);
                const double x0 = std::max(0.0, std::ceil(cx - ex - 0.5));
                const double x1 = std::min(double(W - 1), std::floor(cx + ex - 0.5));
                const double y0 = std::max(0.0, std::ceil(cy - ey - 0.5));
                const double y1 = std::min(double(H - 1), std::floor(cy + ey - 0.5));
                if (!(x0 <= x1 && y0 <= y1)) continue;
                ++local_drawn;
                const double ixx = syy / det_s, ixy = -sxy / det_s, iyy = sxx / det_s;
                const double dz_max = r * gz_len;
                for (int y = int(y0); y <= int(y1); ++y) {
                    const double dy = y + 0.5 - cy;
                    for (int x = int(x0); x <= int(x1); ++x) {
                        const double dx = x + 0.5 - cx;
                        if (ixx * dx * dx + 2.0 * ixy * dx * dy + iyy * dy * dy > 1.0)
                            continue;
                        const double dz = std::clamp(gx * dx + gy * dy, -dz_max, dz_max);
                        const uint64_t key =
                            (uint64_t(ordered_bits(float(depth + dz))) << 32) | i;
                        std::atomic_ref<uint64_t> slot(
                            keys[std::size_t(y) * std::size_t(W) + std::size_t(x)]);
                        uint64_t seen = slot.load(std::memory_order_relaxed);
                        while (key < seen && !slot.compare_exchange_weak(
                                                 seen, key, std::memory_order_relaxed)) {
                        }
                    }
                }
            }
            drawn += local_drawn;
            if (progress) {
                const uint64_t d = done += range.size();
                progress->update(progress_done + d, progress_total);
            }
        });

    ViewTile tile;
    tile.width = W;
    tile.height = H;
    tile.kind = source.kind;
    tile.points_drawn = drawn.load();
    tile.value.assign(pixels, glm::vec3(0.0f));
    tile.point.assign(pixels, ViewTile::kNoPoint);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pixels, 1 << 14),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          for (std::size_t k = range.begin(); k != range.end(); ++k) {
                              if (keys[k] == std::numeric_limits<uint64_t>::max())
                                  continue;
                              const uint32_t i = uint32_t(keys[k] & 0xffffffffu);
                              tile.point[k] = i;
                              tile.value[k] = source.at(cloud, i);
                          }
                      });
    return tile;
}

// ---------------------------------------------------------------------------
// Contact sheets, exposure, false colour
// ---------------------------------------------------------------------------

ContactSheetLayout contact_sheet_layout(int tiles, int tile_width, int tile_height,
                                        int columns, int gap) {
    if (tiles < 1 || tile_width < 1 || tile_height < 1 || columns < 0 || gap < 0)
        throw ValueError("contact sheet: bad layout request");
    ContactSheetLayout l;
    if (columns == 0) {
        columns = 1;
        if (tiles <= 4)
            columns = tiles;
        else
            while (columns * columns < tiles) ++columns;
    }
    l.columns = std::min(columns, tiles);
    l.rows = (tiles + l.columns - 1) / l.columns;
    l.tile_width = tile_width;
    l.tile_height = tile_height;
    l.gap = gap;
    const int64_t w = int64_t(l.columns) * tile_width + int64_t(l.columns - 1) * gap;
    const int64_t h = int64_t(l.rows) * tile_height + int64_t(l.rows - 1) * gap;
    if (w > 65536 || h > 65536)
        throw ValueError("contact sheet of " + std::to_string(w) + " x " +
                         std::to_string(h) + " pixels: larger than 65536 on a side");
    l.width = int(w);
    l.height = int(h);
    return l;
}

glm::vec3 displayed_value(const glm::vec3& value, ViewValueKind kind, double exposure,
                          bool false_color) {
    if (kind == ViewValueKind::Direction) return 0.5f + 0.5f * value;
    // In doubles, clamped to the float range: no Inf (nor an Inf - Inf NaN in
    // the luminance) whatever the value and exposure.
    constexpr double kLargest = 3.0e38;
    const double gain = std::exp2(exposure);
    glm::dvec3 v = glm::dvec3(value) * gain;
    v = glm::clamp(v, -kLargest, kLargest);
    if (false_color) {
        const double lum = kind == ViewValueKind::Grey
                               ? v.x
                               : 0.2126 * v.x + 0.7152 * v.y + 0.0722 * v.z;
        if (lum < 0.0)
            v = -lum * glm::dvec3(kNegativeHue[0], kNegativeHue[1], kNegativeHue[2]);
        else
            v = glm::max(v, glm::dvec3(0.0));
    }
    return glm::vec3(glm::clamp(v, -kLargest, kLargest));
}

PointViewImage render_point_view(const std::vector<LabelledCloud>& clouds,
                                 const ViewCamera& camera,
                                 const PointViewOptions& options) {
    if (clouds.empty()) throw ValueError("no point cloud to show");
    const std::vector<std::pair<std::size_t, ViewChannel>> which =
        view_tiles(clouds, options.channels);
    PointViewImage image;
    image.layout = contact_sheet_layout(int(which.size()), camera.width, camera.height,
                                        options.columns, options.gap);
    uint64_t total = 0;
    for (const auto& [c, channel] : which) total += clouds[c].cloud->size();
    uint64_t done = 0;
    std::vector<ViewTile> tiles;
    for (const auto& [c, channel] : which) {
        const LabelledCloud& l = clouds[c];
        tiles.push_back(render_view_tile(*l.cloud, channel, camera, options.radius_scale,
                                         l.label, options.progress, done, total));
        done += l.cloud->size();
        PointViewTileInfo info;
        info.cloud = c;
        info.channel = channel;
        info.kind = tiles.back().kind;
        info.points_drawn = tiles.back().points_drawn;
        for (std::size_t k = 0; k < tiles.back().point.size(); ++k)
            info.pixels_covered += tiles.back().covered(k) ? 1 : 0;
        image.tiles.push_back(info);
    }
    if (options.progress) options.progress->finish();

    // One exposure for every tile, so that they compare (or one per tile).
    if (options.exposure) {
        image.exposure = *options.exposure;
        for (PointViewTileInfo& info : image.tiles) info.exposure = image.exposure;
    } else {
        image.auto_exposure = true;
        if (options.exposure_per_tile) {
            for (std::size_t t = 0; t < tiles.size(); ++t) {
                image.tiles[t].exposure_reference = exposure_reference({&tiles[t]});
                image.tiles[t].exposure = stops_for(image.tiles[t].exposure_reference);
            }
            image.exposure_reference = image.tiles.front().exposure_reference;
            image.exposure = image.tiles.front().exposure;
        } else {
            std::vector<const ViewTile*> all;
            for (const ViewTile& t : tiles) all.push_back(&t);
            image.exposure_reference = exposure_reference(all);
            image.exposure = stops_for(image.exposure_reference);
            for (PointViewTileInfo& info : image.tiles) {
                info.exposure = image.exposure;
                info.exposure_reference = image.exposure_reference;
            }
        }
    }

    const ContactSheetLayout& l = image.layout;
    image.width = l.width;
    image.height = l.height;
    const glm::vec3 gap_colour(0.2f);
    image.rgb.assign(std::size_t(l.width) * std::size_t(l.height), gap_colour);
    for (std::size_t t = 0; t < tiles.size(); ++t) {
        const ViewTile& tile = tiles[t];
        const int ox = l.tile_x(int(t)), oy = l.tile_y(int(t));
        tbb::parallel_for(0, tile.height, [&](int y) {
            for (int x = 0; x < tile.width; ++x) {
                const std::size_t k = std::size_t(y) * std::size_t(tile.width) + x;
                glm::vec3& out =
                    image.rgb[std::size_t(oy + y) * std::size_t(l.width) + (ox + x)];
                out = tile.covered(k)
                          ? displayed_value(tile.value[k], tile.kind,
                                            image.tiles[t].exposure, options.false_color)
                          : options.background;
            }
        });
    }

    std::string d = "ptview:";
    for (std::size_t t = 0; t < image.tiles.size(); ++t)
        d += std::string(t ? " |" : "") + " " + clouds[image.tiles[t].cloud].label + " " +
             view_channel_text(image.tiles[t].channel);
    d += "; " + camera.description + "; exposure ";
    if (options.exposure_per_tile && image.auto_exposure) {
        for (std::size_t t = 0; t < image.tiles.size(); ++t)
            d += (t ? " | " : "") + number_text(image.tiles[t].exposure);
        d += " (auto, per tile)";
    } else {
        d += number_text(image.exposure) + (image.auto_exposure ? " (auto)" : "");
    }
    d += std::string("; false colour ") + (options.false_color ? "on" : "off");
    image.description = d;
    return image;
}

// ---------------------------------------------------------------------------
// Output
// ---------------------------------------------------------------------------

bool is_exr_path(const std::string& path) {
    return ends_with(path, ".exr");
}

bool is_png_path(const std::string& path) {
    return ends_with(path, ".png");
}

void write_point_view_image(const PointViewImage& image, const std::string& path,
                            const std::string& software) {
    const bool exr = is_exr_path(path);
    const std::size_t n = image.rgb.size();
    ImageFileSpec spec;
    spec.format = exr ? "openexr" : "png";
    spec.width = image.width;
    spec.height = image.height;
    spec.channel_names = {"R", "G", "B"};
    spec.stored = exr ? PixelType::Float : PixelType::UInt8;
    spec.attributes = {{"ImageDescription", image.description}, {"Software", software}};
    if (exr) spec.attributes.push_back({"compression", std::string("zip")});
    if (exr) {
        write_image_file(path, spec, PixelType::Float, image.rgb.data());
    } else {
        std::vector<uint8_t> bytes(3 * n);
        tbb::parallel_for(std::size_t(0), n, [&](std::size_t k) {
            for (int c = 0; c < 3; ++c) {
                const double v = std::clamp(double(image.rgb[k][c]), 0.0, 1.0);
                bytes[3 * k + std::size_t(c)] =
                    uint8_t(std::lround(255.0 * srgb_encode(v)));
            }
        });
        write_image_file(path, spec, PixelType::UInt8, bytes.data());
    }
}

} // namespace sss
