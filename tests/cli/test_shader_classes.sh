#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# RSL 2.0 shader classes through the real tools: `shader` compiles classes
# (surface, staged lighting, light, displacement and surface, co-shader),
# sloinfo lists them under the type they run as; render draws a lit sphere
# with a class surface shader exactly as with the classic shader it
# restates, lights it with a class light, calls a co-shader declared with
# `Shader`, and displaces it with a class's displacement method (exit 0, no
# warning or error line). Needs SSS_BIN_DIR (the build's bin folder).
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must point at the build bin folder}"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_shader_classes.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"
# shellcheck source=lib.sh
source "$here/lib.sh"
# shellcheck source=checks.sh
source "$here/checks.sh"

# Whether a tool's stderr has no warning or error line (the sanitizer build
# adds its own summaries, e.g. of suppressed leaks). Stricter than checks.sh's
# render_clean: the compiler's "warning:" lines count too.
quiet() { ! grep -qE "WARNING|ERROR|warning:|error:" <<<"$1"; }
render_clean() {
    run "$bin/render" "$@"
    [[ "$rc" == 0 ]] && quiet "$err" || fail "render $*: exit $rc, stderr: $err"
}
# chan FILE CHANNEL WHICH: oiiotool's Avg/Min/Max of one channel.
chan() {
    oiiotool "$1" --ch "$2" --printstats 2>/dev/null |
        sed -n "s/^ *Stats $3: *\([^ ]*\).*/\1/p" | head -1
}
# near GOT WANT TOL LABEL
near() {
    python3 -c "import sys; g = float('$1' or 'nan'); sys.exit(0 if abs(g - ($2)) <= $3 else 1)" ||
        fail "$4: got $1, expected $2 (within $3)"
}

cat >classic.sl <<'SL'
surface classic(float Kd = 0.8; color tint = color(1, 0.6, 0.3);) {
    normal Nf = faceforward(normalize(N), I);
    Oi = Os;
    Ci = Oi * Cs * tint * Kd * diffuse(Nf);
}
SL
cat >viaclass.sl <<'SL'
class viaclass(float Kd = 0.8; color tint = color(1, 0.6, 0.3);) {
    public void surface(output color Ci, Oi) {
        normal Nf = faceforward(normalize(N), I);
        Oi = Os;
        Ci = Oi * Cs * tint * Kd * diffuse(Nf);
    }
}
SL
cat >staged.sl <<'SL'
class staged(float Kd = 0.8; color tint = color(1, 0.6, 0.3); string layer = "";
             output varying color pattern = 0;) {
    varying color m_pattern;
    uniform shader m_layer;
    public void begin() { m_layer = getshader(layer); }
    public void opacity(output color Oi) { Oi = Os; }
    public void prelighting(output color Ci, Oi) {
        m_pattern = Cs * tint;
        if (m_layer != null) m_pattern *= m_layer->gain();
        pattern = m_pattern;
    }
    public void lighting(output color Ci, Oi) {
        normal Nf = faceforward(normalize(N), I);
        shader lights[] = getlights();
        uniform float i, n = arraylength(lights);
        color sum = 0;
        for (i = 0; i < n; i += 1) {
            vector L;
            color Cl;
            lights[i]->light(L, Cl);
            sum += Cl * max(0, normalize(-L) . Nf);
        }
        Ci = m_pattern * Kd * sum;
    }
    public void postlighting(output color Ci, Oi) { Ci *= Oi; }
}
SL
cat >gainer.sl <<'SL'
class gainer(float amount = 0.5;) {
    public float gain() { return amount; }
}
SL
cat >classlight.sl <<'SL'
class classlight(float intensity = 1; point from = point "shader" (0, 0, 0);
                 point to = point "shader" (0, 0, 1);) {
    public void light(output vector L; output color Cl) {
        solar(to - from, 0) { Cl = intensity; }
    }
}
SL
cat >bumpy.sl <<'SL'
class bumpy(float Km = 0.3;) {
    public void displacement(output point P; output normal N) {
        P += Km * normalize(N);
        N = calculatenormal(P);
    }
    public void surface(output color Ci, Oi) { Oi = Os; Ci = Oi * Cs * diffuse(normalize(N)); }
}
SL

# --- compiling and sloinfo ------------------------------------------------------
for f in classic viaclass staged gainer classlight bumpy; do
    run "$bin/shader" "$f.sl"
    expect_rc 0 "shader $f.sl" || continue
    quiet "$err" || fail "shader $f.sl: stderr: $err"
    [[ -f "$f.slo" ]] || fail "shader $f.sl wrote no $f.slo"
