#!/usr/bin/env python3
"""Makes data/denhaag/DenHaag_01_noground.json: Den Haag's CityJSON without its GroundSurface faces.

Input: data/denhaag/DenHaag_01.json (CityJSON 0.8, LoD2 Solids with semantic surfaces).
Output: the same file in which every Solid of a Building or BuildingPart loses the faces whose
semantic surface is a GroundSurface and becomes a MultiSurface of its remaining faces, with its
semantics and material values flattened to match (one value per remaining face). Everything else
(vertices, transform, other city objects, attributes, metadata) is kept as it is. That is how many
LoD2 exports come: roofs and walls, no floor, so the meshes are open.

Usage: python3 tools/denhaag_no_ground.py [INPUT [OUTPUT]]
Deterministic: the same input gives the same bytes. Standard library only.
"""

import json
import sys


def strip_ground(geom):
    """Returns (the geometry without its ground faces, how many were removed)."""
    if geom.get("type") != "Solid":
        return geom, 0
    sem = geom.get("semantics")
    if sem is None:
        return geom, 0
    surfaces = sem["surfaces"]
    mats = geom.get("material", {})
    faces, values, removed = [], [], 0
    mat_values = {name: [] for name in mats}
    for si, shell in enumerate(geom["boundaries"]):
        for fi, face in enumerate(shell):
            v = sem["values"][si][fi]
            if v is not None and surfaces[v]["type"] == "GroundSurface":
                removed += 1
                continue
            faces.append(face)
            values.append(v)
            for name, m in mats.items():
                if "values" in m:
                    mat_values[name].append(m["values"][si][fi])
    out = {k: val for k, val in geom.items() if k not in ("type", "boundaries", "semantics", "material")}
    out["type"] = "MultiSurface"
    out["boundaries"] = faces
    out["semantics"] = {"surfaces": surfaces, "values": values}
    if mats:
        out["material"] = {}
        for name, m in mats.items():
            nm = {k: val for k, val in m.items() if k != "values"}
            if "values" in m:
                nm["values"] = mat_values[name]
            out["material"][name] = nm
    # Keep the key order of the input where it can.
    ordered = {}
    for k in geom:
        if k in out:
            ordered[k] = out[k]
    for k in out:
        ordered.setdefault(k, out[k])
    return ordered, removed


def main():
    src = sys.argv[1] if len(sys.argv) > 1 else "data/denhaag/DenHaag_01.json"
    dst = sys.argv[2] if len(sys.argv) > 2 else "data/denhaag/DenHaag_01_noground.json"
    with open(src, encoding="utf-8") as f:
        doc = json.load(f)
    removed = 0
    for obj in doc["CityObjects"].values():
        if obj.get("type") not in ("Building", "BuildingPart"):
            continue
        geoms = []
        for g in obj.get("geometry", []):
            g2, n = strip_ground(g)
            geoms.append(g2)
            removed += n
        if "geometry" in obj:
            obj["geometry"] = geoms
    with open(dst, "w", encoding="utf-8") as f:
        json.dump(doc, f, separators=(",", ":"))
        f.write("\n")
    print(f"{dst}: removed {removed} GroundSurface faces")


if __name__ == "__main__":
    main()
