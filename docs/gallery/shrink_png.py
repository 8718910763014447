#!/usr/bin/env python3
"""Makes the gallery's screenshots smaller: each 8-bit RGB(A) PNG given is rewritten in place with
its channels rounded to multiples of 8 (a change the eye does not see on a screenshot; meshes and
shading otherwise cost many distinct colours) and every row filtered against the one above, then
deflated at the highest level. About a third smaller on the reports' screenshots. Python's
standard library only:  docs/gallery/shrink_png.py FILE.png..."""
import struct
import sys
import zlib


def read_rgb(png):
    """(width, height, rows of bytes R G B ...) of an 8-bit RGB or RGBA PNG, not interlaced."""
    assert png[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    pos, idat, width, height, channels = 8, b"", 0, 0, 0
    while pos < len(png):
        length = int.from_bytes(png[pos:pos + 4], "big")
        kind, body = png[pos + 4:pos + 8], png[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width, height = int.from_bytes(body[0:4], "big"), int.from_bytes(body[4:8], "big")
            assert body[8] == 8 and body[9] in (2, 6) and body[12] == 0, "only 8-bit RGB(A), not interlaced"
            channels = 3 if body[9] == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    raw, stride = zlib.decompress(idat), width * channels
    rows, previous, p = [], bytearray(stride), 0
    for _ in range(height):
        kind, line = raw[p], bytearray(raw[p + 1:p + 1 + stride])
        p += 1 + stride
        for i in range(stride):  # undo the row's filter (PNG specification, section 9)
            a = line[i - channels] if i >= channels else 0
            b, c = previous[i], previous[i - channels] if i >= channels else 0
            if kind == 1:
                line[i] = (line[i] + a) & 255
            elif kind == 2:
                line[i] = (line[i] + b) & 255
            elif kind == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif kind == 4:
                pa, pb, pc = abs(b - c), abs(a - c), abs(a + b - 2 * c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(bytes(v for j in range(0, stride, channels) for v in line[j:j + 3]))
        previous = line
    return width, height, rows


def chunk(kind, body):
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)


def shrink(path):
    with open(path, "rb") as f:
        width, height, rows = read_rgb(f.read())
    rounded = bytes(255 if v >= 252 else (v + 4) & ~7 for v in range(256))
    raw, previous = bytearray(), None
    for row in rows:
        line = row.translate(rounded)
        raw += b"\x00" + line if previous is None else b"\x02" + bytes((x - y) & 255 for x, y in zip(line, previous))
        previous = line
    png = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)) +
           chunk(b"IDAT", zlib.compress(bytes(raw), 9)) + chunk(b"IEND", b""))
    with open(path, "wb") as f:
        f.write(png)


if __name__ == "__main__":
    for name in sys.argv[1:]:
        shrink(name)
