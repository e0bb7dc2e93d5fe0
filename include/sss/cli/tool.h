#pragma once
/// \file tool.h
/// Behaviour shared by every command-line tool: error reporting and exit
/// codes, RenderMan-style option scanning, thread counts, progress lines and
/// atomic output files. Each tool's main() is option parsing around one
/// library call, wrapped in run_tool().

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

namespace sss {

/// Project version string ("0.1.0").
const char* version_string();
/// Multi-line build description for --version: project version and the
/// versions of the libraries it is built with (OpenEXR, OIIO, Embree, oneTBB, zlib).
std::string version_report(const std::string& tool);

/// Runs body(args) with the tools' uniform error handling. args excludes argv[0].
/// UsageError -> "<tool> ERROR: <what>" on stderr, exit 2; any other exception
/// -> "<tool> ERROR: <what>", exit 1. Returns body's result otherwise.
int run_tool(const std::string& tool, int argc, char** argv,
             const std::function<int(const std::vector<std::string>&)>& body);

/// Handles the options every tool shares: "-h"/"help" prints usage and
/// "version" prints version_report(tool), both on stdout. Returns true when
/// opt (without dashes) was one of them: the tool then exits 0.
bool standard_option(const std::string& tool, const std::string& opt,
                     const std::string& usage);

/// Prints "<tool> WARNING: <what>" on stderr.
void warn(const std::string& tool, const std::string& what);

/// Walks a command line the RenderMan way: options start with one or two
/// dashes and take a fixed number of values; other words are positional.
/// Every malformed use throws UsageError naming the option.
class ArgScanner {
public:
    explicit ArgScanner(std::vector<std::string> args);

    bool done() const { return m_pos >= m_args.size(); }
    /// True if the next word is an option ("-x", "--x"; a negative number is not).
    bool at_option() const;
    /// Consumes the next word as an option and returns its name without dashes.
    std::string option();
    /// Consumes the next word as a positional argument.
    std::string positional();
    /// Moves to the next option, appending the positional words before it to
    /// `positionals`; stores its name (option()) in `opt`. False at the end.
    /// The usual loop: `while (args.next_option(o, files)) { ... }`.
    bool next_option(std::string& opt, std::vector<std::string>& positionals);

    /// Consumes the value of option opt; UsageError if missing or if it looks
    /// like another option.
    std::string value(const std::string& opt);
    /// A finite number.
    double number(const std::string& opt);
    /// A finite number > 0.
    double positive(const std::string& opt);
    /// A finite number >= 0.
    double non_negative(const std::string& opt);
    /// An integer in [lo, hi].
    int integer(const std::string& opt, int lo, int hi);
    /// Three finite numbers (r g b).
    glm::dvec3 triple(const std::string& opt);
    /// Peeks the next word without consuming it ("" when done).
    const std::string& peek() const;

private:
    std::vector<std::string> m_args;
    std::size_t m_pos = 0;
};

struct MaterialSpec;
/// Parses the PRMan material options shared by ptfilter and ptbake
/// (-material, -unitlength, -scattering, -absorption, -albedo r g b|fromfile,
/// -diffusemeanfreepath r g b|fromfile, -ior) into spec. Returns false when
/// opt is not one of them; allow_fromfile = false rejects `fromfile`.
bool material_option(ArgScanner& args, const std::string& opt, MaterialSpec& spec,
                     bool allow_fromfile = true);

/// The options of every tool that runs a job: -threads N, -progress 0|1|2
/// and its alias -Progress (= 1), and -frame N for frame patterns in paths
/// (frame_pattern.h).
struct RunOptions {
    int threads = 0;
    int progress = 0;
    std::optional<int> frame;
};
/// Parses one of them into run; false when opt is not one of them.
bool run_option(ArgScanner& args, const std::string& opt, RunOptions& run);

/// The `-newer 1` test of ptfilter, brickmake, ptbake and render: true when
/// every output exists and was modified strictly after every input (file
/// system time, full resolution). Then it prints "<tool>: OUT is newer than
/// its inputs; nothing to do" on stdout and the tool exits 0 without work.
/// False when an output or an input is missing (the job then runs and
/// reports a missing input itself), or when there are no outputs.
bool outputs_up_to_date(const std::string& tool, const std::vector<std::string>& outputs,
                        const std::vector<std::string>& inputs);

struct PointCloudWriteOptions;
/// Parses the point-cloud output options (-compress 0|1, -ptcversion 0|1|2);
/// false when opt is not one of them.
bool write_option(ArgScanner& args, const std::string& opt,
                  PointCloudWriteOptions& write);

/// Resolves a -threads value: N > 0 is exact, 0 = every usable core (CPU
/// affinity and cgroup quota aware), N < 0 = usable cores minus |N| (at least 1).
int resolve_thread_count(int requested);

/// Limits oneTBB parallelism to n threads while alive.
class ThreadLimit {
public:
    explicit ThreadLimit(int n);
    ~ThreadLimit();
    ThreadLimit(const ThreadLimit&) = delete;
    ThreadLimit& operator=(const ThreadLimit&) = delete;

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

/// Thread-safe progress reporter for render farms: prints "ALF_PROGRESS NN%"
/// on stdout, flushed, each time the integer percentage grows.
class Progress {
public:
    explicit Progress(bool enabled) : m_enabled(enabled) {}
    /// Reports that `done` of `total` units are finished.
    void update(uint64_t done, uint64_t total);
    /// Prints 100% if not printed yet.
    void finish();
    bool enabled() const { return m_enabled; }

private:
    bool m_enabled;
    std::atomic<int> m_last{-1};
    std::mutex m_mutex;
};

/// An output file written atomically: write to temp_path() (a unique file in
/// the target's folder), then commit() renames it over the target. If never
/// committed (error, exception, SIGINT/SIGTERM/SIGHUP), the temporary is removed and
/// the target is untouched.
class AtomicOutput {
public:
    explicit AtomicOutput(const std::string& target);
    ~AtomicOutput();
    AtomicOutput(const AtomicOutput&) = delete;
    AtomicOutput& operator=(const AtomicOutput&) = delete;

    const std::string& temp_path() const { return m_temp; }
    const std::string& target() const { return m_target; }
    /// fsyncs the temporary and renames it over the target. Throws IoError.
    void commit();

private:
    std::string m_target;
    std::string m_temp;
    bool m_committed = false;
};

/// Wall-clock stopwatch in seconds.
class Stopwatch {
public:
    Stopwatch();
    double seconds() const;

private:
    int64_t m_start_ns;
};

} // namespace sss
