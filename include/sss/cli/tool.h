// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file tool.h
/// Module cli: everything about command lines; the only module that knows
/// option names.
/// May use: brick, image, diffusion, cloud and util (and reports the versions of
/// every library).
///
/// The command-line layer every tool's main() is built on: error reporting
/// and exit codes (run_tool), --help/--version, warnings. Includes the option
/// scanner and the shared option groups, so a main needs this one header
/// (plus the library headers of the job it runs).

#include <exception>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "sss/cli/args.h"
#include "sss/cli/job.h"
#include "sss/cli/options.h"
#include "sss/util/atomic_output.h"
#include "sss/util/limits.h"
#include "sss/util/messages.h"
#include "sss/util/progress.h"
#include "sss/util/threads.h"
#include "sss/util/version.h"

namespace sss {

/// Multi-line build description for --version: project version and the
/// versions of the libraries it is built with (OpenEXR, OIIO, Embree, oneTBB, zlib).
std::string version_report(const std::string& tool);

/// Runs body(args) with the tools' uniform error handling. args excludes argv[0]
/// and -check (check_only()).
/// UsageError -> "<tool> ERROR: <what>" on stderr, exit 2; std::bad_alloc ->
/// "<tool> ERROR: out of memory while <stage>" (limits.h), exit 1; any other
/// exception -> "<tool> ERROR: <what>", exit 1. Every message is one line
/// (control bytes escaped). A write error on standard output fails the job:
/// "<tool> ERROR: cannot write to standard output: <reason>", exit 1.
/// Returns body's result otherwise, after the warning summaries. Under -check
/// every error exits 2 (the command line is refused).
int run_tool(const std::string& tool, int argc, char** argv,
             const std::function<int(const std::vector<std::string>&)>& body);

/// Whether the command line asked for a dry parse: `-check` (or `--check`),
/// anywhere on it. run_tool takes the word out before the tool parses the
/// rest; the tool then parses and checks its whole command line as for a run
/// (options and their values, the number of file arguments, frame patterns,
/// the file names' extensions, materials) and returns 0 where its checks end,
/// before it opens an input or touches an output: `if (sss::check_only())
/// return 0;`. Every error of a -check run exits 2 (the command would be
/// refused), with the usual ERROR line. What the file system holds (whether
/// inputs exist, output folders are writable) is not looked at: a farm checks
/// a frame's command line before any of its files exist. Without -frame, file
/// names' frame patterns are expanded with frame 0 (check_frame()): checked
/// as patterns, without asking for the frame a farm adds to each task.
bool check_only();

/// Handles the options every tool shares: "-h"/"help" prints usage and
/// "version" prints version_report(tool), both on stdout. Returns true when
/// opt (without dashes) was one of them: the tool then exits 0.
bool standard_option(const std::string& tool, const std::string& opt,
                     const std::string& usage);

/// The message a tool prints for a library error that concerns something its
/// command line sets, in the options' words: a frame pattern without a frame
/// ("...; give the frame with -frame N"), a material given in both forms, an
/// impossible material value ("impossible -albedo value ..."), a channel the
/// diffusion needs that the input lacks ("...; set it with -radiancechannel").
/// nullopt for
/// any other error (its what() is the message). run_tool uses it.
std::optional<std::string> option_wording(const std::exception& e);

/// Prints "<tool> WARNING: <what>" on stderr, one line, unless
/// Warnings::kKeptPerKind warnings of its kind were printed already: those
/// are counted, and summarised at the end of run_tool ("<tool> WARNING: 12
/// more warnings like "..." not shown").
void warn(const std::string& tool, const std::string& what);

/// warn() for each kept warning, and the omitted ones counted for the summary.
void warn_all(const std::string& tool, const Warnings& warnings);

/// Prints the summaries of the warnings not printed so far (run_tool does,
/// before an ERROR line or at the end).
void print_warning_summaries(const std::string& tool);

} // namespace sss
