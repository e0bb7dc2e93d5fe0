#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# The RIB that users' scenes bring: gzip-compressed scenes and archives, a
# scene on standard input, and the RISpec requests render and ptbake carry
# out (each renders a non-empty image with exit 0 and no warning), or refuse
# by default when still not implemented (-lenient: a warning). Needs
# SSS_BIN_DIR (the build's bin folder).
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must point at the build bin folder}"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_rib_requests.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"
# shellcheck source=lib.sh
source "$here/lib.sh"
# shellcheck source=checks.sh
source "$here/checks.sh"

# The mean of an image's alpha: the share of the frame something covers.
coverage() {
    oiiotool "$1" --ch A --printstats 2>/dev/null | sed -n 's/.*Stats Avg: *\([^ ]*\).*/\1/p'
}
# Fails unless the image's alpha coverage lies in [lo, hi].
expect_coverage() {
    local c
    c="$(coverage "$1")"
    python3 -c "import sys; c = float('$c' or 'nan'); sys.exit(0 if $2 <= c <= $3 else 1)" ||
        fail "$1: coverage $c not in [$2, $3]"
}

header() {
    cat <<'RIB'
Format 64 48 1
PixelSamples 2 2
Projection "perspective" "fov" 35
Translate 0 0 6
WorldBegin
  LightSource "distantlight" 1 "from" [0 0 -5] "to" [0 0 0] "intensity" 1
  Surface "matte"
RIB
}

# --- gzip and standard input --------------------------------------------------
{
    header
    echo '  ReadArchive "ball.rib.gz"'
    echo 'WorldEnd'
} >scene.rib
echo 'Sphere 1 -1 1 360' | gzip >ball.rib.gz
gzip -c scene.rib >scene.rib.gz
render_clean -o plain.exr scene.rib
expect_coverage plain.exr 0.15 0.18
render_clean -o gz.exr scene.rib.gz
render_clean -o stdin.exr - <scene.rib
render_clean -o stdin_gz.exr - <scene.rib.gz
for f in gz stdin stdin_gz; do
    oiiotool plain.exr "$f.exr" --fail 0 --diff >/dev/null 2>&1 || fail "$f.exr differs from plain.exr"
done
# Without -o, a scene from standard input renders to render.exr.
render_clean - <scene.rib
[[ -f render.exr ]] || fail "render - wrote no render.exr"
# A truncated gzip stream is an error naming standard input.
head -c 40 scene.rib.gz >cut.rib.gz
run "$bin/render" -o cut.exr - <cut.rib.gz
[[ "$rc" == 1 && "$err" == *"render ERROR: <stdin>"*"truncated"* ]] ||
    fail "truncated gzip on stdin: exit $rc, stderr: $err"
[[ ! -e cut.exr ]] || fail "a failed render left cut.exr"
# ptbake reads standard input too, and -newer never skips it.
cat >bake.rib <<'RIB'
WorldBegin
  LightSource "distantlight" 1 "from" [0 0 -5] "to" [0 0 0] "intensity" 1
  Surface "bake_radiance_t" "string filename" ["ball.ptc"]
  Sphere 1 -1 1 360
WorldEnd
RIB
run "$bin/ptbake" -spacing 0.1 -newer 1 - <bake.rib
[[ "$rc" == 0 && -s ball.ptc ]] || fail "ptbake - : exit $rc, stderr: $err"
touch -d '2 hours ago' bake.rib
run "$bin/ptbake" -spacing 0.1 -newer 1 - <bake.rib
[[ "$rc" == 0 && "$out" != *"nothing to do"* ]] || fail "ptbake -newer 1 - skipped: $out"

# --- primitives -----------------------------------------------------------------
# Each renders with exit 0 and no warning, covering about what it should.
primitive() {
    local name="$1" lo="$2" hi="$3"
    shift 3
    { header; printf '%s\n' "$@"; echo 'WorldEnd'; } >"$name.rib"
    render_clean -o "$name.exr" "$name.rib"
    expect_coverage "$name.exr" "$lo" "$hi"
}
# Three disks of diameter 0.6 facing the camera: 3 x 0.283 of a 5.04 x 3.78
# frame (fov 35 at distance 6): 0.0445.
primitive points 0.042 0.047 'Points "P" [-1 0 0 0 0.5 0 1 0 0] "constantwidth" [0.6]'
# A ribbon about 3 long and 0.3 wide, and a thin closed loop 1.4 long: 0.05.
primitive curves 0.04 0.06 'Basis "catmull-rom" 1 "catmull-rom" 1' \
    'Curves "cubic" [6] "nonperiodic" "P" [-1.5 0 0 -1.3 0 0 -0.5 0.3 0 0.5 -0.3 0 1.3 0 0 1.5 0 0] "constantwidth" 0.3' \
    'Curves "linear" [3] "periodic" "P" [0 -1 0 0.5 -1 0 0.2 -0.5 0] "width" [0.05 0.05 0.05] "Cs" [1 0 0 0 1 0 0 0 1]'
