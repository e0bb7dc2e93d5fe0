/// \file rib_params.cpp
/// Parameter declarations: the declaration syntax ("[class] type[[n]] [name]")
/// and the table of predeclared names.

#include "rib_params.h"

#include <charconv>
#include <sstream>
#include <vector>

namespace sss::rib {

std::string parse_decl(std::string_view text, bool with_name, Decl& decl,
                       std::string* name, std::string* type_text) {
    // Brackets become words of their own so "float[2]" and "float [ 2 ]" read alike.
    std::string spaced;
    for (char c : text) {
        if (c == '[' || c == ']') {
            spaced += ' ';
            spaced += c;
            spaced += ' ';
        } else {
            spaced += c;
        }
    }
    std::vector<std::string> words;
    std::istringstream in(spaced);
    for (std::string w; in >> w;) words.push_back(w);
    std::size_t i = 0;
    const std::string bad = "bad declaration \"" + std::string(text) + "\"";
    if (i < words.size()) {
        if (auto c = parse_param_class(words[i])) {
            decl.storage = *c;
            ++i;
        } else {
            decl.storage = ParamClass::Uniform;
        }
    }
    if (i >= words.size()) return bad + ": no type";
    auto t = parse_param_type(words[i]);
    if (!t) return bad + ": unknown type '" + words[i] + "'";
    decl.type = *t;
    std::string type_words = (i > 0 ? words[0] + " " : std::string()) + words[i];
    ++i;
    decl.array_size = 1;
    if (i < words.size() && words[i] == "[") {
        if (i + 2 >= words.size() || words[i + 2] != "]")
            return bad + ": malformed array size";
        const std::string& ns = words[i + 1];
        int n = 0;
        auto r = std::from_chars(ns.data(), ns.data() + ns.size(), n);
        if (r.ec != std::errc() || r.ptr != ns.data() + ns.size() || n < 1)
            return bad + ": array size must be a positive integer";
        decl.array_size = n;
        type_words += "[" + ns + "]";
        i += 3;
    }
    if (with_name) {
        if (i >= words.size()) return bad + ": no name";
        *name = words[i++];
    }
    if (i != words.size()) return bad + ": unexpected '" + words[i] + "'";
    if (type_text) *type_text = type_words;
    return "";
}

std::unordered_map<std::string, Decl> predeclared() {
    std::unordered_map<std::string, Decl> d;
    auto add = [&](const char* names, ParamType type, ParamClass cls, int n = 1) {
        std::istringstream in(names);
        for (std::string w; in >> w;) d[w] = Decl{type, cls, n};
    };
    using T = ParamType;
    using C = ParamClass;
    add("P", T::Point, C::Vertex);
    add("Pw", T::HPoint, C::Vertex);
    add("Pz", T::Float, C::Vertex);
    add("N", T::Normal, C::Varying);
    add("Np", T::Normal, C::Uniform);
    add("Cs Os", T::Color, C::Varying);
    add("s t", T::Float, C::Varying);
    add("st", T::Float, C::Varying, 2);
    add("constantwidth", T::Float, C::Constant);
    // Standard shader, projection and option parameters.
    add("Ka Kd Ks Kr Kt Kdt roughness intensity fov coneangle conedeltaangle "
        "beamdistribution samples radius blur width height amplitude mindistance "
        "maxdistance distance sphere bias dither",
        T::Float, C::Uniform);
    add("lightcolor specularcolor color background", T::Color, C::Uniform);
    add("from to", T::Point, C::Uniform);
    add("shadowname filename displaychannels texturename name shader texture archive "
        "procedural display resource coordinatesystem compression",
        T::String, C::Uniform);
    add("gridsize eyesplits texturememory binary rasterorient camera diffuse specular "
        "transmission photon maxdiffusedepth maxspeculardepth backfacing hidden",
        T::Integer, C::Uniform);
    add("bucketsize origin resolution", T::Integer, C::Uniform, 2);
    add("quantize", T::Float, C::Uniform, 4);
    add("jitter", T::Integer, C::Uniform);
    add("depthfilter", T::String, C::Uniform);
    return d;
}

} // namespace sss::rib
