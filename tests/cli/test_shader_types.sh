#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# Imager and volume shaders through the real tools: a lit sphere rendered
# with the standard `background` imager (empty pixels get the colour and
# alpha 1, the sphere keeps its colour, before Exposure, AOVs untouched),
# with the standard `fog` and `depthcue` atmospheres (the sphere's colour
# moves towards the fog's by the amount its distance gives, misses are not
# fogged), the requests read without -lenient (no warning, exit 0), ptbake
# ignoring them, sloinfo and shader on the new types. Needs SSS_BIN_DIR.
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must point at the build bin folder}"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_shader_types.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"
# shellcheck source=lib.sh
source "$here/lib.sh"
# shellcheck source=checks.sh
source "$here/checks.sh"

# chan FILE CHANNEL WHICH [CUT]: oiiotool's Avg/Min/Max of one channel,
# over the region CUT (WxH+X+Y) when given.
chan() {
    local cut=()
    [[ -n "${4:-}" ]] && cut=(--cut "$4")
    oiiotool "$1" "${cut[@]}" --ch "$2" --printstats 2>/dev/null |
        sed -n "s/^ *Stats $3: *\([^ ]*\).*/\1/p" | head -1
}
# near GOT WANT TOL LABEL: |got - want| <= tol.
near() {
    python3 -c "import sys; g = float('$1' or 'nan'); sys.exit(0 if abs(g - ($2)) <= $3 else 1)" ||
        fail "$4: got $1, expected $2 (within $3)"
}
# Renders; fails unless the exit is 0 and nothing is on stderr.
render_clean() {
    run "$bin/render" "$@"
    [[ "$rc" == 0 && -z "$err" ]] || fail "render $*: exit $rc, stderr: $err"
}

# scene OPTIONS WORLD: a matte sphere of radius 1, 6 in front of the eye, lit
# by an ambient and a distant light, in a 64 x 48 frame (fov 30: the sphere
# is about 15 pixels in radius, the corners are empty). Float EXR, box filter.
scene() {
    cat <<RIB
Format 64 48 1
PixelSamples 2 2
PixelFilter "box" 1 1
Projection "perspective" "fov" 30
Clipping 1 11
$1
Display "out.exr" "openexr" "rgba,diffuse" "string type" ["float"]
Translate 0 0 6
WorldBegin
  LightSource "ambientlight" 1 "intensity" [0.2]
  LightSource "distantlight" 2 "from" [-1 1 -5] "to" [0 0 0] "intensity" [0.8]
  Color [0.9 0.5 0.3]
  Surface "matte"
$2
  Sphere 1 -1 1 360
WorldEnd
RIB
}
centre=4x4+30+22 # inside the sphere
corner=8x8+0+0   # empty

scene "" "" >ref.rib
render_clean -o ref.exr ref.rib
for c in R G B; do
    eval "ref_$c=\$(chan ref.exr $c Avg $centre)"
    eval "mean_$c=\$(chan ref.exr $c Avg)"
done
ref_A="$(chan ref.exr A Avg)"
near "$(chan ref.exr R Max $corner)" 0 0 "reference: the corner is empty"
python3 -c "import sys; sys.exit(0 if 0.1 < float('$ref_R') < 2 else 1)" ||
    fail "reference: the sphere's centre is not lit (R $ref_R)"

# --- (a) the background imager ------------------------------------------------
scene 'Imager "background" "color bgcolor" [0.25 0.5 0.75]' "" >bg.rib
render_clean -o bg.exr bg.rib
near "$(chan bg.exr R Avg $corner)" 0.25 1e-6 "background: empty pixels' R"
near "$(chan bg.exr G Avg $corner)" 0.5 1e-6 "background: empty pixels' G"
near "$(chan bg.exr B Avg $corner)" 0.75 1e-6 "background: empty pixels' B"
near "$(chan bg.exr A Min)" 1 1e-6 "background: alpha is 1 everywhere (min)"
near "$(chan bg.exr R Avg $centre)" "$ref_R" 1e-6 "background: the sphere's R"
near "$(chan bg.exr B Avg $centre)" "$ref_B" 1e-6 "background: the sphere's B"
# Every pixel, edges too: Ci + (1 - alpha) bgcolor, so the image's mean is
# the reference's mean plus bgcolor times its uncovered share.
near "$(chan bg.exr R Avg)" "$mean_R + 0.25 * (1 - $ref_A)" 1e-5 "background: mean R"
near "$(chan bg.exr B Avg)" "$mean_B + 0.75 * (1 - $ref_A)" 1e-5 "background: mean B"
# AOVs are not the imager's: the empty pixels' diffuse stays 0.
near "$(chan bg.exr diffuse.R Max $corner)" 0 0 "background: the diffuse AOV was changed"
# The imager runs before Exposure (RISpec's pipeline): gain 2 doubles bgcolor.
scene 'Imager "background" "color bgcolor" [0.25 0.5 0.75]
Exposure 2 1' "" >bgexp.rib
render_clean -o bgexp.exr bgexp.rib
near "$(chan bgexp.exr R Avg $corner)" 0.5 1e-6 "background then exposure: empty R"
near "$(chan bgexp.exr R Avg $centre)" "2 * $ref_R" 1e-5 "background then exposure: sphere R"
# Imager "null" turns it off again.
scene 'Imager "background"
Imager "null"' "" >bgnull.rib
render_clean -o bgnull.exr bgnull.rib
near "$(chan bgnull.exr A Avg)" "$ref_A" 0 "Imager \"null\": alpha"

