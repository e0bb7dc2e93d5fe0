// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#include "sss/util/frame_pattern.h"

#include <algorithm>
#include <cctype>
#include <cstdio>

#include "sss/util/error.h"

namespace sss {
namespace {

// The widest pattern expanded; a wider one (%017d, $F17, 17 #s) is kept as
// written. sss-farm applies the same bound.
constexpr int kMaxWidth = 16;

std::string padded(int frame, int width) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%0*d", width, frame);
    return buf;
}

// One pattern occurrence found at some position.
struct Match {
    std::size_t length = 0;
    int width = 0;
    bool lone_hash = false;
    bool literal = false; // too wide: copied as written
};

// Digits of a width from s[j]; stops counting past kMaxWidth (no overflow).
int read_width(const std::string& s, std::size_t& j) {
    int width = 0;
    while (j < s.size() && std::isdigit(static_cast<unsigned char>(s[j]))) {
        if (width <= kMaxWidth) width = width * 10 + (s[j] - '0');
        ++j;
    }
    return width;
}

// Recognises a pattern starting at s[i]; length 0 if none.
Match match_at(const std::string& s, std::size_t i) {
    Match m;
    const std::size_t n = s.size();
    if (s[i] == '#') {
        std::size_t j = i;
        while (j < n && s[j] == '#') ++j;
        m.length = j - i;
        m.width = static_cast<int>(std::min<std::size_t>(m.length, kMaxWidth + 1));
        m.lone_hash = m.length == 1;
        m.literal = m.width > kMaxWidth;
        return m;
    }
    if (s[i] == '%') {
        std::size_t j = i + 1;
        if (j < n && s[j] == '%') return m; // "%%" is a literal percent
        bool zero = false;
        if (j < n && s[j] == '0') {
            zero = true;
            ++j;
        }
        const int width = read_width(s, j);
        if (j < n && s[j] == 'd' && (zero || width == 0) && width <= kMaxWidth) {
            m.length = j + 1 - i;
            m.width = width;
        }
        return m;
    }
    if (s[i] == '$') {
        std::size_t j = i + 1;
        bool brace = j < n && s[j] == '{';
        if (brace) ++j;
        if (j >= n || s[j] != 'F') return m;
        ++j;
        if (j < n && s[j] == 'F') return m; // $FF (float frame) is not supported
        const int width = read_width(s, j);
        if (brace) {
            if (j >= n || s[j] != '}') return m;
            ++j;
        }
        if (width > kMaxWidth) return m;
        m.length = j - i;
        m.width = width;
        return m;
    }
    return m;
}

} // namespace

bool has_frame_pattern(const std::string& path) {
    for (std::size_t i = 0; i < path.size(); ++i) {
        if (path[i] == '%' && i + 1 < path.size() && path[i + 1] == '%') {
            ++i; // literal percent
            continue;
        }
        const Match m = match_at(path, i);
        if (m.length > 0 && !m.literal) return true;
        i += m.length > 0 ? m.length - 1 : 0;
    }
    return false;
}

std::string expand_frame_pattern(const std::string& path, std::optional<int> frame,
                                 const std::string& what) {
    std::string out;
    out.reserve(path.size() + 8);
    for (std::size_t i = 0; i < path.size();) {
        Match m = match_at(path, i);
        if (m.literal) {
            out.append(path, i, m.length);
            i += m.length;
            continue;
        }
        if (m.length == 0) {
            out += path[i];
            // Keep "%%" as a literal percent sign.
            if (path[i] == '%' && i + 1 < path.size() && path[i + 1] == '%') {
                ++i;
            }
            ++i;
            continue;
        }
        if (m.lone_hash)
            throw UsageError(what + ": '" + path +
                             "' has a lone '#' (one or four digits depending on the "
                             "tool); write #### or %04d");
        if (!frame)
            throw MissingFrameError(what + ": '" + path + "' has a frame pattern");
        out += padded(*frame, m.width);
        i += m.length;
    }
    return out;
}

} // namespace sss
