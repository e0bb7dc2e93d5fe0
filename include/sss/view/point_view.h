// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file point_view.h
/// Module view: pictures of point clouds (the ptview tool, PRMan's ptviewer
/// need).
/// May use: image, cloud and util.
///
/// Each point is drawn as a disc of its radius, oriented by its normal (a
/// sphere's outline when it has none), projected as an ellipse through the
/// cloud's own camera (world2eye / world2ndc from its file) or an orbit
/// camera, z-buffered so the nearest surface wins. Several clouds and
/// channels make a contact sheet of tiles that share one camera and one
/// exposure. See docs/ptview.md.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "sss/cloud/point_cloud.h"

namespace sss {

class Progress; // sss/util/progress.h

/// A camera that maps world space to raster space: x in [0, width) from the
/// left, y in [0, height) from the top, pixel centres at +0.5.
struct ViewCamera {
    /// World to eye space (RenderMan's: x right, y up, z away from the viewer).
    glm::dmat4 world_to_eye{1.0};
    /// World to raster space (homogeneous: divide x and y by w).
    glm::dmat4 world_to_raster{1.0};
    int width = 0;
    int height = 0;
    /// Points whose homogeneous w is at most this are behind the camera.
    double min_w = 0.0;
    std::string description; ///< one line: "file camera of X" or "orbit az .. el .."
};

/// Whether a cloud carries a camera: a world2ndc that is not the identity.
bool has_file_camera(const PointCloud& cloud);

/// The camera a cloud was baked with (its world2eye and world2ndc), the NDC
/// square [0,1]^2 fitted into width x height with the frame's aspect
/// (cloud.format; square when the format is unset), centred. Throws
/// ValueError when the cloud has no camera (has_file_camera).
ViewCamera file_camera(const PointCloud& cloud, int width, int height,
                       const std::string& label);

/// The frame's aspect (width / height) of a cloud's camera: format x * pixel
/// aspect / format y, 1 when the format is unset.
double file_camera_aspect(const PointCloud& cloud);

/// A perspective camera on a sphere around `bounds`: it looks at the box's
/// centre from azimuth `azimuth_deg` (around the up axis) and elevation
/// `elevation_deg` (above the plane normal to it), far enough for the box's
/// bounding sphere to fit the field of view `fov_deg`, which spans the
/// image's shorter side. up_axis 0, 1, 2 = x, y, z. Azimuth 0, elevation 0
/// looks from +z (up x or y) or from -y (up z); the azimuth turns
/// counter-clockwise seen from above.
ViewCamera orbit_camera(const Bounds3& bounds, double azimuth_deg, double elevation_deg,
                        int up_axis, double fov_deg, int width, int height);

/// What a tile shows of its cloud.
struct ViewChannel {
    std::string name;       ///< a channel, or "N" (normals) or "radius"
    bool luminance = false; ///< "NAME:lum": Rec. 709 luminance of a colour
};

/// Parses "NAME" or "NAME:lum". Throws ValueError for an empty name or an
/// unknown suffix.
ViewChannel parse_view_channel(const std::string& spec);

/// The spelling parse_view_channel reads back.
std::string view_channel_text(const ViewChannel& channel);

/// How a tile's values are shown.
enum class ViewValueKind {
    Grey,     ///< one value (float channel, radius, luminance): exposed, grey
    Colour,   ///< three values (color, point, vector channels): exposed
    Direction ///< a unit vector (N, normal channels): 0.5 + 0.5 * v, not exposed
};

/// One tile drawn: per pixel the value of the nearest point (unexposed) and
/// which point it is.
struct ViewTile {
    int width = 0;
    int height = 0;
    ViewValueKind kind = ViewValueKind::Grey;
    std::vector<glm::vec3> value; ///< width * height, row-major from the top
    std::vector<uint32_t> point;  ///< the point drawn there, or kNoPoint
    std::size_t points_drawn = 0; ///< points in front of the eye, in the frame
    static constexpr uint32_t kNoPoint = 0xffffffffu;

