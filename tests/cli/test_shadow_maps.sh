#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# Depth-map shadows the PRMan way: a shadow pass (Display "zfile", then
# MakeShadow) and a beauty pass whose shadowspot reads the map, in one RIB of
# two frames rendered frame by frame; a "shadow" display read directly; the
# depth maps' headers; a missing zfile; MakeCubeFaceEnvironment. Needs
# SSS_BIN_DIR (the build's bin folder).
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must point at the build bin folder}"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_shadow_maps.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"
# shellcheck source=lib.sh
source "$here/lib.sh"
# shellcheck source=checks.sh
source "$here/checks.sh"

# The mean of channel $2 of image $1 over the w x h box at (x, y).
box_mean() {
    oiiotool "$1" --cut "$4x$5+$2+$3" --ch "$6" --printstats 2>/dev/null |
        sed -n 's/.*Stats Avg: *\([^ ]*\).*/\1/p'
}
# Fails unless $2 (a number) satisfies the Python comparison $3 ("< 0.05").
expect_value() {
    python3 -c "import sys; v = float('$2' or 'nan'); sys.exit(0 if v $3 else 1)" ||
        fail "$1: $2 is not $3"
}

# The light sits at the origin looking along +z: a ball at z = 4 shadows a
# wall at z = 8 within 2 units of its centre. The beauty camera, 3 units to
# the side, sees the wall beside the ball: the shadow at x = 1 (pixels
# about (18, 32)), the lit wall at x = 3 (the image's centre).
geometry() {
    cat <<'RIB'
    AttributeBegin
      Translate 0 0 4
      Sphere 1 -1 1 360
    AttributeEnd
    Polygon "P" [-10 -10 8  10 -10 8  10 10 8  -10 10 8]
RIB
}
shadow_frame() { # $1 number, $2 display name, $3 display type
    cat <<RIB
FrameBegin $1
  Format 256 256 1
  PixelSamples 1 1
  PixelFilter "box" 1 1
  Projection "perspective" "fov" 80
  Display "$2" "$3" "z"
  WorldBegin
    Surface "constant"
RIB
    geometry
    echo '  WorldEnd'
    echo 'FrameEnd'
}
beauty_frame() { # $1 number, $2 image, $3 map
    cat <<RIB
FrameBegin $1
  Format 64 64 1
  PixelSamples 2 2
  Projection "perspective" "fov" 60
  Display "$2" "openexr" "rgba"
  Translate -3 0 0
  WorldBegin
    LightSource "shadowspot" 1 "from" [0 0 0] "to" [0 0 1] "coneangle" 0.6
      "intensity" 64 "string shadowname" "$3"
    Surface "matte"
RIB
    geometry
    echo '  WorldEnd'
    echo 'FrameEnd'
}
{
    shadow_frame 1 shadow.z zfile
    echo 'MakeShadow "shadow.z" "shadow.tex"'
    beauty_frame 2 beauty.exr shadow.tex
} >passes.rib
make_line="$(grep -n '^MakeShadow' passes.rib | cut -d: -f1)"

# The beauty frame alone first: its map's zfile is not there yet.
run "$bin/render" -frame 2 passes.rib
[[ "$rc" == 1 && "$err" == *"passes.rib:$make_line: MakeShadow"* && "$err" == *"shadow.z"* ]] ||
    fail "-frame 2 without the zfile: exit $rc, stderr: $err"
[[ ! -e beauty.exr ]] || fail "-frame 2 without the zfile wrote an image"

# The shadow pass writes the zfile, then MakeShadow (after it) the map.
render_clean -frame 1 passes.rib
[[ -s shadow.z && -s shadow.tex ]] || fail "frame 1 left no shadow.z or shadow.tex"
info="$(oiiotool --info -v shadow.z 2>&1)"
[[ "$info" =~ 256\ x\ +256 && "$info" == *"channel list: Z"* && "$info" == *"float openexr"* ]] ||
    fail "shadow.z is not a 256 x 256 float Z image: $info"
for attr in worldToCamera worldToScreen; do
    grep -qi "$attr" <<<"$info" || fail "shadow.z lacks $attr: $info"
done
# Depth: the ball's near side at the centre (camera z 3), the wall at the
# corners (z 8 along the axis, farther off it).
centre="$(box_mean shadow.z 126 126 4 4 Z)"
expect_value "shadow.z centre depth" "$centre" "> 2.9 and v < 3.2"
corner="$(box_mean shadow.z 0 0 4 4 Z)"
expect_value "shadow.z corner depth (the wall)" "$corner" "> 7.9 and v < 8.1"
[[ "$(oiiotool --info -v shadow.tex 2>&1)" == *'Shadow'* ]] ||
    fail "shadow.tex is not tagged as a shadow map: $(oiiotool --info -v shadow.tex 2>&1)"

