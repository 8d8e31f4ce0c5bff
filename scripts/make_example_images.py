#!/usr/bin/env python3
"""Dev-only: writes the small synthetic example images under examples/data.

star.png      128x128 8-bit gray, a five-armed star (190) on a dark background (60),
              Gaussian noise sigma 12, seeded.
four.png      128x128, four separate objects (paper Figure 2).
balls.nrrd    48^3 uint8 gzip NRRD, two overlapping balls (paper Figure 3).
"""
import gzip, math, random, struct, zlib, pathlib

out = pathlib.Path(__file__).resolve().parent.parent / "examples" / "data"


def png_gray(path, w, h, rows):
    raw = b"".join(b"\x00" + bytes(r) for r in rows)
    def chunk(t, d):
        return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xFFFFFFFF)
    data = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0))
    data += chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
    path.write_bytes(data)


def picture(w, h, inside, seed):
    rng = random.Random(seed)
    return [[max(0, min(255, round((190 if inside(c + .5, r + .5) else 60) + rng.gauss(0, 12))))
             for c in range(w)] for r in range(h)]


def star(x, y):
    dx, dy = x - 64, y - 64
    return math.hypot(dx, dy) < 34 * (1 + 0.3 * math.cos(5 * math.atan2(dy, dx)))


def four(x, y):
    return (math.hypot(x - 36, y - 36) < 16 or (abs(x - 92) < 14 and abs(y - 38) < 12)
            or ((x - 34) / 18) ** 2 + ((y - 90) / 11) ** 2 < 1 or abs(x - 90) + abs(y - 92) < 18)


png_gray(out / "star.png", 128, 128, picture(128, 128, star, 7))
png_gray(out / "four.png", 128, 128, picture(128, 128, four, 11))

n, rng = 48, random.Random(5)
vox = bytearray()
for k in range(n):
    for j in range(n):
        for i in range(n):
            p = (i + .5, j + .5, k + .5)
            inside = any(math.dist(p, c) < 8.5 for c in [(16.5, 24, 24), (31.5, 24, 24)])
            vox.append(max(0, min(255, round((190 if inside else 60) + rng.gauss(0, 10)))))
header = f"NRRD0004\ntype: uint8\ndimension: 3\nsizes: {n} {n} {n}\nencoding: gzip\n\n".encode()
(out / "balls.nrrd").write_bytes(header + gzip.compress(bytes(vox), 6))
