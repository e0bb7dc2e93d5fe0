// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file tool_test.cpp
/// Tests of the command-line layer (sss/cli): option scanning, run_tool's
/// error handling and exit codes, --version and the -newer test.

#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <new>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "sss/cli/tool.h"
#include "sss/diffusion/material.h"
#include "sss/util/error.h"
#include "sss/util/frame_pattern.h"
#include "test_util.h"

namespace fs = std::filesystem;

namespace {

using TempFolder = sss::test::TempDir;
using sss::test::read_text;
using sss::test::split_lines;
using sss::test::write_text;

sss::ArgScanner scanner(std::vector<std::string> words) {
    return sss::ArgScanner(std::move(words));
}

/// Expects `f` to throw UsageError whose message contains every `parts`.
template <typename F>
void expect_usage_error(F&& f, std::initializer_list<std::string> parts) {
    try {
        f();
        ADD_FAILURE() << "no UsageError thrown";
    } catch (const sss::UsageError& e) {
        std::string what = e.what();
        for (const auto& part : parts)
            EXPECT_NE(what.find(part), std::string::npos)
                << "message '" << what << "' lacks '" << part << "'";
    }
}

} // namespace

// ---------------------------------------------------------------------------
// ArgScanner
// ---------------------------------------------------------------------------

TEST(ArgScanner, OptionsAndPositionals) {
    auto scan = scanner({"-size", "2", "--threads", "4", "in.ptc", "-", "out.ptc"});
    ASSERT_TRUE(scan.at_option());
    EXPECT_EQ(scan.peek(), "-size");
    EXPECT_EQ(scan.option(), "size");
    EXPECT_DOUBLE_EQ(scan.number("size"), 2.0);
    EXPECT_EQ(scan.option(), "threads");
    EXPECT_EQ(scan.integer("threads", -64, 64), 4);
    EXPECT_FALSE(scan.at_option());
    EXPECT_EQ(scan.positional(), "in.ptc");
    EXPECT_FALSE(scan.at_option()) << "a lone dash is a positional (stdin/stdout)";
    EXPECT_EQ(scan.positional(), "-");
    EXPECT_EQ(scan.positional(), "out.ptc");
    EXPECT_TRUE(scan.done());
    EXPECT_EQ(scan.peek(), "");
    EXPECT_THROW(scan.positional(), sss::UsageError);
    EXPECT_THROW(scan.option(), sss::UsageError);
}

TEST(ArgScanner, NextOptionCollectsPositionals) {
    auto scan = scanner({"a.ptc", "b.ptc", "-radius", "-1.5", "c.ptc", "--v", "d.ptc"});
    std::vector<std::string> files;
    std::string opt;
    ASSERT_TRUE(scan.next_option(opt, files));
    EXPECT_EQ(opt, "radius");
    EXPECT_EQ(files, (std::vector<std::string>{"a.ptc", "b.ptc"}));
    EXPECT_DOUBLE_EQ(scan.number(opt), -1.5);
    ASSERT_TRUE(scan.next_option(opt, files));
    EXPECT_EQ(opt, "v");
    EXPECT_FALSE(scan.next_option(opt, files));
    EXPECT_EQ(files, (std::vector<std::string>{"a.ptc", "b.ptc", "c.ptc", "d.ptc"}));
    EXPECT_TRUE(scan.done());
}

TEST(ArgScanner, NegativeNumbersAreValues) {
    auto scan = scanner({"-ambient", "-0.5", "-threads", "-3", "-x", "-.25", "-1e3"});
    EXPECT_EQ(scan.option(), "ambient");
    EXPECT_FALSE(scan.at_option());
    EXPECT_DOUBLE_EQ(scan.number("ambient"), -0.5);
    EXPECT_EQ(scan.option(), "threads");
    EXPECT_FALSE(scan.at_option());
    EXPECT_EQ(scan.integer("threads", -100, 100), -3);
    EXPECT_EQ(scan.option(), "x");
    EXPECT_DOUBLE_EQ(scan.number("x"), -0.25);
    EXPECT_FALSE(scan.at_option());
    EXPECT_EQ(scan.positional(), "-1e3");
}

