// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
// Internal to the shading module: source positions in preprocessed text and
// the collector of compiler messages (compiler.h's Diagnostic).

#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "sss/rsl/compiler.h"
#include "sss/rsl/preprocess.h"
#include "sss/rsl/program.h"

namespace sss::detail {

/// A position in the preprocessed text: 0-based output line, 1-based column.
struct SrcLoc {
    int line = 0;
    int col = 1;
};

/// Thrown to stop compiling early (too many errors, a too deep nesting).
struct CompileAbort {};

/// Collects warnings and errors, mapping positions through the
/// preprocessor's line table to file:line:column with the source line.
class DiagnosticSink {
public:
    explicit DiagnosticSink(const PreprocessResult& source);

    void error(SrcLoc at, const std::string& message);
    void warning(SrcLoc at, const std::string& message);
    int error_count() const { return m_errors; }
    const std::vector<Diagnostic>& all() const { return m_all; }
    std::vector<Diagnostic> warnings() const;
    /// The op location of `at` (file index into the source's files).
    SourceLocation where(SrcLoc at) const;
    const PreprocessResult& source() const { return m_source; }
    /// Adds another sink's messages (a code generation pass's).
    void absorb(const DiagnosticSink& other);

    /// More errors than this stop the compile.
    static constexpr int kMaxErrors = 100;

private:
    void add(Diagnostic::Severity severity, SrcLoc at, const std::string& message);
    bool push(Diagnostic d);
    std::string line_text(int line) const;

    const PreprocessResult& m_source;
    std::vector<std::size_t> m_line_starts;
    std::vector<Diagnostic> m_all;
    // Inlined functions report the same error at each call: keep one.
    std::set<std::tuple<std::string, int, int, std::string>> m_seen;
    int m_errors = 0;
};

} // namespace sss::detail
