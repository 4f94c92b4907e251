"""The arena that keeps every navigator's path table and corridor in one buffer."""

from __future__ import annotations

import numpy as np

from swarm.util.arena import Arena


def test_rows_read_back_what_was_put_through_compactions_and_held_views_keep_their_values() -> None:
    rng = np.random.default_rng(0)
    arena = Arena(5, np.float64, (3,))
    assert all(arena.get(k).shape == (0, 3) for k in range(5))
    want: dict[int, np.ndarray] = {}
    held = []
    buffers = set()
    for step in range(400):
        k = int(rng.integers(0, 5))
        values = rng.normal(size=(int(rng.integers(0, 60)), 3))
        stored = arena.put(k, values)
        assert np.array_equal(stored, values)
        want[k] = values
        buffers.add(id(arena.buffer))
        if step % 50 == 0:
            held.append((stored, values.copy()))
        for row, expected in want.items():
            assert np.array_equal(arena.get(row), expected)
    assert len(buffers) > 1  # it compacted
    assert all(np.array_equal(view, copy) for view, copy in held)
    assert arena.buffer.shape[0] <= 2 * (5 * 59 + 59)  # compaction drops dead rows: twice the live ones at most


def test_a_one_dimensional_arena_of_cell_indices() -> None:
    arena = Arena(2, np.int64)
    arena.put(1, np.array([3, 9, 27]))
    arena.put(0, np.zeros(0, dtype=np.int64))
    assert arena.get(1).tolist() == [3, 9, 27] and arena.get(0).tolist() == []
    assert arena.buffer[arena.start[1]:arena.end[1]].tolist() == [3, 9, 27]  # what a compiled call reads
