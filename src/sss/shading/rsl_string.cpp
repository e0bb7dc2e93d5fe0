// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file rsl_string.cpp
/// RSL's format()/printf() patterns and match() (rsl_math.h).

#include <regex.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <memory>
#include <mutex>
#include <shared_mutex>
#include <unordered_map>

#include "rsl_math.h"
#include "sss/util/error.h"

namespace sss::detail {

namespace {

/// One conversion of a pattern: flags, width and precision as written.
struct Spec {
    std::string flags;
    std::string width;
    std::string precision; ///< with its '.', or empty
    char conversion = 0;
};

/// printf of one number with the spec's flags/width/precision and `conv`.
std::string format_number(const Spec& spec, char conv, double value) {
    const std::string fmt = "%" + spec.flags + spec.width + spec.precision + conv;
    char buf[512];
    int n = std::snprintf(buf, sizeof buf, fmt.c_str(), value);
    if (n < static_cast<int>(sizeof buf)) return std::string(buf, n > 0 ? n : 0);
    // Huge widths or values (1e300 with %f): size exactly.
    std::string big(static_cast<size_t>(n) + 1, '\0');
    std::snprintf(big.data(), big.size(), fmt.c_str(), value);
    big.resize(static_cast<size_t>(n));
    return big;
}

/// %d: the float rounded toward zero, as an integer (NaN as 0, saturated).
std::string format_integer(const Spec& spec, float value) {
    const std::string fmt = "%" + spec.flags + spec.width + spec.precision + "lld";
    long long i = 0;
    if (std::isfinite(value))
        i = std::fabs(value) < 9.0e18f ? static_cast<long long>(value)
                                       : (value < 0 ? INT64_MIN : INT64_MAX);
    const int n = std::snprintf(nullptr, 0, fmt.c_str(), i);
    std::string s(static_cast<size_t>(n > 0 ? n : 0) + 1, '\0');
    std::snprintf(s.data(), s.size(), fmt.c_str(), i);
    s.resize(s.size() - 1);
    return s;
}

/// `count` numbers, each formatted with the spec as %f, separated by spaces.
std::string format_components(const Spec& spec, const float* v, int count) {
    std::string s;
    for (int i = 0; i < count; ++i) {
        if (i) s += ' ';
        s += format_number(spec, 'f', v[i]);
    }
    return s;
}

/// Widths and precisions beyond this are refused: they would only make huge
/// strings per point.
constexpr size_t kMaxDigits = 4;

[[noreturn]] void fail(std::string_view pattern, const std::string& message) {
    throw ValueError("format \"" + std::string(pattern) + "\": " + message);
}

bool type_fits(char conversion, ShadingType t) {
    switch (conversion) {
    case 'f':
    case 'e':
    case 'E':
    case 'g':
    case 'G':
    case 'd':
    case 'i':
        return t == ShadingType::Float;
    case 's':
        return t == ShadingType::String;
    case 'c':
        return t == ShadingType::Color;
    case 'p':
        return is_point_like(t);
    case 'm':
        return t == ShadingType::Matrix;
    }
    return false;
}

const char* expected_type(char conversion) {
    switch (conversion) {
    case 's':
        return "a string";
    case 'c':
        return "a color";
    case 'p':
        return "a point, vector or normal";
    case 'm':
        return "a matrix";
    }
    return "a float";
}

/// The size of a POSIX extended regular expression once glibc has
/// multiplied out its repetitions (an upper bound: a{2,5} is five copies of
/// a, a+ two), or an error for what is refused before regcomp. Syntax errors
/// are left to regcomp.
class RegexSize {
public:
    explicit RegexSize(std::string_view p) : m_p(p) {}

    /// The size; `error` set when the pattern is refused.
    uint64_t measure(std::string& error) {
        uint64_t size = alternation(0);
        while (m_i < m_p.size() && m_error.empty()) { // a stray ')' and on
            ++m_i;
            size = add(size, alternation(0));
        }
        error = m_error;
        return size;
    }

private:
    static uint64_t add(uint64_t a, uint64_t b) {
        return std::min<uint64_t>(a + b, uint64_t(1) << 60);
    }
    static uint64_t times(uint64_t a, uint64_t b) {
        return b != 0 && a > (uint64_t(1) << 60) / b ? uint64_t(1) << 60 : a * b;
    }

    uint64_t alternation(int depth) {
        uint64_t size = sequence(depth);
        while (m_error.empty() && m_i < m_p.size() && m_p[m_i] == '|') {
            ++m_i;
            size = add(size, sequence(depth) + 1);
        }
        return size;
    }

    uint64_t sequence(int depth) {
        uint64_t size = 0;
        while (m_error.empty() && m_i < m_p.size() && m_p[m_i] != '|' && m_p[m_i] != ')')
            size = add(size, repeated(atom(depth)));
        return size;
    }

