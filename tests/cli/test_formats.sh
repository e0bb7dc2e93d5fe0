#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# CLI test of the formats other tools read: the display colours of .ply clouds
# (uchar red/green/blue next to the float channels), read by CloudCompare and
# MeshLab when they are installed, and OpenVDB output (brickmake out.vdb)
# checked with OpenVDB's own vdb_print and described by brickinfo.
# Needs SSS_BIN_DIR (the folder with ptsynth, ptfilter, ptinfo, brickmake and
# brickinfo). CloudCompare (Debian: cloudcompare), meshlabserver with
# xvfb-run (meshlab, xvfb) and vdb_print (libopenvdb-tools) are used when
# present; each check that needs an absent one says SKIP.
#
# Every check runs; failures are listed and the script exits 1 at the end.
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must name the folder with the executables}"
ptsynth="$bin/ptsynth"
ptfilter="$bin/ptfilter"
ptinfo="$bin/ptinfo"
brickmake="$bin/brickmake"
brickinfo="$bin/brickinfo"
for tool in "$ptsynth" "$ptfilter" "$ptinfo" "$brickmake" "$brickinfo"; do
    [[ -x "$tool" ]] || { echo "FAIL: missing executable $tool" >&2; exit 1; }
done
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_formats.XXXXXX")"
trap 'rm -rf "$work"' EXIT
cd "$work"

# shellcheck source=lib.sh
source "$here/lib.sh"
# shellcheck source=checks.sh
source "$here/checks.sh"

# ply_colors FILE: one line "r g b" per vertex of a binary little-endian PLY
# with uchar red/green/blue (ours or another tool's), and on stderr a FAIL
# line for any of our vertices whose bytes are not its _ssdiffusion floats
# clamped to [0, 1], sRGB-encoded and rounded.
ply_colors() {
    python3 - "$1" <<'PY'
import struct, sys
path = sys.argv[1]
data = open(path, "rb").read()
end = data.index(b"end_header\n") + len(b"end_header\n")
props, count, fmt_ok = [], 0, False
in_vertex = False
for line in data[:end].decode().splitlines():
    w = line.split()
    if w[:2] == ["format", "binary_little_endian"]:
        fmt_ok = True
    elif w[:1] == ["element"]:
        in_vertex = w[1] == "vertex"
        if in_vertex:
            count = int(w[2])
    elif w[:1] == ["property"] and in_vertex:
        props.append((w[-1], w[1]))
if not fmt_ok:
    sys.exit("not a binary little-endian PLY")
codes = {"float": "f", "float32": "f", "uchar": "B", "uint8": "B", "double": "d",
         "int": "i", "uint": "I", "short": "h", "ushort": "H", "char": "b"}
fmt = "<" + "".join(codes[t] for _, t in props)
size = struct.calcsize(fmt)
names = [n for n, _ in props]
def srgb(c):
    c = min(max(c, 0.0), 1.0)
    return 12.92 * c if c <= 0.0031308 else 1.055 * c ** (1 / 2.4) - 0.055
bad = 0
for i in range(count):
    v = dict(zip(names, struct.unpack_from(fmt, data, end + i * size)))
    rgb = [v["red"], v["green"], v["blue"]]
    print(*rgb)
    if "_ssdiffusion_r" in v:
        want = [round(255 * srgb(v["_ssdiffusion_" + k])) for k in "rgb"]
        if want != rgb and bad < 5:
            print(f"FAIL: vertex {i}: colour {rgb}, expected {want} from _ssdiffusion",
                  file=sys.stderr)
            bad += 1
PY
}

# ---------------------------------------------------------------------------
# PLY: ptfilter's output has display colours made from _ssdiffusion.
run "$ptsynth" -n 3000 -size 1 -light 1 1 0.5 -ambient 0.05 synth.ptc
expect_rc 0 "ptsynth" || exit 1
run "$ptfilter" -ssdiffusion -material marble -unitlength 0.1 synth.ptc ssd.ply
expect_rc 0 "ptfilter ... ssd.ply" || exit 1
header="$(sed -n '1,/^end_header/p' ssd.ply 2>/dev/null | tr -d '\r')"
grep -q '^comment sss_display_color _ssdiffusion$' <<<"$header" ||
    fail "ssd.ply has no sss_display_color comment: $header"
for p in red green blue; do
    grep -q "^property uchar $p\$" <<<"$header" || fail "ssd.ply lacks the uchar $p: $header"
done
for p in _ssdiffusion_r _ssdiffusion_g _ssdiffusion_b; do
    grep -q "^property float $p\$" <<<"$header" || fail "ssd.ply lacks the float $p"
