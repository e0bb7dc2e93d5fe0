#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# Time and peak memory of ptfilter -ssdiffusion against the point count: for
# each count, a ptsynth sphere (radius 50, marble) filtered with the default
# settings; prints wall time, peak resident memory of the whole process
# (/usr/bin/time %M, KiB) and bytes per point (peak / points). The best wall
# time of -repeat runs is kept (the peak does not vary).
#   bench/memory_bench.sh [-bin DIR] [-threads N] [-repeat R] [-keep DIR] [COUNT...]
# COUNT defaults to 1000000 4000000 16000000. -bin defaults to build/bin;
# -keep keeps the clouds in DIR (else a temporary folder).
set -euo pipefail

bin=build/bin
threads=0
repeat=1
keep=""
counts=()
while (($#)); do
    case "$1" in
    -bin) bin="$2"; shift 2 ;;
    -threads) threads="$2"; shift 2 ;;
    -repeat) repeat="$2"; shift 2 ;;
    -keep) keep="$2"; shift 2 ;;
    -h | --help) sed -n '2,9p' "$0"; exit 0 ;;
    *) counts+=("$1"); shift ;;
    esac
done
((${#counts[@]})) || counts=(1000000 4000000 16000000)
[[ -x /usr/bin/time ]] || { echo "memory_bench: needs GNU time (/usr/bin/time)" >&2; exit 1; }
if [[ -n "$keep" ]]; then
    mkdir -p "$keep"
    work="$keep"
else
    work="$(mktemp -d "${TMPDIR:-/tmp}/sss_memory_bench.XXXXXX")"
    trap 'rm -rf "$work"' EXIT
fi

printf '# ptfilter -ssdiffusion -material marble, ptsynth sphere r = 50, threads %s, %s\n' \
    "$threads" "$("$bin/ptfilter" --version | head -1)"
printf '%-10s %9s %12s %14s\n' points wall_s peak_MB bytes_per_point
for n in "${counts[@]}"; do
    cloud="$work/s$n.ptc"
    [[ -s "$cloud" ]] || "$bin/ptsynth" -n "$n" "$cloud" >/dev/null
    best="" peak=0
    for ((r = 0; r < repeat; r++)); do
        line="$(/usr/bin/time -f '%e %M' "$bin/ptfilter" -ssdiffusion -material marble \
            -threads "$threads" "$cloud" "$work/out.ptc" 2>&1 >/dev/null | tail -1)"
        read -r wall kb <<<"$line"
        if [[ -z "$best" ]] || awk -v a="$wall" -v b="$best" 'BEGIN { exit !(a < b) }'; then
            best="$wall"
        fi
        ((kb > peak)) && peak="$kb"
    done
    awk -v n="$n" -v w="$best" -v kb="$peak" \
        'BEGIN { printf "%-10d %9.2f %12.1f %14.1f\n", n, w, kb * 1024 / 1e6, kb * 1024 / n }'
    rm -f "$work/out.ptc"
done
