/// \file tool_test.cpp
/// Tests of the shared tool behaviour (sss/tool.h) and of the synthetic
/// point clouds (sss/synthetic.h).

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <glm/geometric.hpp>
#include <oneapi/tbb/global_control.h>

#include "sss/util/error.h"
#include "sss/cloud/synthetic.h"
#include "sss/cli/tool.h"

namespace fs = std::filesystem;

namespace {

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

std::vector<std::string> split_lines(const std::string& text) {
    std::vector<std::string> lines;
    std::istringstream in(text);
    std::string line;
    while (std::getline(in, line)) lines.push_back(line);
    return lines;
}

/// A fresh empty folder, removed at the end of the test.
class TempFolder {
public:
    TempFolder() {
        std::random_device rd;
        m_path = fs::temp_directory_path() /
                 ("sss_tool_test_" + std::to_string(rd()) + std::to_string(rd()));
        fs::create_directories(m_path);
    }
    ~TempFolder() {
        std::error_code ec;
        fs::remove_all(m_path, ec);
    }
    const fs::path& path() const { return m_path; }
    std::vector<std::string> entries() const {
        std::vector<std::string> names;
        for (const auto& e : fs::directory_iterator(m_path))
            names.push_back(e.path().filename().string());
        std::sort(names.begin(), names.end());
        return names;
    }

private:
    fs::path m_path;
};

void write_text(const std::string& path, const std::string& text) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out << text;
    ASSERT_TRUE(out.good()) << path;
}

std::string read_text(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
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

TEST(Version, Report) {
    EXPECT_STREQ(sss::version_string(), "0.1.0");
    std::string report = sss::version_report("ptsynth");
    EXPECT_EQ(report.rfind("ptsynth (sss) 0.1.0\n", 0), 0u) << report;
    for (const char* lib :
         {"OpenEXR", "OpenImageIO", "Embree", "oneTBB", "zlib", "compiler"})
        EXPECT_NE(report.find(lib), std::string::npos) << lib;
}

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
    const std::string name = temp.filename().string();
    EXPECT_EQ(name.rfind(".cloud.ptc.", 0), 0u) << name;
    EXPECT_EQ(name.size(), std::string(".cloud.ptc.").size() + 8 + 4) << name;
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
    }
    EXPECT_TRUE(dir.entries().empty());
}

TEST(AtomicOutput, CommitOntoFolderFails) {
    TempFolder dir;
    const fs::path target = dir.path() / "sub";
    fs::create_directories(target / "x");
    sss::AtomicOutput out(target.string());
    write_text(out.temp_path(), "data");
    EXPECT_THROW(out.commit(), sss::IoError);
}

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

// ---------------------------------------------------------------------------
// Synthetic clouds
// ---------------------------------------------------------------------------

namespace {

double area_sum(const sss::PointCloud& cloud) {
    const sss::Channel* area = cloud.find_channel("_area");
    EXPECT_NE(area, nullptr);
    if (!area) return 0.0;
    double sum = 0.0;
    for (float a : area->data) sum += a;
    return sum;
}

void expect_channels(const sss::PointCloud& cloud) {
    const sss::Channel* area = cloud.find_channel("_area");
    const sss::Channel* rad = cloud.find_channel("_radiance_t");
    ASSERT_NE(area, nullptr);
    ASSERT_NE(rad, nullptr);
    EXPECT_EQ(area->type, sss::ChannelType::Float);
    EXPECT_EQ(rad->type, sss::ChannelType::Color);
    EXPECT_EQ(area->data.size(), cloud.size());
    EXPECT_EQ(rad->data.size(), 3 * cloud.size());
    EXPECT_EQ(cloud.normals.size(), cloud.size());
    EXPECT_EQ(cloud.radii.size(), cloud.size());
}

/// Radiance must be light_color * max(0, N.L) + ambient at every point.
void expect_radiance(const sss::PointCloud& cloud, const sss::SyntheticParams& p) {
    const sss::Channel* rad = cloud.find_channel("_radiance_t");
    ASSERT_NE(rad, nullptr);
    glm::dvec3 light = glm::normalize(p.light_dir);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        double cosine = std::max(0.0, glm::dot(glm::dvec3(cloud.normals[i]), light));
        for (int k = 0; k < 3; ++k) {
            double expected = p.light_color[k] * cosine + p.ambient;
            ASSERT_NEAR(rad->data[3 * i + k], expected,
                        1e-5 * (1.0 + std::fabs(expected)))
                << "point " << i;
        }
    }
}

} // namespace

