"""What one robot knows of the others: where they were, where they are going, which doorway they are
going through, and the doorway lists they broadcast.

Alg. 2 has every robot broadcast "map, including walls, explored area, doorways and known robots
location". Positions come from the runtime's map updates (``MapUpdate.pose``) and sensed neighbours;
targets and doorway claims from Minotaur's :class:`~.messages.DoorwayList` heartbeats and
:class:`~.messages.Heading` messages. A robot uses them to split the spin (Alg. 2), to leave a doorway
another robot is going through to it, and to keep its greedy targets away from other robots' targets
(MAES's Minotaur excludes other robots' destinations when it re-targets, docs/maes.md section 7.2).
"""

from __future__ import annotations

import math
import threading
from collections import OrderedDict
from collections.abc import Iterator
from functools import lru_cache
from itertools import compress
from operator import is_not

import numpy as np
from numba import njit

from swarm.api import CELL_M

from .doorways import Doorway, DoorwayBook, Wire, valid_wire
from .messages import DoorwayList, Heading


class Peers:
    def __init__(self) -> None:
        self.poses: dict[int, tuple[float, float, int]] = {}        # robot -> (x, y, tick heard)
        self.targets: dict[int, tuple[float, float, int]] = {}
        self.doors: dict[int, tuple[Doorway, int]] = {}             # robot -> (doorway it goes through, tick)
        self._lists: dict[int, _ListState] = {}                    # robot -> its last doorway list

    def saw(self, robot: int, x: float, y: float, tick: int) -> None:
        self.poses[robot] = (float(x), float(y), tick)

    def fresh_poses(self, tick: int, max_age: int) -> Iterator[tuple[int, float, float]]:
        for robot, (x, y, t) in self.poses.items():
            if tick - t <= max_age:
                yield robot, x, y

    def heard(self, tick: int, m: DoorwayList | Heading, book: DoorwayBook) -> None:
        """Merge a heartbeat or heading into ``book`` and remember the sender's target and doorway. ``m``
        is well formed (``explorer._well_formed``): its target a pair of numbers (NaN: none), its doorway
        ``()`` or a valid wire; the doorway list's entries are checked here, when they are new."""
        if isinstance(m, DoorwayList):
            for w in self._new_entries(m.sender, m.doors):
                book.add_wire(w, tick)
        x, y = m.target
        if math.isfinite(x) and math.isfinite(y):
            self.targets[m.sender] = (float(x), float(y), tick)
        else:
            self.targets.pop(m.sender, None)
        if m.door != ():
            door, _ = book.add_wire(m.door, tick)  # type: ignore[arg-type]
            self.doors[m.sender] = (door, tick)
        else:
            self.doors.pop(m.sender, None)

    def _new_entries(self, sender: int, doors: tuple) -> list[Wire]:
        """The valid entries of a doorway list that its sender's previous list did not have: a robot
        repeats its whole list every heartbeat, and merging only what changed keeps this cheap.

        What is new is ``frozenset(doors) - frozenset(previous)``, in that set's order (the order the
        book adds them). Building both sets hashes every entry of every list a sender sends whenever
        anything in it changed (most lists: one doorway added or marked explored). So the entries are
        counted per sender (:class:`_ListState`) and only the positions that changed are hashed; when one
        entry is new its order is trivial, and only two or more new ones build the sets for their order."""
        state = self._lists.get(sender)
        if state is None:
            state = self._lists[sender] = _ListState()
        if doors is state.doors or doors == state.doors:
            return []
        if state.counts is not None and isinstance(doors, tuple):
            try:
                fresh, before = state.advance(doors, sender)
            except TypeError:            # an unhashable (malformed) entry: the sets below say what it means
                pass
            else:
                if before is None:
                    return [w for w in fresh if valid_wire(w)]
                return [w for w in state.set_of_doors() - before if valid_wire(w)]
        seen = state.set_of_doors()
        try:
            entries = _SHARED.set_of(doors)
        except TypeError:                        # an unhashable (malformed) entry
            entries = frozenset(w for w in doors if valid_wire(w))
            state.reset(doors, entries, None)
        else:
            state.reset(doors, entries, _SHARED.counts_for(sender, doors))
        return [w for w in entries - seen if valid_wire(w)]

    def claimed(self, tick: int, max_age: int) -> list[Doorway]:
        """Doorways other robots said (within ``max_age`` ticks) they are going through."""
        return [d for d, t in self.doors.values() if tick - t <= max_age]

    def targets_mask(self, shape: tuple[int, int], tick: int, max_age: int, radius_m: float,
                     origin: tuple[int, int] = (0, 0)) -> np.ndarray | None:
        """Cells within ``radius_m`` of other robots' current targets (heard within ``max_age``), or None
        when there are none; ``shape`` is the map's, or a window's whose cell (0, 0) is map cell ``origin``."""
        fresh = [(x, y) for x, y, t in self.targets.values() if tick - t <= max_age]
        if not fresh:
            return None
        mask = np.zeros(shape, dtype=bool)
        k = math.ceil(radius_m / CELL_M)
        xy = np.array(fresh, dtype=np.float64)
        rows = np.floor(xy[:, 1] / CELL_M).astype(np.int64) - origin[0]   # cell_of, for every target at once
        cols = np.floor(xy[:, 0] / CELL_M).astype(np.int64) - origin[1]
        _stamp(mask, rows, cols, _disc(k), k)
        return mask


