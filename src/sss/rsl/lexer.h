// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
// Internal to the shading module: the RSL tokenizer (shading.md section 1).

#include <string>
#include <string_view>
#include <vector>

#include "diagnostics.h"

namespace sss::detail {

enum class TokKind { End, Ident, Keyword, Number, String, Punct };

struct Token {
    TokKind kind = TokKind::End;
    std::string text; ///< identifier, keyword, operator, or the string's value
    double number = 0.0;
    SrcLoc loc;
};

/// Whether `word` is an RSL keyword.
bool is_keyword(std::string_view word);

/// Splits preprocessed text into tokens (the last one End). Adjacent string
/// literals are joined. Errors go to `diags`; the bad characters are skipped.
std::vector<Token> tokenize(const std::string& text, DiagnosticSink& diags);

/// "'x'", "a number", "the end of the file"... for messages.
std::string describe(const Token& t);

} // namespace sss::detail
