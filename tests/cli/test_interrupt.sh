#!/usr/bin/env bash
# CLI test of interrupted jobs (docs/cli-conventions.md, "Interrupted jobs"):
# SIGTERM or SIGINT while a tool writes its output leaves the previous file,
# if any, byte-identical (or no file at all), removes the temporary and ends
# the tool with 128 + signal. Covers every tool that writes: ptsynth, ptfilter,
# brickmake, brickinfo (-picture PNG and -lookup cloud), render (OpenEXR) and
# ptbake (gzip .ptc), both signals each; also signals during the computation
# (ptfilter, render), jobs with two outputs interrupted while writing the
# second (ptbake, render), and a SIGINT that the parent ignores.
#
# How the write is caught: the script polls the target's folder until the
# hidden temporary ".NAME.*.tmp" appears, stops the tool (SIGSTOP), checks
# that the temporary still exists while every thread is stopped, sends the
# signal and resumes the tool (SIGCONT): the signal is then handled before
# the tool can commit. A tool that finishes first is retried with a bigger
# input; a case fails when no attempt catches the write.
# Needs SSS_BIN_DIR; Linux (/proc).
#
# Every check runs; failures are listed and the script exits 1 at the end.
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
ptsynth="$bin/ptsynth"
ptfilter="$bin/ptfilter"
ptbake="$bin/ptbake"
brickmake="$bin/brickmake"
brickinfo="$bin/brickinfo"
render="$bin/render"
ptinfo="$bin/ptinfo"
for tool in "$ptsynth" "$ptfilter" "$ptbake" "$brickmake" "$brickinfo" "$render" "$ptinfo"; do
    [[ -x "$tool" ]] || { echo "FAIL: missing executable $tool" >&2; exit 1; }
done
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_interrupt.XXXXXX")"
pid=""
cleanup() {
    # A tool still running after a failed check (only ever our own child).
    if [[ -n "$pid" ]] && kill -0 "$pid" 2>/dev/null; then
        kill -KILL "$pid" 2>/dev/null || true
        wait "$pid" 2>/dev/null || true
    fi
    rm -rf "$work"
}
trap cleanup EXIT
cd "$work"

# shellcheck source=lib.sh
source "$here/lib.sh"
# shellcheck source=checks.sh
source "$here/checks.sh"

# Generous limit for one tool run on a slow, loaded machine.
case_timeout=120
started_at=$SECONDS

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
                    if [[ "$sig" == "$ignored" ]]; then
                        in_mask SigIgn "$sig" || fail "$label: the tool does not ignore SIG$sig"
                    elif ! in_mask SigCgt "$sig"; then
                        fail "$label: the tool has no SIG$sig handler (the signal was not ignored when it started)"
                    fi
                    kill "-$sig" "$pid"
                done
                kill -CONT "$pid"
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

