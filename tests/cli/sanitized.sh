#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# Runs one CLI test script in the sanitizer build (SSS_SANITIZE=ON; CTest uses
# this wrapper there, docs/testing.md): any AddressSanitizer, LeakSanitizer or
# UndefinedBehaviorSanitizer report of a tool the script starts fails the test,
# even when the script discarded the tool's stderr or ignored its exit status.
# A tool dying of a report exits 99 (no tool uses 99 for itself) and leaves a
# mark with its command line in $SSS_SANITIZER_MARKS (src/sanitize).
# Usage: sanitized.sh SCRIPT [ARGS...]
set -uo pipefail

marks="$(mktemp -d "${TMPDIR:-/tmp}/sss_sanitizer.XXXXXX")" || exit 1
trap 'rm -rf "$marks"' EXIT
export SSS_SANITIZER_MARKS="$marks"
# Lets test scripts leave out what cannot work under the sanitizers: ulimit -v
# (ASan reserves terabytes of address space for its shadow memory).
export SSS_SANITIZED=1

bash "$@"
rc=$?

found=("$marks"/mark.*)
if [[ -e "${found[0]}" ]]; then
    echo "FAIL: sanitizer report(s) from ${#found[@]} tool run(s) of $(basename "$1")" \
        "(each report is on that run's stderr, exit status 99):" >&2
    for mark in "${found[@]}"; do
        echo "  pid ${mark##*.}: $(cat "$mark")" >&2
    done
    ((rc != 0)) || rc=1
fi
exit "$rc"
