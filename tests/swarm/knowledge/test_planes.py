"""Knowledge planes (who knows which cell, two bits a robot) and the tiled change tracking of map sharing:
each gives exactly what the map-by-map code gives."""

from __future__ import annotations

import hashlib
import json

import numpy as np
import pytest

import swarm.knowledge.planes as planes_module
from swarm.api import FREE, SOLID, UNSEEN
from swarm.knowledge.maps import mark_tiles, merge_cells_many_counted
from swarm.knowledge.packed import packed_copy, sync_box_tiles_packed, sync_changes_packed
from swarm.knowledge.planes import KnowledgePlanes, check_planes, merge_into_many, note_map
from swarm.sim.loop import Simulation
from swarm.util.memory import lazy_zeros


def planes_of(known: np.ndarray) -> KnowledgePlanes:
    planes = KnowledgePlanes(known.shape[0], known[0].size)
    for r in range(known.shape[0]):
        note_map(planes.free, planes.solid, known[r].reshape(-1), r)
    return planes


@pytest.mark.parametrize("n, few", [(1, False), (63, False), (64, False), (65, False), (130, False), (130, True),
                                    (65, True)])
def test_a_merge_through_the_planes_is_the_map_by_map_merge(n, few):
    """Random maps (every value, so FREE -> SOLID raises and lowered counts occur), random updates into
    random receivers: the same maps, FREE counts and changed tiles, and planes that still mirror the maps.
    ``few``: one to three receivers, across words, so both of the kernel's ways are taken
    (planes_module.FEW_RECEIVERS)."""
    rng = np.random.default_rng(n + few)
    h, w, tile = 37, 45, 8
    known = rng.integers(0, 3, (n, h, w)).astype(np.uint8)
    known[rng.random(known.shape) < 0.5] = UNSEEN
    reference = known.copy()
    planes = planes_of(known)
    counts, counts_ref = np.zeros(n, np.int64), np.zeros(n, np.int64)
    dirty = np.zeros((n, -(-h // tile), -(-w // tile)), np.uint8)
    dirty_ref = np.zeros_like(dirty)
    for _ in range(20):
        idx = np.unique(rng.integers(0, h * w, 60))
        values = rng.integers(0, 3, idx.size).astype(np.uint8)
        robots = np.flatnonzero(rng.random(n) < 0.6).astype(np.int64)
        if few:
            robots = np.sort(rng.choice(n, int(rng.integers(1, planes_module.FEW_RECEIVERS + 2)), replace=False))
        before = reference.copy()
        merge_cells_many_counted(reference, robots, idx, values, robots, counts_ref)
        for r in robots:
            changed = np.flatnonzero(reference[r].reshape(-1) != before[r].reshape(-1))
            mark_tiles(dirty_ref[r], changed, w, tile)
        merge_into_many(known, planes.free, planes.solid, planes.mask(robots), idx, values, counts, dirty, tile)
        assert np.array_equal(known, reference)
        assert np.array_equal(counts, counts_ref)
        assert np.array_equal(dirty, dirty_ref)
    assert check_planes(planes, known)


def test_the_lidar_keeps_the_planes():
    sim = Simulation({"seed": 2, "map": {"kind": "building", "size": 40}, "robots": {"count": 3}, "stop": {"max_ticks": 1}})
    planes = KnowledgePlanes(3, sim.truth.shape[0] * sim.truth.shape[1])
    sim.lidar.scan(sim.start_poses, sim.known, measure=False, planes=planes)
    assert (sim.known == SOLID).any() and (sim.known == FREE).any()
    assert check_planes(planes, sim.known)


def run_digest(spec: dict) -> str:
    r = Simulation(spec).run()
    summary = {k: v for k, v in r.summary.items() if not k.endswith("_time_s")}
    return hashlib.sha256(json.dumps([summary, r.timeseries, r.events, r.comm], sort_keys=True,
                                     default=str).encode()).hexdigest()


@pytest.mark.parametrize("comm", [{}, {"loss": 0.3, "bandwidth": 3000}, {"map_sharing": "full", "share_every": 7},
                                  {"relay": "flood", "loss": 0.2}])
def test_a_run_with_planes_is_the_run_without(monkeypatch, comm):
    """A team large enough for planes gives the same result bit for bit with them and without, whatever
    the sharing: deltas, losses and bandwidth (full maps on gaps), full maps, relaying."""
    spec = {"seed": 5, "map": {"kind": "building", "size": 30}, "robots": {"count": 66, "spawn": "together"},
            "stop": {"max_ticks": 120}, "comm": comm}
    sim = Simulation(spec)
    assert sim.planes is not None
    with_planes = run_digest(spec)
    monkeypatch.setattr(planes_module, "MIN_ROBOTS", 10 ** 6)
    assert Simulation(spec).planes is None
    assert run_digest(spec) == with_planes


def test_planes_are_kept_only_where_every_write_goes_through_them():
    base = {"seed": 1, "map": {"kind": "building", "size": 30}, "robots": {"count": 64}, "stop": {"max_ticks": 1}}
    assert Simulation(base).planes is not None
    assert Simulation({**base, "robots": {"count": 63}}).planes is None                      # a small team
    assert Simulation({**base, "lidar": {"mode": "logodds"}}).planes is None                 # cells may fall
    assert Simulation({**base, "comm": {"map_sharing": "off"}}).planes is None               # nothing merged
    assert Simulation({**base, "comm": {"map_sharing": "maes_sync"}}).planes is None         # maps overwritten


def test_the_tiled_comparison_finds_the_whole_comparisons_cells():
    """Cells changed only inside the box or the marked tiles: the same cells, ascending, and the same copy
    as comparing the whole maps."""
    rng = np.random.default_rng(7)
    for _ in range(300):
        h, w, tile = int(rng.integers(1, 80)), int(rng.integers(1, 80)), int(rng.choice([1, 3, 8, 32]))
        old = rng.integers(0, 3, (h, w)).astype(np.uint8)
        dirty = (rng.random((-(-h // tile), -(-w // tile))) < 0.3).astype(np.uint8)
        box = np.array([*sorted(rng.integers(-5, h + 5, 2)), *sorted(rng.integers(-5, w + 5, 2))], dtype=np.int64)
        covered = np.kron(dirty, np.ones((tile, tile), np.uint8))[:h, :w].astype(bool)
        covered[max(box[0], 0):max(box[1], 0), max(box[2], 0):max(box[3], 0)] = True
        new = old.copy()
        flip = (rng.random((h, w)) < 0.2) & covered
        new[flip] = (new[flip] + 1) % 3
        a, b = packed_copy(old), packed_copy(old)
        assert np.array_equal(sync_box_tiles_packed(new, a, box, dirty, tile), sync_changes_packed(new, b))
        assert np.array_equal(a, b)


def test_lazy_zeros_is_zeros():
    for shape, dtype in (((3, 5), np.uint8), ((2, 1024, 1024), np.uint8), ((600, 700), np.int64)):
        a = lazy_zeros(shape, dtype)
        assert a.shape == shape and a.dtype == dtype and a.flags.c_contiguous and a.flags.writeable
        assert not a.any()
        a[(0,) * len(shape)] = 3
        assert a.sum() == 3


def test_a_full_updates_known_cells_are_its_dense_maps_nonzero_cells():
    from swarm.comm.messages import MapUpdate, decode, encode, full_update

    rng = np.random.default_rng(3)
    for h, w in ((1, 1), (7, 9), (40, 33)):
        known = rng.integers(0, 3, (h, w)).astype(np.uint8)
        known[rng.random((h, w)) < 0.7] = UNSEEN
        for msg in (full_update(0, 1, 0, known, (0.0, 0.0, 0.0)), decode(encode(full_update(0, 1, 0, known, (0.0, 0.0, 0.0))))):
            assert isinstance(msg, MapUpdate)
            idx, values = msg.known_cells()
            dense = msg.dense()
            assert np.array_equal(idx, np.flatnonzero(dense)) and np.array_equal(values, dense[idx])


@pytest.mark.parametrize("tiled", [False, True])
def test_a_full_map_merged_where_it_rises_over_the_last_update_is_the_whole_merge(monkeypatch, tiled):
    """Robots spread at random meet new neighbours and ask them for their full maps; a receiver that never
    heard the sender merges only the cells where the map holds more than its own last update. The run is
    the run that merges every known cell, bit for bit, over dense and tiled maps; the shortcut was taken,
    raised cells and skipped most of the map."""
    from swarm.comm import sharing as sharing_module
    from swarm.knowledge.packed import rising_cells

    spec = {"seed": 3, "map": {"kind": "building", "size": 60}, "robots": {"count": 66, "spawn": "random"},
            "stop": {"max_ticks": 80}, "comm": {"share_every": 3}}
    taken = {"calls": 0, "rising": 0, "known": 0}

    def counted(theirs, mine, cells, values):
        k = rising_cells(theirs, mine, cells, values)
        taken["calls"] += 1
        taken["rising"] += k
        taken["known"] += int(np.count_nonzero(np.unpackbits(theirs).reshape(-1, 2).any(axis=1)))
        return k

    def digest() -> str:
        res = Simulation(spec, tiled=tiled).run()
        summary = {k: v for k, v in res.summary.items() if not k.endswith("_time_s")}
        return hashlib.sha256(json.dumps([summary, res.timeseries, res.comm, res.events], sort_keys=True,
                                         default=str).encode()).hexdigest()

    monkeypatch.setattr(sharing_module, "rising_cells", counted)
    rising = digest()
    assert taken["calls"] > 10 and 0 < taken["rising"] < taken["known"] / 2
    monkeypatch.setattr(sharing_module, "RISING_ONLY", False)
    calls = taken["calls"]
    assert digest() == rising
    assert taken["calls"] == calls, "off: every known cell is merged"


def test_rising_cells_are_where_one_packed_map_holds_more():
    from swarm.knowledge.packed import rising_cells

    rng = np.random.default_rng(4)
    for size, structured in [(1, False), (5, False), (64, False), (1001, False), (40_003, True), (4_096, True)]:
        mine = rng.integers(0, 3, size).astype(np.uint8)
        theirs = rng.integers(0, 3, size).astype(np.uint8)
        theirs[rng.random(size) < 0.3] = UNSEEN
        if structured:  # a map known in a few blocks, mostly held already: empty and equal words, and a tail
            theirs[:] = UNSEEN
            for a in rng.integers(0, size - 300, 5):
                theirs[a:a + int(rng.integers(1, 300))] = rng.integers(1, 3)
            mine = theirs.copy()
            mine[rng.random(size) < 0.01] = UNSEEN
            mine[rng.random(size) < 0.01] = 2
        cells = np.empty(size, np.int64)
        values = np.empty(size, np.uint8)
        k = rising_cells(packed_copy(theirs), packed_copy(mine), cells, values)
        expected = np.flatnonzero(theirs > mine)
        assert np.array_equal(cells[:k], expected) and np.array_equal(values[:k], theirs[expected])
