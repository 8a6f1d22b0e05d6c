#!/usr/bin/env python3
"""Writes data/denhaag/DenHaag_01_lod2.gml: the first 120 Buildings of Den Haag's CityJSON
(data/denhaag/DenHaag_01.json, CityJSON 0.8, LoD2 solids) and their BuildingParts as CityGML 2.0,
the way LoD2 CityGML usually comes: each face a gml:Polygon with a gml:id inside a thematic
surface (bldg:WallSurface, RoofSurface, GroundSurface, by the CityJSON semantics) under
bldg:boundedBy, and the bldg:lod2Solid's shell a list of xlink:href references to those polygons,
in the CityJSON face order. BuildingParts are nested in their Building (consistsOfBuildingPart).

Coordinates are the CityJSON vertices with its transform applied in double precision
(i * scale + translate) and written with repr(), the shortest text that reads back as the same
double, so a reader that applies the transform the same way gets the same numbers. Standard
library only; deterministic: rerunning it gives the same bytes. Usage:
    python3 tools/denhaag_to_citygml.py
"""
import json
import os
from xml.sax.saxutils import quoteattr

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
SRC = os.path.join(ROOT, "data", "denhaag", "DenHaag_01.json")
OUT = os.path.join(ROOT, "data", "denhaag", "DenHaag_01_lod2.gml")
BUILDINGS = 120


def main():
    with open(SRC, encoding="utf-8") as f:
        d = json.load(f)
    scale = d["transform"]["scale"]
    tr = d["transform"]["translate"]
    verts = [[v[k] * scale[k] + tr[k] for k in range(3)] for v in d["vertices"]]
    objs = d["CityObjects"]
    parts_of = {}
    for oid, o in objs.items():
        if o["type"] == "BuildingPart":
            parts_of.setdefault(o["parent"], []).append(oid)
    buildings = [oid for oid, o in objs.items() if o["type"] == "Building"][:BUILDINGS]
    used = [v for b in buildings for v in [b] + parts_of.get(b, [])]
    xs = [verts[i] for oid in used for g in objs[oid].get("geometry", [])
          for shell in g["boundaries"] for s in shell for r in s for i in r]
    lo = [min(p[k] for p in xs) for k in range(3)]
    hi = [max(p[k] for p in xs) for k in range(3)]

    out = []
    w = out.append
    w('<?xml version="1.0" encoding="UTF-8"?>\n')
    w('<core:CityModel xmlns:core="http://www.opengis.net/citygml/2.0" '
      'xmlns:bldg="http://www.opengis.net/citygml/building/2.0" '
      'xmlns:gml="http://www.opengis.net/gml" xmlns:xlink="http://www.w3.org/1999/xlink">\n')
    w('<gml:name>Den Haag tile 01, first %d buildings, LoD2 (from DenHaag_01.json)</gml:name>\n'
      % BUILDINGS)
    w(' <gml:boundedBy><gml:Envelope srsName="urn:ogc:def:crs,crs:EPSG::28992,crs:EPSG::5109" '
      'srsDimension="3"><gml:lowerCorner>%s</gml:lowerCorner><gml:upperCorner>%s</gml:upperCorner>'
      '</gml:Envelope></gml:boundedBy>\n' % (" ".join(map(repr, lo)), " ".join(map(repr, hi))))

    def ring(r):
        pts = [verts[i] for i in r] + [verts[r[0]]]
        return " ".join(repr(c) for p in pts for c in p)

    def polygon(pid, surface):
        s = '<gml:Polygon gml:id=%s><gml:exterior><gml:LinearRing><gml:posList>%s' \
            '</gml:posList></gml:LinearRing></gml:exterior>' % (quoteattr(pid), ring(surface[0]))
        for hole in surface[1:]:
            s += '<gml:interior><gml:LinearRing><gml:posList>%s</gml:posList></gml:LinearRing>' \
                 '</gml:interior>' % ring(hole)
        return s + '</gml:Polygon>'

    def body(oid, indent):
        o = objs[oid]
        solid, bounded = [], []
        for gi, g in enumerate(o.get("geometry", [])):
            if g["type"] != "Solid":
                raise SystemExit("%s: geometry %s" % (oid, g["type"]))
            sem = g.get("semantics")
            hrefs = []
            for si, shell in enumerate(g["boundaries"]):
                for fi, surface in enumerate(shell):
                    pid = "%s_g%d_s%d_f%d" % (oid, gi, si, fi)
                    kind = None
                    if sem is not None:
                        v = sem["values"][si][fi]
                        kind = None if v is None else sem["surfaces"][v]["type"]
                    if kind in ("WallSurface", "RoofSurface", "GroundSurface"):
                        hrefs.append('<gml:surfaceMember xlink:href="#%s"/>' % pid)
                        bounded.append(
                            '<bldg:boundedBy><bldg:%s gml:id=%s><bldg:lod2MultiSurface>'
                            '<gml:MultiSurface><gml:surfaceMember>%s</gml:surfaceMember>'
                            '</gml:MultiSurface></bldg:lod2MultiSurface></bldg:%s></bldg:boundedBy>'
                            % (kind, quoteattr(pid + "_ts"), polygon(pid, surface), kind))
                    else:
                        hrefs.append('<gml:surfaceMember>%s</gml:surfaceMember>'
                                     % polygon(pid, surface))
                if si > 0:
                    raise SystemExit("%s: a solid with interior shells" % oid)
            solid.append('<bldg:lod2Solid><gml:Solid><gml:exterior><gml:CompositeSurface>%s'
                         '</gml:CompositeSurface></gml:exterior></gml:Solid></bldg:lod2Solid>'
                         % "".join(hrefs))
        return "".join(indent + s + "\n" for s in solid + bounded)

    for b in buildings:
        w(' <core:cityObjectMember>\n  <bldg:Building gml:id=%s>\n' % quoteattr(b))
        w(body(b, "   "))
        for p in parts_of.get(b, []):
            w('   <bldg:consistsOfBuildingPart>\n    <bldg:BuildingPart gml:id=%s>\n'
              % quoteattr(p))
            w(body(p, "     "))
            w('    </bldg:BuildingPart>\n   </bldg:consistsOfBuildingPart>\n')
        w('  </bldg:Building>\n </core:cityObjectMember>\n')
    w('</core:CityModel>\n')
    with open(OUT, "w", encoding="utf-8", newline="\n") as f:
        f.write("".join(out))


if __name__ == "__main__":
    main()