@lru_cache(maxsize=8)
def _disc(k: int) -> np.ndarray:
    """The cells within ``k`` of the centre of a (2k + 1)-square (read-only: shared by every call)."""
    yy, xx = np.mgrid[-k:k + 1, -k:k + 1]
    disc = yy * yy + xx * xx <= k * k
    disc.flags.writeable = False
    return disc


@njit(cache=True)
def _stamp(mask, rows, cols, disc, k):  # pragma: no cover - compiled
    """``mask |= disc`` centred on each (row, col), clipped to the mask: a swarm's robot hears hundreds of
    targets, and a slice per target in Python was a tenth of Minotaur's loop at 256 robots (issue 47)."""
    h, w = mask.shape
    for i in range(rows.shape[0]):
        r, c = rows[i], cols[i]
        for dr in range(max(-k, -r), min(k, h - 1 - r) + 1):
            for dc in range(max(-k, -c), min(k, w - 1 - c) + 1):
                if disc[dr + k, dc + k]:
                    mask[r + dr, c + dc] = True


_NO_COUNTS: dict = {}


class _ListState:
    """A sender's last doorway list: the tuple, the number of times each entry occurs in it (None after a
    list with an unhashable entry), and its entries as a set when one was built (``set_of_doors``)."""

    __slots__ = ("doors", "counts", "_set")   # one per receiver and sender: 4,096 in a 64-robot team

    def __init__(self) -> None:
        self.doors: tuple = ()
        self.counts: dict | None = _NO_COUNTS  # shared, never changed in place (see advance)
        self._set: frozenset | None = frozenset()

    def set_of_doors(self) -> frozenset:
        """The entries of the last list as ``Peers._new_entries`` has always taken them: ``frozenset`` of
        the list, or of its valid entries when one was unhashable."""
        if self._set is None:
            self._set = _SHARED.set_of(self.doors)
        return self._set

    def reset(self, doors: tuple, entries: frozenset, counts: dict | None) -> None:
        """Take ``doors`` afresh: its set, and its counts (None when an entry is unhashable)."""
        self.doors, self._set = doors, entries
        self.counts = counts

    def advance(self, doors: tuple, sender: int) -> tuple[list, frozenset | None]:
        """Move to ``doors`` and return the entries it has that the last list had not (each once, in no
        particular order) and, when there are two or more, the last list's set (their order is that of the
        set difference; the set is not kept, so a receiver holds one set per sender, not two). Raises
        TypeError on an unhashable entry, leaving the state as it was.

        The new entries depend only on the last list and this one (the counts are always the last list's),
        the counts only on this one: every receiver that heard the same lists of ``sender`` shares them
        (:class:`_Shared`), so the counts dicts are never changed in place. One per receiver and sender,
        they grew with the team times the doorways (15 MB of a 64-robot run's 6,000 ticks)."""
        last = self.doors
        fresh = _SHARED.fresh_of(sender, last, doors)
        counts = _SHARED.counts_of(sender, doors)
        if fresh is None or counts is None:
            built, fresh = _advance(last, self.counts, doors)
            counts = _SHARED.keep(sender, last, doors, built if counts is None else counts, fresh)
        before = self.set_of_doors() if len(fresh) > 1 else None
        self.counts = counts
        self.doors, self._set = doors, None
        return fresh, before


