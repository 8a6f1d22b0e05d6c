"""vocc: virtual occluders for city models, from Python.

Bake city models (every format ``vocc bake`` reads, with the same reader options) into an
occluder store, read stores, and build a view cell's potentially visible set (PVS) from object
boxes, with the same library the ``vocc`` command line uses::

    import vocc
    store = vocc.bake(["buildings.geojson"], height_attr="HAUTEUR", cell_size=100)
    store.save("city.vocc")                      # atomic: the old file or the new one, never a part
    store = vocc.Store.open("city.vocc")
    cell = store.cell_at(1842000.0, 5176050.0)   # world coordinates; None outside the grid
    vos = store.vos(cell)                        # numpy arrays: a, b (n x 2), bottom, top, ...
    scene = vocc.scene_boxes(["buildings.geojson"], height_attr="HAUTEUR")  # boxes and ids
    visible = store.pvs(cell, scene)             # input feature numbers, ascending (vocc pvs's)

One numbering: a scene's objects are named by input feature number (their position among the
files' features, skipped ones included), as ``vocc pvs``, ``vocc info`` and ``vocc boxes`` name
them; ``scene.ids`` holds them beside ``scene.boxes``. ``Store.pvs`` over a ``SceneBoxes`` gives
these ids, and checks the scene against the one the store was baked from; over an engine's own
n x 6 array it gives positions in that array. Coordinates are world coordinates unless a name
says local (local = world - origin). Library
errors (a bad file, option or store) raise ``vocc.VoccError`` with the library's message; file
errors raise ``OSError``. The bake and scene loading release the GIL. Docs: docs/EMBEDDING.md.
"""

from __future__ import annotations

import os
import warnings
from typing import Callable, NamedTuple, Optional, Sequence, Tuple, Union

import numpy as np

from . import _vocc
from ._vocc import VoccError

__version__ = _vocc.__version__
__all__ = ["bake", "merge", "scene_boxes", "SceneBoxes", "Store", "BakedStore", "BoxTree", "VOs", "VoccError"]

PathLike = Union[str, "os.PathLike[str]"]
Progress = Callable[[int, int], object]


def _paths(paths: Union[PathLike, Sequence[PathLike]]) -> list:
    if isinstance(paths, (str, os.PathLike)):
        paths = [paths]
    return [os.fspath(p) for p in paths]


def _boxes_array(boxes) -> np.ndarray:
    a = np.ascontiguousarray(boxes, dtype=np.float64)
    if a.ndim != 2 or a.shape[1] != 6:
        raise ValueError(f"boxes must be an n x 6 array (xmin, ymin, zmin, xmax, ymax, zmax), got shape {a.shape}")
    return a


def _read(
    height_attr=None,
    base_attr=None,
    levels_attr=None,
    storey_height=3.0,
    lod=None,
    on_bad_height="skip",
    default_height=None,
    types=(),
    min_height_attr="min_height",
    min_levels_attr="building:min_level",
    crs=None,
) -> dict:
    """The reader options as the native module takes them (the CLI's reader flags)."""
    if isinstance(types, str):
        types = types.split(",")
    return {
        "height_attr": height_attr,
        "base_attr": base_attr,
        "levels_attr": levels_attr,
        "storey_height": float(storey_height),
        "lod": None if lod is None else str(lod),
        "on_bad_height": on_bad_height,
        "default_height": None if default_height is None else float(default_height),
        "types": [str(t) for t in types],
        "min_height_attr": min_height_attr,
        "min_levels_attr": min_levels_attr,
        "crs": crs,
    }


_READER_DOC = """
    Reader options, the ``vocc`` reader flags by the same names (README, "Reader flags"):
    ``height_attr``, ``base_attr``, ``levels_attr`` (attribute names), ``storey_height`` (metres
    per storey, default 3), ``lod`` (CityJSON and CityGML level of detail), ``on_bad_height``
    (``"skip"``, the default, or ``"error"``), ``default_height`` (metres, for features with no
    usable height), ``types`` (CityJSON city object types read besides buildings, a list or a
    comma-separated string), ``min_height_attr`` and ``min_levels_attr`` (the bottom of a part
    standing on others; defaults ``"min_height"`` and ``"building:min_level"``, None reads
    none), ``crs`` (``"EPSG:N"``, the metric CRS to put the scene in)."""


