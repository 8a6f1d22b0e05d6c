"""The Python package against the vocc command line on the bundled Lyon data: a bake gives the
CLI's bytes, a saved store reopens to the same bytes, the PVS equals `vocc pvs --json`, the VOs
equal `vocc inspect --cell --json`, errors carry the library's message, the bake releases the GIL
and reports progress. The CLI binary is $VOCC_BIN (default: target/debug/vocc of this checkout).

A 300 m square of Lyon is baked (the cells around the README's sample cell) to keep the test
short; the region is the same for the CLI and for Python.
"""

import json
import os
import subprocess
import threading
import time
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
