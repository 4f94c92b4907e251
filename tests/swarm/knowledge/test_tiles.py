"""Tiled knowledge maps: the layout is a bijection, and a tiled stack written by the lidar holds exactly the
dense stack's maps."""

from __future__ import annotations

import numpy as np
import pytest

from maps import generate
from swarm.knowledge.maps import ExplorationTracker, empty_knowledge
from swarm.knowledge.tiles import TILE, TiledLayout
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