class SceneBoxes:
    """A scene's objects as an engine sees them: ``boxes`` (n x 6 float64: xmin, ymin, zmin,
    xmax, ymax, zmax, world coordinates, in object order) and beside them ``ids`` (n uint32: each
    object's input feature number, as ``vocc pvs``, ``vocc info`` and ``vocc boxes`` give it;
    skipped features keep their number, so ids may have gaps). ``objects``, ``fingerprint`` and
    ``crs`` identify the scene as a store's scene section does, and ``skipped`` counts the
    features the readers skipped. Usable wherever an n x 6 array is (``np.asarray(scene)``)."""

    def __init__(self, boxes: np.ndarray, ids: np.ndarray, facts: tuple):
        self.boxes = boxes
        self.ids = ids
        self.objects, self.fingerprint, self.crs, self.skipped = facts

    def __len__(self) -> int:
        return len(self.boxes)

    def __array__(self, dtype=None, copy=None):
        return self.boxes if dtype is None else self.boxes.astype(dtype)

    def _facts(self) -> tuple:
        return (self.objects, self.fingerprint, self.crs, self.skipped)


def scene_boxes(
    paths: Union[PathLike, Sequence[PathLike]],
    *,
    height_attr: Optional[str] = None,
    base_attr: Optional[str] = None,
    levels_attr: Optional[str] = None,
    storey_height: float = 3.0,
    lod: Optional[str] = None,
    on_bad_height: str = "skip",
    default_height: Optional[float] = None,
    types: Union[str, Sequence[str]] = (),
    min_height_attr: Optional[str] = "min_height",
    min_levels_attr: Optional[str] = "building:min_level",
    crs: Optional[str] = None,
) -> SceneBoxes:
    """Loads scene files, as ``vocc boxes`` does: a ``SceneBoxes`` with each object's box and,
    beside it, its input feature number. Give the reader options of the bake, so that the scene
    is the one baked (``Store.pvs`` checks it).
    """
    read = _read(height_attr, base_attr, levels_attr, storey_height, lod, on_bad_height,
                 default_height, types, min_height_attr, min_levels_attr, crs)
    raw, ids, facts = _vocc.scene_boxes(_paths(paths), read)
    return SceneBoxes(
        np.frombuffer(raw, dtype="<f8").reshape(-1, 6).copy(),
        np.frombuffer(ids, dtype="<u4").copy(),
        facts,
    )


scene_boxes.__doc__ += _READER_DOC


class VOs(NamedTuple):
    """A cell's virtual occluders, world coordinates, most effective first: VO k is the
    vertical quad over the segment ``a[k]``-``b[k]`` from height ``bottom[k]`` to ``top[k]``.
    ``level`` is its stored height level (0..32; 0..16 in a 1.0 store), ``grid`` its stored
    endpoint indices (x1, y1, x2, y2; n x 4) and ``exponents`` their exponents (e1, e2; n x 2,
    0..8; 0 in a 1.0 store): endpoint 1 is ``centre + (x1 - 256, y1 - 256) * quantum * 2**e1``
    of its cell (docs/FORMAT.md section 3)."""

    a: np.ndarray
    b: np.ndarray
    bottom: np.ndarray
    top: np.ndarray
    level: np.ndarray
    grid: np.ndarray
    exponents: np.ndarray


class BoxTree:
    """The box hierarchy over object boxes (a ``SceneBoxes``, or n x 6 world coordinates) for
    one store's frame. Build it once per scene and pass it to ``Store.pvs`` instead of the boxes
    to save the build on every query; built from a ``SceneBoxes``, it keeps the ids and the
    scene's facts."""

    def __init__(self, boxes, store: "Store"):
        self._origin = store.frame["origin"]
        self._scene = boxes if isinstance(boxes, SceneBoxes) else None
        array = boxes.boxes if self._scene is not None else boxes
        self._raw = _vocc.RawTree(_boxes_array(array), tuple(self._origin))

    def __len__(self) -> int:
        return len(self._raw)


