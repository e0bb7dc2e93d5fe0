#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# CLI test of killed jobs, every tool that writes (docs/cli-conventions.md,
# "Interrupted jobs"):
#  - SIGTERM while shader and envdome write (the other tools:
#    test_interrupt.sh): exit 143, the previous output byte-identical, no
#    temporary left;
#  - SIGKILL while ptsynth, ptfilter, brickmake, brickinfo (-picture and
#    -lookup), ptview, render, ptbake, shader and envdome (-sky) write: exit 137, the
#    previous output byte-identical, the writer's temporary left behind; the
#    next run of the same job removes it (it owns it: same target, this host,
#    its writer gone) and writes the new output;
#  - SIGTERM and SIGKILL while envdome computes its dome (its RIB write is
#    too short to catch): nothing written, nothing left;
#  - a live job's temporary is never removed: a second job on the same
#    target, run to the end while the first one is stopped in its write,
#    leaves the first one's temporary alone, and the first one then finishes.
# How a write is caught: signals.sh (no sleeps: poll for the temporary,
# SIGSTOP, check, signal, SIGCONT). Needs SSS_BIN_DIR; Linux (/proc).
#
# Every check runs; failures are listed and the script exits 1 at the end.
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
for tool in ptsynth ptfilter brickmake brickinfo ptview render ptbake shader envdome ptinfo; do
    [[ -x "$bin/$tool" ]] || { echo "FAIL: missing executable $bin/$tool" >&2; exit 1; }
done
ptinfo="$bin/ptinfo"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_kill.XXXXXX")"
pid=""
other=""
cleanup() {
    # Tools still running after a failed check (only ever our own children).
    local p
    for p in "$pid" "$other"; do
        if [[ -n "$p" ]] && kill -0 "$p" 2>/dev/null; then
            kill -KILL "$p" 2>/dev/null || true
            wait "$p" 2>/dev/null || true
        fi
    done
    rm -rf "$work"
}
trap cleanup EXIT
cd "$work"

# shellcheck source=lib.sh
source "$here/lib.sh"
# shellcheck source=checks.sh
source "$here/checks.sh"
case_timeout=120
started_at=$SECONDS
# shellcheck source=signals.sh
source "$here/signals.sh"

# ---------------------------------------------------------------------------
# Inputs, made once per size.
mkdir -p "$work/in"
cloud_path=""
cloud() {
    cloud_path="$work/in/cloud$1.ptc"
    [[ -e "$cloud_path" ]] || "$bin/ptsynth" -n "$1" "$cloud_path" >/dev/null
}
cloud 20000
"$bin/brickmake" "$cloud_path" "$work/in/map.bkm"
# A shader source with N statements (a large .slo to write).
shader_source() {
    local f="$work/in/big$1.sl" i
    if [[ ! -e "$f" ]]; then
        {
            echo "surface big$1(float k = 1;) {"
            echo "  float x = 0;"
            for ((i = 0; i < $1; ++i)); do echo "  x = x + sin(k * $i) * $((i % 7));"; done
            echo "  Ci = color(x); Oi = Os;"
            echo "}"
        } >"$f"
    fi
    source_path="$f"
}
# A light probe for the dome (a procedural sky, lat-long).
"$bin/envdome" -sky 2048 1024 "$work/in/probe.exr" >/dev/null
cat >"$work/in/one.rib" <<'RIB'
Format 64 64 1
PixelSamples 1 1
Projection "perspective" "fov" 35
Display "a.exr" "openexr" "rgba"
Translate 0 0 6
WorldBegin
  LightSource "distantlight" 1 "from" [-3 3 4] "to" [0 0 0] "intensity" [1]
  AttributeBegin
    Surface "matte"
    Sphere 1 -1 1 360
  AttributeEnd
WorldEnd
RIB
cat >"$work/in/bake.rib" <<'RIB'
Format 64 64 1
Projection "perspective" "fov" 40
Translate 0 0 5
WorldBegin
  LightSource "distantlight" 1 "from" [0 1 0] "to" [0 0 0] "intensity" [1]
  AttributeBegin
    Surface "bake_radiance_t" "string filename" ["a.ptc"]
    Sphere 1 -1 1 360
  AttributeEnd
WorldEnd
RIB

