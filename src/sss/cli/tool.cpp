/// \file tool.cpp
/// Shared command-line behaviour: error reporting, option scanning, thread
/// counts, progress lines, atomic output files and their signal cleanup.

#include "sss/cli/tool.h"

#include "sss/util/hash.h"
#include "sss/util/error.h"
#include "sss/diffusion/material.h"
#include "sss/cloud/point_cloud_io.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <new>
#include <optional>
#include <random>
#include <sstream>
#include <string_view>

#include <fcntl.h>
#include <pthread.h>
#include <sched.h>
#include <sys/stat.h>
#include <unistd.h>

#include <OpenEXR/OpenEXRConfig.h>
#include <OpenImageIO/oiioversion.h>
#include <embree3/rtcore_config.h>
#include <oneapi/tbb/global_control.h>
#include <oneapi/tbb/version.h>
#include <zlib.h>

#include "sss/util/error.h"

#ifndef SSS_VERSION_STRING
#error "SSS_VERSION_STRING must be defined by the build (see CMakeLists.txt)"
#endif

namespace sss {

// ---------------------------------------------------------------------------
// Temporary-file registry for signal cleanup
// ---------------------------------------------------------------------------

namespace {

// The signal handler may only touch lock-free atomics and plain memory, so the
// registry is a fixed array of path buffers. A slot is visible to the handler
// only while its state is Armed; paths are written before arming (release) and
// read after observing Armed (acquire). Registration and removal happen in
// normal thread context under a mutex, which the handler never takes.
constexpr int kMaxTempFiles = 128;
constexpr std::size_t kMaxTempPath = 4096;

enum SlotState : int { SlotFree = 0, SlotArmed = 1 };

struct TempSlot {
    std::atomic<int> state{SlotFree};
    char path[kMaxTempPath];
};

TempSlot g_temp_slots[kMaxTempFiles];
std::mutex g_temp_mutex;

static_assert(std::atomic<int>::is_always_lock_free,
              "the signal handler needs lock-free atomics");

void register_temp_file(const std::string& path) {
    if (path.size() + 1 > kMaxTempPath) return; // cannot be cleaned on a signal
    std::lock_guard<std::mutex> lock(g_temp_mutex);
    for (TempSlot& slot : g_temp_slots) {
        if (slot.state.load(std::memory_order_relaxed) != SlotFree) continue;
        std::memcpy(slot.path, path.c_str(), path.size() + 1);
        slot.state.store(SlotArmed, std::memory_order_release);
        return;
    }
    // Registry full: the file is still removed by ~AtomicOutput, just not on a signal.
}

void unregister_temp_file(const std::string& path) {
    std::lock_guard<std::mutex> lock(g_temp_mutex);
    for (TempSlot& slot : g_temp_slots) {
        if (slot.state.load(std::memory_order_relaxed) != SlotArmed) continue;
        if (path == slot.path) {
            slot.state.store(SlotFree, std::memory_order_release);
            return;
        }
    }
}

extern "C" void sss_cleanup_and_die(int sig) {
    for (TempSlot& slot : g_temp_slots) {
        if (slot.state.load(std::memory_order_acquire) == SlotArmed) ::unlink(slot.path);
    }
    // Die by the same signal so the parent (shell, farm daemon) sees the real
    // cause; a shell reports it as 128 + sig. The signal is blocked while its
    // handler runs, hence the unblock before raise().
    struct sigaction dfl {};
    dfl.sa_handler = SIG_DFL;
    sigemptyset(&dfl.sa_mask);
    ::sigaction(sig, &dfl, nullptr);
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, sig);
    ::pthread_sigmask(SIG_UNBLOCK, &set, nullptr);
    ::raise(sig);
    ::_exit(128 + sig);
}

void install_signal_handlers() {
    static std::once_flag once;
    std::call_once(once, [] {
        // SIGHUP too: a closed terminal or dropped ssh session ends the job
        // like a kill would.
        for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
            struct sigaction old {};
            if (::sigaction(sig, nullptr, &old) != 0) continue;
            // A signal ignored by our parent (nohup: SIGHUP, background jobs:
            // SIGINT) stays ignored.
            if (!(old.sa_flags & SA_SIGINFO) && old.sa_handler == SIG_IGN) continue;
            struct sigaction sa {};
            sa.sa_handler = sss_cleanup_and_die;
            sigemptyset(&sa.sa_mask);
            sigaddset(&sa.sa_mask, SIGINT);
            sigaddset(&sa.sa_mask, SIGTERM);
            sigaddset(&sa.sa_mask, SIGHUP);
            ::sigaction(sig, &sa, nullptr);
        }
    });
}

