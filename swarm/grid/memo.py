"""The plan to a far target, read off the target search that found it.

When the nearest unknown is far, :func:`swarm.grid.nearest_reachable_unseen` runs an exact search over
the whole map from the robot to the nearest view cell, and in the same tick the navigator plans from the
robot to that cell on the same map: the same search again (how often, and its cost:
docs/performance-history.md).
Both are :func:`swarm.grid._kernels.grid_bucket_search` from the same seed on the same configuration
space, and both stop at the start of the target's distance bucket (the target search when the bucket
holds a target, the plan when the goal's distance is final, which happens at that same bucket). So their
distance fields are identical, and the path read back from the target search's field is exactly the path
:func:`swarm.grid.plan` returns.

The target search therefore remembers, per thread, its map, configuration space, snapped start, target and
that path; the navigator takes the path when its own map is equal byte for byte, its snapped start and
goal are the same cells and it plans with the exact grid planner. Anything else plans afresh.

The map and the space are not copied: they are the search's kept inputs (:mod:`swarm.grid.kept`), which
the next search on that map brings up to date in place. An entry therefore also remembers the inputs'
``version`` and is recalled only while it is unchanged.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from typing import NamedTuple

import numpy as np

from swarm.knowledge.packed import same_as_packed

MAX_ENTRIES = 128
"""Searches remembered per thread: one or two per robot of a team of up to 64 (see
:data:`swarm.grid.kept.MAX_ENTRIES`). Each refers to its search's kept map and space (no copies of its own),
and all are of one map size (a new size clears them)."""

MAX_BYTES = 1 << 27
"""...and at most this much of kept inputs held through them (128 MB): each holds its search's kept map copy
and space bits alive, 6 MB on a 2,000-tile building, where a 10,000-robot swarm never recalls a plan anyway.
Maps of 600 x 600 cells keep all 128."""

Params = tuple[float, float, bool]
"""(radius_m, margin_m, unseen_traversable): what the configuration space was built with."""


class SearchPlan(NamedTuple):
    known: np.ndarray        # the map searched: the kept 2-bit copy (swarm.grid.kept), valid while version holds
    space_bits: np.ndarray   # its configuration space: the kept bits of the padded grid (swarm.grid.kept)
    shape: tuple[int, int]   # the map's size
    start: tuple[int, int]   # the snapped start the search ran from
    goal: tuple[int, int]    # the target it found
    path: np.ndarray         # int64[N, 2] from start to goal, as swarm.grid.plan gives it
    version: np.ndarray      # the kept inputs' version counter (int64[1])
    seen: int                # its value when the search ran

    @property
    def space(self) -> np.ndarray:
        """The configuration space searched, bool[H, W], read-only; unpacked on each call (the navigator
        reads it once per recalled plan)."""
        h, w = self.shape
        pad = np.unpackbits(self.space_bits, count=(h + 2) * (w + 2), bitorder="little").view(np.bool_)
        space = pad.reshape(h + 2, w + 2)[1:-1, 1:-1]
        space.flags.writeable = False
        return space


class _Memo(threading.local):
    def __init__(self) -> None:
        self.entries: OrderedDict[tuple[Params, tuple[int, int], tuple[int, int]], SearchPlan] = OrderedDict()


_MEMO = _Memo()


def remember(known: np.ndarray, space_bits: np.ndarray, shape: tuple[int, int], version: np.ndarray,
             params: Params, start_cell: tuple[int, int], start: tuple[int, int], goal: tuple[int, int],
             path: np.ndarray) -> None:
    """Keep a whole-map target search on a map of ``shape``: from the robot's cell ``start_cell`` (snapped
    to ``start``) to ``goal`` on the kept 2-bit map copy ``known`` with the configuration space's kept bits
    ``space_bits`` (both valid while the counter ``version`` keeps its present value), and the path read
    off its distances."""
    path.flags.writeable = False
    entries = _MEMO.entries
    if entries and next(iter(entries.values())).shape != shape:
        entries.clear()  # another run's map: its searches can never match again, so hold no memory for them
    key = (params, start_cell, goal)
    entries[key] = SearchPlan(known, space_bits, shape, start, goal, path, version, int(version[0]))
    entries.move_to_end(key)
    limit = max(1, min(MAX_ENTRIES, MAX_BYTES // max(known.nbytes + space_bits.nbytes, 1)))
    while len(entries) > limit:
        entries.popitem(last=False)


def recall(known: np.ndarray, params: Params, start_cell: tuple[int, int], goal: tuple[int, int]
           ) -> SearchPlan | None:
    """The remembered search from ``start_cell`` to ``goal`` with these parameters, if it ran on a map
    equal to ``known``."""
    entry = _MEMO.entries.get((params, start_cell, goal))
    if (entry is None or entry.version[0] != entry.seen or entry.shape != known.shape
            or not same_as_packed(known, entry.known)):
        return None
    return entry


def forget_all() -> None:
    """Drop every remembered search of this thread (for tests)."""
    _MEMO.entries.clear()
