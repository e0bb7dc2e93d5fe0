#!/usr/bin/env bash
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
#   3. a frame whose input is missing: its filter task fails with ptfilter's
#      exit code (Slurm ExitCode 1:0 and `status` "failed (exit 1)"), its
#      brick task does not run; after the input is made, the re-submission
#      redoes that frame only (the other frames' outputs keep their mtime).
# The daemons are stopped by their pid files on exit and the folder removed.
# Needs root (installs slurm-wlm and munge through scripts/install-deps when
# they are missing); skips (exit 77) otherwise. Takes about a minute.
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
[[ "$(grep -c -- '--mem=777 .*filter --part' <<<"$dry")" == 3 ]] || fail "--mem part=777 is not on the part tasks"
grep -q -- "--output=$work/dry/logs/dry-render2.%4a.log" <<<"$dry" || fail "the dry run's render2 log name"
grep -q -- "--dependency=aftercorr:<filter-part1-jobid>:<filter-part2-jobid>:<filter-part3-jobid>" <<<"$dry" ||
    fail "the dry run's filter array does not wait for the 3 part arrays"
[[ ! -e "$work/dry" ]] || fail "the dry run wrote $work/dry"
# The frames are array task ids: 0 to MaxArraySize - 1 (1001 in cluster.sh).
set +e
limit_err="$("${farm[@]}" submit --frames 999-1001 --workdir "$work/dry" --render "$render_args" 2>&1)"
limit_rc=$?
negative_err="$("${farm[@]}" submit --frames -2-3 --workdir "$work/dry" --render "$render_args" 2>&1)"
negative_rc=$?
set -e
[[ "$limit_rc" == 1 && "$limit_err" == *"frame 1001 is above Slurm's array limit"*"MaxArraySize - 1 = 1000;"* ]] ||
    fail "frames above MaxArraySize: exit $limit_rc, '$limit_err'"
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
    "${farm[@]}" submit --frames 1-3 --workdir "$work/orbit" --name fix -c 1 --mem 1024 \
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

status="$("${farm[@]}" status --workdir "$work/orbit" --name fix)" || fail "fix: status exited $?"
echo "$status"
grep -Eq "^  filter +job [0-9]+ +done 1-2; failed \(exit 1\) 3; outputs exist: 1-2$" <<<"$status" ||
    fail "fix: status does not report the filter of frame 3 failed with exit 1"
grep -Eq "^  brick +job [0-9]+ +done 1-2; not run \(an earlier stage failed\) 3; outputs exist: 1-2$" <<<"$status" ||
    fail "fix: status does not report the brick of frame 3 not run"
filter_job="$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["submissions"][-1]["jobs"]["filter"])' \
    "$work/orbit/.sss-farm/fix.json")"
exit_code="$(scontrol -o show job "${filter_job}_3" | grep -o 'ExitCode=[0-9:]*')"
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
fix
wait_for_queue 200
status="$("${farm[@]}" status --workdir "$work/orbit" --name fix)" || fail "fix: status exited $?"
echo "$status"
for stage in filter brick; do
    grep -Eq "^  $stage +job [0-9]+ +done 1-3; outputs exist: 1-3$" <<<"$status" ||
        fail "fix: after the re-submission, status does not report $stage done for 1-3"
done
for f in 1 2; do
    for ext in ptc bkm; do
        [[ "$(mtime "$work/orbit/fix_ssd.000$f.$ext")" == "${before[$f.$ext]}" ]] ||
            fail "fix: the re-submission rewrote fix_ssd.000$f.$ext"
    done
done
grep -q "nothing to do" "$work/orbit/logs/fix-filter.0001.log" || fail "fix: frame 1's filter was not skipped"
cmp "$work/orbit/fix_ssd.0003.ptc" "$work/orbit/fix_ssd.0001.ptc" >/dev/null &&
    fail "fix: frame 3's output is frame 1's"
[[ -s "$work/orbit/fix_ssd.0003.bkm" ]] || fail "fix: no fix_ssd.0003.bkm"

phase "done"
if ((failures > 0)); then
    echo "$failures check(s) failed" >&2
    exit 1
fi
echo "all Slurm farm checks passed in $((SECONDS - start)) s"
