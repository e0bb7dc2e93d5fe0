// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file brickmap_tools.h
/// What the brickmake and brickinfo tools do beyond the brick-map core
/// (brickmap.h): building from files, the -newer check, the text report,
/// pictures of a map (the brickviewer need) and evaluating a map at the
/// points of a cloud to measure its error. See docs/brickmake.md and
/// docs/brickinfo.md.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "sss/brick/brickmap.h"
#include "sss/cloud/point_cloud.h"

namespace sss {

class Progress; // sss/util/progress.h

// ---------------------------------------------------------------------------
// brickmake
// ---------------------------------------------------------------------------

/// Reads the clouds (.ptc/.ply) and builds the map at output (atomically).
/// Refuses an output that is one of the inputs or a folder (JobFiles).
/// ValueErrors of the build are prefixed with the input file names.
BrickMapBuildReport make_brick_map_from_files(const std::vector<std::string>& inputs,
                                              const BrickMapBuildOptions& options,
                                              const std::string& output);

/// Why the file at path is not a usable brick map (the message of the
/// error opening it gives: an older version, a corrupt header or tables, not
/// a brick map at all), or "" when it opens. brickmake -newer 1 rebuilds
/// such an output even when it is newer than the inputs.
std::string brick_map_problem(const std::string& path);

// ---------------------------------------------------------------------------
// brickinfo
// ---------------------------------------------------------------------------

/// The brickinfo report: format version, file size, channels, bounding box
/// and root cube, build settings, header matrices and image format when not
/// the defaults, provenance, bricks per tree, and per level the data bricks,
/// samples with data, occupancy-only nodes and sample spacing, with totals,
/// and what was checked: bricks_verified is BrickMap::verify()'s count, or
/// empty when the bricks were not read.
std::string describe_brick_map(const std::string& path, const BrickMap& map,
                               std::optional<std::size_t> bricks_verified);

/// What a picture shows.
enum class BrickMapPictureMode {
    /// The samples of one depth (or of all depths, finest per pixel), seen
    /// down an axis; per pixel the front-most sample with data.
    Level,
    Slice ///< texture3d lookups on a plane through the map
};

/// brickinfo -picture settings.
struct BrickMapPictureOptions {
    BrickMapPictureMode mode = BrickMapPictureMode::Level;
    /// Level mode: the depth drawn; -1 = every depth, coarse to fine, each
    /// pixel showing the finest data there (what a filter radius 0 lookup sees).
    int level = -1;
    /// Level: the axis looked down (the viewer is on the axis's positive side,
    /// or the negative one with view_from_negative); Slice: the plane's normal.
    int axis = 2;
    bool view_from_negative = false;
    double slice = 0.0;         ///< Slice: the plane's coordinate on axis
    float filter_radius = 0.0f; ///< Slice: lookup filter radius (0: finest data)
    std::string channel;        ///< channel shown; empty = the map's first
    int tree = -1;              ///< 0..6 = one tree, -1 = all of them
    int size = 512;             ///< pixels along the picture's longer side
};

/// What was drawn (brickinfo prints it).
struct BrickMapPictureReport {
    int width = 0;
    int height = 0;
    int level = -1;                ///< Level mode: the depth drawn (-1: all)
    std::size_t samples_drawn = 0; ///< Level mode: samples with data projected
    std::size_t pixels_with_data = 0;
    double black = 0.0;      ///< channel value shown as black
    double white = 0.0;      ///< channel value shown as white (before clamping)
    std::string description; ///< one line, also stored in the PNG's ImageDescription
};

/// Draws a picture of the map and writes it atomically as an 8-bit sRGB PNG
/// (OpenImageIO). Values are auto-exposed between black = min(0, 0.5th
/// percentile) and white = 99.5th percentile of the pixels with data; pixels
/// without data are a grey checkerboard. Throws ValueError (unknown channel,
/// level deeper than the map, bad tree/axis/size, path not ending in .png)
/// and IoError. The picture does not depend on the thread count. Level
/// pictures frame the input's bounding box (plus one sample spacing), slices
/// the bounding box plus 2 %; the longer side gets size pixels.
BrickMapPictureReport write_brick_map_picture(const BrickMap& map,
                                              const BrickMapPictureOptions& options,
                                              const std::string& path);

/// brickinfo -lookup settings.
struct BrickMapCloudLookupOptions {
    /// Filter radius of every lookup; negative = each point's radius times
    /// filter_scale (texture3d with the point's own size).
    float filter_radius = -1.0f;
    float filter_scale = 1.0f;
    bool compare = false; ///< compute differences to the input's channels
    Progress* progress = nullptr;
};

/// Difference between looked-up and input values of one channel, over every
/// point and component (points without data count with the value 0).
struct ChannelDifference {
    std::string name;
    double rms = 0.0;           ///< root mean square of (map - input)
    double max_abs = 0.0;       ///< largest |map - input|
    double reference_rms = 0.0; ///< root mean square of the input values
};

/// What a cloud lookup did.
struct BrickMapCloudLookupReport {
    std::size_t points = 0;
    std::size_t misses = 0; ///< points where the map has no data (values 0)
    std::vector<ChannelDifference> differences; ///< with compare, per shared channel
    /// With compare: map channels the input lacks (or has with another type).
    std::vector<std::string> not_compared;
};

/// Evaluates the map at every point of cloud with the point's normal and
/// returns a cloud with the same P, N, radius and header data plus the map's
/// channels (same names and types). Parallel; the result does not depend on
/// the thread count.
PointCloud lookup_brick_map_cloud(const BrickMap& map, const PointCloud& cloud,
                                  const BrickMapCloudLookupOptions& options,
                                  BrickMapCloudLookupReport* report = nullptr);

} // namespace sss
