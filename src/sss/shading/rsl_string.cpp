/// \file rsl_string.cpp
/// RSL's format()/printf() patterns and match() (rsl_math.h).

#include <regex.h>

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

/// A compiled regular expression, freed with it.
struct Regex {
    regex_t re{};
    bool ok = false;
    explicit Regex(const std::string& pattern) {
        ok = regcomp(&re, pattern.c_str(), REG_EXTENDED | REG_NOSUB) == 0;
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
    if (!re->ok) return false;
    // regexec reads a NUL-terminated string (an embedded NUL ends the subject).
    const std::string s(subject);
    return regexec(&re->re, s.c_str(), 0, nullptr, 0) == 0;
}

} // namespace sss::detail
