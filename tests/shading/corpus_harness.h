// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
// The RSL corpus harness (corpus_test.cpp, and the texture cases of
// tests/binding/engine_textures_test.cpp): corpus files compiled from disk,
// run over a batch, and their check_* outputs asserted to be 0.

#include <gtest/gtest.h>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "engine_test_util.h"
#include "sss/rsl/compiler.h"
#include "sss/rsl/preprocess.h"

namespace sss::test {

/// The corpus folder (tests/shading/corpus).
inline std::filesystem::path corpus_dir() {
    return std::filesystem::path(SSS_TEST_DATA_DIR).parent_path() / "shading" / "corpus";
}

inline PreprocessOptions corpus_options() {
    PreprocessOptions o;
    o.include_dirs = {corpus_dir().string(), (corpus_dir() / "include").string()};
    o.defines = {{"CORPUS_LEVEL", "3"}}; // preprocessor.sl checks it
    return o;
}

/// Every shader of a corpus file, compiled from disk (the test fails on errors).
inline std::vector<std::shared_ptr<const Program>>
compile_corpus(const std::string& file) {
    std::vector<std::shared_ptr<const Program>> out;
    try {
        CompileResult r = compile_file((corpus_dir() / file).string(), corpus_options());
        for (const Diagnostic& w : r.warnings)
            ADD_FAILURE() << file << ": " << w.format();
        for (Program& p : r.shaders)
            out.push_back(std::make_shared<Program>(std::move(p)));
    } catch (const ShaderCompileError& e) {
        std::string all;
        for (const Diagnostic& d : e.diagnostics()) all += d.format() + "\n";
        ADD_FAILURE() << file << " does not compile:\n" << all;
    } catch (const std::exception& e) {
        ADD_FAILURE() << file << ": " << e.what();
    }
    return out;
}

/// Asserts every check_* output of the last execute() is 0 at every point;
/// returns the number of checks.
inline int expect_checks(const ShadingContext& ctx, const Program& prog,
                         const std::string& what, std::size_t points,
                         bool allow_nonfinite = false) {
    int checks = 0;
    for (int index : prog.parameters()) {
        const std::string& name = prog.symbols[index].name;
        if (name.rfind("check_", 0) != 0) continue;
        ++checks;
        TypeSpec type;
        std::vector<float> values;
        if (!ctx.output(name, type, values)) {
            ADD_FAILURE() << what << ": no output " << name;
            continue;
        }
        std::size_t bad = 0, first = 0;
        for (std::size_t i = 0; i < values.size(); ++i) {
            if (values[i] != 0.0f && bad++ == 0) first = i;
        }
        EXPECT_EQ(values.size() == 1 ? points : values.size(), points)
            << what << " " << name;
        EXPECT_EQ(bad, 0u) << what << ": " << name.substr(6) << " fails at " << bad
                           << " of " << values.size() << " points (first: point " << first
                           << ", value " << values[first]
                           << (values[first] == -1.0f ? ": never written" : "") << ")";
    }
    EXPECT_GT(checks, 0) << what << " has no checks";
    if (!allow_nonfinite) {
        EXPECT_EQ(ctx.nonfinite_points(), 0u) << what << ": " << ctx.nonfinite_message();
    }
    return checks;
}

/// Runs shader `name` of `file` (by default the file's first surface shader)
/// over `batch` and checks it.
inline int run_corpus(const std::string& file, ShadingBatch& batch,
                      const ParamList& params = {}, Engine* engine = nullptr,
                      LightList lights = {}, const std::string& name = "",
                      const Matrix4& shader_to_world = Matrix4(1.0)) {
    Engine local;
    Engine& e = engine ? *engine : local;
    std::shared_ptr<const Program> prog;
    for (auto& p : compile_corpus(file))
        if (!prog && (name.empty() ? p->kind == ShaderKind::Surface : p->name == name))
            prog = p;
    if (!prog) {
        ADD_FAILURE() << file << ": no shader " << name;
        return 0;
    }
    const std::string what = file + (name.empty() ? "" : " (" + name + ")");
    try {
        ShaderInstance inst(prog, params, shader_to_world, file);
        e.context.execute(inst, batch, lights);
    } catch (const std::exception& ex) {
        ADD_FAILURE() << what << ": " << ex.what();
        return 0;
    }
    return expect_checks(e.context, *prog, what, batch.size);
}
inline int run_corpus(const std::string& file, ShadingBatch&& batch,
                      const ParamList& params = {}, Engine* engine = nullptr,
                      LightList lights = {}, const std::string& name = "") {
    return run_corpus(file, batch, params, engine, lights, name);
}

} // namespace sss::test
