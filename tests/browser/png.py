"""PNG pictures read with the standard library (8-bit grey, RGB or RGBA, not
interlaced: what ptview and Chromium write), and compared."""
import struct
import zlib


def read_png(data):
    """(width, height, rows): rows[y] is a list of (r, g, b) tuples."""
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError("not a PNG")
    pos, idat, header = 8, b"", None
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        pos += 12 + n
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        elif kind == b"IEND":
            break
    width, height, depth, colour, _, _, interlace = header
    channels = {0: 1, 2: 3, 6: 4, 4: 2}.get(colour)
    if depth != 8 or channels is None or interlace:
        raise ValueError(f"unsupported PNG (depth {depth}, colour type {colour}, interlace {interlace})")
    raw = zlib.decompress(idat)
    stride = width * channels
    rows, previous = [], bytearray(stride)
    for y in range(height):
        kind = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - channels] if i >= channels else 0
            b = previous[i]
            c = previous[i - channels] if i >= channels else 0
            if kind == 1:
                line[i] = (line[i] + a) & 255
            elif kind == 2:
                line[i] = (line[i] + b) & 255
            elif kind == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif kind == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        previous = line
        if channels >= 3:
            rows.append([tuple(line[x * channels:x * channels + 3]) for x in range(width)])
        else:
            rows.append([(v, v, v) for v in line[::channels]])
    return width, height, rows


def read_png_file(path):
    with open(path, "rb") as f:
        return read_png(f.read())


def compare(a, b, region=None, threshold=8):
    """How two pictures of one size differ in a region (x, y, w, h): the mean
    absolute difference per channel (0..255), the largest, and the share of
    pixels with a channel more than `threshold` apart."""
    wa, ha, ra = a
    wb, hb, rb = b
    if (wa, ha) != (wb, hb):
        raise ValueError(f"sizes differ: {wa}x{ha} and {wb}x{hb}")
    x0, y0, w, h = region or (0, 0, wa, ha)
    total, largest, far, n = 0, 0, 0, 0
    for y in range(y0, y0 + h):
        for x in range(x0, x0 + w):
            d = max(abs(p - q) for p, q in zip(ra[y][x], rb[y][x]))
            total += sum(abs(p - q) for p, q in zip(ra[y][x], rb[y][x])) / 3
            largest = max(largest, d)
            far += d > threshold
            n += 1
    return total / n, largest, far / n


def coverage(picture, background, region=None, tolerance=2):
    """The share of pixels in a region not within `tolerance` of a colour."""
    w, h, rows = picture
    x0, y0, rw, rh = region or (0, 0, w, h)
    count = 0
    for y in range(y0, y0 + rh):
        for x in range(x0, x0 + rw):
            count += max(abs(p - q) for p, q in zip(rows[y][x], background)) > tolerance
    return count / (rw * rh)
