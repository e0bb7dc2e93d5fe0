#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# ptview on real clouds (ptsynth, ptfilter, an ASCII .ply with negative
# values): image sizes, pixel values (read back with oiiotool), contact
# sheets, false colour, the same bytes at any -threads, exit codes and error
# lines, outputs left alone on failure.
# Needs SSS_BIN_DIR (the build's bin folder) and SSS_TEST_DATA_DIR (tests/data).
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must point at the build bin folder}"
data="${SSS_TEST_DATA_DIR:?SSS_TEST_DATA_DIR must point at tests/data}"
ptview="$bin/ptview"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
cd "$tmp"

fail() {
    echo "FAIL: $*" >&2
    exit 1
}

# run_status <out> <err> cmd...: runs cmd, prints its exit status.
run_status() {
    local out="$1" err="$2"
    shift 2
    local rc=0
    "$@" >"$out" 2>"$err" || rc=$?
    echo "$rc"
}

# expect_exit <code> <stderr pattern> cmd...: exit code and ERROR line.
expect_exit() {
    local code="$1" pattern="$2"
    shift 2
    local rc
    rc="$(run_status out.txt err.txt "$@")"
    [ "$rc" = "$code" ] || { cat err.txt >&2; fail "'$*': exit $rc, expected $code"; }
    grep -q -- "$pattern" err.txt || { cat err.txt >&2; fail "'$*': no '$pattern' on stderr"; }
}

# size <image>: "W x H" as oiiotool reports it.
size() { oiiotool --info "$1" 2>/dev/null | sed -n 's/.*: *\([0-9]*\) x *\([0-9]*\),.*/\1 x \2/p'; }

# pixel <image> <x> <y>: the pixel's channel values ("r g b").
pixel() {
    oiiotool "$1" --cut "1x1+$2+$3" --printstats 2>/dev/null |
        sed -n 's/.*Stats Avg: *\([^(]*\) (.*/\1/p' | sed 's/ *$//'
}

# near <value> <expected> <tolerance>
near() { awk -v a="$1" -v b="$2" -v t="$3" 'BEGIN { d = a - b; exit !(d <= t && -d <= t) }'; }

# --- a plane seen face-on: the centre pixel is its value, exactly -----------
"$bin/ptsynth" -shape plane -n 20000 -size 10 plane.ptc >/dev/null
"$ptview" -orbit 0 0 -res 64 48 -exposure 0 plane.ptc plane.exr >out.txt
grep -q '^ptview: wrote plane.exr: 64 x 48, 1 tile' out.txt || { cat out.txt; fail "summary line"; }
[ "$(size plane.exr)" = "64 x 48" ] || fail "plane.exr is $(size plane.exr), expected 64 x 48"
[ "$(pixel plane.exr 32 24)" = "1.000000 1.000000 1.000000" ] ||
    fail "centre pixel $(pixel plane.exr 32 24), expected 1 (the plane's _radiance_t)"
# The corner is background (0.05 by default; the plane fills 95 % of the height).
[ "$(pixel plane.exr 0 0)" = "0.050000 0.050000 0.050000" ] ||
    fail "corner pixel $(pixel plane.exr 0 0), expected the background 0.05"
"$ptview" -orbit 0 0 -res 64 48 -exposure 0 -background 1 0 0 plane.ptc bg.exr >/dev/null
[ "$(pixel bg.exr 0 0)" = "1.000000 0.000000 0.000000" ] || fail "-background 1 0 0: $(pixel bg.exr 0 0)"
# -exposure -1 halves; the automatic exposure maps the plane's 1 to 1.
"$ptview" -orbit 0 0 -res 64 48 -exposure -1 plane.ptc half.exr >/dev/null
[ "$(pixel half.exr 32 24)" = "0.500000 0.500000 0.500000" ] || fail "-exposure -1: $(pixel half.exr 32 24)"
"$ptview" -orbit 0 0 -res 64 48 -o auto.png plane.ptc >out.txt
grep -q 'exposure 0 stops (auto: 1 shown as 1' out.txt || { cat out.txt; fail "auto exposure line"; }
[ "$(pixel auto.png 32 24)" = "1.000000 1.000000 1.000000" ] || fail "auto.png centre $(pixel auto.png 32 24)"
# Seen from behind (azimuth 180) the plane still shows: discs are two-sided.
"$ptview" -orbit 180 0 -res 64 48 -exposure 0 plane.ptc back.exr >/dev/null
[ "$(pixel back.exr 32 24)" = "1.000000 1.000000 1.000000" ] || fail "back side $(pixel back.exr 32 24)"
# Normals: +z towards the viewer is (0.5, 0.5, 1).
"$ptview" -orbit 0 0 -res 64 48 -channel N plane.ptc n.exr >/dev/null
[ "$(pixel n.exr 32 24)" = "0.500000 0.500000 1.000000" ] || fail "N: $(pixel n.exr 32 24)"

