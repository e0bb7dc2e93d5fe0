#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# CLI test of displacement shaders: a Displace-style shader (noise along N,
# N = calculatenormal(P)) compiled on demand from the RIB's folder, through
# ptbake (the baked points move off the sphere) and render (exit 0, an image);
# a displacement beyond the displacementbound warns; a missing displacement
# shader is an error (exit 1) naming it.
# Needs SSS_BIN_DIR.
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
ptinfo="$bin/ptinfo"
for tool in "$bin/render" "$bin/ptbake" "$ptinfo"; do
    [[ -x "$tool" ]] || { echo "FAIL: missing executable $tool" >&2; exit 1; }
done
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_displacement.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"

# shellcheck source=lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
# shellcheck source=checks.sh
source "$(dirname "${BASH_SOURCE[0]}")/checks.sh"

# Bumps of noise along the normal, as RenderMan's Displace shaders do.
cat > bumpy.sl <<'SL'
displacement bumpy(float Km = 0.1; float frequency = 4;)
{
    point Po = transform("object", P);
    float height = Km * (noise(frequency * Po) - 0.5);
    P += height * normalize(N);
    N = calculatenormal(P);
}
SL
cat > bake.rib <<'RIB'
Format 64 48 1
Projection "perspective" "fov" 35
Translate 0 0 6
WorldBegin
  LightSource "distantlight" 1 "from" [0 1 -1] "to" [0 0 0]
  AttributeBegin
    Attribute "displacementbound" "sphere" [0.05]
    Displacement "bumpy" "float Km" [0.1]
    Surface "bake_radiance_t" "string filename" ["bumpy.ptc"]
    Sphere 1 -1 1 360
  AttributeEnd
WorldEnd
RIB
run "$bin/ptbake" -spacing 0.05 bake.rib
if expect_rc 0 "ptbake with a displacement shader"; then
    has_channel bumpy.ptc "float _area" || fail "bumpy.ptc has no float _area"
    grep -q "displacementbound" <<<"$err$out" &&
        fail "a displacement within its bound warned: $err"
    box="$("$ptinfo" bumpy.ptc | grep "^bbox" || true)"
    # The same bake without the displacement: the points left the sphere.
    sed '/Displacement/d' bake.rib > plain.rib
    run "$bin/ptbake" -spacing 0.05 -o plain.ptc plain.rib
    plain_box="$("$ptinfo" plain.ptc | grep "^bbox" || true)"
    [[ -n "$box" && -n "$plain_box" ]] || fail "ptinfo gives no bounding box"
    [[ "$box" != "$plain_box" ]] || fail "the baked points did not move: $box"
fi

cat > scene.rib <<'RIB'
Format 64 48 1
Projection "perspective" "fov" 35
Display "bumpy.exr" "openexr" "rgba"
Translate 0 0 6
WorldBegin
  LightSource "distantlight" 1 "from" [0 1 -1] "to" [0 0 0]
  AttributeBegin
    Attribute "displacementbound" "sphere" [0.01]
    Displacement "bumpy" "float Km" [0.4]
    Surface "matte"
    Sphere 1 -1 1 360
  AttributeEnd
WorldEnd
RIB
run "$bin/render" scene.rib
if expect_rc 0 "render with a displacement shader"; then
    [[ -s bumpy.exr ]] || fail "render wrote no bumpy.exr"
    grep -q "displacementbound" <<<"$err$out" ||
        fail "a displacement beyond its bound did not warn: $err"
fi

sed 's/Displacement "bumpy"/Displacement "nosuchshader"/' scene.rib > missing.rib
run "$bin/render" missing.rib
if expect_rc 1 "render with a missing displacement shader"; then
    grep -q "nosuchshader" <<<"$err" || fail "the error does not name the shader: $err"
fi
sed 's/Displacement "bumpy"/Displacement "nosuchshader"/' bake.rib > missing_bake.rib
run "$bin/ptbake" -spacing 0.05 missing_bake.rib
if expect_rc 1 "ptbake with a missing displacement shader"; then
    grep -q "Displacement \"nosuchshader\"" <<<"$err" ||
        fail "the error does not name the Displacement call: $err"
fi

finish_checks displacement
