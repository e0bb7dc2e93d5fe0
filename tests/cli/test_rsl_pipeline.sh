#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# CLI test of RSL shaders in the pipeline: a user's own bake shader (any
# name, compiled on demand from the RIB's folder), a surface shader whose
# output variables become AOVs, a compiled .slo found through
# Option "searchpath", the standard shaders (paintedplastic with a texture
# map, pixel for texel), and missing shaders as errors.
# Needs SSS_BIN_DIR.
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
render="$bin/render"
ptinfo="$bin/ptinfo"
for tool in "$render" "$bin/ptbake" "$bin/shader" "$ptinfo"; do
    [[ -x "$tool" ]] || { echo "FAIL: missing executable $tool" >&2; exit 1; }
done
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_rsl.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"

# shellcheck source=lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
# shellcheck source=checks.sh
source "$(dirname "${BASH_SOURCE[0]}")/checks.sh"

# A bake shader named as the user likes, with a channel of its own.
cat > mybake.sl <<'SL'
surface mybake(string filename = ""; float gain = 2;)
{
    normal Nn = normalize(N);
    float a = area(P, "dicing");
    color irr = gain * (ambient() + diffuse(Nn));
    float height = ycomp(transform("world", P));
    bake3d(filename, "_area,_irr,_height", P, Nn, "interpolate", 1,
           "_area", a, "_irr", irr, "_height", height);
    Ci = irr;
    Oi = Os;
}
SL
cat > bake.rib <<'RIB'
Format 64 48 1
Projection "perspective" "fov" 35
Translate 0 0 6
WorldBegin
  LightSource "ambientlight" 1 "intensity" [0.5]
  AttributeBegin
    Surface "mybake" "string filename" ["mine.ptc"] "float gain" [3]
    Sphere 1 -1 1 360
  AttributeEnd
WorldEnd
RIB
run "$bin/ptbake" -spacing 0.1 bake.rib
if expect_rc 0 "ptbake with a user bake shader"; then
    has_channel mine.ptc "color _irr" || fail "mine.ptc has no color _irr"
    has_channel mine.ptc "float _height" || fail "mine.ptc has no float _height"
    has_channel mine.ptc "float _area" || fail "mine.ptc has no float _area"
    # _irr = gain * ambient = 3 * 0.5 everywhere.
    stats="$("$ptinfo" mine.ptc 2>/dev/null || true)"
    grep -A1 "color _irr" <<<"$stats" | grep -q "min 1.5  mean 1.5  max 1.5" ||
        fail "_irr is not 1.5 everywhere: $stats"
fi

# render on the bake RIB bakes too (bake3d runs in render, as in PRMan).
rm -f mine.ptc
run "$render" -progress 1 -res 32 24 bake.rib
if expect_rc 0 "render of a bake RIB"; then
    [[ -s mine.ptc ]] || fail "render of a bake RIB wrote no mine.ptc"
    grep -q "baked mine.ptc" <<<"$out" || fail "render does not report the baked file: $out"
    has_channel mine.ptc "color _irr" || fail "render's mine.ptc has no color _irr"
fi

# A surface shader with output variables, written as AOVs by Display modes.
cat > glow.sl <<'SL'
surface glow(color tint = 1;
             output varying color Cdif = 0;
             output varying float height = 0;)
{
    normal Nf = faceforward(normalize(N), I);
    Cdif = tint * diffuse(Nf);
    height = ycomp(transform("world", P));
    Oi = Os;
    Ci = Os * Cs * Cdif;
}
SL
run "$bin/shader" -o glow.slo glow.sl
expect_rc 0 "shader glow.sl"
mkdir -p lib && mv glow.slo lib/
cat > scene.rib <<'RIB'
Option "searchpath" "shader" ["lib:&"]
Format 64 48 1
PixelSamples 1 1
Projection "perspective" "fov" 35
Display "glow.exr" "openexr" "rgba"
Display "+glow_dif.exr" "openexr" "Cdif"
Display "+glow_height.exr" "openexr" "height"
Translate 0 0 6
WorldBegin
  LightSource "distantlight" 1 "from" [0 0 0] "to" [0 0 1] "intensity" [1]
  AttributeBegin
    Surface "glow" "color tint" [0.5 1 0.25]
    Sphere 1 -1 1 360
  AttributeEnd
