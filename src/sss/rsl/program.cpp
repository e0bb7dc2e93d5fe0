// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file program.cpp
/// Types and symbol tables of compiled shaders (program.h). The .slo file
/// format is in slo_io.cpp.

#include "sss/rsl/program.h"

namespace sss {

const char* shading_type_name(ShadingType t) {
    switch (t) {
    case ShadingType::Void:
        return "void";
    case ShadingType::Float:
        return "float";
    case ShadingType::Color:
        return "color";
    case ShadingType::Point:
        return "point";
    case ShadingType::Vector:
        return "vector";
    case ShadingType::Normal:
        return "normal";
    case ShadingType::Matrix:
        return "matrix";
    case ShadingType::String:
        return "string";
    case ShadingType::Shader:
        return "shader";
    }
    return "?";
}

int shading_type_floats(ShadingType t) {
    switch (t) {
    case ShadingType::Void:
        return 0;
    case ShadingType::Float:
    case ShadingType::String:
    case ShadingType::Shader:
        return 1;
    case ShadingType::Matrix:
        return 16;
    default:
        return 3;
    }
}

bool is_point_like(ShadingType t) {
    return t == ShadingType::Point || t == ShadingType::Vector ||
           t == ShadingType::Normal;
}

bool is_triple(ShadingType t) {
    return t == ShadingType::Color || is_point_like(t);
}

std::string type_spec_name(const TypeSpec& t) {
    std::string s = shading_type_name(t.type);
    if (t.array > 0) s += "[" + std::to_string(t.array) + "]";
    if (t.array < 0) s += "[]";
    return s;
}

const char* shader_kind_name(ShaderKind k) {
    switch (k) {
    case ShaderKind::Surface:
        return "surface";
    case ShaderKind::Displacement:
        return "displacement";
    case ShaderKind::Light:
        return "light";
    case ShaderKind::Volume:
        return "volume";
    case ShaderKind::Imager:
        return "imager";
    case ShaderKind::Shader:
        return "shader";
    }
    return "?";
}

bool Program::runs_as(ShaderKind k) const {
    return k == kind || pipeline(k) != nullptr;
}

const Pipeline* Program::pipeline(ShaderKind k) const {
    for (const Pipeline& p : pipelines)
        if (p.kind == k) return &p;
    return nullptr;
}

int Program::find_method(const std::string& n) const {
    for (std::size_t i = 0; i < methods.size(); ++i)
        if (methods[i].name == n) return static_cast<int>(i);
    return -1;
}

int Program::find(const std::string& n) const {
    for (std::size_t i = 0; i < symbols.size(); ++i)
        if (symbols[i].name == n) return static_cast<int>(i);
    return -1;
}

std::vector<int> Program::parameters() const {
    std::vector<int> out;
    for (std::size_t i = 0; i < symbols.size(); ++i)
        if (symbols[i].kind == SymbolKind::Param ||
            symbols[i].kind == SymbolKind::OutputParam)
            out.push_back(static_cast<int>(i));
    return out;
}

} // namespace sss
