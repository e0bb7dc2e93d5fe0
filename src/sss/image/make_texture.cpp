/// \file make_texture.cpp
/// make_texture(): OpenImageIO's ImageBufAlgo::make_texture with RenderMan's
/// wrap modes and filter names, written through an atomic output.

#include "sss/image/make_texture.h"

#include <filesystem>
#include <sstream>

#include <OpenImageIO/filter.h>
#include <OpenImageIO/imagebufalgo.h>

#include "sss/util/atomic_output.h"
#include "sss/util/error.h"

namespace sss {

namespace {

std::string wrap_mode(const std::string& w, const std::string& where) {
    if (w == "periodic" || w == "clamp" || w == "black" || w == "mirror") return w;
    throw ValueError(where + ": unknown wrap mode \"" + w +
                     "\" (periodic, clamp, black or mirror)");
}

/// RenderMan's filter names in OpenImageIO's spelling.
std::string filter_name(const std::string& f, const std::string& where) {
    const std::string name = f == "catmullrom" ? "catmull-rom"
                             : f == "b-spline" ? "bspline"
                                               : f;
    for (int i = 0, n = OIIO::Filter2D::num_filters(); i < n; ++i) {
        OIIO::FilterDesc d;
        OIIO::Filter2D::get_filterdesc(i, &d);
        if (name == d.name) return name;
    }
    throw ValueError(where + ": unknown filter \"" + f + "\"");
}

} // namespace

bool make_texture(const TextureMake& m, const std::string& where) {
    namespace fs = std::filesystem;
    std::error_code ec_in, ec_out;
    const auto in_time = fs::last_write_time(m.input, ec_in);
    if (ec_in) throw IoError(m.input, "cannot read the picture (" + where + ")");
    const auto out_time = fs::last_write_time(m.output, ec_out);
    if (!ec_out && out_time > in_time) return false;

    OIIO::ImageSpec config;
    config.attribute("wrapmodes",
                     wrap_mode(m.swrap, where) + "," + wrap_mode(m.twrap, where));
    config.attribute("maketx:filtername", filter_name(m.filter, where));
    config.attribute("maketx:fileformatname", "tiff");
    AtomicOutput out(m.output);
    std::ostringstream log;
    const auto mode = m.kind == TextureMake::Kind::LatLongEnvironment
                          ? OIIO::ImageBufAlgo::MakeTxEnvLatl
                          : OIIO::ImageBufAlgo::MakeTxTexture;
    if (!OIIO::ImageBufAlgo::make_texture(mode, m.input, out.temp_path(), config, &log)) {
        std::string why = OIIO::geterror();
        if (why.empty()) why = log.str();
        throw IoError(m.output, "cannot make the texture from \"" + m.input + "\" (" +
                                    where + "): " + why);
    }
    out.commit();
    return true;
}

} // namespace sss
