#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# CLI stability test: ptfilter -ssdiffusion on degenerate clouds (10 000
# identical points, points on a line, a single point, an empty cloud, zero
# areas, mixed-sign irradiance), every profile, constant and per-point
# material, under a 2 GB address-space limit and a 60 s timeout. Each run must
# exit 0 and write a cloud that ptinfo accepts (ptinfo rejects NaN/Inf) with
# finite _ssdiffusion statistics; zero areas must give exactly 0.
# Needs SSS_BIN_DIR (the folder with the built executables).
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
ptfilter="$bin/ptfilter"
ptinfo="$bin/ptinfo"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_stability.XXXXXX")"
trap 'rm -rf "$work"' EXIT

# shellcheck source=lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
# shellcheck source=checks.sh
source "$(dirname "${BASH_SOURCE[0]}")/checks.sh"

# guarded CMD...: runs CMD with bounded memory and time (exit 124 on timeout).
# No memory bound under the sanitizers (SSS_SANITIZED): ASan's shadow memory
# needs terabytes of address space.
guarded() {
    (
        [[ -n "${SSS_SANITIZED:-}" ]] || ulimit -v 2000000
        exec timeout 60 "$@"
    )
}

# ply FILE COUNT AWK_ROW: writes an ASCII PLY with P, N, radius, _area,
# _radiance_t, _albedo and _diffusemeanfreepath; AWK_ROW prints one row for
# point i (x y z nx ny nz radius area r g b ar ag ab dr dg db).
ply() {
    {
        printf 'ply\nformat ascii 1.0\n'
        printf 'comment sss_channel float _area\n'
        printf 'comment sss_channel color _radiance_t\n'
        printf 'comment sss_channel color _albedo\n'
        printf 'comment sss_channel color _diffusemeanfreepath\n'
        printf 'element vertex %d\n' "$2"
        for p in x y z nx ny nz radius _area _radiance_t_r _radiance_t_g _radiance_t_b \
            _albedo_r _albedo_g _albedo_b _diffusemeanfreepath_r \
            _diffusemeanfreepath_g _diffusemeanfreepath_b; do
            printf 'property float %s\n' "$p"
        done
        printf 'end_header\n'
        awk -v n="$2" "BEGIN { for (i = 0; i < n; ++i) { $3 } }"
    } >"$1"
}

ply "$work/identical.ply" 10000 \
    'print "0.5 -0.25 1 0 0 1 0.0056 0.0001 1 0.5 0.25 0.6 0.6 0.6 2 2.5 3"'
ply "$work/line.ply" 2000 \
    'print 0.02*i, 0.02*i, 0.02*i, 0, 0, 1, 0.01, 0.0004, 1+0.5*sin(0.01*i), (i<1000), 0.5, 0.8, 0.8, 0.8, 0.5, 0.6, 0.7'
ply "$work/single.ply" 1 'print "3 -2 1 0 1 0 0.8 2 1 0.5 0 0.4 0.4 0.4 1.5 1.5 1.5"'
ply "$work/empty.ply" 0 ''
ply "$work/zeroarea.ply" 900 \
    'print (i%30)*0.2, int(i/30)*0.2, 0, 0, 0, 1, 0.1, 0, 1, 1, 1, 0.5, 0.5, 0.5, 1, 1, 1'
ply "$work/signs.ply" 900 \
    'print (i%30)*0.2, int(i/30)*0.2, 0, 0, 0, 1, 0.14, 0.04, (i%2 ? 1 : -1), (i<450 ? -0.5 : 1), 0.1, 0.9, 0.5, 1e-6, 1, 2, 3'

# stat_lines FILE: the r/g/b statistics lines of _ssdiffusion in ptinfo's output.
stat_lines() {
    "$ptinfo" "$1" | sed -n '/color _ssdiffusion/,/^radius/p' | grep -E '^ +[rgb]:'
}

for cloud in identical line single empty zeroarea signs; do
    for profile in classic better burley pbd mc; do
        for material in "" "-albedo fromfile -diffusemeanfreepath fromfile"; do
            label="$cloud $profile ${material:+per-point}"
            result="$work/$cloud.$profile.ptc"
            # shellcheck disable=SC2086 # $material is a list of options
            run guarded "$ptfilter" -ssdiffusion -profile "$profile" $material \
                "$work/$cloud.ply" "$result"
            expect_rc 0 "$label" || continue
            run "$ptinfo" "$result"
            expect_rc 0 "ptinfo $label (rejects NaN/Inf)" || continue
            if [[ "$cloud" == empty ]]; then
                grep -q '^points: 0$' "$work/stdout" || fail "$label: not empty: $result"
                continue
            fi
            stats="$(stat_lines "$result")"
            [[ "$(wc -l <<<"$stats")" == 3 ]] || fail "$label: no _ssdiffusion stats: $result"
            if grep -Eqi 'nan|inf' <<<"$stats"; then fail "$label: non-finite stats: $stats"; fi
            if [[ "$cloud" == zeroarea ]] &&
                grep -Ev '^ +[rgb]: min 0  mean 0  max 0$' <<<"$stats" >/dev/null; then
                fail "$label: zero areas must give exactly 0: $stats"
            fi
            if [[ "$cloud" == signs ]] && ! grep -q 'min -' <<<"$stats"; then
                fail "$label: negative irradiance must stay signed: $stats"
            fi
        done
    done
done

# The exact evaluation on the identical points agrees with the hierarchical one
# (same statistics to 3 digits).
run guarded "$ptfilter" -ssdiffusion -exact "$work/identical.ply" "$work/exact.ptc"
expect_rc 0 "identical -exact"
run guarded "$ptfilter" -ssdiffusion "$work/identical.ply" "$work/tree.ptc"
expect_rc 0 "identical"
digits3() { stat_lines "$1" | awk '{ printf "%.3g %.3g\n", $3, $7 }'; }
[[ "$(digits3 "$work/exact.ptc")" == "$(digits3 "$work/tree.ptc")" ]] ||
    fail "identical points: exact $(digits3 "$work/exact.ptc") vs tree $(digits3 "$work/tree.ptc")"

finish_checks stability
