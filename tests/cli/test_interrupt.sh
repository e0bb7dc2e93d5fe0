#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# CLI test of interrupted jobs (docs/cli-conventions.md, "Interrupted jobs"):
# SIGTERM or SIGINT while a tool writes its output leaves the previous file,
# if any, byte-identical (or no file at all), removes the temporary and ends
# the tool with 128 + signal. Covers every tool that writes: ptsynth, ptfilter,
# brickmake, brickinfo (-picture PNG and -lookup cloud), ptview (PNG), render
# (OpenEXR) and ptbake (gzip .ptc), both signals each; also signals during the computation
# (ptfilter, render), jobs with two outputs interrupted while writing the
# second (ptbake, render: neither output changes), and a SIGINT that the
# parent ignores. SIGKILL and the other tools: test_kill.sh.
#
# How the write is caught: see signals.sh. A tool that finishes first is
# retried with a bigger input; a case fails when no attempt catches the write.
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
ptview="$bin/ptview"
for tool in "$ptsynth" "$ptfilter" "$ptbake" "$brickmake" "$brickinfo" "$render" "$ptinfo" "$ptview"; do
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

# shellcheck source=signals.sh
source "$here/signals.sh"

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
make_view() {
    cloud 100000
    cmd=("$ptview" -res "$1" "$1" "$cloud_path" "$2")
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
    write_case "ptview-$sig" make_view "$sig" "$had" out.png 1024 2048 4096
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
# Two outputs, interrupted while the second is written: a job replaces all
# its outputs or none, so both keep their previous contents (the first one's
# finished temporary is removed with the second's).
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
            cmp -s "$dir/$first" "$dir/$first.orig" ||
                fail "$label: the first output $first was replaced although the job was interrupted"
            passed "$size"
            return
        fi
        [[ "$rc" == 0 ]] || { fail "$label: exit $rc before the write: $(<"$work/job.err")"; return; }
        echo "note: $label: size $size finished before its second write was caught; trying a bigger one"
    done
    fail "$label: no attempt caught the tool writing $second (sizes $*)"
}

multi_case ptbake-two-TERM make_ptbake_two TERM a.ptc b.ptc 0.01 0.005 0.0025
multi_case render-two-INT make_render_two INT a.exr b.exr 500 1000 2000

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
