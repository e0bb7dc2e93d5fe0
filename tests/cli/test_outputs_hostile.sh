#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# CLI test of hostile outputs (issue 15; docs/cli-conventions.md, "Outputs"),
# with the minimal inputs of tests/data/hostile/outputs:
#  - outputs over inputs: a render Display or -o, a ptbake bake file or -o,
#    brickmake, brickinfo, envdome and shader outputs naming a file the same
#    job reads (the RIB, an OBJ archive, a texture a shader parameter names,
#    a texture or cloud whose name a shader makes at run time (texture,
#    textureinfo, texture3d), a cloud, a source),
#    also through a symbolic or hard link, are refused with one ERROR line
#    naming both uses; ptfilter in place is allowed and replaces its input;
#  - unknown output extensions (exit 2 for a command-line name, 1 for a name
#    in a scene); a folder or a missing folder as output;
#  - devices, FIFOs and symbolic links as outputs: a character device (a
#    private one, as root) stays a device, a FIFO receives the data and stays
#    a FIFO, a link stays a link and its file is replaced;
#  - all or nothing: a job with several outputs where one fails (an unknown
#    AOV, a missing folder, a bad format, a file that does not compile)
#    changes none of them;
#  - stale temporaries: a run removes the temporaries of its target whose
#    writer is gone and leaves a live one's alone; 8 concurrent jobs on one
#    file all succeed.
# Every refused case checks the exit status, the first ERROR line, that every
# file in the case's folder (inputs and previous outputs) is byte-identical,
# and that no temporary is left. Needs SSS_BIN_DIR and SSS_TEST_DATA_DIR.
#
# Every check runs; failures are listed and the script exits 1 at the end.
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
data="${SSS_TEST_DATA_DIR:?SSS_TEST_DATA_DIR must name tests/data}/hostile/outputs"
ptinfo="$bin/ptinfo"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_outputs.XXXXXX")"
reader=""
cleanup() {
    if [[ -n "$reader" ]] && kill -0 "$reader" 2>/dev/null; then
        kill "$reader" 2>/dev/null || true
        wait "$reader" 2>/dev/null || true
    fi
    rm -rf "$work"
}
trap cleanup EXIT
cd "$work"

# shellcheck source=lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
# shellcheck source=checks.sh
source "$(dirname "${BASH_SOURCE[0]}")/checks.sh"

