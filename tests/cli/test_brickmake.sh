#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# CLI test of brickmake and brickinfo: PRMan command lines, the report, the
# map's values at the input points (brickinfo -lookup -compare), -maxerror
# against file size, pictures, -newer, frame patterns, channels, thread
# independence, exit codes, error lines and atomic output.
# Needs SSS_BIN_DIR (the folder with brickmake, brickinfo, ptsynth, ptbake,
# ptfilter and ptinfo).
#
# Every check runs; failures are listed and the script exits 1 at the end.
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
brickmake="$bin/brickmake"
brickinfo="$bin/brickinfo"
ptsynth="$bin/ptsynth"
ptbake="$bin/ptbake"
ptfilter="$bin/ptfilter"
ptinfo="$bin/ptinfo"
for tool in "$brickmake" "$brickinfo" "$ptsynth" "$ptbake" "$ptfilter" "$ptinfo"; do
    [[ -x "$tool" ]] || { echo "FAIL: missing executable $tool" >&2; exit 1; }
done
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
scenes="$(cd "$here/../../scenes" && pwd)"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_brickmake.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"

# shellcheck source=lib.sh
source "$here/lib.sh"
# shellcheck source=checks.sh
source "$here/checks.sh"

size_of() { stat -c %s "$1" 2>/dev/null || echo 0; }
# compare_field NAME rms|max: a number from the last run's
# "brickinfo: compare NAME: rms X max Y (...)" line.
compare_field() {
    awk -v name="$1:" -v field="$2" '$1 == "brickinfo:" && $2 == "compare" && $3 == name {
        for (i = 4; i < NF; ++i) if ($i == field) { print $(i + 1); exit }
    }' "$work/stdout"
}
less_than() { awk -v a="$1" -v b="$2" 'BEGIN { exit !(a != "" && a + 0 < b + 0) }'; }
# is_png FILE: the 8-byte PNG signature.
is_png() { [[ "$(head -c 8 "$1" 2>/dev/null | od -An -tx1 | tr -d ' \n')" == "89504e470d0a1a0a" ]]; }
# no_temporaries: hidden .tmp files left next to outputs.
no_temporaries() {
    local left
    left="$(find "$work" -name '.*.tmp')"
    [[ -z "$left" ]] || fail "temporary files left behind: $left"
}

# --help and --version.
for tool in brickmake brickinfo; do
    run "$bin/$tool" --help
    expect_rc 0 "$tool --help" && [[ "$out" == *"usage: $tool"* && -z "$err" ]] ||
        fail "$tool --help: $out $err"
    run "$bin/$tool" --version
    expect_rc 0 "$tool --version" && [[ "$out" == "$tool (sss) "* ]] || fail "$tool --version: $out"
done

# ---------------------------------------------------------------------------
# Inputs: ptbake + ptfilter on the analytic sphere (the PRMan pipeline), and
# a synthetic sphere with a smooth field (ptsynth: E = max(0, N.L) + 0.2).
cp "$scenes/analytic/sphere.rib" .
run "$ptbake" sphere.rib
expect_rc 0 "ptbake sphere.rib" || exit 1
run "$ptfilter" -ssdiffusion -material marble -unitlength 0.1 sphere.ptc ssdiffusion.ptc
expect_rc 0 "ptfilter" || exit 1
run "$ptsynth" -n 20000 -size 1 -light 0 1 0 -ambient 0.2 synth.ptc
expect_rc 0 "ptsynth" || exit 1

# ---------------------------------------------------------------------------
# PRMan syntax; a clean run prints nothing.
run "$brickmake" -maxerror 0.002 ssdiffusion.ptc ssdiffusion.bkm
if expect_rc 0 "brickmake -maxerror 0.002 ssdiffusion.ptc ssdiffusion.bkm"; then
    [[ -s ssdiffusion.bkm ]] || fail "no ssdiffusion.bkm"
    [[ -z "$out" && -z "$err" ]] || fail "a clean brickmake printed: $out $err"
fi

# brickinfo: channels, levels, totals, provenance.
run "$brickinfo" ssdiffusion.bkm
if expect_rc 0 "brickinfo"; then
    grep -q '^  color _ssdiffusion$' stdout || fail "brickinfo lacks the channel line: $out"
    grep -q '^maxerror: 0.002$' stdout || fail "brickinfo lacks maxerror 0.002"
    grep -q '^provenance: brickmake .* -maxerror 0.002 ssdiffusion.ptc ssdiffusion.bkm$' stdout ||
        fail "provenance is not the command line: $(grep provenance stdout)"
    levels="$(sed -n 's/^levels: //p' stdout)"
    [[ "$levels" =~ ^[0-9]+$ ]] && ((levels >= 3)) || fail "expected at least 3 levels, got '$levels'"
    rows="$(grep -cE '^ +[0-9]+ +[0-9]+ +[0-9]+ ' stdout || true)"
    [[ "$rows" == "$levels" ]] || fail "the level table has $rows rows for $levels levels"
    grep -qE '^total: [1-9][0-9]* bricks, [1-9][0-9]* samples' stdout || fail "no totals line"
    [[ "$(sed -n 's/^file size: \([0-9]*\) bytes$/\1/p' stdout)" == "$(size_of ssdiffusion.bkm)" ]] ||
        fail "file size line does not match the file"
