#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# CLI test of ptfilter -part K/N and -merge: the merged cloud is byte-identical
# to a single run with the same options, for several N, thread counts, output
# formats and options; every bad part set is refused with one ERROR line and
# nothing written.
# Needs SSS_BIN_DIR (the folder with ptfilter, ptsynth and ptinfo).
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
ptfilter="$bin/ptfilter"
ptsynth="$bin/ptsynth"
ptinfo="$bin/ptinfo"
for tool in "$ptfilter" "$ptsynth" "$ptinfo"; do
    [[ -x "$tool" ]] || { echo "FAIL: missing executable $tool" >&2; exit 1; }
done
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_ptfilter_part.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"

# shellcheck source=lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
# shellcheck source=checks.sh
source "$(dirname "${BASH_SOURCE[0]}")/checks.sh"

run "$ptsynth" -n 9000 -size 40 in.ptc
expect_rc 0 "ptsynth in.ptc" || exit 1
run "$ptsynth" -shape box -n 1500 -size 20 -light 1 0 0 box.ptc
expect_rc 0 "ptsynth box.ptc" || exit 1

# split_run N THREADS OUT [ptfilter options...]: runs the N parts (threads
# alternating between THREADS and 1) then the merge; sets rc of the merge.
split_run() {
    local n="$1" threads="$2" outfile="$3"
    shift 3
    local parts=() k
    for ((k = 1; k <= n; k++)); do
        run "$ptfilter" -ssdiffusion "$@" -threads $((k % 2 ? threads : 1)) -part "$k/$n" \
            in.ptc "part$k.ptpart"
        expect_rc 0 "part $k/$n ($*)" || return 1
        [[ -z "$out$err" ]] || fail "part $k/$n printed: $out $err"
        parts+=("part$k.ptpart")
    done
    # Parts in reverse order: the order given does not matter.
    local reversed=()
    for ((k = n; k >= 1; k--)); do reversed+=("part$k.ptpart"); done
    run "$ptfilter" -merge "${reversed[@]}" "$outfile"
    expect_rc 0 "merge of $n parts ($*)"
}

# ---------------------------------------------------------------------------
# Byte-identical to the single run.
check_split() { # LABEL "N..." "THREADS..." OPTIONS...: for those N and thread counts
    local label="$1" counts="$2" threads="$3"
    shift 3
    "$ptfilter" -ssdiffusion "$@" -threads 2 in.ptc "single.$label.ptc" ||
        { fail "$label: single run failed"; return; }
    local n t
    for n in $counts; do
        for t in $threads; do
            split_run "$n" "$t" "merged.$label.ptc" "$@" || continue
            cmp -s "single.$label.ptc" "merged.$label.ptc" ||
                fail "$label: $n parts at $t threads differ from the single run"
        done
    done
    rm -f part*.ptpart
}
check_split default "1 2 3 5" "1 2" -material skin1 -unitlength 0.1
check_split options "3" "2" -material marble -maxsolidangle 0.3 -profile better -keepchannels 1 \
    -compress 1 -ptcversion 2
check_split bbox "2" "2" -criterion bbox -maxsolidangle 0.5
[[ "$(points merged.default.ptc)" == 9000 ]] || fail "merged cloud should have 9000 points"

# .ply output, -exact, and several inputs merged before the split.
"$ptsynth" -n 1000 -size 10 tiny2.ptc >/dev/null
"$ptfilter" -ssdiffusion -exact tiny2.ptc box.ptc single.exact.ply
k=0 parts=()
for ((k = 1; k <= 3; k++)); do
    "$ptfilter" -ssdiffusion -exact -part "$k/3" tiny2.ptc box.ptc "px$k.ptpart"
    parts+=("px$k.ptpart")
done
run "$ptfilter" -merge "${parts[@]}" merged.exact.ply
expect_rc 0 "merge -exact to .ply" && { cmp -s single.exact.ply merged.exact.ply ||
    fail "-exact split into .ply differs from the single run"; }

