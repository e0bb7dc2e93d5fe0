#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# CLI test of brick maps under hostile input (issue 15): brickinfo reads and
# checks the whole map before it reports, so a changed byte in the header,
# tables or any brick is exit 1 with one ERROR line naming the file, the
# region and its bytes (-verify 0 skips the bricks); version 1 maps are
# refused with "rebuild it with brickmake", and brickmake -newer 1 rebuilds
# them; SSS_LIMIT_BRICKS and SSS_MEMORY_LIMIT stop brickmake before it builds
# (naming the variable and the option that reduces the need) and brickinfo
# before it reads the tables; outputs that are inputs, or folders, are
# refused before any work. Needs SSS_BIN_DIR.
#
# Every check runs; failures are listed and the script exits 1 at the end.
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_bkm_hostile.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"

# shellcheck source=lib.sh
source "$here/lib.sh"
# shellcheck source=checks.sh
source "$here/checks.sh"

"$bin/ptsynth" -n 600 -size 1 s.ptc >/dev/null
"$bin/brickmake" -maxdepth 2 s.ptc good.bkm

# first_error_is LABEL TEXT...: the first stderr line is "TOOL ERROR: ..."
# containing every TEXT.
first_error_is() {
    local label="$1" first
    shift
    first="$(head -n 1 <<<"$err")"
    [[ "$first" == *" ERROR: "* ]] || fail "$label: no ERROR line first: $err"
    local part
    for part in "$@"; do
        [[ "$first" == *"$part"* ]] || fail "$label: '$part' not in: $first"
    done
}

# --- changed bytes ------------------------------------------------------------
python3 - <<'PY'
import struct
good = bytearray(open("good.bkm", "rb").read())
first_brick = struct.unpack_from("<Q", good, 280)[0]
def save(name, at):
    b = good[:]
    b[at] ^= 0x01
    open(name, "wb").write(bytes(b))
save("matrix.bkm", 140)                 # a world2eye entry: used to pass
save("provenance.bkm", 288 + struct.unpack_from("<I", good, 44)[0] + 2)
save("crc.bkm", 276)                    # the header's own checksum
save("brick.bkm", first_brick + 70)     # a value of the first brick
save("last.bkm", len(good) - 1)         # the last byte of the last brick
open("first_brick", "w").write(str(first_brick))
PY
first_brick="$(cat first_brick)"
for map in matrix provenance crc; do
    run "$bin/brickinfo" "$map.bkm"
    expect_rc 1 "brickinfo $map.bkm" &&
        first_error_is "brickinfo $map.bkm" "brickinfo ERROR: $map.bkm: header and tables (bytes 0 to $((first_brick - 1)))" "CRC-32"
    [[ -z "$out" ]] || fail "brickinfo $map.bkm printed a report: $out"
done
for map in brick last; do
    run "$bin/brickinfo" "$map.bkm"
    expect_rc 1 "brickinfo $map.bkm" &&
        first_error_is "brickinfo $map.bkm" "brickinfo ERROR: $map.bkm: brick of tree" "(bytes " "CRC-32"
    [[ -z "$out" ]] || fail "brickinfo $map.bkm printed a report: $out"
    # -verify 0: the header and tables only, and it says so.
    run "$bin/brickinfo" -verify 0 "$map.bkm"
    expect_rc 0 "brickinfo -verify 0 $map.bkm" &&
        { grep -q "^checked: header and tables (CRC-32); bricks not read" <<<"$out" ||
            fail "brickinfo -verify 0: no 'checked' line: $out"; }
done
run "$bin/brickinfo" brick.bkm -info 0 -verify 0 -picture brick.png
expect_rc 1 "brickinfo -picture brick.bkm" && first_error_is "brickinfo -picture brick.bkm" "CRC-32"
[[ ! -e brick.png ]] || fail "a picture of a corrupt map was written"
run "$bin/brickinfo" good.bkm
expect_rc 0 "brickinfo good.bkm" &&
    { grep -Eq "^checked: header, tables and [0-9]+ bricks" <<<"$out" || fail "no 'checked' line: $out"; }
run "$bin/brickinfo" -verify 2 good.bkm
expect_rc 2 "brickinfo -verify 2"

# --- versions -------------------------------------------------------------------
python3 - <<'PY'
import struct
b = bytearray(open("good.bkm", "rb").read())
struct.pack_into("<I", b, 8, 1)
open("v1.bkm", "wb").write(bytes(b))
PY
run "$bin/brickinfo" v1.bkm
expect_rc 1 "brickinfo v1.bkm" &&
    first_error_is "brickinfo v1.bkm" "unsupported .bkm version 1" "rebuild it with brickmake"