fi

# -maxerror trades accuracy for size.
run "$brickmake" -maxerror 0.02 ssdiffusion.ptc coarse.bkm
if expect_rc 0 "-maxerror 0.02"; then
    small="$(size_of coarse.bkm)"
    big="$(size_of ssdiffusion.bkm)"
    ((small < big)) || fail "-maxerror 0.02 gave $small bytes, not fewer than $big at 0.002"
fi

# ---------------------------------------------------------------------------
# The map reproduces the cloud: brickinfo -lookup evaluates it at every input
# point (with its normal and its radius as the filter radius).
run "$brickmake" synth.ptc synth.bkm
expect_rc 0 "brickmake synth" || true
run "$brickinfo" -info 0 synth.bkm -lookup synth.ptc looked.ptc -compare 1
if expect_rc 0 "brickinfo -lookup -compare 1"; then
    [[ "$(points looked.ptc)" == 20000 ]] || fail "looked.ptc should have 20000 points"
    has_channel looked.ptc "color _radiance_t" || fail "looked.ptc lacks _radiance_t"
    has_channel looked.ptc "float _area" || fail "looked.ptc lacks _area"
    grep -q ' 0 without data' stdout || fail "some lookups found no data: $out"
    rms="$(compare_field _radiance_t rms)"
    max="$(compare_field _radiance_t max)"
    # Bounds: pruning keeps every dropped sample within about -maxerror
    # (0.002) of the data that serves the lookup, and the finest samples are
    # area-weighted means over about one sample spacing s = 0.037 of
    # E = max(0, N.L) + 0.2, whose slope on the unit sphere is at most 1 per
    # unit: RMS below maxerror, no point off by more than s / 2 = 0.018
    # (measured: 0.0007 and 0.006).
    less_than "$rms" 0.002 || fail "_radiance_t RMS difference '$rms' is not below -maxerror 0.002"
    less_than "$max" 0.018 || fail "_radiance_t largest difference '$max' is not below 0.018"
    # The area channel is a constant: reproduced to float precision.
    less_than "$(compare_field _area rms)" 1e-6 || fail "_area RMS '$(compare_field _area rms)'"
fi
# ptfilter's output through the PRMan-syntax maps: RMS within each map's
# -maxerror (measured: 0.0004 at 0.002, 0.0012 at 0.02).
run "$brickinfo" -info 0 ssdiffusion.bkm -lookup ssdiffusion.ptc looked_ssd.ptc -compare 1
if expect_rc 0 "-lookup on the ssdiffusion map"; then
    rms="$(compare_field _ssdiffusion rms)"
    less_than "$rms" 0.002 || fail "_ssdiffusion RMS '$rms' is not below -maxerror 0.002"
fi
run "$brickinfo" -info 0 coarse.bkm -lookup ssdiffusion.ptc looked_coarse.ptc -compare 1
if expect_rc 0 "-lookup on the coarse map"; then
    coarse_rms="$(compare_field _ssdiffusion rms)"
    less_than "$coarse_rms" 0.02 || fail "_ssdiffusion RMS '$coarse_rms' is not below -maxerror 0.02"
    less_than "$rms" "$coarse_rms" || fail "the -maxerror 0.002 map ($rms) is not closer than the 0.02 one ($coarse_rms)"
fi
# A fixed filter radius and thread counts do not change anything.
run "$brickinfo" -info 0 synth.bkm -lookup synth.ptc l1.ptc -filterradius 0 -threads 1
expect_rc 0 "-filterradius 0 -threads 1" || true
run "$brickinfo" -info 0 synth.bkm -lookup synth.ptc l2.ptc -filterradius 0 -threads 2
expect_rc 0 "-filterradius 0 -threads 2" && { cmp -s l1.ptc l2.ptc || fail "-lookup differs between 1 and 2 threads"; }

