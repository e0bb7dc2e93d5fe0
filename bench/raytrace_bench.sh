#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# Ray-traced shadeops on the teapot (issue 14): rays per second next to the
# image error against a high-sample reference, for
#   1. occlusion(): the marble teapot rendered with read_ssdiffusion's
#      ambient occlusion (occlusion_samples N, 1 pixel sample so that the
#      noise is the shadeop's own), and
#   2. gather(): the absorption-only teapot (scenes/absorption), the
#      absorption shader gathering N rays into the teapot per camera hit;
# at N = 16, 64, 256 against N = 2048. Reports per N: wall time of the render
# (best of 3), the time and the secondary rays the shadeop adds (against
# N = 0, which still traces the lights' shadow rays), rays per second of that
# added time, and the RMS and mean absolute error against the reference
# (oiiotool --diff) of the occlusion AOV (occlusion) or the beauty (gather).
#
# usage: bench/raytrace_bench.sh [BIN_DIR]      (default build/bin)
# env:   RES="W H" image size (default 300 225)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bin="$(cd "${1:-$root/build/bin}" && pwd)"
read -r W H <<<"${RES:-300 225}"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_raytrace_bench.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"
export PATH="$bin:$PATH"

# The inputs: the teapot's bake, diffusion and brick maps.
cp "$root/scenes/teapot/bake.rib" "$root/scenes/teapot/teapot.rib" .
cp "$root/scenes/absorption/teapot.rib" absorption.rib
ptbake -spacing 0.03 bake.rib >/dev/null
ptfilter -ssdiffusion -material marble -unitlength 0.1 teapot.ptc teapot_ssd.ptc >/dev/null
brickmake -maxerror 0.002 teapot_ssd.ptc teapot_ssd.bkm >/dev/null
brickmake -maxerror 0.002 teapot.ptc teapot_rad.bkm >/dev/null

# occlusion.rib N / gather.rib N: the two scenes with N rays per hit.
make_occlusion() {
    sed -E "s#^( *)Surface \"read_ssdiffusion\".*#\\1Surface \"read_ssdiffusion\" \"string filename\" [\"teapot_ssd.bkm\"] \"float Ka\" [1] \"float Kd\" [0.1] \"float occlusion_samples\" [$1]#; s#\"teapot.exr\"#\"occ_$1.exr\"#" teapot.rib >occ_$1.rib
}
make_gather() {
    sed -E "s#\"float samples\" \[16\]#\"float samples\" [$1]#; s#\"absorption.exr\"#\"gather_$1.exr\"#" absorption.rib >gather_$1.rib
}
# best_of3 COMMAND...: best wall time of three runs (s); the last run's output in $log.
best_of3() {
    local best="" t0 t1 dt
    for _ in 1 2 3; do
        t0="$(date +%s.%N)"
        "$@" >"$work/log" 2>&1
        t1="$(date +%s.%N)"
        dt="$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.3f", b - a }')"
        if [[ -z "$best" ]] || awk -v a="$dt" -v b="$best" 'BEGIN { exit !(a < b) }'; then best="$dt"; fi
    done
    echo "$best"
}
secondary() { sed -n 's/^render: .* \([0-9][0-9]*\) secondary rays$/\1/p' "$work/log"; }
diffstat() { # A B CHANNELS: "RMS MEAN"
    { oiiotool "$1" --ch "$3" "$2" --ch "$3" --diff 2>&1 || true; } |
        awk '/RMS error/ { r = $4 } /Mean error/ { m = $4 } END { print r + 0, m + 0 }'
}

for kind in occ gather; do
    "make_${kind/occ/occlusion}" 2048
    render -res "$W" "$H" -samples 1 ${kind}_2048.rib >/dev/null
    "make_${kind/occ/occlusion}" 0
    t0="$(best_of3 render -progress 1 -res "$W" "$H" -samples 1 ${kind}_0.rib)"
    rays0="$(secondary)"
    # occlusion: the occlusion AOV (in the beauty it only scales a dim ambient
    # light); gather: the beauty.
    chans=R,G,B
    [[ $kind == occ ]] && chans=occlusion.R
    printf '\n%s (reference: 2048 rays per hit, %sx%s, 1 pixel sample)\n' \
        "$([[ $kind == occ ]] && echo "occlusion() on the marble teapot" || echo "gather() in the absorption-only teapot")" "$W" "$H"
    printf '%8s %9s %10s %14s %9s %10s %10s\n' "rays/hit" "time (s)" "added (s)" "added rays" "Mrays/s" "RMS err" "mean err"
    for n in 16 64 256; do
        "make_${kind/occ/occlusion}" "$n"
        t="$(best_of3 render -progress 1 -res "$W" "$H" -samples 1 ${kind}_$n.rib)"
        rays="$(($(secondary) - rays0))"
        read -r rms mean <<<"$(diffstat ${kind}_$n.exr ${kind}_2048.exr $chans)"
        added="$(awk -v a="$t" -v b="$t0" 'BEGIN { d = a - b; if (d < 0.001) d = 0.001; printf "%.3f", d }')"
        printf '%8d %9.3f %10.3f %14d %9s %10.5f %10.5f\n' "$n" "$t" "$added" "$rays" \
            "$(awk -v r="$rays" -v t="$added" 'BEGIN { if (t < 0.02) printf "-"; else printf "%.2f", r / t / 1e6 }')" "$rms" "$mean"
    done
done