cp v1.bkm old.bkm
touch -d '+1 hour' old.bkm # newer than s.ptc, but unusable: -newer 1 rebuilds it
run "$bin/brickmake" -newer 1 -maxdepth 2 s.ptc old.bkm
expect_rc 0 "brickmake -newer 1 over a version 1 map" &&
    { [[ "$err" == *"WARNING"*"version 1"*"rebuilding it"* ]] || fail "no rebuild warning: $err"; }
run "$bin/brickinfo" old.bkm
expect_rc 0 "brickinfo of the rebuilt map"
run "$bin/brickmake" -newer 1 -maxdepth 2 s.ptc old.bkm
expect_rc 0 "brickmake -newer 1 again" &&
    { [[ "$out" == *"nothing to do"* ]] || fail "a current map was rebuilt: $out"; }

# --- limits and memory ------------------------------------------------------------
cp good.bkm keep.bkm
before="$(md5sum keep.bkm)"
run env SSS_LIMIT_BRICKS=10 "$bin/brickmake" -maxdepth 8 s.ptc keep.bkm
expect_rc 1 "brickmake SSS_LIMIT_BRICKS=10" &&
    first_error_is "brickmake SSS_LIMIT_BRICKS=10" "brickmake ERROR: s.ptc: brick map:" \
        "exceeds the limit of 10 (set SSS_LIMIT_BRICKS to raise it)" "lower -maxdepth (now 8)"
[[ "$(md5sum keep.bkm)" == "$before" ]] || fail "the previous map changed"
run env SSS_LIMIT_BRICKS=10 "$bin/brickinfo" good.bkm
expect_rc 1 "brickinfo SSS_LIMIT_BRICKS=10" &&
    first_error_is "brickinfo SSS_LIMIT_BRICKS=10" "brickinfo ERROR: good.bkm:" "SSS_LIMIT_BRICKS"

# Points scattered through a cube with tiny radii: at -maxdepth 12 about a
# million bricks (some 2 GB) before pruning; the budget is 1 GB (the tool
# itself holds about 130 MB, shared libraries included; more under ASan).
python3 - <<'PY'
import random, struct
random.seed(3)
n = 150000
with open("scattered.ply", "wb") as f:
    f.write(("ply\nformat binary_little_endian 1.0\nelement vertex %d\n" % n).encode())
    for p in ("x", "y", "z", "nx", "ny", "nz", "radius", "v"):
        f.write(("property float %s\n" % p).encode())
    f.write(b"end_header\n")
    for _ in range(n):
        f.write(struct.pack("<8f", random.uniform(-1, 1), random.uniform(-1, 1),
                            random.uniform(-1, 1), 0, 0, 1, 1e-5, random.random()))
PY
start=$SECONDS
run env SSS_MEMORY_LIMIT=1G "$bin/brickmake" -maxdepth 12 scattered.ply scattered.bkm
expect_rc 1 "brickmake SSS_MEMORY_LIMIT=1G" &&
    first_error_is "brickmake SSS_MEMORY_LIMIT=1G" "brickmake ERROR: scattered.ply: brick map:" \
        "needs about" "SSS_MEMORY_LIMIT" "lower -maxdepth"
# Refused before building: seconds, where building would take minutes (30 s leaves
# room for the sanitizer build on a loaded machine).
((SECONDS - start < 30)) || fail "the memory check came late ($((SECONDS - start)) s)"
[[ ! -e scattered.bkm ]] || fail "scattered.bkm written"

# --- outputs that are inputs or folders -----------------------------------------
cp s.ptc in.ptc
before="$(md5sum in.ptc)"
run "$bin/brickmake" in.ptc ./in.ptc
expect_rc 1 "brickmake in.ptc ./in.ptc" && first_error_is "brickmake over its input" "is an input of this job"
run "$bin/brickinfo" -info 0 good.bkm -lookup in.ptc in.ptc
expect_rc 1 "brickinfo -lookup in.ptc in.ptc" && first_error_is "brickinfo -lookup over its input" "is an input of this job"
[[ "$(md5sum in.ptc)" == "$before" ]] || fail "an input cloud was overwritten"
cp good.bkm map.png
before="$(md5sum map.png)"
run "$bin/brickinfo" -info 0 map.png -picture map.png
expect_rc 1 "brickinfo map.png -picture map.png" && first_error_is "brickinfo picture over its map" "is an input of this job"
[[ "$(md5sum map.png)" == "$before" ]] || fail "the map was overwritten by its picture"
run "$bin/brickinfo" -info 0 good.bkm -picture same.png -lookup in.ptc same.png
expect_rc 2 "brickinfo -picture and -lookup to one file"
[[ ! -e same.png ]] || fail "same.png written"
mkdir folder.bkm
run "$bin/brickmake" s.ptc folder.bkm
expect_rc 1 "brickmake to a folder" && first_error_is "brickmake to a folder" "folder.bkm: is a directory"

finish_checks bkm-hostile
