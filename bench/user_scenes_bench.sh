#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# Where users' scenes spend their time, side by side (docs/ptfilter.md,
# "Per-point materials: speed and error"; docs/render.md, "Shading rate" and
# "texture3d on point clouds"):
#   1. per-point materials: build/bin/per_point_bench (1M points: fromfile
#      against one material, time and error against the exact evaluation),
#      and ptfilter on the note's varying teapot, fromfile against three of
#      its own materials one at a time;
#   2. texture3d on the note's filtered cloud (.ptc) against its brick map:
#      the teapot render pass reading each;
#   3. the shading rate: the note's marble teapot and its absorption teapot
#      (16-ray gather) at PixelSamples 1 1 and 4 4, at the ShadingRate and
#      shading every sample (-pixelshading 1): render time, secondary rays,
#      shading points, and the 4 x 4 images' difference.
# The note's scenes come from scenes/appnote/run (full size unless
# SSS_QUICK=1). Times are the best of 3 runs, wall clock, THREADS threads
# (default 2).
#
# usage: bench/user_scenes_bench.sh [BIN_DIR]      (default build/bin)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bin="$(cd "${1:-$root/build/bin}" && pwd)"
threads="${THREADS:-2}"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_user_scenes_bench.XXXXXX")"
trap 'rm -rf "$work"' EXIT

# best_of3 COMMAND...: the best wall time of three runs, in seconds; the
# last run's output stays in $work/last.log.
best_of3() {
    local best="" t0 t1 dt
    for _ in 1 2 3; do
        t0="$(date +%s.%N)"
        "$@" >"$work/last.log" 2>&1
        t1="$(date +%s.%N)"
        dt="$(echo "$t1 - $t0" | bc -l)"
        if [[ -z "$best" ]] || (($(echo "$dt < $best" | bc -l))); then best="$dt"; fi
    done
    printf '%.3f' "$best"
}
# count WORD: the number before WORD in the last run's output.
count() { grep -oE "[0-9]+ $1" "$work/last.log" | head -1 | cut -d' ' -f1; }

echo "== scenes/appnote/run ($work/appnote)"
SSS_BIN_DIR="$bin" "$root/scenes/appnote/run" "$work/appnote" >"$work/appnote.log"
cd "$work/appnote"

echo
echo "== 1. per-point materials"
"$bin/per_point_bench" -threads "$threads"
echo
echo "varying teapot (ptfilter -unitlength 0.1, $threads threads):"
t="$(best_of3 "$bin/ptfilter" -threads "$threads" -ssdiffusion -albedo fromfile \
    -diffusemeanfreepath fromfile -unitlength 0.1 varying_rad_t.ptc v.ptc)"
echo "  fromfile: $t s"
for m in "0.8781 0.6252 0.5096 -diffusemeanfreepath 4.7257 2.5686 1.7865" \
    "0.8556 0.7023 0.6221 -diffusemeanfreepath 6.4958 3.9726 2.7985" \
    "0.8648 0.6707 0.5760 -diffusemeanfreepath 5.7703 3.3972 2.3838"; do
    # shellcheck disable=SC2086 # m is a list of arguments
    t="$(best_of3 "$bin/ptfilter" -threads "$threads" -ssdiffusion -albedo $m \
        -unitlength 0.1 varying_rad_t.ptc u.ptc)"
    echo "  one of its materials (-albedo $m): $t s"
done

echo
echo "== 2. texture3d on the filtered cloud against its brick map"
sed 's/ssdiffusion\.bkm/ssdiffusion.ptc/g' teapot_render.rib >teapot_render_ptc.rib
t_bkm="$(best_of3 "$bin/render" -threads "$threads" -o bkm.exr teapot_render.rib)"
t_ptc="$(best_of3 "$bin/render" -threads "$threads" -o ptc.exr teapot_render_ptc.rib)"
echo "  teapot render from the .bkm: $t_bkm s; from the .ptc: $t_ptc s"
echo "  ptc / bkm: $(echo "$t_ptc / $t_bkm" | bc -l | cut -c1-5)x"
echo "  image difference: $(oiiotool bkm.exr ptc.exr --diff 2>&1 | grep -E 'RMS|Max error' |
    tr -s ' ' | tr '\n' ' ')"

echo
echo "== 3. the shading rate"
printf '%-28s %9s %14s %15s\n' "render" "seconds" "secondary rays" "shading points"
for rib in teapot_render noscatter; do
    for shading in 0 1; do
        for samples in 1 4; do
            t="$(best_of3 "$bin/render" -threads "$threads" -progress 1 -samples "$samples" \
                -pixelshading "$shading" -o "${rib}_${shading}_${samples}.exr" "$rib.rib")"
            label="$rib $samples x $samples"
            ((shading)) && label="$label, each sample"
            printf '%-28s %9s %14s %15s\n' "$label" "$t" "$(count "secondary rays")" \
                "$(count "shading points")"
        done
    done
    echo "  $rib 4 x 4, at the ShadingRate against each sample:" \
        "$(oiiotool "${rib}_1_4.exr" "${rib}_0_4.exr" --diff 2>&1 |
            grep -E 'RMS|Max error' | tr -s ' ' | cut -c1-60 | tr '\n' ' ')"
done
