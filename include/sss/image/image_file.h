// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file image_file.h
/// Module image: writing image files through OpenImageIO, for every module
/// that makes pictures (brick's brickinfo pictures, view's ptview pictures,
/// render's displays), and the sRGB transfer curve they share.
/// May use: util (OpenImageIO and zlib privately).
///
/// One writer: the file is written to a temporary beside the target and
/// renamed when complete (AtomicOutput), the OpenImageIO writer is chosen by
/// format name (the temporary's name does not end in the format's
/// extension), and every failure is an IoError naming the file. The writer
/// writes through a checked file (OpenImageIO's I/O proxy), never through its
/// own FILE: a write that fails part way (a full disk, a quota, an I/O error)
/// is reported after close() and the temporary removed, whatever the format
/// (libjpeg, which calls exit() on a failed write, never sees one), and the
/// temporary's size is checked against what the writer wrote before it is
/// renamed.

#include <array>
#include <string>
#include <variant>
#include <vector>

namespace sss {

/// The type of a pixel value, in memory or in the file.
enum class PixelType { UInt8, UInt16, Half, Float };

/// A metadata attribute of an image file, written in the order given.
struct ImageAttribute {
    std::string name;
    /// A 4x4 matrix is 16 floats, row by row (EXR's row-vector convention).
    std::variant<std::string, int, float, std::array<float, 16>> value;
};

/// What write_image_file() writes.
struct ImageFileSpec {
    std::string format = "png"; ///< OpenImageIO's writer: "png", "openexr", "tiff"
    int width = 0;
    int height = 0;
    std::vector<std::string> channel_names; ///< one per channel
    PixelType stored = PixelType::UInt8;    ///< the file's pixel type
    /// Per channel (EXR half and float channels mixed); empty: all `stored`.
    std::vector<PixelType> channel_stored;
    int alpha_channel = -1; ///< index in channel_names, or -1
    int z_channel = -1;     ///< index in channel_names, or -1
    std::vector<ImageAttribute> attributes;
    /// A short name of what is written, for error messages ("PNG", "image").
    std::string what = "image";
};

/// Writes `pixels` (width x height x channels values of type `data`,
/// interleaved, rows top to bottom) to `path` as `spec` says, atomically.
/// Throws IoError (no writer for the format, a JPEG image wider or higher
/// than 65500 pixels, or the write failed: "cannot write PNG: No space left
/// on device").
void write_image_file(const std::string& path, const ImageFileSpec& spec, PixelType data,
                      const void* pixels);

} // namespace sss
