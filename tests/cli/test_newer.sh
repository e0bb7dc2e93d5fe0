#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# CLI test of -newer 1 in ptbake, ptfilter, brickmake and render: an
# up-to-date job does nothing (exit 0, outputs untouched, one line saying so);
# a changed input (the RIB, an archive it reads, a cloud, a brick map a shader
# reads) or a missing output makes it run; -newer 0 always runs.
# Needs SSS_BIN_DIR.
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
for tool in ptbake ptfilter brickmake render; do
    [[ -x "$bin/$tool" ]] || { echo "FAIL: missing executable $bin/$tool" >&2; exit 1; }
done
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_newer.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"

# shellcheck source=lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
# shellcheck source=checks.sh
source "$(dirname "${BASH_SOURCE[0]}")/checks.sh"

# A scene in two files: the light and camera in bake.rib, the geometry in an
# archive, baked into two clouds.
mkdir -p geo
cat > geo/ball.rib <<'RIB'
AttributeBegin
  Surface "bake_radiance_t" "string filename" ["ball.ptc"]
  Sphere 1 -1 1 360
AttributeEnd
AttributeBegin
  Surface "bake_radiance_t" "string filename" ["floor.ptc"]
  Polygon "P" [-2 -1 -2  -2 -1 2  2 -1 2  2 -1 -2]
AttributeEnd
RIB
cat > bake.rib <<'RIB'
Format 64 48 1
Projection "perspective" "fov" 35
Translate 0 0 6
WorldBegin
  LightSource "distantlight" 1 "from" [1 2 -1] "to" [0 0 0] "intensity" [1]
  ReadArchive "geo/ball.rib"
WorldEnd
RIB
cat > render.rib <<'RIB'
Format 32 24 1
PixelSamples 1 1
Projection "perspective" "fov" 35
Display "ball.exr" "openexr" "rgba"
Display "+ball_sss.png" "png" "sss"
Translate 0 0 6
WorldBegin
  LightSource "distantlight" 1 "from" [1 2 -1] "to" [0 0 0] "intensity" [1]
  Surface "read_ssdiffusion" "string filename" ["ball.bkm"]
  Sphere 1 -1 1 360
WorldEnd
RIB

# Makes FILE older than everything written afterwards (mtimes are compared at
# full resolution, but some file systems round: keep a clear margin).
age() { touch -d '-1 hour' "$@"; }
# skipped LABEL FILE...: the last run exited 0, said "nothing to do" and left
# every FILE's mtime as recorded in the array before[].
skipped() {
    local label="$1"; shift
    expect_rc 0 "$label" || return 0
    [[ "$out" == *"nothing to do"* ]] || fail "$label: did not say 'nothing to do': $out"
    local f
    for f in "$@"; do
        [[ "$(mtime_of "$f")" == "${before[$f]}" ]] || fail "$label: rewrote $f"
    done
}
# redone LABEL FILE...: the last run exited 0 and rewrote every FILE.
redone() {
    local label="$1"; shift
    expect_rc 0 "$label" || return 0
    [[ "$out" != *"nothing to do"* ]] || fail "$label: skipped: $out"
    local f
    for f in "$@"; do
        [[ -s "$f" && "$(mtime_of "$f")" != "${before[$f]:-none}" ]] || fail "$label: did not write $f"
    done
}
declare -A before
remember() { local f; for f in "$@"; do before[$f]="$(mtime_of "$f")"; done; }

# --- ptbake: inputs are the RIB and every archive it reads --------------------
remember ball.ptc floor.ptc
run "$bin/ptbake" -newer 1 bake.rib
redone "ptbake -newer 1, no outputs yet" ball.ptc floor.ptc
age bake.rib geo/ball.rib
remember ball.ptc floor.ptc
run "$bin/ptbake" -newer 1 bake.rib
skipped "ptbake -newer 1, up to date" ball.ptc floor.ptc
[[ "$out" == "ptbake: ball.ptc, floor.ptc are newer than their inputs; nothing to do" ]] ||
    fail "ptbake -newer 1 message: $out"
touch geo/ball.rib
run "$bin/ptbake" -newer 1 bake.rib
redone "ptbake -newer 1, archive changed" ball.ptc floor.ptc
age bake.rib geo/ball.rib
rm floor.ptc
remember ball.ptc floor.ptc
run "$bin/ptbake" -newer 1 bake.rib
redone "ptbake -newer 1, one cloud missing" ball.ptc floor.ptc
age bake.rib geo/ball.rib
remember ball.ptc floor.ptc
run "$bin/ptbake" -newer 0 bake.rib
redone "ptbake -newer 0" ball.ptc floor.ptc
# -o decides the output: a file that does not exist yet is baked.
remember all.ptc
run "$bin/ptbake" -newer 1 -o all.ptc bake.rib
redone "ptbake -newer 1 -o new file" all.ptc
remember all.ptc
run "$bin/ptbake" -newer 1 -o all.ptc bake.rib
skipped "ptbake -newer 1 -o up to date" all.ptc
run "$bin/ptbake" -newer 2 bake.rib
expect_rc 2 "ptbake -newer 2" || true
# A missing archive is still reported as an error, -newer or not.
sed 's/geo\/ball.rib/geo\/gone.rib/' bake.rib > gone.rib
run "$bin/ptbake" -newer 1 gone.rib
expect_rc 1 "ptbake -newer 1, missing archive" && [[ "$err" == *"gone.rib"* ]] ||
    fail "missing archive message: $err"