TEST(ArgScanner, MissingValueNamesTheOption) {
    {
        auto scan = scanner({"-size"});
        scan.option();
        expect_usage_error([&] { scan.value("size"); }, {"-size", "needs a value"});
    }
    {
        auto scan = scanner({"-size", "-n", "5"});
        scan.option();
        expect_usage_error([&] { scan.number("size"); }, {"-size", "needs a value"});
        EXPECT_EQ(scan.peek(), "-n") << "the next option is not consumed";
    }
}

TEST(ArgScanner, RejectsNonNumbers) {
    for (const char* bad : {"abc", "1.5x", "", " 1", "1 ", "nan", "NaN", "inf", "+inf",
                            "1e999", "0x10", "1,5", "+-1"}) {
        auto scan = scanner({bad});
        expect_usage_error([&] { scan.number("size"); }, {"-size", "is not a number"});
    }
    auto scan = scanner({"abc"});
    expect_usage_error([&] { scan.number("size"); },
                       {"option -size: 'abc' is not a number"});
    // "-inf" looks like an option, so it is a missing value rather than a number.
    auto neg_inf = scanner({"-inf"});
    expect_usage_error([&] { neg_inf.number("size"); }, {"-size", "needs a value"});
}

TEST(ArgScanner, AcceptsNumberForms) {
    auto scan = scanner({"1", "+2.5", "1e-3", "-7", ".5", "3."});
    EXPECT_DOUBLE_EQ(scan.number("a"), 1.0);
    EXPECT_DOUBLE_EQ(scan.number("a"), 2.5);
    EXPECT_DOUBLE_EQ(scan.number("a"), 1e-3);
    EXPECT_DOUBLE_EQ(scan.number("a"), -7.0);
    EXPECT_DOUBLE_EQ(scan.number("a"), 0.5);
    EXPECT_DOUBLE_EQ(scan.number("a"), 3.0);
}

TEST(ArgScanner, PositiveAndNonNegative) {
    auto scan = scanner({"0", "-1", "0", "2", "-0.1"});
    expect_usage_error([&] { scan.positive("size"); }, {"-size", "> 0"});
    expect_usage_error([&] { scan.positive("size"); }, {"-size", "> 0"});
    EXPECT_DOUBLE_EQ(scan.non_negative("jitter"), 0.0);
    EXPECT_DOUBLE_EQ(scan.positive("size"), 2.0);
    expect_usage_error([&] { scan.non_negative("jitter"); }, {"-jitter", ">= 0"});
}

TEST(ArgScanner, IntegerRanges) {
    auto scan = scanner({"5", "0", "10", "11", "-1", "2.5", "1e3", "x", "99999999999"});
    EXPECT_EQ(scan.integer("n", 0, 10), 5);
    EXPECT_EQ(scan.integer("n", 0, 10), 0);
    EXPECT_EQ(scan.integer("n", 0, 10), 10);
    expect_usage_error([&] { scan.integer("n", 0, 10); }, {"-n", "11", "[0, 10]"});
    expect_usage_error([&] { scan.integer("n", 0, 10); }, {"-n", "-1", "out of range"});
    expect_usage_error([&] { scan.integer("n", 0, 10); },
                       {"-n", "'2.5' is not an integer"});
    EXPECT_EQ(scan.integer("n", 0, 100000), 1000);
    expect_usage_error([&] { scan.integer("n", 0, 10); }, {"-n", "'x'"});
    expect_usage_error([&] { scan.integer("n", 0, 10); }, {"-n", "out of range"});
}

TEST(ArgScanner, Triple) {
    {
        auto scan = scanner({"-light", "1", "-2", "3.5", "out.ptc"});
        EXPECT_EQ(scan.option(), "light");
        glm::dvec3 v = scan.triple("light");
        EXPECT_EQ(v, glm::dvec3(1.0, -2.0, 3.5));
        EXPECT_EQ(scan.positional(), "out.ptc");
    }
    {
        auto scan = scanner({"1", "2"});
        expect_usage_error([&] { scan.triple("light"); }, {"-light", "needs 3 values"});
    }
    {
        auto scan = scanner({"1", "2", "-n", "4"});
        expect_usage_error([&] { scan.triple("light"); }, {"-light", "needs 3 values"});
    }
    {
        auto scan = scanner({"1", "nan", "2"});
        expect_usage_error([&] { scan.triple("lightcolor"); },
                           {"-lightcolor", "'nan' is not a number"});
    }
}