# --- negative values (blockers): blue with -falsecolor 1, kept with 0 -------
{
    echo "ply"
    echo "format ascii 1.0"
    echo "element vertex 400"
    for p in x y z nx ny nz radius v; do echo "property float $p"; done
    echo "end_header"
    awk 'BEGIN { for (j = 0; j < 20; j++) for (i = 0; i < 20; i++)
                   printf "%g %g 0 0 0 1 0.08 %g\n", i * 0.1, j * 0.1, (i < 10 ? -0.5 : 0.5) }'
} >signed.ply
"$ptview" -orbit 0 0 -res 40 40 -exposure 0 -channel v signed.ply signed.exr >/dev/null
left="$(pixel signed.exr 10 20)"
right="$(pixel signed.exr 30 20)"
[ "$left" = "0.050000 0.150000 0.500000" ] || fail "negative with false colour: $left, expected 0.5 x (0.1 0.3 1)"
[ "$right" = "0.500000 0.500000 0.500000" ] || fail "positive with false colour: $right"
"$ptview" -orbit 0 0 -res 40 40 -exposure 0 -falsecolor 0 -channel v signed.ply raw.exr >/dev/null
[ "$(pixel raw.exr 10 20)" = "-0.500000 -0.500000 -0.500000" ] ||
    fail "-falsecolor 0 EXR keeps -0.5: $(pixel raw.exr 10 20)"
# The largest exposure: values clamp to the float range, never Inf or NaN.
"$ptview" -orbit 0 0 -res 40 40 -exposure 256 -falsecolor 0 -channel v signed.ply big.exr >/dev/null
oiiotool big.exr --printstats 2>/dev/null | grep -q 'NanCount: 0 0 0' || fail "NaN in big.exr"
oiiotool big.exr --printstats 2>/dev/null | grep -q 'InfCount: 0 0 0' || fail "Inf in big.exr"

# --- a contact sheet: the bake next to its diffusion ------------------------
"$bin/ptsynth" -shape sphere -n 5000 -size 1 -light 1 1 1 bake.ptc >/dev/null
"$bin/ptfilter" -ssdiffusion -material marble -unitlength 0.1 bake.ptc ssd.ptc >/dev/null
"$ptview" -res 100 80 -progress 1 bake.ptc ssd.ptc sheet.png >out.txt
[ "$(size sheet.png)" = "202 x 80" ] || fail "sheet.png is $(size sheet.png), expected 202 x 80"
grep -q '^ALF_PROGRESS 100%$' out.txt || fail "-progress 1: no ALF_PROGRESS 100%"
grep -q '^ptview: tile 1: bake.ptc _radiance_t: 5000 of 5000 points drawn' out.txt ||
    { cat out.txt; fail "tile 1 line"; }
grep -q '^ptview: tile 2: ssd.ptc _ssdiffusion: 5000 of 5000 points drawn' out.txt ||
    { cat out.txt; fail "tile 2 line"; }
# The 2-pixel gap between the tiles is grey 0.2 (sRGB 124/255).
[ "$(pixel sheet.png 100 40)" = "0.486275 0.486275 0.486275" ] || fail "gap pixel $(pixel sheet.png 100 40)"
# -exposure tile: each tile's own automatic exposure, listed.
"$ptview" -res 100 80 -exposure tile -channel _radiance_t,_area bake.ptc tile.png >out.txt
grep -Eq '^ptview: wrote tile.png: .*exposure per tile -?[0-9.]+, [0-9.]+ stops' out.txt ||
    { cat out.txt; fail "-exposure tile summary"; }
