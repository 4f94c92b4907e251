"""Input checks shared by the grid helpers.

Every public function in :mod:`swarm.grid` is called with arrays built by the runtime or by an algorithm;
a wrong shape or an out-of-map cell is a programming error that should fail loudly with the field, the
value and what is allowed (:class:`swarm.base.errors.InvalidInput`) rather than as an IndexError deep inside a
numba kernel.
"""

from __future__ import annotations

import math
import weakref
from typing import Any

import numpy as np

from swarm.base.errors import InvalidInput

from swarm.base.types import SOLID


_VOUCHED: weakref.WeakValueDictionary[int, np.ndarray] = weakref.WeakValueDictionary()


def vouch_known(view: np.ndarray, *, trusted: bool = False) -> np.ndarray:
    """Mark ``view`` as a map whose values its owner keeps in {UNSEEN, FREE, SOLID}, so :func:`check_known`
    does not scan it again on every call. For the runtime's read-only per-robot views: the runtime writes
    only those values into the maps behind them (the lidar writes FREE / SOLID, merges take the maximum with
    decoded cells already checked), and an algorithm cannot write through a read-only view. The benchmark's
    target searches scanned the whole map once per call for this (1.4 % of the run). The view is checked
    once here; the mark lasts as long as this very object (a copy or a new view is checked as usual).
    ``trusted=True``: the owner made the values behind ``view`` itself (memory it has just allocated as zeros,
    or a copy of maps it keeps), so they are not scanned (10,000 new maps of 4000 x 4000 cells took 70 % of a
    swarm's set-up to scan)."""
    if trusted:
        if (not isinstance(view, np.ndarray) or view.ndim != 2 or view.size == 0 or view.dtype != np.uint8
                or view.flags.writeable):
            raise InvalidInput("view", f"array {getattr(view, 'dtype', type(view).__name__)}"
                               f"{list(getattr(view, 'shape', ()))}", "a read-only uint8[H, W] view of the owner's values")
        arr = view
    else:
        arr = check_known(view)
    if arr is not view or arr.flags.writeable or arr.dtype != np.uint8:
        raise InvalidInput("view", f"array {arr.dtype}{list(arr.shape)} writeable={arr.flags.writeable}",
                           "a read-only uint8 ndarray view of a runtime-owned map")
    _VOUCHED[id(view)] = view
    return view


def check_known(known: Any, field: str = "known") -> np.ndarray:
    """A knowledge map: 2-D integer array with values in {UNSEEN, FREE, SOLID}."""
    if _VOUCHED.get(id(known)) is known and not known.flags.writeable:  # the runtime's view (vouch_known)
        return known
    arr = np.asarray(known)
    if arr.ndim != 2 or arr.size == 0 or not np.issubdtype(arr.dtype, np.integer):
        raise InvalidInput(field, f"array {arr.dtype}{list(arr.shape)}",
                           "a non-empty 2-D integer array (uint8 UNSEEN=0 / FREE=1 / SOLID=2)")
    if arr.max() > SOLID or (arr.dtype.kind == "i" and arr.min() < 0):  # unsigned maps cannot go below 0
        raise InvalidInput(field, f"values in [{arr.min()}, {arr.max()}]", "cell values 0, 1 or 2")
    return arr


def check_space(space: Any, field: str = "space") -> np.ndarray:
    """A boolean 2-D mask (configuration space, targets, exclude)."""
    arr = np.asarray(space)
    if arr.ndim != 2 or arr.size == 0 or arr.dtype != np.bool_:
        raise InvalidInput(field, f"array {arr.dtype}{list(arr.shape)}", "a non-empty 2-D bool array")
    return arr


def check_same_shape(arr: np.ndarray, shape: tuple[int, ...], field: str) -> None:
    if arr.shape != shape:
        raise InvalidInput(field, f"shape {list(arr.shape)}", f"the grid's shape {list(shape)}")


def check_cell(cell: Any, shape: tuple[int, ...], field: str) -> tuple[int, int]:
    """A (row, col) pair of integers inside the grid."""
    try:
        row, col = cell
        if isinstance(row, (bool, np.bool_)) or isinstance(col, (bool, np.bool_)):
            raise TypeError
        r, c = int(row), int(col)
        if r != row or c != col:
            raise TypeError
    except (TypeError, ValueError):
        raise InvalidInput(field, cell, "a (row, col) pair of integers") from None
    if not (0 <= r < shape[0] and 0 <= c < shape[1]):
        raise InvalidInput(field, cell, f"a cell with 0 <= row < {shape[0]} and 0 <= col < {shape[1]}")
    return r, c


def check_cells(cells: Any, shape: tuple[int, ...], field: str) -> np.ndarray:
    """One (row, col) pair or an int[K, 2] array of them, all inside the grid; returns int64[K, 2]."""
    arr = np.asarray(cells)
    if arr.ndim == 1 and arr.shape == (2,):
        arr = arr.reshape(1, 2)
    if arr.ndim != 2 or arr.shape[1] != 2 or arr.shape[0] == 0 or not (
            np.issubdtype(arr.dtype, np.integer) and arr.dtype != np.bool_):
        raise InvalidInput(field, f"array {arr.dtype}{list(arr.shape)}",
                           "a (row, col) pair or a non-empty int[K, 2] array of cells")
    arr = arr.astype(np.int64, copy=False)
    if arr.min() < 0 or arr[:, 0].max() >= shape[0] or arr[:, 1].max() >= shape[1]:  # (no boolean temporaries)
        raise InvalidInput(field, arr.tolist(), f"cells with 0 <= row < {shape[0]} and 0 <= col < {shape[1]}")
    return arr


def check_length(value: Any, field: str, allow_none: bool = False) -> float | None:
    """A finite, non-negative length in metres (or None where allowed)."""
    if value is None and allow_none:
        return None
    try:
        v = float(value)
    except (TypeError, ValueError):
        v = math.nan
    if isinstance(value, bool) or not math.isfinite(v) or v < 0:
        extra = " or None" if allow_none else ""
        raise InvalidInput(field, value, f"a finite number >= 0 (metres){extra}")
    return v


def check_count(value: Any, field: str, minimum: int, allow_none: bool = False) -> int | None:
    """An integer >= ``minimum`` (or None where allowed)."""
    if value is None and allow_none:
        return None
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or value < minimum:
        extra = " or None" if allow_none else ""
        raise InvalidInput(field, value, f"an integer >= {minimum}{extra}")
    return int(value)