# A NuPatch (a 2 x 2 bilinear square) with a round hole of radius 0.25 in
# (u, v): (4 - pi / 4) of 19.05.
primitive nupatch 0.165 0.172 \
    'TrimCurve [1] [3] [0 0 0 0.25 0.25 0.5 0.5 0.75 0.75 1 1 1] [0] [1] [9] [0.75 0.530330086 0.5 0.176776695 0.25 0.176776695 0.5 0.530330086 0.75] [0.5 0.530330086 0.75 0.530330086 0.5 0.176776695 0.25 0.176776695 0.5] [1 0.707106781 1 0.707106781 1 0.707106781 1 0.707106781 1]' \
    'NuPatch 2 2 [0 0 1 1] 0 1 2 2 [0 0 1 1] 0 1 "P" [-1 -1 0 1 -1 0 -1 1 0 1 1 0]'
# A Blobby: two blobs of radius 1.5 at x = +-0.8, merged (their fields add
# to 0.73 between them), red and blue blended: about 3.3 of 19.05.
primitive blobby 0.16 0.20 \
    'Blobby 2 [1001 0 1001 16 0 2 0 1] [1.5 0 0 0 0 1.5 0 0 0 0 1.5 0 -0.8 0 0 1 1.5 0 0 0 0 1.5 0 0 0 0 1.5 0 0.8 0 0 1] [""] "Cs" [1 0 0 0 0 1]'
# Procedural "RunProgram": the program reads "detail data" lines and answers
# RIB ending with the byte 0377; it is found along the procedural search path.
mkdir -p procs
cat >procs/spheres <<'SH'
#!/bin/sh
while read -r detail n; do
    echo "# detail $detail" >>requests.txt
    i=0
    while [ "$i" -lt "$n" ]; do
        echo "AttributeBegin Translate $((i - 1)) 0 0 Sphere 0.4 -0.4 0.4 360 AttributeEnd"
        i=$((i + 1))
    done
    printf '\377'
done
SH
chmod +x procs/spheres
primitive runprogram 0.065 0.085 'Option "searchpath" "procedural" ["procs:&"]' \
    'Procedural "RunProgram" ["spheres" "3"] [-1.4 1.4 -0.4 0.4 -0.4 0.4]'
# Asked once, with the bound's raster area (64 x 48 image: about 600 pixels).
python3 -c "
import sys
d = [float(l.split()[2]) for l in open('requests.txt')]
sys.exit(0 if len(d) == 1 and 300 < d[0] < 1500 else 1)" || fail "RunProgram requests: $(cat requests.txt)"
printf '#!/bin/sh\nexit 3\n' >procs/broken && chmod +x procs/broken
{ header; echo 'Option "searchpath" "procedural" ["procs"]'
  echo 'Procedural "RunProgram" ["broken" ""] [-1 1 -1 1 -1 1]'; echo 'WorldEnd'; } >broken.rib
run "$bin/render" -o broken.exr broken.rib
[[ "$rc" == 1 && "$err" == *"broken.rib:9: Procedural \"RunProgram\""*"exited with status 3"* ]] ||
    fail "failing RunProgram: exit $rc, stderr: $err"
# ptbake bakes points and curves like any surface.
cat >bake_points.rib <<'RIB'
WorldBegin
  LightSource "distantlight" 1 "from" [0 0 -5] "to" [0 0 0] "intensity" 1
  Surface "bake_radiance_t" "string filename" ["points.ptc"]
  Points "P" [0 0 0 1 0 0] "constantwidth" [0.5]
  Curves "linear" [2] "nonperiodic" "P" [0 1 0 2 1 0] "constantwidth" 0.2
WorldEnd
RIB
run "$bin/ptbake" -progress 1 -spacing 0.02 bake_points.rib
[[ "$rc" == 0 ]] && no_warnings "$err" || fail "ptbake points and curves: exit $rc, stderr: $err"
area="$(sed -n 's/.*wrote points.ptc: .* area \([0-9.e+-]*\),.*/\1/p' <<<"$out")"
python3 -c "import sys, math; a = float('$area' or 'nan'); sys.exit(0 if abs(a - (2 * math.pi * 0.0625 + 0.4)) < 0.01 else 1)" ||
    fail "points.ptc: total area $area, expected $(python3 -c 'import math; print(2 * math.pi * 0.0625 + 0.4)')"

