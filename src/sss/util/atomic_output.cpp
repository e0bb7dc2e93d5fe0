// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file atomic_output.cpp
/// Atomic output files: a unique, locked temporary in the target's folder,
/// renamed over the target on commit (or written into a device or FIFO
/// target), removed by the signal handler otherwise; sets of outputs
/// committed together; stale temporaries of killed writers removed.

#include "sss/util/atomic_output.h"

#include <fstream>

#include <atomic>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <random>
#include <set>
#include <vector>

#include <dirent.h>
#include <fcntl.h>
#include <limits.h>
#include <pthread.h>
#include <sys/file.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <oneapi/tbb/task_scheduler_observer.h>

#include "sss/util/error.h"
#include "sss/util/hash.h"
#include "sss/util/job_files.h"
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
constexpr int kMaxTempFiles = 512;
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

constexpr int kRandomChars = 8;

/// This host's short name as it appears in temporary names: letters, digits
/// and '-' only, at most 32 characters ("host" when unknown).
const std::string& host_tag() {
    static const std::string tag = [] {
        char buf[256] = {};
        std::string name;
        if (::gethostname(buf, sizeof buf - 1) == 0) name = buf;
        name = name.substr(0, name.find('.'));
        for (char& c : name)
            if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-') c = '-';
        if (name.size() > 32) name.resize(32);
        return name.empty() ? std::string("host") : name;
    }();
    return tag;
}

std::string parent_dir(const std::string& path) {
    std::string dir = std::filesystem::path(path).parent_path().string();
    return dir.empty() ? std::string(".") : dir;
}

/// The folder for the temporaries of device and FIFO targets.
std::string staging_dir() {
    const char* env = std::getenv("TMPDIR");
    struct stat st {};
    if (env && *env && ::stat(env, &st) == 0 && S_ISDIR(st.st_mode)) return env;
    return "/tmp";
}

/// The temporary-name prefix of a target's file name: ".<name>." (the name
/// cut so that the whole temporary name stays within NAME_MAX).
std::string temp_prefix(const std::string& path) {
    std::string base = std::filesystem::path(path).filename().string();
    if (base.size() > 180) base.resize(180);
    return "." + base + ".";
}

/// Whether the writer of temporary `name` (".<name>.<host>.<pid>.<random>.tmp"
/// with the given prefix) is a process of this host that is gone.
bool writer_is_gone(const std::string& name, const std::string& prefix) {
    const std::string suffix = ".tmp";
    if (name.size() < prefix.size() + suffix.size() ||
        name.compare(0, prefix.size(), prefix) != 0 ||
        name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0)
        return false;
    const std::string middle =
        name.substr(prefix.size(), name.size() - prefix.size() - suffix.size());
    // <host>.<pid>.<random>, read from the right (hosts have no '.').
    const std::size_t r = middle.rfind('.');
    if (r == std::string::npos || middle.size() - r - 1 != std::size_t(kRandomChars))
        return false;
    const std::size_t p = middle.rfind('.', r - 1);
    if (p == std::string::npos || p == 0 || r - p - 1 == 0 || r - p - 1 > 10)
        return false;
    if (middle.compare(0, p, host_tag()) != 0 || p != host_tag().size()) return false;
    long long pid = 0;
    for (std::size_t i = p + 1; i < r; ++i) {
        const char c = middle[i];
        if (c < '0' || c > '9') return false;
        pid = pid * 10 + (c - '0');
    }
    if (pid <= 0 || pid > INT_MAX || pid == ::getpid()) return false;
    // EPERM: the process exists (another user's).
    return ::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH;
}

