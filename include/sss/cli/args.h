// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file args.h
/// RenderMan-style command-line scanning for the tools' mains.

#include <cstddef>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "sss/util/error.h"

namespace sss {

/// Walks a command line the RenderMan way: options start with one or two
/// dashes and take a fixed number of values; other words are positional.
/// Every malformed use throws UsageError naming the option.
class ArgScanner {
public:
    explicit ArgScanner(std::vector<std::string> args);

    bool done() const { return m_pos >= m_args.size(); }
    /// True if the next word is an option ("-x", "--x"; a negative number is not).
    bool at_option() const;
    /// Consumes the next word as an option and returns its name without dashes.
    std::string option();
    /// Consumes the next word as a positional argument.
    std::string positional();
    /// Moves to the next option, appending the positional words before it to
    /// `positionals`; stores its name (option()) in `opt`. False at the end.
    /// The usual loop: `while (args.next_option(o, files)) { ... }`.
    bool next_option(std::string& opt, std::vector<std::string>& positionals);

    /// Consumes the value of option opt; UsageError if missing or if it looks
    /// like another option.
    std::string value(const std::string& opt);
    /// A finite number.
    double number(const std::string& opt);
    /// A finite number > 0.
    double positive(const std::string& opt);
    /// A finite number >= 0.
    double non_negative(const std::string& opt);
    /// An integer in [lo, hi].
    int integer(const std::string& opt, int lo, int hi);
    /// Three finite numbers (r g b).
    glm::dvec3 triple(const std::string& opt);
    /// Peeks the next word without consuming it ("" when done).
    const std::string& peek() const;

private:
    std::vector<std::string> m_args;
    std::size_t m_pos = 0;
};

/// The options a tool's usage text lists, in order, each once, with its
/// dashes as written ("-material", "--help"): every word of one or two
/// dashes and a letter that starts a line or follows a space, '(', '[' or
/// ',', up to the first character that is not a letter, digit, '_' or a
/// dash between them ("-p:N" lists "-p", "--dry-run" itself).
std::vector<std::string> usage_options(const std::string& usage);

/// The error for an option `opt` (without its dashes) that a tool does not
/// know: "unknown option -materail; did you mean -material?" when one of the
/// options its usage text lists is close (closest_match in
/// sss/util/messages.h), else "unknown option -opt".
UsageError unknown_option(const std::string& opt, const std::string& usage);

/// A word as a POSIX shell reads it back: unchanged when it is made of
/// letters, digits and _./,:=+@%-#, else in single quotes (a quote itself
/// becomes '\'').
std::string shell_quote(const std::string& word);

/// head followed by every argument, shell-quoted: a command line that can be
/// re-run (image metadata, the provenance stored in brick maps).
std::string quoted_command_line(const std::string& head,
                                const std::vector<std::string>& args);

/// The integer written after the first `prefix` characters of an option's
/// name ("p:4" with prefix 2 -> 4), which must lie in [lo, hi]; UsageError
/// naming the option otherwise.
int attached_integer(const std::string& opt, std::size_t prefix, int lo, int hi);

/// Splits a comma-separated channel list ("_ssdiffusion,_radiance_t").
/// UsageError naming opt for an empty list, an empty name or a repeated name.
std::vector<std::string> split_channel_list(const std::string& list,
                                            const std::string& opt);

} // namespace sss
