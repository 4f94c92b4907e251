"""Minotaur's cheaper bookkeeping gives what the forms it replaced gave (issue 35): wall-end and edge
candidates from the compiled pass equal the numpy pass on random windows and on grown maps; a doorway
list's new entries, counted per sender, equal the set difference of the whole lists (order included) after
random sequences of lists (appends, changes, duplicates, removals, shuffles, unhashable and NaN entries);
a book fed wire tuples through its memo equals one fed new records."""

from __future__ import annotations

import math
import random
from collections import Counter

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from algorithms.minotaur.doorways import Doorway, DoorwayBook, valid_wire
from algorithms.minotaur.peers import Peers
from algorithms.minotaur.walls import candidates
from swarm.api import FREE, SOLID, UNSEEN

from .test_tnf_kernels import grown_map

_DIRS = ((1, 0), (-1, 0), (0, 1), (0, -1))


# ----------------------------------------------------------------------------------- the oracles ----
def _shift(a: np.ndarray, dr: int, dc: int, fill: bool = False) -> np.ndarray:
    out = np.full(a.shape, fill, dtype=a.dtype)
    h, w = a.shape
    rs, re = max(0, -dr), min(h, h - dr)
    cs, ce = max(0, -dc), min(w, w - dc)
    out[rs:re, cs:ce] = a[rs + dr:re + dr, cs + dc:ce + dc]
    return out


def candidates_numpy(known: np.ndarray) -> tuple[np.ndarray, ...]:
    """algorithms.minotaur.walls.candidates before issue 35."""
    free, solid, unseen = known == FREE, known == SOLID, known == UNSEEN
    parts = []
    for dr, dc in _DIRS:
        face = solid & _shift(free, dr, dc)
        for tr, tc in ((dc, dr), (-dc, -dr)):
            end = face & _shift(unseen, tr, tc) & ~_shift(solid, tr + dr, tc + dc, True)
            rr, cc = np.nonzero(end)
            if rr.size:
                parts.append((rr, cc, np.full(rr.size, dr), np.full(rr.size, dc), rr + tr, cc + tc,
                              np.zeros(rr.size, dtype=np.int64)))
            face &= ~end
        edge = free & _shift(unseen, -dr, -dc)
        rr, cc = np.nonzero(edge)
        if rr.size:
            parts.append((rr, cc, np.full(rr.size, dr), np.full(rr.size, dc), rr - dr, cc - dc,
                          np.ones(rr.size, dtype=np.int64)))
        free = free & ~edge
    if not parts:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty, empty, empty, empty, empty, empty
    return tuple(np.concatenate(p) for p in zip(*parts))


def new_entries_sets(lists: dict, sender: int, doors: tuple) -> list:
    """Peers._new_entries before issue 35 (``lists``: its per-sender state)."""
    last, seen = lists.get(sender, ((), frozenset()))
    if doors == last:
        return []
    try:
        entries = frozenset(doors)
    except TypeError:
        entries = frozenset(w for w in doors if valid_wire(w))
    lists[sender] = (doors, entries)
    return [w for w in entries - seen if valid_wire(w)]


# -------------------------------------------------------------------------------------- the tests ----
def same(a: tuple[np.ndarray, ...], b: tuple[np.ndarray, ...]) -> bool:
    return all(x.dtype == y.dtype and np.array_equal(x, y) for x, y in zip(a, b))


@settings(max_examples=200, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), h=st.integers(1, 30), w=st.integers(1, 30))
def test_candidates_equal_the_numpy_pass_on_random_windows(seed: int, h: int, w: int) -> None:
    rng = np.random.default_rng(seed)
    known = rng.choice([UNSEEN, FREE, SOLID], size=(h, w), p=rng.dirichlet([1, 1, 1])).astype(np.uint8)
    assert same(candidates(known), candidates_numpy(known))


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 10_000), steps=st.integers(1, 25))
def test_candidates_equal_the_numpy_pass_on_grown_maps(seed: int, steps: int) -> None:
    known = grown_map(seed, steps)
    r, c = np.random.default_rng(seed).integers(0, 40, size=2)
    window = known[r:r + 65, c:c + 65]                        # a robot's window (a view, not a copy)
    got = candidates(window)
    assert same(got, candidates_numpy(window))


