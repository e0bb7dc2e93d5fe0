#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# sss-farm for studios, against fake Slurm commands (any user, seconds):
#   - frames: studio numbers (1001-1003), steps (1-9:2), lists (1,5,10-20:5):
#     the array is 0..n-1 whatever the numbers, each task maps its index back
#     to its frame (and writes that frame's log and status);
#   - every stage's arguments checked at submission by the tool (-check): a
#     misspelled option fails the submission, exit 2, nothing submitted;
#   - retries: a failed task requeues itself (scontrol requeue) up to
#     --retries times, never for a usage error or a cancel; a retried frame
#     that then succeeds reports as done (attempt 2);
#   - status: exit 0 done, 1 failed, 3 pending or running; --json with its
#     keys; a cancelled task (SIGTERM, 143, or Slurm's CANCELLED) is
#     "cancelled", a time limit "failed (timeout)";
#   - re-submission queues only the frames whose outputs are missing or out
#     of date (--force: all), and says how many it skipped;
#   - --help lists every option.
#
# usage: tests/farm/test_farm_studio.sh      env: SSS_BIN_DIR (default build/bin)
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
bin="$(realpath -m "${SSS_BIN_DIR:-$root/build/bin}")"
farm="$bin/sss-farm"
export SSS_BIN_DIR="$bin"
for tool in ptsynth ptfilter ptinfo brickmake render sss-farm; do
    [[ -x "$bin/$tool" ]] || { echo "test_farm_studio ERROR: no $bin/$tool (build first: scripts/build)" >&2; exit 1; }
done
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
# shellcheck source=tests/cli/lib.sh
source "$root/tests/cli/lib.sh"
# shellcheck source=tests/cli/checks.sh
source "$root/tests/cli/checks.sh"
cd "$work"

expect_error() { # CODE 'message part' LABEL: one sss-farm ERROR line with it
    expect_rc "$1" "$3" || return 0
    local line
    line="$(grep '^sss-farm ERROR: ' "$work/stderr" || true)"
    [[ "$line" != *$'\n'* && "$line" == *"$2"* ]] || fail "$3: the ERROR line of '$err' lacks '$2'"
}
field() { # JSON-FILE PYTHON-EXPRESSION-ON-j: prints it
    python3 -c 'import json,sys; j=json.load(open(sys.argv[1])); print(eval(sys.argv[2]))' "$1" "$2"
}

# --- fake Slurm ------------------------------------------------------------------
# sbatch records its arguments and prints job ids 100, 101, ...; squeue and
# scontrol answer from files the test writes (squeue.txt: "JOB INDEX STATE
# REASON" lines; jobs.txt: `scontrol -o show job` lines); scontrol requeue is
# logged (and fails with REQUEUE_FAIL=1); sacct answers from sacct.txt.
mkdir stubs
cat >stubs/sbatch <<'EOF'
#!/usr/bin/env bash
n=$(($(cat "$STUB_DIR/count" 2>/dev/null || echo 0) + 1))
echo "$n" >"$STUB_DIR/count"
printf '%s\n' "$*" >>"$STUB_DIR/sbatch.log"
echo "$((99 + n))"
EOF
cat >stubs/squeue <<'EOF'
#!/usr/bin/env bash
[[ -f "$STUB_DIR/squeue.txt" ]] || exit 0
case "$*" in
    *"%F %K %T %r"*) cat "$STUB_DIR/squeue.txt" ;;
    *) cut -d' ' -f1 "$STUB_DIR/squeue.txt" ;;
esac
EOF
cat >stubs/scontrol <<'EOF'
#!/usr/bin/env bash
case "$*" in
    "show config") echo "MaxArraySize            = 1001" ;;
    "-o show job"*) cat "$STUB_DIR/jobs.txt" 2>/dev/null || true ;;
    requeue*)
        printf '%s\n' "$*" >>"$STUB_DIR/requeue.log"
        [[ "${REQUEUE_FAIL:-0}" == 0 ]] || { echo "scontrol: error: Requested operation is presently disabled" >&2; exit 1; }
        ;;
