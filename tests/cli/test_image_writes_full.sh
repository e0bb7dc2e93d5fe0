#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# CLI test of image writes on a full disk (docs/cli-conventions.md, "Outputs";
# docs/images.md): every tool that writes an image (render's PNG, JPEG, TIFF
# and OpenEXR, ptview's PNG and OpenEXR, brickinfo -picture, envdome -sky,
# a MakeTexture in the RIB)
# writes onto a small tmpfs filled up to its last 8 KB (a write that fails
# part way, where the tools used to rename a truncated file over the output). Each must exit 1 with
# exactly one ERROR line naming the file and the cause, leave the previous
# output byte for byte as it was and no temporary behind. Mounting needs root
# (or CAP_SYS_ADMIN): without it the test is skipped, saying so.
# Needs SSS_BIN_DIR.
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_image_writes_full.XXXXXX")"
disk="$work/disk"
mkdir -p "$disk"
mounted=0
cleanup() {
    if ((mounted)); then umount "$disk" 2>/dev/null || umount -l "$disk" 2>/dev/null || true; fi
    rm -rf "$work"
}
trap cleanup EXIT
cd "$work"

# shellcheck source=lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
# shellcheck source=checks.sh
source "$(dirname "${BASH_SOURCE[0]}")/checks.sh"

if ! mount -t tmpfs -o size=1m tmpfs "$disk" 2>"$work/mount.err"; then
    echo "SKIP: cannot mount a 1 MB tmpfs to fill up ($(head -n1 "$work/mount.err")); run as root"
    exit 0
fi
mounted=1

# Inputs (outside the small disk): a scene, a cloud, a brick map.
cat >scene.rib <<'RIB'
Format 256 256 1
PixelSamples 1 1
Projection "perspective" "fov" 40
Translate 0 0 4
Display "unused.exr" "openexr" "rgba"
WorldBegin
  LightSource "distantlight" 1
  Surface "plastic"
  Sphere 1 -1 1 360
WorldEnd
RIB
"$bin/ptsynth" -n 20000 cloud.ptc >/dev/null
"$bin/brickmake" cloud.ptc map.bkm >/dev/null

# full_disk LABEL OUTPUT FREE_KB TOOL ARGS...: OUTPUT (a name on the disk)
# holds a previous file, the disk is filled but for FREE_KB (a multiple of
# 4: the writer then fails part way), TOOL ARGS runs; expects exit 1, one
# ERROR line naming OUTPUT, OUTPUT unchanged, no temporary.
full_disk() {
    local label="$1" output="$2" free="$3"
    shift 3
    rm -f "$disk"/* "$disk"/.[!.]* 2>/dev/null || true
    printf 'previous %s\n' "$label" >"$disk/$output"
    local before
    before="$(cksum <"$disk/$output")"
    dd if=/dev/zero of="$disk/fill" bs=4k 2>/dev/null || true
    ((free == 0)) || truncate -s "-${free}K" "$disk/fill"
    run "$@"
    expect_rc 1 "$label" || true
    local errors lines
    errors="$(grep -c 'ERROR' <<<"$err" || true)"
    lines="$(grep -c . <<<"$err" || true)"
    [[ "$errors" == 1 ]] || fail "$label: expected one ERROR line, got: $err"
    if [[ -z "${SSS_SANITIZED:-}" && "$lines" != 1 ]]; then
        fail "$label: stderr has more than the ERROR line: $err"
    fi
    grep -q "ERROR: $disk/$output: .*No space left on device" <<<"$err" ||
        fail "$label: the ERROR line does not name the file and the full disk: $err"
    [[ "$(cksum <"$disk/$output")" == "$before" ]] ||
        fail "$label: the previous $output changed"
    local left
    left="$(find "$disk" -name '*.tmp')"
    [[ -z "$left" ]] || fail "$label: temporaries left: $left"
}

full_disk "render -o png" x.png 8 "$bin/render" -o "$disk/x.png" scene.rib
full_disk "render -o jpg" x.jpg 8 "$bin/render" -o "$disk/x.jpg" scene.rib
full_disk "render -o tif" x.tif 8 "$bin/render" -o "$disk/x.tif" scene.rib
full_disk "render -o exr" x.exr 8 "$bin/render" -o "$disk/x.exr" scene.rib
full_disk "ptview png" v.png 8 "$bin/ptview" -o "$disk/v.png" cloud.ptc
full_disk "ptview exr" v.exr 8 "$bin/ptview" -o "$disk/v.exr" cloud.ptc
# brickinfo's picture of a sparse map is 2.5 KB: no room at all.
full_disk "brickinfo -picture" b.png 0 "$bin/brickinfo" -picture "$disk/b.png" map.bkm
full_disk "envdome -sky" sky.exr 8 "$bin/envdome" -sky 1024 512 "$disk/sky.exr"

# MakeTexture's texture (OpenImageIO's maker writes it, TIFF) on the full
# disk: one ERROR line naming it, the old texture (older than the picture,
# so remade) kept, no temporary.
rm -f "$disk"/*
printf 'previous texture\n' >"$disk/pic.tx"
touch -d '2000-01-01' "$disk/pic.tx"
before="$(cksum <"$disk/pic.tx")"
dd if=/dev/zero of="$disk/fill" bs=4k 2>/dev/null || true
truncate -s -8K "$disk/fill"
oiiotool --pattern noise 256x256 3 -d float -o pic.exr
printf 'MakeTexture "pic.exr" "%s/pic.tx" "periodic" "periodic" "gaussian" 2 2\n%s\n' \
    "$disk" 'Format 16 16 1 WorldBegin Sphere 1 -1 1 360 WorldEnd' >make.rib
run "$bin/render" -o make.exr make.rib
if expect_rc 1 "MakeTexture on a full disk"; then
    [[ "$(grep -c ERROR <<<"$err")" == 1 && "$err" == *"$disk/pic.tx"* ]] ||
        fail "MakeTexture on a full disk: $err"
fi
[[ "$(cksum <"$disk/pic.tx")" == "$before" ]] || fail "MakeTexture: the previous texture changed"
[[ -z "$(find "$disk" -name '*.tmp')" ]] || fail "MakeTexture: temporaries left"

# The control: with room on the disk the same jobs write their files.
rm -f "$disk"/*
for ext in png jpg tif exr; do
    run "$bin/render" -o "$disk/x.$ext" scene.rib
    [[ "$rc" == 0 && -s "$disk/x.$ext" ]] || fail "render -o x.$ext with room: exit $rc: $err"
done
run "$bin/ptview" -o "$disk/v.png" cloud.ptc
[[ "$rc" == 0 && -s "$disk/v.png" ]] || fail "ptview with room: exit $rc: $err"

finish_checks image_writes_full