# Command builders: make_<case> SIZE TARGET sets cmd (run in the case folder).
make_ptsynth() { cmd=("$bin/ptsynth" -n "$1" -compress 1 "$2"); }
make_ptfilter() {
    cloud "$1"
    cmd=("$bin/ptfilter" -ssdiffusion -material skin1 -unitlength 1 -compress 1 "$cloud_path" "$2")
}
make_brickmake() {
    cloud "$1"
    cmd=("$bin/brickmake" "$cloud_path" "$2")
}
make_picture() { cmd=("$bin/brickinfo" -info 0 -picture "$2" -size "$1" -level 0 "$work/in/map.bkm"); }
make_lookup() {
    cloud "$1"
    cmd=("$bin/brickinfo" -info 0 -lookup "$cloud_path" "$2" -compress 1 "$work/in/map.bkm")
}
make_view() {
    cloud 100000
    cmd=("$bin/ptview" -res "$1" "$1" "$cloud_path" "$2")
}
make_render() { cmd=("$bin/render" -res "$1" "$1" -o "$2" "$work/in/one.rib"); }
make_ptbake() { cmd=("$bin/ptbake" -compress 1 -spacing "$1" -o "$2" "$work/in/bake.rib"); }
make_shader() {
    shader_source "$1"
    cmd=("$bin/shader" -q -o "$2" "$source_path")
}
make_sky() { cmd=("$bin/envdome" -sky $((2 * $1)) "$1" "$2"); }
make_dome() { cmd=("$bin/envdome" -progress 1 -n "$1" "$work/in/probe.exr" "$2"); }

cases=0
passed() {
    cases=$((cases + 1))
    echo "$label: caught (size $1), exit $rc"
}

# temps_of DIR TARGET: the temporaries of TARGET in DIR (one a line).
temps_of() { compgen -G "$1/.$2.*.tmp" || true; }

# check_killed DIR TARGET: the outcome of a SIGKILL during the write: 137,
# the previous file intact, the writer's temporary still there.
check_killed() {
    local dir="$1" target="$2"
    [[ "$rc" == 137 ]] || fail "$label: exit status $rc, expected 137 (128 + SIGKILL)"
    cmp -s "$dir/$target" "$dir/$target.orig" || fail "$label: the previous $target was not kept byte-identical"
    [[ -n "$(temps_of "$dir" "$target")" ]] || fail "$label: no temporary left (was the write caught?)"
}

# rerun DIR TARGET BUILDER SIZE: the next run of the job removes the stale
# temporary and writes the output.
rerun() {
    local dir="$1" target="$2" builder="$3" size="$4"
    "$builder" "$size" "$target"
    pushd "$dir" >/dev/null
    run "${cmd[@]}"
    popd >/dev/null
    expect_rc 0 "$label, the next run" || return 0
    [[ -z "$(temps_of "$dir" "$target")" ]] || fail "$label: the next run left the stale temporary: $(temps_of "$dir" "$target")"
    [[ -z "$(compgen -G "$dir/.*.tmp" || true)" ]] || fail "$label: temporaries left after the next run"
    cmp -s "$dir/$target" "$dir/$target.orig" && fail "$label: the next run did not write $target"
    [[ -s "$dir/$target" ]] || fail "$label: the next run wrote an empty $target"
}

# write_case LABEL BUILDER SIG TARGET SIZE...: signals the write of TARGET
# (previous contents kept in TARGET.orig), trying each SIZE until caught;
# after SIGKILL, a run at the first size must clean up.
write_case() {
    label="$1"
    local builder="$2" sig="$3" target="$4" size dir first="$5"
    shift 4
    for size in "$@"; do
        dir="$work/$label.$size"
        mkdir -p "$dir"
        previous "$dir/$target"
        "$builder" "$size" "$target"
        start "$dir" "${cmd[@]}"
        catch_write "$dir" "$target" "$sig"
        if ((hit)); then
            if [[ "$sig" == KILL ]]; then
                check_killed "$dir" "$target"
                local killed="$rc"
                rerun "$dir" "$target" "$builder" "$first"
                rc="$killed"
            else
                check_interrupted "$dir" "$target" "$sig" 1
            fi
            passed "$size"
            return
        fi
        [[ "$rc" == 0 ]] || { fail "$label: exit $rc before the write: $(<"$work/job.err")"; return; }
        echo "note: $label: size $size finished before its write was caught; trying a bigger one"
    done
    fail "$label: no attempt caught the tool writing $target (sizes $*)"
}

