#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# ptview writing its picture to standard output (`ptview in.ptc /dev/stdout >
# x.png`, `ptview in.ptc - | ...`, `-o -`): the stream holds a valid PNG and
# nothing else, byte for byte the picture a named .png gets; the report and
# the ALF_PROGRESS lines go to standard error instead; a terminal as standard
# output is refused (exit 2), as gzip refuses to write binary data to one.
# Needs SSS_BIN_DIR (the folder with the built executables).
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_ptview_stdout.XXXXXX")"
trap 'rm -rf "$work"' EXIT
# shellcheck source=checks.sh
source "$(dirname "${BASH_SOURCE[0]}")/checks.sh"
cd "$work"

# valid_png FILE: a PNG whose chunks all pass their CRC, IHDR first, IEND
# last with nothing after it, and whose image data inflate to the size the
# header gives (8-bit RGB).
valid_png() {
    python3 - "$1" <<'PY'
import struct, sys, zlib
data = open(sys.argv[1], "rb").read()
assert data[:8] == b"\x89PNG\r\n\x1a\n", "no PNG signature: %r" % data[:40]
pos, chunks, idat = 8, [], b""
while pos < len(data):
    n, kind = struct.unpack(">I4s", data[pos:pos + 8])
    body = data[pos + 8:pos + 8 + n]
    crc, = struct.unpack(">I", data[pos + 8 + n:pos + 12 + n])
    assert zlib.crc32(kind + body) == crc, "bad CRC in %r" % kind
    chunks.append(kind)
    if kind == b"IHDR":
        width, height, depth, colour = struct.unpack(">IIBB", body[:10])
    if kind == b"IDAT":
        idat += body
    pos += 12 + n
    if kind == b"IEND":
        break
assert chunks[0] == b"IHDR" and chunks[-1] == b"IEND", chunks
assert pos == len(data), "%d bytes after IEND" % (len(data) - pos)
assert (depth, colour) == (8, 2), (depth, colour)
assert len(zlib.decompress(idat)) == height * (1 + 3 * width)
PY
}

"$bin/ptsynth" -n 3000 -light 1 1 1 in.ptc >/dev/null
"$bin/ptview" in.ptc ref.png >ref.out
valid_png ref.png || fail "the reference picture is not a valid PNG"

# /dev/stdout redirected to a file.
if "$bin/ptview" in.ptc /dev/stdout >x.png 2>x.err; then
    valid_png x.png || fail "/dev/stdout > x.png: not a valid PNG: $(head -c 120 x.png | cat -v)"
    cmp -s ref.png x.png || fail "/dev/stdout > x.png differs from ref.png"
    grep -q "^ptview: wrote standard output: 512 x 512" x.err ||
        fail "the report did not go to stderr: $(cat x.err)"
else
    fail "ptview in.ptc /dev/stdout > x.png failed: $(cat x.err)"
fi

# '-' into a pipe, with -progress 1: ALF lines and the report on stderr.
if "$bin/ptview" -progress 1 in.ptc - 2>y.err | cat >y.png; then
    valid_png y.png || fail "- | cat: not a valid PNG: $(head -c 120 y.png | cat -v)"
    cmp -s ref.png y.png || fail "- | cat differs from ref.png"
    grep -qx "ALF_PROGRESS 100%" y.err || fail "no ALF_PROGRESS line on stderr: $(cat y.err)"
    grep -q "^ptview: tile 1: in.ptc" y.err || fail "no tile report on stderr: $(cat y.err)"
else
    fail "ptview in.ptc - | cat failed: $(cat y.err)"
fi

# -o - and /dev/stdout into a pipe.
"$bin/ptview" -o - in.ptc 2>/dev/null | cat >z.png || fail "-o - failed"
cmp -s ref.png z.png || fail "-o - differs from ref.png"
"$bin/ptview" in.ptc /dev/stdout 2>/dev/null | cat >w.png || fail "/dev/stdout | cat failed"
cmp -s ref.png w.png || fail "/dev/stdout | cat differs from ref.png"

# A terminal is no place for a PNG.
if command -v script >/dev/null; then
    rc=0
    script -qec "$bin/ptview in.ptc -" /dev/null >tty.txt || rc=$?
    grep -q "ptview ERROR: the picture would go to a terminal" tty.txt ||
        fail "a terminal as standard output was not refused: $(head -c 300 tty.txt | cat -v)"
    [[ "$rc" == 2 ]] || fail "a terminal as standard output: exit $rc, not 2"
    grep -q "PNG" tty.txt && fail "PNG bytes written to a terminal"
fi

finish_checks "ptview standard output"