/// Removes the stale temporaries with `prefix` in `dir`: written on this
/// host by a process that is gone, and not locked by anyone (a process of
/// another pid namespace on this host, or of another host through the file
/// system's locks, still holds its lock).
void remove_stale_temporaries(const std::string& dir, const std::string& prefix) {
    DIR* d = ::opendir(dir.c_str());
    if (!d) return;
    const int dfd = ::dirfd(d);
    while (const dirent* e = ::readdir(d)) {
        const std::string name = e->d_name;
        if (!writer_is_gone(name, prefix)) continue;
        const int fd =
            ::openat(dfd, name.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
        if (fd < 0) continue;
        struct stat st {};
        if (::fstat(fd, &st) == 0 && S_ISREG(st.st_mode) &&
            ::flock(fd, LOCK_EX | LOCK_NB) == 0)
            ::unlinkat(dfd, name.c_str(), 0);
        ::close(fd);
    }
    ::closedir(d);
}

/// Where a target goes: the file to replace (symbolic links followed, also
/// to a missing file) and whether it is a device, FIFO or socket.
struct Destination {
    std::string path;
    bool special = false;
};

Destination resolve_destination(const std::string& target) {
    if (target.empty()) throw ValueError("empty output file name");
    const std::string base = std::filesystem::path(target).filename().string();
    if (base.empty() || base == "." || base == "..")
        throw IoError(target, "not a file name (it names a folder)");
    struct stat st {};
    if (::stat(target.c_str(), &st) == 0) {
        if (S_ISDIR(st.st_mode)) throw IoError(target, "is a directory", EISDIR);
        if (!S_ISREG(st.st_mode)) return {target, true};
        struct stat lst {};
        if (::lstat(target.c_str(), &lst) == 0 && S_ISLNK(lst.st_mode)) {
            char* real = ::realpath(target.c_str(), nullptr);
            if (!real)
                throw IoError(target,
                              "cannot follow the symbolic link: " + errno_text(errno));
            std::string path = real;
            std::free(real);
            return {path, false};
        }
        return {target, false};
    }
    const int err = errno;
    if (err == ELOOP) throw IoError(target, "too many levels of symbolic links");
    if (err != ENOENT) return {target, false}; // reported when the temporary is made
    // A dangling link: the file it names is created, as a shell's '>' does.
    std::string path = target;
    for (int hops = 0;; ++hops) {
        struct stat lst {};
        if (::lstat(path.c_str(), &lst) != 0 || !S_ISLNK(lst.st_mode)) break;
        if (hops == 40) throw IoError(target, "too many levels of symbolic links");
        std::vector<char> buf(PATH_MAX + 1);
        const ssize_t n = ::readlink(path.c_str(), buf.data(), buf.size() - 1);
        if (n < 0)
            throw IoError(target,
                          "cannot follow the symbolic link: " + errno_text(errno));
        std::string link(buf.data(), static_cast<std::size_t>(n));
        if (!link.empty() && link[0] != '/')
            link = (std::filesystem::path(parent_dir(path)) / link).string();
        path = link;
    }
    const std::string last = std::filesystem::path(path).filename().string();
    if (last.empty() || last == "." || last == "..")
        throw IoError(target, "the symbolic link names a folder, not a file");
    return {path, false};
}

void block_commit_signals(sigset_t* old) {
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    sigaddset(&set, SIGHUP);
    ::pthread_sigmask(SIG_BLOCK, &set, old);
}

/// Writes all of `n` bytes to fd; false with errno on failure.
bool write_all(int fd, const char* data, std::size_t n, bool socket) {
    while (n > 0) {
        const ssize_t k =
            socket ? ::send(fd, data, n, MSG_NOSIGNAL) : ::write(fd, data, n);
        if (k < 0) {
            if (errno == EINTR) continue;
            return false;
        }
        data += k;
        n -= static_cast<std::size_t>(k);
    }
    return true;
}

/// Opens a device, FIFO or (Unix stream) socket target for writing. A FIFO
/// blocks here until a reader opens it, as a shell's '>' does.
int open_special(const std::string& target, bool& socket) {
    socket = false;
    int fd = -1;
    do {
        fd = ::open(target.c_str(), O_WRONLY | O_NOCTTY | O_CLOEXEC);
    } while (fd < 0 && errno == EINTR);
    if (fd >= 0) return fd;
    if (const int err = errno; err != ENXIO)
        throw IoError(target, "cannot open for writing: " + errno_text(err), err);
    // A socket cannot be opened: connect to it.
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    if (target.size() >= sizeof addr.sun_path)
        throw IoError(target, "socket path too long to connect to");
    std::memcpy(addr.sun_path, target.c_str(), target.size() + 1);
    fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd < 0) throw IoError(target, "cannot make a socket: " + errno_text(errno));
    if (::connect(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
        const int err = errno;
        ::close(fd);
        throw IoError(target, "cannot connect to the socket: " + errno_text(err));
    }
    socket = true;
    return fd;
}

/// Writes the temporary's bytes (read through temp_fd) into a device, FIFO
/// or socket target. A reader that goes away (EPIPE) is an error, not a
/// SIGPIPE death.
void copy_into(const std::string& target, const std::string& temp, int temp_fd) {
    bool socket = false;
    const int out = open_special(target, socket);
    sigset_t pipe_set, old;
    sigemptyset(&pipe_set);
    sigaddset(&pipe_set, SIGPIPE);
    ::pthread_sigmask(SIG_BLOCK, &pipe_set, &old);
    std::vector<char> buf(1 << 20);
    off_t offset = 0;
    int err = 0;
    std::string what;
    while (true) {
        const ssize_t n = ::pread(temp_fd, buf.data(), buf.size(), offset);
        if (n < 0) {
            if (errno == EINTR) continue;
            err = errno;
            what = "cannot read the temporary file '" + temp + "': ";
            break;
        }
        if (n == 0) break;
        if (!write_all(out, buf.data(), static_cast<std::size_t>(n), socket)) {
            err = errno;
            what = err == EPIPE ? "the reader closed it before the whole output was "
                                  "written: "
                                : "cannot write into it: ";
            break;
        }
        offset += n;
    }
    if (err == EPIPE) {
        // Consume the SIGPIPE the failed write raised while it is blocked.
        const timespec zero{0, 0};
        ::sigtimedwait(&pipe_set, nullptr, &zero);
    }
    ::pthread_sigmask(SIG_SETMASK, &old, nullptr);
    const int closed = ::close(out);
    if (err == 0 && closed != 0 && errno != EINTR) {
        err = errno;
        what = "cannot write into it: ";
    }
    if (err != 0) throw IoError(target, what + errno_text(err), err);
}

/// fsyncs a folder so that a rename in it survives a crash.
void sync_folder(const std::string& dir) {
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

/// The active OutputSet (the innermost alive), shared by every thread.
std::atomic<OutputSet*> g_active_set{nullptr};
std::mutex g_set_mutex;

/// Same file: the same inode when both exist, else the same absolute path.
bool same_destination(const std::string& a, const std::string& b) {
    if (a == b) return true;
    struct stat sa {
    }, sb{};
    if (::stat(a.c_str(), &sa) == 0 && ::stat(b.c_str(), &sb) == 0)
        return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
    std::error_code ec1, ec2;
    const auto ca = std::filesystem::weakly_canonical(std::filesystem::absolute(a), ec1);
    const auto cb = std::filesystem::weakly_canonical(std::filesystem::absolute(b), ec2);
    return !ec1 && !ec2 && ca == cb;
}

/// Removes a temporary this process owns and releases its lock.
void discard_temp(const std::string& temp, int& fd) {
    if (temp.empty()) return;
    ::unlink(temp.c_str());
    unregister_temp_file(temp);
    if (fd >= 0) ::close(fd);
    fd = -1;
}

void flush_temp(const std::string& target, const std::string& temp, int fd) {
    if (::fsync(fd) != 0)
        throw IoError(target,
                      "cannot flush '" + temp + "' to disk: " + errno_text(errno));
}

} // namespace

// ---------------------------------------------------------------------------
// AtomicOutput
// ---------------------------------------------------------------------------

AtomicOutput::AtomicOutput(const std::string& target) : m_target(target) {
    check_file_name(target);
    const Destination dest = resolve_destination(target);
    m_destination = dest.path;
    m_special = dest.special;
    const std::string dir = m_special ? staging_dir() : parent_dir(m_destination);
    std::string dir_prefix =
        m_special ? dir : std::filesystem::path(m_destination).parent_path().string();
    if (!dir_prefix.empty() && dir_prefix.back() != '/') dir_prefix += '/';
    const std::string prefix = temp_prefix(m_special ? target : m_destination);
    remove_stale_temporaries(dir, prefix);

    // O_EXCL makes the name ours, the lock says we are alive; the writer
    // later reopens and truncates the same file. The name is registered
    // before the file exists: registered after, a signal in between would
    // leave the new file behind.
    const std::string owner = host_tag() + "." + std::to_string(::getpid()) + ".";
    for (int attempt = 0; attempt < 100; ++attempt) {
        std::string temp =
            dir_prefix + prefix + owner + random_alnum(kRandomChars) + ".tmp";
        register_temp_file(temp);
        int fd = ::open(temp.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (fd >= 0) {
            ::flock(fd, LOCK_EX | LOCK_NB); // a new file: nobody else holds it
            m_temp = temp;
            m_fd = fd;
            return;
        }
        const int err = errno;
        unregister_temp_file(temp);
        if (err != EEXIST)
            throw IoError(target,
                          "cannot create a temporary file in '" + dir +
                              "': " + errno_text(err),
                          err);
    }
    throw IoError(target, "cannot find an unused temporary file name");
}

AtomicOutput::~AtomicOutput() {
    if (m_done) return;
    discard_temp(m_temp, m_fd);
}

void AtomicOutput::commit() {
    if (m_done) return;
    if (OutputSet* set = g_active_set.load(std::memory_order_acquire)) {
        set->adopt(*this);
        return;
    }
    // A job whose report could not be written fails without changing its
    // outputs (docs/cli-conventions.md, "Standard output").
    check_standard_output();
    if (m_special) {
        copy_into(m_target, m_temp, m_fd);
        m_done = true;
        discard_temp(m_temp, m_fd);
        return;
    }
    flush_temp(m_target, m_temp, m_fd);
    sigset_t old;
    block_commit_signals(&old);
    const int rc = ::rename(m_temp.c_str(), m_destination.c_str());
    const int err = errno;
    if (rc == 0) {
        m_done = true;
        unregister_temp_file(m_temp);
    }
    ::pthread_sigmask(SIG_SETMASK, &old, nullptr);
    if (rc != 0)
        throw IoError(m_target,
                      "cannot rename '" + m_temp + "' over it: " + errno_text(err));
    ::close(m_fd);
    m_fd = -1;
    sync_folder(parent_dir(m_destination));
}

// ---------------------------------------------------------------------------
// OutputSet
// ---------------------------------------------------------------------------

OutputSet::OutputSet() {
    std::lock_guard<std::mutex> lock(g_set_mutex);
    m_outer = g_active_set.load(std::memory_order_relaxed);
    g_active_set.store(this, std::memory_order_release);
}

OutputSet::~OutputSet() {
    {
        std::lock_guard<std::mutex> lock(g_set_mutex);
        if (g_active_set.load(std::memory_order_relaxed) == this)
            g_active_set.store(m_outer, std::memory_order_release);
    }
    for (Pending& p : m_pending) discard_temp(p.temp, p.fd);
}

std::vector<std::string> OutputSet::targets() const {
    std::vector<std::string> out;
    for (const Pending& p : m_pending) out.push_back(p.target);
    return out;
}

void OutputSet::adopt(AtomicOutput& out) {
    if (!out.m_special) flush_temp(out.m_target, out.m_temp, out.m_fd);
    std::lock_guard<std::mutex> lock(g_set_mutex);
    for (const Pending& p : m_pending)
        if (same_destination(p.destination, out.m_destination))
            throw IoError(out.m_target,
                          "is written twice by this job (also as '" + p.target + "')");
    m_pending.push_back(
        {out.m_target, out.m_destination, out.m_temp, out.m_fd, out.m_special});
    out.m_done = true;
    out.m_fd = -1;
}

void OutputSet::commit() {
    {
        std::lock_guard<std::mutex> lock(g_set_mutex);
        if (g_active_set.load(std::memory_order_relaxed) == this)
            g_active_set.store(m_outer, std::memory_order_release);
    }
    if (m_outer) {
        // Nested: the outer set commits everything together.
        while (!m_pending.empty()) {
            Pending p = m_pending.front();
            std::lock_guard<std::mutex> lock(g_set_mutex);
            for (const Pending& q : m_outer->m_pending)
                if (same_destination(p.destination, q.destination))
                    throw IoError(p.target, "is written twice by this job (also as '" +
                                                q.target + "')");
            m_outer->m_pending.push_back(p);
            m_pending.erase(m_pending.begin());
        }
        return;
    }
    check_standard_output();
    // Devices and FIFOs first: they can fail (a full device, a reader that
    // went away) while nothing has been renamed yet.
    for (Pending& p : m_pending) {
        if (!p.special) continue;
        copy_into(p.target, p.temp, p.fd);
        discard_temp(p.temp, p.fd);
        p.temp.clear();
    }
    // Then every rename, with the termination signals held: a signal
    // arriving now is handled after the last rename (the job then dies by
    // it, its outputs all new).
    sigset_t old;
    block_commit_signals(&old);
    std::string failed_target, failure;
    std::set<std::string> folders;
    for (Pending& p : m_pending) {
        if (p.special || p.temp.empty()) continue;
        if (::rename(p.temp.c_str(), p.destination.c_str()) != 0) {
            failed_target = p.target;
            failure = "cannot rename '" + p.temp + "' over it: " + errno_text(errno);
            break;
        }
        unregister_temp_file(p.temp);
        p.temp.clear();
        ::close(p.fd);
        p.fd = -1;
        folders.insert(parent_dir(p.destination));
    }
    ::pthread_sigmask(SIG_SETMASK, &old, nullptr);
    if (!failure.empty()) throw IoError(failed_target, failure);
    for (const std::string& dir : folders) sync_folder(dir);
    m_pending.clear();
}

bool writes_into_existing(const std::string& path) {
    struct stat st {};
    return ::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode) && !S_ISDIR(st.st_mode);
}

bool is_standard_output(const std::string& path) {
    struct stat out {
    }, st{};
    return ::fstat(STDOUT_FILENO, &out) == 0 && ::stat(path.c_str(), &st) == 0 &&
           out.st_dev == st.st_dev && out.st_ino == st.st_ino;
}

void check_output_target(const std::string& path) {
    check_file_name(path);
    const Destination dest = resolve_destination(path);
    if (dest.special) return;
    const std::string dir = parent_dir(dest.path);
    struct stat st {};
    if (::stat(dir.c_str(), &st) != 0) {
        const int err = errno;
        throw IoError(path, "cannot write into folder '" + dir + "': " + errno_text(err),
                      err);
    }
    if (!S_ISDIR(st.st_mode))
        throw IoError(path, "cannot write into '" + dir + "': it is not a folder",
                      ENOTDIR);
    if (::access(dir.c_str(), W_OK | X_OK) != 0) {
        const int err = errno;
        throw IoError(path, "cannot write into folder '" + dir + "': " + errno_text(err),
                      err);
    }
}

void write_text_file(const std::string& path, const std::string& text) {
    AtomicOutput out(path);
    {
        std::ofstream f(out.temp_path(), std::ios::binary | std::ios::trunc);
        if (!f) throw IoError(path, "cannot create");
        f.write(text.data(), std::streamsize(text.size()));
        f.flush();
        if (!f) throw IoError(path, "cannot write");
    }
    out.commit();
}

} // namespace sss