# compute_case LABEL BUILDER SIG TARGET SIZE...: signals the computation
# (after the first progress line, before any temporary): the previous
# output stays, nothing is left behind.
compute_case() {
    label="$1"
    local builder="$2" sig="$3" target="$4" size dir
    shift 4
    for size in "$@"; do
        dir="$work/$label.$size"
        mkdir -p "$dir"
        previous "$dir/$target"
        "$builder" "$size" "$target"
        start "$dir" "${cmd[@]}"
        catch_compute "$dir" "$target" "$sig" 1
        if ((hit)); then
            local want=$((128 + $(kill -l "$sig")))
            [[ "$rc" == "$want" ]] || fail "$label: exit status $rc, expected $want"
            cmp -s "$dir/$target" "$dir/$target.orig" || fail "$label: the previous $target changed"
            [[ -z "$(compgen -G "$dir/.*.tmp" || true)" ]] || fail "$label: temporaries left behind"
            passed "$size"
            return
        fi
        [[ "$rc" == 0 ]] || { fail "$label: exit $rc: $(<"$work/job.err")"; return; }
        echo "note: $label: size $size finished before its computation was caught; trying a bigger one"
    done
    fail "$label: no attempt caught the computation (sizes $*)"
}

# ---------------------------------------------------------------------------
# SIGTERM for the tools test_interrupt.sh does not cover.
write_case shader-TERM make_shader TERM out.slo 20000 80000 320000
write_case sky-TERM make_sky TERM sky.exr 512 1024 2048
compute_case dome-TERM make_dome TERM dome.rib 4096 16384 65536

# SIGKILL for every tool that writes.
write_case ptsynth-KILL make_ptsynth KILL out.ptc 200000 800000 3200000
write_case ptfilter-KILL make_ptfilter KILL out.ptc 20000 80000 320000
write_case brickmake-KILL make_brickmake KILL out.bkm 100000 400000 1600000
write_case brickinfo-picture-KILL make_picture KILL out.png 1024 2048 4096
write_case brickinfo-lookup-KILL make_lookup KILL out.ptc 100000 400000 1600000
write_case ptview-KILL make_view KILL out.png 1024 2048 4096
write_case render-KILL make_render KILL out.exr 500 1000 2000
write_case ptbake-KILL make_ptbake KILL out.ptc 0.01 0.005 0.0025
write_case shader-KILL make_shader KILL out.slo 20000 80000 320000
write_case sky-KILL make_sky KILL sky.exr 512 1024 2048
compute_case dome-KILL make_dome KILL dome.rib 4096 16384 65536

# ---------------------------------------------------------------------------
# A live job's temporary is never touched: job A is stopped in its write
# while job B writes the same target from start to end.
label="live-temporary"
dir="$work/$label"
mkdir -p "$dir"
hit=0
for size in 200000 800000 3200000; do
    make_ptsynth "$size" out.ptc
    start "$dir" "${cmd[@]}"
    deadline=$((SECONDS + case_timeout))
    while running && ! has_temp "$dir" out.ptc.; do
        overdue "$deadline" && break
        nap 0.005
    done
    if has_temp "$dir" out.ptc. && stop_tool && has_temp "$dir" out.ptc.; then
        hit=1
        break
    fi
    kill -CONT "$pid" 2>/dev/null || true
    finish
    rm -f "$dir/out.ptc"
done
if ((hit)); then
    mine="$(temps_of "$dir" out.ptc)"
    pushd "$dir" >/dev/null
    run "$bin/ptsynth" -n 1000 out.ptc
    popd >/dev/null
    expect_rc 0 "$label: the second job" || true
    [[ -e "$mine" ]] || fail "$label: the second job removed the live job's temporary $mine"
    [[ "$(points "$dir/out.ptc")" == 1000 ]] || fail "$label: the second job's output is not in place"
    kill -CONT "$pid"
    finish
    [[ "$rc" == 0 ]] || fail "$label: the first job failed after the second ran: $(<"$work/job.err")"
    [[ "$(points "$dir/out.ptc")" == "$size" ]] || fail "$label: the first job's output is not in place"
    [[ -z "$(compgen -G "$dir/.*.tmp" || true)" ]] || fail "$label: temporaries left behind"
    passed "$size"
else
    fail "$label: no attempt caught the first job writing"
fi

echo "killed $cases jobs in $((SECONDS - started_at)) s"
finish_checks kill
