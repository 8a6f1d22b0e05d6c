#!/usr/bin/env python3
"""Writes tests/fixtures/scenes/tiny.osm.pbf: a hand-made OpenStreetMap PBF (standard library
only: protobuf encoded by hand, zlib blobs; deterministic) with one case per rule of the reader
(src/scene/osm.rs), near Helsinki (24.94 E, 60.17 N):
  way 100   building=yes, height=12                        -> top 12
  way 101   building=apartments, building:levels=5, building:min_level=1 -> base 3, top 15
  way 102   building=yes, height=10, a node not in the file -> skipped (incomplete)
  way 103   building=no                                    -> not a building
  way 104   building=yes, no height                        -> skipped (no height)
  way 105   building=yes, height=1e300                     -> skipped (bad height)
  relation 200  type=multipolygon, building=yes, height="30 m", roof:height=5: outer ring from
            ways 201 and 202 (joined end to end, 202 reversed), inner way 203 -> top 25, a hole
Usage: python3 tools/osm_sample_pbf.py [OUT]
"""
import os
import struct
import sys
import zlib


def varint(n):
    out = b""
    while True:
        b = n & 0x7F
        n >>= 7
        if n:
            out += bytes([b | 0x80])
        else:
            return out + bytes([b])


def zz(n):
    return (n << 1) ^ (n >> 63)


def key(f, wt):
    return varint((f << 3) | wt)


def ld(f, data):
    return key(f, 2) + varint(len(data)) + data


def vint(f, n):
    return key(f, 0) + varint(n)


def packed(f, values):
    return ld(f, b"".join(varint(v) for v in values))


def delta(values):
    out, last = [], 0
    for v in values:
        out.append(zz(v - last))
        last = v
    return out


class Strings:
    def __init__(self):
        self.s = [b""]

    def id(self, text):
        b = text.encode()
        if b not in self.s:
            self.s.append(b)
        return self.s.index(b)

    def table(self):
        return ld(1, b"".join(ld(1, s) for s in self.s))


def blob(kind, payload):
    body = vint(2, len(payload)) + ld(3, zlib.compress(payload, 9))
    header = ld(1, kind.encode()) + vint(3, len(body))
    return struct.pack(">I", len(header)) + header + body


def main(out):
    lon0, lat0 = 24.94, 60.17
    dx, dy = 0.0004, 0.0002  # about 22 m east, 22 m north
    nodes = {}

    def node(i, x, y):
        nodes[i] = (round((lat0 + y) * 1e7), round((lon0 + x) * 1e7))
        return i

    def square(base, x, y, w=1.0, h=1.0):
        ids = [node(base + k, x + px * dx * w, y + py * dy * h)
               for k, (px, py) in enumerate([(0, 0), (1, 0), (1, 1), (0, 1)])]
        return ids + [ids[0]]

    st = Strings()
    ways = []

    def way(i, refs, tags):
        ways.append((i, refs, tags))

    way(100, square(1000, 0, 0), {"building": "yes", "height": "12"})
    way(101, square(1010, 2 * dx, 0), {"building": "apartments", "building:levels": "5",
                                       "building:min_level": "1"})
    way(102, square(1020, 4 * dx, 0)[:-1] + [999, 1020], {"building": "yes", "height": "10"})
    way(103, square(1030, 6 * dx, 0), {"building": "no", "height": "10"})
    way(104, square(1040, 8 * dx, 0), {"building": "yes"})
    way(105, square(1050, 10 * dx, 0), {"building": "yes", "height": "1e300"})
    # The relation: an outer 3 x 3 square split in two ways, a 1 x 1 hole in its middle.
    o = square(2000, 0, 3 * dy, 3, 3)[:-1]
    way(201, [o[0], o[1], o[2]], {})
    way(202, [o[0], o[3], o[2]], {})
    way(203, square(2010, dx, 4 * dy), {})
    nodes.pop(999, None)

    ng = b""
    for i in sorted(nodes):
        lat, lon = nodes[i]
        ng += ld(1, vint(1, zz(i)) + vint(8, zz(lat)) + vint(9, zz(lon)))
    wg = b""
    for i, refs, tags in ways:
        ks = [st.id(k) for k in tags]
        vs = [st.id(v) for v in tags.values()]
        w = vint(1, i) + (packed(2, ks) + packed(3, vs) if tags else b"") + packed(8, delta(refs))
        wg += ld(3, w)
    rtags = {"type": "multipolygon", "building": "yes", "height": "30 m", "roof:height": "5"}
    roles = [st.id("outer"), st.id("outer"), st.id("inner")]
    rel = (vint(1, 200) + packed(2, [st.id(k) for k in rtags]) +
           packed(3, [st.id(v) for v in rtags.values()]) + packed(8, roles) +
           packed(9, delta([201, 202, 203])) + packed(10, [1, 1, 1]))
    block = st.table() + ld(2, ng) + ld(2, wg) + ld(2, ld(4, rel))
    header = ld(4, b"OsmSchema-V0.6") + ld(16, b"tools/osm_sample_pbf.py")
    with open(out, "wb") as f:
        f.write(blob("OSMHeader", header) + blob("OSMData", block))


if __name__ == "__main__":
    root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    main(sys.argv[1] if len(sys.argv) > 1 else
         os.path.join(root, "tests", "fixtures", "scenes", "tiny.osm.pbf"))
