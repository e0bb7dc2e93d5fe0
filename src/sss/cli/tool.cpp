// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file tool.cpp
/// Shared command-line behaviour: --version, error reporting and exit codes.

#include "sss/cli/tool.h"

#include <cstdio>
#include <iostream>
#include <new>
#include <optional>
#include <sstream>

#include <OpenEXR/OpenEXRConfig.h>
#include <OpenImageIO/oiioversion.h>
#include <embree3/rtcore_config.h>
#include <oneapi/tbb/version.h>
#include <zlib.h>

#include "sss/diffusion/material.h"
#include "sss/diffusion/ssdiffusion.h"
#include "sss/util/error.h"
#include "sss/util/frame_pattern.h"
#include "sss/util/limits.h"
#include "sss/util/messages.h"
#include "sss/util/progress.h"

namespace sss {

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

/// Longest message printed (bytes): a message is one line a farm's log
/// parser reads; echoes of input are already cut to kMaxEcho.
constexpr std::size_t kMaxMessage = 4096;

/// The warnings printed so far, by kind: a kind is printed
/// Warnings::kKeptPerKind times, then counted.
Warnings& printed_warnings() {
    static Warnings* printed = new Warnings(); // never destroyed: used at exit
    return *printed;
}

/// `what` as one line: control bytes escaped, cut at kMaxMessage.
std::string one_line(const std::string& what) {
    return escape_control(truncated(what, kMaxMessage));
}

void print_line(const std::string& tool, const char* kind, const std::string& what) {
    // stdout first, so that merged logs keep their order; a terminal's
    // progress line goes, so that the message starts a line of its own.
    flush_standard_output();
    clear_terminal_progress();
    std::cerr << tool << kind << one_line(what) << "\n";
    std::cerr.flush();
}

void print_error(const std::string& tool, const std::string& what) {
    print_warning_summaries(tool);
    print_line(tool, " ERROR: ", what);
}

/// -check was given: set by run_tool while the tool's body runs.
bool g_check_only = false;

/// The arguments without the -check words; sets g_check_only while alive when
/// there was one.
class CheckOption {
public:
    CheckOption(int argc, char** argv) {
        for (int i = 1; i < argc; ++i) {
            const std::string word = argv[i];
            if (word == "-check" || word == "--check")
                g_check_only = true;
            else
                m_args.push_back(word);
        }
    }
    ~CheckOption() { g_check_only = false; }
    CheckOption(const CheckOption&) = delete;
    CheckOption& operator=(const CheckOption&) = delete;
    const std::vector<std::string>& args() const { return m_args; }

private:
    std::vector<std::string> m_args;
};

} // namespace

bool check_only() {
    return g_check_only;
}

std::optional<std::string> option_wording(const std::exception& e) {
    // The library names settings; a tool names the options that set them.
    if (const auto* frame = dynamic_cast<const MissingFrameError*>(&e))
        return std::string(frame->what()) + "; give the frame with -frame N";
    if (dynamic_cast<const MaterialFormError*>(&e))
        return std::string("give the material either as -scattering/-absorption or as "
                           "-albedo/-diffusemeanfreepath, not both");
    if (const auto* value = dynamic_cast<const MaterialValueError*>(&e))
        return "impossible -" + value->field() + " value " +
               std::to_string(value->value());
    if (const auto* missing = dynamic_cast<const MissingChannelError*>(&e)) {
        const char* option = "-radiancechannel";
        if (missing->role() == MissingChannelError::Role::Albedo)
            option = "-albedo fromfile";
        else if (missing->role() == MissingChannelError::Role::Dmfp)
            option = "-diffusemeanfreepath fromfile";
        return (missing->inputs().empty() ? "" : missing->inputs() + ": ") +
               "input has no channel '" + missing->channel() + "' (set it with " +
               option + "; channels present: " + missing->present() + ")";
    }
    return std::nullopt;
}

int run_tool(const std::string& tool, int argc, char** argv,
             const std::function<int(const std::vector<std::string>&)>& body) {
    install_signal_handlers();
    const CheckOption check(argc, argv);
    // A -check run that fails was refused, whatever the error's kind.
    const auto failed = [](int code) { return g_check_only ? 2 : code; };
    try {
        int status = body(check.args());
        // A result nobody could read (closed pipe, full disk) is a failure,
        // --help and --version included (as in GNU coreutils).
        const std::string stdout_error = standard_output_error();
        if (!stdout_error.empty()) {
            print_error(tool, StandardOutputError(stdout_error).what());
            return status == 0 ? 1 : status;
        }
        print_warning_summaries(tool);
        return status;
    } catch (const UsageError& e) {
        print_error(tool, option_wording(e).value_or(e.what()));
        std::cerr << tool << ": try '" << tool << " --help'\n";
        std::cerr.flush();
        return 2;
    } catch (const std::bad_alloc&) {
        std::string stage = failure_stage();
        print_error(tool, "out of memory while " +
                              (stage.empty() ? std::string("running") : stage));
        return 1;
    } catch (const std::exception& e) {
        print_error(tool, option_wording(e).value_or(e.what()));
        return failed(1);
    } catch (...) {
        print_error(tool, "unknown exception");
        return failed(1);
    }
}

void warn(const std::string& tool, const std::string& what) {
    if (printed_warnings().push_back(what)) print_line(tool, " WARNING: ", what);
}

void warn_all(const std::string& tool, const Warnings& warnings) {
    for (const std::string& w : warnings) warn(tool, w);
    for (const Warnings::Omitted& o : warnings.omitted())
        printed_warnings().add_omitted(o.label, o.count);
}

void print_warning_summaries(const std::string& tool) {
    Warnings& printed = printed_warnings();
    for (const std::string& line : printed.summaries())
        print_line(tool, " WARNING: ", line);
    printed = Warnings(); // printed once
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
    flush_standard_output(); // run_tool reports a failure
    return true;
}

} // namespace sss
