#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# CLI test of ptbake: the bundled scenes bake, areas and values are right,
# ptbake | ptfilter end to end, frame patterns, -o, progress, exit codes,
# error lines, atomic output, thread independence.
# Needs SSS_BIN_DIR (the folder with ptbake, ptfilter and ptinfo).
#
# Every check runs; failures are listed and the script exits 1 at the end.
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
ptbake="$bin/ptbake"
ptfilter="$bin/ptfilter"
ptinfo="$bin/ptinfo"
for tool in "$ptbake" "$ptfilter" "$ptinfo"; do
    [[ -x "$tool" ]] || { echo "FAIL: missing executable $tool" >&2; exit 1; }
done
scenes="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../scenes" && pwd)"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_ptbake.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"

# shellcheck source=lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
# shellcheck source=checks.sh
source "$(dirname "${BASH_SOURCE[0]}")/checks.sh"

# channel_stat FILE CHANNEL-LINE FIELD [ROW]: min/mean/max of a channel from ptinfo.
channel_stat() {
    "$ptinfo" "$1" | grep -A"${4:-1}" "^ *$2\$" | sed -n "$((${4:-1} + 1))p" |
        sed -n "s/.*$3 \\([^ ]*\\).*/\\1/p"
}
# total_area FILE: points x mean _area.
total_area() {
    awk -v n="$(points "$1")" -v m="$(channel_stat "$1" "float _area" mean)" 'BEGIN { printf "%.6f", n * m }'
}
near() { # value expected relative-tolerance
    awk -v v="$1" -v e="$2" -v t="$3" 'BEGIN { d = v - e; if (d < 0) d = -d; exit !(d <= t * (e < 0 ? -e : e)) }'
}

# --help and --version.
run "$ptbake" --help
expect_rc 0 --help && [[ "$out" == *"usage: ptbake"* ]] || fail "--help lacks the usage line"
run "$ptbake" --version
expect_rc 0 --version && [[ "$out" == "ptbake (sss) "* ]] || fail "--version: $out"

# ---------------------------------------------------------------------------
# Analytic sphere: area 4 pi, radiance = max(0, N.y) in [0, 1], mean 1/4.
cp "$scenes/analytic/sphere.rib" .
run "$ptbake" sphere.rib
if expect_rc 0 "sphere bake"; then
    has_channel sphere.ptc "float _area" || fail "sphere.ptc lacks _area"
    has_channel sphere.ptc "color _radiance_t" || fail "sphere.ptc lacks _radiance_t"
    near "$(total_area sphere.ptc)" 12.566371 0.005 || fail "sphere area $(total_area sphere.ptc) != 4 pi"
    # Points are denser on the camera side (ShadingRate), so the plain mean of
    # max(0, N.y) is near, not at, its area mean 1/4.
    near "$(channel_stat sphere.ptc "color _radiance_t" mean)" 0.25 0.1 ||
        fail "sphere mean radiance $(channel_stat sphere.ptc "color _radiance_t" mean) is not about 0.25"
    near "$(channel_stat sphere.ptc "color _radiance_t" max)" 1 0.01 || fail "sphere max radiance"
    [[ -z "$err" ]] || fail "clean bake wrote to stderr: $err"
    [[ -z "$out" ]] || fail "bake without -progress printed: $out"
fi

# Analytic torus: area 4 pi^2 R r; a point light on the axis lights the top
# of the tube (at most I cos / d^2 < 1) and the shadowed underside is 0.
cp "$scenes/analytic/torus.rib" .
run "$ptbake" torus.rib
if expect_rc 0 "torus bake"; then
    near "$(total_area torus.ptc)" 39.478418 0.005 || fail "torus area $(total_area torus.ptc) != 4 pi^2 R r"
    [[ "$(channel_stat torus.ptc "color _radiance_t" min)" == "0" ]] || fail "torus: no unlit points"
    max="$(channel_stat torus.ptc "color _radiance_t" max)"
    awk -v m="$max" 'BEGIN { exit !(m > 0.68 && m < 1.0) }' || fail "torus max radiance $max"
