// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file name_table.h
/// Enum <-> name tables: one list of (value, name) pairs gives both the name
/// of a value (for messages and files) and the value of a name (for parsing),
/// instead of a switch and a chain of string compares written by hand.

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <utility>

namespace sss {

/// A fixed table of (enum value, name) pairs. The first pair of a value gives
/// its name; parse() also accepts later aliases of the same value.
template <class E, std::size_t N>
class NameTable {
public:
    using Entry = std::pair<E, const char*>;

    constexpr explicit NameTable(std::array<Entry, N> entries, const char* unknown = "?")
        : m_entries(entries), m_unknown(unknown) {}

    /// The name of v (the first entry with it), or the table's "unknown" text.
    constexpr const char* name(E v) const {
        for (const Entry& e : m_entries) {
            if (e.first == v) return e.second;
        }
        return m_unknown;
    }

    /// The value named s (exact match), or nullopt.
    constexpr std::optional<E> parse(std::string_view s) const {
        for (const Entry& e : m_entries) {
            if (s == e.second) return e.first;
        }
        return std::nullopt;
    }

    /// The names, comma separated ("a, b, c"), for messages listing choices.
    std::string list() const {
        std::string out;
        for (const Entry& e : m_entries) {
            if (!out.empty()) out += ", ";
            out += e.second;
        }
        return out;
    }

private:
    std::array<Entry, N> m_entries;
    const char* m_unknown;
};

} // namespace sss
