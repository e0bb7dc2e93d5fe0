// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file compiler.h
/// The RSL compiler: preprocessed source -> checked, typed Programs
/// (program.h). Errors are collected (several per run) with file, line,
/// column and the source line, as `shader` prints them.

#include <string>
#include <vector>

#include "sss/rsl/preprocess.h"
#include "sss/rsl/program.h"
#include "sss/util/error.h"

namespace sss {

/// One compiler message.
struct Diagnostic {
    enum class Severity { Warning, Error };
    Severity severity = Severity::Error;
    std::string file;
    int line = 0;
    int column = 0;
    std::string message;
    std::string source_line; ///< the line of source it points into

    /// "file:line:column: error: message\n  source line\n  ^"
    std::string format() const;
};

/// A shader that does not compile: every error found (and the warnings
/// before them). what() is the first error, formatted on one line.
class ShaderCompileError : public ValueError {
public:
    explicit ShaderCompileError(std::vector<Diagnostic> diagnostics);
    /// The same diagnostics under another message (one line).
    ShaderCompileError(std::vector<Diagnostic> diagnostics, const std::string& what);
    const std::vector<Diagnostic>& diagnostics() const { return m_diagnostics; }

private:
    std::vector<Diagnostic> m_diagnostics;
};

struct CompileResult {
    std::vector<Program> shaders; ///< every shader the file defines
    std::vector<Diagnostic> warnings;
};

/// Compiles preprocessed source. Throws ShaderCompileError.
CompileResult compile_preprocessed(const PreprocessResult& source);
/// Preprocesses and compiles a .sl file. Throws PreprocessError /
/// ShaderCompileError / IoError.
CompileResult compile_file(const std::string& path, const PreprocessOptions& options);
/// Compiles source text (tests).
CompileResult compile_text(const std::string& text, const std::string& name = "<string>",
                           const PreprocessOptions& options = {});

} // namespace sss
