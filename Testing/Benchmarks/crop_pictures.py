"""Crops of apcQualitySweep --spacing pictures side by side, for docs/evaluation.md (4.2): where
a lattice shows itself (a staircase, ripple or notches along a silhouette the rays graze,
speckles) it is a few pixels wide, too small to see in the whole picture.

    /usr/bin/python3 crop_pictures.py OUT.png X0 Y0 W H SCALE IN.png [IN.png ...]

Cuts the rectangle (X0, Y0, W, H; pixels from the top left) out of each 8-bit RGB or RGBA
PNG, enlarges it SCALE times (nearest pixel) and writes them left to right with a 4-pixel
white gap, as RGB. Plain Python (zlib), no imaging library.
"""

import struct
import sys
import zlib


def read_png(path):
    with open(path, "rb") as fh:
        data = fh.read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError("%s: not a PNG" % path)
    pos, idat = 8, b""
    width = height = channels = 0
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        pos += 12 + length
        if kind == b"IHDR":
            width, height, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", body)
            if depth != 8 or colour not in (2, 6) or interlace:
                raise ValueError("%s: only 8-bit RGB/RGBA, not interlaced" % path)
            channels = 3 if colour == 2 else 4
        elif kind == b"IDAT":
            idat += body
    raw = zlib.decompress(idat)
    stride = width * channels
    rows, prev = [], bytearray(stride)
    for y in range(height):
        start = y * (stride + 1)
        kind, line = raw[start], bytearray(raw[start + 1:start + 1 + stride])
        for i in range(stride):
            a = line[i - channels] if i >= channels else 0
            b = prev[i]
            c = prev[i - channels] if i >= channels else 0
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
        rows.append(bytes(line))
        prev = line
    rgb = [bytes(b for i, b in enumerate(r) if i % channels < 3) for r in rows]
    return width, height, rgb


def write_png(path, width, height, rows):
    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(
            ">I", zlib.crc32(kind + body) & 0xFFFFFFFF)
    raw = b"".join(b"\x00" + r for r in rows)
    with open(path, "wb") as fh:
        fh.write(b"\x89PNG\r\n\x1a\n")
        fh.write(chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)))
        fh.write(chunk(b"IDAT", zlib.compress(raw, 9)))
        fh.write(chunk(b"IEND", b""))


def main(argv):
    if len(argv) < 8:
        print(__doc__)
        return 2
    out = argv[1]
    x0, y0, w, h, scale = (int(v) for v in argv[2:7])
    gap = 4
    crops = []
    for path in argv[7:]:
        width, height, rgb = read_png(path)
        if x0 < 0 or y0 < 0 or x0 + w > width or y0 + h > height:
            raise ValueError("%s: the rectangle leaves the %dx%d picture" % (path, width, height))
        crop = []
        for y in range(y0, y0 + h):
            line = b"".join(rgb[y][3 * x:3 * x + 3] * scale for x in range(x0, x0 + w))
            crop.extend([line] * scale)
        crops.append(crop)
    white = b"\xff\xff\xff" * gap
    rows = [white.join(c[y] for c in crops) for y in range(h * scale)]
    write_png(out, len(crops) * w * scale + (len(crops) - 1) * gap, h * scale, rows)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
