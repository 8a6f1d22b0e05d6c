"""The Python package against the vocc command line on the bundled Lyon data: a bake gives the
CLI's bytes, a saved store reopens to the same bytes, the PVS equals `vocc pvs --json` (input
feature numbers, ids beside the boxes as `vocc boxes` writes them), the reader options are the
CLI's, a scene that is not the one baked is refused, the VOs equal `vocc inspect --cell --json`,
errors carry the library's message, the bake releases the GIL and reports progress. The CLI binary is $VOCC_BIN (default: target/debug/vocc of this checkout).

A 300 m square of Lyon is baked (the cells around the README's sample cell) to keep the test
short; the region is the same for the CLI and for Python.
"""

import json
import os
import subprocess
import threading
import time
import warnings
from pathlib import Path

import numpy as np
import pytest

import vocc

ROOT = Path(__file__).resolve().parents[2]
LYON = ROOT / "data" / "lyon1" / "buildings_lyon1.geojson"
VOCC = os.environ.get("VOCC_BIN", str(ROOT / "target" / "debug" / "vocc"))
REGION = (1841850.0, 5175900.0, 1842150.0, 5176200.0)
REGION_ARG = ",".join(str(v) for v in REGION)
# One cell's worth, for the tests that only need a bake to run.
SMALL = (1842010.0, 5176010.0, 1842090.0, 5176090.0)


def cli(*args: str) -> str:
    return subprocess.run([VOCC, *args], check=True, capture_output=True, text=True).stdout


@pytest.fixture(scope="module")
def baked(tmp_path_factory):
    calls = []
    store = vocc.bake([LYON], height_attr="HAUTEUR", region=REGION, progress=lambda d, t: calls.append((d, t)))
    out = tmp_path_factory.mktemp("cli") / "lyon.vocc"
    cli("bake", str(LYON), "--height-attr", "HAUTEUR", "--region", REGION_ARG, "-o", str(out))
    return store, calls, out


@pytest.fixture(scope="module")
def boxes():
    return vocc.scene_boxes(LYON, height_attr="HAUTEUR")


def test_bake_gives_the_cli_bytes_and_reports_progress(baked):
    store, calls, cli_store = baked
    assert store.to_bytes() == cli_store.read_bytes()
    assert store.hashes == Path(str(cli_store) + ".hashes").read_bytes()
    s = store.summary
    assert s["cells_selected"] == s["cells_baked"] > 0
    assert s["store_bytes"] == len(store.to_bytes())
    assert calls, "the progress callback was never called"
    total = calls[-1][1]
    assert total == s["cells_baked"]
    assert calls[-1] == (total, total)
    assert [d for d, _ in calls] == sorted(d for d, _ in calls)


def test_save_is_atomic_and_reopens_to_the_same_store(baked, tmp_path):
    store, _, _ = baked
    path = tmp_path / "lyon.vocc"
    path.write_bytes(b"old contents")
    store.save(path)
    assert path.read_bytes() == store.to_bytes()
    assert Path(str(path) + ".hashes").read_bytes() == store.hashes
    assert sorted(p.name for p in tmp_path.iterdir()) == ["lyon.vocc", "lyon.vocc.hashes"]
    again = vocc.Store.open(path)
    assert again.to_bytes() == store.to_bytes()
    assert again.frame == store.frame
    assert again.cell_count == store.frame["nx"] * store.frame["ny"]
    # A folder that does not exist: OSError, and nothing written anywhere.
    with pytest.raises(OSError, match="cannot write"):
        store.save(tmp_path / "missing" / "x.vocc")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["lyon.vocc", "lyon.vocc.hashes"]


def cells_with_vos(store):
    return [c for c in range(store.cell_count) if len(store.vos(c).top) > 0]


