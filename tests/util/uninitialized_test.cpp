// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// UninitVector: a std::vector in every respect except that resize() leaves
// trivial elements uninitialised (not observable here); what is observable
// must still hold: values given are kept, elements built with arguments are
// built with them, class types run their constructors, copies and moves work.

#include <string>
#include <utility>

#include <gtest/gtest.h>

#include "sss/util/uninitialized.h"

namespace {

struct Counted {
    static inline int built = 0;
    int value = 42; // a default member initialiser runs under default-init
    Counted() { ++built; }
    explicit Counted(int v) : value(v) { ++built; }
};

} // namespace

TEST(UninitVector, KeepsValuesAndArguments) {
    sss::UninitVector<int> v(3, 7);
    ASSERT_EQ(v.size(), 3u);
    for (int x : v) EXPECT_EQ(x, 7);
    v.resize(5); // the two new ints are unspecified; the old ones stay
    ASSERT_EQ(v.size(), 5u);
    for (int i = 0; i < 3; ++i) EXPECT_EQ(v[i], 7);
    v[3] = 1;
    v[4] = 2;
    v.emplace_back(9);
    v.push_back(10);
    EXPECT_EQ(v[5], 9);
    EXPECT_EQ(v[6], 10);
    v.resize(8, 5); // an explicit value is a value
    EXPECT_EQ(v[7], 5);
}

TEST(UninitVector, ClassTypesAreConstructed) {
    Counted::built = 0;
    sss::UninitVector<Counted> v(4);
    EXPECT_EQ(Counted::built, 4);
    for (const Counted& c : v) EXPECT_EQ(c.value, 42);
    v.emplace_back(3);
    EXPECT_EQ(v.back().value, 3);
    sss::UninitVector<std::string> s(2);
    EXPECT_TRUE(s[0].empty());
    s[1] = "kept";
    sss::UninitVector<std::string> copy = s;
    sss::UninitVector<std::string> moved = std::move(s);
    EXPECT_EQ(copy[1], "kept");
    EXPECT_EQ(moved[1], "kept");
}