std::string errno_text(int err) {
    return std::strerror(err);
}

std::string random_alnum(int n) {
    static const uint64_t seed = [] {
        std::random_device rd;
        uint64_t s = (uint64_t(rd()) << 32) ^ rd();
        s ^= uint64_t(::getpid()) << 17;
        s ^= uint64_t(std::chrono::steady_clock::now().time_since_epoch().count());
        return s;
    }();
    static std::atomic<uint64_t> counter{0};
    static const char alphabet[] =
        "0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz";
    uint64_t x = detail::splitmix64(seed + 0x632be59bd9b4e019ull * counter.fetch_add(1));
    std::string out;
    for (int i = 0; i < n; ++i) {
        out += alphabet[x % 62];
        x /= 62;
        if (x == 0) x = detail::splitmix64(seed ^ uint64_t(i));
    }
    return out;
}

} // namespace

// ---------------------------------------------------------------------------
// Versions and error handling
// ---------------------------------------------------------------------------

const char* version_string() {
    return SSS_VERSION_STRING;
}

std::string version_report(const std::string& tool) {
    std::ostringstream out;
    out << tool << " (sss) " << version_string() << "\n";
    out << "  OpenEXR     " << OPENEXR_VERSION_STRING << "\n";
    out << "  OpenImageIO " << OIIO_VERSION_STRING << "\n";
    out << "  Embree      " << RTC_VERSION_STRING << "\n";
    out << "  oneTBB      " << TBB_VERSION_STRING << "\n";
    out << "  zlib        " << zlibVersion() << "\n";
#if defined(__clang__)
    out << "  compiler    clang " << __VERSION__ << "\n";
#elif defined(__GNUC__)
    out << "  compiler    g++ " << __VERSION__ << "\n";
#else
    out << "  compiler    " << __VERSION__ << "\n";
#endif
    return out.str();
}

namespace {

void flush_stdout() {
    std::cout.flush();
    std::fflush(stdout);
}

void print_error(const std::string& tool, const std::string& what) {
    flush_stdout();
    std::cerr << tool << " ERROR: " << what << "\n";
    std::cerr.flush();
}

} // namespace

int run_tool(const std::string& tool, int argc, char** argv,
             const std::function<int(const std::vector<std::string>&)>& body) {
    install_signal_handlers();
    try {
        std::vector<std::string> args;
        for (int i = 1; i < argc; ++i) args.emplace_back(argv[i]);
        int status = body(args);
        // A result nobody could read (closed pipe, full disk) is a failure.
        std::cout.flush();
        if (!std::cout || std::fflush(stdout) != 0) {
            std::cerr << tool << " ERROR: cannot write to standard output\n";
            return status == 0 ? 1 : status;
        }
        return status;
    } catch (const UsageError& e) {
        print_error(tool, e.what());
        std::cerr << tool << ": try '" << tool << " --help'\n";
        return 2;
    } catch (const std::bad_alloc&) {
        print_error(tool, "out of memory");
        return 1;
    } catch (const std::exception& e) {
        print_error(tool, e.what());
        return 1;
    } catch (...) {
        print_error(tool, "unknown exception");
        return 1;
    }
}

