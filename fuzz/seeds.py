#!/usr/bin/env python3
"""Seed corpora of the fuzz targets: small valid and broken inputs (docs/FUZZING.md).

Input: tests/fixtures, small slices of the bundled data (data/), the worked examples of
docs/FORMAT.md, and stores and blobs written by `vocc` (path of the binary in $VOCC, default
target/release/vocc). Output: files under the directory given (default fuzz/seeds/<target>/),
named by content. Invariants: deterministic (same inputs, same files); every file is small
(slices of at most a few buildings); nothing outside the output directory is written except
the temporary folder it bakes in. The seeds are committed; fuzz/minimize.sh keeps them whole in
the committed corpora under fuzz/corpus/ and adds what fuzzing found beyond them.
"""

import hashlib
import json
import os
import re
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "fuzz", "seeds")
VOCC = os.environ.get("VOCC", os.path.join(ROOT, "target", "release", "vocc"))


def put(target, data, tag):
    if isinstance(data, str):
        data = data.encode()
    d = os.path.join(OUT, target)
    os.makedirs(d, exist_ok=True)
    name = f"{tag}-{hashlib.sha1(data).hexdigest()[:12]}"
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


def read(rel, mode="rb"):
    with open(os.path.join(ROOT, rel), mode) as f:
        return f.read()


def fixtures(prefixes, target):
    d = os.path.join(ROOT, "tests", "fixtures")
    for sub in ("broken", "scenes"):
        for name in sorted(os.listdir(os.path.join(d, sub))):
            if name.startswith(prefixes):
                put(target, read(f"tests/fixtures/{sub}/{name}"), "fixture")


def doc_hex(name):
    """The bytes of a ```hex example:NAME block of docs/FORMAT.md."""
    text = read("docs/FORMAT.md", "r")
    block = re.search(r"```hex example:" + name + r"\n(.*?)```", text, re.S).group(1)
    out = bytearray()
    for line in block.splitlines():
        body = line.split("#")[0].split(":", 1)[1]
        out += bytes.fromhex(body.replace(" ", ""))
    return bytes(out)


# --- store and blob ---------------------------------------------------------------------------

# The worked examples of both versions (2.0, and the 1.0 of section 12 that 2.0 still reads).
for st_name, blobs in (("store", ("blob-cell0", "blob-cell1")),
                       ("store-1.0", ("blob-1.0-cell0", "blob-1.0-cell1"))):
    store = doc_hex(st_name)
    put("store", store, "doc")
    frame = store[16:128]
    for b in blobs:
        blob = doc_hex(b)
        put("blob", blob, "doc")
        put("blob", frame + blob, "doc-framed")


def cells_to_export(st):
    """Up to 6 cells of a store: the first ones with VOs, one skipped, one empty."""
    nx, ny = (int.from_bytes(st[o:o + 4], "little") for o in (64, 68))
    major = int.from_bytes(st[8:10], "little")
    start = 136 if major == 1 else 136 + 13 + st[148]
    index = st[start:start + nx * ny]
    vos = [i for i, v in enumerate(index) if 0 < v <= 10][:4]
    skipped = [i for i, v in enumerate(index) if v == 255][:1]
    empty = [i for i, v in enumerate(index) if v == 0][:1]
    return vos + skipped + empty


with tempfile.TemporaryDirectory() as tmp:
    city = os.path.join(tmp, "city.geojson")
    subprocess.run([VOCC, "gen-city", "--buildings", "300", "--seed", "3", "-o", city],
                   check=True, capture_output=True)
    bakes = [(city, "height", size, f"gencity-{size}m") for size in ("20", "40")]
    bakes.append((os.path.join(ROOT, "data/lyon1/buildings_lyon1.geojson"), "HAUTEUR", "100",
                  "lyon-100m"))
    for scene, attr, size, tag in bakes:
        path = os.path.join(tmp, f"{tag}.vocc")
        subprocess.run([VOCC, "bake", scene, "--height-attr", attr, "--cell-size", size,
                        "-o", path], check=True, capture_output=True)
        st = open(path, "rb").read()
        put("store", st, tag)
        for cell in cells_to_export(st):
            bl = os.path.join(tmp, f"{tag}-{cell}.blob")
            subprocess.run([VOCC, "export", path, "--cell", str(cell), "--blob", bl],
                           check=True, capture_output=True)
            fr = bl + ".frame"  # export --blob FILE writes the frame to FILE.frame
            put("blob", open(fr, "rb").read() + open(bl, "rb").read(), f"{tag}-framed")
    small = os.path.join(tmp, "small.geojson")
    subprocess.run([VOCC, "gen-city", "--buildings", "6", "--seed", "5", "-o", small],
                   check=True, capture_output=True)
    put("geojson", open(small, "rb").read(), "gencity")

# --- GeoJSON -----------------------------------------------------------------------------------

fixtures(("geojson_",), "geojson")
put("geojson", read("tests/fixtures/scenes/heights_and_levels.geojson"), "fixture")
lyon = json.loads(read("data/lyon1/buildings_lyon1.geojson"))


