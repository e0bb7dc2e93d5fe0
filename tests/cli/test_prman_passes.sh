#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# CLI test of RenderMan passes run as published: a bake RIB rendered bakes the
# clouds ptbake bakes; prman's thread spellings; the null and framebuffer
# displays; AOVs that are the user's; PRMan's leniency, loudly (unknown
# coordinate systems, unsupported shadeop options, undeclared parameters);
# search paths; calculatenormal at ray hits; the texture seam.
# Needs SSS_BIN_DIR (the build's bin folder) and oiiotool.
#
# Every check runs; failures are listed and the script exits 1 at the end.
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
render="$bin/render"
ptbake="$bin/ptbake"
ptinfo="$bin/ptinfo"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
scenes="$(cd "$here/../../scenes" && pwd)"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_prman.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"

# shellcheck source=lib.sh
source "$here/lib.sh"
# shellcheck source=checks.sh
source "$here/checks.sh"

# stats IMAGE CHANNEL WHAT: oiiotool's statistic (Min, Max, Avg) of one
# channel (integer files: in their own units, 0-255 or 0-65535).
stats() {
    oiiotool "$1" --ch "$2" --printstats 2>/dev/null | sed -n "s/^ *Stats $3: *//p" |
        awk 'NR == 1 { print $1 }'
}
# diff_stats IMAGE A B K WHAT: the statistic of channel A - K x channel B.
diff_stats() {
    oiiotool "$1" --ch "$2" "$1" --ch "$3" --mulc "$4" --sub --printstats 2>/dev/null |
        sed -n "s/^ *Stats $5: *//p" | sed 's/ *(float)//' | head -n 1
}
channels() { oiiotool --info -v "$1" 2>/dev/null | sed -n 's/^ *channel list: //p' | tr -d ' '; }
is() { awk -v v="$2" "BEGIN { exit !($1) }"; }