void warn(const std::string& tool, const std::string& what) {
    flush_stdout();
    std::cerr << tool << " WARNING: " << what << "\n";
    std::cerr.flush();
}

// ---------------------------------------------------------------------------
// ArgScanner
// ---------------------------------------------------------------------------

namespace {

bool looks_like_option(const std::string& word) {
    if (word.size() < 2 || word[0] != '-') return false;
    char c = word[1];
    return !(std::isdigit(static_cast<unsigned char>(c)) || c == '.');
}

// Whole-string parse of a finite double; a leading '+' is accepted.
std::optional<double> parse_finite(std::string_view s) {
    if (!s.empty() && s[0] == '+') {
        s.remove_prefix(1);
        if (!s.empty() && (s[0] == '-' || s[0] == '+')) return std::nullopt;
    }
    if (s.empty()) return std::nullopt;
    double v = 0.0;
    auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec != std::errc() || end != s.data() + s.size() || !std::isfinite(v))
        return std::nullopt;
    return v;
}

std::string format_number(double v) {
    std::ostringstream out;
    out << v;
    return out.str();
}

} // namespace

ArgScanner::ArgScanner(std::vector<std::string> args) : m_args(std::move(args)) {}

bool ArgScanner::at_option() const {
    return !done() && looks_like_option(m_args[m_pos]);
}

std::string ArgScanner::option() {
    if (done()) throw UsageError("missing option");
    const std::string& word = m_args[m_pos];
    if (!looks_like_option(word))
        throw UsageError("expected an option, got '" + word + "'");
    ++m_pos;
    std::size_t dashes = (word.size() > 1 && word[1] == '-') ? 2 : 1;
    return word.substr(dashes);
}

std::string ArgScanner::positional() {
    if (done()) throw UsageError("missing argument");
    return m_args[m_pos++];
}

bool ArgScanner::next_option(std::string& opt, std::vector<std::string>& positionals) {
    while (!done()) {
        if (at_option()) {
            opt = option();
            return true;
        }
        positionals.push_back(positional());
    }
    return false;
}

std::string ArgScanner::value(const std::string& opt) {
    if (done() || at_option()) throw UsageError("option -" + opt + " needs a value");
    return m_args[m_pos++];
}

double ArgScanner::number(const std::string& opt) {
    std::string word = value(opt);
    std::optional<double> v = parse_finite(word);
    if (!v) throw UsageError("option -" + opt + ": '" + word + "' is not a number");
    return *v;
}

double ArgScanner::positive(const std::string& opt) {
    double v = number(opt);
    if (!(v > 0.0))
        throw UsageError("option -" + opt + ": must be > 0 (got " + format_number(v) +
                         ")");
    return v;
}

double ArgScanner::non_negative(const std::string& opt) {
    double v = number(opt);
    if (!(v >= 0.0))
        throw UsageError("option -" + opt + ": must be >= 0 (got " + format_number(v) +
                         ")");
    return v;
}

int ArgScanner::integer(const std::string& opt, int lo, int hi) {
    std::string word = value(opt);
    std::string_view s = word;
    if (!s.empty() && s[0] == '+') s.remove_prefix(1);
    long long v = 0;
    auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    bool ok = !s.empty() && ec == std::errc() && end == s.data() + s.size();
    if (!ok) {
        // Accept integral values written as numbers ("1e6", "3.0").
        std::optional<double> d = parse_finite(word);
        if (!d || std::floor(*d) != *d || std::fabs(*d) > 9.0e18)
            throw UsageError("option -" + opt + ": '" + word + "' is not an integer");
        v = static_cast<long long>(*d);
    }
    if (v < lo || v > hi)
        throw UsageError("option -" + opt + ": " + std::to_string(v) +
                         " is out of range [" + std::to_string(lo) + ", " +
                         std::to_string(hi) + "]");
    return static_cast<int>(v);
}

