#!/usr/bin/env python3
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""Writes small hostile image files for the CLI tests (nothing is committed):
headers that declare huge images, tiny tiles, corrupt and truncated data.

usage: hostile_images.py FOLDER

Files written (each a few hundred bytes):
  huge.png      PNG whose IHDR declares 100000000 x 100000000 pixels
  wide.png      PNG of 200000 x 200000 pixels (within libpng's own bounds)
  corrupt.png   PNG whose IDAT holds garbage (a bad zlib stream)
  truncated.png a valid 64 x 64 PNG cut in its IDAT
  huge.tif      TIFF whose first directory declares 100000000 x 100000000
  tiles.tif     tiled TIFF of 60000 x 60000 pixels in 16 x 16 tiles, one offset
  huge.exr      scanline OpenEXR whose data window is 100000000 x 100000000
  tiles.exr     tiled OpenEXR of 60000 x 60000 pixels in 1 x 1 tiles
  truncated.exr a scanline OpenEXR cut in its offset table
  ok.png        a valid 64 x 32 RGB PNG (the control)
"""
import struct
import sys
import zlib
from pathlib import Path


def png_chunk(kind, data):
    body = kind + data
    return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))


def png(width, height, idat, extra=b""):
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + png_chunk(b"IHDR", ihdr) + extra +
            png_chunk(b"IDAT", idat) + png_chunk(b"IEND", b""))


# Valid images whose ancillary chunks are wrong in ways libpng warns about
# (a bogus ICC profile, a zero gamma, repeated or short chunks, a keyword of
# length 0): they must read with no line of libpng's on stderr.
ODD_CHUNKS = {
    "iccp": png_chunk(b"iCCP", b"bogus\0\0" + zlib.compress(b"not a profile" * 8)),
    "gama0": png_chunk(b"gAMA", struct.pack(">I", 0)),
    "gama2": png_chunk(b"gAMA", struct.pack(">I", 100000)) + png_chunk(b"gAMA", b"\0\0\0\1"),
    "srgb": png_chunk(b"sRGB", b"\7\7"),
    "srgb2": png_chunk(b"sRGB", b"\0") + png_chunk(b"sRGB", b"\0"),
    "chrm": png_chunk(b"cHRM", b"\0" * 32),
    "phys": png_chunk(b"pHYs", b"\0" * 9),
    "time": png_chunk(b"tIME", b"\0" * 7),
    "text0": png_chunk(b"tEXt", b"\0hello"),
    "ztxt": png_chunk(b"zTXt", b"key\0\0garbage"),
    "itxt": png_chunk(b"iTXt", b"key\0\1\0\0\0garbage"),
    "bkgd": png_chunk(b"bKGD", b"\0"),
    "sbit": png_chunk(b"sBIT", b"\x09\x09\x09"),
    "trns": png_chunk(b"tRNS", b"\0" * 7),
    "hist": png_chunk(b"hIST", b"\0\0"),
}


def png_rows(width, height):
    raw = b"".join(b"\x00" + bytes((x * 4) % 256 for x in range(width * 3))
                   for _ in range(height))
    return zlib.compress(raw)


def tiff(width, height, tile=0):
    """Little-endian grey 8-bit TIFF; strips (tile 0) or tile x tile tiles."""
    entries = [(256, 4, 1, width), (257, 4, 1, height), (258, 3, 1, 8), (259, 3, 1, 1),
               (262, 3, 1, 1), (277, 3, 1, 1)]
    if tile:
        entries += [(322, 3, 1, tile), (323, 3, 1, tile), (324, 4, 1, 8), (325, 4, 1, 1)]
    else:
        entries += [(273, 4, 1, 8), (278, 4, 1, height), (279, 4, 1, 1)]
    entries.sort()
    out = b"II*\x00" + struct.pack("<I", 16) + b"\x00" * 8
    out += struct.pack("<H", len(entries))
    for tag, kind, count, value in entries:
        out += struct.pack("<HHI", tag, kind, count)
        out += struct.pack("<HH", value, 0) if kind == 3 else struct.pack("<I", value)
    return out + struct.pack("<I", 0)


def exr_attr(name, kind, data):
    return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(data)) + data


def exr(width, height, tile=0, offsets=1):
    """One half channel Y, no compression; `offsets` entries of the table."""
    chlist = b"Y\0" + struct.pack("<iBBBBii", 1, 0, 0, 0, 0, 1, 1) + b"\0"
    box = struct.pack("<iiii", 0, 0, width - 1, height - 1)
    head = exr_attr("channels", "chlist", chlist)
    head += exr_attr("compression", "compression", b"\0")
    head += exr_attr("dataWindow", "box2i", box)
    head += exr_attr("displayWindow", "box2i", box)
    head += exr_attr("lineOrder", "lineOrder", b"\0")
    head += exr_attr("pixelAspectRatio", "float", struct.pack("<f", 1))
    head += exr_attr("screenWindowCenter", "v2f", struct.pack("<ff", 0, 0))
    head += exr_attr("screenWindowWidth", "float", struct.pack("<f", 1))
    version = 2
    if tile:
        head += exr_attr("tiles", "tiledesc", struct.pack("<IIB", tile, tile, 0))
        version |= 0x200
    out = struct.pack("<ii", 20000630, version) + head + b"\0"
    return out + struct.pack("<Q", 0) * offsets


def main():
    folder = Path(sys.argv[1])
    folder.mkdir(parents=True, exist_ok=True)
    ok = png(64, 32, png_rows(64, 32))
    (folder / "ok.png").write_bytes(ok)
    for name, chunk in ODD_CHUNKS.items():
        (folder / f"odd_{name}.png").write_bytes(png(64, 32, png_rows(64, 32), chunk))
    (folder / "huge.png").write_bytes(png(100000000, 100000000, png_rows(4, 4)))
    (folder / "wide.png").write_bytes(png(200000, 200000, png_rows(4, 4)))
    (folder / "corrupt.png").write_bytes(png(64, 32, b"\x78\x9c" + b"garbage" * 20))
    full = png(64, 64, png_rows(64, 64))
    (folder / "truncated.png").write_bytes(full[: len(full) // 2])
    (folder / "huge.tif").write_bytes(tiff(100000000, 100000000))
    (folder / "tiles.tif").write_bytes(tiff(60000, 60000, tile=16))
    (folder / "huge.exr").write_bytes(exr(100000000, 100000000))
    (folder / "tiles.exr").write_bytes(exr(60000, 60000, tile=1))
    (folder / "truncated.exr").write_bytes(exr(64, 64, offsets=10))


if __name__ == "__main__":
    main()
