#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# Procedural "DynamicLoad" through render and ptbake: a DSO written in C
# against sss/scene/ri.h alone (tests/scene/procedural_dso.c, built by the
# tests) and one compiled here the way a user compiles theirs, found along the
# procedural search path without its ".so"; the frame it makes renders and
# bakes with exit 0 and no warning; a DSO that fails, or a file that is not
# one, ends with one ERROR line naming it. Also the compiler options of
# PRMan's `shader` that scripts pass (-C, -nosd, -o -src/-shader). Needs
# SSS_BIN_DIR and SSS_TEST_PROCEDURAL (the test DSO).
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must point at the build bin folder}"
dso="${SSS_TEST_PROCEDURAL:?SSS_TEST_PROCEDURAL must name the test DSO}"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
include="$(cd "$here/../../include/sss/scene" && pwd)"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_dynamic_load.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"
# shellcheck source=lib.sh
source "$here/lib.sh"
# shellcheck source=checks.sh
source "$here/checks.sh"
mean_alpha() {
    oiiotool "$1" --ch A --printstats 2>/dev/null | sed -n 's/.*Stats Avg: *\([^ ]*\).*/\1/p'
}
within() { python3 -c "import sys; v = float('$1' or 'nan'); sys.exit(0 if $2 <= v <= $3 else 1)"; }

scene() { # scene PROCEDURAL-LINE...
    cat <<'RIB'
Format 64 64 1
Projection "perspective" "fov" 40
Translate 0 0 8
WorldBegin
  LightSource "distantlight" 1 "from" [0 0 -1] "to" [0 0 0]
  Surface "matte"
RIB
    printf '  %s\n' "$@"
    echo 'WorldEnd'
}

# --- a recursive procedural of the DSO's own: the frame its RIB makes ------------
scene "Procedural \"DynamicLoad\" [\"$dso\" \"tree 1\"] [-3 3 -3 3 -3 3]" >tree.rib
render_clean -o tree.exr tree.rib
# The same three spheres written out (procedural_dso.c's tree_level).
child() {
    echo "TransformBegin Translate $1 0 -1 Scale 0.5 0.5 0.5 AttributeBegin"
    echo "Sphere 0.5 -0.5 0.5 360 AttributeEnd TransformEnd"
}
scene 'AttributeBegin Sphere 0.5 -0.5 0.5 360' "$(child -1.5)" "$(child 1.5)" \
    'AttributeEnd' >tree_rib.rib
render_clean -o tree_rib.exr tree_rib.rib
oiiotool tree.exr tree_rib.exr --diff --fail 1e-6 >/dev/null 2>&1 ||
    fail "the procedural's tree differs from the same spheres in RIB"
a="$(mean_alpha tree.exr)"
within "$a" 0.01 0.9 || fail "tree.exr covers $a of the frame"
scene "Procedural \"DynamicLoad\" [\"$dso\" \"tree 4\"] [-3 3 -3 3 -3 3]" >tree4.rib
render_clean -o tree4.exr tree4.rib
stats="$(oiiotool tree4.exr --printstats 2>&1)"
[[ "$stats" != *nan* && "$stats" != *inf* ]] || fail "tree4.exr has NaN or inf"

# --- a DSO compiled here as a user would, found along the search path ----------
mkdir -p procs
cat >procs/disk.c <<'C'
#include <stdlib.h>
#include <ri.h>
RtPointer ConvertParameters(RtString s) { float* r = malloc(sizeof(float)); *r = atof(s); return r; }
RtVoid Subdivide(RtPointer data, RtFloat detail) {
    RtColor red = {1, 0, 0};
    RiColor(red);
    RiDisk(0.0f, *(float*)data, 360.0f, RI_NULL);
}
RtVoid Free(RtPointer data) { free(data); }
C
if command -v cc >/dev/null; then
    cc -shared -fPIC -I"$include" -o procs/disk.so procs/disk.c
    scene 'Option "searchpath" "procedural" ["procs"]' \
        'Procedural "DynamicLoad" ["disk" "1.5"] [-2 2 -2 2 -1 1]' >disk.rib
    render_clean -o disk.exr disk.rib
    # A disk of radius 1.5 at distance 8 with a 40 degree view: pi 1.5^2 of
    # (2 * 8 tan 20)^2 = 0.21 of the frame.
    within "$(mean_alpha disk.exr)" 0.18 0.24 || fail "disk.exr alpha $(mean_alpha disk.exr)"
    red="$(oiiotool disk.exr --crop 32,32,33,33 --printstats 2>/dev/null |
        sed -n 's/.*Stats Avg: *\([^ ]*\) \([^ ]*\).*/\1 \2/p')"
    python3 -c "import sys; r, g = map(float, '$red'.split()); sys.exit(0 if r > 0.05 and g < 1e-6 else 1)" ||
        fail "disk centre is not red: $red"
else
    echo "no C compiler: the user-built DSO is not tried"
fi

# --- ptbake bakes what the procedural makes ------------------------------------
{
    cat <<'RIB'
Format 64 64 1
Projection "perspective" "fov" 40
Translate 0 0 8
WorldBegin
  Attribute "cull" "hidden" 0 "backfacing" 0
  Surface "bake_constant" "string filename" "tree.ptc"
RIB
    echo "  Procedural \"DynamicLoad\" [\"$dso\" \"tree 1\"] [-3 3 -3 3 -3 3]"
    echo 'WorldEnd'
} >bake.rib
run "$bin/ptbake" bake.rib
[[ "$rc" == 0 ]] && no_warnings "$err" || fail "ptbake: exit $rc, stderr: $err"
n="$("$bin/ptinfo" tree.ptc 2>/dev/null | sed -n 's/^points: *//p')"
[[ "${n:-0}" -gt 100 ]] || fail "tree.ptc has ${n:-no} points"

# --- errors: one ERROR line naming the DSO and the call ------------------------
scene "Procedural \"DynamicLoad\" [\"$dso\" \"undeclared\"] [-1 1 -1 1 -1 1]" >bad.rib
run "$bin/render" -o bad.exr bad.rib
expect_rc 1 "undeclared parameter" &&
    { [[ "$(grep -c ERROR <<<"$err")" == 1 && "$err" == *"testproc.so (DynamicLoad at bad.rib:7)"* &&
        "$err" == *notdeclared* ]] || fail "undeclared: $err"; }
[[ ! -e bad.exr ]] || fail "bad.exr written"
printf 'not a shared object\n' >fake.so
scene 'Procedural "DynamicLoad" ["./fake.so" ""] [-1 1 -1 1 -1 1]' >fake.rib
run "$bin/render" -o fake.exr fake.rib
expect_rc 1 "not a DSO" && { [[ "$err" == *"cannot load"*fake.so* ]] || fail "fake: $err"; }

finish_checks "dynamic load"
