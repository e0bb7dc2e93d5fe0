#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# sss-farm on a real Slurm: brings up a throw-away single-node cluster
# (munged, slurmctld, slurmd; everything in a temp folder, tests/farm/cluster.sh)
# and checks, through sss-farm:
#   1. the orbit sequence (scenes/orbit, SSS_QUICK draft settings, frames 1-2),
#      whole chain bake -> filter -> brick -> render (+ the render without sss):
#      clouds and brick maps byte-identical to a local run of the same
#      commands, images within 1e-3 (oiiotool --diff), `status` all done;
#   2. the same with the filter split (--splitpoints 1000 --parts 3: each
#      ~19000-point orbit cloud is filtered in 3 part tasks and merged):
#      byte-identical too, part files removed after the merge;
#   3. a frame whose input is missing (--retries 0): its filter task fails
#      with ptfilter's exit code (Slurm ExitCode 1:0 and `status` "failed
#      (exit 1)", exit 1), its brick task does not run; after the input is
#      made, the re-submission queues that frame only (the other frames'
#      outputs keep their mtime);
#   4. studio frames (1001-1005:2, array 0-2): filter and brick maps
#      byte-identical to local runs; a misspelled option refused at
#      submission (exit 2, nothing queued); a frame whose input appears only
#      after its first attempt failed is requeued and done on its second
#      (`status` "done (attempt 2)", exit 0);
#   5. cancels: tasks cancelled while pending or while ptfilter runs are
#      "cancelled" (exit 143 in --json), not failed; `status` exits 3 while
#      frames are pending.
# The daemons are stopped by their pid files on exit and the folder removed.
# Needs root (installs slurm-wlm and munge through scripts/install-deps when
# they are missing); skips (exit 77) otherwise. Takes about two minutes.
#
# usage: tests/farm/test_slurm.sh      env: SSS_BIN_DIR (default build/bin)
#        SSS_FARM_KEEP=1 keeps the temp folder (the daemons are stopped anyway).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
bin="$(realpath -m "${SSS_BIN_DIR:-$root/build/bin}")"
start=$SECONDS

if ((EUID != 0)); then
    echo "SKIP: the Slurm test needs root (it installs slurm-wlm and munge and runs slurmd, which starts jobs as their user)"
    exit 77
fi
for tool in ptbake ptfilter brickmake render ptinfo sss-farm; do
    [[ -x "$bin/$tool" ]] || { echo "test_slurm ERROR: no $bin/$tool (build first: scripts/build)" >&2; exit 1; }
done
if ! command -v sbatch >/dev/null || ! command -v munged >/dev/null || ! command -v slurmd >/dev/null; then
    "$root/scripts/install-deps" # slurm-wlm and munge are in its list
fi

# shellcheck source=tests/farm/cluster.sh
source "$here/cluster.sh"
work="$(mktemp -d /tmp/sss-farm-test.XXXXXX)"
cleanup() {
    cluster_stop "$work/cluster"
    if [[ "${SSS_FARM_KEEP:-0}" != 0 ]]; then
        echo "kept $work" >&2
    else
        rm -rf "$work"
    fi
}
trap cleanup EXIT

failures=0
fail() {
    echo "FAIL: $*" >&2
    failures=$((failures + 1))
}
die() {
    echo "test_slurm ERROR: $*" >&2
    exit 1
}
phase() { echo "== [$((SECONDS - start)) s] $*"; }

phase "starting munged, slurmctld, slurmd in $work/cluster"
cluster_start "$work/cluster" || die "the test cluster did not come up (logs above)"
sinfo

farm=("$bin/sss-farm")

