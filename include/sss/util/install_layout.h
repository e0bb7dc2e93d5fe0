// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file install_layout.h
/// Where the tools find their data relative to their own location, so that an
/// installed tree can be moved (docs/install.md): an install keeps the
/// standard shaders in `<prefix>/share/sss/shaders` and the plugins in
/// `<prefix>/<libdir>/sss`, next to `<prefix>/bin`; the build tree keeps them
/// in `<build>/shaders` and `<build>/lib`, next to `<build>/bin`.

#include <string>

namespace sss {

/// The folder of the running executable ("" when /proc/self/exe cannot be read).
std::string executable_dir();

/// What a folder of the toolchain's data holds.
enum class DataFolder {
    Shaders, ///< the compiled standard shaders
    Plugins  ///< the loadable plugins (libsss_texture2d.so)
};

/// The folder of `kind` beside the running executable: the install's place
/// (relative to its bin folder, fixed when the build was configured), else
/// the build tree's; the first that exists, normalised. A program that is
/// not one of the tools, using libsss.so, finds them the same way relative
/// to the library's folder. "" when none exists.
std::string data_folder(DataFolder kind);

} // namespace sss