def test_pvs_equals_the_cli(baked, boxes):
    store, _, cli_store = baked
    cells = cells_with_vos(store)
    assert len(cells) >= 3, "the region must give cells with VOs"
    tree = store.tree(boxes)
    assert len(tree) == len(boxes) == 2576
    culled = 0
    for cell in cells[:6]:
        want = json.loads(cli(
            "pvs", str(cli_store), str(LYON), "--height-attr", "HAUTEUR", "--cell", str(cell), "--json"
        ))
        got = store.pvs(cell, boxes)
        assert got.dtype == np.uint32
        assert got.tolist() == want["pvs"], f"cell {cell}"
        assert store.pvs(cell, tree).tolist() == want["pvs"]
        culled += len(boxes) - len(got)
    assert culled > 0, "no compared cell culls anything: the comparison proves nothing"
    # A cell outside the region has no VOs: everything is kept.
    empty = next(c for c in range(store.cell_count) if len(store.vos(c).top) == 0 and not store.is_skipped(c))
    assert store.pvs(empty, tree).tolist() == list(range(len(boxes)))


def test_vos_and_cell_at_equal_the_cli(baked):
    store, _, cli_store = baked
    x, y = 1842000.0, 5176050.0
    cell = store.cell_at(x, y)
    assert cell is not None
    ox, oy, _ = store.frame["origin"]
    assert store.cell_at(x - ox, y - oy, local=True) == cell
    assert store.cell_at(-1e9, 0.0) is None
    assert store.cell_at(float("nan"), y) is None
    for c in [cell] + cells_with_vos(store)[:3]:
        want = json.loads(cli("inspect", str(cli_store), "--cell", str(c), "--json"))
        v = store.vos(c)
        assert v.a.shape == (len(want["vos"]), 2) and v.top.shape == (len(want["vos"]),)
        assert v.a.tolist() == [w["a"] for w in want["vos"]]
        assert v.b.tolist() == [w["b"] for w in want["vos"]]
        assert v.bottom.tolist() == [w["bottom"] for w in want["vos"]]
        assert v.top.tolist() == [w["top"] for w in want["vos"]]
        assert v.level.tolist() == [w["level"] for w in want["vos"]]
        assert v.grid.tolist() == [
            [w["fields"]["a"]["x"], w["fields"]["a"]["y"], w["fields"]["b"]["x"], w["fields"]["b"]["y"]]
            for w in want["vos"]
        ]
        assert v.exponents.tolist() == [[w["fields"]["a"]["e"], w["fields"]["b"]["e"]] for w in want["vos"]]
        assert store.is_skipped(c) == want["skipped"]


def test_the_store_records_its_version_and_scene(baked):
    store, _, cli_store = baked
    want = json.loads(cli("inspect", str(cli_store), "--json"))
    assert want["version"] == "2.0"
    assert store.version == (2, 0)
    assert store.objects == want["objects"] == 2576
    assert store.scene == int(want["scene"], 16) != 0
    assert store.crs == want["crs"] == "EPSG:3946"


def doc_hex(name):
    """The bytes of a ```hex example:NAME block of docs/FORMAT.md."""
    text = (ROOT / "docs" / "FORMAT.md").read_text()
    block = text.split("```hex example:" + name + "\n", 1)[1].split("```", 1)[0]
    return bytes.fromhex("".join(line.split("#")[0].split(":", 1)[1] for line in block.splitlines()))


def test_1_0_and_2_0_stores_read_alike():
    # FORMAT.md's 2.0 example (a far VO with exponents 3, a level of 20, a CRS name) and its 1.0
    # example (5-byte VOs, no scene section): cell 0's first VO is the same wall in both.
    new = vocc.Store.from_bytes(doc_hex("store"))
    old = vocc.Store.from_bytes(doc_hex("store-1.0"))
    assert (new.version, new.objects, new.scene, new.crs) == ((2, 0), 2576, 0x9E3779B97F4A7C15, "EPSG:2154")
    assert (old.version, old.objects, old.scene, old.crs) == ((1, 0), 0, 0, "")
    assert old.frame == new.frame
    v, w = new.vos(0), old.vos(0)
    assert v.a[0].tolist() == w.a[0].tolist() == [843020.0, 6518110.0]
    assert v.level.tolist() == [5, 20, 16] and w.level.tolist() == [5, 3]
    assert v.exponents.tolist() == [[0, 0], [3, 3], [0, 2]]
    assert w.exponents.tolist() == [[0, 0], [0, 0]]
    assert v.grid[1].tolist() == [194, 406, 344, 406]
    assert v.a[1].tolist() == [843000.0 - 198.0, 6518000.0 + 650.0]
    assert old.is_skipped(1) and new.is_skipped(1)


