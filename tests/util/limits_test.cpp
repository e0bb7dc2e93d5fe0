// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// Tests of the resource limits, the memory budget and the stages.

#include <gtest/gtest.h>

#include <cstdlib>
#include <stdexcept>

#include "sss/util/limits.h"

namespace {

TEST(Limits, DefaultsEnvironmentAndOverride) {
    using sss::Limit;
    unsetenv("SSS_LIMIT_PRIMITIVE_VERTICES");
    EXPECT_EQ(sss::limit(Limit::PrimitiveVertices),
              sss::limit_default(Limit::PrimitiveVertices));
    setenv("SSS_LIMIT_PRIMITIVE_VERTICES", "2K", 1);
    EXPECT_EQ(sss::limit(Limit::PrimitiveVertices), 2048u);
    setenv("SSS_LIMIT_PRIMITIVE_VERTICES", "1e3", 1);
    EXPECT_EQ(sss::limit(Limit::PrimitiveVertices), 1000u);
    setenv("SSS_LIMIT_PRIMITIVE_VERTICES", "lots", 1);
    EXPECT_THROW(sss::limit(Limit::PrimitiveVertices), sss::UsageError);
    setenv("SSS_LIMIT_PRIMITIVE_VERTICES", "-3", 1);
    EXPECT_THROW(sss::limit(Limit::PrimitiveVertices), sss::UsageError);
    sss::set_limit(Limit::PrimitiveVertices, 7);
    EXPECT_EQ(sss::limit(Limit::PrimitiveVertices), 7u);
    sss::set_limit(Limit::PrimitiveVertices, 0);
    unsetenv("SSS_LIMIT_PRIMITIVE_VERTICES");
}

TEST(Limits, ErrorNamesWhereWhatAndVariable) {
    using sss::Limit;
    sss::set_limit(Limit::ArchiveDepth, 4);
    EXPECT_NO_THROW(sss::check_limit(Limit::ArchiveDepth, 4, "a.rib:3"));
    try {
        sss::check_limit(Limit::ArchiveDepth, 5, "a.rib:3");
        FAIL() << "no LimitError";
    } catch (const sss::LimitError& e) {
        std::string what = e.what();
        EXPECT_NE(
            what.find("a.rib:3: 5 levels of nested archives exceeds the limit of 4"),
            std::string::npos)
            << what;
        EXPECT_NE(what.find("SSS_LIMIT_ARCHIVE_DEPTH"), std::string::npos) << what;
        EXPECT_EQ(e.which(), Limit::ArchiveDepth);
    }
    sss::set_limit(Limit::ArchiveDepth, 0);
}

TEST(Memory, BudgetAndCheck) {
    setenv("SSS_MEMORY_LIMIT", "64M", 1);
    sss::MemoryBudget budget = sss::usable_memory();
    EXPECT_LE(budget.bytes, 64u << 20);
    EXPECT_FALSE(budget.source.empty());
    try {
        sss::check_memory(uint64_t(1) << 40, "dicing x.rib", "raise -spacing");
        FAIL() << "no OutOfMemoryError";
    } catch (const sss::OutOfMemoryError& e) {
        std::string what = e.what();
        EXPECT_NE(what.find("dicing x.rib needs about"), std::string::npos) << what;
        EXPECT_NE(what.find("raise -spacing"), std::string::npos) << what;
    }
    unsetenv("SSS_MEMORY_LIMIT");
    EXPECT_NO_THROW(sss::check_memory(1 << 20, "a little", ""));
    EXPECT_GT(sss::resident_memory(), 0u);
    EXPECT_EQ(sss::format_bytes(1536), "1.5 KB");
    EXPECT_EQ(sss::format_bytes(12), "12 bytes");
}

TEST(Stages, NestAndRememberWhereAnExceptionLeft) {
    EXPECT_EQ(sss::current_stage(), "");
    {
        sss::ScopedStage outer("reading a.rib");
        {
            sss::ScopedStage inner("dicing a.rib");
            EXPECT_EQ(sss::current_stage(), "dicing a.rib");
        }
        EXPECT_EQ(sss::current_stage(), "reading a.rib");
    }
    try {
        sss::ScopedStage outer("rendering");
        sss::ScopedStage inner("shading grid 3");
        throw std::runtime_error("x");
    } catch (const std::exception&) {
        EXPECT_EQ(sss::failure_stage(), "shading grid 3");
    }
}

} // namespace
