#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# ptinfo on real files: report content, exit codes, error lines.
# Needs SSS_BIN_DIR (the build's bin folder) and SSS_TEST_DATA_DIR (tests/data).
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must point at the build bin folder}"
data="${SSS_TEST_DATA_DIR:?SSS_TEST_DATA_DIR must point at tests/data}"
ptinfo="$bin/ptinfo"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

fail() {
    echo "FAIL: $*" >&2
    exit 1
}

# expect_line <file> <exact line>
expect_line() {
    grep -qxF -- "$2" "$1" || { cat "$1" >&2; fail "missing line '$2'"; }
}

# run_status <out> <err> cmd...: runs cmd, prints its exit status.
run_status() {
    local out="$1" err="$2"
    shift 2
    local rc=0
    "$@" >"$out" 2>"$err" || rc=$?
    echo "$rc"
}

# --- a v0 .ptc written by tests/data/make_tiny_ptc.py -----------------------
"$ptinfo" "$data/tiny_v0.ptc" >"$tmp/v0.txt"
expect_line "$tmp/v0.txt" "file: $data/tiny_v0.ptc"
expect_line "$tmp/v0.txt" "format: ptc version 0"
expect_line "$tmp/v0.txt" "compressed: no"
expect_line "$tmp/v0.txt" "points: 3"
expect_line "$tmp/v0.txt" "bbox: min -1 0 0  max 1 2 3"
expect_line "$tmp/v0.txt" "world2eye: 1 0 0 0 | 0 1 0 0 | 0 0 1 0 | 0 0 5 1"
expect_line "$tmp/v0.txt" "image format: 640 480 1"
expect_line "$tmp/v0.txt" "channels: 2 (datasize 4)"
expect_line "$tmp/v0.txt" "  float _area"
expect_line "$tmp/v0.txt" "    min 0.01  mean 0.02  max 0.03"
expect_line "$tmp/v0.txt" "  color _radiance_t"
expect_line "$tmp/v0.txt" "    r: min 0  mean 0.5  max 1"
expect_line "$tmp/v0.txt" "radius: min 0.1  mean 0.2  max 0.3"
if grep -q world2ndc "$tmp/v0.txt"; then fail "identity world2ndc should not be printed"; fi

# --- gzip v2 and a foreign ASCII .ply, several files at once, no stats ------
"$ptinfo" -stats 0 "$data/tiny_v2_gzip.ptc" "$data/tiny_foreign.ply" >"$tmp/two.txt"
expect_line "$tmp/two.txt" "format: ptc version 2"
expect_line "$tmp/two.txt" "compressed: yes (gzip)"
expect_line "$tmp/two.txt" "format: ply"
expect_line "$tmp/two.txt" "  float red"
expect_line "$tmp/two.txt" "  float confidence"
[ "$(grep -c '^points: 3$' "$tmp/two.txt")" = 2 ] || fail "expected two 'points: 3' lines"
if grep -q mean "$tmp/two.txt"; then fail "-stats 0 still printed statistics"; fi

# --- ptsynth output, when the tool is built ---------------------------------
if [ -x "$bin/ptsynth" ]; then
    "$bin/ptsynth" -shape plane -n 100 -compress 1 "$tmp/plane.ptc" >/dev/null
    "$ptinfo" "$tmp/plane.ptc" >"$tmp/plane.txt"
    expect_line "$tmp/plane.txt" "compressed: yes (gzip)"
    expect_line "$tmp/plane.txt" "  float _area"
    expect_line "$tmp/plane.txt" "  color _radiance_t"
    grep -q '^points: [1-9][0-9]*$' "$tmp/plane.txt" || fail "no point count for ptsynth output"
fi

# --- help and version: stdout, exit 0 ---------------------------------------
[ "$(run_status "$tmp/out" "$tmp/err" "$ptinfo" --help)" = 0 ] || fail "--help did not exit 0"
grep -q '^usage: ptinfo' "$tmp/out" || fail "--help printed no usage on stdout"
[ "$(run_status "$tmp/out" "$tmp/err" "$ptinfo" -h)" = 0 ] || fail "-h did not exit 0"
[ "$(run_status "$tmp/out" "$tmp/err" "$ptinfo" --version)" = 0 ] || fail "--version did not exit 0"
grep -q 'ptinfo' "$tmp/out" || fail "--version printed nothing useful"

# --- bad input: exit 1 with an error line naming the file -------------------
rc="$(run_status "$tmp/out" "$tmp/err" "$ptinfo" "$tmp/missing.ptc")"
[ "$rc" = 1 ] || fail "missing file: exit $rc, expected 1"
grep -q "^ptinfo ERROR: .*missing.ptc" "$tmp/err" || fail "missing file: no ERROR line"

head -c 100 "$data/tiny_v0.ptc" >"$tmp/short.ptc"
rc="$(run_status "$tmp/out" "$tmp/err" "$ptinfo" "$tmp/short.ptc")"
[ "$rc" = 1 ] || fail "truncated file: exit $rc, expected 1"
grep -q "^ptinfo ERROR: .*short.ptc" "$tmp/err" || fail "truncated file: no ERROR line"

printf 'not a point cloud at all' >"$tmp/junk.ptc"
rc="$(run_status "$tmp/out" "$tmp/err" "$ptinfo" "$tmp/junk.ptc")"
[ "$rc" = 1 ] || fail "bad magic: exit $rc, expected 1"
grep -q "^ptinfo ERROR: .*junk.ptc.*magic" "$tmp/err" || fail "bad magic: no ERROR line"

# An OpenVDB file (its magic " BDV") is named as one, with the tool that reads it.
printf ' BDV\xdc\x00\x00\x00 an OpenVDB header follows' >"$tmp/grid.vdb"
rc="$(run_status "$tmp/out" "$tmp/err" "$ptinfo" "$tmp/grid.vdb")"
[ "$rc" = 1 ] || fail "a .vdb: exit $rc, expected 1"
grep -q "^ptinfo ERROR: .*grid.vdb: an OpenVDB file, not a point cloud (brickinfo" "$tmp/err" ||
    fail "a .vdb: $(cat "$tmp/err")"

# --- usage errors: exit 2 ----------------------------------------------------
for args in "-bogus $data/tiny_v0.ptc" "" "-stats 7 $data/tiny_v0.ptc" "-stats"; do
    # shellcheck disable=SC2086 # word splitting of args is intended
    rc="$(run_status "$tmp/out" "$tmp/err" "$ptinfo" $args)"
    [ "$rc" = 2 ] || fail "'ptinfo $args': exit $rc, expected 2"
    grep -q "^ptinfo ERROR: " "$tmp/err" || fail "'ptinfo $args': no ERROR line"
done

echo "test_ptinfo: ok"
