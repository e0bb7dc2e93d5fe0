#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# Whole-pipeline benchmark: the marble teapot (scenes/teapot) at 600x450 with
# 4x4 pixel samples, the four stages timed as a user runs them:
#   ptbake -> ptfilter -ssdiffusion -> brickmake -> render
# then the same pipeline at reference quality (ptfilter -maxsolidangle 0.1,
# brickmake -maxerror 0.0002, 8x8 pixel samples) to measure the error of the
# default settings: mean, RMS and max difference of the beauty (oiiotool --diff).
#
# usage: bench/pipeline_bench.sh [BUILD_BIN_DIR]   (default build/bin)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bin="$(cd "${1:-$root/build/bin}" && pwd)"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_pipeline_bench.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cp "$root"/scenes/teapot/*.rib "$work"/
cd "$work"

# time_stage LABEL COMMAND...: runs a stage, prints its wall time.
total=0
time_stage() {
    local label="$1"
    shift
    local t0 t1
    t0=$(date +%s.%N)
    "$@" >/dev/null
    t1=$(date +%s.%N)
    local dt
    dt=$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.2f", b - a }')
    total=$(awk -v a="$total" -v b="$dt" 'BEGIN { printf "%.2f", a + b }')
    printf '  %-10s %6s s   %s\n' "$label" "$dt" "$*"
}

echo "pipeline_bench: scenes/teapot, 600x450, 4x4 samples, $(nproc) cores"
time_stage ptbake "$bin/ptbake" bake.rib
time_stage ptfilter "$bin/ptfilter" -ssdiffusion -material marble -unitlength 0.1 teapot.ptc teapot_ssd.ptc
time_stage brickmake "$bin/brickmake" -maxerror 0.002 teapot_ssd.ptc teapot_ssd.bkm
time_stage render "$bin/render" -o default.exr teapot.rib
echo "  total      $total s"

echo "reference quality (not timed for the target):"
total=0
time_stage ptfilter "$bin/ptfilter" -ssdiffusion -material marble -unitlength 0.1 -maxsolidangle 0.1 teapot.ptc teapot_ssd.ptc
time_stage brickmake "$bin/brickmake" -maxerror 0.0002 teapot_ssd.ptc teapot_ssd.bkm
time_stage render "$bin/render" -samples 8 -o reference.exr teapot.rib
# Mean of the beauty and the difference statistics.
mean="$(oiiotool reference.exr --ch R,G,B --printstats 2>/dev/null | sed -n 's/.*Stats Avg: *//p' | head -n 1)"
echo "  reference beauty mean (R G B): $mean"
echo "  default vs reference, beauty R,G,B:"
oiiotool reference.exr --ch R,G,B default.exr --ch R,G,B --diff 2>&1 |
    grep -E "Mean error|RMS error|Peak SNR|Max error|pixels" | sed 's/ values are.*//; s/^ */    /' || true
