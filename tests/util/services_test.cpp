// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file services_test.cpp
/// Tests of the runtime services every stage uses (sss/util): thread counts,
/// progress lines, atomic output files and their signal cleanup, the stopwatch,
/// the errno an IoError carries.

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <filesystem>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <oneapi/tbb/global_control.h>

#include "sss/util/atomic_output.h"
#include "sss/util/byte_io.h"
#include "sss/util/error.h"
#include "sss/util/progress.h"
#include "sss/util/threads.h"
#include "test_util.h"

namespace fs = std::filesystem;

namespace {

using TempFolder = sss::test::TempDir;
using sss::test::read_text;
using sss::test::split_lines;
using sss::test::write_text;

} // namespace

// ---------------------------------------------------------------------------
// Threads
// ---------------------------------------------------------------------------

TEST(Threads, ResolveThreadCount) {
    const int usable = sss::resolve_thread_count(0);
    EXPECT_GE(usable, 1);
    EXPECT_LE(usable,
              static_cast<int>(std::max(1u, std::thread::hardware_concurrency())));
    EXPECT_EQ(sss::resolve_thread_count(1), 1);
    EXPECT_EQ(sss::resolve_thread_count(7), 7);
    EXPECT_EQ(sss::resolve_thread_count(1000), 1000);
    EXPECT_EQ(sss::resolve_thread_count(-1), std::max(1, usable - 1));
    EXPECT_EQ(sss::resolve_thread_count(-1000), 1);
    EXPECT_EQ(sss::resolve_thread_count(std::numeric_limits<int>::min()), 1);
}

TEST(Threads, ThreadLimitScopesTbbParallelism) {
    using oneapi::tbb::global_control;
    const auto before =
        global_control::active_value(global_control::max_allowed_parallelism);
    {
        sss::ThreadLimit limit(1);
        EXPECT_EQ(global_control::active_value(global_control::max_allowed_parallelism),
                  1u);
    }
    EXPECT_EQ(global_control::active_value(global_control::max_allowed_parallelism),
              before);
}

// ---------------------------------------------------------------------------
// Progress
// ---------------------------------------------------------------------------

TEST(Progress, PrintsEachPercentOnceAndMonotone) {
    testing::internal::CaptureStdout();
    {
        sss::Progress progress(true);
        progress.update(0, 200);   // 0%
        progress.update(1, 200);   // still 0%
        progress.update(3, 200);   // 1%
        progress.update(2, 200);   // going back: nothing
        progress.update(100, 200); // 50%
        progress.update(100, 200); // same: nothing
        progress.update(199, 200); // 99%
        progress.finish();         // 100%
        progress.finish();         // already printed
        progress.update(500, 200); // clamped to 100, already printed
    }
    std::string out = testing::internal::GetCapturedStdout();
    EXPECT_EQ(out, "ALF_PROGRESS 0%\nALF_PROGRESS 1%\nALF_PROGRESS 50%\n"
                   "ALF_PROGRESS 99%\nALF_PROGRESS 100%\n");
}

TEST(Progress, DisabledPrintsNothing) {
    testing::internal::CaptureStdout();
    sss::Progress progress(false);
    EXPECT_FALSE(progress.enabled());
    progress.update(5, 10);
    progress.finish();
    EXPECT_EQ(testing::internal::GetCapturedStdout(), "");
}

TEST(Progress, ZeroTotalIsDone) {
    testing::internal::CaptureStdout();
    sss::Progress progress(true);
    progress.update(0, 0);
    progress.finish();
    EXPECT_EQ(testing::internal::GetCapturedStdout(), "ALF_PROGRESS 100%\n");
}

