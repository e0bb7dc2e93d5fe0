// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// Tests of the instruction-set choice (sss/util/isa.h).

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "sss/util/error.h"
#include "sss/util/isa.h"

namespace {

// Sets (or unsets) SSS_ISA for one test and restores it.
class IsaEnv {
public:
    explicit IsaEnv(const char* value) {
        if (const char* old = std::getenv("SSS_ISA")) m_old = old, m_had = true;
        if (value)
            setenv("SSS_ISA", value, 1);
        else
            unsetenv("SSS_ISA");
    }
    ~IsaEnv() {
        if (m_had)
            setenv("SSS_ISA", m_old.c_str(), 1);
        else
            unsetenv("SSS_ISA");
    }

private:
    std::string m_old;
    bool m_had = false;
};

} // namespace

TEST(Isa, NamesRoundTrip) {
    for (sss::Isa isa :
         {sss::Isa::Auto, sss::Isa::X86_64, sss::Isa::Avx2, sss::Isa::Avx512})
        EXPECT_EQ(sss::parse_isa(sss::isa_name(isa), "test"), isa);
    EXPECT_EQ(sss::parse_isa("sse2", "test"), sss::Isa::X86_64);
    EXPECT_EQ(sss::parse_isa("x86-64-v3", "test"), sss::Isa::Avx2);
    EXPECT_EQ(sss::parse_isa("x86-64-v4", "test"), sss::Isa::Avx512);
    try {
        sss::parse_isa("avx3", "SSS_ISA");
        FAIL() << "no error";
    } catch (const sss::UsageError& e) {
        EXPECT_NE(std::string(e.what()).find("SSS_ISA: unknown instruction set 'avx3'"),
                  std::string::npos)
            << e.what();
    }
}

TEST(Isa, BaselineAlwaysSupportedAndBestIsSupported) {
    EXPECT_TRUE(sss::isa_supported(sss::Isa::X86_64));
    EXPECT_TRUE(sss::isa_supported(sss::best_isa()));
    auto all = sss::supported_isas();
    ASSERT_FALSE(all.empty());
    EXPECT_EQ(all.front(), sss::Isa::X86_64);
    EXPECT_EQ(all.back(), sss::best_isa());
    // AVX-512 here implies AVX2.
    if (sss::isa_supported(sss::Isa::Avx512)) {
        EXPECT_TRUE(sss::isa_supported(sss::Isa::Avx2));
    }
}

TEST(Isa, ResolveFollowsTheEnvironment) {
    {
        IsaEnv env(nullptr);
        EXPECT_EQ(sss::resolve_isa(), sss::best_isa());
    }
    {
        IsaEnv env("x86-64");
        EXPECT_EQ(sss::resolve_isa(), sss::Isa::X86_64);
        // An explicit request wins over the environment.
        EXPECT_EQ(sss::resolve_isa(sss::best_isa()), sss::best_isa());
    }
    {
        IsaEnv env("auto");
        EXPECT_EQ(sss::resolve_isa(), sss::best_isa());
    }
    {
        IsaEnv env("bogus");
        EXPECT_THROW(sss::resolve_isa(), sss::UsageError);
    }
    // A path this CPU lacks is refused, never replaced by another.
    for (sss::Isa isa : {sss::Isa::Avx2, sss::Isa::Avx512})
        if (!sss::isa_supported(isa)) {
            EXPECT_THROW(sss::resolve_isa(isa), sss::UsageError);
        }
}

TEST(Isa, RequestedNamesThePathWithoutAskingTheCpu) {
    {
        IsaEnv env(nullptr);
        EXPECT_EQ(sss::requested_isa(), sss::Isa::Auto);
        EXPECT_EQ(sss::requested_isa(sss::Isa::Avx512), sss::Isa::Avx512);
    }
    {
        IsaEnv env("avx512");
        // Whatever this CPU has: a submit host checks a farm node's path.
        EXPECT_EQ(sss::requested_isa(), sss::Isa::Avx512);
        EXPECT_EQ(sss::requested_isa(sss::Isa::X86_64), sss::Isa::X86_64);
    }
    {
        IsaEnv env("auto");
        EXPECT_EQ(sss::requested_isa(), sss::Isa::Auto);
    }
    {
        IsaEnv env("bogus");
        EXPECT_THROW(sss::requested_isa(), sss::UsageError);
    }
}