TEST(Synthetic, SphereAreasNormalsRadiance) {
    sss::SyntheticParams p;
    p.shape = sss::SyntheticShape::Sphere;
    p.count = 20000;
    p.size = 50.0;
    p.light_dir = {1, 1, 1};
    sss::PointCloud cloud = sss::make_synthetic_cloud(p);
    ASSERT_EQ(cloud.size(), 20000u);
    expect_channels(cloud);
    const double expected_area = 4.0 * std::numbers::pi * 50.0 * 50.0;
    EXPECT_NEAR(area_sum(cloud), expected_area, 1e-6 * expected_area);
    const double share = expected_area / 20000.0;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        glm::dvec3 n(cloud.normals[i]);
        glm::dvec3 pos(cloud.positions[i]);
        ASSERT_NEAR(glm::length(n), 1.0, 1e-6);
        ASSERT_NEAR(glm::length(pos), 50.0, 50.0 * 1e-6);
        ASSERT_NEAR(glm::dot(n, pos / 50.0), 1.0, 1e-5) << "outward normal";
        ASSERT_NEAR(cloud.radii[i], std::sqrt(2.0 * share) / 2.0, 1e-5);
    }
    expect_radiance(cloud, p);

    // The lattice covers the sphere evenly: the mean position is the centre.
    glm::dvec3 mean(0.0);
    for (const auto& q : cloud.positions) mean += glm::dvec3(q);
    mean /= static_cast<double>(cloud.size());
    EXPECT_LT(glm::length(mean), 0.05);
}

TEST(Synthetic, LightColourAndAmbient) {
    sss::SyntheticParams p;
    p.count = 1000;
    p.size = 2.0;
    p.light_dir = {0, 0, -3};
    p.light_color = {2.0, 1.0, 0.5};
    p.ambient = 0.25;
    sss::PointCloud cloud = sss::make_synthetic_cloud(p);
    expect_radiance(cloud, p);
}

TEST(Synthetic, PlaneGridAreas) {
    sss::SyntheticParams p;
    p.shape = sss::SyntheticShape::Plane;
    p.count = 10000;
    p.size = 30.0;
    sss::PointCloud cloud = sss::make_synthetic_cloud(p);
    ASSERT_EQ(cloud.size(), 10000u);
    expect_channels(cloud);
    EXPECT_NEAR(area_sum(cloud), 900.0, 1e-6 * 900.0);
    const double h = 30.0 / 100.0;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        EXPECT_EQ(cloud.normals[i], glm::vec3(0, 0, 1));
        EXPECT_EQ(cloud.positions[i].z, 0.0f);
        ASSERT_NEAR(cloud.radii[i], h * std::sqrt(2.0) / 2.0, 1e-6);
    }
    expect_radiance(cloud, p);

    // round(sqrt(1000)) = 32 -> 1024 points.
    p.count = 1000;
    EXPECT_EQ(sss::make_synthetic_cloud(p).size(), 1024u);
}

TEST(Synthetic, PlaneJitterStaysInCells) {
    sss::SyntheticParams p;
    p.shape = sss::SyntheticShape::Plane;
    p.count = 400;
    p.size = 20.0;
    p.jitter = 1.0;
    p.seed = 42;
    sss::PointCloud cloud = sss::make_synthetic_cloud(p);
    ASSERT_EQ(cloud.size(), 400u);
    EXPECT_NEAR(area_sum(cloud), 400.0, 1e-6 * 400.0);
    const double h = 1.0;
    bool moved = false;
    for (std::size_t j = 0; j < 20; ++j) {
        for (std::size_t i = 0; i < 20; ++i) {
            const glm::vec3& q = cloud.positions[j * 20 + i];
            double cx = -10.0 + (i + 0.5) * h, cy = -10.0 + (j + 0.5) * h;
            EXPECT_LE(std::fabs(q.x - cx), 0.5 * h + 1e-5);
            EXPECT_LE(std::fabs(q.y - cy), 0.5 * h + 1e-5);
            if (std::fabs(q.x - cx) > 1e-3) moved = true;
        }
    }
    EXPECT_TRUE(moved);
}