TEST(Progress, ThreadSafe) {
    testing::internal::CaptureStdout();
    {
        sss::Progress progress(true);
        constexpr uint64_t total = 100000;
        std::atomic<uint64_t> done{0};
        std::vector<std::thread> threads;
        for (int t = 0; t < 4; ++t) {
            threads.emplace_back([&] {
                for (;;) {
                    uint64_t d = done.fetch_add(1) + 1;
                    if (d > total) break;
                    progress.update(d, total);
                }
            });
        }
        for (auto& t : threads) t.join();
        progress.finish();
    }
    std::vector<std::string> lines = split_lines(testing::internal::GetCapturedStdout());
    ASSERT_FALSE(lines.empty());
    int last = -1;
    for (const auto& line : lines) {
        ASSERT_EQ(line.rfind("ALF_PROGRESS ", 0), 0u) << line;
        ASSERT_EQ(line.back(), '%') << line;
        int pct = std::stoi(line.substr(13));
        EXPECT_GT(pct, last) << "lines must be strictly increasing";
        EXPECT_LE(pct, 100);
        last = pct;
    }
    EXPECT_EQ(last, 100);
}

TEST(Progress, NoTerminalOffATerminal) {
    // ctest's stderr is a file or a pipe: the terminal line stays off, and
    // nothing reaches stderr.
    testing::internal::CaptureStderr();
    {
        sss::Progress progress(false);
        progress.show_on_terminal("tool");
        EXPECT_FALSE(progress.on_terminal());
        progress.update(5, 10);
        progress.finish();
    }
    EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
}

TEST(Progress, TerminalLineText) {
    EXPECT_EQ(sss::progress_line("ptfilter", "evaluating the diffusion", 43, 1234567.0,
                                 "points", 63.4, 80),
              "ptfilter: evaluating the diffusion   43%  1.23 M points/s  1:05 left");
    // No unit: no rate; no estimate: no time left; hours.
    EXPECT_EQ(sss::progress_line("render", "rendering", 7, 10.0, "", -1.0, 80),
              "render: rendering    7%");
    // Rounded up to a step that grows with the time (a minute beyond an
    // hour), never "0:00" while the work runs.
    EXPECT_EQ(sss::progress_line("ptbake", "baking", 100, 512.0, "points", 3725.0, 80),
              "ptbake: baking  100%  512 points/s  1:03:00 left");
    EXPECT_EQ(sss::progress_line("brickmake", "b", 50, 2500.0, "lookups", 0.4, 80),
              "brickmake: b   50%  2.5 k lookups/s  0:01 left");
}

TEST(Progress, TerminalLineNeverWraps) {
    // The stage gives way first, then the whole line: \r only returns to the
    // start of the last row, so a wrapped line would scroll the terminal.
    const std::string stage =
        "reading /a/very/long/path/to/a/point/cloud/that/goes/on.ptc";
    const std::string line =
        sss::progress_line("ptfilter", stage, 12, 1e6, "points", 30.0, 60);
    EXPECT_LE(line.size(), 60u);
    EXPECT_EQ(line.rfind("ptfilter: reading /a/", 0), 0u) << line;
    EXPECT_NE(line.find("...   12%  1.00 M points/s  0:30 left"), std::string::npos)
        << line;
    EXPECT_LE(sss::progress_line("ptfilter", stage, 12, 1e6, "points", 30.0, 20).size(),
              20u);
}

// ---------------------------------------------------------------------------
// AtomicOutput
// ---------------------------------------------------------------------------

TEST(AtomicOutput, TempNameInTargetFolder) {
    TempFolder dir;
    const std::string target = (dir.path() / "cloud.ptc").string();
    sss::AtomicOutput out(target);
    EXPECT_EQ(out.target(), target);
    fs::path temp(out.temp_path());
    EXPECT_EQ(temp.parent_path(), dir.path());
    // ".cloud.ptc.<host>.<pid>.<8 random>.tmp"
    const std::string name = temp.filename().string();
    EXPECT_EQ(name.rfind(".cloud.ptc.", 0), 0u) << name;
    const std::string pid = "." + std::to_string(::getpid()) + ".";
    const std::size_t at = name.rfind(pid);
    ASSERT_NE(at, std::string::npos) << name;
    EXPECT_GT(at, std::string(".cloud.ptc").size()) << "a host name before the pid";
    EXPECT_EQ(name.size(), at + pid.size() + 8 + 4) << name;
    EXPECT_EQ(name.substr(name.size() - 4), ".tmp");
    EXPECT_TRUE(fs::exists(temp)) << "the temporary name is reserved on creation";

    sss::AtomicOutput other(target);
    EXPECT_NE(other.temp_path(), out.temp_path());
}

