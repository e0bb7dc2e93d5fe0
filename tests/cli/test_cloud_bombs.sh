#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# CLI test of point-cloud memory bombs (issue 15): tiny gzip .ptc and .ply
# files whose headers claim about 2^31 points (tests/data/hostile/clouds,
# made by make_clouds.py) make ptinfo, ptfilter and brickmake fail at once
# under ulimit -v 1.5 GB with one "<tool> ERROR:" line naming the file and
# what is missing (a FormatError: no "out of memory", no bad_alloc). A real
# gzip bomb, whose data is all there but inflates past the memory the process
# may use (SSS_MEMORY_LIMIT), stops with an error saying how much memory is
# needed, before the arrays outgrow the budget.
# Needs SSS_BIN_DIR and SSS_TEST_DATA_DIR.
#
# Every check runs; failures are listed and the script exits 1 at the end.
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
data="${SSS_TEST_DATA_DIR:?SSS_TEST_DATA_DIR must name tests/data}/hostile/clouds"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_cloud_bombs.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"

# shellcheck source=lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
# shellcheck source=checks.sh
source "$(dirname "${BASH_SOURCE[0]}")/checks.sh"

# limited CMD...: under ulimit -v 1.5 GB (not under the sanitizers, whose
# shadow memory needs terabytes of address space) and a 90 s hang guard.
limited() {
    if [[ -n "${SSS_SANITIZED:-}" ]]; then
        timeout 90 "$@"
    else
        (
            ulimit -v 1500000
            exec timeout 90 "$@"
        )
    fi
}

# refused LABEL TOOL WHAT ARGS...: exit 1 within the guard, the first ERROR
# line is "TOOL ERROR: <file>: ...WHAT...", nothing about running out of
# memory, and no output file.
refused() {
    local label="$1" tool="$2" what="$3"
    shift 3
    rm -f out.ptc out.bkm
    run limited "$bin/$tool" "$@"
    [[ "$rc" != 124 ]] || { fail "$label: killed after 20 s"; return; }
    expect_rc 1 "$label" || return 0
    local first
    first="$(grep -m1 ERROR <<<"$err" || true)"
    [[ "$first" == "$tool ERROR: "*"$input: "*"$what"* ]] ||
        fail "$label: expected '$input: ...$what': $err"
    [[ "$err" != *"out of memory"* && "$err" != *bad_alloc* ]] ||
        fail "$label: ran out of memory: $err"
    [[ ! -e out.ptc && ! -e out.bkm ]] || fail "$label: wrote an output"
}

for case in "claims_2g_gz.ptc:more than the compressed file can hold" \
    "claims_2g_gz.ply:header claims 2147483648 vertices but the file is too short" \
    "claims_2g_ascii_gz.ply:header claims 2147483648 vertices but the file is too short" \
    "claims_2k_gz.ptc:header claims 2000 points, data ends after 4 (point 4)"; do
    input="${case%%:*}"
    what="${case#*:}"
    cp "$data/$input" .
    refused "ptinfo $input" ptinfo "$what" "$input"
    refused "ptfilter $input" ptfilter "$what" -ssdiffusion -unitlength 0.1 "$input" out.ptc
    refused "brickmake $input" brickmake "$what" "$input" out.bkm
done

# A real bomb: 48 KB of gzip holding 2.5 million points (50 MB of zero
# records, 70 MB once read). With 48 MB allowed, reading stops while the
# arrays grow, with the memory it needs; with the default budget it reads.
python3 - <<'PY'
import gzip, struct
identity = struct.pack("<16f", 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1)
n = 2500000
head = (struct.pack("<iid", 0x63747070, 0, float(n)) + bytes(24) + identity * 2
        + struct.pack("<3f", 64, 64, 1) + struct.pack("<ii", 0, 0))
with gzip.GzipFile("bomb_gz.ptc", "wb", mtime=0) as z:
    z.write(head)
    for _ in range(50):
        z.write(bytes(20 * n // 50))
PY
input=bomb_gz.ptc
export SSS_MEMORY_LIMIT=48M
refused "ptinfo bomb" ptinfo "points its header claims needs about" bomb_gz.ptc
[[ "$err" == *"this process may use 48.0 MB (SSS_MEMORY_LIMIT)"* ]] ||
    fail "ptinfo bomb: the message does not name the budget: $err"
refused "brickmake bomb" brickmake "points its header claims needs about" bomb_gz.ptc out.bkm
unset SSS_MEMORY_LIMIT
run limited "$bin/ptinfo" -stats 0 bomb_gz.ptc
expect_rc 0 "ptinfo bomb within the budget" &&
    { [[ "$out" == *"points: 2500000"* ]] || fail "ptinfo bomb: wrong count: $out"; }

finish_checks cloud-bombs