WorldEnd
RIB
run "$render" scene.rib
if expect_rc 0 "render with a user surface shader and AOVs"; then
    info="$(oiiotool --info -v glow.exr 2>&1)"
    grep -q "Cdif.R" <<<"$info" || fail "glow.exr has no Cdif layer: $info"
    grep -q "height" <<<"$info" || fail "glow.exr has no height channel: $info"
    [[ -f glow_dif.exr ]] || fail "glow_dif.exr not written"
    # The centre pixel faces the light: Cdif = tint.
    px="$(oiiotool glow_dif.exr --cut 1x1+32+24 --printstats 2>/dev/null | sed -n 's/.*Stats Max: *//p' | head -1)"
    read -r r g b _ <<<"$px"
    awk -v r="$r" -v g="$g" -v b="$b" 'BEGIN { exit !(r > 0.45 && r < 0.52 && g > 0.9 && g < 1.02 && b > 0.2 && b < 0.27) }' ||
        fail "centre Cdif is not the tint: $px"
fi

# A texture on a square that fills the screen, pixel for texel: paintedplastic
# lit by an ambient light of intensity 1 (Ka 1 only) shows the map's colours.
oiiotool --pattern checker:width=16:height=16:color1=1,0.2,0:color2=0,0.4,1 32x32 3 \
    -d float -o checker.exr
cat > textured.rib <<'RIB'
Format 32 32 1
PixelSamples 2 2
Projection "orthographic"
ScreenWindow -1 1 -1 1
Display "textured.exr" "openexr" "rgba"
Translate 0 0 5
WorldBegin
  LightSource "ambientlight" 1 "intensity" [1]
  Surface "paintedplastic" "float Ka" [1] "float Kd" [0] "float Ks" [0]
      "string texturename" ["checker.exr"]
  Polygon "P" [-1 -1 0  1 -1 0  1 1 0  -1 1 0] "st" [0 1  1 1  1 0  0 0]
WorldEnd
RIB
run "$render" textured.rib
if expect_rc 0 "render with a texture map"; then
    pixel() { oiiotool "$1" --ch R,G,B --cut "1x1+$2+$3" --printstats 2>/dev/null |
        sed -n 's/.*Stats Avg: *//p' | head -1; }
    for xy in "8 8" "24 8" "8 24" "24 24"; do
        read -r x y <<<"$xy"
        want="$(pixel checker.exr "$x" "$y")" got="$(pixel textured.exr "$x" "$y")"
        awk -v w="$want" -v g="$got" 'BEGIN { n = split(w, a, " "); split(g, b, " ");
            if (n < 3) exit 1; for (i = 1; i <= 3; ++i) if ((a[i] - b[i])^2 > 1e-4) exit 1 }' ||
            fail "textured pixel ($x, $y) is $got, the map's texel is $want"
    done
fi

# A shader nobody has: an error naming the shader and the search path.
sed 's/Surface "glow"/Surface "nosuchshader"/' scene.rib > missing.rib
run "$render" missing.rib
if expect_rc 1 "render with a missing shader"; then
    grep -q "nosuchshader" <<<"$err" || fail "the error does not name the shader: $err"
    grep -q "search path" <<<"$err" || fail "the error does not give the search path: $err"
    [[ $(wc -l <<<"$err") -le 3 ]] || fail "the error spans many lines: $err"
fi

# A shader that does not compile: file:line:column in the error, exit 1.
cat > broken.sl <<'SL'
surface broken()
{
    Ci = 1 +;
}
SL
sed 's/Surface "glow"/Surface "broken"/' scene.rib > broken.rib
run "$render" broken.rib
if expect_rc 1 "render with a shader that does not compile"; then
    grep -q "broken.sl:3:" <<<"$err" || fail "the error has no file:line: $err"
fi

finish_checks rsl_pipeline
