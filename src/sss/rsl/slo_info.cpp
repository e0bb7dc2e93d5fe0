// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#include "sss/rsl/slo_info.h"

#include <charconv>
#include <sstream>

#include "sss/util/json.h"

namespace sss {

namespace {

std::string number(float v) {
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, r.ptr);
}

// A default the compiler could not fold into constants runs as ops when the
// shader starts.
bool computed(const Symbol& s) {
    return s.init_begin >= 0 && s.init_end > s.init_begin;
}

std::string kind_line(const Symbol& s) {
    std::string t =
        s.kind == SymbolKind::OutputParam ? "output parameter " : "parameter ";
    t += s.varying ? "varying " : "uniform ";
    t += shading_type_name(s.type.type);
    if (s.type.is_array()) {
        // (Appended piece by piece: GCC 12 warns about "[" + string.)
        t += '[';
        t += std::to_string(s.type.array);
        t += ']';
    }
    return t;
}

// One element's default in PRMan's layout.
std::string element(const Symbol& s, int i) {
    if (s.type.type == ShadingType::String)
        return json_quote(std::size_t(i) < s.strings.size() ? s.strings[std::size_t(i)]
                                                            : "");
    const int nf = shading_type_floats(s.type.type);
    std::string v;
    for (int k = 0; k < nf; ++k) {
        const std::size_t at = std::size_t(i * nf + k);
        if (k) v += ' ';
        v += number(at < s.numbers.size() ? s.numbers[at] : 0.0f);
    }
    switch (s.type.type) {
    case ShadingType::Float:
        return v;
    case ShadingType::Color:
        return "\"rgb\" [" + v + "]";
    default:
        return "\"current\" [" + v + "]";
    }
}

std::string default_text(const Symbol& s) {
    if (computed(s)) return "<computed when the shader runs>";
    if (!s.type.is_array()) return element(s, 0);
    std::string v = "{";
    for (int i = 0; i < s.type.array; ++i) v += (i ? ", " : "") + element(s, i);
    return v + "}";
}

} // namespace

std::string describe_shader(const Program& p) {
    std::ostringstream out;
    out << shader_kind_name(p.kind) << " " << json_quote(p.name) << "\n";
    for (const int k : p.parameters()) {
        const Symbol& s = p.symbols[std::size_t(k)];
        out << "    " << json_quote(s.name) << " \"" << kind_line(s) << "\"\n";
        out << "\t\tDefault value: " << default_text(s) << "\n";
    }
    return out.str();
}

std::string describe_shader_json(const Program& p, const std::string& file) {
    std::ostringstream out;
    out << "{\"file\": " << json_quote(file)
        << ", \"type\": " << json_quote(shader_kind_name(p.kind))
        << ", \"name\": " << json_quote(p.name) << ", \"parameters\": [";
    bool first = true;
    for (const int k : p.parameters()) {
        const Symbol& s = p.symbols[std::size_t(k)];
        out << (first ? "" : ", ") << "{\"name\": " << json_quote(s.name)
            << ", \"storage\": \"" << (s.varying ? "varying" : "uniform") << "\""
            << ", \"type\": " << json_quote(shading_type_name(s.type.type))
            << ", \"array\": " << s.type.array
            << ", \"output\": " << (s.kind == SymbolKind::OutputParam ? "true" : "false")
            << ", \"default\": ";
        first = false;
        if (computed(s)) {
            out << "null}";
            continue;
        }
        out << "[";
        if (s.type.type == ShadingType::String) {
            for (std::size_t i = 0; i < s.strings.size(); ++i)
                out << (i ? ", " : "") << json_quote(s.strings[i]);
        } else {
            for (std::size_t i = 0; i < s.numbers.size(); ++i)
                out << (i ? ", " : "") << number(s.numbers[i]);
        }
        out << "]}";
    }
    out << "]";
    if (p.is_class()) {
        // RSL 2.0 classes: the public methods other shaders may call.
        out << ", \"methods\": [";
        for (std::size_t i = 0; i < p.methods.size(); ++i)
            out << (i ? ", " : "") << json_quote(p.methods[i].name);
        out << "]";
    }
    out << "}";
    return out.str();
}

} // namespace sss
