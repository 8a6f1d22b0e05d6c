#!/usr/bin/env python3
"""Writes a CityJSON file as CityJSONSeq (CityJSON Text Sequences, `.city.jsonl`): line 1 the
header (type, version, transform, metadata; empty CityObjects and vertices), then one
CityJSONFeature per city object without a parent, holding it and its children with their own
vertex list (indices renumbered from 0 in first-use order; the integer coordinates unchanged, so
the header's transform gives the same numbers). What `cjio FILE export jsonl` writes, with the
standard library only; deterministic. Usage:
    python3 tools/cityjson_to_seq.py data/delft/delft.json data/delft/delft.city.jsonl
"""
import json
import sys


def renumber(b, vmap, verts, src):
    if isinstance(b, list):
        return [renumber(x, vmap, verts, src) for x in b]
    if b not in vmap:
        vmap[b] = len(verts)
        verts.append(src[b])
    return vmap[b]


def main(src_path, out_path):
    with open(src_path, encoding="utf-8") as f:
        d = json.load(f)
    header = {"type": "CityJSON", "version": d["version"], "transform": d["transform"],
              "CityObjects": {}, "vertices": []}
    if "metadata" in d:
        header["metadata"] = d["metadata"]
    lines = [json.dumps(header, separators=(",", ":"))]
    objs = d["CityObjects"]
    for oid, o in objs.items():
        if o.get("parents"):
            continue
        ids = [oid] + [c for c in o.get("children", []) if c in objs]
        vmap, verts, out = {}, [], {}
        for i in ids:
            c = dict(objs[i])
            geoms = []
            for g in c.get("geometry", []):
                g = dict(g)
                if "boundaries" in g and g.get("type") != "GeometryInstance":
                    g["boundaries"] = renumber(g["boundaries"], vmap, verts, d["vertices"])
                g.pop("texture", None)
                g.pop("material", None)
                geoms.append(g)
            if "geometry" in c:
                c["geometry"] = geoms
            out[i] = c
        feat = {"type": "CityJSONFeature", "id": oid, "CityObjects": out, "vertices": verts}
        lines.append(json.dumps(feat, separators=(",", ":")))
    with open(out_path, "w", encoding="utf-8", newline="\n") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
