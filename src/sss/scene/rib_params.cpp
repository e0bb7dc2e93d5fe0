// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file rib_params.cpp
/// Parameter declarations: the declaration syntax ("[class] type[[n]] [name]")
/// and the table of predeclared names, and the parameter lists of
/// statements read against them.

#include "rib_params.h"

#include <charconv>
#include <sstream>
#include <vector>

#include "rib_args.h"
#include "rib_reader.h"
#include "sss/util/messages.h"

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
    const std::string bad = "bad declaration " + sss::quoted(text);
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
    if (!t) return bad + ": unknown type '" + truncated(words[i], kMaxEcho) + "'";
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
    if (i != words.size())
        return bad + ": unexpected '" + truncated(words[i], kMaxEcho) + "'";
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
        "maxdistance distance sphere bias bias0 bias1 dither",
        T::Float, C::Uniform);
    add("lightcolor specularcolor color background zthreshold", T::Color, C::Uniform);
    add("from to", T::Point, C::Uniform);
    add("shadowname filename displaychannels texturename name shader texture archive "
        "sense "
        "procedural display resource coordinatesystem compression",
        T::String, C::Uniform);
    add("gridsize eyesplits texturememory binary rasterorient camera diffuse specular "
        "transmission photon maxdiffusedepth maxspeculardepth backfacing hidden "
        "maxdepth trace",
        T::Integer, C::Uniform);
    add("transmissionhitmode diffusehitmode specularhitmode", T::String, C::Uniform);
    add("bucketsize origin resolution", T::Integer, C::Uniform, 2);
    add("quantize", T::Float, C::Uniform, 4);
    add("jitter", T::Integer, C::Uniform);
    add("depthfilter", T::String, C::Uniform);
    return d;
}

namespace {

/// The strings of a string parameter: a whole number of its array size (with
/// `single`, exactly one element).
void read_strings(const Statement& s, const Value& value, const std::string& label,
                  bool single, Param& p) {
    if (value.is_string())
        p.strings = {value.string};
    else if (value.is_array() && (value.string_array || value.numbers.empty()))
        p.strings = value.strings;
    else
        fail(s, label + " (string) expects strings, got " + describe(value));
    if (p.strings.empty() || p.strings.size() % static_cast<std::size_t>(p.array_size))
        fail(s, label + ": " + std::to_string(p.strings.size()) +
                    " strings is not a whole number of string[" +
                    std::to_string(p.array_size) + "] values");
    if (single && p.strings.size() != static_cast<std::size_t>(p.array_size))
        fail(s, label + ": expected " + std::to_string(p.array_size) +
                    " string(s), got " + std::to_string(p.strings.size()));
}

/// The numbers of a numeric parameter: a whole number of elements (with
/// `single`, exactly one), whole numbers for an integer parameter.
void read_numbers(const Statement& s, const Value& value, const std::string& label,
                  bool single, Param& p) {
    if (value.is_number())
        p.numbers = {value.number};
    else if (value.is_array() && !value.string_array)
        p.numbers = value.numbers;
    else
        fail(s, label + " (" + param_type_name(p.type) + ") expects numbers, got " +
                    describe(value));
    const std::size_t es = static_cast<std::size_t>(p.element_size());
    if (p.numbers.empty() || p.numbers.size() % es)
        fail(s,
             label + ": " + std::to_string(p.numbers.size()) +
                 " numbers is not a whole number of " + param_type_name(p.type) +
                 // std::string("["): GCC 12 -O3 warns falsely (-Wrestrict) on "[" + ...
                 (p.array_size > 1 ? std::string("[") + std::to_string(p.array_size) + "]"
                                   : std::string()) +
                 " values (" + std::to_string(es) + " numbers each)");
    if (single && p.numbers.size() != es)
        fail(s, label + ": expected " + std::to_string(es) + " numbers, got " +
                    std::to_string(p.numbers.size()));
    if (p.type == ParamType::Integer)
        for (double d : p.numbers) to_int(s, d, label);
}

} // namespace

ParamList Reader::take_params(const Statement& s, std::size_t i, bool single,
                              bool shader) {
    ParamList list;
    while (i < s.args.size()) {
        const Value& key = s.args[i];
        std::string spelled;
        if (key.is_string())
            spelled = key.string;
        else if (key.is_array() && key.strings.size() == 1)
            spelled = key.strings[0];
        else
            fail(s, std::string("expected a parameter name, got ") + describe(key));
        if (i + 1 >= s.args.size())
            fail(s, "parameter " + sss::quoted(spelled) + " has no value");
        const Value& value = s.args[i + 1];
        i += 2;

        Param p;
        Decl decl;
        if (spelled.find_first_of(" \t\n") != std::string::npos) {
            std::string err = parse_decl(spelled, true, decl, &p.name);
            if (!err.empty()) fail(s, err);
        } else {
            auto it = m_decls.find(spelled);
            if (it == m_decls.end() && shader) {
                // Typed later by the shader's own declaration (binding).
                p.name = spelled;
                p.declared = false;
                const bool strings =
                    value.is_string() || (value.is_array() && value.string_array);
                p.type = strings ? ParamType::String : ParamType::Float;
                const std::string label = "parameter " + sss::quoted(p.name);
                if (strings)
                    read_strings(s, value, label, false, p);
                else
                    read_numbers(s, value, label, false, p);
                list.set(std::move(p));
                continue;
            }
            if (it == m_decls.end()) {
                if (m_warned.insert("undeclared " + spelled).second)
                    warn(s, s.name + ": undeclared parameter " + sss::quoted(spelled) +
                                ", skipped");
                continue;
            }
            p.name = spelled;
            decl = it->second;
        }
        p.type = decl.type;
        p.storage = decl.storage;
        p.array_size = decl.array_size;
        const std::string label = "parameter " + sss::quoted(p.name);

        if (p.type == ParamType::String)
            read_strings(s, value, label, single, p);
        else
            read_numbers(s, value, label, single, p);
        list.set(std::move(p));
    }
    return list;
}

} // namespace sss::rib
