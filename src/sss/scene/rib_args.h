// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file rib_args.h
/// Positional arguments of a RIB statement: numbers, strings, integer and
/// string arrays and handles taken one by one from argument `i` on, with the
/// statement's own error messages.

#include <cstddef>
#include <string>
#include <vector>

#include "rib_lexer.h"
#include "sss/scene/scene.h"

namespace sss::rib {

/// Throws the RibError "file:line: Statement: what".
[[noreturn]] void fail(const Statement& s, const std::string& what);

/// "file.rib:12" of a statement.
std::string where(const Statement& s);

/// Shortest text of a number, for messages.
std::string fmt(double v);

/// Fails with "missing <what>" when there is no argument i.
void need_args(const Statement& s, std::size_t i, const char* what);

/// Fails when there are arguments from i on.
void no_more_args(const Statement& s, std::size_t i);

/// `n` positional numbers, given one by one or as one array.
std::vector<double> take_numbers(const Statement& s, std::size_t& i, std::size_t n);

/// One number.
double take_number(const Statement& s, std::size_t& i);

/// `v` as an int; fails unless it is a whole number in range.
int to_int(const Statement& s, double v, const std::string& what);

/// A string, or an array of exactly one string.
std::string take_string(const Statement& s, std::size_t& i, const char* what);

/// An array of integers >= `min_value` (a single number is accepted too).
std::vector<int> take_ints(const Statement& s, std::size_t& i, const char* what,
                           int min_value);

/// An array of numbers (a single number is accepted too).
std::vector<double> take_float_array(const Statement& s, std::size_t& i,
                                     const char* what);

/// An array of strings (a single string or an empty array is accepted too).
std::vector<std::string> take_string_array(const Statement& s, std::size_t& i,
                                           const char* what);

/// A light or object handle: an integer or a string.
std::string take_handle(const Statement& s, std::size_t& i);

/// 16 numbers as a matrix, loaded the way scene.h documents.
Matrix4 matrix_from(const std::vector<double>& n);

} // namespace sss::rib
