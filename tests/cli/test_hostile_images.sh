#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# CLI test of hostile images read by the tools (docs/limits.md, "Images
# read"): textures, environment maps and envdome probes whose headers declare
# huge images or tiny tiles, damaged and truncated PNG/OpenEXR/TIFF files
# (written by hostile_images.py, a few hundred bytes each), and texture calls
# with absurd filter widths and blur. Each must end with exactly one ERROR
# line naming the file (no libpng line, no OpenImageIO assert, no hang) or,
# for the options, render cleanly. Also the memory budget of ptfilter and
# envdome -sky (SSS_MEMORY_LIMIT): refused up front with the budget's ERROR.
# Needs SSS_BIN_DIR.
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_hostile_images.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"

# shellcheck source=lib.sh
source "$here/lib.sh"
# shellcheck source=checks.sh
source "$here/checks.sh"

python3 "$here/hostile_images.py" img

cat >tx.sl <<'SL'
surface tx(string name = ""; float w = 1; float b = 0) {
    Ci = color texture(name, s, t, "blur", b, "width", w);
    Oi = 1;
}
SL
# The four-corner form with a footprint that is a line (and one corner far out).
cat >tq.sl <<'SL'
surface tq(string name = ""; float w = 1; float b = 0) {
    Ci = color texture(name, 0.5, 0.5, 0.6 + s * 1e30, 0.5, 0.5, 0.5, 0.6, 0.5,
                       "blur", b, "width", w);
    Oi = 1;
}
SL
cat >env.sl <<'SL'
surface env(string name = ""; float w = 1; float b = 0) {
    Ci = color environment(name, normalize(N), "blur", b, "width", w);
    Oi = 1;
}
SL
"$bin/envdome" -sky 64 32 sky.exr >/dev/null

# scene NAME SHADER FILE [PARAMS]: a small RIB NAME.rib looking FILE up.
scene() {
    cat >"$1.rib" <<RIB
Format 16 16 1
PixelSamples 1 1
Projection "perspective" "fov" 40
Translate 0 0 4
Display "$1.exr" "openexr" "rgba"
WorldBegin
  Surface "$2" "string name" "$3" ${4:-}
  Sphere 1 -1 1 360
WorldEnd
RIB
}

# one_error LABEL TEXT: the last run exited 1 with one stderr line, an ERROR
# holding TEXT.
one_error() {
    expect_rc 1 "$1" || return 0
    local lines
    lines="$(grep -c . <<<"$err" || true)"
    if [[ -z "${SSS_SANITIZED:-}" && "$lines" != 1 ]]; then
        fail "$1: expected one stderr line, got: $err"
    fi
    grep -q "ERROR: .*$2" <<<"$err" || fail "$1: no ERROR with '$2' in: $err"
}

# Textures: refused with one line naming the file and what is wrong.
declare -A want=(
    [huge.png]="img/huge.png: 100000000 pixels across one image side exceeds the limit of 65536 (set SSS_LIMIT_IMAGE_SIDE"
    [wide.png]="img/wide.png: 200000 pixels across one image side exceeds the limit"
    [corrupt.png]="img/corrupt.png: damaged PNG: its compressed image data are invalid"
    [truncated.png]="img/truncated.png: damaged PNG: the file ends inside a chunk"
    [huge.tif]="img/huge.tif: "
    [tiles.tif]="img/tiles.tif: "
    [huge.exr]="img/huge.exr: "
    [tiles.exr]="img/tiles.exr: "
    [truncated.exr]="img/truncated.exr: "
)
for f in "${!want[@]}"; do
    scene t tx "img/$f"
    run timeout 120 "$bin/render" t.rib
    one_error "texture $f" "${want[$f]}"
    scene e env "img/$f"
    run timeout 120 "$bin/render" e.rib
    one_error "environment $f" "${want[$f]}"
done

# A valid PNG above a limit lowered by the variable, then within the default.
scene t tx img/ok.png
SSS_LIMIT_IMAGE_SIDE=32 run "$bin/render" t.rib
one_error "texture under SSS_LIMIT_IMAGE_SIDE=32" "img/ok.png: 64 pixels across one image side exceeds the limit of 32"
render_clean t.rib
# Valid PNGs with odd ancillary chunks: read with nothing on stderr.
for f in img/odd_*.png; do
    scene t tx "$f"
    run "$bin/render" t.rib
    [[ "$rc" == 0 && -z "$err" ]] || fail "texture $f: exit $rc, stderr: $err"