# ---------------------------------------------------------------------------
# 1. A bake RIB rendered bakes what ptbake bakes: the application note's
#    teapot, varying-albedo and blocker passes, as published (null displays).
cp "$scenes"/appnote/*_bake.rib .
for pass in teapot:direct_rad_t varying:varying_rad_t blocker:blocker_rad_t; do
    rib="${pass%%:*}_bake.rib" cloud="${pass#*:}.ptc"
    run "$render" -p:2 -progress 1 "$rib"
    expect_rc 0 "render -p:2 $rib" || continue
    [[ -f "$cloud" ]] || { fail "render $rib wrote no $cloud"; continue; }
    grep -q "render: baked $cloud: [0-9]* points" <<<"$out" || fail "render $rib: no 'baked' line: $out"
    grep -q 'every Display is "null": no image rendered' <<<"$out" ||
        fail "render $rib: a null-only pass rendered an image: $out"
    grep -q '^ALF_PROGRESS 100%' <<<"$out$err" || fail "render $rib: no progress of the bake"
    mv "$cloud" "render_$cloud"
    run "$ptbake" -t:2 "$rib"
    expect_rc 0 "ptbake -t:2 $rib" || continue
    cmp -s "render_$cloud" "$cloud" || fail "$rib: render and ptbake baked different clouds"
    n="$(points "$cloud")"
    is "v > 100000" "$n" || fail "$rib: only $n points"
done
# Nothing but the clouds: the null display wrote no file.
[[ -z "$(ls direct_rad_t* varying_rad_t* blocker_rad_t* 2>/dev/null | grep -v '\.ptc$')" ]] ||
    fail "a null display wrote a file: $(ls)"

# A view-dependent request is said: a baked object without cull 0.
cat >culled.rib <<'RIB'
Format 32 32 1
Display "culled" "null" "rgba"
Translate 0 0 5
WorldBegin
  Surface "bake_radiance_t" "string filename" ["culled.ptc"]
  Sphere 1 -1 1 360
WorldEnd
RIB
run "$render" culled.rib
expect_rc 0 "render culled.rib" || true
grep -q 'culled.rib:6: baked whole' <<<"$err" || fail "no warning about culling: $err"
run "$ptbake" -o culled_pb.ptc culled.rib
cmp -s culled.ptc culled_pb.ptc || fail "culled.rib: render and ptbake baked different clouds"

# ---------------------------------------------------------------------------
# 2. prman's thread spellings in ptbake (render's are in test_camera.sh).
for opt in -p:2 -t:2 -p -t -t:all -t:-1 -p:0; do
    run "$ptbake" "$opt" -o t.ptc culled.rib
    expect_rc 0 "ptbake $opt" || true
    cmp -s t.ptc culled.ptc || fail "ptbake $opt baked another cloud"
done
for opt in -p:x -p:-1 -t:1.5 -p:99999; do
    run "$ptbake" "$opt" culled.rib
    expect_rc 2 "ptbake $opt" && [[ "$err" == "ptbake ERROR: "*"-${opt#-}"* ]] || fail "$opt: $err"
done

# ---------------------------------------------------------------------------
# 3. Displays: "it" writes an OpenEXR file and says so; "null" writes nothing.
cat >disp.rib <<'RIB'
Format 32 24 1
PixelSamples 1 1
Display "view" "it" "rgba"
Display "+nothing" "null" "rgba"
Translate 0 0 5
WorldBegin
  Surface "constant"
  Sphere 1 -1 1 360
WorldEnd
RIB
run "$render" disp.rib
expect_rc 0 "render disp.rib" || true
[[ -f view.exr ]] || fail "the it display did not write view.exr"
grep -q 'Display "view" "it" (disp.rib:3): there is no framebuffer window here; the image is written to "view.exr"' \
    <<<"$err" || fail "the it display did not say where the image went: $err"
[[ ! -e nothing && ! -e nothing.exr ]] || fail "the null display wrote a file"

# ---------------------------------------------------------------------------
# 4. AOVs are the user's: their own names and values, no built-in layer the
#    scene did not ask for, and a missing one fails before any work.
cat >aovs.sl <<'SL'
surface aovs(output varying color _occlusion = 0;
             output varying float _sss = 0;
             output varying color mine = 0;)
{
    _occlusion = color(0.25, 0.25, 0.25);
    _sss = 0.5;
    mine = color(0.1, 0.2, 0.3);
    Oi = 1;
    Ci = 1;
}
SL
cat >aovs.rib <<'RIB'
Format 32 24 1
PixelSamples 1 1
Display "aovs.exr" "openexr" "rgba"
Display "+occ.exr" "openexr" "_occlusion"
Display "+sss.tif" "tiff" "_sss" "quantize" [0 255 0 255] "dither" [0]
Display "+mine.exr" "openexr" "color mine"
ScreenWindow -0.1 0.1 -0.1 0.1
Translate 0 0 5
WorldBegin
  Surface "aovs"
  Sphere 1 -1 1 360
WorldEnd
RIB
run "$render" aovs.rib
if expect_rc 0 "render aovs.rib"; then
    v="$(stats occ.exr R Min) $(stats occ.exr R Max)"
    [[ "$v" == "0.250000 0.250000" ]] || fail "_occlusion reads $v, not the shader's 0.25"
    v="$(oiiotool sss.tif --printstats 2>/dev/null | sed -n 's/^ *Stats Avg: *//p' | awk 'NR == 1 { print $1 }')"
    is "v > 127 && v < 128.5" "$v" || fail "_sss in the 8-bit TIFF is $v of 255, not 0.5"
    v="$(stats mine.exr B Avg)"
    is "v > 0.299 && v < 0.301" "$v" || fail "mine.B is $v, not 0.3"
    c="$(channels aovs.exr | tr ',' '\n' | sort | tr '\n' ' ')"
    [[ "$c" == "A B G R _occlusion.B _occlusion.G _occlusion.R _sss mine.B mine.G mine.R " ]] ||
        fail "aovs.exr holds $c"