fi

# ptbake | ptfilter end to end.
run "$ptfilter" -ssdiffusion -material marble -unitlength 10 sphere.ptc sphere_ssd.ptc
if expect_rc 0 "ptfilter on a bake"; then
    has_channel sphere_ssd.ptc "color _ssdiffusion" || fail "no _ssdiffusion after ptfilter"
    [[ "$(points sphere_ssd.ptc)" == "$(points sphere.ptc)" ]] || fail "ptfilter changed the point count"
fi

# Thread count does not change the output; -progress prints ALF_PROGRESS.
run "$ptbake" -threads 1 -o t1.ptc sphere.rib
expect_rc 0 "-threads 1" || true
run "$ptbake" -threads 2 -progress 1 -o t2.ptc sphere.rib
if expect_rc 0 "-threads 2 -progress 1"; then
    cmp -s t1.ptc t2.ptc || fail "-threads 1 and 2 outputs differ"
    [[ "$(grep 'ALF_PROGRESS' stdout | tail -n 1)" == "ALF_PROGRESS 100%" ]] || fail "no final ALF_PROGRESS 100%"
    grep -q "ptbake: wrote t2.ptc" stdout || fail "-progress 1 does not name the output"
fi

# Frame patterns: -frame expands the scene, -o and the bake file names.
sed 's/"sphere.ptc"/"sphere.$F4.ptc"/' sphere.rib > frame.0007.rib
run "$ptbake" -frame 7 frame.####.rib
if expect_rc 0 "-frame 7"; then
    [[ -s sphere.0007.ptc ]] || fail "-frame 7 did not write sphere.0007.ptc"
fi
run "$ptbake" -frame 7 -o 'out.%04d.ptc' frame.0007.rib
expect_rc 0 "-o pattern" && { [[ -s out.0007.ptc ]] || fail "-o out.%04d.ptc did not write out.0007.ptc"; }
run "$ptbake" frame.0007.rib
expect_rc 2 "pattern without -frame" || true
[[ "$err" == *"-frame"* ]] || fail "pattern without -frame: message should mention -frame: $err"

# -spacing and the mean-free-path option.
run "$ptbake" -spacing 0.05 -o sp.ptc sphere.rib
if expect_rc 0 "-spacing 0.05"; then
    n="$(points sp.ptc)"
    awk -v n="$n" 'BEGIN { exit !(n > 3000 && n < 8000) }' || fail "-spacing 0.05 gave $n points (expected about 5000)"
fi
run "$ptbake" -spacing 1 -material skin1 -unitlength 1 -o coarse.ptc sphere.rib
expect_rc 0 "coarse spacing" && { [[ "$err" == *"WARNING"*"mean free path"* ]] || fail "no warning for a spacing coarser than the mfp: $err"; }
run "$ptbake" -spacing mfp -material skin1 -unitlength 10 -o mfp.ptc sphere.rib
expect_rc 0 "-spacing mfp" && { [[ "$err" != *"mean free path"* ]] || fail "-spacing mfp still warns: $err"; }

