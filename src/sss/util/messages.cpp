// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file messages.cpp
/// Quoting input in messages, warnings counted by kind, and the state of
/// standard output.

#include "sss/util/messages.h"

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <mutex>
#include <vector>

namespace sss {

// ---------------------------------------------------------------------------
// Text from inputs in messages

std::string escape_control(std::string_view text) {
    std::string out;
    out.reserve(text.size());
    for (char c : text) {
        const auto u = static_cast<unsigned char>(c);
        if (c == '\n') {
            out += "\\n";
        } else if (u < 0x20 || u == 0x7f) {
            char hex[8];
            std::snprintf(hex, sizeof hex, "\\x%02x", u);
            out += hex;
        } else {
            out += c;
        }
    }
    return out;
}

std::string truncated(std::string_view text, std::size_t max_bytes) {
    if (text.size() <= max_bytes) return std::string(text);
    std::size_t n = max_bytes;
    // Back up to the start of a UTF-8 sequence (not onto a continuation byte).
    while (n > 0 && (static_cast<unsigned char>(text[n]) & 0xc0) == 0x80) --n;
    return std::string(text.substr(0, n)) + "...";
}

std::string quoted(std::string_view text, std::size_t max_bytes) {
    // Appended, not "\"" + ...: GCC 12 warns falsely (-Wrestrict) on that.
    std::string out = "\"";
    out += escape_control(truncated(text, max_bytes));
    out += '"';
    return out;
}

// ---------------------------------------------------------------------------
// Suggestions for misspelled names

std::size_t edit_distance(std::string_view a, std::string_view b) {
    // Three rows of the dynamic programme: the swap looks two rows back.
    std::vector<std::size_t> two(b.size() + 1), one(b.size() + 1), row(b.size() + 1);
    for (std::size_t j = 0; j <= b.size(); ++j) one[j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i) {
        row[0] = i;
        for (std::size_t j = 1; j <= b.size(); ++j) {
            const std::size_t replace = one[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1);
            row[j] = std::min({one[j] + 1, row[j - 1] + 1, replace});
            if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
                row[j] = std::min(row[j], two[j - 2] + 1);
        }
        std::swap(two, one);
        std::swap(one, row);
    }
    return one[b.size()];
}

std::string closest_match(std::string_view word,
                          const std::vector<std::string>& candidates) {
    auto lower = [](std::string_view s) {
        std::string out(s);
        for (char& c : out)
            if (c >= 'A' && c <= 'Z') c = char(c - 'A' + 'a');
        return out;
    };
    const std::string w = lower(word);
    std::string best;
    std::size_t best_distance = SIZE_MAX;
    for (const std::string& c : candidates) {
        const std::size_t d = edit_distance(w, lower(c));
        // Within a third of the longer name: "skin11" -> "skin1", never "x" -> "o".
        if (d * 3 > std::max(w.size(), c.size()) || d >= best_distance) continue;
        best = c;
        best_distance = d;
    }
    return best;
}

// ---------------------------------------------------------------------------
// Warnings

namespace {

bool is_digit(char c) {
    return c >= '0' && c <= '9';
}

} // namespace

std::string_view Warnings::without_location(std::string_view text) {
    // "path:12: ", "path:12:3: " or "path.ext: ": a first word (no spaces)
    // that names a line or looks like a file name, then ": ".
    const std::size_t colon = text.find(": ");
    if (colon == std::string_view::npos || colon == 0) return text;
    const std::string_view head = text.substr(0, colon);
    if (head.find(' ') != std::string_view::npos) return text;
    bool located = false;
    const std::size_t last = head.rfind(':');
    if (last != std::string_view::npos && last + 1 < head.size()) {
        located = true;
        for (std::size_t i = last + 1; i < head.size(); ++i)
            if (!is_digit(head[i])) located = false;
    }
    if (!located && head.find_first_of("./") == std::string_view::npos) return text;
    return text.substr(colon + 2);
}

std::string Warnings::kind_of(std::string_view text) {
    const std::string_view body = without_location(text);
    std::string key;
    key.reserve(body.size());
    char quote = 0;
    for (std::size_t i = 0; i < body.size(); ++i) {
        const char c = body[i];
        if (quote) {
            if (c == quote) {
                key += c;
                quote = 0;
            }
        } else if (c == '"' || c == '\'') {
            key += c;
            quote = c;
        } else if (is_digit(c)) {
            if (key.empty() || key.back() != '#') key += '#';
        } else if (c == '.' && !key.empty() && key.back() == '#' && i + 1 < body.size() &&
                   is_digit(body[i + 1])) {
            // "1.5": one number
        } else {
            key += c;
        }
    }
    return key;
}

std::size_t Warnings::kind_index(std::string_view label) {
    std::string key = kind_of(label);
    auto it = m_kind_index.find(key);
    if (it != m_kind_index.end()) return it->second;
    m_kinds.push_back(Kind{std::string(label), 0, 0});
    m_kind_index.emplace(std::move(key), m_kinds.size() - 1);
    return m_kinds.size() - 1;
}

bool Warnings::add_to(std::size_t index, std::string text) {
    Kind& k = m_kinds[index];
    ++m_total;
    ++k.count;
    if (k.count > kKeptPerKind) {
        ++k.omitted;
        return false;
    }
    m_kept.push_back(std::move(text));
    m_kept_kind.push_back(index);
    return true;
}

bool Warnings::push_back(std::string text) {
    const std::size_t index = kind_index(without_location(text));
    return add_to(index, std::move(text));
}

bool Warnings::add(std::string_view kind, std::string text) {
    return add_to(kind_index(kind), std::move(text));
}

void Warnings::add_omitted(const std::string& label, std::size_t count) {
    if (count == 0) return;
    Kind& k = m_kinds[kind_index(label)];
    k.count += count;
    k.omitted += count;
    m_total += count;
}

void Warnings::append(const Warnings& other) {
    for (std::size_t i = 0; i < other.m_kept.size(); ++i)
        add(other.m_kinds[other.m_kept_kind[i]].label, other.m_kept[i]);
    for (const Kind& k : other.m_kinds) add_omitted(k.label, k.omitted);
}

std::vector<Warnings::Omitted> Warnings::omitted() const {
    std::vector<Omitted> out;
    for (const Kind& k : m_kinds)
        if (k.omitted > 0) out.push_back(Omitted{k.label, k.omitted});
    return out;
}

std::vector<std::string> Warnings::summaries() const {
    std::vector<std::string> out;
    for (const Omitted& o : omitted())
        out.push_back(std::to_string(o.count) +
                      (o.count == 1 ? " more warning like " : " more warnings like ") +
                      quoted(o.label) + " not shown");
    return out;
}

// ---------------------------------------------------------------------------
// Standard output

namespace {

std::mutex g_stdout_mutex;
int g_stdout_errno = 0; // the first failure's errno, 0 if none seen

} // namespace

StandardOutputError::StandardOutputError(const std::string& reason)
    : Error("cannot write to standard output: " + reason) {}

bool flush_standard_output() {
    std::lock_guard<std::mutex> lock(g_stdout_mutex);
    // stdout first: std::cout (synchronised with stdio) has no buffer of its
    // own, and a second flush after a failed one reports nothing.
    errno = 0;
    if (std::fflush(stdout) != 0 && g_stdout_errno == 0)
        g_stdout_errno = errno ? errno : EIO;
    std::cout.flush();
    return !std::ferror(stdout) && std::cout.good();
}

std::string standard_output_error() {
    if (flush_standard_output()) return "";
    std::lock_guard<std::mutex> lock(g_stdout_mutex);
    return g_stdout_errno ? std::strerror(g_stdout_errno) : "write error";
}

void check_standard_output() {
    const std::string reason = standard_output_error();
    if (!reason.empty()) throw StandardOutputError(reason);
}

} // namespace sss
