/// \file make_texture.cpp
/// TextureLibrary::make_texture: RenderMan's texture-making requests through
/// the OpenImageIO plugin, written atomically and skipped when up to date.

#include <filesystem>

#include "sss/binding/texture_library.h"
#include "sss/util/atomic_output.h"
#include "sss/util/error.h"
#include "texture2d_backend.h"
#include "texture_library_impl.h"

namespace sss {

namespace {

std::string wrap_mode(const std::string& w, const std::string& where) {
    if (w == "periodic" || w == "clamp" || w == "black" || w == "mirror") return w;
    throw ValueError(where + ": unknown wrap mode \"" + w +
                     "\" (periodic, clamp, black or mirror)");
}

} // namespace

bool TextureLibrary::make_texture(const Make& m, const std::string& where) {
    namespace fs = std::filesystem;
    std::error_code ec_in, ec_out;
    const auto in_time = fs::last_write_time(m.input, ec_in);
    if (ec_in) throw IoError(m.input, "cannot read the picture (" + where + ")");
    const auto out_time = fs::last_write_time(m.output, ec_out);
    if (!ec_out && out_time > in_time) return false;
    const std::string wraps = wrap_mode(m.swrap, where) + "," + wrap_mode(m.twrap, where);
    const std::string filter = m.filter == "catmullrom" ? "catmull-rom"
                               : m.filter == "b-spline" ? "bspline"
                                                        : m.filter;
    std::string error;
    detail::Texture2dBackend* maker = m_impl->textures(&error);
    if (!maker) throw IoError(m.output, where + ": " + error);
    AtomicOutput out(m.output);
    if (!maker->make_texture(m.input, out.temp_path(), m.latlong, wraps, filter, &error))
        throw IoError(m.output, "cannot make the texture of \"" + m.input + "\" (" +
                                    where + "): " + error);
    out.commit();
    invalidate(m.output);
    return true;
}

} // namespace sss
