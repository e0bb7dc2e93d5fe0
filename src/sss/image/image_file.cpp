/// \file image_file.cpp
/// write_image_file(): the one OpenImageIO writer of the library.

#include "sss/image/image_file.h"

#include <cmath>
#include <memory>

#include <OpenImageIO/imageio.h>

#include "sss/util/atomic_output.h"
#include "sss/util/error.h"

namespace sss {

namespace {

OIIO::TypeDesc type_of(PixelType t) {
    switch (t) {
    case PixelType::UInt8:
        return OIIO::TypeDesc::UINT8;
    case PixelType::UInt16:
        return OIIO::TypeDesc::UINT16;
    case PixelType::Half:
        return OIIO::TypeDesc::HALF;
    case PixelType::Float:
        break;
    }
    return OIIO::TypeDesc::FLOAT;
}

struct AddAttribute {
    OIIO::ImageSpec& spec;
    const std::string& name;
    void operator()(const std::string& v) const { spec.attribute(name, v); }
    void operator()(int v) const { spec.attribute(name, v); }
    void operator()(float v) const { spec.attribute(name, v); }
    void operator()(const std::array<float, 16>& v) const {
        spec.attribute(name, OIIO::TypeMatrix44, v.data());
    }
};

} // namespace

void write_image_file(const std::string& path, const ImageFileSpec& spec, PixelType data,
                      const void* pixels) {
    std::unique_ptr<OIIO::ImageOutput> out = OIIO::ImageOutput::create(spec.format);
    if (!out)
        throw IoError(path, "no '" + spec.format +
                                "' writer in OpenImageIO: " + OIIO::geterror());
    OIIO::ImageSpec oiio(spec.width, spec.height, int(spec.channel_names.size()),
                         type_of(spec.stored));
    oiio.channelnames = spec.channel_names;
    oiio.alpha_channel = spec.alpha_channel;
    oiio.z_channel = spec.z_channel;
    if (!spec.channel_stored.empty())
        for (PixelType t : spec.channel_stored) oiio.channelformats.push_back(type_of(t));
    for (const ImageAttribute& a : spec.attributes)
        std::visit(AddAttribute{oiio, a.name}, a.value);
    AtomicOutput file(path);
    // The temporary is ".<name>.<random>.tmp": the writer is chosen by format
    // name above, so the extension does not matter.
    if (!out->open(file.temp_path(), oiio))
        throw IoError(path, "cannot write " + spec.what + ": " + out->geterror());
    bool ok = out->write_image(type_of(data), pixels);
    ok = out->close() && ok;
    if (!ok) throw IoError(path, "cannot write " + spec.what + ": " + out->geterror());
    file.commit();
}

double srgb_encode(double c) {
    return c <= 0.0031308 ? 12.92 * c : 1.055 * std::pow(c, 1.0 / 2.4) - 0.055;
}

} // namespace sss
