#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# sss-farm without a cluster (any user, seconds): the command line and its
# errors, the dry run, `submit` against stub sbatch/squeue/scontrol commands
# (the spec it writes, the sbatch options, the chaining of the job ids, a
# refused sbatch), and `task` run locally with --frame: the tool's exit code
# and the status files, -newer 1, and the split (parts + merge byte-identical
# to the single ptfilter run; below the threshold the plain ptfilter).
# Studio frames, -check at submission, retries, status codes and JSON,
# cancels and re-submission: test_farm_studio.sh. The real Slurm test is
# test_slurm.sh.
#
# usage: tests/farm/test_sss_farm.sh      env: SSS_BIN_DIR (default build/bin)
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
bin="$(realpath -m "${SSS_BIN_DIR:-$root/build/bin}")"
farm="$bin/sss-farm"
export SSS_BIN_DIR="$bin"
for tool in ptsynth ptfilter ptinfo brickmake sss-farm; do
    [[ -x "$bin/$tool" ]] || { echo "test_sss_farm ERROR: no $bin/$tool (build first: scripts/build)" >&2; exit 1; }
done
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
# shellcheck source=tests/cli/lib.sh
source "$root/tests/cli/lib.sh"
# shellcheck source=tests/cli/checks.sh
source "$root/tests/cli/checks.sh"
cd "$work"

# state_of STATUS_FILE: "state exit attempt" of a task's status file.
state_of() {
    python3 -c 'import json,sys; s=json.load(open(sys.argv[1])); print(s["state"], s["exit"], s["attempt"])' "$1" 2>&1
}

# expect_error CODE 'message part' LABEL: the last run failed with one ERROR
# line (sss-farm's own) containing the message part.
expect_error() {
    expect_rc "$1" "$3" || return 0
    local line
    line="$(grep '^sss-farm ERROR: ' "$work/stderr" || true)"
    [[ "$line" != *$'\n'* && "$line" == *"$2"* ]] || fail "$3: the ERROR line of '$err' lacks '$2'"
}

# --- command line ----------------------------------------------------------------
run "$farm" --help
if expect_rc 0 "--help"; then
    [[ "$out" == *"submit"*"status"* ]] || fail "--help: '$out'"
fi
run "$farm"
expect_error 2 "give a command" "no command"
run "$farm" submit --frames 1-2
expect_error 2 "nothing to submit" "no stage"
run "$farm" submit --frames 1-2 --bogus 1 --render a.rib
expect_error 2 "unrecognized arguments: --bogus" "unknown option"
run "$farm" submit --frames 3-1 --render a.rib --dry-run
expect_error 2 "is empty" "empty range"
run "$farm" submit --frames -1-2 --render a.rib --dry-run
expect_error 2 "cannot be negative" "negative frame"
run "$farm" submit --frames 1-1002 --render a.rib --dry-run
expect_error 1 "1002 frames to queue, more than Slurm's array limit MaxArraySize = 1001" "more frames than MaxArraySize"
run "$farm" submit --frames 1 --filter "-ssdiffusion -frame 1 a.ptc b.ptc" --dry-run
expect_error 2 "leave out -frame" "-frame in the arguments"
run "$farm" submit --frames 1 --render "-check a.rib" --dry-run
expect_error 2 "--render: leave out -check, sss-farm adds it" "-check in the arguments"
run "$farm" submit --frames 1 --filter "-ssdiffusion a.ptc b.ptc" --parts 2 --dry-run
expect_error 2 "--splitpoints and --parts go together" "--parts alone"
run "$farm" submit --frames 1 --render a.rib --splitpoints 5 --parts 2 --dry-run
expect_error 2 "give --filter too" "split without filter"
run "$farm" submit --frames 1 --render a.rib -c gpu=2 --dry-run
expect_error 2 "unknown stage 'gpu'" "-c for an unknown stage"
run "$farm" submit --frames 1 --render a.rib --mem 0 --dry-run
expect_error 2 "N > 0" "--mem 0"
SSS_BIN_DIR="$work/nothing" run "$farm" submit --frames 1 --render a.rib --dry-run
expect_error 1 "no render in $work/nothing" "no tools"
run "$farm" status
expect_error 2 "give the spec" "status without a spec"
run "$farm" status "$work/none.json"
expect_error 1 "none.json: No such file" "status of a missing spec"

