// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file bake_errors_test.cpp
/// The bake's typed errors: they name the scene object and the setting, never
/// a command-line option (ptbake words them for its options).

#include <gtest/gtest.h>

#include <string>

#include "sss/bake/bake.h"
#include "sss/scene/rib.h"
#include "sss/util/error.h"

namespace {

sss::Scene scene_with(const std::string& world) {
    return sss::parse_rib("Format 64 64 1\nTranslate 0 0 6\nWorldBegin\n"
                          "LightSource \"ambientlight\" 1\n" +
                              world + "WorldEnd\n",
                          "errors.rib");
}

} // namespace

TEST(BakeErrors, MissingFilenameNamesTheObjectNotAnOption) {
    const sss::Scene scene =
        scene_with("Surface \"bake_radiance_t\"\nSphere 1 -1 1 360\n");
    try {
        sss::bake_output_files(scene, {});
        FAIL() << "no error";
    } catch (const sss::MissingBakeFileError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("errors.rib:6"), std::string::npos) << what;
        EXPECT_NE(what.find("has no \"filename\""), std::string::npos) << what;
        EXPECT_EQ(what.find("-o"), std::string::npos) << what;
    }
}

TEST(BakeErrors, SpacingFromMaterialWithoutOneIsAUsageErrorWithItsSource) {
    const sss::Scene scene = scene_with("Surface \"bake_radiance_t\" \"string filename\" "
                                        "[\"x.ptc\"]\nSphere 1 -1 1 360\n");
    sss::BakeOptions opt;
    opt.spacing_from_material = true;
    try {
        sss::bake_clouds(scene, opt, nullptr);
        FAIL() << "no error";
    } catch (const sss::SpacingMaterialError& e) {
        EXPECT_EQ(e.source(), "errors.rib:6");
        EXPECT_EQ(std::string(e.what()).find("-spacing"), std::string::npos) << e.what();
        EXPECT_EQ(std::string(e.what()).find("-material"), std::string::npos) << e.what();
    }
}

TEST(BakeErrors, OneUnitlength) {
    const sss::Scene scene = scene_with("Surface \"bake_radiance_t\" \"string filename\" "
                                        "[\"x.ptc\"]\nSphere 1 -1 1 360\n");
    sss::BakeOptions opt;
    opt.unitlength = 0.1;
    sss::MaterialSpec m;
    m.unitlength = 0.1;
    opt.material = m;
    EXPECT_NO_THROW(sss::bake_output_files(scene, opt));
    opt.material->unitlength = 1.0; // the material's differs from the bake's
    EXPECT_THROW(sss::bake_clouds(scene, opt, nullptr), sss::ValueError);
    opt.material->unitlength = 0.1;
    opt.unitlength = 0.0;
    opt.material->unitlength = 0.0;
    EXPECT_THROW(sss::bake_clouds(scene, opt, nullptr), sss::MaterialValueError);
}
