// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file slo_info_test.cpp
/// sloinfo's descriptions (slo_info.h): PRMan's layout line by line, and
/// JSON whose strings are escaped (quotes, backslashes, control bytes).

#include <gtest/gtest.h>

#include <string>

#include "rsl_test_util.h"
#include "sss/rsl/slo_info.h"

namespace {

using namespace sss;
using sss::test::compile_one;

TEST(SloInfo, PrmanLayout) {
    const Program p = compile_one(R"(
displacement d(float Km = 0.25; output varying float h = 0; matrix m = 1;) {
    P += Km * N;
}
)");
    EXPECT_EQ(describe_shader(p),
              "displacement \"d\"\n"
              "    \"Km\" \"parameter uniform float\"\n"
              "\t\tDefault value: 0.25\n"
              "    \"h\" \"output parameter varying float\"\n"
              "\t\tDefault value: 0\n"
              "    \"m\" \"parameter uniform matrix\"\n"
              "\t\tDefault value: \"current\" [1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1]\n");
}

TEST(SloInfo, JsonEscapesStrings) {
    const Program p = compile_one(R"(
surface s(string a = "say \"hi\"\n\\";) { Ci = 1; }
)");
    EXPECT_EQ(describe_shader_json(p, "d\\s.slo"),
              "{\"file\": \"d\\\\s.slo\", \"type\": \"surface\", \"name\": \"s\", "
              "\"parameters\": [{\"name\": \"a\", \"storage\": \"uniform\", \"type\": "
              "\"string\", \"array\": 0, \"output\": false, \"default\": "
              "[\"say \\\"hi\\\"\\u000a\\\\\"]}]}");
}

} // namespace

namespace {

// sloinfo names volume and imager shaders by their type, as PRMan's does.
TEST(SloInfo, VolumeAndImagerTypes) {
    using namespace sss;
    const Program v = sss::test::compile_one(
        "volume fog(float distance = 1; color background = 0;) { Ci = background; }");
    EXPECT_EQ(describe_shader(v), "volume \"fog\"\n"
                                  "    \"distance\" \"parameter uniform float\"\n"
                                  "\t\tDefault value: 1\n"
                                  "    \"background\" \"parameter uniform color\"\n"
                                  "\t\tDefault value: \"rgb\" [0 0 0]\n");
    const Program i = sss::test::compile_one(
        "imager background(color bgcolor = 1;) { Ci += (1 - alpha) * bgcolor; }");
    EXPECT_EQ(describe_shader(i).rfind("imager \"background\"\n", 0), 0u);
    EXPECT_NE(describe_shader_json(i, "background.slo").find("\"type\": \"imager\""),
              std::string::npos);
}

} // namespace
