// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>

#include "sss/util/error.h"
#include "sss/util/frame_pattern.h"

using sss::expand_frame_pattern;
using sss::has_frame_pattern;

TEST(FramePattern, PrintfStyle) {
    EXPECT_EQ(expand_frame_pattern("a.%04d.ptc", 7), "a.0007.ptc");
    EXPECT_EQ(expand_frame_pattern("a.%d.ptc", 123), "a.123.ptc");
    EXPECT_EQ(expand_frame_pattern("a.%06d.ptc", 42), "a.000042.ptc");
    EXPECT_EQ(expand_frame_pattern("100%%.%02d", 3), "100%.03");
}

TEST(FramePattern, HashesAreOneDigitEach) {
    EXPECT_EQ(expand_frame_pattern("img.####.exr", 12), "img.0012.exr");
    EXPECT_EQ(expand_frame_pattern("img.##.exr", 5), "img.05.exr");
    EXPECT_EQ(expand_frame_pattern("img.##.exr", 1234), "img.1234.exr");
    EXPECT_THROW(expand_frame_pattern("img.#.exr", 1), sss::UsageError);
}

TEST(FramePattern, HoudiniStyle) {
    EXPECT_EQ(expand_frame_pattern("c/$F4/skin.$F.ptc", 9), "c/0009/skin.9.ptc");
    EXPECT_EQ(expand_frame_pattern("skin.${F3}.ptc", 9), "skin.009.ptc");
    EXPECT_EQ(expand_frame_pattern("$HOME/x", 1), "$HOME/x");
}

TEST(FramePattern, NegativeFramesKeepTheirSign) {
    EXPECT_EQ(expand_frame_pattern("a.%04d", -5), "a.-005");
}

TEST(FramePattern, PatternWithoutFrameIsAUsageError) {
    EXPECT_EQ(expand_frame_pattern("plain.ptc", std::nullopt), "plain.ptc");
    try {
        expand_frame_pattern("x.####.ptc", std::nullopt, "option -o");
        FAIL() << "no exception";
    } catch (const sss::MissingFrameError& e) {
        // A UsageError (exit code 2); the CLI adds "-frame N" (tool_test.cpp:
        // RunTool.MissingFrameNamesTheOption), the library names no option.
        EXPECT_NE(std::string(e.what()).find("option -o"), std::string::npos);
        EXPECT_NE(std::string(e.what()).find("has a frame pattern"), std::string::npos);
        EXPECT_EQ(std::string(e.what()).find("-frame"), std::string::npos);
    }
}

TEST(FramePattern, Detection) {
    EXPECT_TRUE(has_frame_pattern("a.%04d.ptc"));
    EXPECT_TRUE(has_frame_pattern("a.####.ptc"));
    EXPECT_TRUE(has_frame_pattern("a.$F4.ptc"));
    EXPECT_TRUE(has_frame_pattern("a.#.ptc"));
    EXPECT_FALSE(has_frame_pattern("a.ptc"));
    EXPECT_FALSE(has_frame_pattern("100%%d.ptc"));
}

TEST(FramePattern, WiderThanSixteenDigitsIsKeptAsWritten) {
    // sss-farm applies the same bound (tests/farm/test_farm_hostile.sh).
    const std::string hashes16(16, '#'), hashes17(17, '#');
    EXPECT_EQ(expand_frame_pattern("a." + hashes16, 7), "a.0000000000000007");
    EXPECT_EQ(expand_frame_pattern("a." + hashes17 + ".%02d", 7),
              "a." + hashes17 + ".07");
    EXPECT_EQ(expand_frame_pattern("a.%016d", 7), "a.0000000000000007");
    EXPECT_EQ(expand_frame_pattern("a.%017d", 7), "a.%017d");
    EXPECT_EQ(expand_frame_pattern("a.$F17.${F99999999999999999999}", 7),
              "a.$F17.${F99999999999999999999}");
    EXPECT_EQ(expand_frame_pattern("a.%099999999999999999999d", 7),
              "a.%099999999999999999999d");
    EXPECT_FALSE(has_frame_pattern("a." + hashes17 + ".ptc"));
    EXPECT_EQ(expand_frame_pattern("a." + std::string(100000, '#'), std::nullopt),
              "a." + std::string(100000, '#'));
}