class Store:
    """An occluder store (docs/FORMAT.md), checked whole when opened: version 2.0, or a 1.0
    store written before it (read the same way; it records no scene)."""

    def __init__(self, raw: "_vocc.RawStore"):
        self._raw = raw
        self._frame = raw.frame()

    @classmethod
    def open(cls, path: PathLike) -> "Store":
        """Reads and checks a store file."""
        with open(path, "rb") as f:
            data = f.read()
        try:
            return cls(_vocc.RawStore(data))
        except VoccError as e:
            raise VoccError(f"{os.fspath(path)}: {e}") from None

    @classmethod
    def from_bytes(cls, data: bytes) -> "Store":
        return cls(_vocc.RawStore(bytes(data)))

    def to_bytes(self) -> bytes:
        return self._raw.bytes()

    def save(self, path: PathLike) -> None:
        """Writes the store to ``path`` atomically (a temporary file in the same folder, then a
        rename): the path holds the old file or the new one in full."""
        _vocc.write_atomically(os.fspath(path), self._raw.bytes())

    @property
    def frame(self) -> dict:
        """The frame: origin, grid (min_x, min_y, cell_size, nx, ny; local), quantization and
        vertical frame (docs/FORMAT.md section 4)."""
        return dict(self._frame)

    @property
    def cell_count(self) -> int:
        return self._raw.cell_count()

    @property
    def version(self) -> Tuple[int, int]:
        """``(major, minor)`` of the store file: ``(2, 0)``, or ``(1, minor)`` for a 1.0 store."""
        return self._raw.version()

    @property
    def objects(self) -> int:
        """How many objects the store was baked for (its scene section); 0: not recorded."""
        return self._raw.scene()[0]

    @property
    def scene(self) -> int:
        """The fingerprint of the scene the store was baked from (opaque; docs/FORMAT.md
        section 5.2); 0: not recorded."""
        return self._raw.scene()[1]

    @property
    def crs(self) -> str:
        """The name of the scene's coordinate reference system; empty: unknown."""
        return self._raw.scene()[2]

    def cell_at(self, x: float, y: float, *, local: bool = False) -> Optional[int]:
        """The id of the cell holding world position (x, y) (local with ``local=True``), or None
        outside the grid."""
        if not local:
            ox, oy, _ = self._frame["origin"]
            x, y = x - ox, y - oy
        return self._raw.cell_at(float(x), float(y))

    def is_skipped(self, cell: int) -> bool:
        """Whether the cell lies inside a building (it has no VOs; everything stays visible)."""
        return self._raw.cell(cell)[0]

    def ground(self, cell: int) -> int:
        """The cell's stored ground level."""
        return self._raw.cell(cell)[1]

    def vos(self, cell: int) -> VOs:
        """The cell's VOs as numpy arrays, world coordinates."""
        _, _, geom, grid = self._raw.cell(cell)
        g = np.frombuffer(geom, dtype="<f8").reshape(-1, 6)
        q = np.frombuffer(grid, dtype="<u2").reshape(-1, 7)
        ox, oy, oz = self._frame["origin"]
        o2 = np.array([ox, oy])
        return VOs(
            a=g[:, 0:2] + o2,
            b=g[:, 2:4] + o2,
            bottom=g[:, 4] + oz,
            top=g[:, 5] + oz,
            level=q[:, 4].astype(np.uint8),
            grid=q[:, 0:4].copy(),
            exponents=q[:, 5:7].astype(np.uint8),
        )

    def tree(self, boxes) -> BoxTree:
        """A ``BoxTree`` over ``boxes`` (n x 6, world) in this store's frame."""
        return BoxTree(boxes, self)

    def check_scene(self, scene: "SceneBoxes", *, allow_other_scene: bool = False) -> None:
        """Checks that ``scene`` is the scene this store was baked from (its scene section:
        object count, fingerprint, CRS), as ``vocc pvs`` does: ``VoccError`` naming what differs
        and the likely cause (other reader options, another CRS, another file), or with
        ``allow_other_scene=True`` a warning. A 1.0 store records no scene: a warning says the
        check could not be made."""
        status, message = self._raw.check_scene(*scene._facts())
        if status == "not_recorded":
            warnings.warn(message, stacklevel=3)
        elif status == "differs":
            if not allow_other_scene:
                raise VoccError(
                    message + ". Give the files and reader options of the bake (or allow_other_scene=True)"
                )
            warnings.warn(message + "; its PVSs are not guaranteed", stacklevel=3)

    def pvs(
        self,
        cell: int,
        boxes: Union["SceneBoxes", np.ndarray, BoxTree],
        *,
        allow_other_scene: bool = False,
    ) -> np.ndarray:
        """The PVS of ``cell`` (uint32, ascending): the objects that no VO of the cell hides.
        ``boxes`` is a ``SceneBoxes`` (then the PVS holds their input feature numbers, the ids
        ``vocc pvs`` prints, and the scene is checked against the one baked: see
        ``check_scene``), an engine's own n x 6 array of world boxes (then the PVS holds
        positions in that array), or a ``BoxTree`` built for this store from either. A skipped
        cell or a cell without VOs keeps every box."""
        if not isinstance(boxes, BoxTree):
            boxes = BoxTree(boxes, self)
        elif tuple(boxes._origin) != tuple(self._frame["origin"]):
            raise ValueError("the BoxTree was built for a store with another origin")
        if boxes._scene is not None:
            self.check_scene(boxes._scene, allow_other_scene=allow_other_scene)
        positions = np.frombuffer(self._raw.pvs(int(cell), boxes._raw), dtype="<u4")
        if boxes._scene is not None:
            return boxes._scene.ids[positions]
        return positions.copy()


