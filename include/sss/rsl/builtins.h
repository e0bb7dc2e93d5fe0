// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
// Internal to the shading module: the built-in functions of RSL, each
// overload as a prototype string. The compiler resolves calls against this
// table; the engine binds every op of a Program to an implementation of one
// of these overloads and refuses a program that uses anything else.
//
// Prototype strings (in the manner of Pixie's sdrc tables):
//   "<result>=<arguments>"
//   type letters: f float, c color, p point, v vector, n normal, m matrix,
//                 s string, o void (result only);
//                 x any of point/vector/normal (all x of one prototype are
//                 then the same type, and a result x is that type too);
//                 . any type.
//   an upper-case letter: the argument is written (an output argument);
//   a letter followed by '*': zero or more further arguments of that type;
//   "[f]": an array of that type (any length);
//   '!' at the end: a token-value list follows ("name", value pairs, values
//   read); '@' at the end: a token-value list whose values may be written
//   (texture3d: the channels looked up).

#include <span>
#include <string_view>

#include "sss/rsl/program.h"

namespace sss::detail {

struct BuiltinSignature {
    const char* name;
    const char* proto;
    /// The result is varying whatever the arguments (random, Du, lighting,
    /// texture lookups...).
    bool always_varying = false;
    /// The function differentiates its arguments over the batch (Du, Dv,
    /// Deriv, area, calculatenormal, filterstep, texture with implicit
    /// filter widths): its arguments must be computed on every point.
    bool derivatives = false;
};

/// Every overload of every built-in function, grouped by name.
std::span<const BuiltinSignature> builtin_signatures();

/// Whether `name` is a built-in function.
bool is_builtin(std::string_view name);

/// The type a prototype's type letter names (lower case; 'x' stands for `x`):
/// Void for 'o', '.' and anything else.
ShadingType letter_type(char c, ShadingType x);

} // namespace sss::detail