def random_lists(seed: int, steps: int) -> list[tuple[int, tuple]]:
    """(sender, list) heartbeats of three senders whose lists change as books do, and as a malformed or
    hostile sender's might."""
    rng = random.Random(seed)
    lists: dict[int, list] = {s: [] for s in range(3)}
    out = []
    for _ in range(steps):
        s = rng.randrange(3)
        entries = lists[s]
        op = rng.random()
        if op < 0.4:
            for _ in range(rng.choice([1, 1, 1, 2, 3])):
                entries.append((round(rng.uniform(0, 50), 3), round(rng.uniform(0, 50), 3), rng.randint(0, 1), 1.0,
                                0.5, rng.randint(0, 3), rng.randint(0, 1)))
        elif op < 0.6 and entries:
            i = rng.randrange(len(entries))
            if isinstance(entries[i], tuple):
                entries[i] = entries[i][:5] + (rng.randint(0, 3), rng.randint(0, 1))
        elif op < 0.65 and entries:
            entries.pop(rng.randrange(len(entries)))
        elif op < 0.7 and entries:
            entries.append(entries[rng.randrange(len(entries))])
        elif op < 0.73:
            entries.append([1, 2])                                # unhashable
        elif op < 0.76:
            entries[:] = [w for w in entries if isinstance(w, tuple)]
        elif op < 0.8:
            rng.shuffle(entries)
        elif op < 0.83:
            entries.append((math.nan,) * 7)
        out.append((s, tuple(entries)))
    return out


@settings(max_examples=300, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), steps=st.integers(1, 40))
def test_new_entries_equal_the_set_difference_in_its_order(seed: int, steps: int) -> None:
    """Four receivers of the same list objects (their diffs and sets are shared), each missing some."""
    rng = random.Random(seed)
    receivers = [(Peers(), {}) for _ in range(4)]
    for sender, doors in random_lists(seed, steps):
        for peers, lists in receivers:
            if rng.random() < 0.8:
                assert peers._new_entries(sender, doors) == new_entries_sets(lists, sender, doors)


@settings(max_examples=200, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), steps=st.integers(1, 40))
def test_receivers_of_the_same_list_share_its_counts_unchanged(seed: int, steps: int) -> None:
    """Each receiver's counts are the multiset of the sender's last list it heard, and receivers that
    heard the same list object hold one dict (a 64-robot run held 4,096 of them otherwise)."""
    rng = random.Random(seed)
    receivers = [Peers() for _ in range(4)]
    for sender, doors in random_lists(seed, steps):
        for peers in receivers:
            if rng.random() < 0.8:
                peers._new_entries(sender, doors)
        holders: dict[int, list] = {}
        for peers in receivers:
            for s, state in peers._lists.items():
                if state.counts is not None:
                    assert state.counts == Counter(state.doors)
                    if state.doors:  # (an empty list's counts are empty, shared or not)
                        holders.setdefault((s, id(state.doors)), []).append(state.counts)
        for dicts in holders.values():
            assert all(d is dicts[0] for d in dicts)


@settings(max_examples=200, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), steps=st.integers(1, 60))
def test_a_book_fed_wire_tuples_equals_one_fed_records(seed: int, steps: int) -> None:
    rng = random.Random(seed)
    pool = [(round(rng.uniform(0, 6), 3), round(rng.uniform(0, 6), 3), rng.randint(0, 1), 1.0, 0.5,
             rng.randint(0, 3), rng.randint(0, 1)) for _ in range(12)]
    records, wires = DoorwayBook(), DoorwayBook()
    for _ in range(steps):
        w, tick = rng.choice(pool), rng.randint(0, 100)
        a, new_a = records.add(Doorway.from_wire(w, tick))
        b, new_b = wires.add_wire(w, tick)
        assert new_a == new_b and records.doors.index(a) == wires.doors.index(b)
        assert records.version == wires.version and records.wire() == wires.wire()
        assert [d.found_tick for d in records] == [d.found_tick for d in wires]
        if rng.random() < 0.1:                       # a robot marks a side seen in place
            i = rng.randrange(len(records))
            for book in (records, wires):
                book.doors[i].sides |= 1
                book.touch()


def test_a_doorway_wire_follows_its_explored_facts() -> None:
    d = Doorway(x=1.23456, y=2.0, axis=1, width=1.0, depth=0.5)
    first = d.wire()
    assert first == (1.235, 2.0, 1, 1.0, 0.5, 0, 0) and d.wire() is first
    d.sides |= 2
    d.passed = True
    assert d.wire() == (1.235, 2.0, 1, 1.0, 0.5, 2, 1)


def find_plain(book: DoorwayBook, door: Doorway) -> Doorway | None:
    """DoorwayBook.find before issue 35: the first match, bucket by bucket, looked up every time."""
    axis, bx, by = book._key(door)
    for dx in (-1, 0, 1):
        for dy in (-1, 0, 1):
            for d in book._buckets.get((axis, bx + dx, by + dy), ()):
                if d.matches(door):
                    return d
    return None