# --- dry run -----------------------------------------------------------------------
run "$farm" submit --dry-run --frames 1-3,5 --workdir "$work/dry" --name shot --bake "bake.rib" \
    --filter "-ssdiffusion in.####.ptc out.####.ptc" --brick "out.####.ptc out.####.bkm" \
    --render "shot.rib" --partition big --sbatch=--time=1:00:00
expect_rc 0 "dry run"
[[ ! -e "$work/dry" ]] || fail "the dry run wrote $work/dry"
expected="sbatch --parsable --job-name=sss-shot-brick --array=0-3 --chdir=$work/dry \
--output=$work/dry/logs/shot-brick.slurm.log --open-mode=append --requeue --cpus-per-task=2 --mem=4096 \
--partition=big '--dependency=aftercorr:<filter-jobid>' --kill-on-invalid-dep=yes --time=1:00:00 \
'--wrap=exec $farm task $work/dry/.sss-farm/shot.json brick --submission 1'"
grep -v '^#' stdout >sbatch.txt
[[ "$(sed -n 3p sbatch.txt)" == "$expected" ]] || fail "dry run line 3:"$'\n'"$(sed -n 3p sbatch.txt)"$'\n'"expected"$'\n'"$expected"
[[ "$(wc -l <sbatch.txt)" == 4 ]] || fail "dry run: $(wc -l <sbatch.txt) sbatch lines, not 4"
[[ "$(head -n1 stdout)" == "# sss-farm: shot: queuing 4 frames (1-3,5) as array indices 0-3" ]] ||
    fail "dry run: the first line is '$(head -n1 stdout)'"
head -n1 sbatch.txt | grep -q dependency && fail "dry run: the first stage has a dependency"

# --- submit against stub Slurm commands -------------------------------------------------
mkdir stubs
cat >stubs/sbatch <<'EOF'
#!/usr/bin/env bash
# Records its arguments; prints job ids 100, 101, ...; SBATCH_FAIL_AT=N fails the Nth call.
n=$(($(cat "$STUB_DIR/count" 2>/dev/null || echo 0) + 1))
echo "$n" >"$STUB_DIR/count"
printf '%s\n' "$*" >>"$STUB_DIR/sbatch.log"
if [[ "${SBATCH_FAIL_AT:-0}" == "$n" ]]; then
    echo "sbatch: error: Batch job submission failed: Invalid partition name specified" >&2
    exit 1
