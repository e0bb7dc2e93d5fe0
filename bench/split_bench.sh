#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# Splitting one cloud (ptfilter -part K/N, issue 16): wall time and peak
# resident memory of the single run against N parts run one after another,
# and of the merge, on a ptsynth sphere (marble, defaults), with a check that
# the merged cloud is byte-identical to the single run's.
#
# usage: bench/split_bench.sh [BIN_DIR]      (default build/bin)
# env:   SIZES="1000000 4000000 16000000"  cloud sizes
#        PARTS="4"                         numbers of parts to try
#        THREADS=2                          -threads of every run
#        KEEP_DIR=DIR                       work in DIR and keep the clouds
# Prints one table row per run: points, what, seconds, peak MB, bytes/point.
# Run it on an otherwise idle machine: the numbers are about time.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bin="$(cd "${1:-$root/build/bin}" && pwd)"
sizes="${SIZES:-1000000 4000000 16000000}"
part_counts="${PARTS:-4}"
threads="${THREADS:-2}"
for tool in ptfilter ptsynth; do
    [[ -x "$bin/$tool" ]] || { echo "split_bench: no $bin/$tool (build first)" >&2; exit 1; }
done
[[ -x /usr/bin/time ]] || { echo "split_bench: needs /usr/bin/time (apt-get install time)" >&2; exit 1; }
if [[ -n "${KEEP_DIR:-}" ]]; then
    work="$KEEP_DIR"
    mkdir -p "$work"
else
    work="$(mktemp -d "${TMPDIR:-/tmp}/sss_split_bench.XXXXXX")"
    trap 'rm -rf "$work"' EXIT
fi
cd "$work"

# measure N LABEL COMMAND...: runs COMMAND, prints a row and sets $secs, $kb.
measure() {
    local n="$1" label="$2"
    shift 2
    local line
    /usr/bin/time -o time.txt -f '%e %M' "$@" >/dev/null
    line="$(tail -n 1 time.txt)"
    secs="${line% *}" kb="${line#* }"
    awk -v n="$n" -v l="$label" -v s="$secs" -v k="$kb" 'BEGIN {
        printf "| %d | %s | %.2f | %.0f | %.0f |\n", n, l, s, k / 1024, k * 1024 / n }'
}

echo "ptfilter -ssdiffusion -threads $threads, sphere from ptsynth, marble defaults; $(nproc) cores"
echo
echo "| points | run | seconds | peak MB | bytes/point |"
echo "|---:|---|---:|---:|---:|"
for n in $sizes; do
    cloud="sphere_$n.ptc"
    [[ -f "$cloud" ]] || "$bin/ptsynth" -n "$n" "$cloud" >/dev/null
    measure "$n" "single run" "$bin/ptfilter" -ssdiffusion -threads "$threads" "$cloud" whole.ptc
    single="$secs"
    for parts in $part_counts; do
        total=0 peak=0 slowest=0 files=()
        for ((k = 1; k <= parts; k++)); do
            measure "$n" "part $k/$parts" "$bin/ptfilter" -ssdiffusion -threads "$threads" \
                -part "$k/$parts" "$cloud" "part$k.ptpart" >/dev/null
            total="$(awk -v a="$total" -v b="$secs" 'BEGIN { print a + b }')"
            slowest="$(awk -v a="$slowest" -v b="$secs" 'BEGIN { print (b > a ? b : a) }')"
            ((kb > peak)) && peak="$kb"
            files+=("part$k.ptpart")
        done
        awk -v n="$n" -v p="$parts" -v s="$total" -v k="$peak" 'BEGIN {
            printf "| %d | %d parts, one after another (largest peak) | %.2f | %.0f | %.0f |\n",
                n, p, s, k / 1024, k * 1024 / n }'
        measure "$n" "merge of $parts parts" "$bin/ptfilter" -merge "${files[@]}" merged.ptc
        awk -v n="$n" -v p="$parts" -v s="$total" -v m="$secs" -v one="$single" \
            -v w="$slowest" 'BEGIN {
            printf "| %d | %d parts + merge: %.2fx the single run, merge %.1f %% of it; on %d machines: slowest part %.2f s + merge = %.2f s, %.2fx faster |  |  |  |\n",
                n, p, (s + m) / one, 100 * m / (s + m), p, w, w + m, one / (w + m) }'
        cmp -s whole.ptc merged.ptc || { echo "split_bench: merged cloud differs from the single run" >&2; exit 1; }
        rm -f "${files[@]}" merged.ptc
    done
    rm -f whole.ptc
done
