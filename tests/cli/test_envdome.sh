#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# CLI test of envdome: help, the procedural sky, bad probes (exit 1, no
# output), bad options (exit 2), and a dome the renderer reads: a sphere lit
# by a sky whose sun is at +x is brighter on its +x side.
# Needs SSS_BIN_DIR (the folder with envdome and render).
#
# Every check runs; failures are listed and the script exits 1 at the end.
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
envdome="$bin/envdome"
render="$bin/render"
for tool in "$envdome" "$render"; do
    [[ -x "$tool" ]] || { echo "FAIL: missing executable $tool" >&2; exit 1; }
done
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_envdome.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"

# shellcheck source=lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
# shellcheck source=checks.sh
source "$(dirname "${BASH_SOURCE[0]}")/checks.sh"

run "$envdome" --help
expect_rc 0 --help && [[ "$out" == *"usage: envdome"* && "$out" == *"median cut"* ]] ||
    fail "--help lacks the usage"
run "$envdome" --version
expect_rc 0 --version && [[ "$out" == "envdome (sss) "* ]] || fail "--version: $out"

# The procedural sky: sun 30 degrees up towards +x.
run "$envdome" -sky 128 64 -sun 30 90 sky.exr
if expect_rc 0 "-sky"; then
    info="$(oiiotool --info sky.exr 2>&1)"
    grep -Eq '128 x +64' <<<"$info" || fail "sky.exr is not 128 x 64: $info"
    # The sun pixel: s = 0.25 (+x), t = 0.5 - 30/180 -> row 21.
    sun="$(oiiotool sky.exr --cut 3x3+31+20 --printstats 2>/dev/null | sed -n 's/.*Stats Max: *//p' | head -1)"
    awk -v m="$sun" 'BEGIN { split(m, a, " "); exit !(a[1] > 100) }' || fail "no sun at +x, 30 degrees up: max $sun"
fi
run "$envdome" -sky 128 64 sky2.exr
[[ "$rc" == 0 ]] && cmp -s <(oiiotool sky.exr --printstats 2>&1 | grep Stats) \
    <(oiiotool sky2.exr --printstats 2>&1 | grep Stats) && fail "-sun made no difference"
run "$envdome" -sky 128 60 bad.exr
expect_rc 2 "-sky 128 60" && [[ "$err" == "envdome ERROR: "*"twice"* ]] || fail "-sky W != 2H: $err"
[[ ! -e bad.exr ]] || fail "-sky with a bad size wrote bad.exr"

# Bad probes: exit 1, one clear line, no output.
run "$envdome" missing.exr dome.rib
expect_rc 1 "missing probe" && [[ "$err" == "envdome ERROR: "*"missing.exr"* ]] || fail "missing probe: $err"
[[ ! -e dome.rib ]] || fail "a missing probe left dome.rib"
head -c 300 /dev/urandom > corrupt.exr
printf 'v/1\x01garbage' | cat - corrupt.exr > corrupt2.exr
run "$envdome" corrupt2.exr dome.rib
expect_rc 1 "corrupt probe" && [[ "$err" == "envdome ERROR: "*"corrupt2.exr"* ]] || fail "corrupt probe: $err"
[[ ! -e dome.rib ]] || fail "a corrupt probe left dome.rib"
oiiotool --pattern constant:color=1,1,1 32x32 3 -d float -o square.exr
run "$envdome" square.exr dome.rib
expect_rc 1 "square probe" && [[ "$err" == *"not a lat-long"* ]] || fail "square probe: $err"
[[ ! -e dome.rib ]] || fail "a square probe left dome.rib"
echo keep > keep.rib
run "$envdome" missing.exr keep.rib
[[ "$(cat keep.rib)" == keep ]] || fail "a failed run changed an existing output"