fi
echo "$((99 + n))"
EOF
cat >stubs/scancel <<'EOF'
#!/usr/bin/env bash
printf '%s\n' "$*" >>"$STUB_DIR/scancel.log"
EOF
printf '#!/bin/sh\nexit 0\n' >stubs/squeue
printf '#!/bin/sh\nexit 0\n' >stubs/sacct
# shellcheck disable=SC2016
printf '#!/bin/sh\n[ "$1 $2" = "show config" ] && echo "MaxArraySize            = 50"\nexit 0\n' >stubs/scontrol
chmod +x stubs/*
export STUB_DIR="$work/stubs"
stub_path="$work/stubs:$PATH"

mkdir shot
"$bin/ptsynth" -n 3000 -size 5 shot/in.0001.ptc >/dev/null
"$bin/ptsynth" -n 500 -size 5 -light 0 1 1 shot/in.0002.ptc >/dev/null
filter="-ssdiffusion -material marble -unitlength 0.1 in.####.ptc out.####.ptc"
PATH="$stub_path" run "$farm" submit --frames 1-60 --workdir shot --name s --filter "$filter" --render a.rib
expect_error 1 "60 frames to queue, more than Slurm's array limit MaxArraySize = 50 (array indices go from 0 to 49)" \
    "MaxArraySize from scontrol"
PATH="$stub_path" run "$farm" submit --frames 1-3 --workdir shot --name s --filter "$filter" \
    --brick "out.####.ptc out.####.bkm" --splitpoints 1000 --parts 2 -c 1
expect_rc 0 "submit (stubs)"
spec="$work/shot/.sss-farm/s.json"
[[ -f "$spec" && -d shot/logs ]] || fail "submit wrote no spec or logs folder"
jobs="$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["submissions"][-1]["jobs"])' "$spec")"
[[ "$jobs" == "{'filter-part1': '100', 'filter-part2': '101', 'filter': '102', 'brick': '103'}" ]] ||
    fail "the spec's job ids: $jobs"
grep -q -- "--job-name=sss-s-filter --array=0-2 .*--dependency=aftercorr:100:101 " stubs/sbatch.log ||
    fail "the filter array does not wait for both parts: $(cat stubs/sbatch.log)"
grep -q -- "--job-name=sss-s-brick .*--dependency=aftercorr:102 " stubs/sbatch.log ||
    fail "the brick array does not wait for the filter"
# A refused sbatch: the arrays already queued are cancelled, exit 1.
rm -f stubs/count
SBATCH_FAIL_AT=2 PATH="$stub_path" run "$farm" submit --frames 1 --workdir shot --name t --filter "$filter" \
    --brick "out.####.ptc out.####.bkm"
expect_error 1 "sbatch for stage brick failed (exit 1): sbatch: error: Batch job submission failed: Invalid \
partition name specified; cancelled the arrays this submission had queued (100)" "refused sbatch"
[[ "$(cat stubs/scancel.log 2>/dev/null)" == 100 ]] || fail "the queued filter array was not cancelled"

# --- task, locally ---------------------------------------------------------------------
# Frame 1: 3000 points > 1000, split; frame 2: 500, not split; frame 3: no input.
"$bin/ptfilter" -ssdiffusion -material marble -unitlength 0.1 shot/in.0001.ptc whole.0001.ptc
"$bin/ptfilter" -ssdiffusion -material marble -unitlength 0.1 shot/in.0002.ptc whole.0002.ptc
for f in 1 2; do
    for k in 1 2; do
        run "$farm" task "$spec" filter --part "$k" --frame "$f"
        expect_rc 0 "part $k frame $f"
    done
done
[[ -f shot/out.0001.ptc.part1of2.ptpart && -f shot/out.0001.ptc.part2of2.ptpart ]] ||
    fail "no part files for frame 1: $(ls shot)"
compgen -G "shot/out.0002.ptc.part*" >/dev/null && fail "frame 2 (500 points) was split"
[[ "$out" == *"500 points <= 1000: not split"* ]] || fail "part task of frame 2: '$out'"
for f in 1 2; do
    run "$farm" task "$spec" filter --frame "$f"
    expect_rc 0 "filter frame $f"
    cmp "shot/out.000$f.ptc" "whole.000$f.ptc" || fail "frame $f: the farm's cloud differs from ptfilter's"
    [[ "$(state_of "shot/.sss-farm/status/s.filter.$f")" == "done 0 1" ]] || fail "status file of frame $f"
done
compgen -G "shot/*.ptpart" >/dev/null && fail "part files left after the merge"
# Done frames cost nothing: no part, no merge, no ptfilter.
run "$farm" task "$spec" filter --part 1 --frame 1
[[ "$rc" == 0 && "$out" == *"out.0001.ptc is newer than its inputs; nothing to do"* ]] ||
    fail "a done frame's part task ran: $out"
# Frame 3: the input is missing; the part task fails (ptinfo), so does the filter (ptfilter).
run "$farm" task "$spec" filter --part 1 --frame 3
expect_error 1 "cannot count the points of in.0003.ptc" "part task without input"
[[ "$(state_of shot/.sss-farm/status/s.filter-part1.3)" == "failed 1 1" ]] || fail "status file of the failed part"
run "$farm" task "$spec" brick --frame 3
expect_rc 1 "brick without input"
[[ "$err" == *"brickmake ERROR: "*"out.0003.ptc"*$'\n'"sss-farm ERROR: s brick frame 3: brickmake exited with 1" ]] ||
    fail "brick frame 3 stderr: $err"
[[ "$(state_of shot/.sss-farm/status/s.brick.3)" == "failed 1 1" ]] || fail "status file of the failed brick"
# A usage error of the tool is its exit code 2.
python3 - "$spec" <<'EOF'
import json, sys
s = json.load(open(sys.argv[1]))
s["stages"][1]["args"] = ["-bogus", "out.####.ptc", "out.####.bkm"]
json.dump(s, open(sys.argv[1], "w"))
EOF
run "$farm" task "$spec" brick --frame 1
expect_rc 2 "brick with a bad option"

PATH="$stub_path" run "$farm" status "$spec"
expect_rc 1 "status with failed frames"
[[ "$out" == *"filter-part1 job 100      done 1-2; failed (exit 1) 3"* ]] || fail "status part1: $out"
[[ "$out" == *"filter       job 102      done 1-2; not run 3; outputs exist: 1-2"* ]] || fail "status filter: $out"
[[ "$out" == *"brick        job 103      failed (exit 2) 1; not run 2; failed (exit 1) 3; outputs exist: -"* ]] ||
    fail "status brick: $out"

finish_checks sss-farm
