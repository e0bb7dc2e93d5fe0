// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file job.h
/// What every tool that runs a job shares: the -threads, -progress, -frame and
/// -newer options, and Job, which turns them into the thread limit, the
/// ALF_PROGRESS reporter, the stopwatch and the -newer test.

#include <optional>
#include <string>
#include <vector>

#include "sss/cli/args.h"
#include "sss/util/progress.h"
#include "sss/util/threads.h"

namespace sss {

/// The frame a dry parse (-check, check_only() in tool.h) without -frame
/// expands file names' patterns with, so that the names behind them are
/// checked: 0. nullopt in a run, where a pattern needs -frame.
std::optional<int> check_frame();

/// The options of every tool that runs a job: -threads N, -progress 0|1|2
/// and its alias -Progress (= 1), -frame N for frame patterns in paths
/// (frame_pattern.h), and -newer 0|1 for the tools that take it.
struct RunOptions {
    int threads = 0;
    int progress = 0;
    std::optional<int> frame = check_frame();
    bool newer = false;
};
/// Parses -threads, -progress, -Progress or -frame into run; false when opt
/// is none of them.
bool run_option(ArgScanner& args, const std::string& opt, RunOptions& run);
/// prman's spellings of the thread count, for the tools that run RIB files
/// (render, ptbake): -p and -t (every usable core), -p:N (N threads, 0
/// every core), -t:N (the same, and -N all but N, as -threads), -t:all. False when
/// opt is none of them; UsageError for a malformed count.
bool prman_thread_option(const std::string& opt, RunOptions& run);
/// Parses -newer 0|1 into run (ptfilter, brickmake, ptbake, render); false
/// when opt is not -newer.
bool newer_option(ArgScanner& args, const std::string& opt, RunOptions& run);

/// The `-newer 1` test of ptfilter, brickmake, ptbake and render: true when
/// every output exists and was modified strictly after every input (file
/// system time, full resolution). Then it prints "<tool>: OUT is newer than
/// its inputs; nothing to do" on stdout and the tool exits 0 without work.
/// False when an output or an input is missing (the job then runs and
/// reports a missing input itself), or when there are no outputs.
bool outputs_up_to_date(const std::string& tool, const std::vector<std::string>& outputs,
                        const std::vector<std::string>& inputs);

/// One job of a tool, from its RunOptions: while alive, oneTBB runs on the
/// resolved thread count; progress() reports ALF_PROGRESS lines when
/// -progress is given; seconds() is the time since the job started.
class Job {
public:
    Job(std::string tool, const RunOptions& run);
    Job(const Job&) = delete;
    Job& operator=(const Job&) = delete;

    /// The resolved -threads count (0 = every usable core, -k = all but k).
    int threads() const { return m_threads; }
    /// The reporter to hand to the library (prints only with -progress >= 1).
    Progress* progress() { return &m_progress; }
    /// -progress 1 or more: the tool prints its summary lines.
    bool verbose() const { return m_level > 0; }
    /// -progress 2: the tool prints its detailed statistics too.
    bool detailed() const { return m_level > 1; }
    /// Seconds since the job started.
    double seconds() const { return m_watch.seconds(); }
    /// -newer 1 given and outputs_up_to_date(): the tool then exits 0 without work.
    bool up_to_date(const std::vector<std::string>& outputs,
                    const std::vector<std::string>& inputs) const;
    /// Whether -newer 1 was given (to skip finding the files otherwise).
    bool newer() const { return m_newer; }

private:
    std::string m_tool;
    int m_threads;
    int m_level;
    bool m_newer;
    ThreadLimit m_limit;
    Progress m_progress;
    Stopwatch m_watch;
};

} // namespace sss