# Bad command lines: exit 2.
run "$envdome" -n 3 sky.exr dome.rib
expect_rc 2 "-n 3" && [[ "$err" == *"power of two"* ]] || fail "-n 3: $err"
run "$envdome" -n 0 sky.exr dome.rib
expect_rc 2 "-n 0" || true
run "$envdome" -bogus sky.exr dome.rib
expect_rc 2 "unknown option" || true
run "$envdome" sky.exr
expect_rc 2 "no output" || true
[[ ! -e dome.rib ]] || fail "a bad command line left dome.rib"

# A good dome: 32 lights, a header, the lights' colours sum to the integral / pi.
run "$envdome" -n 32 -progress 1 sky.exr dome.rib
if expect_rc 0 "envdome sky.exr dome.rib"; then
    n="$(grep -c '^LightSource "distantlight" "envdome' dome.rib || true)"
    [[ "$n" == 32 ]] || fail "dome.rib has $n lights, not 32"
    grep -q '^## probe: sky.exr' dome.rib || fail "dome.rib lacks the probe header"
    [[ "$(grep ALF_PROGRESS stdout | tail -n 1)" == "ALF_PROGRESS 100%" ]] || fail "no ALF_PROGRESS 100%"
    awk '/^## integral/ { want = $(NF - 2) }
         /^LightSource/ { for (i = 1; i <= NF; ++i) if ($i == "\"lightcolor\"") { v = $(i + 1); sub(/\[/, "", v); sum += v } }
         END { pi = 3.14159265358979; if (want <= 0 || (sum * pi / want - 1)^2 > 1e-8) { print sum * pi, want; exit 1 } }' dome.rib ||
        fail "the lights' red does not sum to the probe's integral / pi"
    ls -a | grep -q '\.tmp' && fail "a temporary was left behind"
fi
run "$envdome" -n 8 -shadows 1 -intensity 2 -o shadowed.rib sky.exr
if expect_rc 0 "-shadows 1 -o"; then
    [[ "$(grep -c '^LightSource "distantlight_rts".*"intensity" \[2\]' shadowed.rib)" == 8 ]] ||
        fail "-shadows 1 -intensity 2: not 8 distantlight_rts lights of intensity 2"
fi

# The renderer reads the dome: the sun is at +x (world), which is the
# image's right; the lit side is brighter, and the image is not black.
cat > scene.rib <<'RIB'
Format 64 64 1
PixelSamples 2 2
Projection "perspective" "fov" 30
Display "ball.exr" "openexr" "rgba"
Translate 0 0 5
WorldBegin
  ReadArchive "dome.rib"
  Surface "matte" "float Ka" [0] "float Kd" [1]
  Sphere 1 -1 1 360
WorldEnd
RIB
run "$render" scene.rib
if expect_rc 0 "render with the dome"; then
    mean() { oiiotool ball.exr --ch R,G,B --cut "$1" --printstats 2>/dev/null |
        sed -n 's/.*Stats Avg: *//p' | head -1 | awk '{ print ($1 + $2 + $3) / 3 }'; }
    left="$(mean 6x6+12+29)" right="$(mean 6x6+46+29)"
    awk -v l="$left" -v r="$right" 'BEGIN { exit !(l > 0.05 && r > 1.3 * l) }' ||
        fail "sphere under the dome: left $left, right $right (the sun is at +x, on the right)"
    # The sky is above (+y, the image's top), the dark ground below.
    top="$(mean 4x4+30+10)" bottom="$(mean 4x4+30+52)"
    awk -v t="$top" -v b="$bottom" 'BEGIN { exit !(b > 0.01 && t > 3 * b) }' ||
        fail "sphere under the dome: top $top, bottom $bottom (the sky is above)"
fi
# Rotated by 180 degrees the sun is at -x: the left is the brighter side.
run "$envdome" -n 32 -rotate 180 sky.exr dome.rib
run "$render" scene.rib
if expect_rc 0 "render with the rotated dome"; then
    left="$(mean 6x6+12+29)" right="$(mean 6x6+46+29)"
    awk -v l="$left" -v r="$right" 'BEGIN { exit !(r > 0.05 && l > 1.3 * r) }' ||
        fail "rotated dome: left $left, right $right (the sun is now on the left)"
fi

finish_checks envdome
