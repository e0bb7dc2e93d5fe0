// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file main.cpp
/// sloinfo: what a compiled shader (.slo) takes: its type and name, and each
/// parameter's storage class, type, array length, output flag and default,
/// laid out as PRMan's sloinfo prints them, or as JSON (-json 1).

#include <iostream>
#include <string>
#include <vector>

#include "sss/cli/tool.h"
#include "sss/rsl/program.h"
#include "sss/rsl/slo_info.h"
#include "sss/util/error.h"

namespace {

const char* const kTool = "sloinfo";

const char* const kUsage = R"(usage: sloinfo [options] file.slo...

Prints, for each compiled shader, its type and name and, per parameter, its
name, "parameter" or "output parameter", storage class (uniform or varying),
type with array length, and default value (as PRMan's sloinfo lays them
out). A default the shader computes when it runs prints as
<computed when the shader runs>.

options:
  -json 0|1      1: one JSON object per line per file (file, type, name,
                 parameters: name, storage, type, array, output, default)
  -check         check the command line only, reading and writing
                 no file: exit 0 if it would run, 2 if not
  -h, --help     this help
  --version      version information

Exit codes: 0 ok, 1 unreadable or invalid file, 2 bad command line.
)";

int run(const std::vector<std::string>& args) {
    bool json = false;
    std::vector<std::string> files;
    sss::ArgScanner scan(args);
    std::string opt;
    while (scan.next_option(opt, files)) {
        if (sss::standard_option(kTool, opt, kUsage)) {
            return 0;
        } else if (opt == "json") {
            json = scan.integer(opt, 0, 1) != 0;
        } else {
            throw sss::unknown_option(opt, kUsage);
        }
    }
    if (files.empty()) throw sss::UsageError("missing input file");
    if (sss::check_only()) return 0;
    for (std::size_t i = 0; i < files.size(); ++i) {
        sss::ScopedStage stage("reading " + files[i]);
        const sss::Program program = sss::read_program_file(files[i]);
        if (json)
            std::cout << sss::describe_shader_json(program, files[i]) << "\n";
        else
            std::cout << (i > 0 ? "\n" : "") << sss::describe_shader(program);
        sss::flush_standard_output();
    }
    return 0;
}

} // namespace

int main(int argc, char** argv) {
    return sss::run_tool(kTool, argc, argv, run);
}