def slim(f):
    """A Lyon feature with its id and height only (as `height`), 3 decimals."""
    g = f["geometry"]

    def r(c):
        return [r(x) for x in c] if isinstance(c, list) else round(c, 3)

    return {"type": "Feature", "id": f["properties"]["ID"][-6:],
            "properties": {"height": f["properties"]["HAUTEUR"]},
            "geometry": {"type": g["type"], "coordinates": r(g["coordinates"])}}


feats = lyon["features"]
holes = [f for f in feats if f["geometry"]["type"] == "Polygon" and len(f["geometry"]["coordinates"]) > 1]
multi = [f for f in feats if f["geometry"]["type"] == "MultiPolygon"]
by_size = sorted(feats, key=lambda f: len(json.dumps(f["geometry"])))
picks = {
    "first3": feats[:3],
    "hole": holes[:1],
    "multi": multi[:1],
    "mid": by_size[len(by_size) // 2: len(by_size) // 2 + 2],
}
for tag, fs in picks.items():
    if fs:
        doc = {"type": "FeatureCollection", "features": [slim(f) for f in fs]}
        put("geojson", json.dumps(doc, separators=(",", ":")), f"lyon-{tag}")

# --- CityJSON ----------------------------------------------------------------------------------

fixtures(("cityjson_",), "cityjson")


def cj_slice(doc, ids):
    """The city objects `ids` (and their parts) with only the vertices they use, re-indexed."""
    objs = {}
    for i in ids:
        objs[i] = doc["CityObjects"][i]
        for c in objs[i].get("children", []):
            objs[c] = doc["CityObjects"][c]
    used = {}

    def remap(b):
        if isinstance(b, list):
            return [remap(x) for x in b]
        if b not in used:
            used[b] = len(used)
        return used[b]

    out = {}
    for k, o in objs.items():
        o = {"type": o["type"], **({"children": o["children"]} if "children" in o else {}),
             "geometry": [{kk: (remap(vv) if kk == "boundaries" else vv)
                           for kk, vv in g.items() if kk != "semantics" and kk != "texture"}
                          for g in o.get("geometry", [])]}
        out[k] = o
    verts = [None] * len(used)
    for old, new in used.items():
        verts[new] = doc["vertices"][old]
    s = {"type": "CityJSON", "version": doc["version"], "CityObjects": out, "vertices": verts}
    if "transform" in doc:
        s["transform"] = doc["transform"]
    return json.dumps(s, separators=(",", ":"))


for rel, tag in (("data/denhaag/DenHaag_01.json", "denhaag"), ("data/delft/delft.json", "delft")):
    doc = json.loads(read(rel))
    tops = [k for k, o in doc["CityObjects"].items()
            if o["type"] in ("Building", "BuildingPart") and "parents" not in o]
    for k in range(3):
        put("cityjson", cj_slice(doc, tops[k * 7: k * 7 + 2]), tag)

# --- OBJ -----------------------------------------------------------------------------------------

fixtures(("obj_",), "obj")


def obj_slice(text, first, count):
    """Groups first..first+count of an OBJ, with only their vertices, re-indexed."""
    verts, groups, cur = [], [], None
    for line in text.splitlines():
        w = line.split()
        if not w:
            continue
        if w[0] == "v":
            verts.append(line)
        elif w[0] in ("o", "g"):
            cur = [line, []]
            groups.append(cur)
        elif w[0] == "f" and cur is not None:
            cur[1].append([int(t.split("/")[0]) for t in w[1:]])
    used, out_v, body = {}, [], []
    for head, faces in groups[first:first + count]:
        body.append(head)
        for f in faces:
            idx = []
            for i in f:
                i = i - 1 if i > 0 else len(verts) + i
                if i not in used:
                    used[i] = len(used) + 1
                    out_v.append(verts[i])
                idx.append(str(used[i]))
            body.append("f " + " ".join(idx))
    return "\n".join(out_v + body) + "\n"


for rel, tag in (("data/delft/delft_buildings.obj", "delft"),
                 ("data/denhaag/DenHaag_01_buildings.obj", "denhaag"),
                 ("data/gelderseplein/gelderseplein.obj", "gelderseplein")):
    text = read(rel, "r")
    for first in (0, 10, 40, 60):
        piece = obj_slice(text, first, 2)
        if len(piece) <= 12_000:  # keep libFuzzer's max_len (the largest seed) small
            put("obj", piece, tag)

# --- walkable --------------------------------------------------------------------------------------

put("walkable", read("tests/fixtures/scenes/lyon_walkable_street.geojson"), "fixture")
sq = [[1842000, 5176000], [1842100, 5176000], [1842100, 5176100], [1842000, 5176100], [1842000, 5176000]]
hole = [[1842020, 5176020], [1842020, 5176040], [1842040, 5176040], [1842040, 5176020], [1842020, 5176020]]
put("walkable", json.dumps({"type": "Polygon", "coordinates": [sq, hole]}), "bare")
put("walkable", json.dumps({"type": "Feature", "geometry": {"type": "MultiPolygon",
                            "coordinates": [[sq], [[[x + 500, y] for x, y in sq]]]}}), "multi")
put("walkable", json.dumps({"type": "FeatureCollection", "features": [
    {"type": "Feature", "geometry": {"type": "Point", "coordinates": [1842000, 5176000]}}]}), "point")
