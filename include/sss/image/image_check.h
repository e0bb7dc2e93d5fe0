// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file image_check.h
/// Image files checked before OpenImageIO reads them (textures, environment
/// maps, depth maps, envdome's probe): what a header declares is held against
/// the limits (docs/limits.md) and PNG files are checked whole, so that no
/// damaged or hostile file reaches OpenImageIO's asserts, libpng's own error
/// lines or an allocation of what a header claims.

#include <optional>
#include <string>

namespace sss {

/// What an image file's header declares (the first subimage, level 0).
struct ImageHeader {
    int width = 0;
    int height = 0;
    int channels = 0;
    int tile_width = 0;  ///< 0: scanlines
    int tile_height = 0; ///< 0: scanlines
};

/// Most channels an image read by the tools may have.
constexpr int kMaxImageChannels = 1024;
/// Most tiles of an image's first level: OpenEXR and TIFF readers hold a
/// table of every tile's offset (16M tiles: 128 MB of table).
constexpr long long kMaxImageTiles = 1LL << 24;

/// Checks `path` before it is read as an image:
/// - a PNG file (by its signature) is read whole without libpng: its chunks
///   and their CRCs, the header's fields, the palette of a palette image, and
///   the compressed rows, which must inflate to exactly what the header
///   declares (FormatError "damaged PNG: ...");
/// - other formats' headers are read by OpenImageIO (nothing but the header);
/// - every header's width and height are held against SSS_LIMIT_IMAGE_SIDE and
///   SSS_LIMIT_IMAGE_PIXELS (LimitError), its channels against
///   kMaxImageChannels and its tiles against kMaxImageTiles (FormatError).
/// Returns the header, or nothing when OpenImageIO cannot read it or `path`
/// is not a regular file (never opened: a FIFO would block); the caller's
/// reader then reports the file in its own words.
std::optional<ImageHeader> check_image_file(const std::string& path);

/// check_image_file()'s PNG part alone, without OpenImageIO: the header of a
/// PNG file checked whole, nothing for another format (or not a regular file).
std::optional<ImageHeader> check_png_file(const std::string& path);

/// check_image_file()'s hold of a header read elsewhere (the texture plugin's
/// OpenImageIO) against the limits: FormatError or LimitError naming `path`.
void check_image_header(const std::string& path, const ImageHeader& header);

} // namespace sss
