// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
// Internal to the shading module: type checking and code generation from the
// syntax tree (ast.h) to Programs (program.h).

#include <vector>

#include "ast.h"

namespace sss::detail {

/// Checks and compiles every shader of `file`. Errors go to `diags`; the
/// shaders with errors are left out of the result.
std::vector<Program> generate(const SourceFile& file, DiagnosticSink& diags);

} // namespace sss::detail