# Several channels of one cloud, in two columns.
"$ptview" -res 30 20 -columns 2 -gap 0 -channel _radiance_t,_area,N,radius bake.ptc four.png >/dev/null
[ "$(size four.png)" = "60 x 40" ] || fail "four.png is $(size four.png), expected 60 x 40"

# --- the same picture at any thread count -----------------------------------
"$bin/ptsynth" -shape box -n 200000 -jitter 0.5 box.ptc >/dev/null
"$ptview" -threads 1 -res 200 150 box.ptc t1.png >/dev/null
"$ptview" -threads 2 -res 200 150 box.ptc t2.png >/dev/null
"$ptview" -threads 4 -res 200 150 box.ptc t4.png >/dev/null
cmp -s t1.png t2.png || fail "-threads 1 and 2 differ"
cmp -s t1.png t4.png || fail "-threads 1 and 4 differ"

# --- errors: missing channel, no camera, corrupt input: exit 1 --------------
cp sheet.png keep.png
expect_exit 1 "^ptview ERROR: bake.ptc: no channel \"_ssdiffusion\" (its channels: _area, _radiance_t; every cloud also has N and radius)" \
    "$ptview" -channel _ssdiffusion bake.ptc sheet.png
cmp -s sheet.png keep.png || fail "a failed run changed the existing picture"
expect_exit 1 "^ptview ERROR: -camera file: bake.ptc has no camera" "$ptview" -camera file bake.ptc x.png
head -c 100 bake.ptc >short.ptc
expect_exit 1 "^ptview ERROR: short.ptc: " "$ptview" short.ptc x.png
expect_exit 1 "^ptview ERROR: .*missing.ptc" "$ptview" missing.ptc x.png
[ ! -e x.png ] || fail "a failed run left x.png"
expect_exit 1 "ERROR: .*is an input of this job" "$ptview" -o sheet.png sheet.png
[ -n "$(ls -A . | grep '\.tmp$' || true)" ] && fail "temporaries left behind"

# --- usage errors: exit 2 ----------------------------------------------------
expect_exit 2 "option -res: 0 is out of range" "$ptview" -res 0 10 bake.ptc x.png
expect_exit 2 "option -exposure: 'abc' is not a number" "$ptview" -exposure abc bake.ptc x.png
expect_exit 2 "option -exposure: 300 is out of range" "$ptview" -exposure 300 bake.ptc x.png
expect_exit 2 "option -falsecolor: 2 is out of range" "$ptview" -falsecolor 2 bake.ptc x.png
expect_exit 2 "option -orbit needs a value" "$ptview" bake.ptc x.png -orbit 10
expect_exit 2 "option -orbit: elevation 95 is out of range" "$ptview" -orbit 0 95 bake.ptc x.png
expect_exit 2 "option -camera: 'side' is not auto, file or orbit" "$ptview" -camera side bake.ptc x.png
expect_exit 2 "option -channel: channel \"_radiance_t:red\": unknown suffix" \
    "$ptview" -channel _radiance_t:red bake.ptc x.png
expect_exit 2 "'x.jpg' does not end in .png or .exr" "$ptview" bake.ptc x.jpg
expect_exit 2 "no output picture given" "$ptview" bake.ptc
expect_exit 2 "no point cloud given" "$ptview"
expect_exit 2 "-orbit and -camera file exclude each other" "$ptview" -camera file -orbit 0 0 bake.ptc x.png
expect_exit 2 "unknown option -size" "$ptview" -size 10 bake.ptc x.png

# --- help and version: stdout, exit 0 ---------------------------------------
[ "$(run_status out.txt err.txt "$ptview" --help)" = 0 ] || fail "--help did not exit 0"
grep -q '^usage: ptview' out.txt || fail "--help printed no usage on stdout"
[ "$(run_status out.txt err.txt "$ptview" --version)" = 0 ] || fail "--version did not exit 0"
grep -q '^ptview (sss)' out.txt || fail "--version printed $(cat out.txt)"

echo "test_ptview: ok"
