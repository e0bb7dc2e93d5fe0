# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# Shared helpers of the CLI tests that signal a running tool
# (test_interrupt.sh, test_kill.sh; sourced after lib.sh and checks.sh).
# Needs $work (a scratch folder) and $case_timeout (seconds one tool run may
# take); uses $pid (the running tool) and $label (the case, for messages).
# Linux only (/proc).
#
# How a write is caught without sleeping: poll the target's folder until the
# hidden temporary ".NAME.*.tmp" appears, stop the tool (SIGSTOP), check that
# the temporary still exists while every thread is stopped, send the signal
# and resume the tool (SIGCONT): the signal is then handled (or, for SIGKILL,
# takes effect) before the tool can commit.

# nap SECONDS: sleeps without starting a process (read with a timeout on a
# FIFO nobody writes to).
mkfifo "$work/.nap"
exec {nap_fd}<>"$work/.nap"
nap() { read -r -t "$1" -u "$nap_fd" || true; }

# running: true while $pid has not ended (not a zombie). No subshell: this
# runs in the polling loops.
running() {
    local s=""
    read -r _ _ s _ 2>/dev/null <"/proc/$pid/stat" || return 1
    [[ "$s" != Z && "$s" != X ]]
}

# stop_tool: SIGSTOPs $pid and waits until every thread is stopped. Fails
# (status 1) when the process ended instead.
stop_tool() {
    kill -STOP "$pid" 2>/dev/null || return 1
    local t s all deadline=$((SECONDS + case_timeout))
    while ((SECONDS < deadline)); do
        all=1
        for t in /proc/"$pid"/task/*/stat; do
            s=""
            read -r _ _ s _ 2>/dev/null <"$t" || continue
            [[ "$s" == Z || "$s" == X ]] && return 1
            [[ "$s" == T || "$s" == t ]] || all=0
        done
        [[ -d /proc/$pid ]] || return 1
        ((all)) && return 0
        nap 0.001
    done
    return 1
}

# in_mask FIELD SIG: true when $pid's /proc status mask FIELD (SigCgt: a
# handler is installed, SigIgn: ignored) holds SIG.
in_mask() {
    local key value n
    n="$(kill -l "$2")"
    while read -r key value; do
        if [[ "$key" == "$1:" ]]; then
            (((0x$value >> (n - 1)) & 1)) && return 0
            return 1
        fi
    done <"/proc/$pid/status"
    return 1
}

# start DIR CMD...: runs CMD in DIR in the background with SIGINT and SIGTERM
# at their default dispositions (a non-interactive bash starts background
# jobs with SIGINT ignored, and the tools leave an ignored signal ignored),
# stdout in $work/job.out, stderr in $work/job.err. Sets $pid.
start() {
    local dir="$1"
    shift
    : >"$work/job.out"
    (
        cd "$dir"
        trap - INT TERM HUP
        exec "$@"
    ) >"$work/job.out" 2>"$work/job.err" &
    pid=$!
}

# finish: waits for $pid; its exit status in $rc.
finish() {
    set +e
    wait "$pid"
    rc=$?
    set -e
    pid=""
}

# has_temp DIR NAME: a temporary of NAME (or of anything when NAME is "") in DIR.
has_temp() { compgen -G "$1/.$2*.tmp" >/dev/null; }

# overdue DEADLINE: once SECONDS is past DEADLINE, fails the case, kills the
# tool and returns 0.
overdue() {
    ((SECONDS > $1)) || return 1
    fail "$label: still running after ${case_timeout} s"
    kill -KILL "$pid"
}

# catch_write DIR NAME "SIG...": polls DIR until the temporary of NAME exists,
# then delivers the signals while it still does (see the top). Sets hit=1
# when delivered. Each signal must have a handler, except $ignored, which
# must be ignored.
ignored=""
catch_write() {
    local dir="$1" name="$2" sigs="$3" deadline=$((SECONDS + case_timeout)) sig
    hit=0
    while running; do
        if has_temp "$dir" "$name."; then
            if stop_tool && has_temp "$dir" "$name."; then
                for sig in $sigs; do
                    if [[ "$sig" == KILL ]]; then
                        : # cannot be caught or ignored
                    elif [[ "$sig" == "$ignored" ]]; then
                        in_mask SigIgn "$sig" || fail "$label: the tool does not ignore SIG$sig"
                    elif ! in_mask SigCgt "$sig"; then
                        fail "$label: the tool has no SIG$sig handler (the signal was not ignored when it started)"
                    fi
                    kill "-$sig" "$pid"
                done
                kill -CONT "$pid" 2>/dev/null || true
                hit=1
                break
            fi
            kill -CONT "$pid" 2>/dev/null || true
        fi
        overdue "$deadline" && break
        nap 0.005
    done
    finish
}

# catch_compute DIR TARGET SIG [HAD_PREVIOUS]: waits for the first
# ALF_PROGRESS line (the tool computes), stops the tool and delivers SIG if
# no temporary exists yet, nor TARGET (unless HAD_PREVIOUS is 1: a previous
# file). Sets hit=1 when delivered.
catch_compute() {
    local dir="$1" target="$2" sig="$3" had="${4:-0}" deadline=$((SECONDS + case_timeout))
    local line computing
    hit=0
    while running; do
        computing=0
        while IFS= read -r line; do
            [[ "$line" == ALF_PROGRESS* ]] && computing=1 && break
        done <"$work/job.out"
        if ((computing)); then
            if stop_tool && ! has_temp "$dir" "" && { ((had)) || [[ ! -e "$dir/$target" ]]; }; then
                kill "-$sig" "$pid"
                kill -CONT "$pid" 2>/dev/null || true
                hit=1
                break
            fi
            kill -CONT "$pid" 2>/dev/null || true
            break
        fi
        overdue "$deadline" && break
        nap 0.005
    done
    finish
}

# previous FILE: gives FILE known contents, kept in FILE.orig for comparison
# (not a .tmp name, so it never counts as a left-over temporary).
previous() {
    printf 'previous contents of %s\n' "$(basename "$1")" >"$1"
    cp "$1" "$1.orig"
}

# check_interrupted DIR TARGET SIG HAD_PREVIOUS: the outcome of a caught signal.
check_interrupted() {
    local dir="$1" target="$2" sig="$3" had="$4" left
    local want=$((128 + $(kill -l "$sig")))
    [[ "$rc" == "$want" ]] || fail "$label: exit status $rc, expected $want (128 + SIG$sig)"$'\n'"  stderr: $(<"$work/job.err")"
    if ((had)); then
        cmp -s "$dir/$target" "$dir/$target.orig" || fail "$label: the previous $target was not kept byte-identical"
    else
        [[ ! -e "$dir/$target" ]] || fail "$label: $target exists after the interrupted write"
    fi
    left="$(compgen -G "$dir/.*.tmp" || true)"
    [[ -z "$left" ]] || fail "$label: temporary files left behind: $left"
}