# ---------------------------------------------------------------------------
# Bundled scenes.
for s in teapot thinbox varying; do
    mkdir -p "$s" && cp "$scenes/$s"/* "$s"/
done
(cd teapot && "$ptbake" -progress 1 bake.rib >log 2>&1) || fail "teapot bake failed: $(cat teapot/log)"
if [[ -s teapot/teapot.ptc ]]; then
    n="$(points teapot/teapot.ptc)"
    awk -v n="$n" 'BEGIN { exit !(n > 100000 && n < 600000) }' || fail "teapot: $n points"
    # Back light is brighter: the maximum radiance is well above the key light's.
    max="$(channel_stat teapot/teapot.ptc "color _radiance_t" max)"
    awk -v m="$max" 'BEGIN { exit !(m > 2 && m < 50) }' || fail "teapot max radiance $max"
else
    fail "teapot bake wrote no teapot.ptc"
fi
(cd thinbox && "$ptbake" bake.rib >log 2>&1) || fail "thinbox bake failed: $(cat thinbox/log)"
if [[ -s thinbox/thinbox.ptc ]]; then
    # Box 30 x 4 x 30: 2*(900 + 120 + 120) = 2280; torus 4 pi^2 * 6 * 0.8 = 189.5.
    near "$(total_area thinbox/thinbox.ptc)" 2469.5 0.005 || fail "thinbox area $(total_area thinbox/thinbox.ptc)"
    [[ "$(channel_stat thinbox/thinbox.ptc "color _radiance_t" min)" == "-1" ]] ||
        fail "thinbox: the blocker's -1 is missing"
    ( cd thinbox && "$ptfilter" -ssdiffusion -material skin1 -unitlength 1 thinbox.ptc ssd.ptc ) ||
        fail "ptfilter on thinbox failed"
else
    fail "thinbox bake wrote no thinbox.ptc"
fi
(cd varying && "$ptbake" bake.rib >log 2>&1) || fail "varying bake failed: $(cat varying/log)"
if [[ -s varying/blob.ptc ]]; then
    has_channel varying/blob.ptc "color _albedo" || fail "blob.ptc lacks _albedo"
    has_channel varying/blob.ptc "color _diffusemeanfreepath" || fail "blob.ptc lacks dmfp"
    lo="$(channel_stat varying/blob.ptc "color _albedo" min 1)"
    hi="$(channel_stat varying/blob.ptc "color _albedo" max 1)"
    awk -v a="$lo" -v b="$hi" 'BEGIN { exit !(a >= 0.85 && b <= 0.9 && b - a > 0.01) }' ||
        fail "blob red albedo range [$lo, $hi] should vary within [0.85, 0.9]"
    ( cd varying && "$ptfilter" -ssdiffusion -albedo fromfile -diffusemeanfreepath fromfile \
        -unitlength 0.1 blob.ptc ssd.ptc ) || fail "ptfilter fromfile on blob failed"
else
    fail "varying bake wrote no blob.ptc"
fi

# ---------------------------------------------------------------------------
# Errors: exit codes, one line naming file and line, no output left behind.
run "$ptbake" -bogus sphere.rib
expect_rc 2 "unknown option" && [[ "$err" == "ptbake ERROR: "*"-bogus"* ]] || fail "unknown option message: $err"
run "$ptbake"
expect_rc 2 "no scene" || true
run "$ptbake" -spacing -1 sphere.rib
expect_rc 2 "negative spacing" || true
run "$ptbake" missing.rib
expect_rc 1 "missing scene" && [[ "$err" == "ptbake ERROR: "*"missing.rib"* ]] || fail "missing scene message: $err"
printf 'WorldBegin\nSurface "bake_radiance_t" "string filename" ["bad.ptc"]\nSphere 1 -1\nWorldEnd\n' > bad.rib
run "$ptbake" bad.rib
expect_rc 1 "bad RIB" || true
[[ "$err" == "ptbake ERROR: "*"bad.rib:3"*"Sphere"* ]] || fail "bad RIB message should name bad.rib:3 and Sphere: $err"
[[ ! -e bad.ptc ]] || fail "a failed bake left bad.ptc"
# A failing bake leaves an existing output untouched.
cp sphere.ptc keep.ptc
printf 'WorldBegin\nSurface "bake_radiance_t" "string filename" ["keep.ptc"] "color albedo" [1]\nSphere 1 -1 1 360\nWorldEnd\n' > bad2.rib
run "$ptbake" bad2.rib
expect_rc 1 "bad parameter" || true
cmp -s sphere.ptc keep.ptc || fail "a failed bake changed an existing output"
ls -a | grep -q '\.tmp$' && fail "temporary files left behind: $(ls -a | grep '\.tmp$')"

finish_checks ptbake
