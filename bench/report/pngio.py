"""Minimal PNG reading and writing with the Python standard library (zlib + struct).

Reads the 8-bit, non-interlaced greyscale / RGB / RGBA / grey+alpha PNGs that irrcache (stb_image_write)
and Chromium write; writes 8-bit RGB. Used by bench/run to cut zoomed crops out of rendered images and by
the browser test to check that a screenshot is not blank. Images are Image(width, height, channels,
pixels) with pixels one bytes object of rows, top to bottom, channels interleaved.
"""

import struct
import zlib
from collections import namedtuple

Image = namedtuple("Image", "width height channels pixels")

_SIGNATURE = b"\x89PNG\r\n\x1a\n"
_CHANNELS = {0: 1, 2: 3, 4: 2, 6: 4}  # PNG colour type -> samples per pixel


class PngError(ValueError):
    """A file that is not a PNG this module reads (the message says what is unsupported)."""


def _paeth(a, b, c):
    p = a + b - c
    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
    if pa <= pb and pa <= pc:
        return a
    return b if pb <= pc else c


def _unfilter(raw, width, height, bpp):
    """Undoes the per-row PNG filters (None, Sub, Up, Average, Paeth); returns the raw pixel bytes."""
    stride = width * bpp
    out = bytearray(stride * height)
    prev = bytearray(stride)
    pos = 0
    for y in range(height):
        ftype = raw[pos]
        line = bytearray(raw[pos + 1:pos + 1 + stride])
        pos += 1 + stride
        if ftype == 1:
            for i in range(bpp, stride):
                line[i] = (line[i] + line[i - bpp]) & 255
        elif ftype == 2:
            for i in range(stride):
                line[i] = (line[i] + prev[i]) & 255
        elif ftype == 3:
            for i in range(stride):
                left = line[i - bpp] if i >= bpp else 0
                line[i] = (line[i] + ((left + prev[i]) >> 1)) & 255
        elif ftype == 4:
            for i in range(stride):
                left = line[i - bpp] if i >= bpp else 0
                upleft = prev[i - bpp] if i >= bpp else 0
                line[i] = (line[i] + _paeth(left, prev[i], upleft)) & 255
        elif ftype != 0:
            raise PngError("unknown PNG row filter %d" % ftype)
        out[y * stride:(y + 1) * stride] = line
        prev = line
    return bytes(out)


def read_png(path):
    """Decodes an 8-bit non-interlaced PNG file into an Image."""
    with open(path, "rb") as f:
        data = f.read()
    if not data.startswith(_SIGNATURE):
        raise PngError("%s: not a PNG file" % path)
    pos = len(_SIGNATURE)
    header = None
    idat = []
    while pos + 8 <= len(data):
        (length,) = struct.unpack(">I", data[pos:pos + 4])
        kind = data[pos + 4:pos + 8]
        body = data[pos + 8:pos + 8 + length]
        pos += 12 + length
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat.append(body)
        elif kind == b"IEND":
            break
    if header is None:
        raise PngError("%s: PNG without IHDR" % path)
    width, height, depth, ctype, _, _, interlace = header
    if depth != 8 or ctype not in _CHANNELS or interlace:
        raise PngError("%s: only 8-bit non-interlaced grey/RGB/RGBA PNGs are supported (depth %d, colour type %d, "
                       "interlace %d)" % (path, depth, ctype, interlace))
    channels = _CHANNELS[ctype]
    raw = zlib.decompress(b"".join(idat))
    if len(raw) < height * (1 + width * channels):
        raise PngError("%s: truncated PNG image data" % path)
    return Image(width, height, channels, _unfilter(raw, width, height, channels))


def _chunk(kind, body):
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)


def write_png(path, image):
    """Writes an Image as an 8-bit PNG (filter type 0 on every row; zlib does the compression)."""
    ctype = {1: 0, 2: 4, 3: 2, 4: 6}[image.channels]
    stride = image.width * image.channels
    rows = b"".join(b"\x00" + image.pixels[y * stride:(y + 1) * stride] for y in range(image.height))
    header = struct.pack(">IIBBBBB", image.width, image.height, 8, ctype, 0, 0, 0)
    with open(path, "wb") as f:
        f.write(_SIGNATURE + _chunk(b"IHDR", header) + _chunk(b"IDAT", zlib.compress(rows, 9)) +
                _chunk(b"IEND", b""))


def crop(image, x0, y0, x1, y1):
    """The pixels in [x0, x1) x [y0, y1) (clamped to the image) as a new Image."""
    x0, x1 = max(0, x0), min(image.width, x1)
    y0, y1 = max(0, y0), min(image.height, y1)
    if x1 <= x0 or y1 <= y0:
        raise ValueError("empty crop rectangle")
    stride = image.width * image.channels
    rows = [image.pixels[y * stride + x0 * image.channels:y * stride + x1 * image.channels] for y in range(y0, y1)]
    return Image(x1 - x0, y1 - y0, image.channels, b"".join(rows))


def crop_fraction(image, rect):
    """Crop by a rectangle (fx0, fy0, fx1, fy1) given as fractions of the image's width and height."""
    fx0, fy0, fx1, fy1 = rect
    return crop(image, int(round(fx0 * image.width)), int(round(fy0 * image.height)),
                int(round(fx1 * image.width)), int(round(fy1 * image.height)))


def luma_stats(image, step=1):
    """(mean, variance, distinct-value count) of the 8-bit luma over every step-th pixel: a blank image has
    variance 0 and very few distinct values."""
    c = image.channels
    px = image.pixels
    n = 0
    total = 0.0
    total_sq = 0.0
    seen = set()
    for i in range(0, image.width * image.height, step):
        o = i * c
        if c >= 3:
            v = (54 * px[o] + 183 * px[o + 1] + 19 * px[o + 2]) >> 8
        else:
            v = px[o]
        seen.add(v)
        total += v
        total_sq += v * v
        n += 1
    mean = total / n
    return mean, max(0.0, total_sq / n - mean * mean), len(seen)