esac
EOF
cat >stubs/sacct <<'EOF'
#!/usr/bin/env bash
cat "$STUB_DIR/sacct.txt" 2>/dev/null || true
EOF
printf '#!/bin/sh\nexit 0\n' >stubs/scancel
chmod +x stubs/*
export STUB_DIR="$work/stubs" PATH="$work/stubs:$PATH"
reset_slurm() { rm -f stubs/count stubs/sbatch.log stubs/squeue.txt stubs/jobs.txt stubs/requeue.log stubs/sacct.txt; }

# --- --help lists every option -----------------------------------------------------
run "$farm" --help
expect_rc 0 "--help"
for opt in --frames --workdir --name --bake --filter --brick --render --cpus --mem --partition --sbatch \
    --retries --force --splitpoints --parts --dry-run --json --submission --part --frame --version; do
    grep -q -- "$opt" stdout || fail "sss-farm --help does not list $opt"
done
grep -q "exit status: 0 every frame done" stdout || fail "sss-farm --help does not give status's exit codes"
run "$farm" submit --help
for opt in --frames --workdir --name --bake --filter --brick --render --cpus --mem --partition --sbatch \
    --retries --force --splitpoints --parts --dry-run; do
    grep -q -- "$opt" stdout || fail "sss-farm submit --help does not list $opt"
done

# --- studio frames: the array is the position in the frame list ---------------------------
dry() { # FRAMES: the --array values of a dry run with every stage
    run "$farm" submit --dry-run --frames "$1" --workdir "$work/dry" --name d --bake "bake.rib" \
        --filter "-ssdiffusion -material marble in.####.ptc out.####.ptc" --brick "out.####.ptc out.####.bkm" \
        --render "-o img.####.exr shot.rib"
    expect_rc 0 "dry run --frames $1" || return 0
    grep -o -- '--array=[^ ]*' stdout | sort -u | tr '\n' ' '
}
[[ "$(dry 1001-1003)" == "--array=0-2 " ]] || fail "--frames 1001-1003: $(dry 1001-1003)"
grep -q "queuing 3 frames (1001-1003) as array indices 0-2" stdout || fail "1001-1003: '$out'"
[[ "$(dry 1-9:2)" == "--array=0-4 " ]] || fail "--frames 1-9:2: $(dry 1-9:2)"
grep -q "queuing 5 frames (1-9:2) as array indices 0-4" stdout || fail "1-9:2: '$out'"
[[ "$(dry 1,5,10-20:5)" == "--array=0-4 " ]] || fail "--frames 1,5,10-20:5: $(dry 1,5,10-20:5)"
grep -q "queuing 5 frames (1,5-20:5)" stdout || fail "1,5,10-20:5: '$out'"
[[ "$(dry 2000-2999)" == "--array=0-999 " ]] || fail "1000 frames from 2000"
[[ ! -e "$work/dry" ]] || fail "the dry runs wrote $work/dry"
run "$farm" submit --dry-run --frames 1-9:0 --render a.rib
expect_error 2 "the step of 1-9:0 must be 1 or more" "step 0"
run "$farm" submit --dry-run --frames 1000001 --render a.rib
expect_error 2 "frame 1000001 is above 1000000, the largest frame the tools take" "frame above -frame's range"

# --- every stage's arguments checked by its tool, at submission ----------------------------
mkdir chk
refused() { # 'message part' LABEL ARGS...: submit (not dry) refused, exit 2, nothing queued
    local part="$1" label="$2"
    shift 2
    reset_slurm
    run "$farm" submit --frames 1001-1003 --workdir chk --name c "$@"
    expect_error 2 "$part" "$label"
    [[ ! -e stubs/sbatch.log && ! -e chk/.sss-farm ]] || fail "$label: something was submitted or written"
}
refused "--filter, frame 1001: ptfilter ERROR: unknown option -materail" "a misspelled ptfilter option" \
    --filter "-ssdiffusion -materail marble in.####.ptc out.####.ptc"
[[ "$(tail -n1 stderr)" == "sss-farm: try 'ptfilter --help'" ]] || fail "the hint of a refused option: $err"
refused "--filter, frame 1001: ptfilter ERROR: option -material: unknown material 'marbel'" "an unknown material" \
    --filter "-ssdiffusion -material marbel in.####.ptc out.####.ptc"
refused "--brick, frame 1001: brickmake ERROR: option -maxdepth: 99 is out of range [0, 20]" "brickmake's range" \
    --brick "-maxdepth 99 in.####.ptc out.####.bkm"
refused "--render (render2), frame 1001: render ERROR: unknown option -sample" "the second render" \
    --render "shot.rib" --render "-sample 4 shot.rib"
refused "--bake, frame 1001: ptbake ERROR: option -o: 'x.1001.exr' is not a point cloud file name" "ptbake -o" \
    --bake "-o x.####.exr bake.rib"
refused "ptfilter ERROR: -volume and -blocker cannot run in parts" "a split filter's part command" \
    --filter "-ssdiffusion -volume 1 in.####.ptc out.####.ptc" --splitpoints 10 --parts 2
# The last frame is checked too: the tools take frames up to 1000000 only.
run "$farm" submit --dry-run --frames 999999-1000000 --workdir chk --name c --render "shot.rib"
expect_rc 0 "the largest frames"
run "$farm" submit --dry-run --frames 1001-1003 --workdir chk --name c \
    --filter "-ssdiffusion -materail marble in.####.ptc out.####.ptc"
expect_error 2 "unknown option -materail" "a misspelled option, dry run"

# --- a submission: index -> frame, logs and status files per frame ----------------------------
mkdir shot
for f in 1001 1002 1003; do "$bin/ptsynth" -n 300 -size 5 "shot/in.$f.ptc" >/dev/null; done
filter="-ssdiffusion -material marble -unitlength 0.1 in.####.ptc out.####.ptc"
reset_slurm
run "$farm" submit --frames 1001-1003 --workdir shot --name s --filter "$filter" --brick "out.####.ptc out.####.bkm"
expect_rc 0 "submit 1001-1003"
spec="$work/shot/.sss-farm/s.json"
[[ "$(grep -c -- '--array=0-2 ' stubs/sbatch.log)" == 2 ]] || fail "the arrays are not 0-2: $(cat stubs/sbatch.log)"
grep -q -- "--requeue .*task $spec filter --submission 1\$" stubs/sbatch.log || fail "the filter's task: $(cat stubs/sbatch.log)"
[[ "$(field "$spec" 'j["submissions"][-1]["frames"], j["retries"]')" == "('1001-1003', 2)" ]] ||
    fail "the spec's frames and retries: $(cat "$spec")"
# Array task 1 is frame 1002: its log and status file are the frame's.
SLURM_ARRAY_JOB_ID=100 SLURM_ARRAY_TASK_ID=1 SLURM_JOB_ID=201 run "$farm" task "$spec" filter --submission 1
expect_rc 0 "array task 1"
[[ -f shot/out.1002.ptc && ! -e shot/out.1001.ptc && -z "$out" ]] || fail "array task 1 did not make frame 1002 only"
log=shot/logs/s-filter.1002.log
grep -q "== sss-farm: s filter frame 1002 (index 1) on .*attempt 1 of 3" "$log" || fail "task 1's log: $(cat "$log")"
grep -q -- "+ $bin/ptfilter -ssdiffusion -frame 1002 -newer 1 " "$log" || fail "task 1 did not run -frame 1002"
[[ "$(field shot/.sss-farm/status/s.filter.1002 'j["state"], j["exit"], j["attempt"], j["submission"]')" == "('done', 0, 1, 1)" ]] ||
    fail "status file of 1002: $(cat shot/.sss-farm/status/s.filter.1002)"
SLURM_ARRAY_TASK_ID=3 run "$farm" task "$spec" filter --submission 1
expect_error 2 "array index 3: submission 1 of s has 3 frames" "an index past the frames"
SLURM_ARRAY_TASK_ID=0 run "$farm" task "$spec" filter
expect_error 2 "an array task needs --submission N" "an array task without --submission"

# --- retries -------------------------------------------------------------------------
# Frame 1003's input is missing: ptfilter fails (1), the task requeues itself.
rm shot/in.1003.ptc
SLURM_ARRAY_JOB_ID=100 SLURM_ARRAY_TASK_ID=2 run "$farm" task "$spec" filter --submission 1
expect_rc 0 "a failed task that requeues itself"
[[ "$(cat stubs/requeue.log 2>/dev/null)" == "requeue 100_2" ]] || fail "no scontrol requeue 100_2: $(cat stubs/requeue.log 2>/dev/null)"
grep -q "sss-farm WARNING: s filter frame 1003: ptfilter exited with 1 (attempt 1 of 3): requeued" shot/logs/s-filter.1003.log ||
    fail "the requeue is not in the log: $(cat shot/logs/s-filter.1003.log)"
[[ "$(field shot/.sss-farm/status/s.filter.1003 'j["state"], j["exit"], j["attempt"]')" == "('retrying', 1, 1)" ]] ||
    fail "status file of the retried frame: $(cat shot/.sss-farm/status/s.filter.1003)"
# While Slurm holds it for its next attempt: pending, status exit 3.
echo "100 2 PENDING BeginTime" >stubs/squeue.txt
echo "JobId=300 ArrayJobId=100 ArrayTaskId=2 JobState=PENDING Reason=BeginTime Restarts=1 ExitCode=0:0" >stubs/jobs.txt
run "$farm" status "$spec"
expect_rc 3 "status while a retry is pending"
grep -Eq "^  filter +job 100 +not run 1001; done 1002; pending \(attempt 2 of 3\) 1003" stdout || fail "status of the retry: $out"
# The input made, the second attempt succeeds: done (attempt 2).
"$bin/ptsynth" -n 300 -size 5 shot/in.1003.ptc >/dev/null
SLURM_ARRAY_JOB_ID=100 SLURM_ARRAY_TASK_ID=2 SLURM_RESTART_COUNT=1 run "$farm" task "$spec" filter --submission 1
expect_rc 0 "the retry"
grep -q "frame 1003 (index 2) .*attempt 2 of 3" shot/logs/s-filter.1003.log || fail "the retry's log line"
rm -f stubs/squeue.txt stubs/jobs.txt
SLURM_ARRAY_JOB_ID=100 SLURM_ARRAY_TASK_ID=0 run "$farm" task "$spec" filter --submission 1
for i in 0 1 2; do SLURM_ARRAY_JOB_ID=101 SLURM_ARRAY_TASK_ID=$i run "$farm" task "$spec" brick --submission 1; done
run "$farm" status "$spec"
expect_rc 0 "status, every frame done"
grep -Eq "^  filter +job 100 +done 1001-1002; done \(attempt 2\) 1003; outputs exist: 1001-1003$" stdout ||
    fail "status after the retry: $out"
grep -q "^  done (exit 0): 6 done$" stdout || fail "status summary: $out"
run "$farm" status --json "$spec"
expect_rc 0 "status --json"
printf '%s' "$out" >status.json
[[ "$(field status.json 'sorted(j["stages"]["filter"]["frames"]["1003"])')" == \
    "['attempts', 'exit_code', 'frame', 'index', 'log', 'outputs', 'outputs_exist', 'reason', 'skipped', 'state']" ]] ||
    fail "the JSON keys of a frame: $(field status.json 'sorted(j["stages"]["filter"]["frames"]["1003"])')"
[[ "$(field status.json '[j[k] for k in ("result", "exit", "submission", "queued")]')" == "['done', 0, 1, '1001-1003']" ]] ||
    fail "the JSON summary: $out"
[[ "$(field status.json 'tuple(j["stages"]["filter"]["frames"]["1003"][k] for k in ("state", "exit_code", "attempts", "index", "log"))')" == \
    "('done', 0, 2, 2, '$work/shot/logs/s-filter.1003.log')" ]] || fail "the JSON of the retried frame: $out"
# The last attempt fails for good; a usage error is never retried; --retries 0.
rm -f stubs/requeue.log
rm shot/in.1003.ptc shot/out.1003.ptc
SLURM_ARRAY_JOB_ID=100 SLURM_ARRAY_TASK_ID=2 SLURM_RESTART_COUNT=2 run "$farm" task "$spec" filter --submission 1
expect_rc 1 "the last attempt"
grep -q "sss-farm ERROR: s filter frame 1003: ptfilter exited with 1 (attempt 3 of 3)" shot/logs/s-filter.1003.log ||
    fail "the last attempt's ERROR line"
[[ ! -e stubs/requeue.log ]] || fail "the last attempt was requeued"
REQUEUE_FAIL=1 SLURM_ARRAY_JOB_ID=100 SLURM_ARRAY_TASK_ID=2 run "$farm" task "$spec" filter --submission 1
expect_rc 1 "a requeue Slurm refuses: the task fails"
[[ "$(field shot/.sss-farm/status/s.filter.1003 'j["state"]')" == failed ]] || fail "refused requeue: not failed"
rm -f stubs/requeue.log
python3 - "$spec" <<'EOF'
import json, sys
s = json.load(open(sys.argv[1]))
s["stages"][1]["args"] = ["-bogus", "out.####.ptc", "out.####.bkm"]
json.dump(s, open(sys.argv[1], "w"))
EOF
SLURM_ARRAY_JOB_ID=101 SLURM_ARRAY_TASK_ID=0 run "$farm" task "$spec" brick --submission 1
expect_rc 2 "a usage error"
[[ ! -e stubs/requeue.log ]] || fail "a usage error was requeued"
run "$farm" status "$spec"
expect_rc 1 "status with failed frames"
grep -Eq "^  brick +job 101 +failed \(exit 2\) 1001; done 1002-1003" stdout || fail "status of the usage error: $out"

# --- cancelled, not failed ------------------------------------------------------------
# A tool stopped by SIGTERM (scancel, or Slurm's time limit): cancelled, exit
# 143, never retried; Slurm's CANCELLED for tasks that never ran; TIMEOUT wins.
mkdir tools
for t in ptfilter brickmake render ptinfo ptbake; do
    # shellcheck disable=SC2016
    printf '#!/bin/sh\n[ "$1" = -check ] && exit 0\ncase " $* " in *" -frame 2 "*) kill -TERM $$ ;; esac\nexit 0\n' >"tools/$t"
done
chmod +x tools/*
mkdir cancel
reset_slurm
SSS_BIN_DIR="$work/tools" run "$farm" submit --frames 1-4 --workdir cancel --name k --render "a.rib"
expect_rc 0 "submit with stub tools"
kspec="$work/cancel/.sss-farm/k.json"
for i in 0 1; do SLURM_ARRAY_JOB_ID=100 SLURM_ARRAY_TASK_ID=$i run "$farm" task "$kspec" render --submission 1; done
expect_rc 143 "a task whose tool was stopped by SIGTERM"
[[ ! -e stubs/requeue.log ]] || fail "a cancelled task was requeued"
[[ "$(field cancel/.sss-farm/status/k.render.2 'j["state"], j["exit"]')" == "('cancelled', 143)" ]] ||
    fail "status file of the cancelled task: $(cat cancel/.sss-farm/status/k.render.2)"
cat >stubs/jobs.txt <<'EOF'
JobId=103 ArrayJobId=100 ArrayTaskId=2 JobState=CANCELLED Reason=None Restarts=0 ExitCode=0:0
JobId=104 ArrayJobId=100 ArrayTaskId=3 JobState=TIMEOUT Reason=TimeLimit Restarts=0 ExitCode=0:15
EOF
run "$farm" status "$kspec"
expect_rc 1 "status with cancelled frames"
grep -Eq "^  render job 100 +done 1; cancelled 2-3; failed \(timeout\) 4;" stdout || fail "status of cancels: $out"
[[ "$out" != *"exit 143"* ]] || fail "a cancel shows as an exit code: $out"
# scontrol forgot the jobs (MinJobAge): the accounting (sacct) still knows.
rm stubs/jobs.txt
printf '100_2|CANCELLED by 0|0:15\n100_3|TIMEOUT|0:15\n' >stubs/sacct.txt
run "$farm" status --json "$kspec"
printf '%s' "$out" >status.json
[[ "$(field status.json '[(f["state"], f["reason"], f["exit_code"]) for f in j["stages"]["render"]["frames"].values()]')" == \
    "[('done', None, 0), ('cancelled', None, 143), ('cancelled', None, 143), ('failed', 'timeout', 143)]" ]] ||
    fail "status --json of cancels through sacct: $(field status.json '[(f["state"], f["reason"], f["exit_code"]) for f in j["stages"]["render"]["frames"].values()]')"
rm stubs/sacct.txt

# --- re-submission queues only the frames that need work ------------------------------------
# shot: frames 1001-1002 have up-to-date clouds and maps; 1003 has no input.
"$bin/ptsynth" -n 300 -size 5 shot/in.1003.ptc >/dev/null
python3 - "$spec" <<'EOF'
import json, sys
s = json.load(open(sys.argv[1]))
s["stages"][1]["args"] = ["out.####.ptc", "out.####.bkm"]
json.dump(s, open(sys.argv[1], "w"))
EOF
reset_slurm
run "$farm" submit --frames 1001-1003 --workdir shot --name s --filter "$filter" --brick "out.####.ptc out.####.bkm"
expect_rc 0 "re-submission"
grep -q "sss-farm: 2 of 3 frames up to date (outputs newer than inputs), not queued: 1001-1002; --force queues them" stdout ||
    fail "the re-submission does not say what it skipped: $out"
[[ "$(grep -c -- '--array=0 ' stubs/sbatch.log)" == 2 ]] || fail "the re-submission's arrays: $(cat stubs/sbatch.log)"
grep -q -- "filter --submission 2\$" stubs/sbatch.log || fail "the re-submission's task: $(cat stubs/sbatch.log)"
[[ "$(field "$spec" '(j["submissions"][-1]["frames"], j["submissions"][-1]["skipped"])')" == "('1003', '1001-1002')" ]] ||
    fail "the re-submission's frames: $(cat "$spec")"
SLURM_ARRAY_JOB_ID=100 SLURM_ARRAY_TASK_ID=0 run "$farm" task "$spec" filter --submission 2
SLURM_ARRAY_JOB_ID=101 SLURM_ARRAY_TASK_ID=0 run "$farm" task "$spec" brick --submission 2
[[ -f shot/out.1003.bkm ]] || fail "index 0 of the re-submission did not make frame 1003"
run "$farm" status "$spec"
expect_rc 0 "status after the re-submission"
grep -Eq "^  brick +job 101 +up to date 1001-1002; done 1003; outputs exist: 1001-1003$" stdout ||
    fail "status after the re-submission: $out"
# Everything up to date: nothing queued, exit 0; a newer input re-queues its frame; --force queues all.
reset_slurm
run "$farm" submit --frames 1001-1003 --workdir shot --name s --filter "$filter" --brick "out.####.ptc out.####.bkm"
expect_rc 0 "a submission with nothing to do"
[[ "$out" == *"3 of 3 frames up to date"*"every frame is up to date; nothing queued"* && ! -e stubs/sbatch.log ]] ||
    fail "nothing to do: $out"
run "$farm" status "$spec"
expect_rc 0 "status of a submission with nothing to do"
touch shot/out.1002.ptc
run "$farm" submit --dry-run --frames 1001-1003 --workdir shot --name s --filter "$filter" --brick "out.####.ptc out.####.bkm"
{ grep -q "not queued: 1001,1003;" stdout && grep -q "queuing 1 frame (1002)" stdout; } ||
    fail "a newer filter output does not re-queue its brick map's frame: $out"
run "$farm" submit --dry-run --force --frames 1001-1003 --workdir shot --name s --filter "$filter" --brick "out.####.ptc out.####.bkm"
{ grep -q "queuing 3 frames (1001-1003) as array indices 0-2" stdout && ! grep -q "not queued" stdout; } ||
    fail "--force: $out"
run "$farm" submit --dry-run --frames 1001-1003 --workdir shot --name s --filter "$filter -newer 0" \
    --brick "out.####.ptc out.####.bkm"
grep -q "queuing 3 frames" stdout || fail "-newer 0 in the arguments does not queue every frame: $out"

finish_checks sss-farm-studio
