#include "sss/util/frame_pattern.h"

#include <cctype>
#include <cstdio>

#include "sss/util/error.h"

namespace sss {
namespace {

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
};

// Recognises a pattern starting at s[i]; length 0 if none.
Match match_at(const std::string& s, std::size_t i) {
    Match m;
    const std::size_t n = s.size();
    if (s[i] == '#') {
        std::size_t j = i;
        while (j < n && s[j] == '#') ++j;
        m.length = j - i;
        m.width = static_cast<int>(m.length);
        m.lone_hash = m.length == 1;
        return m;
    }
    if (s[i] == '%') {
        std::size_t j = i + 1;
        if (j < n && s[j] == '%') return m; // "%%" is a literal percent
        int width = 0;
        bool zero = false;
        if (j < n && s[j] == '0') {
            zero = true;
            ++j;
        }
        while (j < n && std::isdigit(static_cast<unsigned char>(s[j])))
            width = width * 10 + (s[j++] - '0');
        if (j < n && s[j] == 'd' && (zero || width == 0) && width <= 16) {
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
        int width = 0;
        while (j < n && std::isdigit(static_cast<unsigned char>(s[j])))
            width = width * 10 + (s[j++] - '0');
        if (brace) {
            if (j >= n || s[j] != '}') return m;
            ++j;
        }
        if (width > 16) return m;
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
        if (match_at(path, i).length > 0) return true;
    }
    return false;
}

std::string expand_frame_pattern(const std::string& path, std::optional<int> frame,
                                 const std::string& what) {
    std::string out;
    out.reserve(path.size() + 8);
    for (std::size_t i = 0; i < path.size();) {
        Match m = match_at(path, i);
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
