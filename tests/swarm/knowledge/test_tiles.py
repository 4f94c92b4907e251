"""Tiled knowledge maps: the layout is a bijection, and a tiled stack written by the lidar holds exactly the
dense stack's maps."""

from __future__ import annotations

import numpy as np
import pytest

from maps import generate
from swarm.knowledge.maps import ExplorationTracker, empty_knowledge
from swarm.knowledge.tiles import TILE, TiledKnowledge, TiledLayout
from swarm.world.sensing import Lidar, LidarParams


@pytest.mark.parametrize("shape", [(1, 1), (63, 65), (64, 64), (130, 70), (200, 333)])
def test_the_layout_puts_every_cell_at_its_own_offset_and_back(shape):
    layout = TiledLayout(shape)
    h, w = shape
    cells = np.arange(h * w, dtype=np.int64)
    offsets = layout.offsets(cells)
    assert len(np.unique(offsets)) == h * w and offsets.min() >= 0 and offsets.max() < layout.size
    assert np.array_equal(layout.cells(offsets), cells)
    rows, cols = np.divmod(cells, w)
    same_tile = offsets >> 12 == ((rows // TILE) * layout.tiles[1] + cols // TILE)
    assert same_tile.all(), "a cell lives in the page of its 64 x 64 block"
    dense = np.random.default_rng(1).integers(0, 3, shape).astype(np.uint8)
    tiled = layout.tile(dense)
    assert np.array_equal(tiled[offsets], dense.reshape(-1))
    assert np.array_equal(layout.untile(tiled), dense)


@pytest.mark.parametrize("measure", [True, False])
def test_a_tiled_stack_written_by_the_lidar_holds_the_dense_stacks_maps(measure):
    truth = generate("building", 40, 2)
    layout = TiledLayout(truth.shape)
    n = 12
    free = np.argwhere(truth.free)
    rng = np.random.default_rng(3)
    dense = empty_knowledge(truth.shape, n)
    tiled = layout.stack(n)
    trackers = [ExplorationTracker(truth), ExplorationTracker(truth)]
    for t in trackers:
        t.track_robots(n)
    lidars = [Lidar(truth, LidarParams(), tracker=t) for t in trackers]
    for _ in range(6):
        cells = free[rng.integers(len(free), size=n)]
        poses = np.column_stack([(cells[:, 1] + 0.5) * 0.5, (cells[:, 0] + 0.5) * 0.5, rng.uniform(-3, 3, n)])
        for step in range(3):  # some robots stay put: with measure=False they are settled and not cast
            lidars[0].scan(poses, dense, measure=measure)
            lidars[1].scan(poses, tiled, measure=measure)
            assert np.array_equal(lidars[0].cast, lidars[1].cast)
    for r in range(n):
        assert np.array_equal(layout.untile(tiled[r]), dense[r])
    assert np.array_equal(trackers[0].own_seen_cells, trackers[1].own_seen_cells)


def test_the_settled_test_reads_tiled_maps_as_it_reads_dense_ones():
    """A robot whose reach its map and own sight already hold is not cast; one whose map lacks a cell in
    reach is, in either layout."""
    truth = generate("building", 30, 5)
    layout = TiledLayout(truth.shape)
    full = (truth.solid * 2 + truth.free * 1).astype(np.uint8)
    free = np.argwhere(truth.free)
    cells = free[np.random.default_rng(0).integers(len(free), size=4)]
    poses = np.column_stack([(cells[:, 1] + 0.5) * 0.5, (cells[:, 0] + 0.5) * 0.5, np.zeros(4)])
    casts = []
    for tiled in (False, True):
        tracker = ExplorationTracker(truth)
        tracker.track_robots(4)
        tracker.seen_buffer[:] = True
        own = tracker.sight_buffers[0]
        own[:] = np.iinfo(own.dtype).max
        known = np.stack([full] * 4)
        row, col = int(cells[2, 0]), int(cells[2, 1])
        known[2, row, col] = 0  # robot 2's own cell: unknown to it
        if tiled:
            known = np.stack([layout.tile(m) for m in known])
        lidar = Lidar(truth, LidarParams(), tracker=tracker)
        lidar.scan(poses, known, measure=False)
        casts.append(lidar.cast.tolist())
    assert casts[0] == casts[1] == [False, False, True, False]


@pytest.mark.parametrize("seed", range(4))
def test_tiled_syncs_find_the_cells_the_dense_syncs_find(seed):
    """Against a 2-bit copy in the same order, the tiled sync over a box and dirty tiles (and over the whole
    map) lists the same row-major cells, ascending, as the dense one, and leaves a copy that holds the map."""
    from swarm.knowledge.packed import packed_copy, sync_box_tiles_packed, sync_changes_packed
    from swarm.knowledge.tiles import sync_tiles_packed

    rng = np.random.default_rng(seed)
    shape = (150, 200)
    layout = TiledLayout(shape)
    old = rng.integers(0, 3, shape).astype(np.uint8)
    new = old.copy()
    box = np.array([40, 75, 60, 130])
    dirty = np.zeros((-(-shape[0] // 32), -(-shape[1] // 32)), np.uint8)
    dirty[0, 5] = dirty[4, 1] = 1
    for r0, r1, c0, c1 in ((40, 75, 60, 130), (0, 32, 160, 192), (128, 150, 32, 64)):  # changes where promised
        patch = new[r0:r1, c0:c1]
        raise_ = rng.random(patch.shape) < 0.2
        patch[raise_] = np.maximum(patch[raise_], rng.integers(1, 3, patch.shape)[raise_])
    dense_prev = packed_copy(old)
    tiled_prev = packed_copy(layout.tile(old))
    expected = sync_box_tiles_packed(new, dense_prev, box, dirty, 32)
    got = sync_tiles_packed(layout.tile(new), tiled_prev, layout, box, dirty, 32)
    assert len(expected) > 0 and np.array_equal(got, expected)
    assert np.array_equal(tiled_prev, packed_copy(layout.tile(new)))
    new[3, 3] = 2 if new[3, 3] != 2 else 1  # outside any box: only the whole-map sync sees it
    whole = sync_changes_packed(new, dense_prev)
    assert np.array_equal(sync_tiles_packed(layout.tile(new), tiled_prev, layout, None, None, 32), whole)


@pytest.mark.parametrize("seed, drop_plain", [(0, False), (1, False), (2, False), (0, True)])
def test_map_sharing_over_tiled_maps_sends_and_merges_what_it_does_over_dense_maps(seed, drop_plain, monkeypatch):
    """A swarm's sharing (knowledge planes, deltas, gaps repaired with full maps and caught up) over a tiled
    stack: every message sent is byte for byte the dense run's, and every map and plane ends the same; also
    when full maps are copied out of the tiles each robot's writers noted (``dense``, as the runtime does)."""
    import math

    from swarm.comm.medium import CommSpec
    from swarm.comm.messages import MapRequest, MapUpdate, encode
    from swarm.comm.sharing import MapSharing
    from swarm.knowledge.planes import KnowledgePlanes

    if drop_plain:  # every delta of the tiled runs keeps only its payload (as a swarm's large ones do)
        from swarm.comm import sharing as sharing_module

        monkeypatch.setattr(sharing_module, "DROP_DECODED_CELLS", 1)
    truth = generate("building", 45, seed)
    layout = TiledLayout(truth.shape)
    n = 70
    free = np.argwhere(truth.free)
    reach = int(math.ceil(LidarParams().range_m / 0.5)) + 2  # as the runtime gives it
    runs = []
    for tiled, noted in ((False, False), (True, False), (True, True)):
        rng = np.random.default_rng(seed)
        kept = TiledKnowledge(layout, n) if noted else None
        known = kept.stack if noted else layout.stack(n) if tiled else empty_knowledge(truth.shape, n)
        planes = KnowledgePlanes(n, truth.shape[0] * truth.shape[1])
        tracker = ExplorationTracker(truth)
        lidar = Lidar(truth, LidarParams(), tracker=tracker)
        service = MapSharing(n, truth.shape, CommSpec(share_every=3), lidar_reach=reach, monotone=True,
                             planes=planes, layout=layout if tiled else None,
                             written=kept.note_cells if noted else None, dense=kept.dense if noted else None)
        cells = free[rng.integers(len(free), size=n)]
        live = np.ones(n, bool)
        queue: dict[int, list] = {}
        sent = []
        fulls = 0
        for tick in range(24):
            move = rng.random(n) < 0.3  # a few robots move each tick; the rest stay (settled scans)
            cells[move] = free[rng.integers(len(free), size=int(move.sum()))]
            poses = np.column_stack([(cells[:, 1] + 0.5) * 0.5, (cells[:, 0] + 0.5) * 0.5, np.zeros(n)])
            lidar.scan(poses, known, measure=False, planes=planes)
            if noted:  # the tiles each lidar window may have written
                kept.note_boxes(np.arange(n), np.column_stack([cells[:, 0] - reach, cells[:, 0] + reach + 1,
                                                               cells[:, 1] - reach, cells[:, 1] + reach + 1]))
            service.scanned(poses)
            service.receive_tick(queue.pop(tick, []), known, live, cells=False, tick=tick)
            out = service.outgoing(tick, known, poses)
            sent.append([[encode(m) for m in msgs] for msgs in out])
            for s in range(n):
                for m in out[s]:
                    fulls += isinstance(m, MapUpdate) and m.full
                    heard = rng.random(n) < (1.0 if isinstance(m, MapRequest) else 0.85)  # losses make gaps
                    heard[s] = False
                    queue.setdefault(tick + 1, []).append((m, np.flatnonzero(heard).tolist()))
        maps = np.stack([layout.untile(k) for k in known]) if tiled else known.copy()
        runs.append((sent, maps, planes.free.copy(), planes.solid.copy(), service.seen_seq.copy()))
        assert fulls > 0, "losses made gaps, repaired with full maps"
    sent_d, maps_d, free_d, solid_d, seen_d = runs[0]
    assert any(m for tick in sent_d for msgs in tick for m in msgs)
    for sent_t, maps_t, free_t, solid_t, seen_t in runs[1:]:
        assert sent_t == sent_d
        assert np.array_equal(maps_t, maps_d) and np.array_equal(free_t, free_d)
        assert np.array_equal(solid_t, solid_d) and np.array_equal(seen_t, seen_d)


def _run_digest(spec: dict, tiled: bool) -> str:
    import hashlib
    import json

    from swarm.sim.loop import Simulation

    res = Simulation(spec, tiled=tiled).run()
    summary = {k: v for k, v in res.summary.items() if k not in ("wall_time_s", "setup_time_s")}
    blob = json.dumps([summary, res.timeseries, res.comm, res.events], sort_keys=True, default=str)
    return hashlib.sha256(blob.encode()).hexdigest()


@pytest.mark.parametrize("algorithm, spawn", [("frontier", "together"), ("greed", "random")])
def test_a_run_over_tiled_maps_is_the_dense_run_bit_for_bit(algorithm, spawn):
    """The whole stack (lidar, planes, delta sharing with gaps and full maps, navigation, the algorithm's
    dense view, metrics) over tiled maps gives the dense run's summary, series, comm metrics and events."""
    spec = {"seed": 5, "map": {"kind": "building", "size": 40}, "robots": {"count": 70, "spawn": spawn},
            "algorithm": {"name": algorithm}, "stop": {"max_ticks": 80}}
    assert _run_digest(spec, True) == _run_digest(spec, False)


@pytest.mark.parametrize("change, allowed", [
    ({"robots": {"count": 8}}, "64 robots or more"),
    ({"localization": {"model": "odometry"}}, "maps that only rise"),
    ({"comm": {"map_sharing": "maes"}}, "MAES"),
    ({"motion": {"model": "maes"}}, "motion model"),
])
def test_runs_tiled_maps_cannot_serve_are_refused_in_one_line(change, allowed):
    from swarm.base.errors import InvalidInput
    from swarm.sim.loop import Simulation

    spec = {"seed": 1, "map": {"kind": "building", "size": 30}, "robots": {"count": 70},
            "algorithm": {"name": "frontier"}, "stop": {"max_ticks": 5}, **change}
    with pytest.raises(InvalidInput, match=allowed) as err:
        Simulation(spec, tiled=True)
    assert err.value.field == "tiled"
