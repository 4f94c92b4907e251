"""Variable-length arrays of many owners in one buffer, so that one compiled call can read all of them.

The runtime steps every robot's navigator in one compiled call (:class:`swarm.navigation.navigator.NavigationFleet`).
Each navigator has a path table and a corridor of cells whose lengths change with every plan; a compiled
call cannot take a Python list of arrays without paying per array. An :class:`Arena` keeps row ``k``'s
array at ``buffer[start[k]:end[k]]``: the call takes the buffer and the two index arrays.

Writing a row appends to the buffer and never overwrites, so an array handed out by :meth:`Arena.get` or
:meth:`Arena.put` keeps its values for as long as it is held, also after the buffer is compacted (then the
live rows move to a new buffer and the old one lives on in the views that still point into it).
"""

from __future__ import annotations

import numpy as np

_MIN_CAPACITY = 256


class Arena:
    """One array per row (``n`` rows, each of shape ``(m, *tail)`` with its own ``m``) in one buffer."""

    def __init__(self, n: int, dtype: type, tail: tuple[int, ...] = ()) -> None:
        self.start = np.zeros(n, dtype=np.int64)
        self.end = np.zeros(n, dtype=np.int64)
        self.buffer = np.empty((_MIN_CAPACITY, *tail), dtype=dtype)
        self._fill = 0

    def get(self, row: int) -> np.ndarray:
        """Row ``row``'s array (a view into the buffer; empty before the first :meth:`put`)."""
        return self.buffer[self.start[row]:self.end[row]]

    def put(self, row: int, values: np.ndarray) -> np.ndarray:
        """Make ``values`` (shape ``(m, *tail)``) row ``row``'s array; returns the stored array (a view)."""
        m = values.shape[0]
        if self._fill + m > self.buffer.shape[0]:
            self._compact(m)
        at = self._fill
        self.buffer[at:at + m] = values
        self.start[row] = at
        self.end[row] = at + m
        self._fill = at + m
        return self.buffer[at:at + m]

    def _compact(self, extra: int) -> None:
        """Copy the live rows, in row order, into a new buffer with room for twice them and ``extra`` more."""
        lengths = self.end - self.start
        size = max(2 * (int(lengths.sum()) + extra), _MIN_CAPACITY)
        buffer = np.empty((size, *self.buffer.shape[1:]), dtype=self.buffer.dtype)
        at = 0
        for row, m in enumerate(lengths.tolist()):
            buffer[at:at + m] = self.buffer[self.start[row]:self.end[row]]
            self.start[row] = at
            self.end[row] = at + m
            at += m
        self.buffer = buffer
        self._fill = at
