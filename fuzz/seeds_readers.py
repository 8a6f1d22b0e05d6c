#!/usr/bin/env python3
"""Seeds of the fuzz targets of the readers added for issue 33 (osm, gpkg, fgb, shp, citygml,
cityjsonseq; docs/FUZZING.md), beside fuzz/seeds.py, which makes the others.

Input: tests/fixtures (the broken files of each reader, `tiny.osm.pbf`, `lyon3.fgb`,
`lyon3.shp`), and slices of data/ (the first buildings of `DenHaag_01_lod2.gml`, the first lines
of `delft.city.jsonl`); a GeoPackage of three footprints is written here with sqlite3. Output:
files under the directory given (default fuzz/seeds/<target>/), named by content. Standard
library only; deterministic.
"""

import hashlib
import os
import sqlite3
import struct
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "fuzz", "seeds")


def put(target, data, tag):
    if isinstance(data, str):
        data = data.encode()
    d = os.path.join(OUT, target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, f"{tag}-{hashlib.sha1(data).hexdigest()[:12]}"), "wb") as f:
        f.write(data)


def read(rel):
    with open(os.path.join(ROOT, rel), "rb") as f:
        return f.read()


def fixtures(prefixes, target, scenes=()):
    d = os.path.join(ROOT, "tests", "fixtures", "broken")
    for name in sorted(os.listdir(d)):
        if name.startswith(prefixes):
            put(target, read(f"tests/fixtures/broken/{name}"), "fixture")
    for name in scenes:
        put(target, read(f"tests/fixtures/scenes/{name}"), "fixture")


def gpkg_seed():
    """Three footprints (one with a hole) with a `height` column, in EPSG:3946."""
    def wkb(rings):
        b = struct.pack("<BII", 1, 3, len(rings))
        for r in rings:
            b += struct.pack("<I", len(r)) + b"".join(struct.pack("<dd", x, y) for x, y in r)
        return b"GP\x00\x01" + struct.pack("<i", 3946) + b

    def sq(x, y, s):
        return [(x, y), (x + s, y), (x + s, y + s), (x, y + s), (x, y)]

    with tempfile.TemporaryDirectory() as t:
        p = os.path.join(t, "seed.gpkg")
        c = sqlite3.connect(p)
        c.executescript("""
PRAGMA page_size = 1024;
create table gpkg_spatial_ref_sys (srs_name text, srs_id integer primary key, organization text,
  organization_coordsys_id integer, definition text, description text);
insert into gpkg_spatial_ref_sys values ('RGF93 / CC46', 3946, 'EPSG', 3946, 'undefined', null);
create table gpkg_geometry_columns (table_name text, column_name text, geometry_type_name text,
  srs_id integer, z integer, m integer);
insert into gpkg_geometry_columns values ('b', 'geom', 'POLYGON', 3946, 0, 0);
create table b (fid integer primary key autoincrement, geom blob, height real, levels integer);
""")
        x0, y0 = 1842000.0, 5176000.0
        rows = [
            (wkb([sq(x0, y0, 20)]), 12.5, None),
            (wkb([sq(x0 + 30, y0, 30), sq(x0 + 40, y0 + 10, 10)[::-1]]), None, 4),
            (wkb([sq(x0 + 70, y0, 10)]), 30.0, None),
        ]
        c.executemany("insert into b (geom, height, levels) values (?, ?, ?)", rows)
        c.commit()
        c.execute("VACUUM")
        c.close()
        with open(p, "rb") as f:
            return f.read()


def main():
    fixtures(("osm_",), "osm", ["tiny.osm.pbf"])
    fixtures(("gpkg_",), "gpkg")
    put("gpkg", gpkg_seed(), "footprints")
    fixtures(("fgb_",), "fgb", ["lyon3.fgb"])
    fixtures(("shp_",), "shp", ["lyon3.shp"])
    fixtures(("citygml_",), "citygml")
    gml = read("data/denhaag/DenHaag_01_lod2.gml").decode()
    head, _, rest = gml.partition(" <core:cityObjectMember>")
    members = rest.split(" <core:cityObjectMember>")
    for k in (0, 1, 2):
        body = " <core:cityObjectMember>" + members[k].split("</core:CityModel>")[0]
        put("citygml", head + body + "</core:CityModel>\n", "denhaag")
    fixtures(("cityjsonseq_",), "cityjsonseq")
    lines = read("data/delft/delft.city.jsonl").decode().splitlines(keepends=True)
    put("cityjsonseq", "".join(lines[:4]), "delft")
    put("cityjsonseq", lines[0] + lines[10], "delft")


if __name__ == "__main__":
    main()