TEST(AtomicOutput, CommitLeavesOnlyTheTarget) {
    TempFolder dir;
    const std::string target = (dir.path() / "a.ptc").string();
    {
        sss::AtomicOutput out(target);
        write_text(out.temp_path(), "hello");
        EXPECT_FALSE(fs::exists(target));
        out.commit();
        EXPECT_FALSE(fs::exists(out.temp_path()));
    }
    EXPECT_EQ(read_text(target), "hello");
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"a.ptc"});
}

TEST(AtomicOutput, UncommittedLeavesTargetUntouched) {
    TempFolder dir;
    const std::string target = (dir.path() / "a.ptc").string();
    write_text(target, "old");
    std::string temp;
    try {
        sss::AtomicOutput out(target);
        temp = out.temp_path();
        write_text(temp, "partial");
        throw std::runtime_error("writer failed");
    } catch (const std::runtime_error&) {
    }
    EXPECT_FALSE(temp.empty());
    EXPECT_FALSE(fs::exists(temp));
    EXPECT_EQ(read_text(target), "old");
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"a.ptc"});

    // Also without any existing target.
    const std::string fresh = (dir.path() / "b.ptc").string();
    { sss::AtomicOutput out(fresh); }
    EXPECT_FALSE(fs::exists(fresh));
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"a.ptc"});
}

TEST(AtomicOutput, CommitReplacesExistingFile) {
    TempFolder dir;
    const std::string target = (dir.path() / "a.ply").string();
    write_text(target, "old content that is longer");
    sss::AtomicOutput out(target);
    write_text(out.temp_path(), "new");
    out.commit();
    out.commit(); // second commit is a no-op
    EXPECT_EQ(read_text(target), "new");
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"a.ply"});
}

TEST(AtomicOutput, MissingFolderIsIoError) {
    TempFolder dir;
    const std::string target = (dir.path() / "missing" / "a.ptc").string();
    try {
        sss::AtomicOutput out(target);
        FAIL() << "expected IoError";
    } catch (const sss::IoError& e) {
        EXPECT_EQ(e.path(), target);
        EXPECT_NE(std::string(e.what()).find("No such file or directory"),
                  std::string::npos)
            << e.what();
        EXPECT_EQ(e.error_number(), ENOENT);
    }
    EXPECT_TRUE(dir.entries().empty());
}

TEST(ByteSource, MissingFileAndFolderCarryTheirErrno) {
    TempFolder dir;
    const std::string missing = (dir.path() / "missing.ptc").string();
    try {
        sss::detail::ByteSource in(missing);
        FAIL() << "expected IoError";
    } catch (const sss::IoError& e) {
        EXPECT_EQ(e.path(), missing);
        EXPECT_EQ(e.error_number(), ENOENT) << e.what();
    }
    try {
        sss::detail::ByteSource in(dir.path().string());
        FAIL() << "expected IoError";
    } catch (const sss::IoError& e) {
        EXPECT_EQ(e.error_number(), EISDIR) << e.what();
    }
}

TEST(AtomicOutput, FolderTargetIsRefusedAtOnce) {
    TempFolder dir;
    const fs::path target = dir.path() / "sub";
    fs::create_directories(target / "x");
    try {
        sss::AtomicOutput out(target.string());
        FAIL() << "expected IoError";
    } catch (const sss::IoError& e) {
        EXPECT_NE(std::string(e.what()).find("is a directory"), std::string::npos)
            << e.what();
        EXPECT_EQ(e.error_number(), EISDIR);
    }
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"sub"}) << "no temporary made";
}

// ---------------------------------------------------------------------------
// Stopwatch
// ---------------------------------------------------------------------------

TEST(Stopwatch, Monotone) {
    sss::Stopwatch watch;
    double a = watch.seconds();
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    double b = watch.seconds();
    EXPECT_GE(a, 0.0);
    EXPECT_GE(b - a, 0.015);
    EXPECT_LT(b, 10.0);
}
