/// \file install_layout.cpp
/// The tools' data folders relative to the running executable (install_layout.h).

#include "sss/util/install_layout.h"

#include <filesystem>
#include <system_error>

#if !defined(SSS_INSTALL_SHADER_RELDIR) || !defined(SSS_INSTALL_PLUGIN_RELDIR)
#error                                                                                   \
    "SSS_INSTALL_SHADER_RELDIR and SSS_INSTALL_PLUGIN_RELDIR come from the build (src/sss/CMakeLists.txt)"
#endif

namespace sss {

namespace fs = std::filesystem;

std::string executable_dir() {
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    return ec ? std::string() : exe.parent_path().string();
}

std::string data_folder(DataFolder kind) {
    const std::string exe = executable_dir();
    if (exe.empty()) return {};
    // The install's layout first: a build tree has no share/ or lib/sss beside bin/.
    const char* installed = kind == DataFolder::Shaders ? SSS_INSTALL_SHADER_RELDIR
                                                        : SSS_INSTALL_PLUGIN_RELDIR;
    const char* build_tree = kind == DataFolder::Shaders ? "../shaders" : "../lib";
    for (const char* rel : {installed, build_tree}) {
        std::error_code ec;
        const fs::path dir = (fs::path(exe) / rel).lexically_normal();
        if (fs::is_directory(dir, ec)) return dir.string();
    }
    return {};
}

} // namespace sss
