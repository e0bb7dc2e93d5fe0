// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file make_texture.cpp
/// TextureLibrary::make_texture, make_shadow and make_cube_environment:
/// RenderMan's texture-making requests through the OpenImageIO plugin,
/// written atomically and skipped when up to date.

#include <filesystem>
#include <vector>

#include "sss/binding/texture_library.h"
#include "sss/util/atomic_output.h"
#include "sss/util/error.h"
#include "texture2d_backend.h"
#include "texture_library_impl.h"

namespace sss {

namespace {

namespace fs = std::filesystem;

/// Whether `output` exists and is newer than every input (then it is kept,
/// as farm frames keep what an earlier frame made). IoError when an input
/// is missing.
bool up_to_date(const std::vector<std::string>& inputs, const std::string& output,
                const char* what, const std::string& where) {
    std::error_code ec;
    const auto out_time = fs::last_write_time(output, ec);
    bool newer = !ec;
    for (const std::string& input : inputs) {
        std::error_code ec_in;
        const auto in_time = fs::last_write_time(input, ec_in);
        if (ec_in)
            throw IoError(input,
                          std::string("cannot read the ") + what + " (" + where + ")");
        newer = newer && out_time > in_time;
    }
    return newer;
}

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

bool TextureLibrary::make_shadow(const std::string& input, const std::string& output,
                                 const std::string& where) {
    if (up_to_date({input}, output, "zfile", where)) return false;
    std::string error;
    detail::Texture2dBackend* maker = m_impl->textures(&error);
    if (!maker) throw IoError(output, where + ": " + error);
    AtomicOutput out(output);
    if (!maker->make_shadow(input, out.temp_path(), &error))
        throw IoError(output, "cannot make the shadow map of \"" + input + "\" (" +
                                  where + "): " + error);
    out.commit();
    invalidate(output);
    return true;
}

bool TextureLibrary::make_cube_environment(const std::array<std::string, 6>& faces,
                                           const std::string& output, double fov,
                                           const std::string& filter,
                                           const std::string& where) {
    if (up_to_date({faces.begin(), faces.end()}, output, "picture", where)) return false;
    const std::string name = filter == "catmullrom" ? "catmull-rom"
                             : filter == "b-spline" ? "bspline"
                                                    : filter;
    std::string error;
    detail::Texture2dBackend* maker = m_impl->textures(&error);
    if (!maker) throw IoError(output, where + ": " + error);
    AtomicOutput out(output);
    if (!maker->make_cube_environment(faces, out.temp_path(), fov, name, &error))
        throw IoError(output,
                      "cannot make the cube-face environment (" + where + "): " + error);
    out.commit();
    invalidate(output);
    return true;
}

} // namespace sss