fi
# One output name declared a colour by one shader and a float by another: the
# float fills the colour layer as a grey.
cat >floatocc.sl <<'SL'
surface floatocc(output varying float _occlusion = 0;) { _occlusion = 0.5; Oi = 1; Ci = 1; }
SL
cat >mixed.rib <<'RIB'
Format 16 16 1
PixelSamples 1 1
Display "mixed.exr" "openexr" "_occlusion"
ScreenWindow -0.1 0.1 -0.1 0.1
Translate 0 0 5
WorldBegin
  AttributeBegin Surface "aovs" Translate 0 0 -20 Sphere 1 -1 1 360 AttributeEnd
  AttributeBegin Surface "floatocc" Sphere 1 -1 1 360 AttributeEnd
WorldEnd
RIB
run "$render" mixed.rib
expect_rc 0 "render mixed.rib" && { v="$(stats mixed.exr _occlusion.R Min) $(stats mixed.exr _occlusion.B Max)"
    [[ "$v" == "0.500000 0.500000" ]] || fail "a float _occlusion in a colour layer reads $v, not 0.5"; }
sed -e '/^Display "+/d' aovs.rib >plain.rib
run "$render" -o plain.exr plain.rib
expect_rc 0 "render plain.rib" && { [[ "$(channels plain.exr)" == "R,G,B,A" ]] ||
    fail "an rgba EXR holds $(channels plain.exr): built-in layers nobody asked for"; }

# A mode naming what no shader outputs fails at once: before the bake and the
# image (at 4000 x 4000 and 8 x 8 samples, minutes of work).
cat >bad_aov.rib <<'RIB'
Format 4000 4000 1
PixelSamples 8 8
Display "big.exr" "openexr" "rgba"
Display "+big_missing.exr" "openexr" "_nosuchaov"
Translate 0 0 5
WorldBegin
  Surface "bake_radiance_t" "string filename" ["bad_aov.ptc"]
  Sphere 1 -1 1 360
WorldEnd
RIB
start=$SECONDS
run "$render" bad_aov.rib
expect_rc 1 "a missing AOV" || true
[[ "$err" == "render ERROR: display '+big_missing.exr' (bad_aov.rib:4): mode '_nosuchaov' names '_nosuchaov', which no surface shader"* ]] ||
    fail "missing AOV: $err"
((SECONDS - start < 20)) || fail "the missing AOV was found after $((SECONDS - start)) s"
[[ ! -e bad_aov.ptc && ! -e big.exr ]] || fail "a failed job wrote an output"

# ---------------------------------------------------------------------------
# 5. Leniency, loudly: an unknown space is "current" (warned once per call),
#    an unsupported option of a shadeop is warned once, undeclared parameters
#    are typed by the shader's declaration; a missing texture stays an error.
cat >lenient.sl <<'SL'
surface lenient(string dispSPACE = ""; float Ksub = 1; color tint = 1;)
{
    vector d = vtransform(dispSPACE, vector(0, 0, 1));
    float occ = occlusion(P, normalize(N), 4, "nosuchoption", 1);
    Oi = 1;
    Ci = Ksub * tint * (zcomp(d) + occ * 0);
}
SL
cat >lenient.rib <<'RIB'
Format 16 16 1
PixelSamples 1 1
Display "lenient.exr" "openexr" "rgba"
ScreenWindow -0.1 0.1 -0.1 0.1
Translate 0 0 5
WorldBegin
  Surface "lenient" "Ksub" 0.5 "tint" [1 0.5 0.25] "Kmissing" 3
  Sphere 1 -1 1 360
WorldEnd
RIB
run "$render" lenient.rib
if expect_rc 0 "render lenient.rib"; then
    [[ "$(grep -c 'unknown coordinate system ""' <<<"$err")" == 1 ]] ||
        fail "the unknown space was not warned exactly once: $err"
    grep -q 'lenient.sl:3.*unknown coordinate system "": taken as "current"' <<<"$err" ||
        fail "the space warning names no file:line: $err"
    [[ "$(grep -c 'occlusion option "nosuchoption" is not supported; ignored' <<<"$err")" == 1 ]] ||
        fail "the unsupported option was not warned exactly once: $err"
    grep -q "has no parameter 'Kmissing'" <<<"$err" || fail "Kmissing was not warned: $err"
    # Ci = Ksub x tint x 1: the undeclared numbers took the shader's types.
    v="$(stats lenient.exr R Avg) $(stats lenient.exr G Avg) $(stats lenient.exr B Avg)"
    [[ "$v" == "0.500000 0.250000 0.125000" ]] || fail "Ksub/tint gave $v, not 0.5 0.25 0.125"
