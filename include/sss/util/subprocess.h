// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file subprocess.h
/// Running a helper program as a filter: what RiProcedural "RunProgram"
/// needs (the RIB reader writes a request to the program's standard input
/// and reads the RIB it answers with).

#include <cstddef>
#include <string>
#include <vector>

namespace sss {

/// How long and how much a filter program may take.
struct FilterLimits {
    double timeout_seconds = 300.0; ///< for the whole exchange
    std::size_t max_output = std::size_t(1) << 30;
};

/// Runs argv (argv[0] searched on PATH when it has no '/'), its standard
/// error inherited, writes `input` to its standard input and reads its
/// standard output up to the first `stop` byte (-1: to the end); then
/// closes its standard input and waits for it to exit (a program that does
/// not within a few seconds is killed). Throws IoError naming `what` when
/// the program cannot start, fails (exit status or signal) without having
/// sent the stop byte, answers more than the limit or takes longer.
std::string run_filter(const std::vector<std::string>& argv, const std::string& input,
                       int stop, const FilterLimits& limits, const std::string& what);

} // namespace sss
