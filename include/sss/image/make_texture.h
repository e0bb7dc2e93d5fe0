#pragma once
/// \file make_texture.h
/// RenderMan's texture-making requests (MakeTexture, MakeLatLongEnvironment)
/// through OpenImageIO's texture maker: tiled, MIP-mapped files that
/// texture() and environment() read.

#include <string>

namespace sss {

/// One texture to make.
struct TextureMake {
    enum class Kind { Texture, LatLongEnvironment };
    Kind kind = Kind::Texture;
    std::string input;  ///< the picture (any format OpenImageIO reads)
    std::string output; ///< the texture file written (atomically)
    std::string swrap = "black", twrap = "black"; ///< periodic, clamp, black
    std::string filter = "box";                   ///< the resampling filter
};

/// Makes the texture; IoError / ValueError naming `where` (the RIB
/// statement) when the picture cannot be read, a wrap mode or filter is
/// unknown, or the texture cannot be written. Returns false (nothing done)
/// when the output is already newer than the input.
bool make_texture(const TextureMake& m, const std::string& where);

} // namespace sss
