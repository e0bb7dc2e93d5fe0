#!/usr/bin/env python3
"""Writes the hostile point clouds of this folder: tiny gzip files whose
headers claim about 2^31 points (a memory bomb if a reader allocated for the
header's count) and one whose claim the compressed size could hold but whose
data ends after four points. tests/cli/test_cloud_bombs.sh reads them.

Run once from anywhere: python3 tests/data/hostile/clouds/make_clouds.py
The outputs are committed; rerunning reproduces them byte for byte (gzip
with mtime 0).
"""

import gzip
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))
CLAIM = 2**31
IDENTITY = [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]
POINTS = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)]


def ptc(count):
    """A version 0 .ptc without channels: header, then 20-byte records."""
    out = bytearray(struct.pack("<iid", 0x63747070, 0, float(count)))
    out += struct.pack("<6f", 0, 0, 0, 1, 1, 1)
    out += struct.pack("<16f", *IDENTITY) + struct.pack("<16f", *IDENTITY)
    out += struct.pack("<3f", 64, 64, 1) + struct.pack("<ii", 0, 0)
    for p in POINTS:
        out += struct.pack("<3fHHf", *p, 0, 65535, 0.1)
    return bytes(out)


def ply_header(fmt, count):
    return ("ply\nformat %s 1.0\nelement vertex %d\nproperty float x\n"
            "property float y\nproperty float z\nproperty float radius\n"
            "end_header\n" % (fmt, count)).encode()


def save(name, data):
    with open(os.path.join(HERE, name), "wb") as f:
        # mtime 0 and no file name: reproducible bytes.
        with gzip.GzipFile(fileobj=f, mode="wb", mtime=0, filename="") as z:
            z.write(data)


save("claims_2g_gz.ptc", ptc(CLAIM))
save("claims_2g_gz.ply", ply_header("binary_little_endian", CLAIM)
     + b"".join(struct.pack("<4f", *p, 0.1) for p in POINTS))
save("claims_2g_ascii_gz.ply", ply_header("ascii", CLAIM)
     + b"".join(b"%g %g %g 0.1\n" % p for p in POINTS))
# 2000 points of 20 bytes: within what 66 compressed bytes could inflate
# to, so the reader must start reading and find the data missing.
save("claims_2k_gz.ptc", ptc(2000))