# wait_for_queue LIMIT: until squeue lists no job (the cluster is ours alone).
wait_for_queue() {
    local limit="$1" t0=$SECONDS
    while [[ -n "$(squeue -h -o %i)" ]]; do
        if ((SECONDS - t0 > limit)); then
            squeue -o '%i %j %T %r' >&2
            local log
            for log in "$work"/*/logs/*.log; do
                echo "---- $log" >&2
                tail -n 5 "$log" >&2
            done
            cluster_logs "$work/cluster"
            die "the jobs did not finish in $limit s"
        fi
        sleep 1
    done
}

# mtime FILE: modification time in nanoseconds ("none" if missing).
mtime() { stat -c %.9Y "$1" 2>/dev/null || echo none; }

# --- the reference: the scene's own run script, locally -----------------------
phase "local reference run (scenes/orbit/run, SSS_QUICK=1)"
SSS_QUICK=1 SSS_BIN_DIR="$bin" "$root/scenes/orbit/run" "$work/ref" >"$work/ref.log" 2>&1 ||
    { cat "$work/ref.log" >&2; die "scenes/orbit/run failed"; }
frames=(1 2)

# The farm's argument strings: the commands of scenes/orbit/run, SSS_QUICK.
bake_args="-spacing 0.06 bake.rib"
filter_args="-ssdiffusion -material marble -unitlength 0.1 orbit.####.ptc orbit_ssd.####.ptc"
brick_args="-maxerror 0.002 orbit_ssd.####.ptc orbit_ssd.####.bkm"
render_args="-res 160 120 -samples 1 orbit.rib"
nosss_args="-res 160 120 -samples 1 -o orbit_nosss.####.exr orbit_nosss.rib"

submit_orbit() { # DIR NAME [sss-farm options...]
    local dir="$1" name="$2"
    shift 2
    mkdir -p "$dir"
    cp "$work/ref/bake.rib" "$work/ref/orbit.rib" "$work/ref/orbit_nosss.rib" "$dir/"
    "${farm[@]}" submit --frames 1-2 --workdir "$dir" --name "$name" \
        --bake "$bake_args" --filter "$filter_args" --brick "$brick_args" \
        --render "$render_args" --render "$nosss_args" -c 1 --mem 1024 "$@"
}

# --- 1 + 2: the chain, whole and split, submitted together ---------------------
phase "dry run"
dry="$("${farm[@]}" submit --dry-run --frames 1-2 --workdir "$work/dry" --name dry --bake "$bake_args" \
    --filter "$filter_args" --brick "$brick_args" --render "$render_args" --render "$nosss_args" \
    --splitpoints 1000 --parts 3 -c 3 -c render=5 --mem part=777)"
echo "$dry"
[[ "$(grep -c '^sbatch ' <<<"$dry")" == 8 ]] || fail "the dry run does not print 8 sbatch lines"
[[ "$(grep -c -- '--cpus-per-task=5 .*render' <<<"$dry")" == 2 ]] || fail "-c render=5 is not on both renders"
[[ "$(grep -c -- '--cpus-per-task=3 ' <<<"$dry")" == 6 ]] || fail "-c 3 is not on the other stages"
[[ "$(grep -c -- '--mem=777 .*filter --submission 1 --part' <<<"$dry")" == 3 ]] || fail "--mem part=777 is not on the part tasks"
grep -q -- "--output=$work/dry/logs/dry-render2.slurm.log" <<<"$dry" || fail "the dry run's render2 log name"
grep -q -- "--dependency=aftercorr:<filter-part1-jobid>:<filter-part2-jobid>:<filter-part3-jobid>" <<<"$dry" ||
    fail "the dry run's filter array does not wait for the 3 part arrays"
[[ ! -e "$work/dry" ]] || fail "the dry run wrote $work/dry"
# An array has at most MaxArraySize tasks (1001 in cluster.sh), whatever the frame numbers.
set +e
limit_err="$("${farm[@]}" submit --frames 0-1001 --workdir "$work/dry" --render "$render_args" 2>&1)"
limit_rc=$?
negative_err="$("${farm[@]}" submit --frames -2-3 --workdir "$work/dry" --render "$render_args" 2>&1)"
negative_rc=$?
set -e
[[ "$limit_rc" == 1 && "$limit_err" == *"1002 frames to queue, more than Slurm's array limit MaxArraySize = 1001 "* ]] ||
    fail "more frames than MaxArraySize: exit $limit_rc, '$limit_err'"
[[ "$negative_rc" == 2 && "$negative_err" == "sss-farm ERROR: --frames -2-3: "*"cannot be negative"* ]] ||
    fail "negative frames: exit $negative_rc, '$negative_err'"
[[ -z "$(squeue -h -o %i)" ]] || fail "a refused submission queued jobs"

phase "submitting the orbit chain, whole (orbit) and split (--splitpoints 1000 --parts 3)"
submit_orbit "$work/orbit" orbit
submit_orbit "$work/split" orbit --splitpoints 1000 --parts 3
wait_for_queue 400
phase "jobs done"

# Brick maps record their command line: the reference is brickmake run
# locally with the farm's exact command, on the reference cloud.
mkdir -p "$work/bkmref"
for f in "${frames[@]}"; do
    ff="$(printf %04d "$f")"
    cp "$work/ref/orbit_ssd.$ff.ptc" "$work/bkmref/"
    (cd "$work/bkmref" && "$bin/brickmake" -frame "$f" -newer 1 -threads 1 -maxerror 0.002 \
        'orbit_ssd.####.ptc' 'orbit_ssd.####.bkm') || die "local brickmake failed"
done

for dir in orbit split; do
    status="$("${farm[@]}" status "$work/$dir/.sss-farm/orbit.json")" || fail "$dir: status exited $?"
    echo "$status"
    for stage in bake filter brick render render2; do
        grep -Eq "^  $stage +job [0-9]+ +done 1-2; outputs exist: 1-2$" <<<"$status" ||
            fail "$dir: status does not report $stage done for frames 1-2"
    done
    for f in "${frames[@]}"; do
        ff="$(printf %04d "$f")"
        for file in "orbit.$ff.ptc" "orbit_ssd.$ff.ptc"; do
            cmp "$work/$dir/$file" "$work/ref/$file" || fail "$dir: $file differs from the local run"
        done
        cmp "$work/$dir/orbit_ssd.$ff.bkm" "$work/bkmref/orbit_ssd.$ff.bkm" ||
            fail "$dir: orbit_ssd.$ff.bkm differs from the local brickmake"
        for image in "orbit.$ff.exr" "orbit_nosss.$ff.exr"; do
            oiiotool "$work/$dir/$image" "$work/ref/$image" --fail 0.001 --diff >"$work/diff.log" 2>&1 ||
                { cat "$work/diff.log" >&2; fail "$dir: $image differs from the local render"; }
        done
        log="$work/$dir/logs/orbit-filter.$ff.log"
        [[ -f "$log" ]] || fail "$dir: no log $log (zero-padded %4a)"
    done
done
split_log="$(cat "$work/split/logs/orbit-filter-part2.0001.log" "$work/split/logs/orbit-filter.0001.log" 2>&1)"
grep -q -- "-part 2/3 " <<<"$split_log" || fail "split: part task 2 did not run ptfilter -part 2/3: $split_log"
grep -q -- "ptfilter -merge " <<<"$split_log" || fail "split: the filter task did not merge: $split_log"
! compgen -G "$work/split/*.ptpart" >/dev/null || fail "split: part files left after the merge"
grep -q -- "-part" "$work/orbit/logs/orbit-filter.0001.log" && fail "orbit: the unsplit filter used -part"

# --- 3: a failing frame and its re-submission ----------------------------------
phase "a frame with a missing input (frames 1-3, orbit.0003.ptc missing)"
fix() {
    "${farm[@]}" submit --frames 1-3 --workdir "$work/orbit" --name fix -c 1 --mem 1024 --retries 0 \
        --filter "-ssdiffusion -material marble -unitlength 0.1 orbit.####.ptc fix_ssd.####.ptc" \
        --brick "-maxerror 0.002 fix_ssd.####.ptc fix_ssd.####.bkm"
}
fix
# Meanwhile, a split submission whose clouds are small enough: not split.
"${farm[@]}" submit --frames 1-2 --workdir "$work/split" --name small -c 1 --mem 1024 \
    --filter "-ssdiffusion -material marble -unitlength 0.1 orbit.####.ptc small_ssd.####.ptc" \
    --splitpoints 100000 --parts 2
wait_for_queue 200
status="$("${farm[@]}" status --workdir "$work/split" --name small)" || fail "small: status exited $?"
echo "$status"
for stage in filter-part1 filter-part2 filter; do
    grep -Eq "^  $stage +job [0-9]+ +done 1-2" <<<"$status" || fail "small: $stage is not done for 1-2"
done
for f in "${frames[@]}"; do
    cmp "$work/split/small_ssd.000$f.ptc" "$work/ref/orbit_ssd.000$f.ptc" ||
        fail "small: small_ssd.000$f.ptc differs from the local run"
    grep -q "points <= 100000: not split" "$work/split/logs/small-filter-part1.000$f.log" ||
        fail "small: part task 1 of frame $f did not skip"
    grep -q -- "-merge\|-part" "$work/split/logs/small-filter.000$f.log" &&
        fail "small: the filter of frame $f used -part or -merge"
done

set +e
status="$("${farm[@]}" status --workdir "$work/orbit" --name fix)"
status_rc=$?
set -e
echo "$status"
[[ "$status_rc" == 1 ]] || fail "fix: status exited $status_rc with a failed frame, not 1"
grep -Eq "^  filter +job [0-9]+ +done 1-2; failed \(exit 1\) 3; outputs exist: 1-2$" <<<"$status" ||
    fail "fix: status does not report the filter of frame 3 failed with exit 1"
grep -Eq "^  brick +job [0-9]+ +done 1-2; not run \(an earlier stage failed\) 3; outputs exist: 1-2$" <<<"$status" ||
    fail "fix: status does not report the brick of frame 3 not run"
filter_job="$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["submissions"][-1]["jobs"]["filter"])' \
    "$work/orbit/.sss-farm/fix.json")"
exit_code="$(scontrol -o show job "${filter_job}_2" | grep -o 'ExitCode=[0-9:]*')" # frame 3 is index 2
[[ "$exit_code" == "ExitCode=1:0" ]] || fail "fix: Slurm's exit code of the failed task is '$exit_code', not 1:0"
grep -q "ptfilter ERROR: orbit.0003.ptc" "$work/orbit/logs/fix-filter.0003.log" ||
    fail "fix: the log of frame 3 lacks ptfilter's error"

declare -A before
for f in 1 2; do
    for ext in ptc bkm; do
        before[$f.$ext]="$(mtime "$work/orbit/fix_ssd.000$f.$ext")"
    done
done
phase "the input made, re-submission"
(cd "$work/orbit" && "$bin/ptbake" -frame 3 -spacing 0.06 bake.rib) || die "ptbake -frame 3 failed"
sleep 0.1 # the redone outputs are strictly newer
resubmit="$(fix)"
echo "$resubmit"
grep -q "2 of 3 frames up to date (outputs newer than inputs), not queued: 1-2;" <<<"$resubmit" ||
    fail "fix: the re-submission does not skip frames 1-2"
grep -q "queuing 1 frame (3) as array index 0" <<<"$resubmit" || fail "fix: the re-submission does not queue frame 3 alone"
wait_for_queue 200
status="$("${farm[@]}" status --workdir "$work/orbit" --name fix)" || fail "fix: status exited $?"
echo "$status"
for stage in filter brick; do
    grep -Eq "^  $stage +job [0-9]+ +up to date 1-2; done 3; outputs exist: 1-3$" <<<"$status" ||
        fail "fix: after the re-submission, status does not report $stage up to date for 1-2 and done for 3"
done
for f in 1 2; do
    for ext in ptc bkm; do
        [[ "$(mtime "$work/orbit/fix_ssd.000$f.$ext")" == "${before[$f.$ext]}" ]] ||
            fail "fix: the re-submission rewrote fix_ssd.000$f.$ext"
    done
done
[[ "$(grep -c "^== sss-farm: fix filter frame 1 " "$work/orbit/logs/fix-filter.0001.log")" == 1 ]] ||
    fail "fix: frame 1's filter ran again"
cmp "$work/orbit/fix_ssd.0003.ptc" "$work/orbit/fix_ssd.0001.ptc" >/dev/null &&
    fail "fix: frame 3's output is frame 1's"
[[ -s "$work/orbit/fix_ssd.0003.bkm" ]] || fail "fix: no fix_ssd.0003.bkm"

# --- 4: studio frames, -check at submission, a retry -----------------------------
phase "studio frames 1001-1005:2, a misspelled option, a retried frame"
mkdir -p "$work/studio" "$work/studioref"
for f in 1001 1003 1005; do
    "$bin/ptsynth" -n 2000 -size 5 -light 0 "$((f - 1002))" 1 "$work/studioref/in.$f.ptc" >/dev/null
    (cd "$work/studioref" && "$bin/ptfilter" -ssdiffusion -frame "$f" -threads 1 -material skin1 -unitlength 0.1 \
        'in.####.ptc' 'out.####.ptc' && "$bin/brickmake" -frame "$f" -newer 1 -threads 1 'out.####.ptc' 'out.####.bkm') ||
        die "local studio reference failed"
done
cp "$work/studioref/in.1001.ptc" "$work/studioref/in.1003.ptc" "$work/studio/" # in.1005.ptc comes later
studio() { # [sss-farm options...]
    "${farm[@]}" submit --frames 1001-1005:2 --workdir "$work/studio" --name studio -c 1 --mem 1024 \
        --filter "-ssdiffusion -material skin1 -unitlength 0.1 in.####.ptc out.####.ptc" \
        --brick "out.####.ptc out.####.bkm" "$@"
}
set +e
typo_err="$(studio --brick "-maxdepht 12 out.####.ptc out.####.bkm" 2>&1)"
typo_rc=$?
set -e
[[ "$typo_rc" == 2 && "$typo_err" == "sss-farm ERROR: --brick, frame 1001: brickmake ERROR: unknown option -maxdepht"* ]] ||
    fail "studio: a misspelled option: exit $typo_rc, '$typo_err'"
[[ -z "$(squeue -h -o %i)" && ! -e "$work/studio/.sss-farm" ]] || fail "studio: the refused submission queued or wrote something"
studio_out="$(studio)"
echo "$studio_out"
grep -q "queuing 3 frames (1001-1005:2) as array indices 0-2" <<<"$studio_out" || fail "studio: not queued as indices 0-2"
# Frame 1005's first attempt fails (no input); once it has, the input appears.
for ((t = 0; t < 120; t++)); do
    grep -q '"retrying"' "$work/studio/.sss-farm/status/studio.filter.1005" 2>/dev/null && break
    sleep 0.5
done
grep -q '"retrying"' "$work/studio/.sss-farm/status/studio.filter.1005" 2>/dev/null ||
    fail "studio: frame 1005's filter was not requeued: $(cat "$work/studio/logs/studio-filter.1005.log" 2>&1)"
set +e
"${farm[@]}" status --workdir "$work/studio" --name studio >"$work/studio.status"
pending_rc=$?
set -e
cat "$work/studio.status"
[[ "$pending_rc" == 3 ]] || fail "studio: status exited $pending_rc while frame 1005 waits for its retry, not 3"
cp "$work/studioref/in.1005.ptc" "$work/studio/"
wait_for_queue 200
set +e
status="$("${farm[@]}" status --workdir "$work/studio" --name studio)"
status_rc=$?
set -e
echo "$status"
[[ "$status_rc" == 0 ]] || fail "studio: status exited $status_rc, not 0"
grep -Eq "^  filter +job [0-9]+ +done 1001,1003; done \(attempt 2\) 1005; outputs exist: 1001-1005:2$" <<<"$status" ||
    fail "studio: status does not report frame 1005 done on its second attempt"
grep -Eq "^  brick +job [0-9]+ +done 1001-1005:2; outputs exist: 1001-1005:2$" <<<"$status" ||
    fail "studio: the brick maps are not all done"
for f in 1001 1003 1005; do
    cmp "$work/studio/out.$f.ptc" "$work/studioref/out.$f.ptc" || fail "studio: out.$f.ptc differs from the local run"
    cmp "$work/studio/out.$f.bkm" "$work/studioref/out.$f.bkm" || fail "studio: out.$f.bkm differs from the local run"
done
grep -q "ptfilter exited with 1 (attempt 1 of 3): requeued" "$work/studio/logs/studio-filter.1005.log" ||
    fail "studio: frame 1005's log lacks the requeue"

# --- 5: cancels ---------------------------------------------------------------------
phase "cancels: pending tasks, and a running ptfilter"
mkdir -p "$work/cancel"
"$bin/ptsynth" -n 60000 -size 5 "$work/cancel/big.0001.ptc" >/dev/null
cp "$work/cancel/big.0001.ptc" "$work/cancel/big.0002.ptc"
# Frame 1 runs ptfilter -exact (minutes); frame 2 waits for the cores frame 1 holds.
"${farm[@]}" submit --frames 1-2 --workdir "$work/cancel" --name long -c "$(nproc)" --mem 1024 \
    --filter "-ssdiffusion -exact -material marble big.####.ptc long.####.ptc" --brick "long.####.ptc long.####.bkm"
for ((t = 0; t < 120; t++)); do
    grep -q '"running"' "$work/cancel/.sss-farm/status/long.filter.1" 2>/dev/null &&
        grep -q -- "ptfilter -ssdiffusion -frame 1 " "$work/cancel/logs/long-filter.0001.log" 2>/dev/null && break
    sleep 0.5
done
sleep 1
set +e
"${farm[@]}" status --workdir "$work/cancel" --name long >"$work/long.status"
running_rc=$?
set -e
cat "$work/long.status"
[[ "$running_rc" == 3 ]] || fail "cancel: status exited $running_rc while frame 1 runs, not 3"
# shellcheck disable=SC2046
scancel $(python3 -c 'import json,sys; print(" ".join(json.load(open(sys.argv[1]))["submissions"][-1]["jobs"].values()))' \
    "$work/cancel/.sss-farm/long.json")
wait_for_queue 120
set +e
"${farm[@]}" status --json --workdir "$work/cancel" --name long >"$work/long.json"
cancel_rc=$?
status="$("${farm[@]}" status --workdir "$work/cancel" --name long)"
set -e
echo "$status"
[[ "$cancel_rc" == 1 ]] || fail "cancel: status exited $cancel_rc after the cancel, not 1"
grep -Eq "^  filter +job [0-9]+ +cancelled 1-2; outputs exist: -$" <<<"$status" ||
    fail "cancel: the filter's frames are not reported cancelled"
[[ "$status" != *"exit 143"* ]] || fail "cancel: a cancel reported as an exit code"
python3 - "$work/long.json" <<'EOF' || fail "cancel: --json: $(cat "$work/long.json")"
import json, sys
j = json.load(open(sys.argv[1]))
f = j["stages"]["filter"]["frames"]
assert (f["1"]["state"], f["1"]["exit_code"], f["1"]["attempts"]) == ("cancelled", 143, 1), f["1"]
assert f["2"]["state"] == "cancelled", f["2"]
assert j["result"] == "failed" and j["exit"] == 1, j
EOF
! compgen -G "$work/cancel/*.tmp*" >/dev/null || fail "cancel: ptfilter left a temporary: $(ls "$work/cancel")"

phase "done"
if ((failures > 0)); then
    echo "$failures check(s) failed" >&2
    exit 1
fi
echo "all Slurm farm checks passed in $((SECONDS - start)) s"
