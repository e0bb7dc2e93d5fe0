// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file preprocess.h
/// The C preprocessor subset RSL shaders rely on (PRMan's `shader` runs cpp
/// first): `#include "f"` / `<f>` (the including file's folder, then the -I
/// folders in order), `#define` with and without arguments (`#`, `##`),
/// `#undef`, `#if` / `#elif` with `defined` and integer arithmetic,
/// `#ifdef`, `#ifndef`, `#else`, `#endif`, `#line`, `#pragma` (ignored),
/// `#error`; `/* */` and `//` comments; line splices. Predefined: `PI` is not
/// a macro (the language has it), `__SSS__` and `RSL` are defined as 1;
/// `__LINE__` and `__FILE__` work as in C, and so do variadic macros
/// (`...`, `__VA_ARGS__`). Macros are not expanded inside string literals.
///
/// The output has one line per logical source line, followed by an empty
/// line for each further physical line it spanned (multi-line comments,
/// splices, macro arguments over several lines), so compiler messages keep
/// their line numbers; a comment within one line becomes as many spaces, so
/// columns after it stay right too. Directives and skipped lines become
/// empty lines; an `#include` becomes the included file's lines.
///
/// Hostile input is bounded: includes nest at most 64 deep (a cycle is
/// reported as such), the output stops at 10 million characters, a run at a
/// million macro expansions, macro arguments and `#if` expressions nest at
/// most 200 deep; each is a PreprocessError.

#include <string>
#include <utility>
#include <vector>

#include "sss/util/error.h"

namespace sss {

/// Where a character of the preprocessed text came from.
struct PreprocessedLine {
    int file = 0; ///< index into PreprocessResult::files
    int line = 0; ///< 1-based line in that file
};

struct PreprocessOptions {
    std::vector<std::string> include_dirs; ///< -I, in order
    std::vector<std::pair<std::string, std::string>>
        defines;                        ///< -D name=value ("1" if none)
    std::vector<std::string> undefines; ///< -U name
};

struct PreprocessResult {
    /// The text after preprocessing, comments replaced by spaces, one output
    /// line per entry of `lines`.
    std::string text;
    std::vector<PreprocessedLine> lines;
    std::vector<std::string> files; ///< files read, the main one first
};

/// A preprocessing error. what() is "file:line:column: message"; the source
/// line is kept apart.
class PreprocessError : public ValueError {
public:
    PreprocessError(std::string file, int line, int column, const std::string& message,
                    const std::string& source_line);
    const std::string& file() const { return m_file; }
    int line() const { return m_line; }
    int column() const { return m_column; }
    /// The text of the line the error points into (after `#line`, still the
    /// physical line that was read).
    const std::string& source_line() const { return m_source_line; }

private:
    std::string m_file;
    int m_line = 0;
    int m_column = 0;
    std::string m_source_line;
};

/// Preprocesses the file at `path`.
PreprocessResult preprocess_file(const std::string& path,
                                 const PreprocessOptions& options);
/// Preprocesses `text` as if read from a file named `name` (includes are
/// searched from the current folder and the -I folders).
PreprocessResult preprocess_text(const std::string& text, const std::string& name,
                                 const PreprocessOptions& options);

} // namespace sss
