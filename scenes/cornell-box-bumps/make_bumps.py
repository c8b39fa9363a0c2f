#!/usr/bin/env python3
"""Writes bumps.png, the tangent-space normal map of cornell-box-bumps.json: 4 x 4 round bumps (spherical
caps whose rim slopes 40 degrees) per tile, 8-bit RGB, +x right, +y up (green up), no sRGB curve."""
import math
import struct
import zlib

SIZE, BUMPS, SLOPE = 64, 4, math.radians(40.0)


def texel(x, y):
    cell = SIZE / BUMPS
    u = ((x + 0.5) % cell) / cell * 2.0 - 1.0  # -1..1 across a bump
    v = -(((y + 0.5) % cell) / cell * 2.0 - 1.0)  # rows run downwards; +y is up
    r = math.hypot(u, v)
    if r >= 1.0:
        n = (0.0, 0.0, 1.0)
    else:
        s = math.sin(SLOPE) * r  # the cap's slope grows from 0 at the centre to SLOPE at the rim
        n = (s * u / max(r, 1e-9), s * v / max(r, 1e-9), math.sqrt(1.0 - s * s))
    return bytes(min(255, max(0, round(255.0 * (0.5 + 0.5 * c)))) for c in n)


def chunk(kind, data):
    return struct.pack('>I', len(data)) + kind + data + struct.pack('>I', zlib.crc32(kind + data) & 0xFFFFFFFF)


rows = b''.join(b'\x00' + b''.join(texel(x, y) for x in range(SIZE)) for y in range(SIZE))
with open('bumps.png', 'wb') as f:
    f.write(b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', SIZE, SIZE, 8, 2, 0, 0, 0)) +
            chunk(b'IDAT', zlib.compress(rows, 9)) + chunk(b'IEND', b''))
