#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# CLI test of bad input files for every tool that reads .ptc, .ply, .bkm or
# RIB files (ptinfo, ptfilter, brickmake, brickinfo, ptview, render, ptbake):
# truncated, bit-flipped, NaN and huge-count files each give exit status 1, a
# "<tool> ERROR:" line as the last (and only error) line on stderr, no output
# file, no temporary left in the output folder, and an output that existed
# before stays byte-identical. The huge-count cases run under ulimit -v
# (1.5 GB) to show that no tool allocates for the claimed count.
# Needs SSS_BIN_DIR. The reader-level sweeps are tests/reader_sweep_test.cpp.
#
# Every check runs; failures are listed and the script exits 1 at the end.
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
for tool in ptinfo ptfilter brickmake brickinfo ptview render ptbake ptsynth; do
    [[ -x "$bin/$tool" ]] || { echo "FAIL: missing executable $bin/$tool" >&2; exit 1; }
done
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_bad_input.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"

# shellcheck source=lib.sh
source "$here/lib.sh"
# shellcheck source=checks.sh
source "$here/checks.sh"

# --- good inputs ------------------------------------------------------------
"$bin/ptsynth" -n 300 -size 1 good.ptc >/dev/null
"$bin/ptsynth" -n 300 -size 1 -compress 1 good_gz.ptc >/dev/null
"$bin/ptsynth" -n 300 -size 1 good.ply >/dev/null
"$bin/ptfilter" -ssdiffusion -unitlength 0.1 good.ptc good_ssd.ptc >/dev/null
"$bin/brickmake" -maxdepth 2 good_ssd.ptc good.bkm >/dev/null
cat >bake.rib <<'RIB'
Format 32 24 1
Projection "perspective" "fov" 35
Translate 0 0 6
WorldBegin
  LightSource "distantlight" 1 "from" [0 1 0] "to" [0 0 0] "intensity" [1]
  AttributeBegin
    Surface "bake_radiance_t" "string filename" ["baked.ptc"]
    Sphere 1 -1 1 360
  AttributeEnd
WorldEnd
RIB
# render_rib MAP: a scene whose shader reads brick map MAP.
render_rib() {
    cat <<RIB
Format 32 24 1
Projection "perspective" "fov" 35
Display "image.exr" "openexr" "rgba"
Translate 0 0 6
WorldBegin
  LightSource "distantlight" 1 "from" [0 1 0] "to" [0 0 0] "intensity" [1]
  AttributeBegin
    Surface "read_ssdiffusion" "string filename" ["$1"] "float Kd" [0.2]
    Sphere 1 -1 1 360
  AttributeEnd
WorldEnd
RIB
}
render_rib good.bkm >good_render.rib

# --- bad inputs (deterministic byte edits) ------------------------------------
python3 - <<'PY'
import re
import struct

def load(name):
    return bytearray(open(name, "rb").read())

def save(name, data):
    open(name, "wb").write(bytes(data))