fi
cat >notex.sl <<'SL'
surface notex() { Oi = 1; Ci = color texture("nosuch_map.tif"); }
SL
sed -e 's/"lenient" .*/"notex"/' -e 's/lenient.exr/notex.exr/' lenient.rib >notex.rib
run "$render" notex.rib
expect_rc 1 "a missing texture" || true
[[ "$err" == *"nosuch_map.tif"*"texture search path \".\""* ]] ||
    fail "the missing texture's error does not name the search path: $err"
[[ ! -e notex.exr ]] || fail "a render with a missing texture wrote its image"

# ---------------------------------------------------------------------------
# 6. Search paths, as PRMan: relative to the working folder, with & and @.
mkdir -p lib lib2 maps parts sub
oiiotool --create 8x8 3 --fill:color=0.8,0.8,0.8 8x8 -d uint8 -o maps/grey.png 2>/dev/null
cat >lib/fromlib.sl <<'SL'
surface fromlib() { Oi = 1; Ci = color texture("grey.png"); }
SL
cp aovs.sl lib2/aovs2.sl
sed -i 's/surface aovs/surface aovs2/' lib2/aovs2.sl
printf 'Sphere 1 -1 1 360\n' >parts/ball.rib
cat >sub/paths.rib <<'RIB'
Option "searchpath" "shader" ["lib:&"]
Option "searchpath" "shader" ["lib2:&"]
Option "searchpath" "texture" ["maps:@"]
Option "searchpath" "archive" ["parts"]
Format 16 16 1
PixelSamples 1 1
Display "paths.exr" "openexr" "rgba"
ScreenWindow -0.1 0.1 -0.1 0.1
Translate 0 0 5
WorldBegin
  AttributeBegin
    Surface "fromlib"
    ReadArchive "ball.rib"
  AttributeEnd
  AttributeBegin
    Surface "aovs2"
    Translate 0 0 -10
    Sphere 0.1 -0.1 0.1 360
  AttributeEnd
WorldEnd
RIB
run "$render" sub/paths.rib
if expect_rc 0 "render sub/paths.rib (lib, lib2, maps, parts from the working folder)"; then
    v="$(stats paths.exr R Avg)"
    is "v > 0.799 && v < 0.801" "$v" || fail "the texture found along the path gave $v, not 0.8"
fi
cd sub
run "$render" paths.rib
cd ..
expect_rc 1 "paths.rib from another working folder" || true
[[ "$err" == *'ball.rib: cannot open: No such file or directory (not found along the archive search path "parts"'* ]] ||
    fail "relative search folders are not the working folder's: $err"

# ---------------------------------------------------------------------------
# 7. calculatenormal at ray hits faces like N on every primitive, bumped or
#    not: white where it does, black where it does not (R = A everywhere).
cat >bumpcheck.sl <<'SL'
surface bumpcheck(float amp = 0.01;)
{
    normal Nn = normalize(N);
    normal Nb = normalize(calculatenormal(P + amp * noise(P * 8) * Nn));
    Oi = 1;
    Ci = Nb . Nn > 0 ? color 1 : color 0;
}
SL
cat >bump.rib <<'RIB'
Format 120 90 1
PixelSamples 2 2
Projection "perspective" "fov" 40
Display "bump.exr" "openexr" "rgba"
Translate 0 0 14
WorldBegin
  Surface "bumpcheck"
  AttributeBegin Translate -4 2 0 Sphere 1.4 -1.4 1.4 360 AttributeEnd
  AttributeBegin Translate 0 2 0 Rotate 60 1 0 0 Torus 1.1 0.4 0 360 360 AttributeEnd
  AttributeBegin
    Translate 4 1.5 0 Rotate -90 1 0 0 Scale 0.6 0.6 0.6 Geometry "teapot"
  AttributeEnd
  AttributeBegin Translate -4 -2.5 0 Rotate 70 1 0 0 Cylinder 1 -1 1 360 AttributeEnd
  AttributeBegin
    Translate 0 -2.5 0 Rotate 30 1 1 0
    SubdivisionMesh "catmull-clark" [4 4 4 4 4 4] [0 1 3 2 2 3 7 6 6 7 5 4 4 5 1 0 1 5 7 3 4 0 2 6]
      ["interpolateboundary"] [0 0] [] []
      "P" [-1 -1 1  1 -1 1  -1 1 1  1 1 1  -1 -1 -1  1 -1 -1  -1 1 -1  1 1 -1]
  AttributeEnd
  AttributeBegin Translate 4 -2.5 0 ReverseOrientation Sphere 1.4 -1.4 1.4 360 AttributeEnd
  # A background patch, mirrored and inside out: both flip its N.
  AttributeBegin
    Translate 0 0 3 Orientation "inside" Scale 1 1 -1
    Patch "bilinear" "P" [-9 -7 0  9 -7 0  -9 7 0  9 7 0]
  AttributeEnd