# ---------------------------------------------------------------------------
# Pictures.
run "$brickinfo" -info 0 ssdiffusion.bkm -picture level.png
if expect_rc 0 "-picture"; then
    is_png level.png || fail "level.png is not a PNG"
    (($(size_of level.png) > 2000)) || fail "level.png is only $(size_of level.png) bytes"
    [[ "$out" == *"wrote level.png: "*"pixels with data"* ]] || fail "-picture report: $out"
    if command -v oiiotool >/dev/null; then
        oiiotool --info level.png 2>&1 | grep -Eq '512 x +512' || fail "oiiotool: $(oiiotool --info level.png 2>&1)"
    fi
fi
run "$brickinfo" -info 0 ssdiffusion.bkm -picture 'slice.PNG' -slice y 0.2 -size 200 -channel _ssdiffusion
if expect_rc 0 "-picture -slice"; then
    is_png slice.PNG || fail "slice.PNG is not a PNG"
    [[ "$out" == *"200 x 200"* ]] || fail "-size 200 not honoured: $out"
fi
run "$brickinfo" -info 0 ssdiffusion.bkm -picture l2.png -level 2 -axis -x -tree 1
expect_rc 0 "-level 2 -axis -x -tree 1" && { is_png l2.png || fail "l2.png is not a PNG"; }
run "$brickinfo" ssdiffusion.bkm -picture bad.jpg
expect_rc 2 "-picture bad.jpg" || true
run "$brickinfo" ssdiffusion.bkm -picture deep.png -level 30
expect_rc 1 "-level 30" && [[ "$err" == *"deeper than the map"* ]] || fail "-level 30 message: $err"
run "$brickinfo" ssdiffusion.bkm -picture ch.png -channel nope
expect_rc 1 "-channel nope" && [[ "$err" == *"'nope'"* ]] || fail "-channel nope message: $err"
run "$brickinfo" ssdiffusion.bkm -level 2
expect_rc 2 "-level without -picture" || true
[[ ! -e deep.png && ! -e ch.png ]] || fail "a failed picture left a file"

# ---------------------------------------------------------------------------
# -newer 1 skips an up-to-date map, rebuilds a stale one.
before="$(mtime_of synth.bkm)"
sleep 0.05
run "$brickmake" -newer 1 synth.ptc synth.bkm
if expect_rc 0 "-newer 1"; then
    [[ "$(mtime_of synth.bkm)" == "$before" ]] || fail "-newer 1 rewrote an up-to-date map"
    [[ "$out" == *"nothing to do"* ]] || fail "-newer 1 did not say so: $out"
fi
touch synth.ptc
run "$brickmake" -newer 1 synth.ptc synth.bkm
expect_rc 0 "-newer 1, stale" && { [[ "$(mtime_of synth.bkm)" != "$before" ]] || fail "-newer 1 did not rebuild a stale map"; }

# Frame patterns in every path.
cp synth.ptc s.0007.ptc
run "$brickmake" -frame 7 's.####.ptc' 'm.$F4.bkm'
expect_rc 0 "-frame 7" && { [[ -s m.0007.bkm ]] || fail "-frame 7 did not write m.0007.bkm"; }
run "$brickinfo" -frame 7 'm.%04d.bkm'
expect_rc 0 "brickinfo -frame 7" || true
run "$brickmake" 's.####.ptc' m.bkm
expect_rc 2 "pattern without -frame" && [[ "$err" == *"-frame"* ]] || fail "pattern without -frame: $err"

# The provenance quotes what a shell would need quoted.
cp synth.ptc 'with space.ptc'
run "$brickmake" -maxdepth 3 'with space.ptc' quoted.bkm
if expect_rc 0 "input name with a space"; then
    run "$brickinfo" quoted.bkm
    grep -qF "provenance: brickmake $("$brickmake" --version | sed -n '1s/.* //p') -maxdepth 3 'with space.ptc' quoted.bkm" stdout ||
        fail "provenance does not quote the file name: $(grep provenance stdout)"
    grep -q '^maxdepth: 3$' stdout || fail "-maxdepth 3 not recorded"
fi

# Channels, several inputs, -threads, -progress.
run "$brickmake" -channels _radiance_t synth.ptc rad.bkm
if expect_rc 0 "-channels _radiance_t"; then
    run "$brickinfo" rad.bkm
    grep -q '^channels: 1 ' stdout || fail "-channels _radiance_t kept $(grep '^channels' stdout)"