# The beauty pass reads the map: the wall behind the ball is dark, beside it lit.
render_clean -frame 2 passes.rib
[[ -s beauty.exr ]] || fail "frame 2 wrote no beauty.exr"
dark="$(box_mean beauty.exr 16 30 4 4 R)"
lit="$(box_mean beauty.exr 30 30 4 4 R)"
expect_value "the shadow on the wall" "$dark" "< 0.05"
expect_value "the lit wall" "$lit" "> 0.3"

# The lookups' jitter is the point's: the image is the same for any thread count.
render_clean -frame 2 -threads 1 -o t1.exr passes.rib
render_clean -frame 2 -threads 2 -o t2.exr passes.rib
diff_out="$(oiiotool t1.exr t2.exr --diff 2>&1 || true)"
grep -q "Max error  = 0" <<<"$diff_out" || grep -q "PASS" <<<"$diff_out" ||
    fail "-threads 1 and 2 differ: $diff_out"

# The scene's shadow bias: past the gap between ball and wall, no shadow.
sed 's/^FrameBegin 2$/FrameBegin 2\n  Option "shadow" "bias" [6]/' passes.rib >biased.rib
render_clean -frame 2 biased.rib
biased="$(box_mean beauty.exr 16 30 4 4 R)"
expect_value "the wall with a bias of 6" "$biased" "> 0.3"

# shadowpoint: the +z map of six (the others empty: unshadowed) gives the
# same shadow on the wall, whose points lie towards +z from the light.
sed 's/"shadowspot" 1 "from" \[0 0 0\] "to" \[0 0 1\] "coneangle" 0.6/"shadowpoint" 1 "from" [0 0 0]/; s/"string shadowname" "shadow.tex"/"string sfpz" "shadow.tex"/' \
    passes.rib >point.rib
grep -q '"shadowpoint"' point.rib || fail "point.rib has no shadowpoint: $(cat point.rib)"
render_clean -frame 2 point.rib
dark="$(box_mean beauty.exr 16 30 4 4 R)"
lit="$(box_mean beauty.exr 30 30 4 4 R)"
expect_value "the shadow of shadowpoint" "$dark" "< 0.05"
expect_value "the wall lit by shadowpoint" "$lit" "> 0.3"

# Without a shadowname the same wall is lit everywhere.
sed 's/"string shadowname" "shadow.tex"//' passes.rib >unshadowed.rib
render_clean -frame 2 unshadowed.rib
open_wall="$(box_mean beauty.exr 16 30 4 4 R)"
expect_value "the wall without shadows" "$open_wall" "> 0.3"

# A "shadow" display is a shadow map at once; render without -frame renders
# every frame in order.
{
    shadow_frame 1 direct.shd shadow
    beauty_frame 2 direct.exr direct.shd
} >direct.rib
render_clean direct.rib
[[ -s direct.shd && -s direct.exr ]] || fail "render direct.rib: no direct.shd or direct.exr"
dark="$(box_mean direct.exr 16 30 4 4 R)"
lit="$(box_mean direct.exr 30 30 4 4 R)"
expect_value "the shadow from the shadow display" "$dark" "< 0.05"
expect_value "the lit wall (shadow display)" "$lit" "> 0.3"

# MakeCubeFaceEnvironment: six pictures into an OpenEXR cube-face map.
for face in px nx py ny pz nz; do
    oiiotool --pattern constant:color=0.2,0.4,0.8 16x16 3 -d half -o "$face.exr"
done
cat >cube.rib <<'RIB'
MakeCubeFaceEnvironment "px.exr" "nx.exr" "py.exr" "ny.exr" "pz.exr" "nz.exr" "cube.env" 90 "gaussian" 2 2
Format 16 16 1
Display "cube_frame.exr" "openexr" "rgba"
Projection "perspective" "fov" 40
Translate 0 0 4
WorldBegin
  Surface "constant"
  Sphere 1 -1 1 360
WorldEnd
RIB
render_clean cube.rib
info="$(oiiotool --info -v cube.env 2>&1)"
[[ "$info" =~ 16\ x\ +96 ]] || fail "cube.env is not 16 x 96: $info"
[[ "$info" == *'textureformat: "CubeFace Environment"'* ]] ||
    fail "cube.env is not tagged as a cube map: $info"

((failures == 0)) || { echo "$failures check(s) failed" >&2; exit 1; }
echo "shadow maps: all checks passed"
