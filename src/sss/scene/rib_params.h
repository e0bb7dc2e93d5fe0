// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file rib_params.h
/// Parameter declarations of the RIB reader: what a parameter name means
/// (type, storage class, array size), from `Declare`, an inline declaration
/// or the predeclared names.

#include <string>
#include <string_view>
#include <unordered_map>

#include "sss/scene/scene.h"

namespace sss::rib {

/// What a declaration says about a parameter.
struct Decl {
    ParamType type = ParamType::Float;
    ParamClass storage = ParamClass::Uniform;
    int array_size = 1;
};

/// Parses "[class] type[[n]] [name]". Returns an error message or "" on success.
std::string parse_decl(std::string_view text, bool with_name, Decl& decl,
                       std::string* name, std::string* type_text = nullptr);

/// The predeclared names: the RI spec's standard variables and the
/// parameters of the standard shaders and common options.
std::unordered_map<std::string, Decl> predeclared();

} // namespace sss::rib
