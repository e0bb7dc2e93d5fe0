// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file isa.h
/// Instruction-set paths for the hot kernels. The tools are built for baseline
/// x86-64, so one binary runs on every x86-64 machine; the kernels that pay
/// for wider vectors (ptfilter's evaluation) are compiled once per path and
/// chosen at run time: the best the CPU has, or the one `SSS_ISA` (or a
/// tool's `-isa` option) names, so that every node of a farm can run the same
/// path. The paths give identical results (docs/ptfilter.md#instruction-sets).

#include <string>
#include <string_view>
#include <vector>

namespace sss {

/// A kernel path. Auto: SSS_ISA if set, else the best the CPU supports.
enum class Isa {
    Auto,
    X86_64, ///< baseline x86-64 (SSE2)
    Avx2,   ///< x86-64-v3: AVX2, FMA, BMI2
    Avx512, ///< x86-64-v4: AVX-512 F/BW/CD/DQ/VL
};

/// The name used by SSS_ISA and -isa: "auto", "x86-64", "avx2", "avx512".
const char* isa_name(Isa isa);

/// Parses an ISA name (also "sse2", "baseline", "x86-64-v3", "x86-64-v4");
/// throws UsageError naming the accepted values and `what` (e.g. "SSS_ISA").
Isa parse_isa(std::string_view name, std::string_view what);

/// Whether this CPU (and OS) can run the path.
bool isa_supported(Isa isa);

/// The best path this CPU supports.
Isa best_isa();

/// The path asked for: `requested`, or for Auto the one the SSS_ISA environment
/// variable names (Auto when it is unset or "auto"). Throws UsageError for a
/// name SSS_ISA cannot hold; whether this CPU runs the path is not checked (a
/// dry parse on a machine that is not the one that will run).
Isa requested_isa(Isa requested = Isa::Auto);

/// The path to run: `requested`, or for Auto the SSS_ISA environment variable,
/// or best_isa(). Throws UsageError when the path named is not supported by
/// this CPU: a farm that asked for one path never silently gets another.
Isa resolve_isa(Isa requested = Isa::Auto);

/// The paths this CPU supports, baseline first.
std::vector<Isa> supported_isas();

} // namespace sss