# More parts than it takes: empty parts are fine.
"$ptsynth" -n 5 tiny.ptc >/dev/null
"$ptfilter" -ssdiffusion tiny.ptc single.tiny.ptc
parts=()
for ((k = 1; k <= 8; k++)); do
    "$ptfilter" -ssdiffusion -part "$k/8" tiny.ptc "pt$k.ptpart"
    parts+=("pt$k.ptpart")
done
run "$ptfilter" -merge "${parts[@]}" merged.tiny.ptc
expect_rc 0 "merge of 8 parts of 5 points" && { cmp -s single.tiny.ptc merged.tiny.ptc ||
    fail "8 parts of 5 points differ from the single run"; }

# Progress, frame patterns and -newer work as in a single run.
run "$ptfilter" -ssdiffusion -progress 1 -part 2/3 -frame 7 in.ptc p.%04d.part2.ptpart
expect_rc 0 "-progress 1 -frame 7 -part 2/3"
[[ -f p.0007.part2.ptpart ]] || fail "-frame 7 did not expand the part file name"
[[ "$out" == *"ALF_PROGRESS 100%"* ]] || fail "-part -progress 1 printed no ALF_PROGRESS 100%: $out"
[[ "$out" == *"part 2/3: points 3000 to 6000 of 9000"* ]] ||
    fail "-part -progress 1 does not say which points: $out"
run "$ptfilter" -ssdiffusion -newer 1 -part 2/3 -frame 7 in.ptc p.####.part2.ptpart
expect_rc 0 "-newer 1 -part" && [[ "$out" == *"nothing to do"* ]] ||
    fail "-newer 1 on an up-to-date part did not skip: $out"
parts=()
for ((k = 1; k <= 2; k++)); do
    "$ptfilter" -ssdiffusion -part "$k/2" in.ptc "q$k.ptpart"
    parts+=("q$k.ptpart")
done
"$ptfilter" -merge "${parts[@]}" newer.ptc
run "$ptfilter" -merge -newer 1 "${parts[@]}" newer.ptc
expect_rc 0 "-merge -newer 1" && [[ "$out" == *"nothing to do"* ]] ||
    fail "-merge -newer 1 on an up-to-date output did not skip: $out"

# ---------------------------------------------------------------------------
# Bad input: exit 2 (usage) or 1, one ERROR line, nothing written.
expect_refused() { # CODE LABEL PATTERN OUTPUT -- command...
    local code="$1" label="$2" pattern="$3" output="$4"
    shift 5
    local before
    before="$(mtime_of "$output")"
    run "$@"
    expect_rc "$code" "$label" || return 0
    [[ "$(head -n 1 <<<"$err")" == "ptfilter ERROR: "*$pattern* ]] ||
        fail "$label: first stderr line is not 'ptfilter ERROR: ...$pattern...': $err"
    [[ "$(grep -c ERROR <<<"$err")" == 1 ]] || fail "$label: more than one ERROR line: $err"
    [[ "$(mtime_of "$output")" == "$before" ]] || fail "$label: $output was changed"
    # No temporary left behind.
    local tmp
    tmp="$(find . -name '.*.tmp' | head -n 1)"
    [[ -z "$tmp" ]] || fail "$label: temporary left: $tmp"
}
for bad in 0/4 5/4 1/0 4 a/b 1/4x -1/4 2/2000000; do
    expect_refused 2 "-part $bad" "expected K/N" bad.ptpart -- \
        "$ptfilter" -ssdiffusion -part "$bad" in.ptc bad.ptpart
done
expect_refused 2 "-part into .ptc" "name it *.ptpart" in.ptc -- \
    "$ptfilter" -ssdiffusion -part 1/2 box.ptc in.ptc
expect_refused 2 "-merge with filter options" "takes no -material" merged.default.ptc -- \
    "$ptfilter" -merge -material skin1 q1.ptpart q2.ptpart merged.default.ptc
