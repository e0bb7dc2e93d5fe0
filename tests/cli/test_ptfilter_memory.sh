#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# CLI test of ptfilter -ssdiffusion's memory, without timing anything: the
# peak resident memory ptfilter reports with -progress 2 (getrusage) grows by
# at most BYTES_PER_NODE per octree node and MAX_BYTES_PER_POINT per point
# between two clouds of the same density (the slope leaves out the process's
# fixed base: libraries, thread stacks); and the streamed run's output does
# not depend on the thread count (byte for byte; the unit tests
# SsdiffusionFiles.* compare it with the whole-cloud library path).
# Skipped in the sanitizer build (ASan's shadow memory and quarantine).
# Needs SSS_BIN_DIR (the folder with ptfilter and ptsynth).
set -euo pipefail

if [[ -n "${SSS_SANITIZED:-}" ]]; then
    echo "SKIP: memory measurements are meaningless under the sanitizers"
    exit 0
fi
bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
ptfilter="$bin/ptfilter"
ptsynth="$bin/ptsynth"
for tool in "$ptfilter" "$ptsynth"; do
    [[ -x "$tool" ]] || { echo "FAIL: missing executable $tool" >&2; exit 1; }
done
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_ptfilter_memory.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"

# At its peak (the evaluation) ptfilter holds the octree's nodes and their
# expansions, 200 bytes per node (Node 56 + Expansion 144; leaves of at most
# 16 points: 0.14 to 0.27 nodes per point on these spheres, depending on how
# the octree's levels fall on them), and 48 bytes per point: the sorted
# sources (pos_rho2, power_area: 32), their order (4), the irradiance that the
# result overwrites (12); 12 more for the
# sources' normals when a disk may need the quadrature (not on these
# spheres). A regression that holds one more float per point exceeds the
# budget below; one more array of vectors (a copy of the positions, a second
# output cloud) far exceeds it.
BYTES_PER_NODE=200
MAX_BYTES_PER_POINT=53

# run POINTS SIZE: runs ptfilter on a sphere of POINTS points and radius SIZE
# (the same density for POINTS / SIZE^2 constant, so that no disk needs the
# quadrature); prints the peak in bytes and the octree's nodes it reports.
run_sphere() {
    "$ptsynth" -n "$1" -size "$2" "s$1.ptc" >/dev/null
    "$ptfilter" -ssdiffusion -threads 2 -progress 2 "s$1.ptc" "o$1.ptc" >"log$1.txt"
    local mb nodes
    mb="$(sed -n 's/^ptfilter: peak memory \([0-9.]*\) MB.*/\1/p' "log$1.txt")"
    nodes="$(sed -n 's/^ptfilter: octree \([0-9]*\) nodes.*/\1/p' "log$1.txt")"
    if [[ -z "$mb" || -z "$nodes" ]]; then
        echo "FAIL: no peak memory or octree line in:" >&2
        cat "log$1.txt" >&2
        exit 1
    fi
    awk -v mb="$mb" -v nodes="$nodes" 'BEGIN { printf "%.0f %d\n", mb * 1e6, nodes }'
}

small=150000
large=600000
read -r p_small n_small < <(run_sphere "$small" 12.5)
read -r p_large n_large < <(run_sphere "$large" 25)
# The slope between the two leaves out the process's fixed base (libraries,
# thread stacks), the node term the octree's shape.
per_point="$(awk -v a="$p_small" -v b="$p_large" -v na="$n_small" -v nb="$n_large" \
    -v n="$small" -v m="$large" -v node="$BYTES_PER_NODE" \
    'BEGIN { printf "%.1f\n", (b - a - node * (nb - na)) / (m - n) }')"
echo "peak: $small points $p_small bytes ($n_small nodes)," \
    "$large points $p_large bytes ($n_large nodes):" \
    "$BYTES_PER_NODE per node + $per_point per point"
if ! awk -v s="$per_point" -v max="$MAX_BYTES_PER_POINT" 'BEGIN { exit !(s <= max) }'; then
    echo "FAIL: ptfilter -ssdiffusion holds $per_point bytes per point besides the" \
        "octree's nodes at its peak (budget $MAX_BYTES_PER_POINT)" >&2
    exit 1
fi

# The streamed run's output does not depend on the thread count.
"$ptfilter" -ssdiffusion -threads 1 "s$small.ptc" "one.ptc"
cmp "one.ptc" "o$small.ptc" || { echo "FAIL: 1 and 2 threads differ" >&2; exit 1; }
echo "PASS"