// ---------------------------------------------------------------------------
// run_tool, warn, versions
// ---------------------------------------------------------------------------

namespace {

int call_run_tool(std::vector<std::string> words,
                  const std::function<int(const std::vector<std::string>&)>& body) {
    std::vector<char*> argv;
    for (auto& w : words) argv.push_back(w.data());
    argv.push_back(nullptr);
    return sss::run_tool("mytool", static_cast<int>(words.size()), argv.data(), body);
}

} // namespace

TEST(RunTool, PassesArgumentsWithoutProgramName) {
    std::vector<std::string> seen;
    int rc = call_run_tool({"mytool", "-a", "b"}, [&](const std::vector<std::string>& a) {
        seen = a;
        return 7;
    });
    EXPECT_EQ(rc, 7);
    EXPECT_EQ(seen, (std::vector<std::string>{"-a", "b"}));
}

TEST(RunTool, UsageErrorExits2) {
    testing::internal::CaptureStderr();
    int rc =
        call_run_tool({"mytool", "-bogus"}, [](const std::vector<std::string>&) -> int {
            throw sss::UsageError("unknown option -bogus");
        });
    std::string err = testing::internal::GetCapturedStderr();
    EXPECT_EQ(rc, 2);
    EXPECT_EQ(err, "mytool ERROR: unknown option -bogus\nmytool: try 'mytool --help'\n");
}

TEST(RunTool, CheckIsTakenOutAndToldToTheBody) {
    std::vector<std::string> seen;
    bool checking = false;
    std::optional<int> frame;
    int rc = call_run_tool({"mytool", "-a", "-check", "b", "--check"},
                           [&](const std::vector<std::string>& a) {
                               seen = a;
                               checking = sss::check_only();
                               frame = sss::RunOptions().frame;
                               return 0;
                           });
    EXPECT_EQ(rc, 0);
    EXPECT_EQ(seen, (std::vector<std::string>{"-a", "b"}));
    EXPECT_TRUE(checking);
    EXPECT_EQ(frame, 0); // patterns expand without -frame under -check
    EXPECT_FALSE(sss::check_only());
    EXPECT_EQ(sss::RunOptions().frame, std::nullopt);
    call_run_tool({"mytool", "-checks"}, [&](const std::vector<std::string>& a) {
        seen = a;
        checking = sss::check_only();
        return 0;
    });
    EXPECT_EQ(seen, (std::vector<std::string>{"-checks"}));
    EXPECT_FALSE(checking);
}

TEST(RunTool, EveryErrorOfACheckExits2) {
    const auto body = [](const std::vector<std::string>&) -> int {
        throw sss::ValueError("impossible value");
    };
    testing::internal::CaptureStderr();
    const int checked = call_run_tool({"mytool", "-check"}, body);
    const int run = call_run_tool({"mytool"}, body);
    const std::string err = testing::internal::GetCapturedStderr();
    EXPECT_EQ(checked, 2);
    EXPECT_EQ(run, 1);
    EXPECT_EQ(err, "mytool ERROR: impossible value\nmytool ERROR: impossible value\n");
}

TEST(RunTool, MissingFrameNamesTheOption) {
    testing::internal::CaptureStderr();
    int rc =
        call_run_tool({"mytool", "x.####.ptc"}, [](const std::vector<std::string>& a) {
            return sss::expand_frame_pattern(a[0], std::nullopt, "file name").empty() ? 1
                                                                                      : 0;
        });
    std::string err = testing::internal::GetCapturedStderr();
    EXPECT_EQ(rc, 2);
    EXPECT_EQ(err, "mytool ERROR: file name: 'x.####.ptc' has a frame pattern; give the "
                   "frame with -frame N\nmytool: try 'mytool --help'\n");
}

