// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file shader_library.cpp
/// The shader search path and on-demand loading (shader_library.h).

#include "sss/rsl/shader_library.h"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <system_error>
#include <unistd.h>

#include "sss/rsl/compiler.h"
#include "sss/util/install_layout.h"
#include "sss/util/limits.h"
#include "sss/util/messages.h"

namespace sss {

namespace fs = std::filesystem;

namespace {

std::string join_path(const std::vector<std::string>& dirs) {
    std::string out;
    for (const std::string& d : dirs) out += (out.empty() ? "" : ":") + d;
    return out;
}

} // namespace

std::string standard_shader_dir() {
    if (const char* env = std::getenv("SSS_SHADER_DIR"); env && *env) return env;
    return data_folder(DataFolder::Shaders);
}

std::vector<std::string>
resolve_shader_search_path(const std::vector<std::string>& entries) {
    const std::string standard = standard_shader_dir();
    std::vector<std::string> out;
    for (const std::string& entry : entries) {
        const std::string dir = entry == "@" ? standard : entry;
        if (!dir.empty() && std::find(out.begin(), out.end(), dir) == out.end())
            out.push_back(dir);
    }
    return out;
}

namespace {

/// compile_file for a shader a scene calls, whose errors are one line (the
/// tools print one ERROR line; `shader file.sl` shows them all):
/// "<where>: file.sl:3:14: message (and 2 more errors)".
CompileResult compile_on_the_fly(const std::string& path,
                                 const PreprocessOptions& options,
                                 const std::string& where) {
    try {
        ScopedStage stage("compiling " + path);
        return compile_file(path, options);
    } catch (const ShaderCompileError& e) {
        const Diagnostic* first = nullptr;
        std::size_t errors = 0;
        for (const Diagnostic& d : e.diagnostics())
            if (d.severity == Diagnostic::Severity::Error && errors++ == 0) first = &d;
        if (!first) throw;
        std::string text = where + ": " + first->file + ":" +
                           std::to_string(first->line) + ":" +
                           std::to_string(first->column) + ": " + first->message;
        if (errors > 1)
            text += " (and " + std::to_string(errors - 1) +
                    (errors == 2 ? " more error)" : " more errors)");
        throw ShaderCompileError(e.diagnostics(), text);
    } catch (const PreprocessError& e) {
        throw ValueError(where + ": " + e.what());
    }
}

} // namespace

ShaderLibrary::ShaderLibrary(std::vector<std::string> search_path)
    : m_path(std::move(search_path)) {}

std::shared_ptr<const Program>
ShaderLibrary::load(const std::string& name, ShaderKind kind, const std::string& where) {
    std::shared_ptr<const Program> program = load_any(name, where);
    if (program->kind == ShaderKind::Shader && kind != ShaderKind::Shader)
        throw ShaderNotFoundError(
            where + ": " + sss::quoted(name) +
            " is a co-shader (a class without pipeline methods such "
            "as surface or light): declare it with Shader \"" +
            name + "\" \"handle\"");
    if (!program->runs_as(kind))
        throw ShaderNotFoundError(where + ": " + sss::quoted(name) + " is a " +
                                  shader_kind_name(program->kind) + " shader, not a " +
                                  shader_kind_name(kind) + " shader");
    return program;
}

std::shared_ptr<const Program> ShaderLibrary::load_any(const std::string& name,
                                                       const std::string& where) {
    std::lock_guard<std::mutex> lock(m_mutex);
    return find(name, where);
}

std::shared_ptr<const Program> ShaderLibrary::find(const std::string& name,
                                                   const std::string& where) {
    auto it = m_loaded.find(name);
    std::shared_ptr<const Program> program;
    if (it != m_loaded.end()) {
        program = it->second;
    } else {
        std::error_code ec;
        for (const std::string& dir : m_path) {
            const fs::path slo = fs::path(dir) / (name + ".slo");
            const fs::path sl = fs::path(dir) / (name + ".sl");
            if (fs::is_regular_file(slo, ec)) {
                program =
                    std::make_shared<const Program>(read_program_file(slo.string()));
                m_files.push_back(slo.string());
                break;
            }
            if (fs::is_regular_file(sl, ec)) {
                PreprocessOptions options;
                options.include_dirs.push_back(dir);
                if (const std::string standard = standard_shader_dir(); !standard.empty())
                    options.include_dirs.push_back(standard);
                CompileResult result = compile_on_the_fly(sl.string(), options, where);
                for (Program& p : result.shaders)
                    if (p.name == name)
                        program = std::make_shared<const Program>(std::move(p));
                m_files.push_back(sl.string());
                if (!program)
                    throw ShaderNotFoundError(where + ": " + sl.string() +
                                              " does not define a shader named " +
                                              sss::quoted(name));
                break;
            }
        }
        if (!program)
            throw ShaderNotFoundError(where + ": shader " + sss::quoted(name) +
                                      " not found (no .slo or .sl of that name in the "
                                      "shader search path " +
                                      join_path(m_path) + ")");
        m_loaded.emplace(name, program);
    }
    return program;
}

std::vector<std::string> ShaderLibrary::files() const {
    std::lock_guard<std::mutex> lock(m_mutex);
    return m_files;
}

} // namespace sss
