// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file parse.cpp
/// Number parsing and formatting.

#include "sss/util/parse.h"

#include <charconv>
#include <cmath>
#include <sstream>

namespace sss {

std::optional<double> parse_finite(std::string_view s) {
    if (!s.empty() && s[0] == '+') {
        s.remove_prefix(1);
        if (!s.empty() && (s[0] == '-' || s[0] == '+')) return std::nullopt;
    }
    if (s.empty()) return std::nullopt;
    double v = 0.0;
    auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec != std::errc() || end != s.data() + s.size() || !std::isfinite(v))
        return std::nullopt;
    return v;
}

std::string format_number(double v) {
    std::ostringstream out;
    out << v;
    return out.str();
}

std::string join(const std::vector<std::string>& words, const std::string& sep) {
    std::string out;
    for (const std::string& w : words) {
        if (!out.empty()) out += sep;
        out += w;
    }
    return out;
}

std::vector<std::string> split_words(std::string_view text) {
    std::vector<std::string> out;
    std::string cur;
    for (char c : text) {
        if (c == ',' || c == ' ' || c == '\t') {
            if (!cur.empty()) out.push_back(cur);
            cur.clear();
        } else {
            cur += c;
        }
    }
    if (!cur.empty()) out.push_back(cur);
    return out;
}

} // namespace sss
