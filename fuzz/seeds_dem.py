#!/usr/bin/env python3
"""Seeds of the `dem` fuzz target: small GeoTIFF DEMs written by hand (struct and zlib only),
each exercising one path of src/scene/dem.rs: float32 with ModelPixelScale + ModelTiepoint and
GDAL_NODATA, pixel-is-point, a north-up ModelTransformation, int16 Deflate, no georeferencing,
a rotated transformation, a truncated file. Writes them into fuzz/seeds/dem and fuzz/corpus/dem.

Usage: python3 fuzz/seeds_dem.py
"""
import os
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))


def tiff(w, h, samples, fmt, sample_format, bits, tags, compress=False):
    """A little-endian single-strip TIFF. `tags`: list of (tag, type, values)."""
    data = struct.pack("<" + fmt * len(samples), *samples)
    if compress:
        data = zlib.compress(data)
    entries = [
        (256, 3, [w]),
        (257, 3, [h]),
        (258, 3, [bits]),
        (259, 3, [8 if compress else 1]),
        (262, 3, [1]),
        (273, 4, [0]),  # strip offset, patched below
        (277, 3, [1]),
        (278, 3, [h]),
        (279, 4, [len(data)]),
        (284, 3, [1]),
        (339, 3, [sample_format]),
    ] + tags
    entries.sort(key=lambda e: e[0])
    sizes = {2: 1, 3: 2, 4: 4, 12: 8}
    codes = {2: "s", 3: "H", 4: "I", 12: "d"}
    ifd_off = 8
    ifd_len = 2 + 12 * len(entries) + 4
    extra = bytearray()
    extra_off = ifd_off + ifd_len
    out_entries = []
    for tag, typ, vals in entries:
        if typ == 2:
            raw = vals.encode() + b"\0"
            count = len(raw)
        else:
            raw = struct.pack("<" + codes[typ] * len(vals), *vals)
            count = len(vals)
        out_entries.append([tag, typ, count, raw])
    # Values over 4 bytes go after the IFD; the strip after them.
    for e in out_entries:
        if len(e[3]) > 4:
            e.append(extra_off + len(extra))
            extra += e[3]
            if len(extra) % 2:
                extra += b"\0"
    strip_off = extra_off + len(extra)
    buf = bytearray(b"II*\0" + struct.pack("<I", ifd_off))
    buf += struct.pack("<H", len(out_entries))
    for e in out_entries:
        tag, typ, count, raw = e[:4]
        if tag == 273:
            raw = struct.pack("<I", strip_off)
        if len(raw) > 4:
            buf += struct.pack("<HHII", tag, typ, count, e[4])
        else:
            buf += struct.pack("<HHI", tag, typ, count) + raw.ljust(4, b"\0")
    buf += struct.pack("<I", 0)
    buf += extra
    buf += data
    return bytes(buf)


GEO = lambda raster_type, epsg: (34735, 3, [1, 1, 0, 2, 1025, 0, 1, raster_type, 3072, 0, 1, epsg])
SCALE = (33550, 12, [25.0, 25.0, 0.0])
TIE = (33922, 12, [0.0, 0.0, 0.0, 264000.0, 6244000.0, 0.0])


def seeds():
    w, h = 5, 4
    z = [10.0 + 0.5 * i + 2.0 * j for j in range(h) for i in range(w)]
    nd = list(z)
    nd[7] = -9999.0
    yield "float32_area_nodata.tif", tiff(w, h, nd, "f", 3, 32, [SCALE, TIE, GEO(1, 32734), (42113, 2, "-9999")])
    yield "float32_point.tif", tiff(w, h, z, "f", 3, 32, [SCALE, TIE, GEO(2, 32734)])
    m = [25.0, 0.0, 0.0, 264000.0, 0.0, -25.0, 0.0, 6244000.0, 0, 0, 1, 0, 0, 0, 0, 1]
    yield "float64_transformation.tif", tiff(w, h, z, "d", 3, 64, [(34264, 12, m)])
    zi = [int(v) for v in z]
    yield "int16_deflate.tif", tiff(w, h, zi, "h", 2, 16, [SCALE, TIE], compress=True)
    yield "no_georeferencing.tif", tiff(w, h, z, "f", 3, 32, [])
    r = list(m)
    r[1] = 3.0
    yield "rotated.tif", tiff(w, h, z, "f", 3, 32, [(34264, 12, r)])
    yield "truncated.tif", tiff(w, h, z, "f", 3, 32, [SCALE, TIE])[:-7]


def main():
    for d in ("seeds", "corpus"):
        os.makedirs(os.path.join(HERE, d, "dem"), exist_ok=True)
    for name, data in seeds():
        for d in ("seeds", "corpus"):
            with open(os.path.join(HERE, d, "dem", name), "wb") as f:
                f.write(data)
        print(name, len(data))


if __name__ == "__main__":
    main()
