// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file compiler.cpp
/// compile_preprocessed: tokens, syntax tree, then checked Programs
/// (lexer.cpp, parser.cpp, codegen.cpp). compile_file and compile_text,
/// which run the preprocessor first, are in compile_source.cpp.

#include "sss/rsl/compiler.h"

#include "ast.h"
#include "codegen.h"
#include "lexer.h"

namespace sss {

CompileResult compile_preprocessed(const PreprocessResult& source) {
    detail::DiagnosticSink diags(source);
    CompileResult result;
    try {
        const std::vector<detail::Token> tokens = detail::tokenize(source.text, diags);
        const detail::SourceFile file = detail::parse(tokens, diags);
        // Type errors on a tree with syntax errors would mostly be noise.
        if (diags.error_count() == 0) result.shaders = detail::generate(file, diags);
    } catch (const detail::CompileAbort&) {
        // Too many errors or too deep a nesting: report what we have.
    }
    if (diags.error_count() > 0) throw ShaderCompileError(diags.all());
    result.warnings = diags.warnings();
    return result;
}

} // namespace sss
