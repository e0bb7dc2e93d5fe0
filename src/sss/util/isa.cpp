// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file isa.cpp
/// CPU feature detection and the choice of kernel path.

#include "sss/util/isa.h"

#include <cstdlib>

#include "sss/util/error.h"

namespace sss {

const char* isa_name(Isa isa) {
    switch (isa) {
    case Isa::Auto:
        return "auto";
    case Isa::X86_64:
        return "x86-64";
    case Isa::Avx2:
        return "avx2";
    case Isa::Avx512:
        return "avx512";
    }
    return "?";
}

Isa parse_isa(std::string_view name, std::string_view what) {
    if (name == "auto") return Isa::Auto;
    if (name == "x86-64" || name == "sse2" || name == "baseline") return Isa::X86_64;
    if (name == "avx2" || name == "x86-64-v3") return Isa::Avx2;
    if (name == "avx512" || name == "x86-64-v4") return Isa::Avx512;
    throw UsageError(std::string(what) + ": unknown instruction set '" +
                     std::string(name) + "' (auto, x86-64, avx2 or avx512)");
}

bool isa_supported(Isa isa) {
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
    // __builtin_cpu_supports also checks that the OS saves the wide registers.
    __builtin_cpu_init();
    switch (isa) {
    case Isa::Auto:
    case Isa::X86_64:
        return true;
    case Isa::Avx2:
        return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") &&
               __builtin_cpu_supports("bmi2");
    case Isa::Avx512:
        return isa_supported(Isa::Avx2) && __builtin_cpu_supports("avx512f") &&
               __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512cd") &&
               __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512vl");
    }
    return false;
#else
    return isa == Isa::Auto || isa == Isa::X86_64;
#endif
}

Isa best_isa() {
    if (isa_supported(Isa::Avx512)) return Isa::Avx512;
    if (isa_supported(Isa::Avx2)) return Isa::Avx2;
    return Isa::X86_64;
}

Isa requested_isa(Isa requested) {
    if (requested != Isa::Auto) return requested;
    const char* env = std::getenv("SSS_ISA");
    if (!env || !*env) return Isa::Auto;
    return parse_isa(env, "SSS_ISA");
}

Isa resolve_isa(Isa requested) {
    const std::string from = requested == Isa::Auto ? "SSS_ISA" : "-isa";
    requested = requested_isa(requested);
    if (requested == Isa::Auto) return best_isa();
    if (!isa_supported(requested))
        throw UsageError(from + " " + isa_name(requested) +
                         ": this CPU does not support that instruction set (best: " +
                         isa_name(best_isa()) + ")");
    return requested;
}

std::vector<Isa> supported_isas() {
    std::vector<Isa> out;
    for (Isa isa : {Isa::X86_64, Isa::Avx2, Isa::Avx512})
        if (isa_supported(isa)) out.push_back(isa);
    return out;
}

} // namespace sss
