#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# Triangulation of many-sided polygons (issue 15): wall time of ptbake and
# render on one Polygon of N vertices for N = 8000, 16000, 32000, 64000, and
# of ptbake on an OBJ file whose only face has 200000 vertices. Two shapes:
#   disk: N points on a circle (convex; every ear is a sliver), and
#   star: N points alternately on radii 1 and 0.8 (N / 2 reflex vertices).
# The triangulation used to be quadratic in N (64000: 36 s in ptbake); the
# times should now grow about linearly with N.
#
# usage: bench/polygon_bench.sh [BIN_DIR]      (default build/bin)
# env:   SIZES="8000 16000" polygon sizes; OBJ_SIZE=200000; SHAPES="disk star";
#        TIMEOUT=300 seconds per run
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bin="$(cd "${1:-$root/build/bin}" && pwd)"
sizes="${SIZES:-8000 16000 32000 64000}"
obj_size="${OBJ_SIZE:-200000}"
shapes="${SHAPES:-disk star}"
limit="${TIMEOUT:-300}"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_polygon_bench.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"

# points SHAPE N FORMAT: the polygon's vertices, one printf FORMAT per point.
points() {
    awk -v shape="$1" -v n="$2" -v fmt="$3" 'BEGIN {
        for (k = 0; k < n; ++k) {
            a = 2 * 3.14159265358979 * k / n
            r = (shape == "star" && k % 2) ? 0.8 : 1.0
            printf fmt, r * cos(a), r * sin(a)
        }
    }'
}

# scene SHAPE N: a bake RIB and a render RIB of the polygon facing the camera.
scene() {
    local head='Format 320 240 1
Projection "perspective" "fov" 40
Translate 0 0 4
WorldBegin
  LightSource "distantlight" 1 "from" [0 0 -1] "to" [0 0 0]'
    {
        echo "$head"
        echo '  Surface "bake_radiance_t" "string filename" ["poly.ptc"] "string displaychannels" ["_area,_radiance_t"]'
        echo -n '  Polygon "P" ['
        points "$1" "$2" ' %.7f %.7f 0'
        echo ']'
        echo 'WorldEnd'
    } >bake.rib
    {
        echo 'Display "poly.exr" "openexr" "rgba"'
        echo "$head"
        echo '  Surface "matte"'
        echo -n '  Polygon "P" ['
        points "$1" "$2" ' %.7f %.7f 0'
        echo ']'
        echo 'WorldEnd'
    } >render.rib
}

# seconds COMMAND...: wall time of one run (s), ">LIMIT" when it ran past
# TIMEOUT seconds; fails the bench if the command does.
seconds() {
    local t0 t1 rc=0
    t0="$(date +%s.%N)"
    timeout "$limit" "$@" >"$work/log" 2>&1 || rc=$?
    if ((rc == 124)); then
        echo ">$limit"
        return 0
    elif ((rc != 0)); then
        cat "$work/log" >&2
        return 1
    fi
    t1="$(date +%s.%N)"
    awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.2f", b - a }'
}

printf '%-6s %8s %10s %10s\n' shape vertices "ptbake s" "render s"
for shape in $shapes; do
    for n in $sizes; do
        scene "$shape" "$n"
        printf '%-6s %8d %10s %10s\n' "$shape" "$n" "$(seconds "$bin/ptbake" bake.rib)" \
            "$(seconds "$bin/render" render.rib)"
    done
    # One OBJ face of obj_size vertices, read through ReadArchive.
    {
        points "$shape" "$obj_size" 'v %.7f %.7f 0\n'
        echo -n 'f'
        awk -v n="$obj_size" 'BEGIN { for (k = 1; k <= n; ++k) printf " %d", k; print "" }'
    } >face.obj
    {
        echo 'Format 320 240 1
Projection "perspective" "fov" 40
Translate 0 0 4
WorldBegin
  LightSource "distantlight" 1 "from" [0 0 -1] "to" [0 0 0]
  Surface "bake_radiance_t" "string filename" ["obj.ptc"] "string displaychannels" ["_area,_radiance_t"]
  ReadArchive "face.obj"
WorldEnd'
    } >obj.rib
    printf '%-6s %8d %10s %10s\n' "$shape" "$obj_size" "$(seconds "$bin/ptbake" obj.rib)" "(obj)"
done
