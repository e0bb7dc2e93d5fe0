#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# CLI test: every name a tool writes is one it can read back, and what the
# tools say about hostile names stays one readable line. A file name with a
# NUL (RSL's "\0", a RIB's Display) is refused instead of cut at the NUL; a
# bake3d channel name longer than the .ptc reader takes is refused before
# anything is written; ptfilter's channel options are checked the same way;
# a 100000-character shader name keeps the cause of its error; the shader
# compiler escapes control bytes of the source in its diagnostics; 40000
# nested macro arguments fail at once, in little memory.
# Needs SSS_BIN_DIR.
#
# Every check runs; failures are listed and the script exits 1 at the end.
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_hostile_names.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"

# shellcheck source=lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
# shellcheck source=checks.sh
source "$(dirname "${BASH_SOURCE[0]}")/checks.sh"

# refused LABEL CODE TOOL WHAT ARGS...: exit CODE, one "TOOL ERROR:" line (the
# first of stderr) containing WHAT, no raw control byte on stderr.
refused() {
    local label="$1" code="$2" tool="$3" what="$4"
    shift 4
    run timeout 120 "$bin/$tool" "$@"
    expect_rc "$code" "$label" || return 0
    line="$(head -n 1 <<<"$err")"
    [[ "$line" == "$tool ERROR: "* ]] || fail "$label: first line: ${line:0:300}"
    [[ "$(grep -c "^$tool ERROR: " <<<"$err")" == 1 ]] || fail "$label: not one ERROR line: ${err:0:300}"
    [[ "$line" == *"$what"* ]] || fail "$label: '$what' missing from: ${line:0:600}"
    LC_ALL=C grep -q $'[\x01-\x08\x0b-\x1f\x7f]' <<<"$err" && fail "$label: raw control bytes on stderr"
    return 0
}

