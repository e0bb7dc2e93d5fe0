// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// Messages: input echoed on one line, quoted and cut; warnings counted by
// kind (a flood keeps a few strings); the standard output error state.

#include <gtest/gtest.h>

#include <string>

#include "sss/util/messages.h"

namespace {

TEST(Messages, EscapeControlKeepsEveryMessageOnOneLine) {
    EXPECT_EQ(sss::escape_control("a\nb"), "a\\nb");
    EXPECT_EQ(sss::escape_control("tab\there\r\x01\x7f"), "tab\\x09here\\x0d\\x01\\x7f");
    EXPECT_EQ(sss::escape_control("caf\xc3\xa9"), "caf\xc3\xa9"); // UTF-8 kept
    EXPECT_EQ(sss::escape_control(std::string("nul\0x", 5)), "nul\\x00x");
}

TEST(Messages, QuotedTruncatesLongEchoes) {
    EXPECT_EQ(sss::quoted("foo\nbar"), "\"foo\\nbar\"");
    const std::string long_name(100000, 'x');
    const std::string q = sss::quoted(long_name);
    EXPECT_EQ(q.size(), 1 + sss::kMaxEcho + 3 + 1);
    EXPECT_EQ(q.substr(q.size() - 4), "...\"");
    // A cut never splits a UTF-8 sequence.
    std::string accents;
    for (int i = 0; i < 150; ++i) accents += "\xc3\xa9";
    const std::string t = sss::truncated(accents, 201);
    EXPECT_EQ(t.size(), 200u + 3u);
}

TEST(Messages, KindsIgnoreLocationNumbersAndQuotedParts) {
    using sss::Warnings;
    EXPECT_EQ(Warnings::without_location("a.rib:12: TransformBegin is never closed"),
              "TransformBegin is never closed");
    EXPECT_EQ(Warnings::without_location("c.obj: no faces, nothing imported"),
              "no faces, nothing imported");
    EXPECT_EQ(Warnings::without_location("Surface: not a location"),
              "Surface: not a location");
    EXPECT_EQ(Warnings::kind_of("a.rib:1: unknown light shader 'x', ignored"),
              Warnings::kind_of("b.rib:9: unknown light shader 'yy', ignored"));
    EXPECT_EQ(Warnings::kind_of("12 samples were NaN"),
              Warnings::kind_of("3 samples were NaN"));
    EXPECT_NE(Warnings::kind_of("x is never closed"),
              Warnings::kind_of("y is never closed"));
}

TEST(Messages, WarningsKeepAFewOfEachKindAndCountTheRest) {
    sss::Warnings w;
    for (int i = 0; i < 100000; ++i)
        w.push_back("f.rib:" + std::to_string(i + 3) +
                    ": TransformBegin is never closed");
    w.push_back("f.rib:1: something else");
    EXPECT_EQ(w.size(), sss::Warnings::kKeptPerKind + 1);
    EXPECT_EQ(w.total(), 100001u);
    EXPECT_EQ(w[0], "f.rib:3: TransformBegin is never closed");
    EXPECT_EQ(w.back(), "f.rib:1: something else");
    ASSERT_EQ(w.summaries().size(), 1u);
    EXPECT_EQ(w.summaries()[0],
              "99995 more warnings like \"TransformBegin is never closed\" not shown");

    // Explicit kinds group texts that differ.
    sss::Warnings u;
    for (int i = 0; i < 7; ++i)
        u.add("unknown statement",
              "f.rib:1: unknown statement Foo" + std::string(i, 'x'));
    EXPECT_EQ(u.size(), 5u);
    EXPECT_EQ(u.summaries().at(0),
              "2 more warnings like \"unknown statement\" not shown");

    // Appending keeps kinds and counts.
    sss::Warnings all;
    all.append(w);
    all.append(u);
    EXPECT_EQ(all.total(), w.total() + u.total());
    EXPECT_EQ(all.size(), w.size() + u.size());
    EXPECT_EQ(all.summaries().size(), 2u);
}

TEST(Messages, StandardOutputErrorIsEmptyWhenWritable) {
    // The test binary's stdout is a terminal, a file or a pipe that reads.
    EXPECT_TRUE(sss::flush_standard_output());
    EXPECT_EQ(sss::standard_output_error(), "");
    EXPECT_NO_THROW(sss::check_standard_output());
    EXPECT_EQ(std::string(sss::StandardOutputError("No space left on device").what()),
              "cannot write to standard output: No space left on device");
}

} // namespace

TEST(Messages, EditDistanceCountsSwapsAsOneStep) {
    EXPECT_EQ(sss::edit_distance("", ""), 0u);
    EXPECT_EQ(sss::edit_distance("abc", ""), 3u);
    EXPECT_EQ(sss::edit_distance("", "abc"), 3u);
    EXPECT_EQ(sss::edit_distance("material", "material"), 0u);
    EXPECT_EQ(sss::edit_distance("materail", "material"), 1u); // swap
    EXPECT_EQ(sss::edit_distance("skin11", "skin1"), 1u);      // insertion
    EXPECT_EQ(sss::edit_distance("kitten", "sitting"), 3u);
    EXPECT_EQ(sss::edit_distance("ca", "abc"), 3u); // OSA: no edit of a swapped pair
    EXPECT_EQ(sss::edit_distance("tread", "threads"), 2u);
}

TEST(Messages, ClosestMatchOnlyWhenClose) {
    const std::vector<std::string> options = {"material", "maxerror", "threads",
                                              "o",        "help",     "progress"};
    EXPECT_EQ(sss::closest_match("materail", options), "material");
    EXPECT_EQ(sss::closest_match("Material", options), "material"); // case ignored
    EXPECT_EQ(sss::closest_match("thread", options), "threads");
    EXPECT_EQ(sss::closest_match("progres", options), "progress");
    // Nothing close: no guess.
    EXPECT_EQ(sss::closest_match("bogus", options), "");
    EXPECT_EQ(sss::closest_match("x", options), ""); // one letter is never guessed
    EXPECT_EQ(sss::closest_match("mat", options), "");
    EXPECT_EQ(sss::closest_match("", options), "");
    EXPECT_EQ(sss::closest_match("material", {}), "");
    // The nearest wins, then the first of equals.
    EXPECT_EQ(sss::closest_match("skin3", {"skin1", "skin2"}), "skin1");
    EXPECT_EQ(sss::closest_match("skin22", {"skin1", "skin2"}), "skin2");
}