glm::dvec3 ArgScanner::triple(const std::string& opt) {
    glm::dvec3 out(0.0);
    for (int i = 0; i < 3; ++i) {
        if (done() || at_option()) throw UsageError("option -" + opt + " needs 3 values");
        out[i] = number(opt);
    }
    return out;
}

const std::string& ArgScanner::peek() const {
    static const std::string empty;
    return done() ? empty : m_args[m_pos];
}

// ---------------------------------------------------------------------------
// Threads
// ---------------------------------------------------------------------------

namespace {

int affinity_cpu_count() {
    // Start with the fixed-size set and grow for machines with > 1024 CPUs.
    for (int ncpu = CPU_SETSIZE; ncpu <= (1 << 20); ncpu *= 4) {
        cpu_set_t* set = CPU_ALLOC(ncpu);
        if (!set) break;
        std::size_t bytes = CPU_ALLOC_SIZE(ncpu);
        CPU_ZERO_S(bytes, set);
        if (::sched_getaffinity(0, bytes, set) == 0) {
            int count = CPU_COUNT_S(bytes, set);
            CPU_FREE(set);
            return count;
        }
        int err = errno;
        CPU_FREE(set);
        if (err != EINVAL) break;
    }
    long n = ::sysconf(_SC_NPROCESSORS_ONLN);
    return n > 0 ? static_cast<int>(n) : 1;
}

std::optional<std::string> read_first_line(const std::string& path) {
    std::ifstream in(path);
    std::string line;
    if (!in || !std::getline(in, line)) return std::nullopt;
    return line;
}

// CPUs allowed by a quota/period pair; nullopt when unlimited or unreadable.
std::optional<int> quota_cpus(double quota, double period) {
    if (!(quota > 0.0) || !(period > 0.0)) return std::nullopt;
    return std::max(1, static_cast<int>(std::ceil(quota / period)));
}

// cgroup v2 "cpu.max": "<quota|max> <period>".
std::optional<int> read_cpu_max(const std::string& dir) {
    auto line = read_first_line(dir + "/cpu.max");
    if (!line) return std::nullopt;
    std::istringstream in(*line);
    std::string quota;
    double period = 0.0;
    if (!(in >> quota >> period) || quota == "max") return std::nullopt;
    auto q = parse_finite(quota);
    return q ? quota_cpus(*q, period) : std::nullopt;
}

// cgroup v1 "cpu.cfs_quota_us" (-1 = unlimited) and "cpu.cfs_period_us".
std::optional<int> read_cfs(const std::string& dir) {
    auto quota = read_first_line(dir + "/cpu.cfs_quota_us");
    auto period = read_first_line(dir + "/cpu.cfs_period_us");
    if (!quota || !period) return std::nullopt;
    auto q = parse_finite(*quota);
    auto p = parse_finite(*period);
    return (q && p) ? quota_cpus(*q, *p) : std::nullopt;
}

struct CgroupMount {
    std::string mount_point;
    std::string root;
};

std::optional<int> min_opt(std::optional<int> a, std::optional<int> b) {
    if (!a) return b;
    if (!b) return a;
    return std::min(*a, *b);
}

// Smallest quota on the way from the process's cgroup up to the mount point:
// a parent's quota limits every child.
template <typename Reader>
std::optional<int> walk_cgroup(const CgroupMount& mount, std::string cg_path,
                               Reader read) {
    // Inside a cgroup namespace the mount root is a prefix of our path.
    if (mount.root != "/" && cg_path.rfind(mount.root, 0) == 0)
        cg_path = cg_path.substr(mount.root.size());
    std::filesystem::path dir = std::filesystem::path(mount.mount_point);
    std::filesystem::path rel = std::filesystem::path(cg_path).relative_path();
    std::optional<int> best;
    std::vector<std::filesystem::path> chain{dir};
    for (const auto& part : rel) {
        if (part.empty()) continue;
        dir /= part;
        chain.push_back(dir);
    }
    for (const auto& d : chain) best = min_opt(best, read(d.string()));
    return best;
}

std::optional<int> cgroup_cpu_limit() {
    // Our cgroup paths: "0::/path" (v2) and "N:cpu,cpuacct:/path" (v1).
    std::optional<std::string> v2_path, v1_path;
    {
        std::ifstream in("/proc/self/cgroup");
        std::string line;
        while (std::getline(in, line)) {
            auto c1 = line.find(':');
            auto c2 = c1 == std::string::npos ? c1 : line.find(':', c1 + 1);
            if (c2 == std::string::npos) continue;
            std::string id = line.substr(0, c1);
            std::string ctrls = line.substr(c1 + 1, c2 - c1 - 1);
            std::string path = line.substr(c2 + 1);
            if (id == "0" && ctrls.empty()) {
                v2_path = path;
                continue;
            }
            std::istringstream cs(ctrls);
            std::string c;
            while (std::getline(cs, c, ','))
                if (c == "cpu") v1_path = path;
        }
    }
    // Mount points from mountinfo: "... root mountpoint opts ... - fstype src superopts".
    std::optional<CgroupMount> v2_mount, v1_mount;
    {
        std::ifstream in("/proc/self/mountinfo");
        std::string line;
        while (std::getline(in, line)) {
            auto sep = line.find(" - ");
            if (sep == std::string::npos) continue;
            std::istringstream pre(line.substr(0, sep));
            std::istringstream post(line.substr(sep + 3));
            std::string id, parent, devno, root, mount_point, fstype, source, superopts;
            if (!(pre >> id >> parent >> devno >> root >> mount_point)) continue;
            if (!(post >> fstype >> source >> superopts)) continue;
            if (fstype == "cgroup2" && !v2_mount) {
                v2_mount = CgroupMount{mount_point, root};
            } else if (fstype == "cgroup" && !v1_mount) {
                std::istringstream os(superopts);
                std::string o;
                while (std::getline(os, o, ','))
                    if (o == "cpu") v1_mount = CgroupMount{mount_point, root};
            }
        }
    }
    std::optional<int> limit;
    if (v2_path && v2_mount)
        limit = min_opt(limit, walk_cgroup(*v2_mount, *v2_path, read_cpu_max));
    if (v1_path && v1_mount)
        limit = min_opt(limit, walk_cgroup(*v1_mount, *v1_path, read_cfs));
    if (!v2_mount && !v1_mount) {
        // No readable mountinfo: try the usual locations.
        limit = min_opt(limit, read_cpu_max("/sys/fs/cgroup"));
        limit = min_opt(limit, read_cfs("/sys/fs/cgroup/cpu"));
        limit = min_opt(limit, read_cfs("/sys/fs/cgroup/cpu,cpuacct"));
    }
    return limit;
}

int usable_cpu_count() {
    int n = affinity_cpu_count();
    if (auto limit = cgroup_cpu_limit()) n = std::min(n, *limit);
    return std::max(1, n);
}

} // namespace