# --- ptfilter -----------------------------------------------------------------
age ball.ptc floor.ptc
remember ball_ssd.ptc
run "$bin/ptfilter" -newer 1 -ssdiffusion -material marble -unitlength 0.1 ball.ptc ball_ssd.ptc
redone "ptfilter -newer 1, no output yet" ball_ssd.ptc
remember ball_ssd.ptc
run "$bin/ptfilter" -newer 1 -ssdiffusion -material marble -unitlength 0.1 ball.ptc ball_ssd.ptc
skipped "ptfilter -newer 1, up to date" ball_ssd.ptc
[[ "$out" == "ptfilter: ball_ssd.ptc is newer than its inputs; nothing to do" ]] ||
    fail "ptfilter -newer 1 message: $out"
# Any one of several inputs newer: run.
run "$bin/ptfilter" -newer 1 -ssdiffusion -material marble -unitlength 0.1 ball.ptc floor.ptc ball_ssd.ptc
skipped "ptfilter -newer 1, two old inputs" ball_ssd.ptc
touch floor.ptc
run "$bin/ptfilter" -newer 1 -ssdiffusion -material marble -unitlength 0.1 ball.ptc floor.ptc ball_ssd.ptc
redone "ptfilter -newer 1, second input changed" ball_ssd.ptc
remember ball_ssd.ptc
run "$bin/ptfilter" -newer 0 -ssdiffusion -material marble -unitlength 0.1 ball.ptc ball_ssd.ptc
redone "ptfilter -newer 0" ball_ssd.ptc
# In place (input = output): the output is never newer than itself, so it runs.
cp ball.ptc inplace.ptc
age inplace.ptc
remember inplace.ptc
run "$bin/ptfilter" -newer 1 -ssdiffusion -material marble -unitlength 0.1 inplace.ptc inplace.ptc
redone "ptfilter -newer 1 in place" inplace.ptc
# A missing input is an error, not "nothing to do".
run "$bin/ptfilter" -newer 1 -ssdiffusion -material marble gone.ptc ball_ssd.ptc
expect_rc 1 "ptfilter -newer 1, missing input" || true
run "$bin/ptfilter" -newer x -ssdiffusion ball.ptc ball_ssd.ptc
expect_rc 2 "ptfilter -newer x" || true

# --- brickmake (also covered in test_brickmake.sh) ------------------------------
"$bin/brickmake" ball_ssd.ptc ball.bkm
age ball_ssd.ptc
touch ball.bkm
remember ball.bkm
run "$bin/brickmake" -newer 1 ball_ssd.ptc ball.bkm
skipped "brickmake -newer 1, up to date" ball.bkm

# --- render: inputs are the RIB, its archives and the maps its shaders read ----
age ball.bkm
remember ball.exr ball_sss.png
run "$bin/render" -newer 1 render.rib
redone "render -newer 1, no images yet" ball.exr ball_sss.png
age render.rib ball.bkm
remember ball.exr ball_sss.png
run "$bin/render" -newer 1 render.rib
skipped "render -newer 1, up to date" ball.exr ball_sss.png
[[ "$out" == "render: ball.exr, ball_sss.png are newer than their inputs; nothing to do" ]] ||
    fail "render -newer 1 message: $out"
touch ball.bkm
run "$bin/render" -newer 1 render.rib
redone "render -newer 1, brick map changed" ball.exr ball_sss.png
age render.rib ball.bkm
rm ball_sss.png
remember ball.exr ball_sss.png
run "$bin/render" -newer 1 render.rib
redone "render -newer 1, one Display missing" ball.exr ball_sss.png
age render.rib ball.bkm
touch render.rib
remember ball.exr ball_sss.png
run "$bin/render" -newer 1 render.rib
redone "render -newer 1, RIB changed" ball.exr ball_sss.png
# -o replaces the primary Display's file; -frame expands patterns first.
age render.rib ball.bkm ball.exr ball_sss.png
remember ball.exr ball_sss.png
run "$bin/render" -newer 1 -o 'shot.$F4.png' -frame 3 render.rib
redone "render -newer 1 -o new file" shot.0003.png
remember shot.0003.png ball_sss.png
run "$bin/render" -newer 1 -o 'shot.$F4.png' -frame 3 render.rib
skipped "render -newer 1 -o, up to date" shot.0003.png ball_sss.png
# One plan per job: ptbake and render read each shader file once, with and
# without -newer 1 (they used to bind the scene's shaders for every phase).
# opens TOOL ARGS...: "count file" per .slo the run opened (strace).
# LeakSanitizer cannot run under ptrace (it stops the process with a fatal
# error): the sanitizer build's leak check is off for these runs only.
opens() {
    ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0" \
        strace -f -qq -e trace=openat -o "$work/trace" "$@" >/dev/null 2>&1 || true
    grep '\.slo"' "$work/trace" | grep -v ENOENT | sed 's/^[^"]*"\([^"]*\)".*/\1/' |
        sort | uniq -c
}
if command -v strace >/dev/null 2>&1; then
    for newer in 0 1; do
        for job in "ptbake bake.rib" "render render.rib"; do
            read -r tool scene <<<"$job"
            rm -f ball.ptc ball.exr ball_sss.png
            [[ "$tool" == render ]] && "$bin/ptbake" bake.rib >/dev/null 2>&1
            counts="$(opens "$bin/$tool" -newer "$newer" "$scene")"
            [[ -n "$counts" ]] || fail "$tool -newer $newer: opened no .slo (strace)"
            twice="$(awk '$1 > 1' <<<"$counts")"
            [[ -z "$twice" ]] || fail "$tool -newer $newer read shader files more than once: $twice"
        done
    done
else
    fail "strace is missing (scripts/install-deps installs it)"
fi

# A missing brick map is an error, not "nothing to do".
rm ball.bkm
run "$bin/render" -newer 1 render.rib
expect_rc 1 "render -newer 1, missing map" && [[ "$err" == *"ball.bkm"* ]] ||
    fail "missing map message: $err"

finish_checks newer