# A scene whose surface shader bakes one point cloud (file and channel names
# are the shader's parameters, so RSL's escapes reach bake3d).
cat >baker.sl <<'EOF'
surface baker(string filename = ""; string channel = "_x") {
    bake3d(filename, channel, P, normalize(N), channel, 1.0);
    Ci = 1;
}
EOF
scene() { # scene FILE SURFACE-LINE [DISPLAY-LINE]
    local display='Display "out.exr" "file" "rgba"'
    [[ $# -lt 3 ]] || display="$3"
    cat >"$1" <<EOF
Format 8 8 1
Projection "perspective" "fov" [40]
$display
Translate 0 0 3
WorldBegin
$2
Sphere 1 -1 1 360
WorldEnd
EOF
}

# --- NUL bytes in file names -------------------------------------------------
cat >nul.sl <<'EOF'
surface nul() {
    bake3d("x\0y.ptc", "_x", P, normalize(N), "_x", 1.0);
    Ci = 1;
}
EOF
scene nul.rib 'Surface "nul"'
refused "bake3d to x\\0y.ptc" 1 render 'a file name cannot hold a NUL byte' nul.rib
[[ ! -e x && ! -e out.exr ]] || fail "bake3d to x\\0y.ptc wrote: $(ls)"
refused "ptbake: bake3d to x\\0y.ptc" 1 ptbake 'a file name cannot hold a NUL byte' -spacing 0.2 nul.rib
[[ ! -e x ]] || fail "ptbake: bake3d to x\\0y.ptc wrote x"

scene display.rib 'Surface "constant"' 'Display "a\000b.exr" "file" "rgba"'
refused 'Display "a\0b.exr"' 1 render 'a file name cannot hold a NUL byte' display.rib
[[ ! -e a ]] || fail 'Display "a\0b.exr" wrote a'

# --- channel names the .ptc reader would refuse --------------------------------
long="$(printf 'c%.0s' {1..5001})"
scene long_channel.rib "Surface \"baker\" \"string filename\" \"long.ptc\" \"string channel\" \"$long\""
refused "bake3d with a 5001-byte channel name" 1 render 'at most 4089' long_channel.rib
[[ ! -e long.ptc && ! -e out.exr ]] || fail "a 5001-byte channel name wrote $(ls)"
[[ "$line" == *'bake3d file "long.ptc": channel name "cccc'*'..." is 5001 bytes long'* ]] ||
    fail "channel name error: ${line:0:400}"
# The longest name the reader takes is written and read back.
ok="$(printf 'c%.0s' {1..4089})"
scene ok_channel.rib "Surface \"baker\" \"string filename\" \"ok.ptc\" \"string channel\" \"$ok\""
run "$bin/render" ok_channel.rib
expect_rc 0 "bake3d with a 4089-byte float channel name"
run "$bin/ptinfo" ok.ptc
expect_rc 0 "ptinfo of the 4089-byte channel name"

"$bin/ptsynth" -n 100 in.ptc >/dev/null
refused "ptfilter -areachannel of 5000 bytes" 2 ptfilter 'option -areachannel: channel name "' \
    -ssdiffusion -areachannel "$(printf 'a%.0s' {1..5000})" in.ptc out.ptc
[[ "$line" == *'is 5000 bytes long'* ]] || fail "ptfilter -areachannel: ${line:0:400}"
refused "ptfilter -radiancechannel with a tab" 2 ptfilter 'contains whitespace or control characters' \
    -ssdiffusion -radiancechannel $'a\tb' in.ptc out.ptc

# --- long names keep the cause -------------------------------------------------
huge="$(printf 's%.0s' {1..100000})"
scene huge_shader.rib "Surface \"$huge\""
refused "a 100000-character shader name" 1 render 'not found' huge_shader.rib

# --- compiler diagnostics escape control bytes ------------------------------------
printf 'surface ctl() {\n    float a\001b = 1;\n    Ci = foo\002;\n}\n' >ctl.sl
run "$bin/shader" ctl.sl
expect_rc 1 "shader with control bytes"
LC_ALL=C grep -q $'[\x01\x02]' <<<"$err" && fail "shader: raw control bytes in diagnostics: $err"
[[ "$err" == *'\x01'* ]] || fail "shader: the control byte is not shown escaped: $err"

# --- nested macro arguments fail fast and small ---------------------------------------
python3 -c '
n = 40000
print("#define F(x) x")
print("surface deep() { float a = " + "F(" * n + "1" + ")" * n + "; Ci = a; }")' >deep.sl
start=$SECONDS
# Under 1 GB of address space (not under the sanitizers, whose shadow memory
# needs terabytes of it).
limit=1000000
[[ -n "${SSS_SANITIZED:-}" ]] && limit=unlimited
(ulimit -v "$limit" && "$bin/shader" deep.sl) >deep.out 2>deep.err && fail "40000 nested macro arguments compiled"
grep -q 'macro arguments nested too deeply' deep.err || fail "nested macro arguments: $(head -c 300 deep.err)"
((SECONDS - start <= 10)) || fail "nested macro arguments took $((SECONDS - start)) s"

# --- a bake3d value that is not a number: an error at the shader's line ----------------
cat >nanbake.sl <<'SL'
surface nanbake() {
    bake3d("nan.ptc", "_c", P, normalize(N), "interpolate", 1, "_c", color(pow(-0.25, s), 0, 0));
    Ci = 0;
}
SL
printf '%s\n' 'Format 16 16 1' 'Projection "perspective" "fov" 40' 'Translate 0 0 5' \
    'WorldBegin' 'Attribute "cull" "hidden" 0 "backfacing" 0' 'Surface "nanbake"' \
    'Sphere 1 -1 1 360' 'WorldEnd' >nanbake.rib
run "$bin/ptbake" nanbake.rib
expect_rc 1 "bake3d of NaN" &&
    { [[ "$err" == *'nanbake.sl:2'*'channel "_c" is NaN'* ]] || fail "bake3d of NaN: $err"; }
[[ ! -e nan.ptc ]] || fail "bake3d of NaN wrote nan.ptc"

finish_checks hostile-names
