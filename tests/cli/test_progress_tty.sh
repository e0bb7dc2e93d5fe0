#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# The terminal progress line (sss/util/progress.h, docs/cli-conventions.md):
# with stderr on a terminal (a pseudo-terminal from script(1)) a long stage
# shows one line rewritten in place with the stage, percent, rate and time
# left, erased at the end; off a terminal, and with SSS_TTY_PROGRESS=0, stderr
# stays empty and the ALF_PROGRESS lines are unchanged.
# Needs SSS_BIN_DIR (the folder with the built executables).
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_progress_tty.XXXXXX")"
trap 'rm -rf "$work"' EXIT
fail() {
    echo "FAIL: $*" >&2
    exit 1
}
command -v script >/dev/null || fail "script(1) (bsdutils) is needed for a pseudo-terminal"

cd "$work"
"$bin/ptsynth" -n 8000 -light 1 1 1 big.ptc >/dev/null
"$bin/ptsynth" -n 5000 -light 1 1 1 in.ptc >/dev/null
# All pairs on one thread: a stage of 3 s or more for big.ptc (the line shows
# after 0.5 s, the time left after 2 s: sss::TimeLeftEstimator), 1 s for in.ptc.
filter=("$bin/ptfilter" -ssdiffusion -exact -threads 1 in.ptc out.ptc)

# On a terminal: stdout and stderr both go to the pseudo-terminal.
script -qec "$bin/ptfilter -ssdiffusion -exact -threads 1 big.ptc out.ptc" /dev/null >tty.txt ||
    fail "ptfilter on a terminal failed: $(cat tty.txt)"
cr=$'\r'
esc=$'\033'
grep -q "${cr}ptfilter: evaluating the diffusion (all pairs) *[0-9]*%  [0-9.]* k\?M\?G\? \?points/s  [0-9]*:[0-9][0-9] left${esc}\[K" tty.txt ||
    fail "no progress line on the terminal: $(cat -v tty.txt | head -c 600)"
# Never "0:00 left" while the work runs.
grep -q " 0:00 left" tty.txt && fail "0:00 left shown: $(cat -v tty.txt | head -c 600)"
# Erased at the end: the last thing the line wrote is the erase sequence.
last="$(tr "$cr" '\n' <tty.txt | grep -v '^$' | tail -1)"
[[ "$last" == "${esc}[K" ]] || fail "the progress line was not erased: last '$(cat -v <<<"$last")'"

# Off a terminal: nothing on stderr, nothing but ALF lines on stdout.
"${filter[@]}" -progress 0 >plain.out 2>plain.err
[[ ! -s plain.err && ! -s plain.out ]] || fail "output off a terminal: $(cat plain.out plain.err)"
"$bin/ptfilter" -ssdiffusion -exact -threads 1 -progress 1 in.ptc out.ptc >alf.out 2>alf.err
[[ ! -s alf.err ]] || fail "stderr off a terminal: $(cat -v alf.err)"
grep -q "$cr" alf.out && fail "a carriage return in a farm log"
grep -qx 'ALF_PROGRESS 100%' alf.out || fail "no ALF_PROGRESS 100% line: $(cat alf.out)"
bad="$(grep '^ALF_PROGRESS' alf.out | grep -vx 'ALF_PROGRESS [0-9]*%' || true)"
[[ -z "$bad" ]] || fail "ALF lines changed: $bad"

# SSS_TTY_PROGRESS=0 turns the line off, even on a terminal.
SSS_TTY_PROGRESS=0 script -qec "${filter[*]}" /dev/null >off.txt || fail "ptfilter failed"
grep -q "$cr"ptfilter off.txt && fail "SSS_TTY_PROGRESS=0 still drew the line: $(cat -v off.txt | head -c 300)"
echo "all progress_tty CLI checks passed"
