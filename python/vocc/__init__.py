"""vocc: virtual occluders for city models, from Python.

Bake city models (GeoJSON footprints with heights, CityJSON, OBJ) into an occluder store, read
stores, and build a view cell's potentially visible set (PVS) from object boxes, with the same
library the ``vocc`` command line uses::

    import vocc
    store = vocc.bake(["buildings.geojson"], height_attr="HAUTEUR", cell_size=100)
    store.save("city.vocc")                      # atomic: the old file or the new one, never a part
    store = vocc.Store.open("city.vocc")
    cell = store.cell_at(1842000.0, 5176050.0)   # world coordinates; None outside the grid
    vos = store.vos(cell)                        # numpy arrays: a, b (n x 2), bottom, top, ...
    boxes = vocc.scene_boxes(["buildings.geojson"], height_attr="HAUTEUR")  # n x 6, world
    visible = store.pvs(cell, boxes)             # numpy uint32 object indices, ascending

Coordinates are world coordinates unless a name says local (local = world - origin). Library
errors (a bad file, option or store) raise ``vocc.VoccError`` with the library's message; file
errors raise ``OSError``. The bake and scene loading release the GIL. Docs: docs/EMBEDDING.md.
"""

from __future__ import annotations

import os
from typing import Callable, NamedTuple, Optional, Sequence, Tuple, Union

import numpy as np

from . import _vocc
from ._vocc import VoccError

__version__ = _vocc.__version__
__all__ = ["bake", "scene_boxes", "Store", "BakedStore", "BoxTree", "VOs", "VoccError"]

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


def scene_boxes(
    paths: Union[PathLike, Sequence[PathLike]],
    *,
    height_attr: Optional[str] = None,
    base_attr: Optional[str] = None,
    levels_attr: Optional[str] = None,
    storey_height: float = 3.0,
    lod: Optional[str] = None,
) -> np.ndarray:
    """The bounding boxes of a scene's objects: an n x 6 float64 array (xmin, ymin, zmin, xmax,
    ymax, zmax; world coordinates), in object order, the order PVS indices refer to."""
    raw = _vocc.scene_boxes(_paths(paths), height_attr, base_attr, levels_attr, storey_height, lod)
    return np.frombuffer(raw, dtype="<f8").reshape(-1, 6).copy()


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
    """The box hierarchy over object boxes (n x 6, world coordinates) for one store's frame.
    Build it once per scene and pass it to ``Store.pvs`` instead of the array to save the build
    on every query."""

    def __init__(self, boxes, store: "Store"):
        self._origin = store.frame["origin"]
        self._raw = _vocc.RawTree(_boxes_array(boxes), tuple(self._origin))

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

    def pvs(self, cell: int, boxes: Union[np.ndarray, BoxTree]) -> np.ndarray:
        """The PVS of ``cell``: the ascending indices (uint32) of the boxes that no VO of the cell
        hides. ``boxes`` is an n x 6 array of world boxes, or a ``BoxTree`` built for this
        store. A skipped cell or a cell without VOs keeps every box."""
        if not isinstance(boxes, BoxTree):
            boxes = BoxTree(boxes, self)
        elif tuple(boxes._origin) != tuple(self._frame["origin"]):
            raise ValueError("the BoxTree was built for a store with another origin")
        return np.frombuffer(self._raw.pvs(int(cell), boxes._raw), dtype="<u4").copy()


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
    cell_size: float = 100.0,
    eye: tuple = (1.5, 2.0),
    slices: Optional[int] = None,
    max_vos: int = 10,
    region: Optional[tuple] = None,
    threads: Optional[int] = None,
    effort: str = "default",
    progress: Union[None, bool, Progress] = None,
) -> BakedStore:
    """Bakes scene files into an occluder store, as ``vocc bake`` does (same options, same
    bytes). ``region`` is a world rectangle ``(x0, y0, x1, y1)``: only the cells meeting it are
    baked. ``slices`` is 1..5, or None for automatic. ``effort`` is ``"fast"``, ``"default"`` or
    ``"tight"`` (``vocc bake --effort``). ``threads`` defaults to every core.

    ``progress``: a callable ``progress(done, total)`` called from this thread as cells finish;
    None (the default) shows a tqdm bar when tqdm is installed; False shows nothing. The GIL is
    released while the bake runs. A KeyboardInterrupt (or an exception from the callback) is
    raised when the bake has finished: the bake itself cannot be stopped midway.
    """
    bar = None
    if progress is None:
        progress, bar = _tqdm_progress()
    elif progress is False or progress is True:
        progress, bar = _tqdm_progress() if progress else (None, None)
    try:
        store, hashes, summary = _vocc.bake(
            _paths(paths),
            height_attr,
            base_attr,
            levels_attr,
            storey_height,
            lod,
            float(cell_size),
            (float(eye[0]), float(eye[1])),
            slices,
            int(max_vos),
            None if region is None else tuple(float(v) for v in region),
            threads,
            str(effort),
            progress,
        )
    finally:
        if bar is not None:
            bar.close()
    import json

    return BakedStore(_vocc.RawStore(store), hashes, json.loads(summary))