# catch_compute DIR TARGET SIG: waits for the first ALF_PROGRESS line (the
# tool computes), stops the tool and delivers SIG if no temporary and no
# TARGET exist yet. Sets hit=1 when delivered.
catch_compute() {
    local dir="$1" target="$2" sig="$3" deadline=$((SECONDS + case_timeout)) line computing
    hit=0
    while running; do
        computing=0
        while IFS= read -r line; do
            [[ "$line" == ALF_PROGRESS* ]] && computing=1 && break
        done <"$work/job.out"
        if ((computing)); then
            if stop_tool && ! has_temp "$dir" "" && [[ ! -e "$dir/$target" ]]; then
                kill "-$sig" "$pid"
                kill -CONT "$pid"
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

# Inputs, made once per size: synthetic clouds (uncompressed, quick to write).
mkdir -p "$work/in"
cloud_path=""
cloud() {
    cloud_path="$work/in/cloud$1.ptc"
    [[ -e "$cloud_path" ]] || "$ptsynth" -n "$1" "$cloud_path" >/dev/null
}
# A small brick map for brickinfo.
cloud 20000
"$brickmake" "$cloud_path" "$work/in/map.bkm"
# The render scene: one sphere; the primary EXR holds every AOV layer (a big
# write); with "two" also a second, rgba-only Display.
render_scene() {
    cat <<RIB
Format 64 64 1
PixelSamples 1 1
Projection "perspective" "fov" 35
Display "a.exr" "openexr" "rgba"
$([[ "$1" == two ]] && echo 'Display "+b.exr" "openexr" "rgba"')
Translate 0 0 6
WorldBegin
  LightSource "distantlight" 1 "from" [-3 3 4] "to" [0 0 0] "intensity" [1]
  AttributeBegin
    Surface "matte"
    Sphere 1 -1 1 360
  AttributeEnd
WorldEnd
RIB
}
render_scene one >"$work/in/one.rib"
render_scene two >"$work/in/two.rib"
# The bake scene: two spheres baked into two clouds, a.ptc and then b.ptc.
cat >"$work/in/bake.rib" <<'RIB'
Format 64 64 1
Projection "perspective" "fov" 40
Translate 0 0 5
WorldBegin
  LightSource "distantlight" 1 "from" [0 1 0] "to" [0 0 0] "intensity" [1]
  AttributeBegin
    Surface "bake_radiance_t" "string filename" ["a.ptc"]
    Translate -1.5 0 0
    Sphere 1 -1 1 360
  AttributeEnd
  AttributeBegin
    Surface "bake_radiance_t" "string filename" ["b.ptc"]
    Translate 1.5 0 0
    Sphere 1 -1 1 360
  AttributeEnd
WorldEnd
RIB

# Command builders: make_<case> SIZE TARGET sets cmd (run in the case folder).
make_ptsynth() { cmd=("$ptsynth" -n "$1" -compress 1 "$2"); }
make_ptfilter() {
    cloud "$1"
    cmd=("$ptfilter" -ssdiffusion -material skin1 -unitlength 1 -compress 1 -progress 1
        "$cloud_path" "$2")
}
make_brickmake() {
    cloud "$1"
    cmd=("$brickmake" "$cloud_path" "$2")
}
make_picture() { cmd=("$brickinfo" -info 0 -picture "$2" -size "$1" -level 0 "$work/in/map.bkm"); }
make_lookup() {
    cloud "$1"
    cmd=("$brickinfo" -info 0 -lookup "$cloud_path" "$2" -compress 1 "$work/in/map.bkm")
}
make_render() { cmd=("$render" -progress 1 -res "$1" "$1" -o "$2" "$work/in/one.rib"); }
make_render_two() { cmd=("$render" -res "$1" "$1" "$work/in/two.rib"); }
make_ptbake() { cmd=("$ptbake" -compress 1 -spacing "$1" -o "$2" "$work/in/bake.rib"); }
make_ptbake_two() { cmd=("$ptbake" -compress 1 -spacing "$1" "$work/in/bake.rib"); }

cases=0
# passed SIZE: counts a caught job and says where it was caught.
passed() {
    cases=$((cases + 1))
    echo "$label: caught (size $1), exit $rc"
}
# write_case LABEL BUILDER SIG HAD_PREVIOUS TARGET SIZE...: interrupts the
# write of TARGET, trying each SIZE until the write is caught.
write_case() {
    label="$1"
    local builder="$2" sig="$3" had="$4" target="$5" size dir
    shift 5
    for size in "$@"; do
        dir="$work/$label.$size"
        mkdir -p "$dir"
        ((had)) && previous "$dir/$target"
        "$builder" "$size" "$target"
        start "$dir" "${cmd[@]}"
        catch_write "$dir" "$target" "$sig"
        if ((hit)); then
            check_interrupted "$dir" "$target" "$sig" "$had"
            passed "$size"
            return
        fi
        [[ "$rc" == 0 ]] || { fail "$label: exit $rc before the write: $(<"$work/job.err")"; return; }
        echo "note: $label: size $size finished before its write was caught; trying a bigger one"
    done
    fail "$label: no attempt caught the tool writing $target (sizes $*)"
}

# compute_case LABEL BUILDER SIG TARGET SIZE...: interrupts the computation,
# before any file is created: nothing may be written.
compute_case() {
    label="$1"
    local builder="$2" sig="$3" target="$4" size dir
    shift 4
    for size in "$@"; do
        dir="$work/$label.$size"
        mkdir -p "$dir"
        "$builder" "$size" "$target"
        start "$dir" "${cmd[@]}"
        catch_compute "$dir" "$target" "$sig"
        if ((hit)); then
            check_interrupted "$dir" "$target" "$sig" 0
            passed "$size"
            return
        fi
        [[ "$rc" == 0 ]] || { fail "$label: exit $rc: $(<"$work/job.err")"; return; }
        echo "note: $label: size $size finished before its computation was caught; trying a bigger one"
    done
    fail "$label: no attempt caught the computation (sizes $*)"
}

# ---------------------------------------------------------------------------
# One output per tool, SIGTERM onto a previous file and SIGINT with none.
for sig in TERM INT; do
    had=$([[ $sig == TERM ]] && echo 1 || echo 0)
    write_case "ptsynth-$sig" make_ptsynth "$sig" "$had" out.ptc 200000 800000 3200000
    write_case "ptfilter-$sig" make_ptfilter "$sig" "$had" out.ptc 20000 80000 320000
    write_case "brickmake-$sig" make_brickmake "$sig" "$had" out.bkm 100000 400000 1600000
    write_case "brickinfo-picture-$sig" make_picture "$sig" "$had" out.png 1024 2048 4096
    write_case "brickinfo-lookup-$sig" make_lookup "$sig" "$had" out.ptc 100000 400000 1600000
    write_case "render-$sig" make_render "$sig" "$had" out.exr 500 1000 2000
    write_case "ptbake-$sig" make_ptbake "$sig" "$had" out.ptc 0.01 0.005 0.0025
done

# SIGHUP (a closed terminal or ssh session) cleans up the same way.
write_case "ptfilter-HUP" make_ptfilter HUP 1 out.ptc 20000 80000 320000

# The computation: nothing is written, no temporary exists.
for sig in TERM INT; do
    compute_case "ptfilter-compute-$sig" make_ptfilter "$sig" out.ptc 20000 80000 320000
    compute_case "render-compute-$sig" make_render "$sig" out.exr 500 1000 2000
done

# ---------------------------------------------------------------------------
# Two outputs, interrupted while the second is written: every file is atomic
# on its own, and the first, already complete, stays (the new one); the
# second keeps its previous contents.
ptbake_ref="$work/ptbake_ref"
mkdir -p "$ptbake_ref"
# multi_case LABEL BUILDER SIG FIRST SECOND SIZE...
multi_case() {
    label="$1"
    local builder="$2" sig="$3" first="$4" second="$5" size dir
    shift 5
    for size in "$@"; do
        dir="$work/$label.$size"
        mkdir -p "$dir"
        previous "$dir/$first"
        previous "$dir/$second"
        "$builder" "$size"
        start "$dir" "${cmd[@]}"
        catch_write "$dir" "$second" "$sig"
        if ((hit)); then
            check_interrupted "$dir" "$second" "$sig" 1
            if cmp -s "$dir/$first" "$dir/$first.orig"; then
                fail "$label: the first output $first was not replaced although it was complete"
            fi
            passed "$size"
            last_dir="$dir"
            last_size="$size"
            return
        fi
        [[ "$rc" == 0 ]] || { fail "$label: exit $rc before the write: $(<"$work/job.err")"; return; }
        echo "note: $label: size $size finished before its second write was caught; trying a bigger one"
    done
    fail "$label: no attempt caught the tool writing $second (sizes $*)"
    last_dir=""
}

last_dir=""
multi_case ptbake-two-TERM make_ptbake_two TERM a.ptc b.ptc 0.01 0.005 0.0025
if [[ -n "$last_dir" ]]; then
    # The first cloud is the complete bake: byte-identical to an uninterrupted one.
    (cd "$ptbake_ref" && "$ptbake" -compress 1 -spacing "$last_size" "$work/in/bake.rib" >/dev/null)
    cmp -s "$last_dir/a.ptc" "$ptbake_ref/a.ptc" ||
        fail "ptbake-two: the kept a.ptc differs from an uninterrupted bake's"
fi
last_dir=""
multi_case render-two-INT make_render_two INT a.exr b.exr 500 1000 2000
if [[ -n "$last_dir" ]]; then
    # The first image is a complete OpenEXR file (magic number, a real size).
    magic="$(head -c 4 "$last_dir/a.exr" | od -An -tx1 | tr -d ' \n')"
    [[ "$magic" == 762f3101 ]] || fail "render-two: the kept a.exr is not an OpenEXR file"
    (($(stat -c %s "$last_dir/a.exr") > 10000)) || fail "render-two: the kept a.exr is too small"
fi

# ---------------------------------------------------------------------------
# A SIGINT ignored by the parent (nohup, background jobs of a shell without
# job control, some farm daemons) stays ignored: the tool finishes and writes
# its output; SIGTERM still interrupts it.
# start_ignoring_int DIR SIZE: ptsynth with SIGINT ignored, as its parent would.
start_ignoring_int() {
    : >"$work/job.out"
    (
        cd "$1"
        trap '' INT
        trap - TERM
        exec "$ptsynth" -n "$2" -compress 1 out.ptc
    ) >"$work/job.out" 2>"$work/job.err" &
    pid=$!
}
ignored=INT
label="ignored-INT"
dir="$work/$label"
mkdir -p "$dir"
for size in 200000 800000 3200000; do
    rm -f "$dir/out.ptc"
    start_ignoring_int "$dir" "$size"
    catch_write "$dir" out.ptc INT
    ((hit)) && break
done
if ((hit)); then
    [[ "$rc" == 0 ]] || fail "$label: exit $rc, expected 0 (SIGINT ignored)"
    [[ "$("$ptinfo" "$dir/out.ptc" 2>/dev/null | sed -n 's/^points: *//p')" =~ ^[1-9] ]] ||
        fail "$label: out.ptc is not a complete cloud"
    [[ -z "$(compgen -G "$dir/.*.tmp" || true)" ]] || fail "$label: temporary files left behind"
    passed "$size"
else
    fail "$label: no attempt caught the write"
fi
# INT (ignored: discarded) then TERM, both while the tool is stopped in the
# write: had INT been handled, the tool would die from it (130), not 143.
label="ignored-INT-then-TERM"
dir="$work/$label"
mkdir -p "$dir"
for size in 200000 800000 3200000; do
    previous "$dir/out.ptc"
    start_ignoring_int "$dir" "$size"
    catch_write "$dir" out.ptc "INT TERM"
    ((hit)) && break
done
if ((hit)); then
    check_interrupted "$dir" out.ptc TERM 1
    passed "$size"
else
    fail "$label: no attempt caught the write"
fi
ignored=""

echo "interrupted $cases jobs in $((SECONDS - started_at)) s"
finish_checks interrupt