done
if ply_colors ssd.ply >ours.txt 2>ours.err; then
    [[ ! -s ours.err ]] || fail "ssd.ply colour bytes: $(head -n 5 ours.err)"
    [[ "$(wc -l <ours.txt)" == "$(points ssd.ply)" ]] || fail "ssd.ply: not one colour per point"
    # Lit and unlit sides: the colours vary, and are not all white.
    distinct="$(sort -u ours.txt | wc -l)"
    ((distinct > 20)) || fail "ssd.ply has only $distinct distinct colours"
    grep -qv '^255 255 255$' ours.txt || fail "ssd.ply is all white"
else
    fail "cannot read the colours of ssd.ply: $(cat ours.err)"
fi
# Our reader skips the colour bytes: the same channels as the .ptc, no red.
run "$ptinfo" ssd.ply
if expect_rc 0 "ptinfo ssd.ply"; then
    grep -Eq '^ *color _ssdiffusion$' stdout || fail "ptinfo ssd.ply lacks _ssdiffusion: $out"
    ! grep -Eq '(red|green|blue)$' stdout || fail "ptinfo ssd.ply shows colour channels: $out"
fi
run "$ptfilter" -ssdiffusion -material marble -unitlength 0.1 synth.ptc ssd.ptc
expect_rc 0 "ptfilter ... ssd.ptc" || true
run "$ptinfo" ssd.ptc
ptc_report="$(grep -E '^ *(color|float) ' stdout || true)"
run "$ptinfo" ssd.ply
[[ "$(grep -E '^ *(color|float) ' stdout || true)" == "$ptc_report" ]] ||
    fail "ssd.ply and ssd.ptc list different channels"
# A .ply with every channel (-keepchannels 1) is ptfilter's input again: the
# colour bytes are not read back as channels, and the result is the same.
run "$ptfilter" -ssdiffusion -material marble -unitlength 0.1 -keepchannels 1 synth.ptc keep.ply
expect_rc 0 "ptfilter -keepchannels 1 ... keep.ply" || true
run "$ptfilter" -ssdiffusion -material marble -unitlength 0.1 -keepchannels 1 keep.ply again.ply
expect_rc 0 "ptfilter reads its own .ply" || true
cmp -s keep.ply again.ply || fail "keep.ply filtered again is not the same file"

# CloudCompare, headless (Qt's offscreen platform): the RGB it reads are ours.
if command -v CloudCompare >/dev/null 2>&1; then
    run env QT_QPA_PLATFORM=offscreen timeout 120 CloudCompare -SILENT -AUTO_SAVE OFF \
        -O ssd.ply -C_EXPORT_FMT ASC -ADD_HEADER -SAVE_CLOUDS FILE cc.asc
    if expect_rc 0 "CloudCompare -O ssd.ply" && [[ -s cc.asc ]]; then
        head -n 1 cc.asc | grep -q '^//X Y Z R G B' ||
            fail "CloudCompare read no colours: $(head -n 1 cc.asc)"
        awk 'NR > 1 { print $4, $5, $6 }' cc.asc >cc.txt
        cmp -s cc.txt ours.txt ||
            fail "CloudCompare's colours differ from ours: $(diff cc.txt ours.txt | head -n 4)"
    else
        fail "CloudCompare wrote no cc.asc: $(tail -n 3 stdout)"
    fi
else
    echo "SKIP: CloudCompare is not installed (Debian: apt-get install cloudcompare)"
fi

# MeshLab's meshlabserver needs an X display (OpenGL): under xvfb-run.
if command -v meshlabserver >/dev/null 2>&1 && command -v xvfb-run >/dev/null 2>&1; then
    run timeout 120 xvfb-run -a meshlabserver -i ssd.ply -o ml.ply -m vc
    if expect_rc 0 "meshlabserver -i ssd.ply" && [[ -s ml.ply ]]; then
        if ply_colors ml.ply >ml.txt 2>ml.err; then
            cmp -s ml.txt ours.txt ||
                fail "MeshLab's colours differ from ours: $(diff ml.txt ours.txt | head -n 4)"
        else
            fail "cannot read MeshLab's ml.ply: $(cat ml.err)"
        fi
    else
        fail "meshlabserver wrote no ml.ply: $(tail -n 3 stdout)"
    fi
else
    echo "SKIP: meshlabserver or xvfb-run is not installed (Debian: apt-get install meshlab xvfb)"
fi

# ---------------------------------------------------------------------------
# OpenVDB: brickmake in.ptc out.vdb.
run "$brickmake" -progress 1 ssd.ptc ssd.vdb
if expect_rc 0 "brickmake ssd.ptc ssd.vdb"; then
    [[ -s ssd.vdb ]] || fail "no ssd.vdb"
    grep -Eq '^brickmake: ssd.vdb: [0-9]+ points, [0-9]+ bricks, [0-9]+ grids \(main grids at depth [0-9]+\)' stdout ||
        fail "brickmake -progress 1 does not report the grids: $out"