int resolve_thread_count(int requested) {
    if (requested > 0) return requested;
    int usable = usable_cpu_count();
    if (requested == 0) return usable;
    // requested < 0: all but |requested|; widen to avoid overflow at INT_MIN.
    long long n = static_cast<long long>(usable) + requested;
    return static_cast<int>(std::max<long long>(1, n));
}

struct ThreadLimit::Impl {
    explicit Impl(int n)
        : control(oneapi::tbb::global_control::max_allowed_parallelism,
                  static_cast<std::size_t>(n)) {}
    oneapi::tbb::global_control control;
};

// n < 1 follows the -threads rules (0 = usable CPUs, -k = all but k).
ThreadLimit::ThreadLimit(int n)
    : m_impl(std::make_unique<Impl>(n > 0 ? n : resolve_thread_count(n))) {}

ThreadLimit::~ThreadLimit() = default;

// ---------------------------------------------------------------------------
// Progress
// ---------------------------------------------------------------------------

void Progress::update(uint64_t done, uint64_t total) {
    if (!m_enabled) return;
    int pct = 100;
    if (total > 0 && done < total)
        pct = static_cast<int>((static_cast<unsigned __int128>(done) * 100u) / total);
    // Cheap check first: most calls change nothing and must not serialise.
    if (pct <= m_last.load(std::memory_order_relaxed)) return;
    std::lock_guard<std::mutex> lock(m_mutex);
    if (pct <= m_last.load(std::memory_order_relaxed)) return;
    std::cout << "ALF_PROGRESS " << pct << "%\n" << std::flush;
    m_last.store(pct, std::memory_order_relaxed);
}

