#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# CLI test of ptfilter -ssdiffusion: output, progress, exit codes, error lines,
# atomic and in-place output, merging, thread independence, .ply output.
# Needs SSS_BIN_DIR (the folder with ptfilter, ptsynth and ptinfo).
#
# Every check runs; failures are listed and the script exits 1 at the end.
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
ptfilter="$bin/ptfilter"
ptsynth="$bin/ptsynth"
ptinfo="$bin/ptinfo"
for tool in "$ptfilter" "$ptsynth" "$ptinfo"; do
    [[ -x "$tool" ]] || { echo "FAIL: missing executable $tool" >&2; exit 1; }
done
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_ptfilter.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"

# shellcheck source=lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
# shellcheck source=checks.sh
source "$(dirname "${BASH_SOURCE[0]}")/checks.sh"

# Entries of a folder other than the given names (temporaries, stray outputs).
extra_files() { # folder name...
    local folder="$1"
    shift
    local f base keep
    for f in "$folder"/* "$folder"/.[!.]*; do
        [[ -e "$f" ]] || continue
        base="$(basename "$f")"
        keep=0
        for name in "$@"; do [[ "$base" == "$name" ]] && keep=1; done
        [[ $keep == 1 ]] || echo "$base"
    done
}

# ---------------------------------------------------------------------------
# Inputs.
run "$ptsynth" -n 20000 -size 50 in.ptc
expect_rc 0 "ptsynth in.ptc" || exit 1
run "$ptsynth" -n 10000 -size 30 -light 1 0 0 small.ptc
expect_rc 0 "ptsynth small.ptc" || exit 1
[[ "$(points in.ptc)" == 20000 ]] || { fail "in.ptc should have 20000 points"; exit 1; }

# ---------------------------------------------------------------------------
# A normal run.
run "$ptfilter" -ssdiffusion -material skin1 -unitlength 1 in.ptc out.ptc
if expect_rc 0 "basic run"; then
    [[ "$(points out.ptc)" == 20000 ]] || fail "out.ptc should have 20000 points: $("$ptinfo" out.ptc 2>&1)"
    has_channel out.ptc "color _ssdiffusion" || fail "out.ptc lacks 'color _ssdiffusion'"
    if has_channel out.ptc "color _radiance_t"; then fail "out.ptc should hold only _ssdiffusion by default"; fi
    [[ -z "$out" ]] || fail "a run without -progress printed to stdout: $out"
    [[ -z "$err" ]] || fail "a clean run printed to stderr: $err"
fi
[[ -z "$(extra_files "$work" in.ptc small.ptc out.ptc stdout stderr)" ]] ||
    fail "stray files after a run: $(extra_files "$work" in.ptc small.ptc out.ptc stdout stderr)"

# The output's values are plausible: skin1 red albedo 0.436, light from +z on
# a sphere (mean irradiance 0.25), so the red mean is about 0.1 and max < 0.45.
stats="$("$ptinfo" out.ptc)"
red_line="$(grep -A1 'color _ssdiffusion' <<<"$stats" | sed -n 2p)"
red_mean="$(sed -n 's/.*mean \([^ ]*\).*/\1/p' <<<"$red_line")"
red_max="$(sed -n 's/.*max \([^ ]*\).*/\1/p' <<<"$red_line")"
awk -v m="$red_mean" -v x="$red_max" 'BEGIN { exit !(m > 0.09 && m < 0.12 && x > 0.3 && x < 0.45) }' ||
    fail "implausible _ssdiffusion red statistics: $red_line"

# -filter ssdiffusion is the same filter.
run "$ptfilter" -filter ssdiffusion -material skin1 -unitlength 1 in.ptc out_filter.ptc
if expect_rc 0 "-filter ssdiffusion"; then
    cmp -s out.ptc out_filter.ptc || fail "-filter ssdiffusion output differs from -ssdiffusion"
fi

# -keepchannels 1 copies the inputs.
run "$ptfilter" -ssdiffusion -keepchannels 1 in.ptc out_keep.ptc
if expect_rc 0 "-keepchannels 1"; then
    has_channel out_keep.ptc "color _radiance_t" || fail "-keepchannels 1 lost _radiance_t"
    has_channel out_keep.ptc "float _area" || fail "-keepchannels 1 lost _area"
    has_channel out_keep.ptc "color _ssdiffusion" || fail "-keepchannels 1 lacks _ssdiffusion"
fi

# ---------------------------------------------------------------------------
# -progress 1: material values and ALF_PROGRESS lines ending at 100 %.
run "$ptfilter" -ssdiffusion -material skin1 -progress 1 in.ptc out_progress.ptc
if expect_rc 0 "-progress 1"; then
    grep -q 'ALF_PROGRESS' "$work/stdout" || fail "-progress 1 printed no ALF_PROGRESS line"
    last="$(grep 'ALF_PROGRESS' "$work/stdout" | tail -n 1)"
    [[ "$last" == "ALF_PROGRESS 100%" ]] || fail "last progress line is '$last'"
    grep -v 'ALF_PROGRESS' "$work/stdout" | grep -q 'albedo' || fail "-progress 1 does not print the albedo"
    grep -q 'diffusemeanfreepath' "$work/stdout" || fail "-progress 1 does not print the dmfp"
    grep -Eq 'albedo +0\.43' "$work/stdout" || fail "-progress 1 albedo is not skin1's (0.436): $out"
    # Percentages are well formed and never go down.
    if grep 'ALF_PROGRESS' "$work/stdout" | grep -Evq '^ALF_PROGRESS [0-9]{1,3}%$'; then
        fail "malformed ALF_PROGRESS line: $(grep 'ALF_PROGRESS' "$work/stdout" | grep -Ev '^ALF_PROGRESS [0-9]{1,3}%$' | head -n 1)"
    fi
    grep 'ALF_PROGRESS' "$work/stdout" | sed 's/[^0-9]//g' |
        awk 'NR > 1 && $1 < prev { bad = 1 } { prev = $1 } END { exit bad }' ||
        fail "ALF_PROGRESS percentages go down"
    cmp -s out.ptc out_progress.ptc || fail "-progress changed the output"
fi

# ---------------------------------------------------------------------------
# Usage errors: exit 2, "ptfilter ERROR:" on stderr, no output file.
usage_error() { # label args...
    local label="$1"
    shift
    rm -f bad.ptc
    run "$ptfilter" "$@"
    expect_rc 2 "$label" || true
    [[ "$err" == *"ptfilter ERROR:"* ]] || fail "$label: stderr lacks 'ptfilter ERROR:': $err"
    if [[ -e bad.ptc ]]; then fail "$label: created an output file"; fi
    [[ -z "$(extra_files "$work" in.ptc small.ptc out.ptc out_filter.ptc out_keep.ptc out_progress.ptc stdout stderr)" ]] ||
        fail "$label: left files behind: $(extra_files "$work" in.ptc small.ptc out.ptc out_filter.ptc out_keep.ptc out_progress.ptc stdout stderr)"
}
usage_error "-maxsolidangle without value" -ssdiffusion -maxsolidangle in.ptc bad.ptc
usage_error "-maxsolidangle abc" -ssdiffusion -maxsolidangle abc in.ptc bad.ptc
usage_error "-maxsolidangle 0" -ssdiffusion -maxsolidangle 0 in.ptc bad.ptc
usage_error "-maxsolidangle -1" -ssdiffusion -maxsolidangle -1 in.ptc bad.ptc
usage_error "-material nosuch" -ssdiffusion -material nosuch in.ptc bad.ptc
[[ "$err" == *nosuch* ]] || fail "-material nosuch: message does not name it: $err"
usage_error "-unknownopt" -ssdiffusion -unknownopt in.ptc bad.ptc
[[ "$err" == *unknownopt* ]] || fail "-unknownopt: message does not name it: $err"
usage_error "-unitlength 0" -ssdiffusion -unitlength 0 in.ptc bad.ptc
usage_error "-threads x" -ssdiffusion -threads x in.ptc bad.ptc
usage_error "no input files" -ssdiffusion bad.ptc
usage_error "no files at all" -ssdiffusion
usage_error "no filter option" in.ptc bad.ptc
usage_error "-filter nosuch" -filter nosuch in.ptc bad.ptc
usage_error "-profile nosuch" -ssdiffusion -profile nosuch in.ptc bad.ptc
usage_error "-criterion nosuch" -ssdiffusion -criterion nosuch in.ptc bad.ptc
usage_error "-albedo with two values" -ssdiffusion -albedo 0.5 0.5 in.ptc bad.ptc
usage_error "-scattering and -albedo" -ssdiffusion -scattering 1 1 1 -albedo 0.5 0.5 0.5 in.ptc bad.ptc

# A usage error leaves an existing output untouched.
cp out.ptc keep_me.ptc
run "$ptfilter" -ssdiffusion -maxsolidangle 0 in.ptc keep_me.ptc
expect_rc 2 "usage error onto an existing output" || true
cmp -s out.ptc keep_me.ptc || fail "a usage error changed an existing output file"
rm -f keep_me.ptc

# ---------------------------------------------------------------------------
# Impossible material values. Observed: -albedo 1.5 and -diffusemeanfreepath 0
# are value errors (exit 1: the numbers parse, the physics is rejected);
# -ior 0 is rejected by the option parser (exit 2, "must be > 0").
bad_value() { # label args...
    local label="$1"
    shift
    rm -f bad.ptc
    run "$ptfilter" -ssdiffusion "$@" in.ptc bad.ptc
    [[ "$rc" == 1 || "$rc" == 2 ]] || fail "$label: expected exit 1 or 2, got $rc ($err)"
    [[ "$err" == *"ptfilter ERROR:"* ]] || fail "$label: stderr lacks 'ptfilter ERROR:': $err"
    if [[ -e bad.ptc ]]; then fail "$label: created an output file"; fi
    echo "note: $label -> exit $rc: $err"
}
bad_value "-albedo 1.5 1 1" -albedo 1.5 1 1
bad_value "-albedo -0.1 0.5 0.5" -albedo -0.1 0.5 0.5
bad_value "-diffusemeanfreepath 0 1 1" -diffusemeanfreepath 0 1 1
bad_value "-diffusemeanfreepath -1 1 1" -diffusemeanfreepath -1 1 1
bad_value "-ior 0" -ior 0
bad_value "-absorption -1 0 0" -absorption -1 0 0

# ---------------------------------------------------------------------------
# Runtime errors: exit 1, "ptfilter ERROR:" naming the file, no output.
runtime_error() { # label file args...
    local label="$1" file="$2"
    shift 2
    rm -f bad.ptc
    run "$ptfilter" -ssdiffusion "$@" bad.ptc
    expect_rc 1 "$label" || true
    [[ "$err" == *"ptfilter ERROR:"* ]] || fail "$label: stderr lacks 'ptfilter ERROR:': $err"
    [[ "$err" == *"$file"* ]] || fail "$label: the error does not name $file: $err"
    if [[ -e bad.ptc ]]; then fail "$label: created an output file"; fi
}
runtime_error "missing input" missing.ptc missing.ptc
head -c 300 in.ptc >truncated.ptc
runtime_error "truncated input" truncated.ptc truncated.ptc
head -c 4096 /dev/urandom >garbage.ptc
runtime_error "garbage input" garbage.ptc garbage.ptc
printf 'not a point cloud at all\n' >text.ply
runtime_error "garbage .ply input" text.ply text.ply
runtime_error "truncated second input" truncated.ptc in.ptc truncated.ptc
runtime_error "missing radiance channel" in.ptc -radiancechannel nosuch in.ptc
[[ "$err" == *nosuch* ]] || fail "missing radiance channel: the error does not name the channel: $err"
runtime_error "missing albedo channel" in.ptc -albedo fromfile in.ptc
[[ "$err" == *_albedo* ]] || fail "missing albedo channel: the error does not name _albedo: $err"
# Output into a folder that does not exist.
run "$ptfilter" -ssdiffusion in.ptc no/such/folder/out.ptc
expect_rc 1 "output into a missing folder" || true
[[ "$err" == *"ptfilter ERROR:"*"no/such/folder"* ]] || fail "missing output folder not named: $err"
rm -f truncated.ptc garbage.ptc text.ply

# ---------------------------------------------------------------------------
# In place: input and output the same file.
mkdir inplace
cp in.ptc inplace/cloud.ptc
run "$ptfilter" -ssdiffusion -keepchannels 1 inplace/cloud.ptc inplace/cloud.ptc
if expect_rc 0 "in-place run"; then
    has_channel inplace/cloud.ptc "color _ssdiffusion" || fail "in-place run: no _ssdiffusion in the file"
    [[ "$(points inplace/cloud.ptc)" == 20000 ]] || fail "in-place run: wrong point count"
fi
[[ -z "$(extra_files inplace cloud.ptc)" ]] || fail "in-place run left files: $(extra_files inplace cloud.ptc)"
cp inplace/cloud.ptc before.ptc
run "$ptfilter" -ssdiffusion -radiancechannel nosuch inplace/cloud.ptc inplace/cloud.ptc
expect_rc 1 "failing in-place run" || true
cmp -s before.ptc inplace/cloud.ptc || fail "a failing in-place run changed the file"
[[ -z "$(extra_files inplace cloud.ptc)" ]] || fail "failing in-place run left files: $(extra_files inplace cloud.ptc)"
# A plain in-place run without -keepchannels also works (the file then has
# only _ssdiffusion, so a second run fails cleanly and leaves it alone).
cp in.ptc inplace/plain.ptc
run "$ptfilter" -ssdiffusion inplace/plain.ptc inplace/plain.ptc
if expect_rc 0 "plain in-place run"; then
    has_channel inplace/plain.ptc "color _ssdiffusion" || fail "plain in-place run: no _ssdiffusion"
    cp inplace/plain.ptc before.ptc
    run "$ptfilter" -ssdiffusion inplace/plain.ptc inplace/plain.ptc
    expect_rc 1 "second in-place run without _radiance_t" || true
    cmp -s before.ptc inplace/plain.ptc || fail "a failing second in-place run changed the file"
fi
[[ -z "$(extra_files inplace cloud.ptc plain.ptc)" ]] || fail "in-place runs left files: $(extra_files inplace cloud.ptc plain.ptc)"
rm -rf inplace before.ptc

# ---------------------------------------------------------------------------
# Several inputs are merged.
run "$ptfilter" -ssdiffusion in.ptc small.ptc merged.ptc
if expect_rc 0 "merge"; then
    [[ "$(points merged.ptc)" == 30000 ]] || fail "merged output should have 30000 points, has '$(points merged.ptc)'"
fi
run "$ptfilter" -ssdiffusion small.ptc in.ptc small.ptc merged3.ptc
if expect_rc 0 "merge of three"; then
    [[ "$(points merged3.ptc)" == 40000 ]] || fail "merged output of three should have 40000 points"
fi
rm -f merged.ptc merged3.ptc

# ---------------------------------------------------------------------------
# --help and --version.
run "$ptfilter" --help
expect_rc 0 "--help" || true
[[ "$out" == *"usage: ptfilter"* ]] || fail "--help lacks the usage line"
[[ "$out" == *"-maxsolidangle"* && "$out" == *"skin1"* ]] || fail "--help lacks options or materials"
[[ -z "$err" ]] || fail "--help wrote to stderr: $err"
run "$ptfilter" -h
expect_rc 0 "-h" || true
[[ "$out" == *"usage: ptfilter"* ]] || fail "-h lacks the usage line"
run "$ptfilter" --version
expect_rc 0 "--version" || true
[[ "$out" == "ptfilter "* ]] || fail "--version output starts with: ${out:0:80}"
[[ -z "$err" ]] || fail "--version wrote to stderr: $err"

# ---------------------------------------------------------------------------
# Thread count does not change the output.
run "$ptfilter" -ssdiffusion -threads 1 in.ptc t1.ptc
expect_rc 0 "-threads 1" || true
run "$ptfilter" -ssdiffusion -threads 2 in.ptc t2.ptc
expect_rc 0 "-threads 2" || true
run "$ptfilter" -ssdiffusion -threads 0 in.ptc t0.ptc
expect_rc 0 "-threads 0" || true
cmp -s t1.ptc t2.ptc || fail "-threads 1 and -threads 2 outputs differ"
cmp -s t1.ptc t0.ptc || fail "-threads 1 and -threads 0 outputs differ"
run "$ptfilter" -ssdiffusion -criterion bbox -threads 1 in.ptc b1.ptc
run "$ptfilter" -ssdiffusion -criterion bbox -threads 2 in.ptc b2.ptc
cmp -s b1.ptc b2.ptc || fail "-criterion bbox: -threads 1 and 2 outputs differ"
rm -f t0.ptc t2.ptc b1.ptc b2.ptc

# ---------------------------------------------------------------------------
# .ply output (and input).
run "$ptfilter" -ssdiffusion in.ptc out.ply
if expect_rc 0 ".ply output"; then
    [[ "$(points out.ply)" == 20000 ]] || fail "out.ply: ptinfo does not report 20000 points: $("$ptinfo" out.ply 2>&1 | head -n 5)"
    has_channel out.ply "color _ssdiffusion" || fail "out.ply lacks _ssdiffusion"
    "$ptinfo" out.ply | grep -qi 'ply' || fail "ptinfo does not call out.ply a .ply file"
fi
run "$ptsynth" -n 5000 -size 20 in.ply
run "$ptfilter" -ssdiffusion in.ply out2.ptc
if expect_rc 0 ".ply input"; then
    [[ "$(points out2.ptc)" == 5000 ]] || fail ".ply input: wrong point count"
fi
rm -f out.ply in.ply out2.ptc

# ---------------------------------------------------------------------------
# Other options are accepted.
run "$ptfilter" -ssdiffusion -albedo 0.8 0.5 0.3 -diffusemeanfreepath 5 2 1 -ior 1.4 \
    -profile burley -maxsolidangle 0.5 -compress 1 -ptcversion 2 in.ptc opts.ptc
if expect_rc 0 "albedo/dmfp options"; then
    [[ "$(points opts.ptc)" == 20000 ]] || fail "albedo/dmfp options: wrong point count"
fi
run "$ptfilter" -ssdiffusion -scattering 1 1 1 -absorption 0.1 0.1 0.1 -profile better \
    -criterion centroid -organize 1 in.ptc opts.ptc
expect_rc 0 "scattering/absorption options" || true
run "$ptfilter" -ssdiffusion -exact small.ptc exact.ptc
expect_rc 0 "-exact" || true
rm -f opts.ptc exact.ptc

# -progress 2: also the values at a glance (min, mean, max and 8 points), as
# PRMan's ptfilter prints a sample of them.
run "$ptfilter" -ssdiffusion -progress 2 small.ptc sample.ptc
if expect_rc 0 "-progress 2"; then
    n="$(points small.ptc)"
    grep -Eq "^ptfilter: _ssdiffusion of $n points: min [^,]+, mean [^,]+, max " "$work/stdout" ||
        fail "-progress 2 prints no summary of the values: $out"
    [[ "$(grep -Ec '^ptfilter: _ssdiffusion of point [0-9]+: [0-9.e+-]+ [0-9.e+-]+ [0-9.e+-]+$' "$work/stdout")" == 8 ]] ||
        fail "-progress 2 prints no sample of 8 points: $out"
    grep -q "^ptfilter: _ssdiffusion of point $((n - 1)): " "$work/stdout" ||
        fail "-progress 2's sample does not end at the last point"
fi
run "$ptfilter" -ssdiffusion -progress 1 small.ptc sample.ptc
grep -q '_ssdiffusion of' "$work/stdout" && fail "-progress 1 prints the sample of values"
rm -f sample.ptc

# -frame expands frame patterns in every file name.
cp small.ptc small.0042.ptc
run "$ptfilter" -ssdiffusion -frame 42 small.####.ptc 'framed.%04d.ptc'
if expect_rc 0 "-frame 42"; then
    [[ -s framed.0042.ptc ]] || fail "-frame 42 did not write framed.0042.ptc"
fi
run "$ptfilter" -ssdiffusion small.####.ptc framed.ptc
expect_rc 2 "pattern without -frame" || true
rm -f small.0042.ptc framed.0042.ptc

finish_checks ptfilter