def _advance(last: tuple, counts: dict | None, doors: tuple) -> tuple[dict, list]:
    """The counts of ``doors`` (a new dict, built from ``counts``, those of ``last``) and the entries of
    ``doors`` that ``last`` had not, each once. Raises TypeError on an unhashable entry."""
    assert counts is not None
    n = min(len(doors), len(last))
    # a sender's unchanged entries are the same objects (Doorway.wire is kept): identity first, in C
    changed = [i for i in compress(range(n), map(is_not, doors, last)) if doors[i] != last[i]]
    gone = [last[i] for i in changed] + list(last[n:])
    came = [doors[i] for i in changed] + list(doors[n:])
    for w in gone + came:
        hash(w)                                # raise before building anything
    fresh = []
    for w in came:
        if w not in counts and w not in fresh:
            fresh.append(w)
    out = dict(counts)
    for w in gone:
        k = out[w] - 1
        if k:
            out[w] = k
        else:
            del out[w]
    for w in came:
        out[w] = out.get(w, 0) + 1
    return out, fresh


class _Shared(threading.local):
    """What every receiver of one heartbeat computes alike, computed once: in-process, all receivers of a
    sender's list get the same tuple object, and all that heard its previous one hold that same object.
    Entries hold the tuples they describe, so an id is never reused while its entry lives."""

    SIZE = 64
    PER_SENDER = 4
    """Lists kept per sender: the receivers that heard its every list share the newest; one that missed
    some moves from an older list."""

    def __init__(self) -> None:
        self.moves: dict[int, list[tuple[tuple, tuple, list]]] = {}   # sender -> (last, doors, fresh)
        self.counted: dict[int, list[tuple[tuple, dict]]] = {}        # sender -> (doors, its counts)
        self.sets: OrderedDict[int, tuple[tuple, frozenset]] = OrderedDict()

    def fresh_of(self, sender: int, last: tuple, doors: tuple) -> list | None:
        """:func:`_advance`'s new entries for this move of ``sender``'s list, if a receiver computed them."""
        for a, b, fresh in self.moves.get(sender, ()):
            if a is last and b is doors:
                return fresh
        return None

    def counts_of(self, sender: int, doors: tuple) -> dict | None:
        """The counts of ``sender``'s list ``doors``, if a receiver computed them (not to be changed)."""
        for b, counts in self.counted.get(sender, ()):
            if b is doors:
                return counts
        return None

    def keep(self, sender: int, last: tuple, doors: tuple, counts: dict, fresh: list) -> dict:
        """Remember a move's new entries and the counts of ``doors`` (returned, for the caller to hold)."""
        moves = self.moves.setdefault(sender, [])
        moves.insert(0, (last, doors, fresh))
        del moves[self.PER_SENDER:]
        return self.counts_for(sender, doors, counts)

    def counts_for(self, sender: int, doors: tuple, built: dict | None = None) -> dict:
        """The shared counts of ``sender``'s list ``doors``: those a receiver computed, else ``built`` (or
        counted now), kept for the next. Raises TypeError on an unhashable entry."""
        counts = self.counts_of(sender, doors)
        if counts is None:
            counts = _counts(doors) if built is None else built
            counted = self.counted.setdefault(sender, [])
            counted.insert(0, (doors, counts))
            del counted[self.PER_SENDER:]
        return counts

    def set_of(self, doors: tuple) -> frozenset:
        """``frozenset(doors)`` (raises TypeError on an unhashable entry)."""
        hit = self.sets.get(id(doors))
        if hit is not None and hit[0] is doors:
            return hit[1]
        out = frozenset(doors)
        _put(self.sets, id(doors), (doors, out), self.SIZE)
        return out


def _put(cache: OrderedDict, key: object, value: object, size: int) -> None:
    cache[key] = value
    cache.move_to_end(key)
    while len(cache) > size:
        cache.popitem(last=False)


_SHARED = _Shared()


def _counts(doors: tuple) -> dict:
    out: dict = {}
    for w in doors:
        out[w] = out.get(w, 0) + 1
    return out