expect_refused 2 "-merge -part" "takes no -part" merged.default.ptc -- \
    "$ptfilter" -merge -part 1/2 q1.ptpart q2.ptpart merged.default.ptc
expect_refused 2 "-merge into .ptpart" "is not a point cloud file name" q3.ptpart -- \
    "$ptfilter" -merge q1.ptpart q2.ptpart q3.ptpart

# Part sets that cannot be joined (the output exists and must stay as it is).
cp merged.default.ptc keep.ptc
for ((k = 1; k <= 4; k++)); do
    "$ptfilter" -ssdiffusion -part "$k/4" in.ptc "a$k.ptpart"
done
"$ptfilter" -ssdiffusion -part 3/4 box.ptc other_input.ptpart
"$ptfilter" -ssdiffusion -part 3/4 -maxsolidangle 0.5 in.ptc other_options.ptpart
"$ptfilter" -ssdiffusion -part 3/4 -compress 1 in.ptc other_write.ptpart
"$ptfilter" -ssdiffusion -part 3/5 in.ptc other_count.ptpart
expect_refused 1 "missing part" "missing part 3 of 4" keep.ptc -- \
    "$ptfilter" -merge a1.ptpart a2.ptpart a4.ptpart keep.ptc
expect_refused 1 "part given twice" "part 2/4 given twice" keep.ptc -- \
    "$ptfilter" -merge a1.ptpart a2.ptpart a2.ptpart a4.ptpart keep.ptc
expect_refused 1 "part of another input" "is not from the job of" keep.ptc -- \
    "$ptfilter" -merge a1.ptpart a2.ptpart other_input.ptpart a4.ptpart keep.ptc
expect_refused 1 "part with other options" "is not from the job of" keep.ptc -- \
    "$ptfilter" -merge a1.ptpart a2.ptpart other_options.ptpart a4.ptpart keep.ptc
expect_refused 1 "part with other write options" "is not from the job of" keep.ptc -- \
    "$ptfilter" -merge a1.ptpart a2.ptpart other_write.ptpart a4.ptpart keep.ptc
expect_refused 1 "part of another split" "is not from the job of" keep.ptc -- \
    "$ptfilter" -merge a1.ptpart a2.ptpart other_count.ptpart a4.ptpart keep.ptc
size="$(stat -c %s a3.ptpart)"
head -c $((size / 2)) a3.ptpart >cut.ptpart
expect_refused 1 "truncated part" "cut.ptpart: part file is truncated" keep.ptc -- \
    "$ptfilter" -merge a1.ptpart a2.ptpart cut.ptpart a4.ptpart keep.ptc
head -c 100 a3.ptpart >head.ptpart
expect_refused 1 "part cut in its header" "head.ptpart: not a part file" keep.ptc -- \
    "$ptfilter" -merge a1.ptpart a2.ptpart head.ptpart a4.ptpart keep.ptc
cp a3.ptpart flipped.ptpart
printf '\x55' | dd of=flipped.ptpart bs=1 seek=$((size - 100)) conv=notrunc status=none
expect_refused 1 "damaged part" "part file data is damaged" keep.ptc -- \
    "$ptfilter" -merge a1.ptpart a2.ptpart flipped.ptpart a4.ptpart keep.ptc
expect_refused 1 "a cloud given as a part" "in.ptc: not a part file" keep.ptc -- \
    "$ptfilter" -merge a1.ptpart a2.ptpart in.ptc a4.ptpart keep.ptc
expect_refused 1 "missing part file" "nope.ptpart" keep.ptc -- \
    "$ptfilter" -merge a1.ptpart a2.ptpart nope.ptpart a4.ptpart keep.ptc
cmp -s keep.ptc merged.default.ptc || fail "a refused merge changed its output"
# And the good set still joins.
run "$ptfilter" -merge a4.ptpart a3.ptpart a1.ptpart a2.ptpart four.ptc
expect_rc 0 "merge of a1-a4"
cmp -s four.ptc newer.ptc ||
    fail "a1-a4 do not join into the single run's cloud"

finish_checks ptfilter-part
