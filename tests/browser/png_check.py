#!/usr/bin/env python3
"""Checks two screenshots of the animation page (stdlib only): each shows
the mechanism (enough pixels of the links' blue and the masses' orange in
the 3-D view) and the view differs between them (the mechanism moved).
Usage: png_check.py A.png B.png
       png_check.py --flash AT_IMPACT.png BEFORE.png   (the impact halo)"""
import struct
import sys
import zlib


def read_png(path):
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", f"{path}: not a PNG"
    pos, idat = 8, b""
    while pos < len(data):
        (n,) = struct.unpack(">I", data[pos:pos + 4])
        kind, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            w, h, depth, ctype, _, _, interlace = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    assert depth == 8 and ctype in (2, 6) and interlace == 0, f"{path}: unsupported PNG"
    bpp = 3 if ctype == 2 else 4
    raw, stride = zlib.decompress(idat), w * bpp
    rows, prev, i = [], bytearray(stride), 0
    for _ in range(h):
        f, line = raw[i], bytearray(raw[i + 1:i + 1 + stride])
        i += 1 + stride
        for x in range(stride):
            a = line[x - bpp] if x >= bpp else 0
            b, c = prev[x], prev[x - bpp] if x >= bpp else 0
            if f == 1:
                line[x] = (line[x] + a) & 255
            elif f == 2:
                line[x] = (line[x] + b) & 255
            elif f == 3:
                line[x] = (line[x] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append([tuple(line[x:x + 3]) for x in range(0, stride, bpp)])
        prev = line
    return rows


def main(a, b):
    pa, pb = read_png(a), read_png(b)
    view = len(pa) - 50  # above the control bar
    for path, img in ((a, pa), (b, pb)):
        blue = sum(1 for row in img[:view] for (r, g, bl) in row if bl > r + 40 and bl > 80)
        orange = sum(1 for row in img[:view] for (r, g, bl) in row if r > 150 and bl < 90 and r > g + 30)
        print(f"{path}: {blue} link pixels, {orange} mass pixels")
        if blue < 100 or orange < 100:
            sys.exit(f"{path}: the mechanism is not drawn")
    moved = sum(1 for ra, rb in zip(pa[:view], pb[:view]) for x, y in zip(ra, rb) if x != y)
    print(f"{moved} pixels of the view differ")
    if moved < 500:
        sys.exit("the two screenshots show the same picture: nothing moved")


def flash(at_impact, before):
    """The impact halo (translucent red) is drawn at an impact and not
    before it."""
    counts = []
    for path in (at_impact, before):
        img = read_png(path)
        view = len(img) - 50
        n = sum(1 for row in img[:view] for (r, g, b) in row
                if r > 220 and 100 < g < 190 and abs(g - b) < 25)
        print(f"{path}: {n} halo pixels")
        counts.append(n)
    if counts[0] < 100 or counts[1] > 10:
        sys.exit("the impact does not flash (or something flashes without one)")


if __name__ == "__main__":
    if sys.argv[1] == "--flash":
        flash(sys.argv[2], sys.argv[3])
    else:
        main(sys.argv[1], sys.argv[2])
