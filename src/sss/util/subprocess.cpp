// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file subprocess.cpp
/// run_filter: a child process with pipes on its standard input and output,
/// driven by poll() against one deadline.

#include "sss/util/subprocess.h"

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <thread>

#include <fcntl.h>
#include <poll.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include "sss/util/error.h"

extern char** environ;

namespace sss {

namespace {

using Clock = std::chrono::steady_clock;

/// A pipe whose ends close themselves.
struct Pipe {
    int fd[2] = {-1, -1};
    Pipe() {
        if (::pipe2(fd, O_CLOEXEC) != 0)
            throw IoError("pipe",
                          std::string("cannot create a pipe: ") + std::strerror(errno));
    }
    ~Pipe() {
        close_end(0);
        close_end(1);
    }
    void close_end(int k) {
        if (fd[k] >= 0) ::close(fd[k]);
        fd[k] = -1;
    }
};

/// Waits for the child until `deadline`, then kills it; returns its status.
int reap(pid_t pid, Clock::time_point deadline) {
    int status = 0;
    for (;;) {
        const pid_t r = ::waitpid(pid, &status, WNOHANG);
        if (r == pid) return status;
        if (r < 0 && errno != EINTR) return 0;
        if (Clock::now() >= deadline) {
            ::kill(pid, SIGKILL);
            ::waitpid(pid, &status, 0);
            return status;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
}

} // namespace

std::string run_filter(const std::vector<std::string>& argv, const std::string& input,
                       int stop, const FilterLimits& limits, const std::string& what) {
    if (argv.empty() || argv[0].empty()) throw IoError(what, "no program to run");
    Pipe in, out;
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, in.fd[0], STDIN_FILENO);
    posix_spawn_file_actions_adddup2(&actions, out.fd[1], STDOUT_FILENO);
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    pid_t pid = 0;
    const int err =
        ::posix_spawnp(&pid, args[0], &actions, nullptr, args.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (err != 0)
        throw IoError(what, "cannot run \"" + argv[0] + "\": " + std::strerror(err));
    in.close_end(0);
    out.close_end(1);
    // A program that dies early must not kill us with SIGPIPE.
    struct sigaction ignore {
    }, saved{};
    ignore.sa_handler = SIG_IGN;
    ::sigaction(SIGPIPE, &ignore, &saved);

    const auto deadline =
        Clock::now() + std::chrono::duration_cast<Clock::duration>(
                           std::chrono::duration<double>(limits.timeout_seconds));
    std::string answer;
    std::size_t written = 0;
    bool done = false;
    bool stopped = false; // the stop byte came
    std::string failure;
    char buf[65536];
    while (!done && failure.empty()) {
        pollfd fds[2] = {{out.fd[0], POLLIN, 0}, {in.fd[1], POLLOUT, 0}};
        const nfds_t n = in.fd[1] >= 0 ? 2 : 1;
        const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
            deadline - Clock::now());
        if (left.count() <= 0) {
            failure = "no answer within " + std::to_string(limits.timeout_seconds) + " s";
            break;
        }
        const int r =
            ::poll(fds, n, static_cast<int>(std::min<long long>(left.count(), 1000)));
        if (r < 0 && errno != EINTR)
            failure = std::string("poll: ") + std::strerror(errno);
        if (r <= 0) continue;
        if (n == 2 && (fds[1].revents & (POLLOUT | POLLERR | POLLHUP))) {
            const ssize_t w =
                ::write(in.fd[1], input.data() + written, input.size() - written);
            if (w > 0) written += static_cast<std::size_t>(w);
            if (w < 0 && errno != EAGAIN && errno != EINTR)
                in.close_end(1); // it stopped reading
            if (written == input.size()) in.close_end(1);
        }
        if (fds[0].revents & (POLLIN | POLLHUP | POLLERR)) {
            const ssize_t got = ::read(out.fd[0], buf, sizeof buf);
            if (got < 0 && errno != EINTR && errno != EAGAIN)
                failure = std::string("read: ") + std::strerror(errno);
            if (got == 0) done = true;
            for (ssize_t k = 0; k < got && !done; ++k) {
                if (stop >= 0 && static_cast<unsigned char>(buf[k]) == stop)
                    done = stopped = true;
                else
                    answer.push_back(buf[k]);
            }
            if (answer.size() > limits.max_output)
                failure =
                    "answered more than " + std::to_string(limits.max_output) + " bytes";
        }
    }
    in.close_end(1);
    out.close_end(0);
    const int status = reap(pid, failure.empty() ? Clock::now() + std::chrono::seconds(5)
                                                 : Clock::now());
    ::sigaction(SIGPIPE, &saved, nullptr);
    if (!failure.empty()) throw IoError(what, "\"" + argv[0] + "\": " + failure);
    // After its answer, how the program ends does not matter.
    if (WIFSIGNALED(status) && !stopped)
        throw IoError(what, "\"" + argv[0] + "\" was killed by signal " +
                                std::to_string(WTERMSIG(status)));
    if (WIFEXITED(status) && WEXITSTATUS(status) != 0 && !stopped)
        throw IoError(what, "\"" + argv[0] + "\" exited with status " +
                                std::to_string(WEXITSTATUS(status)));
    return answer;
}

} // namespace sss
