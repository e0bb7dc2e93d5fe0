#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# CLI test of shading at the ShadingRate (docs/render.md, "Shading rate"):
# render shades each lattice point of the diced surfaces once, whatever the
# pixel samples, and every sample that hits it takes its values. Checks:
#   - at PixelSamples 4 4 the image matches shading every sample on its own
#     (-pixelshading 1) within the documented tolerance, for
#     ShadingInterpolation "constant" and "smooth", with a gather shader too;
#   - the shading points (and the gather shader's secondary rays) do not
#     grow with the pixel samples, and shrink with a coarser ShadingRate;
#   - the image is the same for any thread count, bit for bit;
#   - -progress 1 reports the camera, shadow and secondary rays and the
#     shading points; motion blur shades every sample (as documented).
# Needs SSS_BIN_DIR.
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_shading_rate.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"

# shellcheck source=lib.sh
source "$here/lib.sh"
# shellcheck source=checks.sh
source "$here/checks.sh"

# A gather-heavy surface: occlusion from 16 rays per shading point.
cat >occ.sl <<'SL'
surface occ() {
    normal Nf = faceforward(normalize(N), I);
    float hits = 0;
    gather("illuminance", P, Nf, PI / 2, 16, "distribution", "cosine") {
        hits += 1;
    }
    Ci = Cs * (1 - hits / 16) * (0.2 + 0.8 * max(0, Nf . normalize(-I)));
    Oi = 1;
}
SL
"$bin/shader" occ.sl >/dev/null

# scene NAME SAMPLES RATE INTERP SURFACE [EXTRA]: spheres on a floor.
scene() {
    cat >"$1.rib" <<RIB
Format 96 72 1
PixelSamples $2 $2
ShadingRate $3
ShadingInterpolation "$4"
Projection "perspective" "fov" 40
${6:-}
Translate 0 0 5
Display "$1.exr" "openexr" "rgba"
WorldBegin
  LightSource "distantlight" 1 "intensity" 1 "from" [0 0 0] "to" [1 -1 1]
  LightSource "ambientlight" 2 "intensity" 0.1
  Attribute "visibility" "trace" 1
  Surface "$5"
  Color [0.8 0.3 0.2]
  Sphere 1 -1 1 360
  AttributeBegin
    Translate 1.2 0.5 0.5
    Sphere 0.5 -0.5 0.5 360
  AttributeEnd
  AttributeBegin
    Translate 0 -1 0
    Rotate 90 1 0 0
    Disk 0 4 360
  AttributeEnd
WorldEnd
RIB
}

# stat LOG WORD: the number before WORD in render's summary.
stat() { grep -oE "[0-9]+ $2" "$1" | head -1 | cut -d' ' -f1; }

# rms A B: the RMS difference of two images (oiiotool --diff).
# (oiiotool --diff exits 1 when the images differ at all.)
rms() { { oiiotool "$1" "$2" --diff 2>&1 || true; } | sed -n 's/.*RMS error = //p' | head -1; }
maxerr() {
    { oiiotool "$1" "$2" --diff 2>&1 || true; } |
        sed -n 's/.*Max error  = \([^ ]*\).*/\1/p' | head -1
}

# within VALUE LIMIT: VALUE <= LIMIT (floats).
within() { awk -v v="$1" -v l="$2" 'BEGIN { exit !(v <= l) }'; }

for interp in constant smooth; do
    for surface in plastic occ; do
        name="${interp}_${surface}"
        scene "$name" 4 1 "$interp" "$surface"
        "$bin/render" -progress 1 "$name.rib" >"$name.log" 2>&1 ||
            fail "$name: render failed: $(cat "$name.log")"
        cp "$name.exr" "$name.rate.exr"
        "$bin/render" -progress 1 -pixelshading 1 "$name.rib" >"$name.pixel.log" 2>&1 ||
            fail "$name: render -pixelshading 1 failed"
        cp "$name.exr" "$name.pixel.exr"
        # The documented tolerance against shading every sample.
        r="$(rms "$name.rate.exr" "$name.pixel.exr")"
        m="$(maxerr "$name.rate.exr" "$name.pixel.exr")"
        limit_rms=0.004
        [[ "$surface" == occ ]] && limit_rms=0.02 # (16 gather rays: their noise)
        within "$r" "$limit_rms" || fail "$name: RMS difference $r above $limit_rms"
        within "$m" 0.25 || fail "$name: largest difference $m above 0.25"
        # Far fewer shading points, and for the gather shader far fewer rays.
        p_rate="$(stat "$name.log" "shading points")"
        p_pixel="$(stat "$name.pixel.log" "shading points")"
        ((p_rate > 0 && p_rate * 4 < p_pixel)) ||
            fail "$name: $p_rate shading points at the ShadingRate against $p_pixel per sample"
        if [[ "$surface" == occ ]]; then
            s_rate="$(stat "$name.log" "secondary rays")"
            s_pixel="$(stat "$name.pixel.log" "secondary rays")"
            ((s_rate > 0 && s_rate * 4 < s_pixel)) ||
                fail "$name: $s_rate secondary rays at the ShadingRate against $s_pixel"
        fi
    done
done

# The summary line of -progress 1.
grep -qE "render: [0-9]+ camera rays, [0-9]+ shadow and occlusion rays, [0-9]+ secondary rays, [0-9]+ shading points" constant_occ.log ||
    fail "no ray and shading point counts in: $(cat constant_occ.log)"

# The shading points follow the ShadingRate, not the pixel samples.
scene s1 1 1 smooth plastic
scene s4 4 1 smooth plastic
scene r4 4 4 smooth plastic
for n in s1 s4 r4; do "$bin/render" -progress 1 "$n.rib" >"$n.log" 2>&1 || fail "$n failed"; done
p1="$(stat s1.log "shading points")"
p4="$(stat s4.log "shading points")"
pr="$(stat r4.log "shading points")"
((p4 * 2 < p1 * 3)) || fail "16 samples per pixel shade $p4 points against $p1 at one"
# (Cells are at most ShadingRate in area, a whole number per triangle edge.)
((pr * 3 < p4 * 2)) || fail "ShadingRate 4 shades $pr points against $p4 at ShadingRate 1"

# Any thread count, the same image.
"$bin/render" -p:1 -o one.exr constant_occ.rib >/dev/null 2>&1 || fail "render -p:1 failed"
"$bin/render" -p:2 -o two.exr constant_occ.rib >/dev/null 2>&1 || fail "render -p:2 failed"
oiiotool one.exr two.exr --diff --fail 0 >/dev/null 2>&1 ||
    fail "the image depends on the thread count"

# Motion blur: every sample is shaded at its own time.
scene mb 2 1 constant plastic 'Shutter 0 1'
sed -i 's/^  Sphere 1 -1 1 360$/  MotionBegin [0 1]\n    Translate 0 0 0\n    Translate 0.3 0 0\n  MotionEnd\n  Sphere 1 -1 1 360/' mb.rib
"$bin/render" -progress 1 mb.rib >mb.log 2>&1 || fail "motion blur render failed: $(cat mb.log)"
"$bin/render" -progress 1 -pixelshading 1 -o mb_pixel.exr mb.rib >mb_pixel.log 2>&1 ||
    fail "motion blur -pixelshading 1 failed"
[[ "$(stat mb.log "shading points")" == "$(stat mb_pixel.log "shading points")" ]] ||
    fail "motion blur: shading points differ from shading every sample"

expect_usage() {
    run "$bin/render" "$@" constant_occ.rib
    expect_rc 2 "render $*"
}
expect_usage -pixelshading 2
expect_usage -pixelshading

finish_checks shading_rate
