// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file parse.h
/// Number parsing and text formatting shared by the readers and the command line.

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace sss {

/// Whole-string parse of a finite double; a leading '+' is accepted. nullopt
/// for anything else (empty, trailing characters, inf, nan, out of range).
std::optional<double> parse_finite(std::string_view s);

/// The words separated by sep ("a, b, c" with the default), for messages.
std::string join(const std::vector<std::string>& words, const std::string& sep = ", ");

/// The words of a list separated by commas, spaces or tabs ("_area, _radiance_t"),
/// empty words dropped.
std::vector<std::string> split_words(std::string_view text);

/// A number as a person reads it in a message (iostream default format).
std::string format_number(double v);

} // namespace sss