@settings(max_examples=200, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), steps=st.integers(1, 60))
def test_remembered_matches_equal_a_fresh_lookup(seed: int, steps: int) -> None:
    """Records added between two lookups of the same doorway (a new one can be an earlier match)."""
    rng = random.Random(seed)
    queries = [Doorway(x=rng.uniform(0, 5), y=rng.uniform(0, 5), axis=rng.randint(0, 1), width=1.0, depth=0.5)
               for _ in range(8)]
    book = DoorwayBook()
    for _ in range(steps):
        q = rng.choice(queries)
        assert book.find(q) is find_plain(book, q)
        if rng.random() < 0.3:
            book.add(Doorway(x=rng.uniform(0, 5), y=rng.uniform(0, 5), axis=rng.randint(0, 1), width=1.0, depth=0.5))


@settings(max_examples=100, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(0, 12))
def test_cut_doors_closes_what_slicing_closed(seed: int, n: int) -> None:
    from algorithms.minotaur.rooms import cut_doors
    rng = np.random.default_rng(seed)
    space = rng.random((30, 40)) < 0.8
    book = DoorwayBook()
    for _ in range(n):
        book.add(Doorway(x=float(rng.uniform(-2, 22)), y=float(rng.uniform(-2, 17)), axis=int(rng.integers(2)),
                         width=float(rng.choice([1.0, 1.5, 2.0])), depth=float(rng.choice([0.5, 1.0]))))
    origin = (int(rng.integers(-5, 10)), int(rng.integers(-5, 10)))
    want = space.copy()
    h, w = want.shape
    for d in book:
        r0, c0, r1, c1 = d.cut()
        r0, r1, c0, c1 = r0 - origin[0], r1 - origin[0], c0 - origin[1], c1 - origin[1]
        if r1 < 0 or c1 < 0 or r0 >= h or c0 >= w:
            continue
        want[max(r0, 0):r1 + 1, max(c0, 0):c1 + 1] = False
    assert np.array_equal(cut_doors(space, book, origin), want)
    assert np.array_equal(cut_doors(space, list(book), origin), want)


def choose_door_fields(space, cut, start, doors, views):
    """algorithms.minotaur.rooms.choose_door before issue 35 (two whole distance fields)."""
    from swarm.api import grid

    from algorithms.minotaur.rooms import nearest_in_room, snap
    if not doors:
        return None
    in_room = grid.distance_field(cut, [start])
    anywhere = grid.distance_field(space, [start])
    options = []
    for k, d in enumerate(doors):
        best = None
        for side in (-1, 1):
            cell = snap(space, d.point(side, 1.0))
            if cell is None:
                continue
            room_d = float(in_room[cell]) if cut[cell] else math.inf
            if math.isfinite(room_d):
                cand = (0, room_d, side)
            elif math.isfinite(float(anywhere[cell])):
                cand = (1, float(anywhere[cell]), side)
            else:
                continue
            if best is None or cand[:2] < best[:2]:
                best = cand
        if best is not None:
            options.append((best[0], best[1], k, d, best[2]))
    options.sort(key=lambda o: o[:3])
    for rank, dist, _, d, side in options:
        far = snap(cut, d.point(-side, 1.0))
        if far is not None and nearest_in_room(cut, far, views) is None:
            d.resolved = True
            continue
        return d, side, rank == 0, dist
    return None


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10_000), steps=st.integers(3, 25))
def test_choose_door_reads_the_fields_it_read(seed: int, steps: int) -> None:
    from swarm.api import grid

    from algorithms.minotaur.rooms import choose_door, cut_doors, view_cells
    known = grown_map(seed, steps)
    rng = np.random.default_rng(seed)
    space = grid.configuration_space(known)
    free = np.argwhere(space)
    if not len(free):
        return
    start = tuple(int(v) for v in free[rng.integers(len(free))])

    def doors() -> list[Doorway]:
        r = np.random.default_rng(seed + 1)
        return [Doorway(x=float(r.uniform(0, 40)), y=float(r.uniform(0, 40)), axis=int(r.integers(2)), width=1.0,
                        depth=0.5) for _ in range(int(r.integers(1, 12)))]

    a, b = doors(), doors()
    cut = cut_doors(space, a)
    views = view_cells(known, space, 2)
    got, want = choose_door(space, cut, start, a, views), choose_door_fields(space, cut, start, b, views)
    assert (got is None) == (want is None)
    if got is not None:
        assert (a.index(got[0]),) + got[1:] == (b.index(want[0]),) + want[1:]
    assert [d.resolved for d in a] == [d.resolved for d in b]