    uint64_t atom(int depth) {
        const char c = m_p[m_i++];
        if (c == '(') {
            if (depth + 1 > kMaxRegexNesting) {
                m_error =
                    "groups nest more than " + std::to_string(kMaxRegexNesting) + " deep";
                return 1;
            }
            const uint64_t inner = alternation(depth + 1);
            if (m_i < m_p.size() && m_p[m_i] == ')') ++m_i;
            return add(inner, 1);
        }
        if (c == '[') {
            // A bracket expression: one element, whatever it lists.
            if (m_i < m_p.size() && m_p[m_i] == '^') ++m_i;
            if (m_i < m_p.size() && m_p[m_i] == ']') ++m_i;
            while (m_i < m_p.size() && m_p[m_i] != ']') {
                if (m_p[m_i] == '[' && m_i + 1 < m_p.size() &&
                    (m_p[m_i + 1] == ':' || m_p[m_i + 1] == '=' || m_p[m_i + 1] == '.')) {
                    const char close[] = {m_p[m_i + 1], ']', 0};
                    const std::size_t end = m_p.find(close, m_i + 2);
                    m_i = end == std::string_view::npos ? m_p.size() : end + 2;
                } else {
                    ++m_i;
                }
            }
            if (m_i < m_p.size()) ++m_i;
            return 1;
        }
        if (c == '\\' && m_i < m_p.size()) {
            const char e = m_p[m_i++];
            if (e >= '1' && e <= '9')
                m_error = std::string("back-references (\\") + e +
                          ") are not supported: they match in exponential time";
        }
        return 1;
    }

    /// `size` under the repetitions that follow it.
    uint64_t repeated(uint64_t size) {
        while (m_error.empty() && m_i < m_p.size()) {
            const char c = m_p[m_i];
            if (c == '*' || c == '?') {
                size = add(size, 1);
            } else if (c == '+') {
                size = add(times(size, 2), 1);
            } else if (c == '{') {
                std::size_t j = m_i + 1;
                uint64_t low = 0, high = 0;
                bool has_low = false, has_comma = false, has_high = false;
                while (j < m_p.size() &&
                       std::isdigit(static_cast<unsigned char>(m_p[j]))) {
                    low =
                        std::min<uint64_t>(low * 10 + uint64_t(m_p[j++] - '0'), 1u << 30);
                    has_low = true;
                }
                if (j < m_p.size() && m_p[j] == ',') {
                    has_comma = true;
                    ++j;
                    while (j < m_p.size() &&
                           std::isdigit(static_cast<unsigned char>(m_p[j]))) {
                        high = std::min<uint64_t>(high * 10 + uint64_t(m_p[j++] - '0'),
                                                  1u << 30);
                        has_high = true;
                    }
                }
                if (j >= m_p.size() || m_p[j] != '}' || (!has_low && !has_high))
                    return size; // not an interval: regcomp decides
                m_i = j;
                // glibc copies the element for each repetition: {n} n times,
                // {n,} n + 1 (the last starred), {n,m} m.
                const uint64_t copies =
                    !has_comma ? low : (has_high ? std::max(low, high) : low + 1);
                size = add(times(size, std::max<uint64_t>(copies, 1)), 1);
            } else {
                return size;
            }
            ++m_i;
        }
        return size;
    }

    std::string_view m_p;
    std::size_t m_i = 0;
    std::string m_error;
};

/// A compiled regular expression, freed with it; `error` says why a
/// pattern was refused or did not compile.
struct Regex {
    regex_t re{};
    bool ok = false;
    uint64_t size = 0;
    std::string error;
    explicit Regex(const std::string& pattern) {
        if (pattern.size() > kMaxRegexLength) {
            error = "a pattern of " + std::to_string(pattern.size()) +
                    " bytes is longer than the bound of " +
                    std::to_string(kMaxRegexLength);
            return;
        }
        size = RegexSize(pattern).measure(error);
        if (!error.empty()) return;
        if (size > kMaxRegexSize) {
            error = "the pattern has " + std::to_string(size) +
                    " elements once its repetitions are multiplied out, more than "
                    "the bound of " +
                    std::to_string(kMaxRegexSize);
            return;
        }
        const int code = regcomp(&re, pattern.c_str(), REG_EXTENDED | REG_NOSUB);
        ok = code == 0;
        if (!ok) {
            char text[256];
            regerror(code, &re, text, sizeof text);
            error = std::string("invalid regular expression: ") + text;
        }
    }
    ~Regex() {
        if (ok) regfree(&re);
    }
    Regex(const Regex&) = delete;
    Regex& operator=(const Regex&) = delete;
};

/// Patterns compiled so far. Shaders use a handful of constant patterns;
/// the cap only guards against a shader building patterns per point.
struct RegexCache {
    std::shared_mutex mutex;
    std::unordered_map<std::string, std::shared_ptr<const Regex>> map;
    static constexpr size_t kCapacity = 256;

