// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// JSON string quoting (sloinfo -json, ptview -serve).

#include <string>

#include <gtest/gtest.h>

#include "sss/util/json.h"

namespace {

TEST(JsonQuote, EscapesQuotesBackslashesAndControlCharacters) {
    EXPECT_EQ(sss::json_quote(""), "\"\"");
    EXPECT_EQ(sss::json_quote("plain text"), "\"plain text\"");
    EXPECT_EQ(sss::json_quote("a \"b\" c\\d"), "\"a \\\"b\\\" c\\\\d\"");
    EXPECT_EQ(sss::json_quote("tab\there\nnew\rline"),
              "\"tab\\u0009here\\u000anew\\u000dline\"");
    EXPECT_EQ(sss::json_quote(std::string("nul\0end", 7)), "\"nul\\u0000end\"");
    EXPECT_EQ(sss::json_quote("\x1f\x7f"), "\"\\u001f\x7f\"");
}

TEST(JsonQuote, Utf8PassesThrough) {
    EXPECT_EQ(sss::json_quote("marbre \xc3\xa9t\xc3\xa9 \xe2\x86\x92 \xf0\x9f\x8e\xa8"),
              "\"marbre \xc3\xa9t\xc3\xa9 \xe2\x86\x92 \xf0\x9f\x8e\xa8\"");
}

} // namespace
