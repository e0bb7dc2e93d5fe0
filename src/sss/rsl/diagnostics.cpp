// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file diagnostics.cpp
/// Compiler messages: Diagnostic::format, ShaderCompileError and the
/// collector that maps preprocessed positions back to the source files.

#include "diagnostics.h"

#include "sss/util/messages.h"

namespace sss {

std::string Diagnostic::format() const {
    // Control bytes from the source are escaped (an editor or a log reads one
    // message per line); tabs stay in the echoed line so the caret lines up.
    std::string out = escape_control(file) + ":" + std::to_string(line) + ":" +
                      std::to_string(column) + ": " +
                      (severity == Severity::Error ? "error" : "warning") + ": " +
                      escape_control(message);
    if (!source_line.empty()) {
        std::string echo, caret;
        for (int i = 0; i < static_cast<int>(source_line.size()); ++i) {
            const char c = source_line[i];
            const std::string shown =
                c == '\t' ? std::string(1, c) : escape_control(std::string_view(&c, 1));
            echo += shown;
            if (i + 1 < column)
                caret += c == '\t' ? std::string(1, c) : std::string(shown.size(), ' ');
        }
        out += "\n  " + echo + "\n  " + caret + '^';
    }
    return out;
}

namespace {

std::string first_error(const std::vector<Diagnostic>& diagnostics) {
    for (const Diagnostic& d : diagnostics)
        if (d.severity == Diagnostic::Severity::Error)
            return d.file + ":" + std::to_string(d.line) + ":" +
                   std::to_string(d.column) + ": error: " + d.message;
    return "shader compile error";
}

} // namespace

ShaderCompileError::ShaderCompileError(std::vector<Diagnostic> diagnostics)
    : ValueError(first_error(diagnostics)), m_diagnostics(std::move(diagnostics)) {}

ShaderCompileError::ShaderCompileError(std::vector<Diagnostic> diagnostics,
                                       const std::string& what)
    : ValueError(what), m_diagnostics(std::move(diagnostics)) {}

} // namespace sss

namespace sss::detail {

DiagnosticSink::DiagnosticSink(const PreprocessResult& source) : m_source(source) {
    m_line_starts.push_back(0);
    for (std::size_t i = 0; i < source.text.size(); ++i)
        if (source.text[i] == '\n') m_line_starts.push_back(i + 1);
}

std::string DiagnosticSink::line_text(int line) const {
    if (line < 0 || line >= static_cast<int>(m_line_starts.size())) return "";
    std::size_t b = m_line_starts[line];
    std::size_t e = m_source.text.find('\n', b);
    if (e == std::string::npos) e = m_source.text.size();
    std::string s = m_source.text.substr(b, e - b);
    if (!s.empty() && s.back() == '\r') s.pop_back();
    return s;
}

SourceLocation DiagnosticSink::where(SrcLoc at) const {
    SourceLocation w;
    if (at.line >= 0 && at.line < static_cast<int>(m_source.lines.size())) {
        w.file = m_source.lines[at.line].file;
        w.line = m_source.lines[at.line].line;
    } else {
        // No line table (text compiled without the preprocessor).
        w.file = m_source.files.empty() ? -1 : 0;
        w.line = at.line + 1;
    }
    w.column = at.col;
    return w;
}

void DiagnosticSink::add(Diagnostic::Severity severity, SrcLoc at,
                         const std::string& message) {
    const SourceLocation w = where(at);
    Diagnostic d;
    d.severity = severity;
    d.file = w.file >= 0 && w.file < static_cast<int>(m_source.files.size())
                 ? m_source.files[w.file]
                 : std::string("<string>");
    d.line = w.line;
    d.column = at.col;
    d.message = message;
    d.source_line = line_text(at.line);
    push(std::move(d));
}

bool DiagnosticSink::push(Diagnostic d) {
    if (!m_seen.emplace(d.file, d.line, d.column, d.message).second) return false;
    if (d.severity == Diagnostic::Severity::Error) ++m_errors;
    m_all.push_back(std::move(d));
    return true;
}

void DiagnosticSink::absorb(const DiagnosticSink& other) {
    for (const Diagnostic& d : other.m_all) push(d);
    if (m_errors >= kMaxErrors) throw CompileAbort{};
}

void DiagnosticSink::error(SrcLoc at, const std::string& message) {
    add(Diagnostic::Severity::Error, at, message);
    if (m_errors >= kMaxErrors) throw CompileAbort{};
}

void DiagnosticSink::warning(SrcLoc at, const std::string& message) {
    add(Diagnostic::Severity::Warning, at, message);
}

std::vector<Diagnostic> DiagnosticSink::warnings() const {
    std::vector<Diagnostic> out;
    for (const Diagnostic& d : m_all)
        if (d.severity == Diagnostic::Severity::Warning) out.push_back(d);
    return out;
}

} // namespace sss::detail