TEST(RunTool, MaterialErrorsNameTheOptions) {
    sss::MaterialSpec both;
    both.scattering = glm::dvec3(1.0);
    both.albedo = glm::dvec3(0.5);
    testing::internal::CaptureStderr();
    int rc = call_run_tool({"mytool"}, [&](const std::vector<std::string>&) {
        both.validate();
        return 0;
    });
    std::string err = testing::internal::GetCapturedStderr();
    EXPECT_EQ(rc, 2);
    EXPECT_EQ(err,
              "mytool ERROR: give the material either as -scattering/-absorption or "
              "as -albedo/-diffusemeanfreepath, not both\nmytool: try 'mytool --help'\n");

    sss::MaterialSpec bright;
    bright.albedo = glm::dvec3(0.5, 1.5, 0.5);
    testing::internal::CaptureStderr();
    rc = call_run_tool({"mytool"}, [&](const std::vector<std::string>&) {
        bright.validate();
        return 0;
    });
    err = testing::internal::GetCapturedStderr();
    EXPECT_EQ(rc, 1);
    EXPECT_EQ(err, "mytool ERROR: impossible -albedo value 1.500000\n");
}

TEST(RunTool, RuntimeErrorsExit1) {
    testing::internal::CaptureStderr();
    int rc = call_run_tool({"mytool"}, [](const std::vector<std::string>&) -> int {
        throw sss::IoError("a.ptc", "No such file or directory");
    });
    std::string err = testing::internal::GetCapturedStderr();
    EXPECT_EQ(rc, 1);
    EXPECT_EQ(err, "mytool ERROR: a.ptc: No such file or directory\n");

    testing::internal::CaptureStderr();
    rc = call_run_tool({"mytool"},
                       [](const std::vector<std::string>&) -> int { throw 42; });
    err = testing::internal::GetCapturedStderr();
    EXPECT_EQ(rc, 1);
    EXPECT_NE(err.find("mytool ERROR: "), std::string::npos);
}

TEST(RunTool, WarnFormat) {
    testing::internal::CaptureStderr();
    sss::warn("mytool", "something odd");
    EXPECT_EQ(testing::internal::GetCapturedStderr(), "mytool WARNING: something odd\n");
}

TEST(RunTool, EveryMessageIsOneLine) {
    testing::internal::CaptureStderr();
    int rc = call_run_tool({"mytool"}, [](const std::vector<std::string>&) -> int {
        sss::warn("mytool", "a.rib:3: Surface \"x\ny\": odd\r");
        throw sss::ValueError("a.rib:4: Surface \"x\ny\": bad\x01");
    });
    std::string err = testing::internal::GetCapturedStderr();
    EXPECT_EQ(rc, 1);
    EXPECT_EQ(err, "mytool WARNING: a.rib:3: Surface \"x\\ny\": odd\\x0d\n"
                   "mytool ERROR: a.rib:4: Surface \"x\\ny\": bad\\x01\n");
}

TEST(RunTool, OutOfMemoryNamesTheStage) {
    testing::internal::CaptureStderr();
    int rc = call_run_tool({"mytool"}, [](const std::vector<std::string>&) -> int {
        sss::ScopedStage job("reading scene.rib");
        {
            sss::ScopedStage inner("dicing scene.rib");
            // An allocation no estimate caught (thrown, not made: under
            // AddressSanitizer a huge allocation is a report, not bad_alloc;
            // tests/cli/test_messages.sh makes a real one).
            throw std::bad_alloc();
        }
        return 0;
    });
    std::string err = testing::internal::GetCapturedStderr();
    EXPECT_EQ(rc, 1);
    EXPECT_EQ(err, "mytool ERROR: out of memory while dicing scene.rib\n");
}

TEST(RunTool, WarningsOfOneKindArePrintedFiveTimesThenSummarised) {
    testing::internal::CaptureStderr();
    int rc = call_run_tool({"mytool"}, [](const std::vector<std::string>&) -> int {
        sss::Warnings scene;
        for (int i = 0; i < 100000; ++i)
            scene.push_back("s.rib:" + std::to_string(i + 3) +
                            ": TransformBegin is never closed");
        sss::warn_all("mytool", scene);
        for (int i = 0; i < 7; ++i)
            sss::warn("mytool", "frame " + std::to_string(i) + " odd");
        sss::warn("mytool", "another kind");
        return 0;
    });
    const std::vector<std::string> lines =
        split_lines(testing::internal::GetCapturedStderr());
    EXPECT_EQ(rc, 0);
    ASSERT_EQ(lines.size(), 5u + 5u + 1u + 2u);
    EXPECT_EQ(lines[0], "mytool WARNING: s.rib:3: TransformBegin is never closed");
    EXPECT_EQ(lines[5], "mytool WARNING: frame 0 odd");
    EXPECT_EQ(lines[10], "mytool WARNING: another kind");
    EXPECT_EQ(lines[11], "mytool WARNING: 99995 more warnings like \"TransformBegin is "
                         "never closed\" not shown");
    // Kinds without a name are labelled by their first text.
    EXPECT_EQ(lines[12],
              "mytool WARNING: 2 more warnings like \"frame 0 odd\" not shown");
}

