// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file rib_args.cpp
/// Positional arguments of a RIB statement and the reader's error messages.

#include "rib_args.h"

#include <charconv>
#include <cmath>

#include "sss/scene/rib.h"

namespace sss::rib {

std::string fmt(double v) {
    char buf[64];
    auto r = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, r.ptr);
}

void fail(const Statement& s, const std::string& what) {
    throw RibError(*s.file, s.line, s.name, what);
}

std::string where(const Statement& s) {
    return *s.file + ":" + std::to_string(s.line);
}

void need_args(const Statement& s, std::size_t i, const char* what) {
    if (i >= s.args.size()) fail(s, std::string("missing ") + what);
}

void no_more_args(const Statement& s, std::size_t i) {
    if (i < s.args.size())
        fail(s, "unexpected extra argument (" + std::string(describe(s.args[i])) + ")");
}

std::vector<double> take_numbers(const Statement& s, std::size_t& i, std::size_t n) {
    if (i < s.args.size() && s.args[i].is_array()) {
        const Value& v = s.args[i];
        if (v.string_array)
            fail(s, "expected " + std::to_string(n) + " numbers, got strings");
        if (v.numbers.size() != n)
            fail(s, "expected " + std::to_string(n) + " numbers, got " +
                        std::to_string(v.numbers.size()));
        ++i;
        return v.numbers;
    }
    std::vector<double> out;
    while (out.size() < n && i < s.args.size() && s.args[i].is_number())
        out.push_back(s.args[i++].number);
    if (out.size() != n)
        fail(s, "expected " + std::to_string(n) + " numbers, got " +
                    std::to_string(out.size()));
    return out;
}

double take_number(const Statement& s, std::size_t& i) {
    return take_numbers(s, i, 1)[0];
}

int to_int(const Statement& s, double v, const std::string& what) {
    if (v != std::floor(v) || std::abs(v) > 2147483647.0)
        fail(s, what + " must be an integer, got " + fmt(v));
    return static_cast<int>(v);
}

std::string take_string(const Statement& s, std::size_t& i, const char* what) {
    need_args(s, i, what);
    const Value& v = s.args[i];
    if (v.is_string()) {
        ++i;
        return v.string;
    }
    if (v.is_array() && v.strings.size() == 1) {
        ++i;
        return v.strings[0];
    }
    fail(s, std::string("expected ") + what + " (a string), got " + describe(v));
}

std::vector<int> take_ints(const Statement& s, std::size_t& i, const char* what,
                           int min_value) {
    need_args(s, i, what);
    const Value& v = s.args[i];
    std::vector<double> nums;
    if (v.is_number())
        nums = {v.number};
    else if (v.is_array() && !v.string_array)
        nums = v.numbers;
    else
        fail(s, std::string("expected ") + what + " (an array of integers), got " +
                    describe(v));
    ++i;
    std::vector<int> out;
    out.reserve(nums.size());
    for (double d : nums) {
        int k = to_int(s, d, what);
        if (k < min_value)
            fail(s, std::string(what) + " must be >= " + std::to_string(min_value) +
                        ", got " + std::to_string(k));
        out.push_back(k);
    }
    return out;
}

std::vector<double> take_float_array(const Statement& s, std::size_t& i,
                                     const char* what) {
    need_args(s, i, what);
    const Value& v = s.args[i];
    if (v.is_number()) {
        ++i;
        return {v.number};
    }
    if (!v.is_array() || v.string_array)
        fail(s, std::string("expected ") + what + " (an array of numbers), got " +
                    describe(v));
    ++i;
    return v.numbers;
}

std::vector<std::string> take_string_array(const Statement& s, std::size_t& i,
                                           const char* what) {
    need_args(s, i, what);
    const Value& v = s.args[i];
    if (v.is_string()) {
        ++i;
        return {v.string};
    }
    if (!v.is_array() || (!v.string_array && !v.numbers.empty()))
        fail(s, std::string("expected ") + what + " (an array of strings), got " +
                    describe(v));
    ++i;
    return v.strings;
}

std::string take_handle(const Statement& s, std::size_t& i) {
    need_args(s, i, "handle");
    const Value& v = s.args[i];
    if (v.is_number()) {
        ++i;
        return std::to_string(to_int(s, v.number, "handle"));
    }
    if (v.is_string()) {
        ++i;
        return v.string;
    }
    if (v.is_array() && v.numbers.size() == 1) {
        ++i;
        return std::to_string(to_int(s, v.numbers[0], "handle"));
    }
    if (v.is_array() && v.strings.size() == 1) {
        ++i;
        return v.strings[0];
    }
    fail(s, std::string("expected a handle (integer or string), got ") + describe(v));
}

Matrix4 matrix_from(const std::vector<double>& n) {
    Matrix4 m(1.0);
    for (int k = 0; k < 16; ++k) m[k / 4][k % 4] = n[static_cast<std::size_t>(k)];
    return m;
}

} // namespace sss::rib
