// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file install_layout.cpp
/// The tools' data folders relative to the running executable or to
/// libsss.so (install_layout.h).

#include "sss/util/install_layout.h"

#include <dlfcn.h>

#include <filesystem>
#include <initializer_list>
#include <system_error>

#if !defined(SSS_INSTALL_SHADER_RELDIR) || !defined(SSS_INSTALL_PLUGIN_RELDIR) ||        \
    !defined(SSS_INSTALL_LIB_SHADER_RELDIR) || !defined(SSS_INSTALL_LIB_PLUGIN_RELDIR)
#error "the SSS_INSTALL_*_RELDIR folders come from the build (src/sss/CMakeLists.txt)"
#endif

namespace sss {

namespace fs = std::filesystem;

std::string executable_dir() {
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    return ec ? std::string() : exe.parent_path().string();
}

namespace {

// The folder of the shared object this code is in, when it is not the
// executable (the library is libsss.so in a program of someone else's).
std::string library_dir() {
    Dl_info info{};
    if (dladdr(reinterpret_cast<void*>(&library_dir), &info) == 0 || !info.dli_fname)
        return {};
    std::error_code ec;
    const fs::path lib = fs::canonical(info.dli_fname, ec);
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    if (lib.empty() || lib == exe) return {};
    return lib.parent_path().string();
}

std::string first_folder(const std::string& base,
                         std::initializer_list<const char*> rels) {
    if (base.empty()) return {};
    for (const char* rel : rels) {
        std::error_code ec;
        const fs::path dir = (fs::path(base) / rel).lexically_normal();
        if (fs::is_directory(dir, ec)) return dir.string();
    }
    return {};
}

} // namespace

std::string data_folder(DataFolder kind) {
    const bool shaders = kind == DataFolder::Shaders;
    // The install's layout first: a build tree has no share/ or lib/sss beside bin/.
    std::string dir = first_folder(executable_dir(), {shaders ? SSS_INSTALL_SHADER_RELDIR
                                                              : SSS_INSTALL_PLUGIN_RELDIR,
                                                      shaders ? "../shaders" : "../lib"});
    if (dir.empty()) {
        // libsss.so: the install's layout beside <libdir>, or the build tree's lib/.
        dir = first_folder(library_dir(), {shaders ? SSS_INSTALL_LIB_SHADER_RELDIR
                                                   : SSS_INSTALL_LIB_PLUGIN_RELDIR,
                                           shaders ? "../shaders" : "."});
    }
    return dir;
}

} // namespace sss
