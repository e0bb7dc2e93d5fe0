#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# CLI test of render's camera and display options: -p, -p:N, -t:N; PNG
# quantisation (round(255 v) without dither, within one step with it, the
# same bytes for every thread count); DepthOfField, PixelFilter, Exposure and
# Quantize errors naming the RIB line.
# Needs SSS_BIN_DIR (the folder with render).
#
# Every check runs; failures are listed and the script exits 1 at the end.
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
render="$bin/render"
[[ -x "$render" ]] || { echo "FAIL: missing executable $render" >&2; exit 1; }
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_camera.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"

# shellcheck source=lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
# shellcheck source=checks.sh
source "$(dirname "${BASH_SOURCE[0]}")/checks.sh"

# A constant card (0.2 0.4 0.8) filling the frame, and a sphere with a
# lens: 8-bit values are round(255 v) exactly when "dither" is [0].
scene() { # scene NAME OPTIONS
    cat > "$1" <<RIB
Format 48 32 1
PixelSamples 3 3
$2
Projection "perspective" "fov" 40
Translate 0 0 5
WorldBegin
  Surface "constant"
  AttributeBegin
    Color [0.2 0.4 0.8]
    Polygon "P" [-20 -20 2  -20 20 2  20 20 2  20 -20 2]
  AttributeEnd
  AttributeBegin
    Color [1 1 1]
    Translate 0.6 0 -2
    Sphere 0.5 -0.5 0.5 360
  AttributeEnd
WorldEnd
RIB
}

# value FILE X Y CHANNEL: one pixel's value as stored (0..1 for 8-bit).
value() {
    oiiotool "$1" --ch "$4" --crop "$2,$3,$2,$3" -o v.exr >/dev/null 2>&1 &&
        oiiotool --dumpdata v.exr 2>/dev/null | sed -n 's/.*Pixel ([0-9]*, [0-9]*): *//p'
}

# --help lists the thread spellings.
run "$render" --help
expect_rc 0 --help || true
[[ "$out" == *"-p:N, -t:N"* && "$out" == *"-p, -t, -t:all"* ]] || fail "--help lacks -p:N, -t:N, -p and -t"

# Exact quantisation: the card's corner pixel is 0.2 0.4 0.8 -> 51 102 204.
scene card.rib 'Display "card.png" "png" "rgba" "float dither" [0]'
run "$render" -p:2 card.rib
if expect_rc 0 "-p:2"; then
    for pair in "R 51" "G 102" "B 204" "A 255"; do
        set -- $pair
        v="$(value card.png 0 0 "$1")"
        awk -v v="$v" -v want="$2" 'BEGIN { exit !(int(v * 255 + 0.5) == want) }' ||
            fail "card.png $1 is $v (x 255), not $2"
    done
fi

# Dithered (PRMan's default amplitude 0.5): within one step of round(255 v),
# and the same bytes for 1 and 2 threads (-t:1, -p:2, -threads 2, -p).
scene dither.rib 'DepthOfField 2.8 0.5 4
PixelFilter "catmull-rom" 3 3
Display "dither.png" "png" "rgb"'
run "$render" -t:1 -o d1.png dither.rib
expect_rc 0 "-t:1" || true
run "$render" -p:2 -o d2.png dither.rib
expect_rc 0 "-p:2 dither" || true
run "$render" -threads 2 -o d3.png dither.rib
expect_rc 0 "-threads 2" || true
run "$render" -p -o d4.png dither.rib
expect_rc 0 "-p" || true
# The files' metadata differ (command line, thread count, date): compare
# the pixels' SHA-1.
pixels() { oiiotool --info -v --hash "$1" 2>/dev/null | grep 'SHA-1'; }
h1="$(pixels d1.png)"
[[ -n "$h1" ]] || fail "no pixel hash of d1.png"
[[ "$(pixels d2.png)" == "$h1" ]] || fail "-t:1 and -p:2 wrote different pixels"
[[ "$(pixels d3.png)" == "$h1" ]] || fail "-t:1 and -threads 2 wrote different pixels"
[[ "$(pixels d4.png)" == "$h1" ]] || fail "-t:1 and -p wrote different pixels"
v="$(value d1.png 0 0 G)"
awk -v v="$v" 'BEGIN { q = int(v * 255 + 0.5); exit !(q >= 101 && q <= 103) }' ||
    fail "dithered G $v x 255 is not within one step of 102"

# Exposure 2 2 (gain 2, gamma 2): 0.2 -> sqrt(0.4) = 0.63246 -> 161.
scene exposure.rib 'Exposure 2 2
Display "exposure.png" "png" "rgb" "float dither" [0]'
run "$render" exposure.rib
if expect_rc 0 "Exposure"; then
    v="$(value exposure.png 0 0 R)"
    awk -v v="$v" 'BEGIN { exit !(int(v * 255 + 0.5) == 161) }' || fail "exposed R $v x 255 is not 161"
fi

# Bad thread values are usage errors.
for opt in -p:x -t: -p:-1 -t:1.5 -p:99999; do
    run "$render" "$opt" card.rib
    expect_rc 2 "$opt" && [[ "$err" == "render ERROR: "*"-${opt#-}"* ]] || fail "$opt: $err"
done

# Bad requests: one error line naming file:line, exit 1.
bad() { # bad LABEL LINE3 EXPECTED
    printf 'Format 8 8 1\nPixelSamples 1 1\n%s\nWorldBegin\nWorldEnd\n' "$2" > bad.rib
    run "$render" bad.rib
    expect_rc 1 "$1" && [[ "$err" == "render ERROR: bad.rib:3"*"$3"* ]] || fail "$1: $err"
}
bad "unknown filter" 'PixelFilter "mitchell" 2 2' mitchell
bad "negative width" 'PixelFilter "box" -1 1' widths
bad "huge width" 'PixelFilter "gaussian" 40 2' widths
bad "focallength beyond focaldistance" 'DepthOfField 2 5 3' focaldistance
bad "fstop 0" 'DepthOfField 0 1 5' fstop
bad "exposure gamma" 'Exposure 1 0' gamma
bad "quantize" 'Quantize "rgba" 255 0' Quantize
ls -a | grep -q '\.tmp$' && fail "temporary files left: $(ls -a | grep '\.tmp$')"

finish_checks camera
