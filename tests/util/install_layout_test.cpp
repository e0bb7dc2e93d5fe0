// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// The tools' data folders beside the running executable (install_layout.h):
// sss_tests runs from <build>/bin, so it sees the build tree's layout.
#include <filesystem>

#include <gtest/gtest.h>

#include "sss/util/install_layout.h"

namespace fs = std::filesystem;

TEST(InstallLayout, ExecutableDirIsTheTestsBinFolder) {
    const fs::path dir = sss::executable_dir();
    ASSERT_FALSE(dir.empty());
    EXPECT_TRUE(fs::exists(dir / "sss_tests"));
}

TEST(InstallLayout, BuildTreeShadersAndPlugins) {
    const fs::path bin = sss::executable_dir();
    const std::string shaders = sss::data_folder(sss::DataFolder::Shaders);
    EXPECT_EQ(shaders, (bin / "../shaders").lexically_normal().string());
    EXPECT_TRUE(fs::exists(fs::path(shaders) / "bake_radiance_t.slo"));
    const std::string plugins = sss::data_folder(sss::DataFolder::Plugins);
    EXPECT_EQ(plugins, (bin / "../lib").lexically_normal().string());
}