TEST(Synthetic, BoxSurfaceArea) {
    sss::SyntheticParams p;
    p.shape = sss::SyntheticShape::Box;
    p.count = 20000;
    p.size = 40.0;
    p.thickness = 5.0;
    p.light_dir = {0.3, -0.2, 1.0};
    p.jitter = 0.5;
    sss::PointCloud cloud = sss::make_synthetic_cloud(p);
    expect_channels(cloud);
    EXPECT_NEAR(static_cast<double>(cloud.size()), 20000.0, 0.1 * 20000.0);
    const double surface = 2.0 * (40.0 * 40.0 + 2.0 * 40.0 * 5.0);
    EXPECT_NEAR(area_sum(cloud), surface, 1e-6 * surface);
    const glm::dvec3 half(20.0, 20.0, 2.5);
    int faces[6] = {0, 0, 0, 0, 0, 0};
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        glm::dvec3 n(cloud.normals[i]);
        glm::dvec3 q(cloud.positions[i]);
        ASSERT_NEAR(glm::length(n), 1.0, 1e-7);
        int axis = std::fabs(n.x) > 0.5 ? 0 : (std::fabs(n.y) > 0.5 ? 1 : 2);
        ASSERT_NEAR(std::fabs(n[axis]), 1.0, 1e-7) << "axis-aligned normal";
        // On its face, inside the box outline.
        ASSERT_NEAR(q[axis] * n[axis], half[axis], 1e-5);
        for (int k = 0; k < 3; ++k) ASSERT_LE(std::fabs(q[k]), half[k] + 1e-5);
        faces[2 * axis + (n[axis] > 0 ? 0 : 1)]++;
    }
    for (int f : faces) EXPECT_GT(f, 0);
    EXPECT_EQ(faces[4], faces[5]);
    expect_radiance(cloud, p);
}

TEST(Synthetic, Deterministic) {
    for (auto shape : {sss::SyntheticShape::Sphere, sss::SyntheticShape::Plane,
                       sss::SyntheticShape::Box}) {
        sss::SyntheticParams p;
        p.shape = shape;
        p.count = 3000;
        p.jitter = 0.7;
        p.seed = 1234;
        sss::PointCloud a = sss::make_synthetic_cloud(p);
        sss::PointCloud b = sss::make_synthetic_cloud(p);
        ASSERT_EQ(a.size(), b.size());
        EXPECT_EQ(a.positions, b.positions);
        EXPECT_EQ(a.normals, b.normals);
        EXPECT_EQ(a.radii, b.radii);
        EXPECT_EQ(a.find_channel("_radiance_t")->data,
                  b.find_channel("_radiance_t")->data);
        if (shape != sss::SyntheticShape::Sphere) {
            p.seed = 1235;
            EXPECT_NE(sss::make_synthetic_cloud(p).positions, a.positions)
                << "the seed drives the jitter";
        }
    }
}

TEST(Synthetic, RejectsBadParameters) {
    auto bad = [](auto change) {
        sss::SyntheticParams p;
        p.count = 10;
        change(p);
        EXPECT_THROW(sss::make_synthetic_cloud(p), sss::ValueError);
    };
    bad([](sss::SyntheticParams& p) { p.count = 0; });
    bad([](sss::SyntheticParams& p) { p.size = 0.0; });
    bad([](sss::SyntheticParams& p) { p.size = std::nan(""); });
    bad([](sss::SyntheticParams& p) { p.jitter = 1.5; });
    bad([](sss::SyntheticParams& p) { p.light_dir = glm::dvec3(0.0); });
    bad([](sss::SyntheticParams& p) {
        p.shape = sss::SyntheticShape::Box;
        p.thickness = -1.0;
    });
}