done
run "$bin/sloinfo" viaclass.slo staged.slo gainer.slo classlight.slo bumpy.slo
expect_rc 0 "sloinfo"
for line in 'surface "viaclass"' 'surface "staged"' 'shader "gainer"' 'light "classlight"' \
    'surface "bumpy"' '    "tint" "parameter uniform color"' \
    '    "pattern" "output parameter varying color"' '    "amount" "parameter uniform float"'; do
    grep -Fqx -- "$line" <<<"$out" || fail "sloinfo: no line '$line' in: $out"
done
grep -q "m_pattern" <<<"$out" && fail "sloinfo lists a member variable: $out"
run "$bin/sloinfo" -json 1 staged.slo
grep -Fq '"methods": ["begin", "opacity", "prelighting", "lighting", "postlighting"]' <<<"$out" ||
    fail "sloinfo -json: methods: $out"

# --- rendering ------------------------------------------------------------------
# scene LIGHTS BEFORE SURFACE ATTRIBUTES: a sphere of radius 1 six units in front
# of the eye in a 64 x 48 float EXR.
scene() {
    cat <<RIB
Format 64 48 1
PixelSamples 2 2
PixelFilter "box" 1 1
Projection "perspective" "fov" 30
Display "out.exr" "openexr" "rgba" "string type" ["float"]
Translate 0 0 6
WorldBegin
  $1
  AttributeBegin
    Color [0.9 0.8 0.7]
    $2
    Surface $3
    $4
    Sphere 1 -1 1 360
  AttributeEnd
WorldEnd
RIB
}
distant='LightSource "distantlight" 1 "from" [-1 1 -5] "to" [0 0 0] "intensity" 1'

scene "$distant" "" '"classic"' "" >classic.rib
render_clean -o classic.exr classic.rib
scene "$distant" "" '"viaclass"' "" >viaclass.rib
render_clean -o viaclass.exr viaclass.rib
ref_R="$(chan classic.exr R Avg)"
python3 -c "import sys; sys.exit(0 if 0.02 < float('$ref_R' or 0) < 1 else 1)" ||
    fail "classic: the sphere is not lit (R $ref_R)"
for c in R G B A; do
    near "$(chan viaclass.exr $c Avg)" "$(chan classic.exr $c Avg)" 1e-6 \
        "class surface() against the classic shader, channel $c"
done

# Staged lighting through getlights() and light(): the same image.
scene "$distant" "" '"staged"' "" >staged.rib
render_clean -o staged.exr staged.rib
for c in R G B; do
    near "$(chan staged.exr $c Avg)" "$(chan classic.exr $c Avg)" 1e-5 \
        "prelighting/lighting/postlighting against classic, channel $c"
done

# A co-shader from the RIB halves the pattern.
scene "$distant" 'Shader "gainer" "half" "float amount" [0.5]' '"staged" "string layer" ["half"]' \
    "" >coshader.rib
render_clean -o coshader.exr coshader.rib
near "$(chan coshader.exr R Avg)" "0.5 * $(chan classic.exr R Avg)" 1e-5 \
    "the co-shader's gain() halves the colour"

# A class light as the distant light.
classlight='LightSource "classlight" 1 "from" [-1 1 -5] "to" [0 0 0] "intensity" 1'
scene "$classlight" "" '"classic"' "" >classlight.rib
render_clean -o classlight.exr classlight.rib
for c in R G B; do
    near "$(chan classlight.exr $c Avg)" "$(chan classic.exr $c Avg)" 1e-5 \
        "a class light against distantlight, channel $c"
done

# Displacement by the surface class's own method: the sphere grows.
scene "$distant" "" '"bumpy"' 'Attribute "displacementbound" "sphere" [0.3]' >bumpy.rib
render_clean -o bumpy.exr bumpy.rib
scene "$distant" "" '"bumpy" "float Km" [0]' 'Attribute "displacementbound" "sphere" [0.3]' \
    >flat.rib
render_clean -o flat.exr flat.rib
python3 - "$(chan bumpy.exr A Avg)" "$(chan flat.exr A Avg)" <<'PY' ||
import sys
bumpy, flat = float(sys.argv[1]), float(sys.argv[2])
# Radius 1.3 instead of 1: about 1.69 times the covered area.
sys.exit(0 if 1.5 < bumpy / flat < 1.9 else 1)
PY
    fail "the displacement method does not grow the sphere (coverage $(chan bumpy.exr A Avg) vs $(chan flat.exr A Avg))"

# A co-shader is not a surface: an error naming the call and what to do.
scene "$distant" "" '"gainer"' "" >wrong.rib
run "$bin/render" -o wrong.exr wrong.rib
expect_rc 1 "Surface naming a co-shader class" &&
    { grep -q 'wrong.rib:[0-9]*: Surface "gainer": "gainer" is a co-shader' <<<"$err" ||
        fail "Surface \"gainer\": unexpected message: $err"; }

finish_checks "shader classes"