void Progress::finish() {
    update(1, 1);
}

// ---------------------------------------------------------------------------
// AtomicOutput
// ---------------------------------------------------------------------------

namespace {

std::string parent_dir(const std::string& target) {
    std::string dir = std::filesystem::path(target).parent_path().string();
    return dir.empty() ? std::string(".") : dir;
}

} // namespace

AtomicOutput::AtomicOutput(const std::string& target) : m_target(target) {
    if (target.empty()) throw ValueError("empty output file name");
    std::filesystem::path path(target);
    std::string base = path.filename().string();
    if (base.empty() || base == "." || base == "..")
        throw IoError(target, "not a file name (it names a folder)");
    // Keep the temporary name within NAME_MAX (255) even for long targets.
    if (base.size() > 200) base.resize(200);
    std::string dir_prefix = path.parent_path().string();
    if (!dir_prefix.empty() && dir_prefix.back() != '/') dir_prefix += '/';

    // O_EXCL makes the name ours; the writer later reopens and truncates it.
    // The name is registered before the file exists: registered after, a
    // signal in between would leave the new file behind.
    for (int attempt = 0; attempt < 100; ++attempt) {
        std::string temp = dir_prefix + "." + base + "." + random_alnum(8) + ".tmp";
        register_temp_file(temp);
        int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (fd >= 0) {
            ::close(fd);
            m_temp = temp;
            return;
        }
        const int err = errno;
        unregister_temp_file(temp);
        if (err != EEXIST)
            throw IoError(target, "cannot create a temporary file in '" +
                                      parent_dir(target) + "': " + errno_text(err));
    }
    throw IoError(target, "cannot find an unused temporary file name");
}

AtomicOutput::~AtomicOutput() {
    if (m_committed || m_temp.empty()) return;
    ::unlink(m_temp.c_str());
    unregister_temp_file(m_temp);
}

void AtomicOutput::commit() {
    if (m_committed) return;
    int fd = ::open(m_temp.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        throw IoError(m_target, "cannot open temporary file '" + m_temp +
                                    "': " + errno_text(errno));
    if (::fsync(fd) != 0) {
        int err = errno;
        ::close(fd);
        throw IoError(m_target,
                      "cannot flush '" + m_temp + "' to disk: " + errno_text(err));
    }
    ::close(fd);
    if (::rename(m_temp.c_str(), m_target.c_str()) != 0)
        throw IoError(m_target,
                      "cannot rename '" + m_temp + "' over it: " + errno_text(errno));
    m_committed = true;
    unregister_temp_file(m_temp);

    // Make the rename itself durable.
    std::string dir = parent_dir(m_target);
    int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dfd < 0)
        throw IoError(dir, "cannot open folder to sync it: " + errno_text(errno));
    int rc = ::fsync(dfd);
    int err = errno;
    ::close(dfd);
    // Some file systems cannot sync folders (EINVAL); the rename is done anyway.
    if (rc != 0 && err != EINVAL && err != ENOTSUP)
        throw IoError(dir, "cannot flush folder to disk: " + errno_text(err));
}

// ---------------------------------------------------------------------------
// Stopwatch
// ---------------------------------------------------------------------------

namespace {

int64_t now_ns() {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(
               std::chrono::steady_clock::now().time_since_epoch())
        .count();
}

} // namespace

