// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file rib_camera_test.cpp
/// The RIB reader's camera and display options: DepthOfField, PixelFilter,
/// Exposure and Quantize, their defaults and their errors (file:line).

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "sss/scene/rib.h"
#include "sss/util/error.h"

namespace {

sss::Scene parse(const std::string& text) {
    return sss::parse_rib(text, "cam.rib");
}

/// The RibError of `text`: its line, and that its message names every part.
int error_line(const std::string& text, std::initializer_list<std::string> parts) {
    try {
        parse(text);
    } catch (const sss::RibError& e) {
        const std::string what = e.what();
        for (const auto& p : parts)
            EXPECT_NE(what.find(p), std::string::npos) << what << " lacks " << p;
        EXPECT_NE(what.find("cam.rib:"), std::string::npos) << what;
        return e.line();
    }
    ADD_FAILURE() << "no error for " << text;
    return -1;
}

} // namespace

TEST(RibCamera, DefaultsArePinholeGaussianNoExposureNoQuantize) {
    const sss::Scene s = parse("WorldBegin\nWorldEnd\n");
    EXPECT_FALSE(s.options.camera.depth_of_field());
    EXPECT_EQ(s.options.camera.lens_radius(), 0.0);
    EXPECT_EQ(s.options.pixel_filter.name, "gaussian");
    EXPECT_EQ(s.options.pixel_filter.xwidth, 2.0);
    EXPECT_EQ(s.options.pixel_filter.ywidth, 2.0);
    EXPECT_EQ(s.options.exposure_gain, 1.0);
    EXPECT_EQ(s.options.exposure_gamma, 1.0);
    EXPECT_FALSE(s.options.quantize.has_value());
    EXPECT_TRUE(s.warnings.empty());
}

TEST(RibCamera, RequestsAreParsed) {
    const sss::Scene s = parse("DepthOfField 2.8 0.05 3\nPixelFilter \"catmullrom\" 3 4\n"
                               "Exposure 1.5 2.2\nQuantize \"rgba\" 65535 0 65535 0.25\n"
                               "Quantize \"z\" 0 0 0 0\nWorldBegin\nWorldEnd\n");
    const sss::Camera& c = s.options.camera;
    EXPECT_TRUE(c.depth_of_field());
    EXPECT_EQ(c.fstop, 2.8);
    EXPECT_EQ(c.focal_length, 0.05);
    EXPECT_EQ(c.focal_distance, 3.0);
    EXPECT_DOUBLE_EQ(c.lens_radius(), 0.05 / 5.6);
    EXPECT_EQ(s.options.pixel_filter.name, "catmull-rom");
    EXPECT_EQ(s.options.pixel_filter.xwidth, 3.0);
    EXPECT_EQ(s.options.pixel_filter.ywidth, 4.0);
    EXPECT_EQ(s.options.exposure_gain, 1.5);
    EXPECT_EQ(s.options.exposure_gamma, 2.2);
    ASSERT_TRUE(s.options.quantize.has_value()); // "z" left the rgba one alone
    EXPECT_EQ(s.options.quantize->one, 65535.0);
    EXPECT_EQ(s.options.quantize->max, 65535.0);
    EXPECT_EQ(s.options.quantize->dither, 0.25);
    EXPECT_TRUE(s.warnings.empty());
    // No arguments, or RI_INFINITY as the fstop: the pinhole again.
    EXPECT_FALSE(parse("DepthOfField 2 1 5\nDepthOfField\nWorldBegin\nWorldEnd\n")
                     .options.camera.depth_of_field());
    EXPECT_FALSE(parse("DepthOfField 1e38 1 5\nWorldBegin\nWorldEnd\n")
                     .options.camera.depth_of_field());
}

TEST(RibCamera, BadValuesAreErrorsNamingTheLine) {
    EXPECT_EQ(error_line("Format 4 4 1\nPixelFilter \"mitchell\" 2 2\n", {"mitchell"}),
              2);
    EXPECT_EQ(error_line("PixelFilter \"box\" -1 1\n", {"widths"}), 1);
    EXPECT_EQ(error_line("PixelFilter \"box\" 1 17\n", {"widths"}), 1);
    EXPECT_EQ(error_line("PixelFilter \"box\" 1\n", {"PixelFilter"}), 1);
    EXPECT_EQ(error_line("\nDepthOfField 0 1 5\n", {"fstop"}), 2);
    EXPECT_EQ(error_line("DepthOfField 2 5 5\n", {"focaldistance"}), 1);
    EXPECT_EQ(error_line("DepthOfField 2 6 5\n", {"focaldistance"}), 1);
    EXPECT_EQ(error_line("DepthOfField 2 1\n", {"DepthOfField"}), 1);
    EXPECT_EQ(error_line("Exposure 1 0\n", {"gamma"}), 1);
    EXPECT_EQ(error_line("Exposure -1 1\n", {"gain"}), 1);
    EXPECT_EQ(error_line("Exposure \"a\" 1\n", {"Exposure"}), 1);
    EXPECT_EQ(error_line("Quantize \"rgba\" 255 0 255\n", {"Quantize"}), 1);
    EXPECT_EQ(error_line("Quantize \"rgba\" 255 10 5 0.5\n", {"min"}), 1);
    EXPECT_EQ(error_line("Quantize \"cmyk\" 255 0 255 0.5\n", {"cmyk"}), 1);
}