class BakedStore(Store):
    """A store fresh from ``bake``, with its ``.hashes`` bytes (for incremental rebakes with
    ``vocc bake --reuse``) and the bake's summary."""

    def __init__(self, raw: "_vocc.RawStore", hashes: bytes, summary: dict):
        super().__init__(raw)
        self.hashes = hashes
        self.summary = summary

    def save(self, path: PathLike, *, hashes: bool = True) -> None:
        """Writes the store atomically and, unless ``hashes=False``, ``PATH.hashes`` beside it
        as ``vocc bake`` does (the old hashes file is removed first and the new one written
        last, so a stop between the two never leaves a store with stale hashes)."""
        path = os.fspath(path)
        if hashes:
            try:
                os.remove(path + ".hashes")
            except FileNotFoundError:
                pass
        super().save(path)
        if hashes:
            _vocc.write_atomically(path + ".hashes", self.hashes)


def _tqdm_progress():
    try:
        from tqdm import tqdm  # type: ignore
    except ImportError:
        return None, None
    bar = tqdm(total=0, unit="cell", desc="bake")

    def update(done: int, total: int) -> None:
        if bar.total != total:
            bar.total = total
            bar.refresh()
        bar.update(done - bar.n)

    return update, bar


def bake(
    paths: Union[PathLike, Sequence[PathLike]],
    *,
    height_attr: Optional[str] = None,
    base_attr: Optional[str] = None,
    levels_attr: Optional[str] = None,
    storey_height: float = 3.0,
    lod: Optional[str] = None,
    on_bad_height: str = "skip",
    default_height: Optional[float] = None,
    types: Union[str, Sequence[str]] = (),
    min_height_attr: Optional[str] = "min_height",
    min_levels_attr: Optional[str] = "building:min_level",
    crs: Optional[str] = None,
    cell_size: float = 100.0,
    eye: tuple = (1.5, 2.0),
    slices: Optional[int] = None,
    max_vos: int = 10,
    region: Optional[tuple] = None,
    threads: Optional[int] = None,
    effort: str = "default",
    progress: Union[None, bool, Progress] = None,
    reach: Optional[float] = None,
) -> BakedStore:
    """Bakes scene files into an occluder store, as ``vocc bake`` does (same options, same
    bytes). ``region`` is a world rectangle ``(x0, y0, x1, y1)``: only the cells meeting it are
    baked. ``slices`` is 1..8, or None for automatic (5, or 8 in low-rise cells). ``effort`` is
    ``"fast"``, ``"default"`` or ``"tight"`` (``vocc bake --effort``). ``reach`` is how far past
    a cell's sides its own VOs are sought, metres, 100 to 5000, or None for automatic (``vocc
    bake --reach``: 900 in a compact or low-rise city, up to 1800 among free-standing towers or
    wide streets). ``threads`` defaults to every core.

    ``progress``: a callable ``progress(done, total)`` called from this thread as cells finish;
    None (the default) shows a tqdm bar when tqdm is installed; False shows nothing. The GIL is
    released while the bake runs. A KeyboardInterrupt (or an exception from the callback) is
    raised when the bake has finished: the bake itself cannot be stopped midway.

    ``BakedStore.summary`` holds the fields of ``vocc bake --json`` (in its words: the scene's
    ``convex_pieces``, ``blocker_objects``, ...), but the file names and the load time.
    """
    bar = None
    if progress is None:
        progress, bar = _tqdm_progress()
    elif progress is False or progress is True:
        progress, bar = _tqdm_progress() if progress else (None, None)
    try:
        read = _read(height_attr, base_attr, levels_attr, storey_height, lod, on_bad_height,
                     default_height, types, min_height_attr, min_levels_attr, crs)
        store, hashes, summary = _vocc.bake(
            _paths(paths),
            read,
            float(cell_size),
            (float(eye[0]), float(eye[1])),
            slices,
            int(max_vos),
            None if region is None else tuple(float(v) for v in region),
            threads,
            str(effort),
            progress,
            None if reach is None else float(reach),
        )
    finally:
        if bar is not None:
            bar.close()
    import json

    return BakedStore(_vocc.RawStore(store), hashes, json.loads(summary))


bake.__doc__ += _READER_DOC


def merge(shards: Sequence[PathLike]) -> BakedStore:
    """Merges the shards of one bake (``vocc bake --shard I/N``, each with its ``.hashes`` file
    beside it) into the store a single bake writes, as ``vocc merge`` does. Every index
    ``0..N`` must be given once, all from one bake; a broken rule raises ``VoccError`` naming
    it. The result's ``hashes`` serve ``vocc bake --reuse``; its ``summary`` holds ``shards``
    and ``cells_from`` (cells taken from each shard, in the order given)."""
    given = []
    for p in _paths(shards):
        with open(p, "rb") as f:
            store = f.read()
        with open(p + ".hashes", "rb") as f:
            hashes = f.read()
        given.append((store, hashes))
    store, hashes, count, cells_from = _vocc.merge_shards(given)
    summary = {"shards": count, "cells_from": list(cells_from)}
    return BakedStore(_vocc.RawStore(store), hashes, summary)
