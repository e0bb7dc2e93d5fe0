// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file job.cpp
/// The job options (-threads, -progress, -frame, -newer) and Job.

#include "sss/cli/job.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "sss/cli/tool.h"
#include "sss/util/messages.h"
#include "sss/util/parse.h"

namespace sss {

std::optional<int> check_frame() {
    // A farm checks a stage's arguments before it adds each task's -frame.
    return check_only() ? std::optional<int>(0) : std::nullopt;
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

bool prman_thread_option(const std::string& o, RunOptions& run) {
    if (o == "p" || o == "t" || o == "t:all" || o == "p:all") {
        run.threads = 0;
    } else if (o.rfind("p:", 0) == 0) {
        run.threads = attached_integer(o, 2, 0, 1024); // processes: a count
    } else if (o.rfind("t:", 0) == 0) {
        run.threads = attached_integer(o, 2, -1024, 1024); // -t:-N: all but N
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
    const std::string names = join(outputs);
    std::printf("%s: %s %s newer than %s inputs; nothing to do\n", tool.c_str(),
                names.c_str(), outputs.size() == 1 ? "is" : "are",
                outputs.size() == 1 ? "its" : "their");
    flush_standard_output();
    return true;
}

bool newer_option(ArgScanner& args, const std::string& o, RunOptions& run) {
    if (o != "newer") return false;
    run.newer = args.integer(o, 0, 1) != 0;
    return true;
}

Job::Job(std::string tool, const RunOptions& run)
    : m_tool(std::move(tool)), m_threads(resolve_thread_count(run.threads)),
      m_level(run.progress), m_newer(run.newer), m_limit(m_threads),
      m_progress(run.progress > 0) {
    m_progress.show_on_terminal(m_tool);
}

bool Job::up_to_date(const std::vector<std::string>& outputs,
                     const std::vector<std::string>& inputs) const {
    return m_newer && outputs_up_to_date(m_tool, outputs, inputs);
}

} // namespace sss
