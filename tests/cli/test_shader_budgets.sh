#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# Hostile shaders through the real tools (docs/limits.md, "The limits"): a
# runaway loop nest, string doubling, array growth, a bake3d flood and a
# bake3d file per iteration, a regular-expression bomb and an invalid regular
# expression. Each run ends within seconds with exit 1 and exactly one
# ERROR line naming the RIB call, the shader's file:line and the limit (its
# SSS_LIMIT_* variable, lowered here so that the runs are short), and writes
# nothing. A shader inside the limits renders cleanly. Needs SSS_BIN_DIR.
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must point at the build bin folder}"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_shader_budgets.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"
# shellcheck source=lib.sh
source "$here/lib.sh"
# shellcheck source=checks.sh
source "$here/checks.sh"

# scene SHADER: a sphere shaded by SHADER (a .sl in this folder), 16 x 16.
scene() {
    cat <<RIB
Format 16 16 1
Projection "perspective" "fov" 30
Display "out.exr" "openexr" "rgba"
Translate 0 0 6
WorldBegin
  LightSource "ambientlight" 1
  Surface "$1"
  Sphere 1 -1 1 360
WorldEnd
RIB
}

# shader NAME BODY: writes NAME.sl, a surface shader with BODY.
shader() {
    printf 'surface %s()\n{\n%s\n}\n' "$1" "$2" >"$1.sl"
    scene "$1" >"$1.rib"
}

# one_error TOOL LABEL WANT...: the last run exited 1 within 20 s with
# exactly one line on stderr, "TOOL ERROR: ...", containing every WANT.
one_error() {
    local tool="$1" label="$2"
    shift 2
    expect_rc 1 "$label" || return 0
    ((seconds <= 20)) || fail "$label: took $seconds s"
    local lines
    lines="$(grep -c . <<<"$err" || true)"
    [[ "$lines" == 1 ]] || fail "$label: $lines lines on stderr, expected one: $err"
    [[ "$err" == "$tool ERROR: "* ]] || fail "$label: not a $tool ERROR line: $err"
    local want
    for want in "$@"; do
        [[ "$err" == *"$want"* ]] || fail "$label: no \"$want\" in: $err"
    done
    [[ ! -e out.exr ]] || fail "$label: wrote out.exr"
}

# timed TOOL ARGS...: run, with the elapsed seconds in $seconds.
timed() {
    local start=$SECONDS
    run timeout 120 "$@"
    seconds=$((SECONDS - start))
}

# Nested loops, each far under the per-loop guard of 10^7 iterations.
shader loops '    float i, j, x = 0;
    for (i = 0; i < 1e6; i += 1)
        for (j = 0; j < 1e6; j += 1)
            x += 1;
    Ci = x;'
SSS_LIMIT_SHADER_OPERATIONS=200000 timed "$bin/render" loops.rib
one_error render "runaway loops" 'loops.rib:7: Surface "loops": ./loops.sl:5: shader '"'loops'" \
    "limit of 200000" SSS_LIMIT_SHADER_OPERATIONS

shader strings '    string s = "ab";
    float i;
    for (i = 0; i < 60; i += 1)
        s = concat(s, s);
    printf("%s\n", s);'
SSS_LIMIT_SHADER_STRING_LENGTH=4K timed "$bin/render" strings.rib
one_error render "string doubling" "./strings.sl:6" \
    "a string of 8192 bytes exceeds the limit of 4096 (set SSS_LIMIT_SHADER_STRING_LENGTH to raise it)"

shader arrays '    float a[];
    float i;
    for (i = 0; i < 1e7; i += 1)
        push(a, i);
    Ci = arraylength(a);'
SSS_LIMIT_SHADER_ARRAY_LENGTH=5000 timed "$bin/render" arrays.rib
one_error render "array growth" "./arrays.sl:6" \
    "push: an array of 5001 elements exceeds the limit of 5000 (set SSS_LIMIT_SHADER_ARRAY_LENGTH"

# A varying array of a million elements per point: counted against the job's
# memory budget.
shader memory '    varying float a[];
    resize(a, 1000000);
    Ci = arraylength(a);'
SSS_MEMORY_LIMIT=300M timed "$bin/render" memory.rib
one_error render "array memory" "./memory.sl:4" "(SSS_MEMORY_LIMIT)"

shader regex '    float m = match("((a{1,100}){1,100}){1,100}", "aaaa");
    Ci = m;'
timed "$bin/render" regex.rib
one_error render "regex bomb" "./regex.sl:3" "more than the bound of 2000"

shader badregex '    float m = match("[z-a", "aaaa");
    Ci = m;'
timed "$bin/render" badregex.rib
one_error render "invalid regex" "./badregex.sl:3" 'match("[z-a"): invalid regular expression'

# ptbake: bake3d in a loop.
shader flood '    float i;
    for (i = 0; i < 1e6; i += 1)
        bake3d("flood.ptc", "", P, N);'
SSS_LIMIT_BAKE3D_POINTS=100000 timed "$bin/ptbake" -spacing 0.05 flood.rib
one_error ptbake "bake3d flood" "./flood.sl:5" \
    "the points baked in one job exceed the limit of 100000 (set SSS_LIMIT_BAKE3D_POINTS"
[[ ! -e flood.ptc ]] || fail "bake3d flood: wrote flood.ptc"

shader files '    float i;
    for (i = 0; i < 1000; i += 1)
        bake3d(format("part%d.ptc", i), "", P, N);'
SSS_LIMIT_BAKE3D_FILES=8 timed "$bin/ptbake" -spacing 0.05 files.rib
one_error ptbake "bake3d files" "./files.sl:5" \
    'bake3d "part8.ptc": a new file after 8' "SSS_LIMIT_BAKE3D_FILES"
compgen -G "part*.ptc" >/dev/null && fail "bake3d files: wrote part files"

# A bad value of a limit is a usage error.
SSS_LIMIT_SHADER_OPERATIONS=lots timed "$bin/render" loops.rib
expect_rc 2 "a bad SSS_LIMIT_SHADER_OPERATIONS" &&
    { [[ "$err" == *"SSS_LIMIT_SHADER_OPERATIONS"* ]] || fail "bad limit value: $err"; }

# Heavy but legitimate work stays inside the defaults: 4096 gather samples
# per point and a few thousand loop iterations, strings and array elements.
shader heavy '    float x = 0, i;
    float a[];
    string s = "";
    gather("", P, N, PI / 2, 4096) { x += 1; } else { x += 0.5; }
    for (i = 0; i < 2000; i += 1) {
        push(a, i);
        s = concat(s, "x");
    }
    if (match("^x+$", s) == 1) x += arraylength(a);
    Ci = x;'
timed "$bin/render" heavy.rib
[[ "$rc" == 0 ]] && no_warnings "$err" || fail "heavy shader: exit $rc, stderr: $err"

finish_checks shader_budgets
