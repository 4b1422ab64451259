"""Checks that plot files are real pictures, not empty frames (tests/plots/run.sh).

    python3 tests/plots/png_check.py FILE.png|FILE.gif|FILE.svg ...

PNG (8-bit RGB/RGBA, as gnuplot's pngcairo writes them), decoded with the
standard library: at least MIN_DRAWN (2 %) of the pixels differ from the
background (the most common colour) and at least 6 colours are used.
GIF: the GIF89a header and at least MIN_FRAMES image descriptors (an
animation). SVG: an <svg> element with at least 20 drawing elements.
Prints one line per file; exits 1 if any file fails.
"""
import struct
import sys
import zlib
from collections import Counter

MIN_DRAWN = 0.02
MIN_COLOURS = 6
MIN_FRAMES = 10


def png_pixels(path):
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    pos, idat, w = 8, b"", None
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            w, h, depth, ctype = struct.unpack(">IIBB", body[:10])
            assert depth == 8 and ctype in (2, 6), f"PNG colour type {ctype}, depth {depth} not handled"
            bpp = 3 if ctype == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    raw = zlib.decompress(idat)
    stride = w * bpp
    rows, prev = [], bytearray(stride)
    for y in range(h):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b = prev[i]
            c = prev[i - bpp] if i >= bpp else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(bytes(line))
        prev = line
    return w, h, bpp, rows


def check_png(path):
    w, h, bpp, rows = png_pixels(path)
    count = Counter()
    for r in rows[::2]:   # every other row and pixel: fast enough, same statistics
        for i in range(0, len(r), 2 * bpp):
            count[r[i:i + 3]] += 1
    total = sum(count.values())
    bg, nbg = count.most_common(1)[0]
    drawn = 1 - nbg / total
    ok = drawn >= MIN_DRAWN and len(count) >= MIN_COLOURS
    return ok, f"{w}x{h}, {100 * drawn:.1f} % drawn, {len(count)} colours"


def check_gif(path):
    data = open(path, "rb").read()
    frames = data.count(b"\x21\xf9\x04")   # one graphic control extension per frame
    ok = data[:6] == b"GIF89a" and frames >= MIN_FRAMES
    return ok, f"{len(data)} bytes, {frames} frames"


def check_svg(path):
    text = open(path, encoding="utf-8", errors="replace").read()
    n = sum(text.count(t) for t in ("<path", "<polyline", "<line", "<text"))
    return "<svg" in text and n >= 20, f"{n} drawing elements"


bad = 0
for f in sys.argv[1:]:
    try:
        ok, what = (check_png if f.endswith(".png") else check_gif if f.endswith(".gif") else check_svg)(f)
    except (OSError, AssertionError, zlib.error, struct.error) as e:
        ok, what = False, str(e)
    print(f"{'ok  ' if ok else 'FAIL'} {f}: {what}")
    bad |= not ok
sys.exit(1 if bad else 0)