# --- (b) the fog atmosphere ---------------------------------------------------
# The centre pixels' camera rays travel 5 (to z = -1 of the sphere): the colour
# moves towards the fog's by 1 - exp(-5 / distance) = 1 - exp(-1) = 0.632.
scene "" '  Atmosphere "fog" "float distance" [5] "color background" [0.5 0.6 0.7]' >fog.rib
render_clean -o fog.exr fog.rib
a="(1 - math.exp(-1))"
for c in R G B; do
    bgv="$(case $c in R) echo 0.5 ;; G) echo 0.6 ;; B) echo 0.7 ;; esac)"
    eval "r=\$ref_$c"
    want="$(python3 -c "import math; print($r + ($bgv - $r) * $a)")"
    near "$(chan fog.exr $c Avg $centre)" "$want" 2e-3 "fog: the sphere's $c"
done
near "$(chan fog.exr R Max $corner)" 0 0 "fog: camera rays that hit nothing are not fogged (R)"
near "$(chan fog.exr A Max $corner)" 0 0 "fog: camera rays that hit nothing are not fogged (A)"
near "$(chan fog.exr A Avg $centre)" 1 1e-6 "fog: the opaque sphere stays opaque"
# The fog is the atmosphere's colour, not the AOVs': diffuse is the surface's.
near "$(chan fog.exr diffuse.R Avg $centre)" "$(chan ref.exr diffuse.R Avg $centre)" 1e-6 \
    "fog: the diffuse AOV changed"

# depthcue: depth(P) = (5 - 1) / (11 - 1) = 0.4 at the centre; from 0 to 0.8
# the colour is half way to the background.
scene "" '  Atmosphere "depthcue" "float mindistance" [0] "float maxdistance" [0.8] "color background" [1 1 1]' >cue.rib
render_clean -o cue.exr cue.rib
near "$(chan cue.exr R Avg $centre)" "$ref_R + (1 - $ref_R) * 0.5" 3e-3 "depthcue: the sphere's R"

# --- (c) the requests are read strictly, ptbake ignores what it does not run ---
# (every render above ran without -lenient and printed nothing)
cat >bake.rib <<'RIB'
Imager "nosuchimager"
WorldBegin
  LightSource "distantlight" 1 "from" [0 0 -5] "to" [0 0 0]
  Atmosphere "nosuchvolume"
  Surface "bake_radiance_t" "string filename" ["ball.ptc"]
  Sphere 1 -1 1 360
WorldEnd
RIB
run "$bin/ptbake" bake.rib
[[ "$rc" == 0 && -z "$err" && -s ball.ptc ]] ||
    fail "ptbake with an Imager and an Atmosphere it does not run: exit $rc, stderr: $err"
scene 'Imager "nosuchimager"' "" >missing.rib
run "$bin/render" -o missing.exr missing.rib
[[ "$rc" == 1 && "$err" == *'missing.rib:6: Imager "nosuchimager"'* ]] ||
    fail "render with a missing imager: exit $rc, stderr: $err"
scene "" '  Atmosphere "matte"' >wrongkind.rib
run "$bin/render" -o wrongkind.exr wrongkind.rib
[[ "$rc" == 1 && "$err" == *"Atmosphere"*"surface shader, not a volume shader"* ]] ||
    fail "render with a surface as an atmosphere: exit $rc, stderr: $err"

# --- the compiler and sloinfo on the new types ----------------------------------
run "$bin/sloinfo" "$bin/../shaders/fog.slo" "$bin/../shaders/background.slo"
[[ "$rc" == 0 && "$out" == *'volume "fog"'* && "$out" == *'imager "background"'* ]] ||
    fail "sloinfo fog background: exit $rc, stdout: $out"
printf 'transformation t() { P = P; }\n' >t.sl
run "$bin/shader" t.sl
[[ "$rc" == 1 && "$err" == *"t.sl:1:1: error: transformation shaders are not supported"* ]] ||
    fail "shader on a transformation shader: exit $rc, stderr: $err"

finish_checks "shader types"