def test_errors_carry_the_library_message(tmp_path, baked):
    store, _, _ = baked
    bad = tmp_path / "bad.vocc"
    bad.write_bytes(b"\x89VOCC\r\n\x1a" + bytes(200))
    with pytest.raises(vocc.VoccError, match="bad.vocc: unsupported major version 0"):
        vocc.Store.open(bad)
    with pytest.raises(vocc.VoccError, match=r"truncated: 136 bytes needed, 3 given"):
        vocc.Store.from_bytes(b"abc")
    with pytest.raises(OSError):
        vocc.Store.open(tmp_path / "missing.vocc")
    with pytest.raises(vocc.VoccError, match="missing.geojson"):
        vocc.bake([tmp_path / "missing.geojson"], height_attr="HAUTEUR", progress=False)
    with pytest.raises(vocc.VoccError, match=r"cell size must be .*, got -1"):
        vocc.bake([LYON], height_attr="HAUTEUR", cell_size=-1, progress=False)
    with pytest.raises(vocc.VoccError, match=r"--reach must be 100 to 5000 m, got 50"):
        vocc.bake([LYON], height_attr="HAUTEUR", reach=50, progress=False)
    with pytest.raises(vocc.VoccError, match="HAUTEUR_X"):
        vocc.bake([LYON], height_attr="HAUTEUR_X", progress=False)
    with pytest.raises(vocc.VoccError, match="outside the grid"):
        store.vos(store.cell_count)
    with pytest.raises(ValueError, match="n x 6"):
        store.pvs(0, np.zeros((3, 5)))
    with pytest.raises(ZeroDivisionError):
        vocc.bake([LYON], height_attr="HAUTEUR", region=SMALL, progress=lambda d, t: 1 / 0)


def test_the_bake_releases_the_gil():
    ticks = 0
    stop = threading.Event()

    def count():
        nonlocal ticks
        while not stop.is_set():
            ticks += 1
            time.sleep(0.001)

    t = threading.Thread(target=count)
    t.start()
    start = time.monotonic()
    try:
        vocc.bake([LYON], height_attr="HAUTEUR", region=SMALL, progress=False)
    finally:
        stop.set()
        t.join()
    elapsed = time.monotonic() - start
    # With the GIL held for the whole bake the counter would stand still; released, it ticks
    # about once a millisecond (at least a few times per 50 ms on a loaded machine).
    assert ticks >= max(5, elapsed * 20), f"{ticks} ticks in {elapsed:.2f} s"


def cli_boxes(out, path, *flags):
    """`vocc boxes` of a scene into the file `out`: (ids, boxes, the "# scene" line)."""
    subprocess.run([VOCC, "boxes", str(path), *flags, "-o", str(out)], check=True, capture_output=True)
    lines = out.read_text().splitlines()
    rows = [[float(v) for v in l.split()] for l in lines if not l.startswith("#")]
    scene = next(l for l in lines if l.startswith("# scene "))
    return [int(r[0]) for r in rows], [r[1:] for r in rows], scene


def test_three_numberings_pvs_gives_input_feature_numbers_with_ids_beside_the_boxes(tmp_path):
    # Issue 33, defect 2: scene_boxes and Store.pvs gave positions among loaded objects while
    # vocc pvs gives input feature numbers. With --base-attr Z_MIN_SOL five Lyon features are
    # skipped (feature 13 first): the ids skip them, as vocc boxes's do, and the PVS is vocc pvs's.
    flags = dict(height_attr="HAUTEUR", base_attr="Z_MIN_SOL")
    scene = vocc.scene_boxes(LYON, **flags)
    assert len(scene) == scene.objects == 2571 and scene.skipped == 5
    assert 13 not in scene.ids.tolist() and scene.ids[-1] == 2575
    ids, boxes, line = cli_boxes(tmp_path / "lyon.boxes", LYON, "--height-attr", "HAUTEUR", "--base-attr", "Z_MIN_SOL")
    assert scene.ids.tolist() == ids
    assert scene.boxes.tolist() == boxes
    assert line.startswith(f"# scene {scene.fingerprint:016x} objects 2571 crs \"EPSG:3946\"")
    store = vocc.bake([LYON], region=SMALL, progress=False, **flags)
    path = tmp_path / "base.vocc"
    store.save(path)
    cell = store.cell_at(1842050.0, 5176050.0)
    want = json.loads(cli(
        "pvs", str(path), str(LYON), "--height-attr", "HAUTEUR", "--base-attr", "Z_MIN_SOL",
        "--cell", str(cell), "--json",
    ))
    got = store.pvs(cell, scene)
    assert got.tolist() == want["pvs"] and len(got) < 2571
    assert store.pvs(cell, store.tree(scene)).tolist() == want["pvs"]
    # An engine's own array: positions in it.
    assert scene.ids[store.pvs(cell, scene.boxes)].tolist() == want["pvs"]