Stopwatch::Stopwatch() : m_start_ns(now_ns()) {}

double Stopwatch::seconds() const {
    return static_cast<double>(now_ns() - m_start_ns) * 1e-9;
}

bool standard_option(const std::string& tool, const std::string& opt,
                     const std::string& usage) {
    if (opt == "h" || opt == "help") {
        std::fputs(usage.c_str(), stdout);
    } else if (opt == "version") {
        std::fputs(version_report(tool).c_str(), stdout);
    } else {
        return false;
    }
    std::fflush(stdout);
    return true;
}

namespace {

std::optional<glm::dvec3> triple_or_fromfile(ArgScanner& args, const std::string& opt,
                                             bool& fromfile, bool allow) {
    if (args.peek() == "fromfile") {
        if (!allow)
            throw UsageError("option -" + opt + ": fromfile is not available here");
        args.value(opt);
        fromfile = true;
        return std::nullopt;
    }
    return args.triple(opt);
}

} // namespace

bool material_option(ArgScanner& args, const std::string& o, MaterialSpec& m,
                     bool allow_fromfile) {
    if (o == "material") {
        m.preset = args.value(o);
        if (!find_material(m.preset))
            throw UsageError("option -material: unknown material '" + m.preset +
                             "' (known: " + material_names() + ")");
    } else if (o == "unitlength") {
        m.unitlength = args.positive(o);
    } else if (o == "scattering") {
        m.scattering = args.triple(o);
    } else if (o == "absorption") {
        m.absorption = args.triple(o);
    } else if (o == "albedo") {
        m.albedo = triple_or_fromfile(args, o, m.albedo_from_file, allow_fromfile);
    } else if (o == "diffusemeanfreepath") {
        m.dmfp = triple_or_fromfile(args, o, m.dmfp_from_file, allow_fromfile);
    } else if (o == "ior") {
        m.ior = args.positive(o);
    } else {
        return false;
    }
    return true;
}

bool run_option(ArgScanner& args, const std::string& o, RunOptions& run) {
    if (o == "threads") {
        run.threads = args.integer(o, -1024, 1024);
    } else if (o == "progress") {
        run.progress = args.integer(o, 0, 2);
    } else if (o == "Progress") {
        run.progress = std::max(run.progress, 1);
    } else if (o == "frame") {
        run.frame = args.integer(o, -1000000, 1000000);
    } else {
        return false;
    }
    return true;
}

bool outputs_up_to_date(const std::string& tool, const std::vector<std::string>& outputs,
                        const std::vector<std::string>& inputs) {
    namespace fs = std::filesystem;
    if (outputs.empty()) return false;
    std::error_code ec;
    std::optional<fs::file_time_type> newest_input;
    for (const std::string& in : inputs) {
        const fs::file_time_type t = fs::last_write_time(in, ec);
        if (ec) return false;
        if (!newest_input || t > *newest_input) newest_input = t;
    }
    for (const std::string& out : outputs) {
        if (!fs::is_regular_file(out, ec) || ec) return false;
        const fs::file_time_type t = fs::last_write_time(out, ec);
        if (ec || (newest_input && !(t > *newest_input))) return false;
    }
    std::string names;
    for (const std::string& out : outputs) names += (names.empty() ? "" : ", ") + out;
    std::printf("%s: %s %s newer than %s inputs; nothing to do\n", tool.c_str(),
                names.c_str(), outputs.size() == 1 ? "is" : "are",
                outputs.size() == 1 ? "its" : "their");
    std::fflush(stdout);
    return true;
}

bool write_option(ArgScanner& args, const std::string& o, PointCloudWriteOptions& write) {
    if (o == "compress") {
        write.compress = args.integer(o, 0, 1) != 0;
    } else if (o == "ptcversion") {
        write.ptc_version = args.integer(o, 0, 2);
    } else {
        return false;
    }
    return true;
}

} // namespace sss
