// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file json.cpp
/// JSON string quoting.

#include "sss/util/json.h"

#include <cstdio>

namespace sss {

std::string json_quote(std::string_view text) {
    std::string out;
    out.reserve(text.size() + 2);
    out += '"';
    for (const char ch : text) {
        const unsigned char c = static_cast<unsigned char>(ch);
        if (c == '"' || c == '\\') {
            out += '\\';
            out += ch;
        } else if (c < 0x20) {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\u%04x", c);
            out += buf;
        } else {
            out += ch;
        }
    }
    out += '"';
    return out;
}

} // namespace sss
