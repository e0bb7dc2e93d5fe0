#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# shader (the RSL compiler) on real files: .slo named after the shader, -o,
# -I/-D through the preprocessor, error lines with file:line:column, exit codes.
# Needs SSS_BIN_DIR (the build's bin folder).
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must point at the build bin folder}"
shader="$bin/shader"
[[ -x "$shader" ]] || { echo "FAIL: missing executable $shader" >&2; exit 1; }
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_shader.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"

fail() {
    echo "FAIL: $*" >&2
    exit 1
}

# run_status <out> <err> cmd...: runs cmd, prints its exit status.
run_status() {
    local out="$1" err="$2"
    shift 2
    local rc=0
    "$@" >"$out" 2>"$err" || rc=$?
    echo "$rc"
}

mkdir inc
cat >inc/helpers.h <<'SL'
#define DEFAULT_KD 0.8
float half(float x) { return x / 2; }
SL
cat >file_name.sl <<'SL'
#include "helpers.h"
surface matte_half(float Ka = 1; float Kd = DEFAULT_KD) {
    normal Nf = faceforward(normalize(N), I);
#ifdef BRIGHT
    Oi = Os;
#else
    Oi = Os * half(1);
#endif
    Ci = Os * Cs * (Ka * ambient() + Kd * diffuse(Nf));
}
SL

# --- success: the .slo is named after the shader, in the current folder ----
rc=$(run_status out.txt err.txt "$shader" -I inc -DBRIGHT file_name.sl)
[[ "$rc" = 0 ]] || { cat err.txt >&2; fail "compile exit $rc"; }
[[ -f matte_half.slo ]] || fail "matte_half.slo not written"
[[ ! -f file_name.slo ]] || fail "output named after the file"
head -1 matte_half.slo | grep -qx "sss-slo 1" || fail "bad .slo header"
grep -q '^sym "Kd" float 0 u param -1 -1 1 0.8 0$' matte_half.slo ||
    fail "-I include or macro not applied"
ls .*.tmp* 2>/dev/null && fail "temporary file left behind"
# -Iinc (attached), -D with a value, -q: nothing on stdout.
rc=$(run_status out.txt err.txt "$shader" -q -Iinc -DBRIGHT=1 -o named.slo file_name.sl)
[[ "$rc" = 0 ]] || { cat err.txt >&2; fail "-o compile exit $rc"; }
[[ -f named.slo ]] || fail "-o output not written"
[[ ! -s out.txt ]] || fail "-q printed on stdout"
cmp -s named.slo matte_half.slo || fail "-o output differs"
# Without BRIGHT the body differs (half(1) is inlined: a block op).
"$shader" -q -Iinc -o dim.slo file_name.sl
grep -q '^op "block"' dim.slo || fail "-D did not change the compiled code"
grep -q '^op "block"' matte_half.slo && fail "BRIGHT was not defined"

# --- several files, several shaders per file --------------------------------
cat >two.sl <<'SL'
light pl(float intensity = 1; point from = point "shader" (0, 0, 0)) {
    illuminate(from) { Cl = intensity / (L . L); }
}
displacement dent(float Km = 0.1) { P -= Km * normalize(N); N = calculatenormal(P); }
SL
"$shader" -q two.sl
[[ -f pl.slo && -f dent.slo ]] || fail "two shaders of one file not both written"

# --- compile errors: exit 1, file:line:column and the source line ----------
cat >bad.sl <<'SL'
surface bad(float Kd = 1) {
    float x = 1
    Ci = x;
    color c = P;
    Kd = 2;
}
SL
rc=$(run_status out.txt err.txt "$shader" bad.sl)
[[ "$rc" = 1 ]] || fail "compile error exit $rc, expected 1"
grep -q "^bad.sl:3:5: error: expected ';'" err.txt || { cat err.txt >&2; fail "no file:line:col error"; }
grep -qF "      Ci = x;" err.txt || fail "source line not printed"
grep -q "^shader ERROR: 1 error in bad.sl$" err.txt || { cat err.txt >&2; fail "no summary line"; }
[[ ! -f bad.slo ]] || fail "bad.slo written despite errors"

cat >types.sl <<'SL'
surface types(float Kd = 1) {
    color c = P;
    Kd = 2;
}
SL
rc=$(run_status out.txt err.txt "$shader" types.sl)
[[ "$rc" = 1 ]] || fail "type error exit $rc"
grep -q "^types.sl:2:15: error: cannot convert point to color" err.txt ||
    { cat err.txt >&2; fail "type error not reported"; }
grep -q "^types.sl:3:5: error: cannot assign to shader parameter 'Kd'" err.txt ||
    { cat err.txt >&2; fail "second error not reported"; }
grep -q "^shader ERROR: 2 errors in types.sl$" err.txt || fail "no summary line"

# A bad file does not stop the others.
rc=$(run_status out.txt err.txt "$shader" types.sl two.sl)
[[ "$rc" = 1 ]] || fail "mixed files exit $rc"

# Preprocessor errors and missing files.
rc=$(run_status out.txt err.txt "$shader" file_name.sl)
[[ "$rc" = 1 ]] || fail "missing include exit $rc"
grep -q "^file_name.sl:1:10: error: " err.txt || { cat err.txt >&2; fail "include error"; }
rc=$(run_status out.txt err.txt "$shader" nonexistent.sl)
[[ "$rc" = 1 ]] || fail "missing file exit $rc"
grep -q "^shader ERROR: " err.txt || fail "missing file message"

# --- usage errors: exit 2 --------------------------------------------------
rc=$(run_status out.txt err.txt "$shader" -bogus file_name.sl)
[[ "$rc" = 2 ]] || fail "bad option exit $rc, expected 2"
grep -q "^shader ERROR: unknown option -bogus" err.txt || fail "bad option message"
rc=$(run_status out.txt err.txt "$shader")
[[ "$rc" = 2 ]] || fail "no input exit $rc"
rc=$(run_status out.txt err.txt "$shader" -o x.slo a.sl b.sl)
[[ "$rc" = 2 ]] || fail "-o with two inputs exit $rc"
rc=$(run_status out.txt err.txt "$shader" -I)
[[ "$rc" = 2 ]] || fail "-I without a value exit $rc"

# --- PRMan's options that scripts pass: -C, -nosd, -o -src / -shader ---------
cat >glow.sl <<'SL'
/* a comment the preprocessor keeps with -C */
surface glowing(float Kd = 1) { Ci = Kd * Cs; Oi = Os; }
SL
rc=$(run_status out.txt err.txt "$shader" -C -nosd glow.sl)
[[ "$rc" = 0 && -s glowing.slo ]] || fail "-C -nosd: exit $rc, $(cat err.txt)"
mv glowing.slo glowing_c.slo
rc=$(run_status out.txt err.txt "$shader" -o -src glow.sl)
[[ "$rc" = 0 && -s glow.slo && ! -e glowing.slo ]] || fail "-o -src: exit $rc, $(cat err.txt)"
cmp -s glow.slo glowing_c.slo || fail "-o -src and -C -nosd give different .slo files"
rc=$(run_status out.txt err.txt "$shader" -o -shader glow.sl)
[[ "$rc" = 0 && -s glowing.slo ]] || fail "-o -shader: exit $rc, $(cat err.txt)"

# --- help and version on stdout, exit 0 -------------------------------------
"$shader" --help | grep -q "^usage: shader" || fail "--help"
"$shader" --version | grep -q "^shader (sss)" || fail "--version"

echo "test_shader: ok"
