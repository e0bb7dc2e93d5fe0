#pragma once
/// \file parse.h
/// Number parsing and formatting shared by the readers and the command line.

#include <optional>
#include <string>
#include <string_view>

namespace sss {

/// Whole-string parse of a finite double; a leading '+' is accepted. nullopt
/// for anything else (empty, trailing characters, inf, nan, out of range).
std::optional<double> parse_finite(std::string_view s);

/// A number as a person reads it in a message (iostream default format).
std::string format_number(double v);

} // namespace sss
