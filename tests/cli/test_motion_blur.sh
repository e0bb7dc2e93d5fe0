#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# Motion blur (RIB MotionBegin/MotionEnd and Shutter) through render and
# ptbake: a sphere moving across the frame covers each point for the share of
# the shutter it spends there, a moving camera gives the same image as the
# object moving the other way, deformation (a growing sphere, a deforming
# subdivision mesh, curves) renders, a shutter that does not open renders
# the first time sharp, and ptbake bakes the scene as it is when the shutter
# opens. Needs SSS_BIN_DIR (the build's bin folder).
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must point at the build bin folder}"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_motion_blur.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"
# shellcheck source=lib.sh
source "$here/lib.sh"
# shellcheck source=checks.sh
source "$here/checks.sh"
# The mean alpha of a pixel (x, y) of an image.
alpha_at() {
    oiiotool "$1" --ch A --crop "$2,$3,$(($2 + 1)),$(($3 + 1))" --printstats 2>/dev/null |
        sed -n 's/.*Stats Avg: *\([^ ]*\).*/\1/p'
}
mean_alpha() {
    oiiotool "$1" --ch A --printstats 2>/dev/null | sed -n 's/.*Stats Avg: *\([^ ]*\).*/\1/p'
}
within() { python3 -c "import sys; v = float('$1' or 'nan'); sys.exit(0 if $2 <= v <= $3 else 1)"; }

# A 4 x 2 frame (64 x 32 pixels, 16 per unit), orthographic, box-filtered.
header() {
    cat <<RIB
Format 64 32 1
Projection "orthographic"
ScreenWindow -2 2 -1 1
Shutter $1 $2
PixelSamples 8 8
PixelFilter "box" 1 1
RIB
}
ball() {
    cat <<'RIB'
  LightSource "ambientlight" 1 "intensity" 1
  Surface "constant"
  AttributeBegin
    MotionBegin [0 1]
      Translate -1 0 0
      Translate 1 0 0
    MotionEnd
    Sphere 0.5 -0.5 0.5 360
  AttributeEnd
RIB
}

# --- a sphere of radius 0.5 moving from x = -1 to x = 1 -----------------------
{ header 0 1; echo 'Translate 0 0 5'; echo 'WorldBegin'; ball; echo 'WorldEnd'; } >move.rib
render_clean -o move.exr move.rib
# x = 0 (pixel 32) is covered while the centre is within 0.5: half the shutter;
# x = 1.03 (pixel 48) a quarter; x = 1.66 (pixel 58) never; the sphere never
# covers a pixel for the whole shutter.
within "$(alpha_at move.exr 32 16)" 0.44 0.56 || fail "centre alpha $(alpha_at move.exr 32 16), expected 0.5"
within "$(alpha_at move.exr 48 16)" 0.17 0.32 || fail "x = 1 alpha $(alpha_at move.exr 48 16), expected 0.24"
within "$(alpha_at move.exr 58 16)" 0 0.001 || fail "x = 1.66 alpha $(alpha_at move.exr 58 16), expected 0"
max="$(oiiotool move.exr --ch A --printstats | sed -n 's/.*Stats Max: *\([^ ]*\).*/\1/p')"
within "$max" 0.4 0.6 || fail "blurred sphere reaches alpha $max"
# Blur moves coverage around without changing its total: the sharp sphere's.
{ header 0 0; echo 'Translate 0 0 5'; echo 'WorldBegin'; ball; echo 'WorldEnd'; } >sharp.rib
render_clean -o sharp.exr sharp.rib
m_move="$(mean_alpha move.exr)"
m_sharp="$(mean_alpha sharp.exr)"
python3 -c "import sys; sys.exit(0 if abs($m_move - $m_sharp) < 0.01 * $m_sharp else 1)" ||
    fail "mean alpha blurred $m_move, sharp $m_sharp"
# A shutter that does not open: the sphere sharp where it is at that time.
within "$(alpha_at sharp.exr 16 16)" 0.99 1.01 || fail "sharp sphere at x = -1: $(alpha_at sharp.exr 16 16)"
within "$(alpha_at sharp.exr 48 16)" 0 0.001 || fail "sharp sphere at x = 1: $(alpha_at sharp.exr 48 16)"

# --- the camera moving the other way gives the same image ----------------------
{
    header 0 1
    printf 'MotionBegin [0 1]\n  Translate -1 0 5\n  Translate 1 0 5\nMotionEnd\n'
    printf 'WorldBegin\n  LightSource "ambientlight" 1\n  Surface "constant"\n'
    printf '  Sphere 0.5 -0.5 0.5 360\nWorldEnd\n'
} >camera.rib
render_clean -o camera.exr camera.rib
oiiotool camera.exr move.exr --fail 0.02 --diff >/dev/null 2>&1 ||
    fail "moving camera and moving sphere differ: $(oiiotool camera.exr move.exr --diff 2>&1 | tail -3)"

