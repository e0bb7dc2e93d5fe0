// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file texture_options_test.cpp
/// The token-value options of RSL's texture, texture3d and bake3d calls, as
/// the engine reads them (texture_services.h, texture_options.h).

#include <gtest/gtest.h>

#include <string>

#include "../../src/sss/shading/texture_options.h"
#include "sss/shading/texture_services.h"

using namespace sss;
using namespace sss::detail;

TEST(RslTextureOptions, EveryOptionAndUnknownNames) {
    TextureOptions o;
    const float two = 2.0f, half = 0.5f, zero = 0.0f, four = 4.0f;
    EXPECT_TRUE(set_texture_option(o, "blur", &half, 1, nullptr));
    EXPECT_EQ(o.sblur, 0.5f);
    EXPECT_EQ(o.tblur, 0.5f);
    EXPECT_TRUE(set_texture_option(o, "sblur", &two, 1, nullptr));
    EXPECT_TRUE(set_texture_option(o, "tblur", &zero, 1, nullptr));
    EXPECT_EQ(o.sblur, 2.0f);
    EXPECT_EQ(o.tblur, 0.0f);
    EXPECT_TRUE(set_texture_option(o, "width", &zero, 1, nullptr));
    EXPECT_EQ(o.swidth, 0.0f);
    EXPECT_EQ(o.twidth, 0.0f);
    EXPECT_TRUE(set_texture_option(o, "swidth", &two, 1, nullptr));
    EXPECT_TRUE(set_texture_option(o, "twidth", &half, 1, nullptr));
    EXPECT_EQ(o.swidth, 2.0f);
    EXPECT_EQ(o.twidth, 0.5f);
    EXPECT_TRUE(set_texture_option(o, "samples", &four, 1, nullptr));
    EXPECT_EQ(o.samples, 4);
    const std::string gaussian = "gaussian";
    EXPECT_TRUE(set_texture_option(o, "filter", nullptr, 0, &gaussian));
    EXPECT_EQ(o.filter, "gaussian");
    EXPECT_TRUE(set_texture_option(o, "fill", &half, 1, nullptr));
    EXPECT_EQ(o.fill, 0.5f);
    EXPECT_TRUE(set_texture_option(o, "lerp", &zero, 1, nullptr));
    EXPECT_EQ(o.lerp, 0);
    EXPECT_TRUE(set_texture_option(o, "lerp", &four, 1, nullptr));
    EXPECT_EQ(o.lerp, 2); // clamped to 0..2

    // "bias" is shadow()'s (depth maps).
    EXPECT_EQ(o.bias, -1.0f); // unset: the scene's
    EXPECT_TRUE(set_texture_option(o, "bias", &half, 1, nullptr));
    EXPECT_EQ(o.bias, 0.5f);

    const TextureOptions before = o;
    EXPECT_FALSE(set_texture_option(o, "Bias", &half, 1, nullptr));
    EXPECT_FALSE(set_texture_option(o, "Blur", &half, 1, nullptr));
    EXPECT_FALSE(set_texture_option(o, "", &half, 1, nullptr));
    EXPECT_EQ(o.sblur, before.sblur);
    EXPECT_EQ(o.fill, before.fill);
}

TEST(RslTextureOptions, Texture3dAndBake3dOptions) {
    const float two = 2.0f, half = 0.5f, one = 1.0f;
    const std::string shader = "shader";
    Texture3dOptions t;
    EXPECT_TRUE(set_texture3d_option(t, "coordsystem", nullptr, 0, &shader));
    EXPECT_EQ(t.coordsystem, "shader");
    EXPECT_TRUE(set_texture3d_option(t, "filterradius", &half, 1, nullptr));
    EXPECT_EQ(t.filterradius, 0.5f);
    EXPECT_TRUE(set_texture3d_option(t, "filterscale", &two, 1, nullptr));
    EXPECT_EQ(t.filterscale, 2.0f);
    EXPECT_TRUE(set_texture3d_option(t, "maxdepth", &two, 1, nullptr));
    EXPECT_EQ(t.maxdepth, 2);
    EXPECT_TRUE(set_texture3d_option(t, "radius", &one, 1, nullptr)); // Pixie
    EXPECT_EQ(t.filterradius, 1.0f);
    EXPECT_TRUE(set_texture3d_option(t, "radiusscale", &half, 1, nullptr));
    EXPECT_EQ(t.filterscale, 0.5f);
    EXPECT_TRUE(set_texture3d_option(t, "interpolate", &one, 1, nullptr));
    EXPECT_FALSE(set_texture3d_option(t, "blur", &one, 1, nullptr));

    Bake3dOptions b;
    EXPECT_LT(b.radius, 0.0f);
    EXPECT_TRUE(set_bake3d_option(b, "radius", &half, 1, nullptr));
    EXPECT_EQ(b.radius, 0.5f);
    EXPECT_TRUE(set_bake3d_option(b, "radiusscale", &two, 1, nullptr));
    EXPECT_EQ(b.radiusscale, 2.0f);
    EXPECT_TRUE(set_bake3d_option(b, "coordsystem", nullptr, 0, &shader));
    EXPECT_EQ(b.coordsystem, "shader");
    EXPECT_TRUE(set_bake3d_option(b, "interpolate", &one, 1, nullptr));
    EXPECT_TRUE(b.interpolate);
    EXPECT_FALSE(set_bake3d_option(b, "filterradius", &one, 1, nullptr));
}
