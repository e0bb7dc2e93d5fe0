// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file image_check_oiio.cpp
/// check_image_file(): the PNG check, else the header OpenImageIO reads, held
/// against the limits. In a file of its own: only the tools that call it
/// load OpenImageIO for it.

#include <OpenImageIO/imageio.h>

#include <filesystem>
#include <memory>

#include "sss/image/image_check.h"

namespace sss {

std::optional<ImageHeader> check_image_file(const std::string& path) {
    // A FIFO or device would block or never end: the caller's reader refuses it.
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) return std::nullopt;
    if (std::optional<ImageHeader> png = check_png_file(path)) return png;
    // Only the header: OpenImageIO's readers allocate nothing more on open.
    std::unique_ptr<OIIO::ImageInput> in = OIIO::ImageInput::open(path);
    if (!in) {
        (void)OIIO::geterror(); // the caller's reader says why
        return std::nullopt;
    }
    const OIIO::ImageSpec& spec = in->spec();
    ImageHeader h;
    h.width = spec.width;
    h.height = spec.height;
    h.channels = spec.nchannels;
    h.tile_width = spec.tile_width;
    h.tile_height = spec.tile_height;
    in->close();
    check_image_header(path, h);
    return h;
}

} // namespace sss