fi
depth="$(sed -n 's/.*main grids at depth \([0-9]*\).*/\1/p' stdout)"
left="$(find . -name '.*.tmp' -o -name '*.bkm')"
[[ -z "$left" ]] || fail "brickmake left scratch files: $left"

if command -v vdb_print >/dev/null 2>&1; then
    run vdb_print -l ssd.vdb
    if expect_rc 0 "vdb_print -l ssd.vdb"; then
        grep -q '^Name: _ssdiffusion$' stdout || fail "vdb_print lists no _ssdiffusion grid: ${out:0:600}"
        grep -q '^Name: _ssdiffusion_level1$' stdout || fail "vdb_print lists no _ssdiffusion_level1"
        grep -q 'Type: Tree_vec3s_5_4_3' stdout || fail "_ssdiffusion is not a vec3s grid"
        grep -q 'sss_channel_type: color' stdout || fail "no sss_channel_type metadata"
        # The main grid's voxels are the map's samples at its depth: voxel
        # size = root cube side / (7 * 2^depth), as brickinfo prints for a .bkm.
        vsize="$(awk '/^Name: _ssdiffusion$/ { g = 1 } g && /voxel size:/ { print $3; exit }' stdout)"
        run "$brickmake" ssd.ptc ssd.bkm
        run "$brickinfo" -verify 0 ssd.bkm
        side="$(sed -n 's/^root cube: .* side //p' stdout)"
        awk -v v="$vsize" -v s="$side" -v d="$depth" 'BEGIN {
            want = s / (7 * 2 ^ d); exit !(v != "" && want > 0 && (v - want) ^ 2 < (2e-3 * want) ^ 2) }' ||
            fail "voxel size '$vsize' is not the side $side / (7 * 2^$depth)"
    fi
else
    echo "SKIP: vdb_print is not installed (Debian: apt-get install libopenvdb-tools)"
fi

# brickinfo describes a .vdb after reading every grid.
run "$brickinfo" ssd.vdb
if expect_rc 0 "brickinfo ssd.vdb"; then
    grep -q '^format: OpenVDB ' stdout || fail "brickinfo ssd.vdb: no format line: $out"
    grep -Eq '^  _ssdiffusion: vec3s, [1-9][0-9]* active voxels' stdout ||
        fail "brickinfo ssd.vdb does not describe _ssdiffusion: $out"
    grep -Eq '^checked: [1-9][0-9]* float and vec3s grids read' stdout ||
        fail "brickinfo ssd.vdb: no checked line"
    grep -q '^sss_provenance: brickmake .* ssd.ptc ssd.vdb$' stdout ||
        fail "brickinfo ssd.vdb: no provenance: $out"
fi
run "$brickinfo" ssd.vdb -picture p.png
expect_rc 2 "brickinfo ssd.vdb -picture" &&
    [[ "$err" == *"brickinfo ERROR: ssd.vdb is an OpenVDB file"* ]] ||
    fail "brickinfo -picture on a .vdb: $err"
printf 'not a vdb file at all\n' >junk.vdb
run "$brickinfo" junk.vdb
expect_rc 1 "brickinfo junk.vdb" && [[ "$err" == *"brickinfo ERROR: junk.vdb: not a readable OpenVDB file"* ]] ||
    fail "brickinfo junk.vdb: $err"

# -newer 1 keeps an up-to-date .vdb and rebuilds one OpenVDB cannot read.
run "$brickmake" -newer 1 ssd.ptc ssd.vdb
expect_rc 0 "-newer 1 on ssd.vdb" && [[ "$out" == *"nothing to do"* ]] ||
    fail "brickmake -newer 1 rebuilt an up-to-date .vdb: $out"
touch junk.vdb
run "$brickmake" -newer 1 ssd.ptc junk.vdb
expect_rc 0 "-newer 1 on junk.vdb" && [[ "$err" == *"rebuilding it"* ]] ||
    fail "brickmake -newer 1 kept an unreadable .vdb: $err"
run "$brickinfo" -info 0 junk.vdb
expect_rc 0 "junk.vdb rebuilt" || true

# ptfilter writes clouds, not grids.
run "$ptfilter" -ssdiffusion -material marble synth.ptc out.vdb
expect_rc 2 "ptfilter ... out.vdb" || true
[[ ! -e out.vdb ]] || fail "ptfilter wrote out.vdb"

finish_checks formats