done

# Filter options: absurd widths and blur are bounded, not asserted on.
for params in '"float w" 1e38 "float b" 1' '"float w" 1000 "float b" 1' \
    '"float w" 1e38 "float b" 0' '"float w" 0 "float b" 1e30' '"float w" 1 "float b" 1'; do
    for shader in tx tq; do
        scene o "$shader" img/ok.png "$params"
        render_clean o.rib
    done
    scene o env sky.exr "$params"
    render_clean o.rib
done

# envdome's probe: the same checks before it is read.
for f in huge.png corrupt.png truncated.png huge.exr; do
    cp "img/$f" "probe.${f##*.}"
    run timeout 120 "$bin/envdome" "probe.${f##*.}" out.rib
    one_error "envdome $f" "probe.${f##*.}: "
    [[ ! -e out.rib ]] || fail "envdome $f wrote out.rib"
done
grep -q "libpng" "$work/stderr" && fail "a libpng line on stderr"

# The memory budget: refused before the work, with the budget's ERROR.
"$bin/ptsynth" -n 1000000 big.ptc >/dev/null
SSS_MEMORY_LIMIT=64M run "$bin/ptfilter" -ssdiffusion big.ptc out.ptc
one_error "ptfilter 1M points under 64M" "filtering the 1000000 points of big.ptc needs about .* MB; this process may use 64.0 MB (SSS_MEMORY_LIMIT)"
[[ ! -e out.ptc ]] || fail "ptfilter under 64M wrote out.ptc"
SSS_MEMORY_LIMIT=64M run "$bin/envdome" -sky 8192 4096 sky8k.exr
one_error "envdome -sky 8192 4096 under 64M" "a 8192 x 4096 sky needs about .* GB; this process may use 64.0 MB (SSS_MEMORY_LIMIT); make a smaller sky (-sky W H)"
[[ ! -e sky8k.exr ]] || fail "envdome under 64M wrote sky8k.exr"
# The volume diffusion's grids (checked as each level is made) and -merge.
"$bin/ptsynth" -shape box -size 400 -thickness 4 -n 50000 -light 0 0 1 slab.ptc >/dev/null
SSS_MEMORY_LIMIT=256M run "$bin/ptfilter" -ssdiffusion -material skin1 -volume 1 slab.ptc out.ptc
one_error "ptfilter -volume under 256M" "the volume diffusion's grid of [0-9]*x[0-9]*x[0-9]* voxels needs about .*; this process may use 256 MB (SSS_MEMORY_LIMIT)"
[[ ! -e out.ptc ]] || fail "ptfilter -volume under 256M wrote out.ptc"
"$bin/ptfilter" -ssdiffusion -part 1/2 big.ptc p1.ptpart
"$bin/ptfilter" -ssdiffusion -part 2/2 big.ptc p2.ptpart
SSS_MEMORY_LIMIT=64M run "$bin/ptfilter" -merge p1.ptpart p2.ptpart out.ptc
one_error "ptfilter -merge under 64M" "joining the 1000000 points of 2 parts needs about .*; this process may use 64.0 MB (SSS_MEMORY_LIMIT)"
[[ ! -e out.ptc ]] || fail "ptfilter -merge under 64M wrote out.ptc"
# What fits still runs.
SSS_MEMORY_LIMIT=512M run "$bin/ptfilter" -merge p1.ptpart p2.ptpart out.ptc
[[ "$rc" == 0 ]] || fail "ptfilter -merge 1M points under 512M: exit $rc: $err"
rm -f out.ptc
SSS_MEMORY_LIMIT=512M run "$bin/ptfilter" -ssdiffusion big.ptc out.ptc
[[ "$rc" == 0 ]] || fail "ptfilter 1M points under 512M: exit $rc: $err"
SSS_MEMORY_LIMIT=512M run "$bin/envdome" -sky 1024 512 sky1k.exr
[[ "$rc" == 0 ]] || fail "envdome -sky 1024 512 under 512M: exit $rc: $err"

finish_checks hostile_images