    bool covered(std::size_t pixel) const { return point[pixel] != kNoPoint; }
};

/// Draws one channel of a cloud. Each point is a disc (an ellipse on screen)
/// of radius radius * radius_scale, widened to at least about one pixel so
/// that no point vanishes. Per pixel the nearest disc wins (depth of its
/// plane at the pixel centre; equal depths: the lower point index). Parallel;
/// the result does not depend on the thread count. Throws ValueError when the
/// channel is missing (naming the ones `label` has) or cannot be shown (a
/// matrix), or the cloud has 2^32 points or more. `progress` (may be null) is
/// given points done out of `progress_total`, starting at `progress_done`.
ViewTile render_view_tile(const PointCloud& cloud, const ViewChannel& channel,
                          const ViewCamera& camera, float radius_scale,
                          const std::string& label, Progress* progress = nullptr,
                          uint64_t progress_done = 0, uint64_t progress_total = 0);

/// Where the tiles of a contact sheet go.
struct ContactSheetLayout {
    int columns = 1;
    int rows = 1;
    int width = 0;  ///< the sheet's width in pixels
    int height = 0; ///< the sheet's height in pixels
    /// Top-left corner of tile i (reading order: left to right, top to bottom).
    int tile_x(int i) const { return (i % columns) * (tile_width + gap); }
    int tile_y(int i) const { return (i / columns) * (tile_height + gap); }
    int tile_width = 0;
    int tile_height = 0;
    int gap = 0;
};

/// Lays out `tiles` tiles of tile_width x tile_height with `gap` pixels
/// between them in `columns` columns (0: one row for up to 4 tiles, else the
/// smallest number of columns c with c * c >= tiles). Throws ValueError for
/// a sheet wider or taller than 65536 pixels.
ContactSheetLayout contact_sheet_layout(int tiles, int tile_width, int tile_height,
                                        int columns, int gap);

/// The settings of a picture.
struct PointViewOptions {
    /// Channels shown; empty: each cloud's first colour channel (else its
    /// first channel, else N).
    std::vector<ViewChannel> channels;
    /// nullopt: automatic (the value at the 99.5th percentile of the largest
    /// |component| of the exposed pixels becomes 1).
    std::optional<double> exposure;
    /// Automatic exposure chosen for each tile on its own (channels of
    /// different scales side by side) instead of one for the sheet.
    bool exposure_per_tile = false;
    bool false_color = true;     ///< negative values shown blue
    glm::vec3 background{0.05f}; ///< linear RGB of pixels without points
    float radius_scale = 1.0f;   ///< multiplies every point's radius
    int columns = 0;             ///< contact sheet columns (0: automatic)
    int gap = 2;                 ///< pixels between tiles
    Progress* progress = nullptr;
};

/// A cloud to show and the name it is shown under (its file).
struct LabelledCloud {
    const PointCloud* cloud = nullptr;
    std::string label;
};

/// One tile of a picture: which cloud and channel.
struct PointViewTileInfo {
    std::size_t cloud = 0; ///< index into the clouds given
    ViewChannel channel;
    ViewValueKind kind = ViewValueKind::Grey;
    std::size_t points_drawn = 0;
    std::size_t pixels_covered = 0;
    double exposure = 0.0;           ///< stops applied to this tile
    double exposure_reference = 0.0; ///< auto: the value shown as 1
};

/// A finished picture: linear RGB, exposure and false colour applied,
/// unclamped (PNG output clamps and encodes to sRGB; EXR keeps it).
struct PointViewImage {
    int width = 0;
    int height = 0;
    std::vector<glm::vec3> rgb; ///< width * height, row-major from the top
    ContactSheetLayout layout;
    std::vector<PointViewTileInfo> tiles;
    double exposure = 0.0;           ///< stops applied (given or automatic)
    bool auto_exposure = false;      ///< exposure was chosen automatically
    double exposure_reference = 0.0; ///< auto: the percentile value mapped to 1
    std::string description;         ///< one line, stored in the image's metadata
};

/// The tiles a request shows: for each cloud in order, each requested
/// channel it has (N and radius: every cloud), in the order requested; the
/// default channel of each cloud when none is requested. Throws ValueError
/// when a requested channel is in none of the clouds, or a cloud has none of
/// them (naming the channels it has).
std::vector<std::pair<std::size_t, ViewChannel>>
view_tiles(const std::vector<LabelledCloud>& clouds,
           const std::vector<ViewChannel>& channels);

/// The displayed linear colour of a tile value: Direction values as 0.5 +
/// 0.5 v; others times 2^exposure, then with false colour a negative
/// luminance becomes blue of that magnitude (kNegativeHue * |luminance|) and
/// other negative components 0.
glm::vec3 displayed_value(const glm::vec3& value, ViewValueKind kind, double exposure,
                          bool false_color);
/// The hue of negative values with false colour (linear RGB, blue).
inline constexpr float kNegativeHue[3] = {0.1f, 0.3f, 1.0f};

/// Draws every tile (view_tiles) with the camera, chooses the exposure and
/// assembles the contact sheet.
PointViewImage render_point_view(const std::vector<LabelledCloud>& clouds,
                                 const ViewCamera& camera,
                                 const PointViewOptions& options);

/// Writes the picture atomically: .png as 8-bit sRGB (clamped to [0, 1]),
/// .exr as 32-bit float linear RGB; any other name (a device, a FIFO) as PNG.
/// `software` goes into the Software attribute, the description into
/// ImageDescription. Throws IoError.
void write_point_view_image(const PointViewImage& image, const std::string& path,
                            const std::string& software);

/// Whether a path names an EXR output (ends in .exr, any case).
bool is_exr_path(const std::string& path);
/// Whether a path names a PNG output (ends in .png, any case).
bool is_png_path(const std::string& path);

} // namespace sss