# ... and a Blobby: one blob of radius 1, a sphere of radius sqrt(1 - 0.5^(1/3)).
cat >bake_blobby.rib <<'RIB'
WorldBegin
  LightSource "distantlight" 1 "from" [0 0 -5] "to" [0 0 0] "intensity" 1
  Surface "bake_radiance_t" "string filename" ["blobby.ptc"]
  Blobby 1 [1001 0] [1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1] [""]
WorldEnd
RIB
run "$bin/ptbake" -progress 1 -spacing 0.02 bake_blobby.rib
[[ "$rc" == 0 && -s blobby.ptc ]] && no_warnings "$err" || fail "ptbake blobby: exit $rc, stderr: $err"
area="$(sed -n 's/.*wrote blobby.ptc: .* area \([0-9.e+-]*\),.*/\1/p' <<<"$out")"
python3 -c "import sys, math; a = float('$area' or 'nan'); e = 4 * math.pi * (1 - 0.5 ** (1 / 3)); sys.exit(0 if abs(a - e) < 0.01 * e else 1)" ||
    fail "blobby.ptc: total area $area, expected $(python3 -c 'import math; print(4 * math.pi * (1 - 0.5 ** (1 / 3)))')"

# --- MakeTexture and MakeLatLongEnvironment -------------------------------------
oiiotool --pattern checker:width=8:height=8:color1=1,0,0:color2=0,0,1 64x64 3 -d uint8 -o checker.png
oiiotool --pattern constant:color=0.2,0.4,0.8 64x32 3 -d half -o sky.exr
cat >make.rib <<'RIB'
MakeTexture "checker.png" "checker.tx" "periodic" "clamp" "gaussian" 2 2
MakeLatLongEnvironment "sky.exr" "sky.tx" "box" 1 1
Format 64 48 1
Projection "perspective" "fov" 35
Translate 0 0 6
WorldBegin
  LightSource "ambientlight" 1 "intensity" 1
  Surface "paintedplastic" "texturename" "checker.tx" "Ka" 1 "Kd" 0 "Ks" 0
  Sphere 1 -1 1 360
WorldEnd
RIB
render_clean -o make.exr make.rib
info="$(oiiotool --info -v checker.tx 2>&1)"
[[ "$info" == *"MIP-map levels"* && "$info" == *"wrapmodes: \"periodic,clamp\""* ]] ||
    fail "checker.tx is not a MIP-mapped texture with the wrap modes: $info"
[[ "$(oiiotool --info -v sky.tx 2>&1)" == *'textureformat: "LatLong Environment"'* ]] ||
    fail "sky.tx is not a lat-long environment: $(oiiotool --info -v sky.tx 2>&1)"
# The sphere shows the checker's red and blue (ambient light 1, Ka 1).
red="$(oiiotool make.exr --ch R --printstats | sed -n 's/.*Stats Max: *\([^ ]*\).*/\1/p')"
blue="$(oiiotool make.exr --ch B --printstats | sed -n 's/.*Stats Max: *\([^ ]*\).*/\1/p')"
python3 -c "import sys; sys.exit(0 if float('$red') > 0.5 and float('$blue') > 0.5 else 1)" ||
    fail "make.exr: red max $red, blue max $blue"
# A second run finds the textures newer than the pictures and keeps them.
before="$(stat -c %Y.%s checker.tx)"
sleep 1
render_clean -o make.exr make.rib
[[ "$(stat -c %Y.%s checker.tx)" == "$before" ]] || fail "checker.tx was made again"

# --- not implemented: an error by default, -lenient: one warning --------------
{ header; echo '  MotionBegin [0 1]'; echo '    Color 1 0 0'; echo '    Color 0 1 0';
  echo '  MotionEnd'; echo '  Sphere 1 -1 1 360'; echo '  Frobnicate 3'; echo 'WorldEnd'; } >todo.rib
run "$bin/render" -o todo.exr todo.rib
[[ "$rc" == 1 && "$err" == "render ERROR: todo.rib:9: Color: motion blur of Color is not supported (reading leniently: the first time sample is used, with a warning)" ]] ||
    fail "strict: exit $rc, stderr: $err"
[[ ! -e todo.exr ]] || fail "strict: an image was written"
run "$bin/ptbake" todo.rib
[[ "$rc" == 1 && "$err" == *"ptbake ERROR: todo.rib:9: Color"* ]] || fail "ptbake strict: exit $rc, stderr: $err"
run "$bin/render" -lenient -o todo.exr todo.rib
[[ "$rc" == 0 && -s todo.exr ]] || fail "-lenient: exit $rc, stderr: $err"
[[ "$(grep -c 'render WARNING' <<<"$err")" == 2 && "$err" == *"first time sample is used"* &&
    "$err" == *"unknown statement Frobnicate, skipped"* ]] || fail "-lenient warnings: $err"

((failures == 0)) || { echo "$failures check(s) failed" >&2; exit 1; }
echo "rib requests: all checks passed"
