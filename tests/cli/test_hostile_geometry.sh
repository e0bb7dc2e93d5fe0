#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# CLI test of hostile geometry, cameras and rays (issue 15): render and ptbake
# on the inputs of tests/data/hostile/geometry and on generated ones. Each
# refused input ends within seconds with exit 1, a first ERROR line naming
# the RIB (or OBJ) file and line and what is wrong, and nothing written:
#   - cameras whose rays would start beyond the coordinate range (+-1e18) or
#     that have no rays (Embree aborted on them: Assertion 'ray.valid()');
#   - geometry beyond the coordinate range (huge transforms, "Pw" with a tiny w);
#   - the vertex and micropolygon limits (SSS_LIMIT_*), per primitive and scene;
#   - a scene that needs more memory than the process may use (SSS_MEMORY_LIMIT).
# The accepted ones end with exit 0 within a bound that still catches a
# quadratic blow-up: a patch with one coordinate of 4294967296 and vertex
# colours (minutes before), rays a shader makes NaN or far (one warning), a
# 64000-vertex Polygon and a 200000-vertex OBJ face (36 s and > 120 s before).
# Needs SSS_BIN_DIR and SSS_TEST_DATA_DIR.
#
# Every check runs; failures are listed and the script exits 1 at the end.
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
data="${SSS_TEST_DATA_DIR:?SSS_TEST_DATA_DIR must name tests/data}/hostile/geometry"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_hostile_geometry.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"
cp "$data"/* .

# shellcheck source=lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
# shellcheck source=checks.sh
source "$(dirname "${BASH_SOURCE[0]}")/checks.sh"

# Hang guards: seconds a refused input may take, and an accepted one. What is
# checked is the refusal itself (the error line, nothing written); the guards
# only stop a run that hangs, with room for the sanitizer build on a machine
# three times slower than a quiet one (refusals take well under a second there,
# the accepted inputs up to 20 s).
refuse_limit=120
accept_limit=300

listing() { ls -A | grep -v "^std\(out\|err\)$" || true; }

# refused LABEL TOOL WHAT ARGS...: exit 1 within refuse_limit seconds, a first
# "TOOL ERROR:" line that starts with (or contains) WHAT, no new files.
refused() {
    local label="$1" tool="$2" what="$3"
    shift 3
    local before after first
    before="$(listing)"
    run timeout "$refuse_limit" "$bin/$tool" "$@"
    after="$(listing)"
    if [[ "$rc" == 124 ]]; then
        fail "$label: $tool ran past $refuse_limit s"
        return 0
    fi
    expect_rc 1 "$label" || return 0
    first="$(grep -m1 "ERROR" <<<"$err" || true)"
    [[ "$first" == "$tool ERROR: "*"$what"* ]] || fail "$label: expected '$what': $first"
    [[ "$before" == "$after" ]] ||
        fail "$label: files appeared: $(diff <(echo "$before") <(echo "$after") | tr '\n' ' ')"
}

# accepted LABEL TOOL ARGS...: exit 0 within accept_limit seconds, no ERROR line.
accepted() {
    local label="$1" tool="$2"
    shift 2
    run timeout "$accept_limit" "$bin/$tool" "$@"
    if [[ "$rc" == 124 ]]; then
        fail "$label: $tool ran past $accept_limit s (quadratic?)"
        return 1
    fi
    expect_rc 0 "$label" || return 1
    [[ "$err" != *ERROR* ]] || fail "$label: $err"
}

# --- cameras: an error at camera setup naming the statement ----------------
refused "orthographic screen window" render \
    "ortho_window.rib:5: ScreenWindow: orthographic rays would start" ortho_window.rib
refused "singular camera" render "singular_camera.rib:7: WorldBegin: the camera transform" \
    singular_camera.rib
[[ "$err" == *"is singular"* ]] || fail "singular camera: $err"
# ptbake traces no camera rays, but camera space must exist (shaders, bake3d).
refused "ptbake: singular camera" ptbake "singular_camera.rib:7: WorldBegin: the camera transform" \
    -spacing 0.1 singular_camera.rib
refused "far camera" render "far_camera.rib:6: WorldBegin: the camera lies at" far_camera.rib
refused "far hither" render "far_clipping.rib:4: Clipping: hither" far_clipping.rib
refused "huge lens" render "huge_lens.rib:4: DepthOfField: the lens radius" huge_lens.rib

# --- geometry beyond the coordinate range ----------------------------------
for tool in render ptbake; do
    refused "$tool: Pw with a tiny w" $tool \
        "pw_far.rib:10: Patch: its surface reaches" pw_far.rib
    [[ "$err" == *"beyond the coordinate range"* ]] || fail "$tool pw_far: $err"
    refused "$tool: sphere scaled by 1e20" $tool \
        "scaled_sphere.rib:11: Sphere: its surface reaches" scaled_sphere.rib
done

# --- huge coordinates against a fixed spacing: the limit, at once ----------
refused "ptbake: patch near 4e9" ptbake "huge_patch.rib:11: Patch: " -spacing 0.05 huge_patch.rib
[[ "$err" == *"micropolygons in one primitive exceeds the limit"*"SSS_LIMIT_PRIMITIVE_MICROPOLYGONS"* ]] ||
    fail "huge patch: $err"

# --- accepted: fast, and one warning for the rays a shader breaks ----------
if accepted "render: Pw 4294967296 with colours" render pw_colors.rib; then
    [[ -s pw_colors.exr ]] || fail "pw_colors.exr not written"
fi
if accepted "render: NaN and far shader rays" render farray.rib; then
    [[ -s farray.exr ]] || fail "farray.exr not written"
    n="$(grep -c "rays with a NaN, infinite or out-of-range origin or direction" <<<"$err" || true)"
    [[ "$n" == 1 ]] || fail "NaN rays: expected one summarising warning: $err"
fi

# --- limits ------------------------------------------------------------------
SSS_LIMIT_PRIMITIVE_VERTICES=4 refused "vertex limit: Polygon" ptbake \
    "pentagon.rib:9: Polygon: 5 vertices in one primitive exceeds the limit of 4 (set SSS_LIMIT_PRIMITIVE_VERTICES" \
    pentagon.rib
SSS_LIMIT_PRIMITIVE_VERTICES=5 refused "vertex limit: OBJ mesh" render \
    "pentagon.obj:8: f (the mesh's face corners so far): 8 vertices in one primitive exceeds the limit of 5" \
    pentagon.rib
SSS_LIMIT_PRIMITIVE_MICROPOLYGONS=1000 refused "micropolygon limit" ptbake \
    "teapot.rib:9: Teapot: " -spacing 0.05 teapot.rib
[[ "$err" == *"exceeds the limit of 1000 (set SSS_LIMIT_PRIMITIVE_MICROPOLYGONS"* ]] ||
    fail "micropolygon limit: $err"

# teapots FILE N: N instances of the teapot on a grid, baked.
teapots() {
    {
        echo 'Format 64 48 1'
        echo 'Projection "perspective" "fov" 40'
        echo 'Translate 0 0 400'
        echo 'WorldBegin'
        echo '  Surface "bake_radiance_t" "string filename" ["pots.ptc"] "string displaychannels" ["_area,_radiance_t"]'
        echo '  ObjectBegin 1 Geometry "teapot" ObjectEnd'
        awk -v n="$2" 'BEGIN { s = int(sqrt(n)); for (k = 0; k < n; ++k)
            printf "  TransformBegin Translate %d %d 0 ObjectInstance 1 TransformEnd\n",
                8 * (k % s) - 400, 8 * int(k / s) - 400 }'
        echo 'WorldEnd'
    } >"$1"
}
teapots pots100.rib 100
SSS_LIMIT_SCENE_MICROPOLYGONS=1000000 refused "scene micropolygon limit" ptbake \
    "pots100.rib: " -spacing 0.05 pots100.rib
[[ "$err" == *"micropolygons in the scene exceeds the limit of 1000000 (set SSS_LIMIT_SCENE_MICROPOLYGONS"* ]] ||
    fail "scene limit: $err"

# --- memory: stop before dicing, naming the option that reduces it --------
teapots pots10k.rib 10000
SSS_MEMORY_LIMIT=64M refused "memory: 10000 teapots at -spacing 0.05" ptbake \
    "baking pots10k.rib (about " -spacing 0.05 pots10k.rib
[[ "$err" == *"needs about "*"; this process may use 64.0 MB (SSS_MEMORY_LIMIT); raise -spacing" ]] ||
    fail "memory (-spacing): $err"
SSS_MEMORY_LIMIT=64M refused "memory: ShadingRate" ptbake "baking pots10k.rib (about " pots10k.rib
[[ "$err" == *"raise ShadingRate"* ]] || fail "memory (ShadingRate): $err"
# The image buffers are checked first (docs/limits.md), then the dicing.
SSS_MEMORY_LIMIT=1G refused "memory: render image" render "needs about " \
    -res 4000 3000 teapot.rib
[[ "$err" == *"this process may use 1.0 GB (SSS_MEMORY_LIMIT); lower the resolution"* ]] ||
    fail "memory (render image): $err"

# --- many-sided polygons: O(n log n) triangulation -------------------------
# points N FORMAT: N points on the unit circle.
points() {
    awk -v n="$1" -v fmt="$2" 'BEGIN { for (k = 0; k < n; ++k) {
        a = 2 * 3.14159265358979 * k / n; printf fmt, cos(a), sin(a) } }'
}
head='Format 64 48 1
Projection "perspective" "fov" 40
Translate 0 0 4
WorldBegin'
{
    echo "$head"
    echo '  Surface "bake_radiance_t" "string filename" ["disk.ptc"] "string displaychannels" ["_area,_radiance_t"]'
    echo -n '  Polygon "P" ['
    points 64000 ' %.7f %.7f 0'
    echo ']'
    echo 'WorldEnd'
} >disk.rib
if accepted "ptbake: 64000-vertex Polygon" ptbake disk.rib; then
    [[ -s disk.ptc ]] || fail "disk.ptc not written"
fi
sed 's/^WorldBegin/Display "disk.exr" "openexr" "rgba"\nWorldBegin/' disk.rib >disk_render.rib
accepted "render: 64000-vertex Polygon" render disk_render.rib || true
{
    points 200000 'v %.7f %.7f 0\n'
    awk 'BEGIN { printf "f"; for (k = 1; k <= 200000; ++k) printf " %d", k; print "" }'
} >face.obj
{
    echo "$head"
    echo '  Surface "bake_radiance_t" "string filename" ["face.ptc"] "string displaychannels" ["_area,_radiance_t"]'
    echo '  ReadArchive "face.obj"'
    echo 'WorldEnd'
} >face.rib
if accepted "ptbake: 200000-vertex OBJ face" ptbake face.rib; then
    [[ -s face.ptc ]] || fail "face.ptc not written"
fi

finish_checks "hostile geometry"
