#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# CLI test of ptsynth: output, point counts, exit codes, error lines, atomic output.
# Needs SSS_BIN_DIR (the folder with the built executables).
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
ptsynth="$bin/ptsynth"
ptinfo="$bin/ptinfo"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_ptsynth.XXXXXX")"
trap 'rm -rf "$work"' EXIT

fail() {
    echo "FAIL: $*" >&2
    exit 1
}

# shellcheck source=lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"

expect_rc() {
    [[ "$rc" == "$1" ]] || fail "expected exit $1, got $rc: ${*:2}"$'\n'"stdout: $out"$'\n'"stderr: $err"
}

# --help and --version go to stdout with exit 0.
run "$ptsynth" --help
expect_rc 0 --help
[[ "$out" == *"usage: ptsynth"* ]] || fail "--help lacks usage line"
[[ -z "$err" ]] || fail "--help wrote to stderr: $err"
run "$ptsynth" -h
expect_rc 0 -h
run "$ptsynth" --version
expect_rc 0 --version
[[ "$out" == "ptsynth (sss) "* ]] || fail "--version starts with: $out"

# Each shape writes a file with the expected number of points.
check_count() { # file expected
    [[ -s "$1" ]] || fail "no output $1"
    if [[ -x "$ptinfo" ]]; then
        run "$ptinfo" "$1"
        expect_rc 0 ptinfo "$1"
        grep -Eq "^points: $2\$" "$work/stdout" || fail "ptinfo of $1 does not report $2 points: $out"
    fi
}

run "$ptsynth" -shape sphere -n 1000 -size 5 -light 1 1 1 "$work/sphere.ptc"
expect_rc 0 sphere
[[ "$out" == *"1000 points"* ]] || fail "sphere summary: $out"
check_count "$work/sphere.ptc" 1000

run "$ptsynth" -shape plane -n 900 -size 10 -jitter 0.5 -seed 7 -ambient 0.2 "$work/plane.ply"
expect_rc 0 plane
check_count "$work/plane.ply" 900

run "$ptsynth" -shape box -n 2000 -size 10 -thickness 2 -compress 1 "$work/box.ptc"
expect_rc 0 box
[[ "$(head -c 2 "$work/box.ptc" | od -An -tx1 | tr -d ' ')" == "1f8b" ]] ||
    fail "-compress 1 did not gzip the output"

# Same arguments -> identical bytes (deterministic, also with jitter).
run "$ptsynth" -shape plane -n 900 -size 10 -jitter 0.5 -seed 7 -ambient 0.2 "$work/plane2.ply"
expect_rc 0 plane again
cmp -s "$work/plane.ply" "$work/plane2.ply" || fail "same seed gave different files"

# Rewriting an existing output replaces it.
run "$ptsynth" -shape sphere -n 500 "$work/sphere.ptc"
expect_rc 0 overwrite
check_count "$work/sphere.ptc" 500

# Usage errors: exit 2 with an ERROR line naming the problem.
run "$ptsynth" -bogus "$work/x.ptc"
expect_rc 2 bad option
[[ "$err" == *"ptsynth ERROR:"*"-bogus"* ]] || fail "bad option message: $err"
[[ "$err" == *"ptsynth --help"* ]] || fail "no --help hint: $err"

run "$ptsynth" -n abc "$work/x.ptc"
expect_rc 2 -n abc
[[ "$err" == *"ptsynth ERROR:"*"-n"*"abc"* ]] || fail "-n abc message: $err"

run "$ptsynth" -size -3 "$work/x.ptc"
expect_rc 2 negative size
run "$ptsynth" -size
expect_rc 2 missing value
[[ "$err" == *"-size needs a value"* ]] || fail "missing value message: $err"
run "$ptsynth" -light 1 2 "$work/x.ptc"
expect_rc 2 short triple
run "$ptsynth" -shape cube "$work/x.ptc"
expect_rc 2 unknown shape
run "$ptsynth"
expect_rc 2 no output
run "$ptsynth" a.ptc b.ptc
expect_rc 2 two outputs
[[ ! -e "$work/x.ptc" ]] || fail "a usage error left an output file"

# Runtime failure: missing output folder -> exit 1, nothing written.
run "$ptsynth" -n 100 "$work/missing/out.ptc"
expect_rc 1 missing folder
[[ "$err" == "ptsynth ERROR: "* ]] || fail "missing folder message: $err"
[[ ! -e "$work/missing" ]] || fail "the missing folder was created"

# No temporary files are left anywhere in the work folder.
leftovers="$(find "$work" -name '*.tmp')"
[[ -z "$leftovers" ]] || fail "temporary files left: $leftovers"

echo "ptsynth CLI tests passed"
