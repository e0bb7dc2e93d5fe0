// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file args.cpp
/// ArgScanner: options with a fixed number of values, positional words.

#include "sss/cli/args.h"

#include <cctype>
#include <charconv>
#include <cmath>
#include <optional>
#include <string_view>
#include <unordered_set>

#include "sss/util/error.h"
#include "sss/util/messages.h"
#include "sss/util/parse.h"

namespace sss {

namespace {

bool looks_like_option(const std::string& word) {
    if (word.size() < 2 || word[0] != '-') return false;
    char c = word[1];
    return !(std::isdigit(static_cast<unsigned char>(c)) || c == '.');
}

} // namespace

ArgScanner::ArgScanner(std::vector<std::string> args) : m_args(std::move(args)) {}

bool ArgScanner::at_option() const {
    return !done() && looks_like_option(m_args[m_pos]);
}

std::string ArgScanner::option() {
    if (done()) throw UsageError("missing option");
    const std::string& word = m_args[m_pos];
    if (!looks_like_option(word))
        throw UsageError("expected an option, got '" + word + "'");
    ++m_pos;
    std::size_t dashes = (word.size() > 1 && word[1] == '-') ? 2 : 1;
    return word.substr(dashes);
}

std::string ArgScanner::positional() {
    if (done()) throw UsageError("missing argument");
    return m_args[m_pos++];
}

bool ArgScanner::next_option(std::string& opt, std::vector<std::string>& positionals) {
    while (!done()) {
        if (at_option()) {
            opt = option();
            return true;
        }
        positionals.push_back(positional());
    }
    return false;
}

std::string ArgScanner::value(const std::string& opt) {
    if (done() || at_option()) throw UsageError("option -" + opt + " needs a value");
    return m_args[m_pos++];
}

double ArgScanner::number(const std::string& opt) {
    std::string word = value(opt);
    std::optional<double> v = parse_finite(word);
    if (!v) throw UsageError("option -" + opt + ": '" + word + "' is not a number");
    return *v;
}

double ArgScanner::positive(const std::string& opt) {
    double v = number(opt);
    if (!(v > 0.0))
        throw UsageError("option -" + opt + ": must be > 0 (got " + format_number(v) +
                         ")");
    return v;
}

double ArgScanner::non_negative(const std::string& opt) {
    double v = number(opt);
    if (!(v >= 0.0))
        throw UsageError("option -" + opt + ": must be >= 0 (got " + format_number(v) +
                         ")");
    return v;
}

int ArgScanner::integer(const std::string& opt, int lo, int hi) {
    std::string word = value(opt);
    std::string_view s = word;
    if (!s.empty() && s[0] == '+') s.remove_prefix(1);
    long long v = 0;
    auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    bool ok = !s.empty() && ec == std::errc() && end == s.data() + s.size();
    if (!ok) {
        // Accept integral values written as numbers ("1e6", "3.0").
        std::optional<double> d = parse_finite(word);
        if (!d || std::floor(*d) != *d || std::fabs(*d) > 9.0e18)
            throw UsageError("option -" + opt + ": '" + word + "' is not an integer");
        v = static_cast<long long>(*d);
    }
    if (v < lo || v > hi)
        throw UsageError("option -" + opt + ": " + std::to_string(v) +
                         " is out of range [" + std::to_string(lo) + ", " +
                         std::to_string(hi) + "]");
    return static_cast<int>(v);
}

glm::dvec3 ArgScanner::triple(const std::string& opt) {
    glm::dvec3 out(0.0);
    for (int i = 0; i < 3; ++i) {
        if (done() || at_option()) throw UsageError("option -" + opt + " needs 3 values");
        out[i] = number(opt);
    }
    return out;
}

const std::string& ArgScanner::peek() const {
    static const std::string empty;
    return done() ? empty : m_args[m_pos];
}

std::vector<std::string> usage_options(const std::string& usage) {
    std::vector<std::string> options;
    std::unordered_set<std::string> seen;
    auto is_name = [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
    };
    for (std::size_t i = 0; i < usage.size(); ++i) {
        if (usage[i] != '-') continue;
        const char before = i == 0 ? '\n' : usage[i - 1];
        if (std::string_view(" \n([,").find(before) == std::string_view::npos) continue;
        const std::size_t dashes = i + 1 < usage.size() && usage[i + 1] == '-' ? 2 : 1;
        const std::size_t start = i + dashes;
        if (start >= usage.size() ||
            !std::isalpha(static_cast<unsigned char>(usage[start])))
            continue;
        std::size_t end = start;
        while (end < usage.size() &&
               (is_name(usage[end]) ||
                (usage[end] == '-' && end + 1 < usage.size() && is_name(usage[end + 1]))))
            ++end;
        std::string option = usage.substr(i, end - i);
        if (seen.insert(option).second) options.push_back(std::move(option));
        i = end - 1;
    }
    return options;
}

UsageError unknown_option(const std::string& opt, const std::string& usage) {
    // Compared without dashes: "--materail" is as close to "-material".
    std::vector<std::string> names;
    const std::vector<std::string> options = usage_options(usage);
    for (const std::string& o : options)
        names.push_back(o.substr(o.find_first_not_of('-')));
    const std::string guess = closest_match(opt, names);
    std::string what = "unknown option -" + opt;
    // A listed option refused where it stands gets no hint of itself.
    for (std::size_t i = 0; i < names.size() && !guess.empty() && guess != opt; ++i)
        if (names[i] == guess) {
            what += "; did you mean " + options[i] + "?";
            break;
        }
    return UsageError(what);
}

std::string shell_quote(const std::string& word) {
    bool plain = !word.empty();
    for (unsigned char c : word)
        if (!(std::isalnum(c) ||
              std::string_view("_./,:=+@%-#").find(char(c)) != std::string_view::npos))
            plain = false;
    if (plain) return word;
    // Single quotes keep everything; a quote itself becomes '\''.
    std::string q = "'";
    for (char c : word) q += (c == '\'') ? std::string("'\\''") : std::string(1, c);
    q += '\'';
    return q;
}

std::string quoted_command_line(const std::string& head,
                                const std::vector<std::string>& args) {
    std::string line = head;
    for (const std::string& a : args) {
        line += ' ';
        line += shell_quote(a);
    }
    return line;
}

std::vector<std::string> split_channel_list(const std::string& list,
                                            const std::string& opt) {
    std::vector<std::string> names;
    std::unordered_set<std::string> seen;
    std::size_t start = 0;
    while (true) {
        std::size_t comma = list.find(',', start);
        std::string name = list.substr(
            start, comma == std::string::npos ? std::string::npos : comma - start);
        if (name.empty())
            throw UsageError("option -" + opt + ": empty channel name in '" + list + "'");
        if (!seen.insert(name).second)
            throw UsageError("option -" + opt + ": channel '" + name + "' named twice");
        names.push_back(name);
        if (comma == std::string::npos) break;
        start = comma + 1;
    }
    return names;
}

int attached_integer(const std::string& opt, std::size_t prefix, int lo, int hi) {
    const std::string text = opt.size() > prefix ? opt.substr(prefix) : std::string();
    std::size_t used = 0;
    long value = 0;
    bool ok = !text.empty() && (std::isdigit(static_cast<unsigned char>(text[0])) ||
                                text[0] == '-' || text[0] == '+');
    if (ok) {
        try {
            value = std::stol(text, &used);
        } catch (const std::exception&) {
            ok = false;
        }
    }
    if (!ok || used != text.size())
        throw UsageError("option -" + opt + ": '" + text + "' is not an integer");
    if (value < lo || value > hi)
        throw UsageError("option -" + opt + ": " + text + " is not in [" +
                         std::to_string(lo) + ", " + std::to_string(hi) + "]");
    return static_cast<int>(value);
}

} // namespace sss