# Shared inputs: the data, a texture, clouds and a brick map.
mkdir -p "$work/in"
cp "$data"/* "$work/in/"
"$bin/envdome" -sky 64 32 "$work/in/tex.exr" >/dev/null
"$bin/ptsynth" -n 2000 "$work/in/keep.ptc" >/dev/null
"$bin/brickmake" "$work/in/keep.ptc" "$work/in/map.bkm" >/dev/null

# fresh NAME: a case folder $dir with a copy of the inputs, and previous
# outputs a.exr b.exr a.ptc b.ptc out.ptc (known contents); cd into it.
fresh() {
    dir="$work/$1"
    rm -rf "$dir"
    mkdir -p "$dir"
    cp -a "$work/in/." "$dir/"
    local f
    for f in a.exr b.exr b.png a.ptc b.ptc out.ptc; do printf 'previous %s\n' "$f" >"$dir/$f"; done
    cd "$dir"
}

# snapshot: every name in the folder (hidden ones too) with its type and,
# for files, its checksum.
snapshot() {
    find . -mindepth 1 -printf '%p %y\n' | sort
    find . -type f -exec cksum {} + | sort
}

# refused LABEL RC TOOL "TEXT"... -- ARGS...: runs TOOL ARGS in the current
# case folder; expects exit RC, a first line "TOOL ERROR: ..." holding each
# TEXT, and the folder exactly as before (no file changed, none added).
refused() {
    local label="$1" want="$2" tool="$3"
    shift 3
    local texts=()
    while [[ "$1" != -- ]]; do
        texts+=("$1")
        shift
    done
    shift
    local before after first t
    before="$(snapshot)"
    run timeout 60 "$bin/$tool" "$@"
    after="$(snapshot)"
    expect_rc "$want" "$label" || return 0
    first="$(grep -m1 'ERROR' <<<"$err" || true)"
    [[ "$first" == "$tool ERROR: "* ]] || fail "$label: no '$tool ERROR:' line: $err"
    for t in "${texts[@]}"; do
        [[ "$first" == *"$t"* ]] || fail "$label: the ERROR line does not say '$t': $first"
    done
    [[ "$before" == "$after" ]] ||
        fail "$label: the folder changed: $(diff <(echo "$before") <(echo "$after") | grep '^[<>]' | tr '\n' ' ')"
}

# ---------------------------------------------------------------------------
# Outputs over inputs
fresh over
refused "render: Display over the OBJ archive" 1 render \
    'Display "cube.obj" (display_archive.rib:6) is an input of this job' \
    'ReadArchive "cube.obj" at display_archive.rib:10' -- display_archive.rib
refused "render: Display over its own RIB" 1 render \
    'Display "display_self.rib" (display_self.rib:6)' 'the scene file "display_self.rib"' \
    -- display_self.rib
refused "render -o over the RIB" 1 render 'option -o "two_displays.rib"' \
    'the scene file "two_displays.rib"' -- -o two_displays.rib two_displays.rib
refused "render: Display over a texture parameter" 1 render \
    'Display "tex.exr" (display_texture.rib:6) is an input of this job' \
    'parameter "texturename" "tex.exr"' -- display_texture.rib
refused "render: Display over a texture named at run time" 1 render \
    'texture "tex.exr"' 'Display "tex.exr" (display_runtime.rib:7) is an input of this job' \
    'a texture lookup' -- display_runtime.rib
refused "render: Display over a texture whose header is read at run time" 1 render \
    'textureinfo "tex.exr"' 'Display "tex.exr" (display_runtime_info.rib:7) is an input of this job' \
    'a textureinfo lookup' -- display_runtime_info.rib
refused "render: two Displays, one file" 1 render \
    'Display "+a.exr" (display_twice.rib:7) names the same file as Display "a.exr" (display_twice.rib:6)' \
    -- display_twice.rib
ln -s cube.obj link.exr
ln cube.obj hard.exr
refused "render -o a symbolic link to the OBJ archive" 1 render 'option -o "link.exr"' \
    'ReadArchive "cube.obj"' -- -o link.exr two_displays.rib
refused "render -o a hard link to the OBJ archive" 1 render 'option -o "hard.exr"' \
    'ReadArchive "cube.obj"' -- -o hard.exr two_displays.rib
rm link.exr hard.exr
refused "ptbake -o over the RIB" 1 ptbake 'option -o "bake_two.rib"' \
    'the scene file "bake_two.rib"' -- -o bake_two.rib bake_two.rib
refused "ptbake: bake file over its own RIB" 1 ptbake \
    'bake file "bake_self.rib" (parameter "filename" of bake_self.rib:12' \
    'is an input of this job (the scene file "bake_self.rib")' -- bake_self.rib
refused "ptbake: bake file over a cloud a shader reads" 1 ptbake \
    'bake file "keep.ptc"' 'is an input of this job (parameter "texturename" "keep.ptc"' \
    -- bake_over_lookup.rib
refused "ptbake: bake file over a cloud looked up at run time" 1 ptbake \
    'texture3d: bake file "keep.ptc" (parameter "filename" of bake_over_runtime_lookup.rib:13' \
    'is an input of this job (a texture3d lookup)' -- bake_over_runtime_lookup.rib
refused "brickmake over its cloud" 1 brickmake 'the output "keep.ptc" is an input of this job' \
    'the input cloud "keep.ptc"' -- keep.ptc keep.ptc
refused "brickinfo -lookup over its cloud" 1 brickinfo 'the -lookup output "keep.ptc"' \
    'the -lookup input "keep.ptc"' -- -lookup keep.ptc keep.ptc map.bkm
refused "brickinfo -lookup over the map" 1 brickinfo 'the -lookup output "map.ptc"' \
    'the brick map "map.ptc"' -- -lookup keep.ptc map.ptc map.ptc
refused "envdome over its probe" 1 envdome 'the output "tex.exr" is an input of this job' \
    'the probe "tex.exr"' -- tex.exr tex.exr
refused "shader -o over its source" 1 shader 'option -o "good.sl" is an input of this job' \
    'the source "good.sl"' -- -o good.sl good.sl
refused "shader: two shaders, one .slo" 1 shader '"dup.slo" (shader dup of dup_b.sl)' \
    'names the same file as "dup.slo" (shader dup of dup_a.sl)' -- dup_a.sl dup_b.sl
refused "shader: one file does not compile" 1 shader '1 error in broken.sl' \
    'nothing was written' -- good.sl broken.sl
# ptfilter in place: meaningful (the input is read whole first), allowed.
cp keep.ptc inplace.ptc
run "$bin/ptfilter" -ssdiffusion -material marble inplace.ptc inplace.ptc
if expect_rc 0 "ptfilter in place"; then
    has_channel inplace.ptc "color _ssdiffusion" || fail "ptfilter in place: no _ssdiffusion in the result"
    [[ "$(points inplace.ptc)" == 2000 ]] || fail "ptfilter in place: the result is not the filtered cloud"
    [[ -z "$(compgen -G '.*.tmp' || true)" ]] || fail "ptfilter in place: temporaries left"
fi

# ---------------------------------------------------------------------------
# Unknown extensions, folders, missing folders
fresh names
known_images='(known: .exr, .tif, .tiff, .png, .jpg, .jpeg)'
refused "render -o out.xyz" 2 render "option -o: 'out.xyz' is not an image file name" \
    "$known_images" -- -o out.xyz two_displays.rib
refused "render -o without extension" 2 render "'out' is not an image file name: it has no extension" \
    -- -o out two_displays.rib
refused "render: a file Display with an unknown extension" 1 render \
    "Display \"out.xyz\" (display_unknown_ext.rib:6): 'out.xyz' is not an image file name" \
    "$known_images" -- display_unknown_ext.rib
refused "ptbake -o out.xyz" 2 ptbake "option -o: 'out.xyz' is not a point cloud file name" \
    '(known: .ptc, .ply)' -- -o out.xyz bake_two.rib
refused "ptbake: a bake file with an unknown extension" 1 ptbake \
    "bake file \"b.xyz\"" "'b.xyz' is not a point cloud file name" -- bake_unknown_ext.rib
refused "ptsynth out.xyz" 2 ptsynth "'out.xyz' is not a point cloud file name" -- -n 10 out.xyz
refused "ptfilter to out.xyz" 2 ptfilter "'out.xyz' is not a point cloud file name" \
    -- -ssdiffusion keep.ptc out.xyz
refused "brickinfo -lookup to out.xyz" 2 brickinfo "'out.xyz' is not a point cloud file name" \
    -- -lookup keep.ptc out.xyz map.bkm
refused "envdome -sky to a .png" 2 envdome "-sky writes OpenEXR: 'sky.png' is not an OpenEXR file name" \
    -- -sky 64 32 sky.png
mkdir folder.exr folder.ptc
refused "render -o a folder" 1 render 'folder.exr: is a directory' -- -o folder.exr two_displays.rib
refused "ptsynth to a folder" 1 ptsynth 'folder.ptc: is a directory' -- -n 10 folder.ptc
refused "render -o into a missing folder" 1 render "missing/out.exr: cannot write into folder 'missing'" \
    -- -o missing/out.exr two_displays.rib
refused "ptfilter into a missing folder" 1 ptfilter "missing/out.ptc: cannot write into folder 'missing'" \
    -- -ssdiffusion keep.ptc missing/out.ptc

# ---------------------------------------------------------------------------
# All or nothing: one failing output of several changes none.
fresh all
refused "render: second Display with an unknown AOV" 1 render "display '+b.exr' (two_displays_bad_aov.rib:7)" \
    "nosuchaov" -- two_displays_bad_aov.rib
refused "render: second Display into a missing folder" 1 render "missing/b.exr: cannot write into folder 'missing'" \
    -- two_displays_missing_folder.rib
refused "render: second Display with depth in a PNG" 1 render "display '+b.png' (two_displays_bad_format.rib:7)" \
    "depth (Z) cannot be stored" -- two_displays_bad_format.rib
refused "ptbake: second bake file into a missing folder" 1 ptbake \
    "missing/b.ptc: cannot write into folder 'missing'" -- bake_missing_folder.rib
refused "brickinfo: -picture fine, -lookup into a missing folder" 1 brickinfo \
    "missing/out.ptc: cannot write into folder 'missing'" -- -picture pic.png -lookup keep.ptc missing/out.ptc map.bkm
# The same jobs without the failing output replace everything.
run "$bin/render" two_displays.rib
if expect_rc 0 "render: two good Displays"; then
    cmp -s a.exr "$work/all/a.exr.none" 2>/dev/null || true
    for f in a.exr b.exr; do
        [[ "$(head -c 4 "$f" | od -An -tx1 | tr -d ' \n')" == 762f3101 ]] || fail "render: $f is not the new image"
    done
fi
run "$bin/ptbake" bake_two.rib
if expect_rc 0 "ptbake: two good bake files"; then
    for f in a.ptc b.ptc; do
        [[ "$(points "$f")" =~ ^[1-9] ]] || fail "ptbake: $f is not the new cloud"
    done
fi

# ---------------------------------------------------------------------------
# Devices, FIFOs, symbolic links
fresh special
# release FIFO: ends the reader of FIFO when the tool failed to write it.
release() {
    kill -0 "$reader" 2>/dev/null && timeout 5 bash -c ': >"$1"' _ "$1" || true
}
# A FIFO receives the bytes a regular file would get, and stays a FIFO.
"$bin/ptsynth" -n 500 regular.ptc >/dev/null
mkfifo fifo.ptc
cat fifo.ptc >received.ptc &
reader=$!
run timeout 60 "$bin/ptsynth" -n 500 fifo.ptc
expect_rc 0 "ptsynth into a FIFO" || release fifo.ptc
wait "$reader" || true
reader=""
[[ -p fifo.ptc ]] || fail "ptsynth into a FIFO: fifo.ptc is no longer a FIFO"
cmp -s received.ptc regular.ptc || fail "ptsynth into a FIFO: the reader did not get the cloud"
mkfifo fifo.exr
cat fifo.exr >received.exr &
reader=$!
run timeout 60 "$bin/render" -o fifo.exr two_displays.rib
expect_rc 0 "render -o a FIFO" || release fifo.exr
wait "$reader" || true
reader=""
[[ -p fifo.exr ]] || fail "render -o a FIFO: fifo.exr is no longer a FIFO"
[[ "$(head -c 4 received.exr | od -An -tx1 | tr -d ' \n')" == 762f3101 ]] ||
    fail "render -o a FIFO: the reader did not get an OpenEXR image"
# (A FIFO's temporary is staged in $TMPDIR.)
[[ -z "$(compgen -G '.*.tmp' || true)" && -z "$(compgen -G "${TMPDIR:-/tmp}/.fifo.[ep][xt][rc].*.tmp" || true)" ]] ||
    fail "FIFO outputs: temporaries left"
# A symbolic link stays a link; the file it names is replaced.
mkdir real
printf 'previous\n' >real/cloud.ptc
ln -s real/cloud.ptc link.ptc
run "$bin/ptsynth" -n 300 link.ptc
if expect_rc 0 "ptsynth onto a symbolic link"; then
    [[ -L link.ptc && "$(readlink link.ptc)" == real/cloud.ptc ]] || fail "ptsynth onto a link: the link was replaced"
    [[ "$(points real/cloud.ptc)" == 300 ]] || fail "ptsynth onto a link: the linked file was not replaced"
fi
# A character device (never the real /dev/null: a private node of the same
# device, as root) is written into and stays a device.
if [[ "$(id -u)" == 0 ]] && mknod null c 1 3 2>/dev/null; then
    device_ok() {
        [[ -c null && "$(stat -c '%t,%T' null)" == 1,3 ]] || fail "$1: null is no longer the character device 1,3"
    }
    for job in "ptsynth -n 100 null" "render -o null two_displays.rib" "ptbake -o null bake_two.rib" \
        "ptfilter -ssdiffusion keep.ptc null" "brickmake keep.ptc null" "envdome -sky 32 16 null" \
        "brickinfo -info 0 -picture null map.bkm" "shader -o null good.sl"; do
        # shellcheck disable=SC2086
        run timeout 60 "$bin"/$job
        expect_rc 0 "$job" || true
        device_ok "$job"
    done
    [[ -z "$(compgen -G '.*.tmp' || true)" ]] || fail "device outputs: temporaries left"
else
    echo "note: not root: the character-device output cases are skipped"
fi

# ---------------------------------------------------------------------------
# Stale temporaries: named .<name>.<host>.<pid>.<random>.tmp.
fresh stale
host="$(</proc/sys/kernel/hostname)"
host="${host%%.*}"
host="${host//[^A-Za-z0-9-]/-}"
host="${host:0:32}"
[[ -n "$host" ]] || host=host
true &
gone=$!
wait "$gone"
stale=".out.ptc.$host.$gone.Abcd1234.tmp"
live=".out.ptc.$host.$$.Wxyz5678.tmp"
other=".other.ptc.$host.$gone.Abcd1234.tmp"
printf 'stale\n' >"$stale"
printf 'live\n' >"$live"
printf 'other target\n' >"$other"
run "$bin/ptsynth" -n 100 out.ptc
if expect_rc 0 "ptsynth over stale temporaries"; then
    [[ ! -e "$stale" ]] || fail "the temporary of a writer that is gone was not removed"
    [[ -e "$live" ]] || fail "the temporary of a live writer (this shell) was removed"
    [[ -e "$other" ]] || fail "another target's temporary was removed"
fi
rm -f "$live" "$other"
# 8 concurrent jobs on one file: all succeed, the file is one of theirs.
pids=()
for i in 1 2 3 4 5 6 7 8; do
    "$bin/ptsynth" -n $((1000 + i)) -seed "$i" same.ptc >/dev/null 2>"err.$i" &
    pids+=($!)
done
for i in "${!pids[@]}"; do
    wait "${pids[$i]}" || fail "concurrent job $((i + 1)) failed: $(<"err.$((i + 1))")"
done
[[ "$(points same.ptc)" =~ ^100[1-8]$ ]] || fail "concurrent jobs: same.ptc is not one job's cloud"
[[ -z "$(compgen -G '.*.tmp' || true)" ]] || fail "concurrent jobs: temporaries left"

finish_checks "hostile outputs"
