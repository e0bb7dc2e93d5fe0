#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# CLI test of ptfilter's instruction-set paths (-isa, SSS_ISA): every path this
# CPU has writes the same bytes; -progress 1 names the path that ran; unknown
# names are usage errors (exit 2) and nothing is written.
# Needs SSS_BIN_DIR (the folder with ptfilter and ptsynth).
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
ptfilter="$bin/ptfilter"
ptsynth="$bin/ptsynth"
for tool in "$ptfilter" "$ptsynth"; do
    [[ -x "$tool" ]] || { echo "FAIL: missing executable $tool" >&2; exit 1; }
done
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_ptfilter_isa.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"

# shellcheck source=lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
# shellcheck source=checks.sh
source "$(dirname "${BASH_SOURCE[0]}")/checks.sh"

run "$ptsynth" -n 20000 -size 40 in.ptc
expect_rc 0 "ptsynth" || exit 1

# The paths this CPU has (baseline always).
paths=(x86-64)
flags="$(grep -m1 '^flags' /proc/cpuinfo 2>/dev/null || true)"
has() { [[ " $flags " == *" $1 "* ]]; }
if has avx2 && has fma && has bmi2; then
    paths+=(avx2)
    if has avx512f && has avx512bw && has avx512cd && has avx512dq && has avx512vl; then
        paths+=(avx512)
    fi
fi

unset SSS_ISA
for p in "${paths[@]}"; do
    run "$ptfilter" -ssdiffusion -progress 1 -isa "$p" in.ptc "out_$p.ptc"
    expect_rc 0 "-isa $p" || continue
    grep -q "kernels $p\$" <<<"$out" || fail "-isa $p: -progress 1 does not say 'kernels $p': $out"
    cmp -s out_x86-64.ptc "out_$p.ptc" || fail "-isa $p writes other bytes than x86-64"
done
# The sampled profiles' kernels (disks as their means, with the normals) too.
for p in "${paths[@]}"; do
    run "$ptfilter" -ssdiffusion -profile mc -material skin1 -isa "$p" in.ptc "mc_$p.ptc"
    expect_rc 0 "-profile mc -isa $p" || continue
    cmp -s mc_x86-64.ptc "mc_$p.ptc" || fail "-profile mc -isa $p writes other bytes than x86-64"
done
# An old CPU: glibc's math functions (exp, expm1, sincos, atan2: the profiles
# and their tables) in their SSE2 variants, which glibc picks on a CPU
# without AVX/FMA (masked here with GLIBC_TUNABLES), and the baseline kernels:
# the same bytes as this CPU's best path.
GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2,-FMA,-AVX512F,-AVX run "$ptfilter" -ssdiffusion \
    -isa x86-64 in.ptc old_cpu.ptc
expect_rc 0 "old CPU (GLIBC_TUNABLES, -isa x86-64)" &&
    { cmp -s "out_${paths[-1]}.ptc" old_cpu.ptc || fail "an old CPU's libm and kernels write other bytes"; }

# SSS_ISA picks the path when -isa does not; -isa wins over it.
last="${paths[-1]}"
SSS_ISA=x86-64 run "$ptfilter" -ssdiffusion -progress 1 in.ptc env.ptc
expect_rc 0 "SSS_ISA=x86-64" && { grep -q "kernels x86-64\$" <<<"$out" || fail "SSS_ISA ignored: $out"; }
cmp -s out_x86-64.ptc env.ptc || fail "SSS_ISA=x86-64 writes other bytes"
SSS_ISA=x86-64 run "$ptfilter" -ssdiffusion -progress 1 -isa "$last" in.ptc env.ptc
expect_rc 0 "SSS_ISA + -isa" && { grep -q "kernels $last\$" <<<"$out" || fail "-isa does not win over SSS_ISA: $out"; }
# Without either: the best path.
run "$ptfilter" -ssdiffusion -progress 1 in.ptc best.ptc
expect_rc 0 "auto" && { grep -q "kernels $last\$" <<<"$out" || fail "auto is not the best path ($last): $out"; }

# Bad names: usage errors, one ERROR line, nothing written.
run "$ptfilter" -ssdiffusion -isa avx3 in.ptc bad1.ptc
expect_rc 2 "-isa avx3" && { grep -q "ERROR: option -isa: unknown instruction set 'avx3'" <<<"$err" || fail "-isa avx3 message: $err"; }
SSS_ISA=fast run "$ptfilter" -ssdiffusion in.ptc bad2.ptc
expect_rc 2 "SSS_ISA=fast" && { grep -q "ERROR: SSS_ISA: unknown instruction set 'fast'" <<<"$err" || fail "SSS_ISA=fast message: $err"; }
[[ ! -e bad1.ptc && ! -e bad2.ptc ]] || fail "a failed run wrote its output"
# A path this CPU lacks is refused (only testable on a CPU without AVX-512).
if [[ "$last" != avx512 ]]; then
    run "$ptfilter" -ssdiffusion -isa avx512 in.ptc bad3.ptc
    expect_rc 2 "-isa avx512 on a CPU without it"
    grep -q "does not support" <<<"$err" || fail "unsupported path message: $err"
fi

finish_checks ptfilter_isa