ROW = {
    "type": "FeatureCollection",
    "crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::3946"}},
    "features": [
        {"type": "Feature", "properties": {"h": None},
         "geometry": {"type": "Polygon", "coordinates": [[[1842000, 5176000], [1842010, 5176000], [1842010, 5176010], [1842000, 5176010], [1842000, 5176000]]]}},
        {"type": "Feature", "properties": {"h": "tall"},
         "geometry": {"type": "Polygon", "coordinates": [[[1842020, 5176000], [1842030, 5176000], [1842030, 5176010], [1842020, 5176010], [1842020, 5176000]]]}},
        {"type": "Feature", "properties": {"h": None, "levels": 4},
         "geometry": {"type": "Polygon", "coordinates": [[[1842040, 5176000], [1842050, 5176000], [1842050, 5176010], [1842040, 5176010], [1842040, 5176000]]]}},
        {"type": "Feature", "properties": {"h": 9},
         "geometry": {"type": "Polygon", "coordinates": [[[1842060, 5176000], [1842070, 5176000], [1842070, 5176010], [1842060, 5176010], [1842060, 5176000]]]}},
    ],
}

BRIDGE = {
    "type": "CityJSON", "version": "2.0", "transform": {"scale": [1, 1, 1], "translate": [0, 0, 0]},
    "vertices": [[0, 0, 0], [10, 0, 0], [10, 10, 0], [0, 10, 0], [0, 0, 8], [10, 0, 8], [10, 10, 8], [0, 10, 8]],
    "CityObjects": {
        t: {"type": t, "geometry": [{"type": "Solid", "lod": "1", "boundaries": [[
            [[0, 3, 2, 1]], [[4, 5, 6, 7]], [[0, 1, 5, 4]], [[1, 2, 6, 5]], [[2, 3, 7, 6]], [[3, 0, 4, 7]]]]}]}
        for t in ["Building", "Bridge"]
    },
}


def test_reader_options_are_the_clis_default_height_on_bad_height_types_levels_attr(tmp_path):
    # Issue 33, defect 3: Python lacked the reader options its docs promised ("same options,
    # same bytes"). Each gives what the same CLI flag gives.
    row = tmp_path / "row.geojson"
    row.write_text(json.dumps(ROW))
    flags = ["--height-attr", "h", "--levels-attr", "levels", "--default-height", "5"]
    opts = dict(height_attr="h", levels_attr="levels", default_height=5)
    scene = vocc.scene_boxes(row, **opts)
    out = tmp_path / "row.boxes"
    ids, boxes, line = cli_boxes(out, row, *flags)
    assert scene.ids.tolist() == ids == [0, 1, 2, 3]
    assert scene.boxes.tolist() == boxes
    assert [b[5] for b in boxes] == [5.0, 5.0, 12.0, 9.0]
    assert line == f'# scene {scene.fingerprint:016x} objects 4 crs "EPSG:3946"'
    # Without the fallbacks, features 0 and 1 are skipped and the ids say so.
    assert vocc.scene_boxes(row, height_attr="h", levels_attr="levels").ids.tolist() == [2, 3]
    with pytest.raises(vocc.VoccError, match=r'"tall", which is not a number'):
        vocc.scene_boxes(row, on_bad_height="error", **opts)
    with pytest.raises(vocc.VoccError, match="on_bad_height must be"):
        vocc.scene_boxes(row, on_bad_height="maybe", **opts)
    with pytest.raises(vocc.VoccError, match="storey_height must be a number greater than 0"):
        vocc.scene_boxes(row, storey_height=-3, **opts)
    # --crs: the scene projected, as the CLI's.
    projected = vocc.scene_boxes(row, crs="EPSG:2154", **opts)
    assert projected.crs == "EPSG:2154"
    assert projected.boxes.tolist() == cli_boxes(out, row, *flags, "--crs", "EPSG:2154")[1]
    # --types: a CityJSON Bridge is read only when asked for.
    city = tmp_path / "bridge.city.json"
    city.write_text(json.dumps(BRIDGE))
    assert len(vocc.scene_boxes(city)) == 1
    both = vocc.scene_boxes(city, types=["Bridge"])
    assert both.ids.tolist() == cli_boxes(out, city, "--types", "Bridge")[0] == [0, 1]
    assert vocc.scene_boxes(city, types="Bridge").ids.tolist() == [0, 1]
    # The bake with the same options gives the CLI's bytes.
    store = tmp_path / "row.vocc"
    cli("bake", str(row), *flags, "--cell-size", "50", "-o", str(store))
    assert vocc.bake(row, cell_size=50, progress=False, **opts).to_bytes() == store.read_bytes()


