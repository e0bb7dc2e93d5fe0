#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# -check, the dry parse every tool shares (docs/cli-conventions.md): each
# tool accepts a good command line whose files do not exist (exit 0, nothing
# printed, nothing written; frame patterns with and without -frame), refuses
# a misspelled option, a missing value, an impossible number and an unknown
# material with its usual ERROR line and exit 2, reads no input (a FIFO given
# as input is never opened) and leaves existing outputs alone. Needs
# SSS_BIN_DIR (the build's bin folder).
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must point at the build bin folder}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
# shellcheck source=tests/cli/lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
# shellcheck source=tests/cli/checks.sh
source "$(dirname "${BASH_SOURCE[0]}")/checks.sh"
mkdir "$work/cwd"
cd "$work/cwd"

# accepted TOOL ARGS...: -check exits 0, silent.
accepted() {
    local tool="$1"
    shift
    run "$bin/$tool" -check "$@"
    if expect_rc 0 "$tool -check $*"; then
        [[ -z "$out$err" ]] || fail "$tool -check $*: printed '$out' '$err'"
    fi
}
# refused TOOL 'message part' ARGS...: -check exits 2 with one ERROR line
# holding the message part (and the usual --help hint for usage errors).
refused() {
    local tool="$1" part="$2"
    shift 2
    run "$bin/$tool" "$@"
    expect_rc 2 "$tool $*" || return 0
    local line
    line="$(grep "^$tool ERROR: " "$work/stderr" || true)"
    [[ "$line" != *$'\n'* && "$line" == *"$part"* ]] || fail "$tool $*: the ERROR line of '$err' lacks '$part'"
}

# --- good command lines, files that do not exist --------------------------------
accepted ptfilter -ssdiffusion -material marble -unitlength 0.1 in.%04d.ptc out.%04d.ptc
accepted ptfilter -ssdiffusion -frame 1001 -material skin1 -newer 1 -threads 4 in.####.ptc out.####.ptc
accepted ptfilter -ssdiffusion -part 2/4 in.ptc out.ptc.part2of4.ptpart
accepted ptfilter -merge a.ptpart b.ptpart out.ptc
accepted ptbake -frame 7 -spacing 0.06 -material marble bake.\$F4.rib
accepted brickmake -maxerror 0.002 -frame 1 in.####.ptc out.####.bkm
accepted brickinfo -picture map.png -level all -frame 3 map.####.bkm
accepted render -frame 2 -res 64 48 -o img.####.exr shot.rib
accepted ptinfo -stats 0 a.ptc b.ply
accepted ptsynth -shape box -n 1000 out.ply
accepted ptview -channel _radiance_t -o view.png a.ptc
accepted shader -I include -DFOO=1 missing.sl
accepted sloinfo -json 1 missing.slo
accepted envdome -n 16 probe.exr dome.rib
accepted envdome -sky 64 32 sky.exr
accepted ssprofile -material marble -profile classic,mc -photons 1000
accepted ssprofile -scene scene.rib -unitlength 0.1 baked.ptc truth.ptc
# --check and anywhere on the line
run "$bin/ptfilter" -ssdiffusion in.ptc --check out.ptc
expect_rc 0 "--check after the first file"
[[ -z "$(ls -A)" ]] || fail "the accepted checks wrote into the folder: $(ls -A)"

# --- refused: the tools' own messages, exit 2 --------------------------------------
refused ptfilter "unknown option -materail" -check -ssdiffusion -materail marble in.ptc out.ptc
refused ptfilter "unknown material 'marbel'" -check -ssdiffusion -material marbel in.ptc out.ptc
refused ptfilter "impossible -albedo value" -check -ssdiffusion -albedo 2 2 2 in.ptc out.ptc
refused ptfilter "option -maxsolidangle: must be > 0" -check -ssdiffusion -maxsolidangle 0 in.ptc out.ptc
refused ptfilter "option -frame: 2000000 is out of range" -check -ssdiffusion -frame 2000000 in.ptc out.ptc
refused ptfilter "cannot run in parts" -check -ssdiffusion -volume 1 -part 1/2 in.ptc out.ptpart
refused ptfilter "'out.xyz' is not a point cloud file name" -check -ssdiffusion in.ptc out.xyz
refused ptfilter "lone '#'" -check -ssdiffusion -frame 1 in.#.ptc out.ptc
refused ptfilter "unknown instruction set 'bogus'" -check -ssdiffusion -isa bogus in.ptc out.ptc
SSS_ISA=bogus run "$bin/ptfilter" -check -ssdiffusion in.ptc out.ptc
expect_rc 2 "SSS_ISA=bogus"
refused ptbake "unknown option -spacng" -check -spacng 0.06 bake.rib
refused ptbake "unknown material" -check -material jelly bake.rib
refused ptbake "more than one scene" -check a.rib b.rib
refused brickmake "option -maxerror needs a value" -check in.ptc out.bkm -maxerror
refused brickmake "option -maxdepth: 40 is out of range" -check -maxdepth 40 in.ptc out.bkm
refused brickinfo "need -picture" -check -level 2 map.bkm
refused render "option -samples: 0 is out of range" -check -samples 0 shot.rib
refused render "is not an image file name" -check -o img.xyz shot.rib
refused ptinfo "unknown option -stat" -check -stat 0 a.ptc
refused ptsynth "option -size: must be > 0" -check -size 0 out.ptc
refused ptview "'out.jpg' does not end in .png or .exr" -check a.ptc out.jpg
refused shader "unknown option -x" -check -x a.sl
refused sloinfo "missing input file" -check
refused envdome "-n must be a power of two" -check -n 3 probe.exr dome.rib
refused envdome "more than one probe" -check a.exr b.exr dome.rib
refused ssprofile "unknown material" -check -material jelly
refused ssprofile "impossible -albedo value" -check -albedo 1.5 0.5 0.5
refused ssprofile "-scene needs the baked cloud" -check -scene s.rib baked.ptc
# Without -check the same impossible material is a runtime error (exit 1).
run "$bin/ptfilter" -ssdiffusion -albedo 2 2 2 in.ptc out.ptc
expect_rc 1 "impossible -albedo without -check"

# --- nothing read, nothing written ----------------------------------------------------
mkfifo fifo.ptc
run timeout 20 "$bin/ptinfo" -check fifo.ptc
expect_rc 0 "ptinfo -check on a FIFO (never opened)"
run timeout 20 "$bin/ptfilter" -check -ssdiffusion fifo.ptc out.ptc
expect_rc 0 "ptfilter -check on a FIFO (never opened)"
"$bin/ptsynth" -n 200 small.ptc >/dev/null
before="$(mtime_of small.ptc)"
accepted ptsynth -n 500 small.ptc
accepted ptfilter -ssdiffusion small.ptc small.ptc
accepted brickmake small.ptc small.bkm
[[ "$(mtime_of small.ptc)" == "$before" && ! -e small.bkm && ! -e out.ptc ]] ||
    fail "-check changed or wrote files: $(ls -A)"
printf 'surface s() { Ci = 1; }\n' >s.sl
accepted shader s.sl
[[ ! -e s.slo ]] || fail "shader -check compiled s.sl"

# --- every tool documents it -------------------------------------------------------
for tool in ptbake ptfilter brickmake brickinfo render ptinfo ptsynth ptview shader sloinfo envdome ssprofile; do
    run "$bin/$tool" --help
    [[ "$rc" == 0 && "$out" == *"-check "*"check the command line only"* ]] ||
        fail "$tool --help does not describe -check"
done

finish_checks check
