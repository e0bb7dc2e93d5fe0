#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# RSL shading against the built-in C++ shaders it replaced (issue 13): the
# same jobs run by a build of the last revision with C++ shaders
# (OLD_REV, default 499617c) and by this build.
#   1. ptbake of the marble teapot at -spacing 0.0083 (868k points): time
#      and the largest difference of the baked _radiance_t;
#   2. the 600x450 teapot render (4x4 pixel samples): time and the image
#      difference (idiff);
#   3. every bundled scene (scenes/*/run) with both builds: idiff of every
#      image, against the stated tolerance (fewer than 0.5% of the pixels off
#      by more than 0.05, and an RMS difference below 0.005).
# Times are the best of 3 runs, wall clock, all threads.
#
# usage: bench/shading_bench.sh [OLD_BIN_DIR [NEW_BIN_DIR]]
#   OLD_BIN_DIR  tools built from OLD_REV (built into a temporary worktree when
#                not given); NEW_BIN_DIR defaults to build/bin.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
old_rev="${OLD_REV:-499617c}"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_shading_bench.XXXXXX")"
cleanup() {
    if [[ -n "${old_tree:-}" ]]; then git -C "$root" worktree remove --force "$old_tree" || true; fi
    rm -rf "$work"
}
trap cleanup EXIT

if [[ $# -ge 1 ]]; then
    old_bin="$(cd "$1" && pwd)"
else
    old_tree="$work/old-tree"
    git -C "$root" worktree add --detach "$old_tree" "$old_rev" >/dev/null
    cmake -S "$old_tree" -B "$work/old-build" -DCMAKE_BUILD_TYPE=Release >/dev/null
    cmake --build "$work/old-build" -j"$(nproc)" --target ptbake ptfilter brickmake render >/dev/null
    old_bin="$work/old-build/bin"
fi
new_bin="$(cd "${2:-$root/build/bin}" && pwd)"

# best_of3 COMMAND...: the best wall time of three runs, in seconds.
best_of3() {
    local best="" t0 t1 dt
    for _ in 1 2 3; do
        t0=$(date +%s.%N)
        "$@" >/dev/null 2>&1
        t1=$(date +%s.%N)
        dt=$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.3f", b - a }')
        if [[ -z "$best" ]] || awk -v a="$dt" -v b="$best" 'BEGIN { exit !(a < b) }'; then best=$dt; fi
    done
    echo "$best"
}

cd "$work"
cp "$root"/scenes/teapot/*.rib .
echo "## Bake: marble teapot, -spacing 0.0083"
t_old=$(best_of3 "$old_bin/ptbake" -spacing 0.0083 -o old.ptc bake.rib)
t_new=$(best_of3 "$new_bin/ptbake" -spacing 0.0083 -o new.ptc bake.rib)
points=$("$new_bin/ptinfo" new.ptc 2>/dev/null | sed -n 's/^points: *//p' || true)
echo "  points: ${points:-?}"
echo "  C++ shaders: $t_old s   RSL: $t_new s   ratio $(awk -v a="$t_new" -v b="$t_old" 'BEGIN { printf "%.2f", a / b }')"
for f in old new; do "$new_bin/ptinfo" $f.ptc | grep -A3 "_radiance_t" | sed "s/^/  $f /"; done

echo "## Render: teapot 600x450, 4x4 samples"
"$new_bin/ptfilter" -ssdiffusion -material marble -unitlength 0.1 new.ptc teapot_ssd.ptc >/dev/null
"$new_bin/brickmake" -maxerror 0.002 teapot_ssd.ptc teapot_ssd.bkm >/dev/null
t_old=$(best_of3 "$old_bin/render" -o old.exr teapot.rib)
t_new=$(best_of3 "$new_bin/render" -o new.exr teapot.rib)
echo "  C++ shaders: $t_old s   RSL: $t_new s   ratio $(awk -v a="$t_new" -v b="$t_old" 'BEGIN { printf "%.2f", a / b }')"
idiff -fail 0.05 -failpercent 0.5 old.exr new.exr 2>&1 | grep -E "Mean|RMS|Max|over|PASS|FAIL|WARN" | sed 's/^/  /' || true

echo "## Bundled scenes (fail: > 0.5% of pixels off by > 0.05, or RMS > 0.005)"
status=0
for scene in "$root"/scenes/*/run; do
    name=$(basename "$(dirname "$scene")")
    SSS_BIN_DIR="$old_bin" "$scene" "$work/old-$name" >/dev/null 2>&1 || { echo "  $name: old build failed"; continue; }
    SSS_BIN_DIR="$new_bin" "$scene" "$work/new-$name" >/dev/null 2>&1 || { echo "  $name: FAILED with the RSL build"; status=1; continue; }
    for img in "$work/old-$name"/*.exr; do
        f=$(basename "$img")
        out=$(idiff -v -a -fail 0.05 -failpercent 0.5 "$img" "$work/new-$name/$f" 2>&1 || true)
        rms=$(sed -n 's/.*RMS error = *\([^ ]*\).*/\1/p' <<<"$out" | head -1)
        max=$(sed -n 's/.*Max error *= *\([^ ]*\).*/\1/p' <<<"$out" | head -1)
        verdict=PASS
        grep -q FAILURE <<<"$out" && verdict=FAIL
        awk -v r="${rms:-0}" 'BEGIN { exit !(r > 0.005) }' && verdict=FAIL
        [[ $verdict == FAIL ]] && status=1
        printf '  %-28s RMS %-12s max %-12s %s\n' "$name/$f" "${rms:-0}" "${max:-0}" "$verdict"
    done
done
exit $status