TEST(Version, Report) {
    EXPECT_STREQ(sss::version_string(), "0.1.0");
    std::string report = sss::version_report("ptsynth");
    EXPECT_EQ(report.rfind("ptsynth (sss) 0.1.0\n", 0), 0u) << report;
    for (const char* lib :
         {"OpenEXR", "OpenImageIO", "Embree", "oneTBB", "zlib", "compiler"})
        EXPECT_NE(report.find(lib), std::string::npos) << lib;
}

// ---------------------------------------------------------------------------
// -newer 1
// ---------------------------------------------------------------------------

TEST(OutputsUpToDate, StrictlyNewerThanEveryInputAndAllPresent) {
    TempFolder dir;
    const auto at = [&](const std::string& name, int seconds_ago) {
        const std::string path = (dir.path() / name).string();
        std::ofstream(path) << name;
        fs::last_write_time(path, fs::file_time_type::clock::now() -
                                      std::chrono::seconds(seconds_ago));
        return path;
    };
    const std::string in1 = at("in1", 300), in2 = at("in2", 200);
    const std::string out1 = at("out1", 100), out2 = at("out2", 100);
    testing::internal::CaptureStdout();
    EXPECT_TRUE(sss::outputs_up_to_date("tool", {out1, out2}, {in1, in2}));
    EXPECT_NE(testing::internal::GetCapturedStdout().find("nothing to do"),
              std::string::npos);

    testing::internal::CaptureStdout();
    // One input as new as an output: not strictly newer.
    fs::last_write_time(in2, fs::last_write_time(out2));
    EXPECT_FALSE(sss::outputs_up_to_date("tool", {out1, out2}, {in1, in2}));
    // A missing output or input, or no outputs at all: the job runs.
    EXPECT_FALSE(
        sss::outputs_up_to_date("tool", {out1, (dir.path() / "x").string()}, {in1}));
    EXPECT_FALSE(sss::outputs_up_to_date("tool", {out1}, {(dir.path() / "y").string()}));
    EXPECT_FALSE(sss::outputs_up_to_date("tool", {}, {in1}));
    // A folder is not an output file.
    EXPECT_FALSE(sss::outputs_up_to_date("tool", {dir.path().string()}, {in1}));
    EXPECT_EQ(testing::internal::GetCapturedStdout(), "") << "only a skip prints";
    // No inputs (an in-memory scene): an existing output is up to date.
    testing::internal::CaptureStdout();
    EXPECT_TRUE(sss::outputs_up_to_date("tool", {out1}, {}));
    testing::internal::GetCapturedStdout();
}

// ---------------------------------------------------------------------------
// Signals during a tool's run (run_tool installs the handlers)
// ---------------------------------------------------------------------------

TEST(AtomicOutputDeathTest, SignalRemovesTemporaries) {
    TempFolder dir;
    const std::string target = (dir.path() / "a.ptc").string();
    write_text(target, "old");
    auto body = [&] {
        std::string name = "mytool";
        char* argv[] = {name.data(), nullptr};
        sss::run_tool("mytool", 1, argv, [&](const std::vector<std::string>&) {
            sss::AtomicOutput first(target);
            sss::AtomicOutput second((dir.path() / "b.ptc").string());
            write_text(first.temp_path(), "partial");
            std::raise(SIGTERM);
            return 0;
        });
        std::_Exit(0);
    };
    EXPECT_EXIT(body(), testing::KilledBySignal(SIGTERM), "");
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"a.ptc"});
    EXPECT_EQ(read_text(target), "old");
}