WorldEnd
RIB
run "$render" bump.rib
if expect_rc 0 "render bump.rib"; then
    covered="$(stats bump.exr A Avg)"
    is "v > 0.1" "$covered" || fail "bump.rib: the primitives cover only $covered of the image"
    v="$(diff_stats bump.exr R A 1 Min)"
    is "v > -1e-6" "$v" || fail "calculatenormal faces into the surface somewhere (R - A min $v)"
fi

# ---------------------------------------------------------------------------
# 8. No seam: a uniform map on a sphere and a torus whose s = 0 seams face
#    the camera reads the same everywhere (R = 0.8 A).
cat >tex.sl <<'SL'
surface tex(string map = "";) { Oi = 1; Ci = color texture(map); }
SL
cat >seam.rib <<'RIB'
Format 160 120 1
PixelSamples 2 2
Projection "perspective" "fov" 30
Display "seam.exr" "openexr" "rgba"
Translate 0 0 8
WorldBegin
  Surface "tex" "string map" ["maps/grey.png"]
  AttributeBegin Translate -1.2 0 0 Rotate 90 0 1 0 Sphere 1 -1 1 360 AttributeEnd
  AttributeBegin Translate 1.2 0 0 Rotate 90 1 0 0 Torus 0.7 0.3 0 360 360 AttributeEnd
WorldEnd
RIB
run "$render" seam.rib
if expect_rc 0 "render seam.rib"; then
    v="$(diff_stats seam.exr R A 0.8 Min)"
    is "v > -0.002" "$v" || fail "a dark seam: R - 0.8 A down to $v"
fi

# ---------------------------------------------------------------------------
# 9. Rays hit both faces of a one-sided surface (PRMan's default "hitsides"):
#    a gather from inside a Sides 1 ball finds where it leaves it (the
#    application note's absorption pass); "hitsides" "front" does not.
cat >inside.sl <<'SL'
surface inside(string sides = "both";)
{
    float hits = 0, depth = 0;
    rayinfo("depth", depth);
    if (depth == 0) {
        gather("illuminance", P, -normalize(N), PI / 4, 16, "hitsides", sides,
               "label", "subsurf") {
            hits += 1;
        }
    }
    Oi = 1;
    Ci = hits / 16;
}
SL
cat >inside.rib <<'RIB'
Format 16 16 1
PixelSamples 1 1
Display "inside.exr" "openexr" "rgba"
ScreenWindow -0.1 0.1 -0.1 0.1
Translate 0 0 5
WorldBegin
  Sides 1
  Surface "inside"
  Sphere 1 -1 1 360
WorldEnd
RIB
run "$render" inside.rib
expect_rc 0 "render inside.rib" && { v="$(stats inside.exr R Min)"
    is "v == 1" "$v" || fail "gather from inside a Sides 1 ball: only $v of the rays hit"; }
sed -e 's/Surface "inside"/Surface "inside" "string sides" ["front"]/' -e 's/inside.exr/front.exr/' \
    inside.rib >front.rib
run "$render" front.rib
expect_rc 0 "render front.rib" && { v="$(stats front.exr R Max)"
    is "v == 0" "$v" || fail "hitsides front: $v of the rays hit back faces"; }

finish_checks prman_passes