def test_pvs_with_another_scene_is_refused_naming_what_differs(baked):
    # Issue 33, defect 4: Python's PVS with a scene that is not the one baked answered silently.
    store, _, _ = baked
    other = vocc.scene_boxes(LYON, height_attr="HAUTEUR", base_attr="Z_MIN_SOL")
    cell = store.cell_at(1842000.0, 5176050.0)
    with pytest.raises(vocc.VoccError, match=r"2571 objects where 2576 were baked, fingerprint .*; likely other reader flags: 5 features were skipped here"):
        store.pvs(cell, other)
    with pytest.warns(UserWarning, match="not the one the store was baked from"):
        store.pvs(cell, other, allow_other_scene=True)
    # A 1.0 store records no scene: a warning says the check could not be made.
    old = vocc.Store.from_bytes(doc_hex("store-1.0"))
    with pytest.warns(UserWarning, match=r"records no scene, so whether .* could not be checked"):
        old.pvs(0, other)
    # The same scene: no warning.
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        store.pvs(cell, vocc.scene_boxes(LYON, height_attr="HAUTEUR"))


def test_bake_summary_counts_convex_pieces_and_blocker_objects_as_info_does(baked):
    # Issue 33, defect 8: the bake's summary called convex pieces "blockers" while info counts
    # objects; one vocabulary now.
    store, _, _ = baked
    info = json.loads(cli("info", str(LYON), "--height-attr", "HAUTEUR", "--json"))
    sc = store.summary["scene"]
    assert "blockers" not in sc and "no_blocker" not in sc
    assert sc["convex_pieces"] == info["convex_pieces"]
    assert sc["blocker_objects"] == info["blocker_objects"]
    assert sc["no_blocker_objects"] == info["no_blocker_objects"]


def test_merge_of_cli_shards_gives_the_single_bake(tmp_path):
    """`vocc.merge` is the library's merge (`vocc::bake::merge`): two shards baked by the CLI
    merge into the CLI's single bake, byte for byte, hashes included; a missing shard is refused
    by name."""
    region = ["--height-attr", "HAUTEUR", "--region", REGION_ARG, "--effort", "fast"]
    whole = tmp_path / "whole.vocc"
    cli("bake", str(LYON), *region, "-o", str(whole))
    shards = []
    for i in range(2):
        p = tmp_path / f"sh{i}.vocc"
        cli("bake", str(LYON), *region, "--shard", f"{i}/2", "-o", str(p))
        shards.append(p)
    merged = vocc.merge(shards[::-1])
    assert merged.to_bytes() == whole.read_bytes()
    assert merged.hashes == (tmp_path / "whole.vocc.hashes").read_bytes()
    assert merged.summary["shards"] == 2
    with pytest.raises(vocc.VoccError, match="1 of 2 shards are missing: 1/2"):
        vocc.merge(shards[:1])
