// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file image_io.h
/// Multi-channel float images and their output through OpenImageIO /
/// OpenEXR, following RenderMan's Display semantics and the OpenEXR layer
/// naming convention (beauty in R, G, B, A; AOV "diffuse" in diffuse.R,
/// diffuse.G, diffuse.B). The user-facing rules are in docs/images.md.

#include <array>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "sss/scene/scene.h"

namespace sss {

/// A float image with named channels, pixels interleaved, rows top to bottom.
struct Image {
    int width = 0;
    int height = 0;
    std::vector<std::string> channels; ///< e.g. R G B A diffuse.R diffuse.G diffuse.B
    std::vector<float> pixels;         ///< width * height * channels.size()

    Image() = default;
    /// A w x h image with the given channels, every value 0. Throws
    /// ValueError for a negative size or an empty or repeated channel name.
    Image(int w, int h, std::vector<std::string> names);
    int channel_count() const { return static_cast<int>(channels.size()); }
    /// Index of a channel, or -1.
    int channel_index(const std::string& name) const;
    float* pixel(int x, int y) {
        return pixels.data() + (std::size_t(y) * width + x) * channels.size();
    }
    const float* pixel(int x, int y) const {
        return pixels.data() + (std::size_t(y) * width + x) * channels.size();
    }
};

/// Provenance written into image headers (EXR: Software, capDate, utcOffset,
/// renderTimeSeconds, worldToCamera, worldToNDC, sss:commandLine, sss:scene...).
struct ImageMetadata {
    std::string software;     ///< "render (sss) 0.1.0"
    std::string command_line; ///< the full command line
    double render_seconds = 0.0;
    /// Column-vector matrices (p' = M * p, like every sss Matrix4); the EXR
    /// attributes hold them in Imath's row-vector layout (docs/images.md).
    Matrix4 world_to_camera{1.0};
    Matrix4 world_to_ndc{1.0};
    /// World to screen with the screen window at [-1, 1] x [-1, 1], y up
    /// (zfiles' and shadow maps' "worldtoscreen", docs/scene.md).
    Matrix4 world_to_screen{1.0};
    std::vector<std::pair<std::string, std::string>> extra; ///< "sss:scene" -> path...
};

/// How one Display line is written, resolved from its DisplaySpec.
struct DisplayTarget {
    std::string path;   ///< file name (frame patterns already expanded)
    std::string format; ///< "openexr", "png", "tiff", "jpeg" (OIIO format names)
    std::vector<std::string> channels; ///< image channels written, in order
    std::vector<std::string> names;    ///< their names in the file
    bool half = true;                  ///< OpenEXR: half floats (default) or float
    std::string compression = "zip";   ///< OpenEXR compression (`"string compression"`)
    /// Exposure gain gamma: the colour channels (R, G, B and every layer.R/G/B
    /// but the P and N layers) become (gain * v)^(1/gamma) (v <= 0: gain * v)
    /// in every format; alpha, Z and one-channel AOVs are left alone.
    double exposure_gain = 1.0;
    double exposure_gamma = 1.0;
    /// PNG, TIFF, JPEG: the integer value is round(zero + one * v + dither * r)
    /// clamped to [min, max], r in [-1, 1) a hash of (pixel, channel). max >
    /// 255 writes 16 bits (PNG, TIFF); one = 0 writes float (TIFF only).
    /// Unused for OpenEXR.
    QuantizeSpec quantize{};
    /// The file's pixel type for PNG/TIFF/JPEG: 8 or 16 (bits), 32 (float).
    int bits = 8;
    /// Display types "zfile" and "shadow": a depth map (docs/scene.md,
    /// "Depth maps"): float Z only, no surface = kNoSurfaceDepth, with the
    /// worldtocamera and worldtoscreen matrices; `shadow_map` also tags it
    /// as a shadow map (textureinfo "type" "shadow").
    bool depth_map = false;
    bool shadow_map = false;
};

/// Whether a Display is a depth map ("zfile" or "shadow", any case).
bool display_is_depth_map(const DisplaySpec& display);

/// What a Display takes from the scene unless its parameters say otherwise:
/// Exposure, and Quantize (PRMan's 0 255 0 255 dither 0.5 when absent).
struct DisplayDefaults {
    double exposure_gain = 1.0;
    double exposure_gamma = 1.0;
    std::optional<QuantizeSpec> quantize;
};

/// The image file extensions render writes (.exr .tif .tiff .png .jpg .jpeg).
const std::vector<std::string>& image_extensions();

/// The format a Display writes: from the display type ("openexr"/"exr",
/// "tiff"/"tif", "png", "jpeg"/"jpg"; "zfile" and "shadow": OpenEXR
/// whatever the name), else ("file", "it", "framebuffer",
/// any other driver) from the extension of display_file(). Throws
/// ValueError naming the Display and its line when that extension is not
/// one of image_extensions() ("it"/"framebuffer" never: they add ".exr").
std::string display_format(const DisplaySpec& display);

/// Resolves a Display: the file format (display_format: "it"/"framebuffer"
/// write a file, adding ".exr" to a name without an image extension;
/// another extension with type "file" is an error), the channels from the mode ("rgba",
/// "rgb", "a", "z", "rgbz", "rgbaz", or AOV names such as "diffuse", "color diffuse" or
/// lists such as "Ci,a"), the EXR pixel type from `"string type" "half"|"float"` and
/// compression from `"string compression"`, the quantisation of PNG/TIFF/JPEG from
/// `"quantize" [zero one min max]` and
/// `"dither" [amplitude]` (else `defaults.quantize`, else PRMan's 0 255 0 255
/// and 0.5; ignored for OpenEXR), the exposure from `defaults`. For the
/// primary (non-'+') OpenEXR display, every AOV of `image` (every channel
/// but R, G, B, A, Z: the AOVs the scene asks for) is appended. Throws
/// ValueError, naming the display, for a mode naming a channel the image does
/// not have or channels the format cannot hold.
DisplayTarget resolve_display(const DisplaySpec& display, const Image& image,
                              bool primary, const DisplayDefaults& defaults = {});

/// Throws ValueError, naming the Display, when its format cannot hold a
/// width x height image (JPEG: at most 65500 pixels a side, libjpeg's bound).
void check_display_size(const DisplaySpec& display, const DisplayTarget& target,
                        int width, int height);

/// The dither number r in [-1, 1) of pixel (x, y), channel k of a file: a
/// hash of the three, the same for every run and thread count.
double dither_noise(int x, int y, int k);

/// Whether a Display is RenderMan's "null" driver (any case), which writes
/// nothing: the usual display of a bake pass.
bool display_writes_nothing(const DisplaySpec& display);

/// Whether a Display names a window ("it", "framebuffer", "x11"...): there
/// is none here, and the image goes to display_file() instead.
bool display_is_window(const DisplaySpec& display);

/// The file a Display writes (resolve_display's path, without the image):
/// its name, plus ".exr" for an "it"/"framebuffer" display whose name has no
/// image extension.
std::string display_file(const DisplaySpec& display);

/// Writes the target atomically (AtomicOutput) with OIIO. OpenEXR: linear
/// (after the exposure), half or float, with the metadata. PNG, TIFF, JPEG:
/// colour divided by alpha (straight alpha), then the exposure, then
/// quantised by target.quantize (no sRGB encoding: 8-bit values are
/// round(255 v) plus dither unless the exposure's gamma says otherwise). Throws
/// ValueError (NaN/Inf pixels, channels the image does not have: nothing is
/// written) and IoError (missing folder, write failure: the target is
/// untouched and no temporary is left).
void write_display(const Image& image, const DisplayTarget& target,
                   const ImageMetadata& metadata);

/// Reads an image file back (for tests and tools): the first subimage,
/// every channel as float, channel names and order as OpenImageIO reports
/// them. Throws IoError (missing file) and FormatError (unreadable).
Image read_image(const std::string& path);
/// One attribute of an image's header in text form ("" if absent). OpenEXR
/// names that OIIO renames on reading (capDate, comments, owner) are found too.
std::string read_image_attribute(const std::string& path, const std::string& name);

} // namespace sss
