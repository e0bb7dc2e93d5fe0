#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# CLI test of the ray-traced shadeops on bad input (issue 14): a missing or
# corrupt environment map is an error naming the file (ptbake and render, no
# output written); two mirrors that trace each other with no useful depth
# limit finish with a warning and a finite image; a hit shader that makes NaN
# gives finite results and says so; Option "trace" "maxdepth" 0 turns the
# rays off (trace() gives 0: the mirror shows nothing).
# Needs SSS_BIN_DIR (the folder with ptbake and render) and oiiotool.
#
# Every check runs; failures are listed and the script exits 1 at the end.
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
for tool in ptbake render; do
    [[ -x "$bin/$tool" ]] || { echo "FAIL: missing executable $bin/$tool" >&2; exit 1; }
done
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_raytrace.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"

# shellcheck source=lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
# shellcheck source=checks.sh
source "$(dirname "${BASH_SOURCE[0]}")/checks.sh"

cat > envbake.sl <<'SL'
surface envbake(string filename = ""; string envmap = "") {
    color c = indirectdiffuse(P, normalize(N), 16, "environmentmap", envmap);
    bake3d(filename, "c", P, N, "c", c);
    Ci = c;
}
SL
# mirror: what a ray along the reflection sees, plus a little of its own.
cat > mirror.sl <<'SL'
surface mirror(float samples = 1) {
    normal Nf = faceforward(normalize(N), I);
    vector R = reflect(normalize(I), Nf);
    color c = 0;
    gather("illuminance", P, R, 0.3, samples, "surface:Ci", c) {
        Ci += 0.9 * c / samples;
    }
    Ci += Cs * 0.1;
}
SL
cat > nan.sl <<'SL'
surface nan() {
    float z = 0;
    Ci = color(0 / z, 1, log(z - 1));
}
SL

bake_scene() { # NAME ENVMAP
    cat > "$1" <<RIB
Format 64 64 1
Projection "perspective" "fov" 40
Translate 0 0 5
WorldBegin
Surface "envbake" "string filename" ["out.ptc"] "string envmap" ["$2"]
Sphere 1 -1 1 360
WorldEnd
RIB
}

# Missing and corrupt maps: an error naming the file, nothing written.
bake_scene missing.rib nothere.exr
run "$bin/ptbake" -spacing 0.2 missing.rib
if expect_rc 1 "ptbake, missing environment map"; then
    # One line that names the file (a sanitizer build may add its report after it).
    first="$(head -n 1 <<<"$err")"
    [[ "$first" == "ptbake ERROR: "*"nothere.exr: cannot open: No such file or directory"* ]] ||
        fail "missing map: $err"
fi
[[ ! -e out.ptc ]] || fail "a cloud was written despite the missing map"
echo "not an image" > corrupt.exr
bake_scene corrupt.rib corrupt.exr
run "$bin/ptbake" -spacing 0.2 corrupt.rib
if expect_rc 1 "ptbake, corrupt environment map"; then
    [[ "$err" == "ptbake ERROR: "*"corrupt.exr"* ]] || fail "corrupt map: $err"
fi
[[ ! -e out.ptc ]] || fail "a cloud was written despite the corrupt map"

# Two parallel mirrors (the camera sees the far one through the near one),
# each gathering 8 rays per hit, allowed 64 levels: the ray budget stops the
# tree, with a warning, and the image is finite.
mirrors() { # NAME OPTIONS SAMPLES [SIZE]
    cat > "$1" <<RIB
Format ${4:-32} ${4:-32} 1
PixelSamples 1 1
$2
Projection "perspective" "fov" 30
Display "$1.exr" "openexr" "rgba"
Translate 0 0 6
WorldBegin
Attribute "trace" "maxspeculardepth" [64]
Color [0.2 0.5 1]
Surface "mirror" "float samples" [$3]
AttributeBegin
Translate 0 0 1
Polygon "P" [-50 -50 0  50 -50 0  50 50 0  -50 50 0]
AttributeEnd
AttributeBegin
Attribute "visibility" "camera" [0]
Translate 0 0 -1
Polygon "P" [-50 -50 0  50 -50 0  50 50 0  -50 50 0]
AttributeEnd
WorldEnd
RIB
}
mirrors deep.rib 'Option "trace" "maxdepth" [64]' 8 4
run timeout 120 "$bin/render" deep.rib
if expect_rc 0 "render, mirrors tracing each other 64 levels deep"; then
    [[ "$out$err" == *"deeper rays miss"* ]] || fail "runaway ray tree: no warning: $out $err"
    max="$(oiiotool deep.rib.exr --ch R,G,B --printstats 2>/dev/null | sed -n 's/^ *Stats Max: *//p')"
    [[ "$max" =~ ^[0-9.]+\ [0-9.]+\ [0-9.]+ ]] || fail "mirrors: unreadable or non-finite image: $max"
fi

# maxdepth 0: no rays; the mirror shows only its own 0.1 Cs.
mirrors none.rib 'Option "trace" "maxdepth" [0]' 1
run "$bin/render" none.rib
if expect_rc 0 "render, maxdepth 0"; then
    b="$(oiiotool none.rib.exr --ch B --cut 8x8+12+12 --printstats 2>/dev/null | sed -n 's/^ *Stats Max: *//p' | sed 's/ *(float)//')"
    awk -v b="$b" 'BEGIN { exit !(b + 0 > 0.0999 && b + 0 < 0.1001) }' ||
        fail "maxdepth 0: the mirror should show only its own 0.1 Cs, got B max $b"
fi
mirrors one.rib 'Option "trace" "maxdepth" [1]' 1
run "$bin/render" one.rib
b1="$(oiiotool one.rib.exr --ch B --cut 8x8+12+12 --printstats 2>/dev/null | sed -n 's/^ *Stats Avg: *//p' | sed 's/ *(float)//')"
awk -v b="$b1" 'BEGIN { exit !(b + 0 > 0.15) }' ||
    fail "maxdepth 1: the mirror should reflect the other (0.1 + 0.9 * 0.1 blue), got $b1"

# A mirror reflecting a NaN-making surface: finite, with a note.
cat > nanscene.rib <<'RIB'
Format 32 32 1
PixelSamples 1 1
Projection "perspective" "fov" 30
Display "nanscene.exr" "openexr" "rgba"
Translate 0 0 6
WorldBegin
AttributeBegin
Surface "mirror"
Translate 0 0 1
Polygon "P" [-3 -3 0  3 -3 0  3 3 0  -3 3 0]
AttributeEnd
AttributeBegin
Attribute "visibility" "camera" [0]
Surface "nan"
Translate 0 0 -1
Polygon "P" [-3 -3 0  3 -3 0  3 3 0  -3 3 0]
AttributeEnd
WorldEnd
RIB
run "$bin/render" nanscene.rib
if expect_rc 0 "render, NaN at ray hits"; then
    [[ "$err" == *"NaN"* ]] || fail "NaN at hits: no warning: $err"
    stats="$(oiiotool nanscene.exr --ch R,G,B --printstats 2>/dev/null | sed -n 's/^ *Stats \(Min\|Max\): *//p')"
    [[ "$stats" != *nan* && "$stats" != *inf* ]] || fail "NaN at hits reached the image: $stats"
    g="$(oiiotool nanscene.exr --ch G --cut 8x8+12+12 --printstats 2>/dev/null | sed -n 's/^ *Stats Avg: *//p' | sed 's/ *(float)//')"
    awk -v g="$g" 'BEGIN { exit !(g + 0 > 0.5) }' ||
        fail "NaN at hits: the finite green (0.9) should still be reflected, got $g"
fi

finish_checks raytrace
