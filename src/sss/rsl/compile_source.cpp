// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file compile_source.cpp
/// compile_file and compile_text: the preprocessor (preprocess.cpp), then
/// compile_preprocessed. A file of its own so that code calling only
/// compile_preprocessed does not pull in the preprocessor.

#include "sss/rsl/compiler.h"

namespace sss {

CompileResult compile_file(const std::string& path, const PreprocessOptions& options) {
    return compile_preprocessed(preprocess_file(path, options));
}

CompileResult compile_text(const std::string& text, const std::string& name,
                           const PreprocessOptions& options) {
    return compile_preprocessed(preprocess_text(text, name, options));
}

} // namespace sss
