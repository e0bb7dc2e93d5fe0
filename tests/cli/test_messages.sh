#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# CLI test of what the tools say about hostile scenes (issue 15): every error
# is one "<tool> ERROR:" line naming the file and line (control bytes of
# echoed input escaped, long echoes cut), a shader that does not compile is
# one line in render/ptbake and compiler diagnostics in `shader`, a flood of
# one warning is printed 5 times and summarised, the limits (string and token
# length, archive nesting, image size, memory) stop a scene with an error that
# names the variable to raise, an out-of-memory names the stage, and scenes
# that render something other than asked warn. Inputs: tests/data/hostile/messages.
# Needs SSS_BIN_DIR and SSS_TEST_DATA_DIR.
#
# Every check runs; failures are listed and the script exits 1 at the end.
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
data="${SSS_TEST_DATA_DIR:?SSS_TEST_DATA_DIR must name tests/data}/hostile/messages"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_messages.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cp "$data"/* "$work"/
cd "$work"

# shellcheck source=lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
# shellcheck source=checks.sh
source "$(dirname "${BASH_SOURCE[0]}")/checks.sh"

# error LABEL TOOL WHAT... ARGS: runs TOOL ARGS (a 180 s hang guard); expects exit 1
# and exactly one "TOOL ERROR:" line, the first line of stderr, containing
# every WHAT (given as -w WHAT before the arguments). Sets $line.
error() {
    local label="$1" tool="$2"
    shift 2
    local -a what=()
    while [[ "${1:-}" == "-w" ]]; do
        what+=("$2")
        shift 2
    done
    run timeout 180 "$bin/$tool" "$@"
    line=""
    if [[ "$rc" == 124 ]]; then
        fail "$label: $tool ran for more than 180 s"
        return 0
    fi
    expect_rc 1 "$label" || return 0
    local count
    count="$(grep -c "^$tool ERROR: " <<<"$err" || true)"
    [[ "$count" == 1 ]] || fail "$label: $count ERROR lines: $err"
    line="$(head -n 1 <<<"$err")"
    [[ "$line" == "$tool ERROR: "* ]] || fail "$label: first line is not the error: $line"
    for w in "${what[@]}"; do
        [[ "$line" == *"$w"* ]] || fail "$label: '$w' missing from: ${line:0:400}"
    done
}

# --- one line per error ------------------------------------------------------

error "escaped newline echoed" render -w 'escaped_newline.rib:3: Surface "foo\nbar"' \
    escaped_newline.rib
error "raw newline echoed" render -w 'raw_newline.rib:3: ObjectInstance' \
    -w 'unknown object handle "x\ny"' raw_newline.rib
[[ "$(wc -l <<<"$err")" == 1 ]] || fail "a newline in a RIB string split the error: $err"

# A 100000-byte name is echoed cut to 200 bytes.
{
    printf 'Format 8 8 1\nWorldBegin\nSurface "'
    head -c 100000 /dev/zero | tr '\0' x
    printf '"\nSphere 1 -1 1 360\nWorldEnd\n'
} >long_name.rib
error "long name" render -w 'long_name.rib:3: Surface "xxxx' -w 'x..."' long_name.rib
((${#line} < 1000)) || fail "long name: the error is ${#line} bytes long"

# Shaders compiled on the fly: the first diagnostic and a count, one line.
for tool in render ptbake; do
    error "$tool, shader errors" $tool \
        -w "bad_shader.rib:3: Surface \"bad\": ./bad.sl:2:10: unknown variable 'foo'" \
        -w "(and 2 more errors)" bad_shader.rib
done
# The shader tool: compiler diagnostics (editors parse them), then one ERROR.
run "$bin/shader" bad.sl
expect_rc 1 "shader bad.sl" && {
    grep -q "^bad.sl:2:10: error: unknown variable 'foo'$" stderr || fail "shader: no diagnostic: $err"
    grep -q "^ *\^$" stderr || fail "shader: no caret line: $err"
    [[ "$(grep -c "ERROR" stderr)" == 1 ]] || fail "shader: not one ERROR line: $err"
    [[ "$(tail -n 1 stderr)" == "shader ERROR: 3 errors in bad.sl" ]] || fail "shader: last line: $err"
    [[ -z "$out" ]] || fail "shader: diagnostics on stdout: $out"
}

# --- warning floods ----------------------------------------------------------

# count_warnings TOOL: "WARNING" lines of the last run.
count_warnings() { grep -c "^$1 WARNING: " <<<"$err" || true; }

{
    printf 'Format 8 8 1\nWorldBegin\nSurface "constant"\nSphere 1 -1 1 360\n'
    for ((i = 0; i < 100000; i++)); do echo TransformBegin; done
} >unclosed.rib
run timeout 120 "$bin/render" unclosed.rib
if expect_rc 0 "100000 unclosed TransformBegin"; then
    n="$(count_warnings render)"
    # WorldBegin, 5 TransformBegin, the summary.
    [[ "$n" == 7 ]] || fail "unclosed TransformBegin: $n warning lines (expected 7): ${err:0:600}"
    grep -qx 'render WARNING: 99995 more warnings like "TransformBegin is never closed" not shown' \
        stderr || fail "unclosed TransformBegin: no summary: ${err:0:600}"
    grep -q '^render WARNING: unclosed.rib:5: TransformBegin is never closed$' stderr ||
        fail "unclosed TransformBegin: the first warnings keep their text: ${err:0:600}"
fi

{
    printf 'Format 8 8 1\nWorldBegin\nSurface "constant"\nSphere 1 -1 1 360\n'
    for ((i = 0; i < 1000; i++)); do echo "Bogus$i"; done
    printf 'WorldEnd\n'
} >unknown.rib
run timeout 120 "$bin/render" unknown.rib
expect_rc 1 "1000 unknown statements, not lenient" &&
    [[ "$err" == "render ERROR: unknown.rib:5: Bogus0: unknown statement Bogus0 "* ]] ||
    fail "unknown statements, not lenient: ${err:0:600}"
run timeout 120 "$bin/render" -lenient unknown.rib
if expect_rc 0 "1000 unknown statements, -lenient"; then
    n="$(count_warnings render)"
    [[ "$n" == 6 ]] || fail "unknown statements: $n warning lines (expected 6): ${err:0:600}"
    grep -qx 'render WARNING: 995 more warnings like "unknown statement" not shown' stderr ||
        fail "unknown statements: no summary: ${err:0:600}"
fi

# --- limits ------------------------------------------------------------------

printf 'Format 8 8 1\nWorldBegin\nSurface "%s"\nWorldEnd\n' "$(head -c 2000 /dev/zero | tr '\0' s)" >long_string.rib
SSS_LIMIT_STRING_LENGTH=1000 error "string length" render \
    -w "long_string.rib:3: Surface: 2000 bytes in one string exceeds the limit of 1000" \
    -w "SSS_LIMIT_STRING_LENGTH" long_string.rib
printf 'Format 8 8 1\nWorldBegin\nColor 1%s 1 1\nWorldEnd\n' "$(head -c 200 /dev/zero | tr '\0' 0)" >long_token.rib
SSS_LIMIT_TOKEN_LENGTH=100 error "token length" render \
    -w "long_token.rib:3: Color: 201 bytes in one token exceeds the limit of 100" \
    -w "SSS_LIMIT_TOKEN_LENGTH" long_token.rib
SSS_LIMIT_TOKEN_LENGTH=100 error "token length, ptbake" ptbake -w "long_token.rib:3" \
    -w "SSS_LIMIT_TOKEN_LENGTH" long_token.rib

# Archives: a cycle is named as one; nesting deeper than the limit names it.
error "archive cycle" render -w 'cycle_c.rib:1: ReadArchive: "cycle_b.rib" reads itself' \
    -w "(cycle_b.rib -> cycle_c.rib -> cycle_b.rib)" cycle_a.rib
for ((i = 0; i < 40; i++)); do
    if ((i < 39)); then echo "ReadArchive \"level$((i + 1)).rib\"" >level$i.rib; else echo 'Sphere 1 -1 1 360' >level$i.rib; fi
done
printf 'Format 8 8 1\nWorldBegin\nSurface "constant"\nReadArchive "level0.rib"\nWorldEnd\n' >deep.rib
error "archive depth" render -w 'level31.rib:1: ReadArchive "level32.rib": 33 levels of nested archives exceeds the limit of 32 (set SSS_LIMIT_ARCHIVE_DEPTH to raise it)' deep.rib
SSS_LIMIT_ARCHIVE_DEPTH=64 run "$bin/render" deep.rib
expect_rc 0 "archive depth raised" || true
error "inline archive replays" render -w "archive_replays.rib:" \
    -w 'archive_replays.rib:126: ReadArchive: "a30" replays 3221225470 statements from inline archives, more than 10000000' \
    archive_replays.rib

# Image size: Format and -res, before anything is allocated.
error "Format side" render -w "format_side.rib:1: Format 70000 10: 70000 pixels across one image side exceeds the limit of 65536" \
    -w SSS_LIMIT_IMAGE_SIDE format_side.rib
error "Format pixels" ptbake -w "format_pixels.rib:1: Format 20000 20000: 400000000 pixels in one image exceeds the limit of 268435456" \
    -w SSS_LIMIT_IMAGE_PIXELS format_pixels.rib
error "-res side" render -w "option -res 70000 10: 70000 pixels across one image side" \
    -w SSS_LIMIT_IMAGE_SIDE -res 70000 10 unlit.rib
SSS_LIMIT_IMAGE_PIXELS=100 error "-res pixels" render -w "option -res 20 20: 400 pixels in one image exceeds the limit of 100" \
    -res 20 20 unlit.rib
# The image buffers are estimated before they are allocated.
SSS_MEMORY_LIMIT=1G error "image memory" render -w "unlit.rib: a 16000 x 16000 image of" \
    -w "SSS_MEMORY_LIMIT" -w "lower the resolution" -res 16000 16000 unlit.rib
[[ ! -e unlit.exr ]] || fail "image memory: an image was written"

# Memory bombs in the scene's text: a long array, exponential instancing.
python3 -c "import sys; sys.stdout.write('Format 8 8 1\nWorldBegin\nPolygon \"P\" [' + '0 ' * 4200000 + ']\nWorldEnd\n')" >array.rib
SSS_MEMORY_LIMIT=200M error "array memory" render -w "needs about" -w "SSS_MEMORY_LIMIT" array.rib
# (Under the sanitizers a process starts larger: a budget it can start in.)
budget=600M
[[ -z "${SSS_SANITIZED:-}" ]] || budget=2G
SSS_MEMORY_LIMIT=$budget error "ObjectInstance memory" render \
    -w "object_instances.rib:" -w ": ObjectInstance \"o" -w "SSS_MEMORY_LIMIT" object_instances.rib

# --- out of memory names the stage ---------------------------------------------

# ptsynth -n 1e8 asks for gigabytes under a 800 MB address space: no estimate
# comes first, the allocation fails. (Not under the sanitizers: ASan's shadow
# memory needs terabytes of address space.)
if [[ -z "${SSS_SANITIZED:-}" ]]; then
    run bash -c "ulimit -v 800000 && exec '$bin/ptsynth' -n 100000000 big.ptc"
    if expect_rc 1 "bad_alloc"; then
        [[ "$(head -n 1 <<<"$err")" == "ptsynth ERROR: out of memory while making the point cloud" ]] ||
            fail "bad_alloc does not name the stage: $err"
        [[ ! -e big.ptc ]] || fail "bad_alloc: big.ptc written"
    fi
fi

# --- scenes that render something other than asked ------------------------------

run "$bin/render" unlit.rib
expect_rc 0 "unlit scene" &&
    { [[ "$err" == *"render WARNING: unlit.rib: no light sources: the surfaces shaded by matte"* ]] ||
        fail "no warning for a scene without lights: $err"; }
run "$bin/render" look_away.rib
expect_rc 0 "camera looking away" && {
    [[ "$err" == *"render WARNING: look_away.rib: no camera ray hit a surface: the image is empty"* ]] ||
        fail "no warning for an empty view: $err"
    [[ "$err" != *"no light sources"* ]] || fail "a lit scene warned about lights: $err"
}
printf 'Format 16 16 1\nProjection "perspective" "fov" 40\nTranslate 0 0 5\nWorldBegin\nLightSource "distantlight" 1\nSurface "matte"\nSphere 1 -1 1 360\nWorldEnd\n' >fine.rib
run "$bin/render" fine.rib
expect_rc 0 "a fine scene" && { [[ -z "$err" ]] || fail "a fine scene warned: $err"; }

finish_checks "messages"
