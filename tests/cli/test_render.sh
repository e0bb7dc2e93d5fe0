#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# CLI test of render: outputs and their channels, progress lines, exit codes,
# error lines, atomic output, frame patterns, thread independence.
# Needs SSS_BIN_DIR (the folder with ptbake, ptfilter, brickmake, render).
#
# Every check runs; failures are listed and the script exits 1 at the end.
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
render="$bin/render"
ptinfo="$bin/ptinfo"
for tool in "$render" "$bin/ptbake" "$bin/ptfilter" "$bin/brickmake"; do
    [[ -x "$tool" ]] || { echo "FAIL: missing executable $tool" >&2; exit 1; }
done
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_render.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"

# shellcheck source=lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
# shellcheck source=checks.sh
source "$(dirname "${BASH_SOURCE[0]}")/checks.sh"

# A small scene: a sphere lit from behind-left, a plate, bake -> diffuse -> map.
cat > bake.rib <<'RIB'
Format 96 72 1
Projection "perspective" "fov" 35
Translate 0 0 6
WorldBegin
  LightSource "pointlight" 1 "from" [-3 3 4] "intensity" [30] "string shadowname" ["raytrace"]
  AttributeBegin
    Surface "bake_radiance_t" "string filename" ["ball.ptc"]
    Sphere 1 -1 1 360
  AttributeEnd
WorldEnd
RIB
cat > scene.rib <<'RIB'
Format 96 72 1
PixelSamples 2 2
Projection "perspective" "fov" 35
DisplayChannel "color ambient"
DisplayChannel "color diffuse"
DisplayChannel "color specular"
DisplayChannel "float occlusion"
Display "ball.exr" "openexr" "rgba"
Display "+ball_sss.png" "png" "sss"
Translate 0 0 6
WorldBegin
  LightSource "pointlight" 1 "from" [-3 3 4] "intensity" [30] "string shadowname" ["raytrace"]
  AttributeBegin
    Surface "read_ssdiffusion" "string filename" ["ball.bkm"] "float Kd" [0.2]
    Sphere 1 -1 1 360
  AttributeEnd
  AttributeBegin
    Surface "matte"
    Polygon "P" [-4 -1 -4  -4 -1 4  4 -1 4  4 -1 -4]
  AttributeEnd
WorldEnd
RIB
"$bin/ptbake" -spacing 0.05 bake.rib
"$bin/ptfilter" -ssdiffusion -material marble -unitlength 0.1 ball.ptc ball_ssd.ptc
"$bin/brickmake" -maxerror 0.002 ball_ssd.ptc ball.bkm

run "$render" --help
expect_rc 0 --help && [[ "$out" == *"usage: render"* ]] || fail "--help lacks the usage line"
run "$render" --version
expect_rc 0 --version && [[ "$out" == "render (sss) "* ]] || fail "--version: $out"

# Every Display is written; the EXR holds the beauty and the AOV layers.
run "$render" scene.rib
if expect_rc 0 "render scene.rib"; then
    [[ -z "$out" && -z "$err" ]] || fail "a clean render printed: $out $err"
    [[ -s ball.exr ]] || fail "no ball.exr"
    [[ -s ball_sss.png ]] || fail "no ball_sss.png (the '+' display)"
    info="$(oiiotool --info -v ball.exr 2>&1)"
    for ch in R G B A ambient.R diffuse.G specular.B sss.R occlusion.R; do
        grep -Eq "channel list:.*\b${ch//./\\.}\b" <<<"$info" || fail "ball.exr lacks channel $ch"
    done
    grep -q 'Software: "render (sss)' <<<"$info" || fail "ball.exr lacks the Software attribute"
    grep -q 'sss:commandLine' <<<"$info" || fail "ball.exr lacks sss:commandLine"
    grep -q 'renderTimeSeconds' <<<"$info" || fail "ball.exr lacks renderTimeSeconds"
    grep -q '96 x  *72' <<<"$info" || grep -q '96 x 72' <<<"$info" || fail "ball.exr is not 96 x 72"
    # The ball is lit from behind: the diffusion reaches round to the camera
    # side, so the sss layer carries light (the map reached the shader).
    sss_max="$(oiiotool ball.exr --ch sss.R --printstats 2>/dev/null | sed -n 's/.*Stats Max: *\([^ ]*\).*/\1/p')"
    awk -v m="$sss_max" 'BEGIN { exit !(m > 0.1) }' || fail "sss layer max $sss_max: no diffused light"
fi

# -progress 1: counts, timings and ALF_PROGRESS lines ending at 100 %.
run "$render" -progress 1 -o p.exr scene.rib
if expect_rc 0 "-progress 1"; then
    [[ "$(grep ALF_PROGRESS stdout | tail -n 1)" == "ALF_PROGRESS 100%" ]] || fail "no final ALF_PROGRESS 100%"
    grep -q "render: wrote p.exr" stdout || fail "-progress 1 does not name the image"
fi

# -res, -samples and -o with a frame pattern; PNG output.
run "$render" -frame 12 -res 48 36 -samples 1 -o 'small.%04d.png' scene.rib
if expect_rc 0 "-frame 12 -o small.%04d.png"; then
    [[ -s small.0012.png ]] || fail "no small.0012.png"
    [[ "$(head -c 8 small.0012.png | od -An -tx1 | tr -d ' \n')" == "89504e470d0a1a0a" ]] ||
        fail "small.0012.png is not a PNG"
    oiiotool --info small.0012.png 2>&1 | grep -q '48 x  *36' || fail "small.0012.png is not 48 x 36"
fi

# The image does not depend on the thread count.
run "$render" -threads 1 -o t1.exr scene.rib
expect_rc 0 "-threads 1" || true
run "$render" -threads 2 -o t2.exr scene.rib
if expect_rc 0 "-threads 2"; then
    diff_out="$(oiiotool t1.exr t2.exr --diff 2>&1 || true)"
    grep -q "Max error  = 0" <<<"$diff_out" || grep -q "PASS" <<<"$diff_out" ||
        fail "-threads 1 and 2 differ: $diff_out"
fi

# Errors: one line, exit codes, nothing left behind.
run "$render" -bogus scene.rib
expect_rc 2 "unknown option" && [[ "$err" == "render ERROR: "*"-bogus"* ]] || fail "unknown option: $err"
run "$render"
expect_rc 2 "no scene" || true
run "$render" missing.rib
expect_rc 1 "missing scene" && [[ "$err" == "render ERROR: "*"missing.rib"* ]] || fail "missing scene: $err"
sed 's/ball.bkm/nothere.bkm/' scene.rib > nomap.rib
cp ball.exr keep.exr
run "$render" -o ball.exr nomap.rib
expect_rc 1 "missing brick map" || true
[[ "$err" == "render ERROR: nomap.rib:"*"nothere.bkm"* ]] || fail "missing map message should name nomap.rib:LINE and the file: $err"
cmp -s ball.exr keep.exr || fail "a failed render changed the existing image"
printf 'WorldBegin\nSphere 1 -1\nWorldEnd\n' > bad.rib
run "$render" bad.rib
expect_rc 1 "bad RIB" && [[ "$err" == "render ERROR: bad.rib:2"*"Sphere"* ]] || fail "bad RIB message: $err"
ls -a | grep -q '\.tmp$' && fail "temporary files left: $(ls -a | grep '\.tmp$')"

finish_checks render
