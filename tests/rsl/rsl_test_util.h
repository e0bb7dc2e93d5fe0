// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
// Helpers of the RSL compiler tests: source text compiled without the
// preprocessor (one output line per input line of "test.sl").

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "sss/rsl/compiler.h"

namespace sss::test {

inline PreprocessResult raw_source(const std::string& text,
                                   const std::string& file = "test.sl") {
    PreprocessResult r;
    r.text = text;
    r.files = {file};
    int n = 1;
    for (char c : text) n += c == '\n';
    for (int i = 0; i < n; ++i) r.lines.push_back({0, i + 1});
    return r;
}

inline CompileResult compile_raw(const std::string& text) {
    return compile_preprocessed(raw_source(text));
}

inline Program compile_one(const std::string& text) {
    CompileResult r;
    try {
        r = compile_raw(text);
    } catch (const ShaderCompileError& e) {
        std::string all;
        for (const Diagnostic& d : e.diagnostics()) all += d.format() + "\n";
        ADD_FAILURE() << "compile failed:\n" << all;
        return {};
    }
    EXPECT_EQ(r.shaders.size(), 1u);
    return r.shaders.empty() ? Program{} : r.shaders[0];
}

/// The diagnostics of a source that must not compile.
inline std::vector<Diagnostic> compile_errors(const std::string& text) {
    try {
        compile_raw(text);
    } catch (const ShaderCompileError& e) {
        return e.diagnostics();
    }
    ADD_FAILURE() << "compiled, but errors were expected:\n" << text;
    return {};
}

/// True if some error message contains `part`.
inline bool has_error(const std::vector<Diagnostic>& ds, const std::string& part) {
    for (const Diagnostic& d : ds)
        if (d.severity == Diagnostic::Severity::Error &&
            d.message.find(part) != std::string::npos)
            return true;
    return false;
}

inline std::string all_messages(const std::vector<Diagnostic>& ds) {
    std::string s;
    for (const Diagnostic& d : ds) s += d.format() + "\n";
    return s;
}

/// Number of ops named `name`.
inline int count_ops(const Program& p, const std::string& name) {
    int n = 0;
    for (const Op& op : p.ops) n += op.name == name;
    return n;
}

inline const Op* find_op(const Program& p, const std::string& name) {
    for (const Op& op : p.ops)
        if (op.name == name) return &op;
    return nullptr;
}

} // namespace sss::test
