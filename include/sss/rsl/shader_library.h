// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file shader_library.h
/// Finding compiled shaders as PRMan does: `<name>.slo` along the shader
/// search path, where a folder with only `<name>.sl` has it compiled on
/// demand (the compiled program is cached for the job).
///
/// The search path is `Option "searchpath" "shader" ["a:b:..."]` of the
/// scene: ':'-separated folders, relative ones taken from the RIB's folder;
/// `@` stands for the standard shaders and `&` for the previous value (the
/// default). The default is the RIB's folder, then the standard shaders.
/// The standard shaders are the compiled `shaders/` of the toolchain: the
/// folder named by the environment variable SSS_SHADER_DIR when set, else
/// the one beside the running executable: an install's
/// `<prefix>/share/sss/shaders`, or the build tree's `<build>/shaders`
/// (sss/util/install_layout.h).

#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "sss/rsl/program.h"
#include "sss/util/error.h"

namespace sss {

/// A shader the search path does not have, or one of the wrong kind. The
/// message names the shader, the call's RIB location and the search path.
class ShaderNotFoundError : public ValueError {
public:
    using ValueError::ValueError;
};

/// The folder of the standard shaders (see above); "" when it cannot be found.
std::string standard_shader_dir();

/// A shader search path, folders in search order, from a scene's entries
/// (`Option "searchpath" "shader"`, "&" already expanded): "@" becomes the
/// standard shaders' folder (dropped when there is none); relative folders
/// stay relative to the working folder.
std::vector<std::string>
resolve_shader_search_path(const std::vector<std::string>& entries);

/// Loads shaders by name along a search path; each once. Thread-safe.
class ShaderLibrary {
public:
    explicit ShaderLibrary(std::vector<std::string> search_path);

    /// The shader `name` of kind `kind`. `where` (e.g. "scene.rib:12:
    /// Surface \"glass\"") prefixes errors: ShaderNotFoundError when no
    /// folder has it or it is of another kind, ShaderCompileError /
    /// ValueError when its file does not compile or read.
    std::shared_ptr<const Program> load(const std::string& name, ShaderKind kind,
                                        const std::string& where);
    /// The shader `name` of any kind: a co-shader (`Shader "name" "handle"`).
    std::shared_ptr<const Program> load_any(const std::string& name,
                                            const std::string& where);
    const std::vector<std::string>& search_path() const { return m_path; }
    /// The .slo / .sl files loaded so far, in load order (inputs of -newer).
    std::vector<std::string> files() const;

private:
    std::vector<std::string> m_path;
    std::shared_ptr<const Program> find(const std::string& name,
                                        const std::string& where);
    mutable std::mutex m_mutex;
    std::map<std::string, std::shared_ptr<const Program>> m_loaded;
    std::vector<std::string> m_files;
};

} // namespace sss