# .ptc v0: the point count (f64) at 8; records of 20 + 4 * datasize bytes end
# the file (P, packed N, radius, _area, _radiance_t: 36 bytes).
ptc = load("good.ptc")
n = int(struct.unpack_from("<d", ptc, 8)[0])
first = len(ptc) - n * 36
save("trunc.ptc", ptc[: len(ptc) // 2])
b = ptc[:]; b[0] ^= 0x01; save("flip.ptc", b)  # a bit of the magic
b = ptc[:]; struct.pack_into("<f", b, first + 7 * 36, float("nan")); save("nan.ptc", b)
b = ptc[:]; struct.pack_into("<d", b, 8, 2.0 ** 53); save("huge.ptc", b)
gz = load("good_gz.ptc")
save("trunc_gz.ptc", gz[: len(gz) - 5])  # inside the CRC / length trailer
b = gz[:]; b[len(gz) // 2] ^= 0x10; save("flip_gz.ptc", b)

# .ply (binary, ours): header text, then records of 4 bytes per float property
# and 1 per uchar (the display colour).
ply = load("good.ply")
head_end = ply.index(b"end_header\n") + len(b"end_header\n")
text = bytes(ply[:head_end]).decode()
stride = 4 * text.count("\nproperty float ") + text.count("\nproperty uchar ")
save("trunc.ply", ply[: head_end + (len(ply) - head_end) // 3])
b = ply[:]; b[1] ^= 0x02; save("flip.ply", b)  # "ply" becomes "pny"
b = ply[:]; struct.pack_into("<f", b, head_end + 7 * stride, float("nan")); save("nan.ply", b)
save("huge.ply", re.sub(r"element vertex \d+", "element vertex 1000000000000", text).encode()
     + ply[head_end:])

# .bkm: first brick offset at 280; the tree directory follows the header,
# channel table (length at 44) and provenance (length at 40).
bkm = load("good.bkm")
first_brick = struct.unpack_from("<Q", bkm, 280)[0]
dir_at = 288 + struct.unpack_from("<I", bkm, 44)[0] + struct.unpack_from("<I", bkm, 40)[0]
save("trunc.bkm", bkm[: len(bkm) - 100])
b = bkm[:]; b[dir_at + 16 * 5 + 2] ^= 0x04; save("flip.bkm", b)  # tree 5's table offset
b = bkm[:]; struct.pack_into("<f", b, first_brick + 64, float("nan")); save("nan.bkm", b)
b = bkm[:]; struct.pack_into("<I", b, dir_at + 16 * 5 + 8, 0xFFFFFFF0); save("huge.bkm", b)

# RIB: cut inside a quoted string, a NaN number, a bit flip turning a quote
# into a different byte (unterminated string), a huge PatchMesh count.
rib = open("bake.rib").read()
cut = rib.index('"bake_radiance_t"') + 5
open("trunc.rib", "w").write(rib[:cut])
open("nan.rib", "w").write(rib.replace("Sphere 1 -1 1 360", "Sphere nan -1 1 360"))
b = bytearray(rib.encode()); q = rib.index('["baked.ptc"]') + 1; b[q] ^= 0x01
save("flip.rib", b)
open("huge.rib", "w").write(rib.replace(
    "Sphere 1 -1 1 360",
    'PatchMesh "bilinear" 2000000000 "nonperiodic" 2000000000 "nonperiodic" "P" [0 0 0]'))
PY
for map in trunc flip nan huge; do render_rib "$map.bkm" >"render_$map.rib"; done

# --- checks -----------------------------------------------------------------
no_temporaries() {
    local left
    left="$(find "$work" -name '.*.tmp')"
    [[ -z "$left" ]] || fail "temporary files left behind: $left"
}

# expect_clean_failure TOOL LABEL: exit 1, stderr ends in one "TOOL ERROR:" line.
expect_clean_failure() {
    local tool="$1" label="$2"
    expect_rc 1 "$label" || return 0
    local last errors
    last="$(tail -n 1 <<<"$err")"
    errors="$(grep -c "ERROR" <<<"$err" || true)"
    [[ "$last" == "$tool ERROR: "* && "$errors" == 1 ]] ||
        fail "$label: stderr is not one '$tool ERROR:' line: $err"
    no_temporaries
}

# limited CMD...: runs CMD under ulimit -v 1.5 GB (not under the sanitizers,
# whose shadow memory needs terabytes of address space).
limited() {
    if [[ -n "${SSS_SANITIZED:-}" ]]; then
        "$@"
    else
        (
            ulimit -v 1500000
            exec "$@"
        )
    fi
}

# check_tool LABEL TOOL OUTPUT ARGS...: runs TOOL ARGS without OUTPUT (it
# must not appear) and, when $keep is 1, again with an existing OUTPUT (it
# must stay identical). The message must name the bad file ($kind.*).
# Prints the error line with $SHOW set.
keep=1
check_tool() {
    local label="$1" tool="$2" output="$3"
    shift 3
    rm -f "$output"
    run limited "$bin/$tool" "$@"
    expect_clean_failure "$tool" "$label"
    [[ -z "${SHOW:-}" ]] || echo "$label: $err"
    # The message names the bad file (the last argument, or the map a RIB names).
    [[ "$err" == *"$kind."* ]] || fail "$label: the message does not name the $kind file: $err"
    [[ -z "$output" || ! -e "$output" ]] || fail "$label: created $output"
    if [[ -n "$output" && "$keep" == 1 ]]; then
        printf 'precious %s\n' "$label" >"$output"
        cp "$output" before
        run limited "$bin/$tool" "$@"
        expect_clean_failure "$tool" "$label (existing output)"
        cmp -s before "$output" || fail "$label: changed the existing $output"
        rm -f "$output" before
    fi
}

for kind in trunc flip nan huge; do
    # Existing outputs are checked once per tool and input format.
    [[ "$kind" == trunc ]] && keep=1 || keep=0
    check_tool "ptinfo $kind.ptc" ptinfo "" "$kind.ptc"
    check_tool "ptinfo $kind.ply" ptinfo "" "$kind.ply"
    check_tool "ptfilter $kind.ptc" ptfilter out.ptc -ssdiffusion -unitlength 0.1 "$kind.ptc" out.ptc
    check_tool "ptfilter $kind.ply" ptfilter out.ptc -ssdiffusion -unitlength 0.1 good.ptc "$kind.ply" out.ptc
    check_tool "brickmake $kind.ptc" brickmake out.bkm "$kind.ptc" out.bkm
    check_tool "brickmake $kind.ply" brickmake out.bkm "$kind.ply" out.bkm
    check_tool "brickinfo -picture $kind.bkm" brickinfo out.png -picture out.png "$kind.bkm"
    check_tool "ptview $kind.ptc" ptview out.png -o out.png "$kind.ptc"
    check_tool "ptview $kind.ply" ptview out.png -o out.png good.ptc "$kind.ply"
    check_tool "render $kind.bkm" render image.exr "render_$kind.rib"
    check_tool "render $kind.rib" render out.exr -o out.exr "$kind.rib"
    check_tool "ptbake $kind.rib" ptbake out.ptc -o out.ptc "$kind.rib"
done
for kind in trunc_gz flip_gz; do
    check_tool "ptinfo $kind.ptc" ptinfo "" "$kind.ptc"
    check_tool "brickmake $kind.ptc" brickmake out.bkm "$kind.ptc" out.bkm
done
# brickinfo checks every brick before it reports (-verify 1, the default):
# the NaN brick fails its checksum too.
for kind in trunc flip nan huge; do
    check_tool "brickinfo $kind.bkm" brickinfo "" "$kind.bkm"
done

# The good inputs work with the same commands (the failures above come from
# the edits, not from the command lines).
run "$bin/ptinfo" good.ptc good_gz.ptc good.ply
expect_rc 0 "ptinfo good files" || true
run "$bin/brickinfo" good.bkm
expect_rc 0 "brickinfo good.bkm" || true
run limited "$bin/render" good_render.rib
expect_rc 0 "render good_render.rib" && { [[ -s image.exr ]] || fail "no image.exr"; }
run limited "$bin/ptbake" -o out.ptc bake.rib
expect_rc 0 "ptbake bake.rib" && { [[ -s out.ptc ]] || fail "no out.ptc"; }
run limited "$bin/brickmake" good.ply out.bkm
expect_rc 0 "brickmake good.ply" || true
no_temporaries

finish_checks bad-input
