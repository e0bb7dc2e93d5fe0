#!/usr/bin/env python3
"""Writes the tiny point clouds in tests/data with Python's struct module,
independently of the sss writer, so the C++ reader is checked against a
second implementation of the layout in docs/file-formats.md.

Run once from anywhere: python3 tests/data/make_tiny_ptc.py
The outputs are committed; rerunning reproduces them byte for byte.
"""

import gzip
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))

# Three points: P, (phi, z) normal codes, radius, _area, _radiance_t.
POINTS = [
    ((0.0, 0.0, 0.0), (0, 65535), 0.1, 0.01, (1.0, 0.0, 0.0)),  # N = +z
    ((1.0, 2.0, 3.0), (65535, 65535), 0.2, 0.02, (0.0, 1.0, 0.0)),  # zero normal
    ((-1.0, 0.5, 2.0), (49151, 32768), 0.3, 0.03, (0.5, 0.25, 0.125)),  # N ~ +x
]
CHANNELS = [("float", "_area"), ("color", "_radiance_t")]
DATASIZE = 4


def ptc_bytes(version, world2eye, world2ndc, image_format):
    out = bytearray()
    out += struct.pack("<iid", 0x63747070, version, float(len(POINTS)))
    xs = [p[0] for p in POINTS]
    lo = [min(c[i] for c in xs) for i in range(3)]
    hi = [max(c[i] for c in xs) for i in range(3)]
    out += struct.pack("<6f", *lo, *hi)
    if version >= 1:
        out += struct.pack("<4f", 0.0, 0.0, 0.0, 0.0)
    if version >= 2:
        out += struct.pack("<f", max(p[2] for p in POINTS))
        out += struct.pack("<32I", *([0xDEADBEEF] * 32))
    out += struct.pack("<16f", *world2eye)
    out += struct.pack("<16f", *world2ndc)
    out += struct.pack("<3f", *image_format)
    assert len(out) == {0: 180, 1: 196, 2: 328}[version]
    out += struct.pack("<ii", len(CHANNELS), DATASIZE)
    for ctype, name in CHANNELS:
        out += f"{ctype} {name}\n".encode("ascii")
    if version >= 1:
        out += struct.pack("<2f", 0.0, 0.0)
    for pos, (phi, z), radius, area, rad in POINTS:
        out += struct.pack("<3f2Hf", *pos, phi, z, radius)
        out += struct.pack("<f3f", area, *rad)
    return bytes(out)


IDENTITY = (1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1)
TRANSLATE = (1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 5, 1)

with open(os.path.join(HERE, "tiny_v0.ptc"), "wb") as f:
    f.write(ptc_bytes(0, TRANSLATE, IDENTITY, (640.0, 480.0, 1.0)))

# mtime=0 keeps the gzip bytes reproducible.
with open(os.path.join(HERE, "tiny_v2_gzip.ptc"), "wb") as f:
    f.write(gzip.compress(ptc_bytes(2, IDENTITY, IDENTITY, (0.0, 0.0, 1.0)), mtime=0))

# An ASCII PLY as another tool would write it: no sss comments, a face element.
with open(os.path.join(HERE, "tiny_foreign.ply"), "w", newline="\n") as f:
    f.write(
        "ply\nformat ascii 1.0\ncomment made by make_tiny_ptc.py\n"
        "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
        "property uchar red\nproperty double confidence\n"
        "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
        "0 0 0 255 0.5\n1 2 3 128 0.25\n-1 0.5 2 0 1\n3 0 1 2\n"
    )