    std::shared_ptr<const Regex> get(std::string_view pattern) {
        const std::string key(pattern);
        {
            std::shared_lock lock(mutex);
            if (auto it = map.find(key); it != map.end()) return it->second;
        }
        // Compile outside the lock; a race compiles twice, harmlessly.
        auto compiled = std::make_shared<const Regex>(key);
        std::unique_lock lock(mutex);
        if (map.size() >= kCapacity) map.clear(); // users hold shared_ptrs
        return map.emplace(key, std::move(compiled)).first->second;
    }
};

RegexCache& regex_cache() {
    static RegexCache cache;
    return cache;
}

} // namespace

std::string rsl_format(std::string_view pattern, std::span<const RslFormatArg> args) {
    std::string out;
    size_t next_arg = 0;
    for (size_t i = 0; i < pattern.size(); ++i) {
        const char ch = pattern[i];
        if (ch != '%') {
            out += ch;
            continue;
        }
        const size_t start = i++;
        if (i < pattern.size() && pattern[i] == '%') {
            out += '%';
            continue;
        }
        Spec spec;
        while (i < pattern.size() &&
               std::string_view("-+ 0#").find(pattern[i]) != std::string_view::npos)
            spec.flags += pattern[i++];
        while (i < pattern.size() && std::isdigit(static_cast<unsigned char>(pattern[i])))
            spec.width += pattern[i++];
        if (i < pattern.size() && pattern[i] == '.') {
            spec.precision += pattern[i++];
            while (i < pattern.size() &&
                   std::isdigit(static_cast<unsigned char>(pattern[i])))
                spec.precision += pattern[i++];
        }
        const std::string written(pattern.substr(start, i + 1 - start));
        if (i >= pattern.size()) fail(pattern, "incomplete conversion at the end");
        if (spec.width.size() > kMaxDigits || spec.precision.size() > kMaxDigits + 1)
            fail(pattern, "width or precision too large in '" + written + "'");
        spec.conversion = pattern[i];
        if (std::string_view("feEgGdiscpm").find(spec.conversion) ==
            std::string_view::npos)
            fail(pattern, "unknown conversion '" + written + "'");
        if (next_arg >= args.size())
            fail(pattern, "too few arguments: '" + written + "' has no argument " +
                              std::to_string(next_arg + 1));
        const RslFormatArg& arg = args[next_arg++];
        if (!type_fits(spec.conversion, arg.type))
            fail(pattern, "'" + written + "' needs " + expected_type(spec.conversion) +
                              ", argument " + std::to_string(next_arg) + " is a " +
                              shading_type_name(arg.type));
        if (arg.type == ShadingType::String ? !arg.string : !arg.numbers)
            fail(pattern, "argument " + std::to_string(next_arg) + " has no value");
        switch (spec.conversion) {
        case 'd':
        case 'i':
            out += format_integer(spec, arg.numbers[0]);
            break;
        case 's': {
            const std::string fmt = "%" + spec.flags + spec.width + spec.precision + "s";
            const int n = std::snprintf(nullptr, 0, fmt.c_str(), arg.string->c_str());
            std::string s(static_cast<size_t>(n > 0 ? n : 0) + 1, '\0');
            std::snprintf(s.data(), s.size(), fmt.c_str(), arg.string->c_str());
            s.resize(s.size() - 1);
            out += s;
            break;
        }
        case 'c':
        case 'p':
            out += format_components(spec, arg.numbers, 3);
            break;
        case 'm':
            out += format_components(spec, arg.numbers, 16);
            break;
        default:
            out += format_number(spec, spec.conversion, arg.numbers[0]);
        }
    }
    if (next_arg < args.size())
        fail(pattern, "too many arguments: " + std::to_string(args.size()) + " given, " +
                          std::to_string(next_arg) + " used");
    return out;
}

bool rsl_match(std::string_view pattern, std::string_view subject) {
    const auto re = regex_cache().get(pattern);
    const auto refuse = [&](const std::string& why) -> bool {
        std::string shown(pattern.substr(0, 200));
        if (pattern.size() > 200) shown += "...";
        throw ValueError("match(\"" + shown + "\"): " + why);
    };
    if (!re->ok) return refuse(re->error);
    // regexec's time grows with the pattern's size times the subject's.
    if (std::max<uint64_t>(re->size, 1) * subject.size() > kMaxRegexWork)
        return refuse("a subject of " + std::to_string(subject.size()) +
                      " bytes is too long for a pattern of " + std::to_string(re->size) +
                      " elements (their product is bounded by " +
                      std::to_string(kMaxRegexWork) + ")");
    // regexec reads a NUL-terminated string (an embedded NUL ends the subject).
    const std::string s(subject);
    return regexec(&re->re, s.c_str(), 0, nullptr, 0) == 0;
}

} // namespace sss::detail
