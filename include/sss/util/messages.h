// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file messages.h
/// What the tools say (docs/cli-conventions.md): input echoed in messages
/// quoted, escaped and truncated so that every ERROR and WARNING is one
/// line; warnings counted by kind so that a flood of one kind is kept (and
/// printed) a few times and summarised; and the state of standard output,
/// whose write errors fail a job before it commits its outputs.

#include <cstddef>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "sss/util/error.h"

namespace sss {

// ---------------------------------------------------------------------------
// Text from inputs in messages

/// Longest echo of input text in a message (bytes, before escaping).
constexpr std::size_t kMaxEcho = 200;

/// `text` with control bytes escaped: newline as `\n`, every other byte
/// below 0x20 and 0x7f as `\xNN`. Other bytes (UTF-8 included) are kept.
std::string escape_control(std::string_view text);

/// `text` quoted for a message: `"` + escape_control(first max_bytes bytes)
/// + `..."` when it was longer. Use it for every string a message echoes
/// from an input (names, file names, tokens).
std::string quoted(std::string_view text, std::size_t max_bytes = kMaxEcho);

/// The first max_bytes bytes of `text` (not cutting a UTF-8 sequence) and
/// "..." when it was longer.
std::string truncated(std::string_view text, std::size_t max_bytes);

// ---------------------------------------------------------------------------
// Suggestions for misspelled names

/// Edit distance between a and b: inserting, deleting or replacing a
/// character, or swapping two neighbouring ones, costs 1 each (optimal string
/// alignment; "materail" is 1 from "material").
std::size_t edit_distance(std::string_view a, std::string_view b);

/// The candidate that `word` was most likely meant to be, for a "did you
/// mean" hint; "" when none is close. Case is ignored; a candidate is close
/// when its edit distance to `word` is at most a third of the longer of the
/// two (so one-letter names are never guessed). The first of equally close
/// candidates wins.
std::string closest_match(std::string_view word,
                          const std::vector<std::string>& candidates);

// ---------------------------------------------------------------------------
// Warnings

/// Warnings of one job, counted by kind: the first kKeptPerKind of each kind
/// are kept in order, later ones only counted, so a file that repeats one
/// mistake 100000 times costs a few strings, not 100000. A kind is given
/// (add) or derived from the text (push_back: the text without its leading
/// "file:line: " and with its numbers and quoted parts left out).
///
/// Iterating, size() and operator[] see the kept texts; total() counts all.
class Warnings {
public:
    static constexpr std::size_t kKeptPerKind = 5;

    /// A kind left out beyond kKeptPerKind: its label and how many.
    struct Omitted {
        std::string label;
        std::size_t count = 0;
    };

    /// Adds a warning of the kind derived from its text. Returns whether it
    /// was kept.
    bool push_back(std::string text);
    /// Adds a warning of the given kind ("unknown statement"): the kind is
    /// also the label of its summary.
    bool add(std::string_view kind, std::string text);
    /// Adds every warning of `other` (kept ones as warnings, omitted ones as
    /// counts).
    void append(const Warnings& other);
    /// Counts `count` warnings like `label` that were left out elsewhere.
    void add_omitted(const std::string& label, std::size_t count);

    std::size_t size() const { return m_kept.size(); }
    bool empty() const { return m_kept.empty(); }
    const std::string& operator[](std::size_t i) const { return m_kept[i]; }
    const std::string& front() const { return m_kept.front(); }
    const std::string& back() const { return m_kept.back(); }
    std::vector<std::string>::const_iterator begin() const { return m_kept.begin(); }
    std::vector<std::string>::const_iterator end() const { return m_kept.end(); }
    /// The kept texts.
    const std::vector<std::string>& kept() const { return m_kept; }

    /// Every warning added, kept or not.
    std::size_t total() const { return m_total; }
    /// The kinds with warnings left out, in the order they first appeared.
    std::vector<Omitted> omitted() const;
    /// `N more warnings like "label" not shown` for each omitted kind.
    std::vector<std::string> summaries() const;

    /// The kind of a warning text: without a leading location ("a.rib:12: ",
    /// "a.obj: "), its numbers as '#' and its quoted parts as "".
    static std::string kind_of(std::string_view text);
    /// The text without a leading location: the label of a derived kind.
    static std::string_view without_location(std::string_view text);

private:
    struct Kind {
        std::string label;
        std::size_t count = 0;   ///< added of this kind
        std::size_t omitted = 0; ///< of which not kept (or counted elsewhere)
    };
    /// The index of this label's kind (created on first use), keyed by
    /// kind_of(label).
    std::size_t kind_index(std::string_view label);
    bool add_to(std::size_t kind, std::string text);

    std::vector<std::string> m_kept;
    std::vector<std::size_t> m_kept_kind; ///< index into m_kinds per kept text
    std::vector<Kind> m_kinds;
    std::unordered_map<std::string, std::size_t> m_kind_index;
    std::size_t m_total = 0;
};

// ---------------------------------------------------------------------------
// Standard output

/// Writing to standard output failed (a full disk, /dev/full, a closed pipe):
/// "cannot write to standard output: No space left on device".
class StandardOutputError : public Error {
public:
    explicit StandardOutputError(const std::string& reason);
};

/// Flushes std::cout and stdout. Returns false, and remembers why, when
/// something written to standard output could not be written. Every flush
/// of standard output should go through it (so the reason is known).
bool flush_standard_output();

/// "" while everything written to standard output so far was written;
/// else why not (strerror of the first failure, or "write error"). Flushes.
std::string standard_output_error();

/// Throws StandardOutputError when standard_output_error() is not "".
/// Outputs are committed only after it passed: a job whose report could not
/// be written fails without changing its outputs.
void check_standard_output();

} // namespace sss
