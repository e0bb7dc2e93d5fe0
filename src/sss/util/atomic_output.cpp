/// \file atomic_output.cpp
/// Atomic output files: a unique temporary in the target's folder, renamed
/// over the target on commit, and removed by the signal handler otherwise.

#include "sss/util/atomic_output.h"

#include <atomic>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <random>

#include <fcntl.h>
#include <pthread.h>
#include <unistd.h>

#include <oneapi/tbb/task_scheduler_observer.h>

#include "sss/util/error.h"
#include "sss/util/hash.h"
#include "sss/util/messages.h"

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

/// The thread that installed the handlers (the tool's main thread, which
/// commits outputs).
std::atomic<pthread_t> g_main_thread{};
std::atomic<bool> g_main_thread_set{false};

void block_termination_signals() {
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    sigaddset(&set, SIGHUP);
    ::pthread_sigmask(SIG_BLOCK, &set, nullptr);
}

/// Worker threads block the termination signals, so that the kernel hands
/// them to the main thread: a handler on a worker used to run while the
/// main thread went on to rename its temporary over the target, and the job
/// died by the signal with its output replaced.
class WorkerSignalMask final : public oneapi::tbb::task_scheduler_observer {
public:
    WorkerSignalMask() { observe(true); }
    void on_scheduler_entry(bool is_worker) override {
        if (is_worker) block_termination_signals();
    }
};

std::atomic<WorkerSignalMask*> g_worker_signal_mask{nullptr};

extern "C" void sss_cleanup_and_die(int sig) {
    // Taken by a thread other than the main one (a library's own thread):
    // hand it to the main thread, which is the one that commits.
    if (g_main_thread_set.load(std::memory_order_acquire) &&
        !::pthread_equal(::pthread_self(),
                         g_main_thread.load(std::memory_order_relaxed))) {
        block_termination_signals();
        ::pthread_kill(g_main_thread.load(std::memory_order_relaxed), sig);
        return;
    }
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

} // namespace

void install_signal_handlers() {
    static std::once_flag once;
    std::call_once(once, [] {
        g_main_thread.store(::pthread_self(), std::memory_order_relaxed);
        g_main_thread_set.store(true, std::memory_order_release);
        // Lives until exit (never destroyed: threads may enter until then);
        // held by a global so that leak checkers see it reachable.
        g_worker_signal_mask.store(new WorkerSignalMask(), std::memory_order_release);
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

namespace {

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
    // A job whose report could not be written fails without changing its
    // outputs (docs/cli-conventions.md, "Standard output").
    check_standard_output();
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

} // namespace sss
