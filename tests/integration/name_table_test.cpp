// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file name_table_test.cpp
/// Tests of NameTable (sss/util/name_table.h) and of the tables built on it.

#include <gtest/gtest.h>

#include "sss/cloud/point_cloud.h"
#include "sss/util/name_table.h"

namespace {

enum class Fruit { Apple, Pear, Plum };

constexpr sss::NameTable<Fruit, 4> kFruits({{{Fruit::Apple, "apple"},
                                             {Fruit::Pear, "pear"},
                                             {Fruit::Apple, "malus"}, // alias
                                             {Fruit::Plum, "plum"}}});

} // namespace

TEST(NameTable, NameIsTheFirstEntryOfAValue) {
    EXPECT_STREQ(kFruits.name(Fruit::Apple), "apple");
    EXPECT_STREQ(kFruits.name(Fruit::Plum), "plum");
    EXPECT_STREQ(kFruits.name(static_cast<Fruit>(42)), "?");
}

TEST(NameTable, ParseTakesNamesAndAliasesExactly) {
    EXPECT_EQ(kFruits.parse("pear"), Fruit::Pear);
    EXPECT_EQ(kFruits.parse("malus"), Fruit::Apple);
    EXPECT_FALSE(kFruits.parse("Pear").has_value());
    EXPECT_FALSE(kFruits.parse("").has_value());
    EXPECT_FALSE(kFruits.parse("pears").has_value());
}

TEST(NameTable, ListNamesEveryEntry) {
    EXPECT_EQ(kFruits.list(), "apple, pear, malus, plum");
}

TEST(NameTable, UsableAtCompileTime) {
    static_assert(kFruits.parse("plum") == Fruit::Plum);
    static_assert(!kFruits.parse("fig").has_value());
}

TEST(NameTable, ChannelTypesRoundTrip) {
    for (sss::ChannelType t :
         {sss::ChannelType::Float, sss::ChannelType::Color, sss::ChannelType::Point,
          sss::ChannelType::Vector, sss::ChannelType::Normal, sss::ChannelType::Matrix})
        EXPECT_EQ(sss::parse_channel_type(sss::channel_type_name(t)), t);
    EXPECT_STREQ(sss::channel_type_name(sss::ChannelType::Color), "color");
    EXPECT_FALSE(sss::parse_channel_type("colour").has_value());
}