# --- deformation: a growing sphere, a subdivision mesh, curves; shadows ----------
{
    header 0 1
    cat <<'RIB'
Translate 0 0 5
WorldBegin
  LightSource "distantlight" 1 "from" [0 0 -5] "to" [0 0 0]
  Surface "matte"
  AttributeBegin
    Translate -1 0 0
    MotionBegin [0 1]
      Sphere 0.25 -0.25 0.25 360
      Sphere 0.75 -0.75 0.75 360
    MotionEnd
  AttributeEnd
  AttributeBegin
    Translate 1 0 0
    Scale 0.4 0.4 0.4
    MotionBegin [0 0.5 1]
      SubdivisionMesh "catmull-clark" [4 4 4 4 4 4] [0 1 3 2 2 3 5 4 4 5 7 6 6 7 1 0 1 7 5 3 6 0 2 4] ["interpolateboundary"] [0 0] [] [] "P" [-1 -1 1 1 -1 1 -1 1 1 1 1 1 -1 1 -1 1 1 -1 -1 -1 -1 1 -1 -1]
      SubdivisionMesh "catmull-clark" [4 4 4 4 4 4] [0 1 3 2 2 3 5 4 4 5 7 6 6 7 1 0 1 7 5 3 6 0 2 4] ["interpolateboundary"] [0 0] [] [] "P" [-2 -1 1 2 -1 1 -2 1 1 2 1 1 -1 1 -1 1 1 -1 -1 -1 -1 1 -1 -1]
      SubdivisionMesh "catmull-clark" [4 4 4 4 4 4] [0 1 3 2 2 3 5 4 4 5 7 6 6 7 1 0 1 7 5 3 6 0 2 4] ["interpolateboundary"] [0 0] [] [] "P" [-1 -1 1 1 -1 1 -1 1 1 1 1 1 -1 1 -1 1 1 -1 -1 -1 -1 1 -1 -1]
    MotionEnd
  AttributeEnd
  MotionBegin [0 1]
    Curves "linear" [2] "nonperiodic" "P" [0 -1 0 0 1 0] "constantwidth" 0.1
    Curves "linear" [2] "nonperiodic" "P" [0 -1 0 0.5 1 0] "constantwidth" 0.1
  MotionEnd
  AttributeBegin
    MotionBegin [0 1]
      Translate 0 0.6 0
      Translate 0.5 0.6 0
    MotionEnd
    Blobby 2 [1001 0 1001 16 0 2 0 1] [0.5 0 0 0 0 0.5 0 0 0 0 0.5 0 -0.2 0 0 1  0.5 0 0 0 0 0.5 0 0 0 0 0.5 0 0.2 0 0 1] [""]
  AttributeEnd
WorldEnd
RIB
} >deform.rib
render_clean -o deform.exr deform.rib
# The sphere's radius grows from 0.25 to 0.75: at 0.5 from its centre (x =
# -1.5, pixel 8) it is there for the last half of the shutter.
within "$(alpha_at deform.exr 8 16)" 0.4 0.62 || fail "growing sphere alpha $(alpha_at deform.exr 8 16), expected 0.5"
within "$(alpha_at deform.exr 16 16)" 0.99 1.01 || fail "growing sphere centre $(alpha_at deform.exr 16 16)"
out="$(oiiotool deform.exr --printstats 2>&1)"
[[ "$out" != *nan* && "$out" != *inf* ]] || fail "deform.exr has NaN or inf: $out"

# --- ptbake bakes the shutter's open time ---------------------------------------
{
    header 0.25 1
    cat <<'RIB'
Translate 0 0 5
WorldBegin
  Attribute "cull" "hidden" 0 "backfacing" 0
  Surface "bake_constant" "string filename" "ball.ptc"
  MotionBegin [0 1]
    Translate -1 0 0
    Translate 1 0 0
  MotionEnd
  Sphere 0.5 -0.5 0.5 360
WorldEnd
RIB
} >bake.rib
run "$bin/ptbake" bake.rib
[[ "$rc" == 0 ]] && no_warnings "$err" || fail "ptbake: exit $rc, stderr: $err"
# Every point of the sphere around x = -0.5 (the transform at time 0.25).
bounds="$("$bin/ptinfo" ball.ptc 2>&1 | grep -i 'bbox\|bound' | head -1)"
python3 - "$bounds" <<'PY' || fail "baked bounds: $bounds"
import re, sys
nums = [float(x) for x in re.findall(r"-?\d+\.?\d*(?:e-?\d+)?", sys.argv[1])]
assert len(nums) >= 6, nums
xmin, xmax = nums[0], nums[3]
assert abs((xmin + xmax) / 2 + 0.5) < 0.02, (xmin, xmax)
PY

((failures == 0)) || { echo "$failures check(s) failed" >&2; exit 1; }
echo "motion blur: all checks passed"