fi
run "$brickmake" -channels _radiance_t,nope synth.ptc nope.bkm
expect_rc 1 "unknown channel" && [[ "$err" == "brickmake ERROR: "*"nope"* ]] || fail "unknown channel message: $err"
run "$brickmake" -channels _radiance_t,,_area synth.ptc nope.bkm
expect_rc 2 "empty channel name" || true
run "$ptsynth" -n 3000 -size 0.5 -shape plane other.ptc
run "$brickmake" synth.ptc other.ptc both.bkm
expect_rc 0 "two inputs" && {
    run "$brickinfo" -info 0 both.bkm -lookup other.ptc both.ptc
    grep -q ' 0 without data' stdout || fail "the second input is missing from both.bkm: $out"
}
# The thread count changes nothing but the provenance (the command line).
run "$brickmake" -threads 1 synth.ptc t1.bkm
run "$brickmake" -threads 2 -progress 1 synth.ptc t2.bkm
if expect_rc 0 "-threads 2 -progress 1"; then
    "$brickinfo" -info 0 t1.bkm -lookup synth.ptc t1.ptc -filterradius 0 >/dev/null || fail "lookup on t1.bkm"
    "$brickinfo" -info 0 t2.bkm -lookup synth.ptc t2.ptc -filterradius 0 >/dev/null || fail "lookup on t2.bkm"
    cmp -s t1.ptc t2.ptc || fail "-threads 1 and 2 maps give different lookups"
    diff <("$brickinfo" t1.bkm | grep -Ev '^(file|file size|provenance):') \
        <("$brickinfo" t2.bkm | grep -Ev '^(file|file size|provenance):') >/dev/null ||
        fail "-threads 1 and 2 maps differ in brickinfo's report"
    [[ "$(grep ALF_PROGRESS stdout | tail -n 1)" == "ALF_PROGRESS 100%" ]] || fail "no ALF_PROGRESS 100%"
    grep -q '^brickmake: t2.bkm: 20000 points, [0-9]* bricks.*bytes$' stdout || fail "-progress 1 summary: $out"
fi
run "$brickmake" -radiusscale 0.5 synth.ptc rs.bkm
expect_rc 0 "-radiusscale 0.5" && { [[ "$err" == "brickmake WARNING: "*"radiusscale"* ]] || fail "no -radiusscale warning: $err"; }

# ---------------------------------------------------------------------------
# Errors: exit codes and messages; existing outputs untouched; no temporaries.
run "$brickmake" -bogus synth.ptc x.bkm
expect_rc 2 "unknown option" && [[ "$err" == "brickmake ERROR: unknown option -bogus"* ]] || fail "unknown option: $err"
run "$brickinfo" -bogus synth.bkm
expect_rc 2 "brickinfo unknown option" || true
run "$brickmake" synth.ptc
expect_rc 2 "one file" || true
for bad in "-maxdepth 21" "-maxerror -1" "-radiusscale 0" "-newer 2" "-ignorenormals x"; do
    # shellcheck disable=SC2086
    run "$brickmake" $bad synth.ptc x.bkm
    expect_rc 2 "$bad" || true
done
run "$brickmake" missing.ptc x.bkm
expect_rc 1 "missing input" && [[ "$err" == "brickmake ERROR: "*"missing.ptc"* ]] || fail "missing input message: $err"
[[ ! -e x.bkm ]] || fail "a failed brickmake left x.bkm"

cp synth.bkm keep.bkm
run "$brickmake" missing.ptc keep.bkm
expect_rc 1 "missing input over an existing map" || true
run "$brickmake" -channels nope synth.ptc keep.bkm
expect_rc 1 "bad channel over an existing map" || true
cmp -s synth.bkm keep.bkm || fail "a failed brickmake changed an existing map"
cp looked.ptc keep.ptc
run "$brickinfo" synth.bkm -lookup missing.ptc keep.ptc
expect_rc 1 "-lookup missing cloud" && [[ "$err" == *"missing.ptc"* ]] || fail "-lookup missing cloud: $err"
cmp -s looked.ptc keep.ptc || fail "a failed -lookup changed an existing output"

head -c 20000 /dev/urandom > corrupt.bkm
run "$brickinfo" corrupt.bkm
expect_rc 1 "corrupt .bkm" && [[ "$err" == "brickinfo ERROR: "*"corrupt.bkm"* ]] || fail "corrupt .bkm message: $err"
head -c "$(($(size_of synth.bkm) / 2))" synth.bkm > truncated.bkm
run "$brickinfo" truncated.bkm
expect_rc 1 "truncated .bkm" && [[ "$err" == "brickinfo ERROR: "*"truncated.bkm"* ]] || fail "truncated .bkm message: $err"
head -c 100 synth.bkm > short.bkm
run "$brickinfo" short.bkm
expect_rc 1 "header-only .bkm" || true
run "$brickinfo" missing.bkm
expect_rc 1 "missing .bkm" && [[ "$err" == *"missing.bkm"* ]] || fail "missing .bkm message: $err"
run "$brickinfo" synth.ptc
expect_rc 1 "a .ptc given to brickinfo" || true
no_temporaries

finish_checks brickmake
