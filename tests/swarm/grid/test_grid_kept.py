"""The whole-map target search's kept inputs (:mod:`swarm.grid.kept`): after any sequence of map changes
they equal a fresh computation bit for bit, and so the search's answers equal the uncached search's."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from maps import generate
from swarm import grid
from swarm.api import CELL_M, FREE, SOLID, UNSEEN
from swarm.grid import kept, memo
from swarm.grid.cspace import _erosion_rows
from swarm.grid.local import TARGET_FOUND, erosion_depth, window_target
from swarm.grid.search import _WORK
from swarm.grid.targets import default_view_reach_cells
from swarm.knowledge.packed import unpacked


def padded_grid(bits: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """Kept bits (the kept space or targets: a bit per padded cell) as a padded uint8 grid."""
    h, w = shape[0] + 2, shape[1] + 2
    return np.unpackbits(bits, bitorder="little")[:h * w].reshape(h, w)


def growing_maps(seed: int, steps: int) -> tuple[np.ndarray, list[np.ndarray]]:
    """A building revealed step by step, as a robot's map grows: a disc around a wandering point (the
    lidar), scattered cells in random rows (merged updates from others) and now and then a FREE cell that
    turns SOLID (noisy sensing). Returns the truth and the map after each step."""
    truth = generate("building", 60, seed)
    rng = np.random.default_rng(seed)
    h, w = truth.solid.shape
    known = np.zeros((h, w), np.uint8)
    rows, cols = np.indices((h, w))
    centre = rng.integers(0, (h, w))
    out = []
    for _ in range(steps):
        centre = np.clip(centre + rng.integers(-6, 7, size=2), 0, (h - 1, w - 1))
        radius = rng.integers(3, 15)
        seen = (rows - centre[0]) ** 2 + (cols - centre[1]) ** 2 <= radius ** 2
        seen |= rng.random((h, w)) < rng.choice([0.0, 0.001, 0.01])
        known = np.maximum(known, np.where(seen, np.where(truth.solid, SOLID, FREE), UNSEEN).astype(np.uint8))
        if rng.random() < 0.2:
            free = np.flatnonzero(known == FREE)
            known.flat[rng.choice(free, min(3, free.size), replace=False)] = SOLID
        out.append(known.copy())
    return truth.solid, out


@pytest.mark.parametrize("radius, margin, unseen_ok", [(0.3, 0.05, False), (0.3, 0.05, True), (0.9, 0.1, False),
                                                       (0.0, 0.0, False)])
def test_kept_inputs_equal_a_fresh_computation_after_every_change(radius: float, margin: float,
                                                                  unseen_ok: bool) -> None:
    kept.forget_all()
    reach = default_view_reach_cells(radius, margin)
    rows, widths = _erosion_rows(radius, margin)
    band = max(erosion_depth(radius, margin), reach + 1)
    partial = 0
    for seed in range(2):
        _, maps = growing_maps(seed, 40)
        robot_map = np.zeros_like(maps[0])  # one buffer for the whole run, as a robot's knowledge map
        for known in maps:
            before = robot_map.copy()
            robot_map[:] = known
            inputs = kept.inputs_for(robot_map, radius, margin, unseen_ok, reach)
            total = kept.refresh(robot_map, *inputs, unseen_ok, rows, widths, reach, band)
            space = grid.configuration_space(robot_map, radius, margin, unseen_ok).view(np.uint8)
            view = grid.view_cells(robot_map, reach)
            assert np.array_equal(unpacked(inputs.copy, robot_map.shape), robot_map)
            pad = padded_grid(inputs.space, robot_map.shape)
            assert np.array_equal(pad[1:-1, 1:-1], space)
            assert not pad[[0, -1]].any() and not pad[:, [0, -1]].any()
            targets = padded_grid(inputs.targets, robot_map.shape)
            assert np.array_equal(targets[1:-1, 1:-1], (view & (space != 0)).view(np.uint8))
            assert not targets[[0, -1]].any() and not targets[:, [0, -1]].any()
            assert total == int(np.count_nonzero(view & (space != 0)))
            partial += 0 < np.count_nonzero((before != robot_map).any(axis=1)) < robot_map.shape[0] // 2
    assert partial >= 20  # most steps changed some rows only: the band updates were exercised


@pytest.mark.parametrize("radius, margin, unseen_ok", [(0.3, 0.05, False), (0.9, 0.1, False), (0.3, 0.05, True)])
def test_one_changed_cell_is_recomputed_as_far_as_it_reaches_in_every_direction(radius: float, margin: float,
                                                                               unseen_ok: bool) -> None:
    """A single cell that changes in an open map changes view cells exactly ``reach + 1`` steps away along
    its row and column (and the space ``erosion depth`` away): the box recomputed around it must reach that
    far on all four sides, and the slice it is computed from as far again (an unseen cell that far makes
    the box's edge cells view cells). Checked for a revealed cell (UNSEEN -> FREE) and a new wall
    (FREE -> SOLID) at several places, each after a refresh that saw the map before the change."""
    reach = default_view_reach_cells(radius, margin)
    rows, widths = _erosion_rows(radius, margin)
    band = max(erosion_depth(radius, margin), reach + 1)
    for where, before, after, far in itertools.product(((20, 20), (20, 3), (2, 25), (37, 38)),
                                                       (UNSEEN, FREE), (FREE, SOLID), (False, True)):
        if before == after:
            continue
        kept.forget_all()
        robot_map = np.full((40, 41), FREE, np.uint8)
        if far:
            for dr, dc in ((0, 2 * band), (0, -2 * band), (2 * band, 0), (-2 * band, 0)):
                r, c = where[0] + dr, where[1] + dc  # seen from the box's edge: the slice must reach it
                if 0 <= r < 40 and 0 <= c < 41:
                    robot_map[r, c] = UNSEEN
        robot_map[where] = before
        inputs = kept.inputs_for(robot_map, radius, margin, unseen_ok, reach)
        kept.refresh(robot_map, *inputs, unseen_ok, rows, widths, reach, band)
        robot_map[where] = after
        total = kept.refresh(robot_map, *inputs, unseen_ok, rows, widths, reach, band)
        space = grid.configuration_space(robot_map, radius, margin, unseen_ok).view(np.uint8)
        view = grid.view_cells(robot_map, reach)
        assert np.array_equal(padded_grid(inputs.space, robot_map.shape)[1:-1, 1:-1], space)
        assert np.array_equal(padded_grid(inputs.targets, robot_map.shape)[1:-1, 1:-1],
                              (view & (space != 0)).view(np.uint8))
        assert total == int(np.count_nonzero(view & (space != 0)))


def test_the_kept_search_finds_what_the_fresh_search_finds() -> None:
    kept.forget_all()
    rng = np.random.default_rng(7)
    rows, widths = _erosion_rows(0.3, 0.05)
    found = 0
    for seed in range(2):
        _, maps = growing_maps(seed, 30)
        robot_map = np.zeros_like(maps[0])
        for known in maps:
            robot_map[:] = known
            free = np.argwhere(known == FREE)
            if free.size == 0:
                continue
            start = tuple(int(v) for v in free[rng.integers(len(free))])
            exclude = rng.random(known.shape) < 0.01 if rng.random() < 0.3 else None
            got = grid.nearest_reachable_unseen(robot_map, start, exclude=exclude, local_first_m=None)
            # the reference: the same search on the whole map as one window, computed from scratch
            h, w = known.shape
            dist, ring = _WORK.get((h + 2) * (w + 2))
            ex = np.zeros((0, 0), bool) if exclude is None else exclude
            status, row, col, cells, sr, sc = window_target(known, 0, h, 0, w, ex, 2, False, rows, widths,
                                                            start[0], start[1], 3, dist, ring)
            if status != TARGET_FOUND:
                assert got is None
                continue
            found += 1
            assert got is not None and got[0] == (int(row), int(col))
            assert got[1] == float(cells * 0.5) + 0.5 * math.hypot(int(sr) - start[0], int(sc) - start[1])
            entry = memo.recall(known, (0.3, 0.05, False), start, got[0])
            assert entry is not None
            assert np.array_equal(entry.space, grid.configuration_space(known))
            assert entry.path.tobytes() == grid.plan(entry.space, entry.start, entry.goal).tobytes()
    assert found >= 30


def test_a_different_map_in_a_kept_buffer_is_recomputed() -> None:
    kept.forget_all()
    a = generate("building", 60, 1).solid
    b = generate("cave", 60, 2).solid
    buffer = np.where(a, SOLID, FREE).astype(np.uint8)
    buffer[:40] = UNSEEN
    start = tuple(int(v) for v in np.argwhere(buffer == FREE)[-1])
    first = grid.nearest_reachable_unseen(buffer, start, local_first_m=None)
    buffer[:] = np.where(b, SOLID, FREE)
    buffer[-40:] = UNSEEN
    start = tuple(int(v) for v in np.argwhere(buffer == FREE)[0])
    second = grid.nearest_reachable_unseen(buffer, start, local_first_m=None)
    kept.forget_all()
    assert second == grid.nearest_reachable_unseen(buffer, start, local_first_m=None)
    assert first is not None and second is not None and first != second


def test_kept_entries_are_bounded() -> None:
    kept.forget_all()
    maps = [np.zeros((20, 20), np.uint8) for _ in range(kept.MAX_ENTRIES + 5)]
    for m in maps:
        m[5:15, 5:15] = FREE
        grid.nearest_reachable_unseen(m, (10, 10), local_first_m=None)
    assert len(kept._KEPT.entries) == kept.MAX_ENTRIES
    memo.forget_all()


def test_kept_entries_are_bounded_in_bytes_too(monkeypatch) -> None:
    """Big maps keep fewer entries (a swarm on a 2,000-tile building would hold 8 MB an entry), and a search
    whose entry was dropped finds what it found with it."""
    kept.forget_all()
    maps = [np.zeros((20, 20), np.uint8) for _ in range(10)]
    for m in maps:
        m[5:15, 5:15] = FREE
    first = [grid.nearest_reachable_unseen(m, (10, 10), local_first_m=None) for m in maps]
    one = kept._entry_bytes(next(iter(kept._KEPT.entries.values())))
    kept.forget_all()
    memo.forget_all()
    monkeypatch.setattr(kept, "MAX_BYTES", 3 * one)
    again = [grid.nearest_reachable_unseen(m, (10, 10), local_first_m=None) for m in maps]
    assert len(kept._KEPT.entries) == 3
    assert again == first
    kept.forget_all()
    memo.forget_all()


def test_a_team_of_64_searched_round_robin_keeps_every_map() -> None:
    """The runtime searches its robots' maps in robot order: with fewer entries than robots each search
    found its entry dropped and rebuilt it from scratch (a 64-robot run cost 2.3x a 32-robot one)."""
    kept.forget_all()
    maps = [np.zeros((20, 20), np.uint8) for _ in range(64)]
    for m in maps:
        m[5:15, 5:15] = FREE
    for _ in range(2):
        for m in maps:
            grid.nearest_reachable_unseen(m, (10, 10), local_first_m=None)
        entries = dict(kept._KEPT.entries)
    grid.nearest_reachable_unseen(maps[0], (10, 10), local_first_m=None)
    assert len(entries) == 64 and all(kept._KEPT.entries[k] is e for k, e in entries.items())
    kept.forget_all()
    memo.forget_all()


def test_kept_entries_hold_one_map_size_at_a_time() -> None:
    kept.forget_all()
    small, big = np.zeros((20, 20), np.uint8), np.zeros((30, 20), np.uint8)
    for m in (small, big):
        m[5:15, 5:15] = FREE
        grid.nearest_reachable_unseen(m, (10, 10), local_first_m=None)
    assert len(kept._KEPT.entries) == 1 and kept._KEPT.shape == big.shape


def test_a_remembered_search_is_not_recalled_once_its_kept_inputs_moved_on() -> None:
    # the memo shares the kept copy and space: after a later search on a changed map in the same buffer,
    # the copy equals the new map, but the remembered path belongs to the old one
    kept.forget_all()
    memo.forget_all()
    _, maps = growing_maps(3, 25)
    robot_map = maps[-2].copy()
    free = [tuple(int(v) for v in cell) for cell in np.argwhere(robot_map == FREE)]
    start = next(cell for cell in free if grid.nearest_reachable_unseen(robot_map, cell, local_first_m=None))
    found = grid.nearest_reachable_unseen(robot_map, start, local_first_m=None)
    params = (0.3, 0.05, False)
    assert memo.recall(robot_map, params, start, found[0]) is not None
    robot_map[:] = maps[-1]
    assert not np.array_equal(maps[-1], maps[-2])
    other = free[-1]
    grid.nearest_reachable_unseen(robot_map, other, local_first_m=None)   # refreshes the kept inputs in place
    assert np.array_equal(unpacked(kept.inputs_for(robot_map, 0.3, 0.05, False, 2).copy, robot_map.shape), robot_map)
    assert memo.recall(robot_map, params, start, found[0]) is None


def test_a_map_converted_for_one_search_is_not_kept() -> None:
    kept.forget_all()
    known = np.zeros((20, 20), np.int64)  # converted to uint8 for the search: a buffer of its own each call
    known[5:15, 5:15] = FREE
    first = grid.nearest_reachable_unseen(known, (10, 10), local_first_m=None)
    assert not kept._KEPT.entries
    assert first == grid.nearest_reachable_unseen(known.astype(np.uint8), (10, 10), local_first_m=None)
    assert len(kept._KEPT.entries) == 1


def test_a_recording_search_lists_every_cell_it_gave_a_distance_and_reads_targets_as_bits_too() -> None:
    # the whole-map search skips filling its distance array: it relies on the search listing every cell
    # it wrote, so they can be set back to inf
    from swarm.grid._kernels import NO_TOUCHED, grid_bucket_search

    rng = np.random.default_rng(3)
    found = 0
    for seed in range(2):
        _, maps = growing_maps(seed, 12)
        for known in maps[::3]:
            space = grid.configuration_space(known)
            h, w = space.shape
            pad = np.zeros((h + 2, w + 2), np.uint8)
            pad[1:-1, 1:-1] = space
            free = np.flatnonzero(pad)
            if free.size == 0:
                continue
            seeds = rng.choice(free, min(2, free.size), replace=False).astype(np.int64)
            targets = (rng.random(pad.size) < 0.01).astype(np.uint8)
            for max_d in (np.inf, 12.0):
                plain, ring = np.empty(pad.size), np.empty(3 * pad.size, np.int32)
                a = grid_bucket_search(pad.reshape(-1), w + 2, seeds, -1, targets, max_d, plain, ring, NO_TOUCHED)
                clean, touched = np.full(pad.size, np.inf), np.empty(4 * pad.size, np.int32)
                b = grid_bucket_search(pad.reshape(-1), w + 2, seeds, -1, targets, max_d, clean, ring, touched)
                assert a[:2] == b[:2] and np.array_equal(plain.view(np.int64), clean.view(np.int64))
                assert set(touched[:b[2]].tolist()) == set(np.flatnonzero(np.isfinite(clean)).tolist())
                bits = np.packbits(targets, bitorder="little")  # the kept layout: a bit per cell
                c = grid_bucket_search(pad.reshape(-1), w + 2, seeds, -1, bits, max_d, plain, ring, NO_TOUCHED)
                assert c[:2] == a[:2]
                found += a[0] >= 0
    assert found > 5  # the searches stopped at targets, not only ran out


def test_the_whole_map_search_leaves_its_workspace_clean() -> None:
    kept.forget_all()
    _, maps = growing_maps(1, 20)
    found = 0
    for known in maps[5:]:
        free = np.argwhere(known == FREE)
        for cell in free[::max(1, len(free) // 4)]:
            found += grid.nearest_reachable_unseen(known, (int(cell[0]), int(cell[1])), local_first_m=None) is not None
            assert np.isinf(_WORK.inf).all()  # the whole shared buffer, also beyond this map's cells
    assert found >= 10


def test_the_searches_share_one_workspace_and_leave_it_clean() -> None:
    """field_at, the kept target search, plan and nearest_reachable interleave on maps of two sizes; each
    must leave the shared all-inf array all inf and the marks all 0, or the next reads stale distances."""
    kept.forget_all()
    rng = np.random.default_rng(11)
    _, grown = growing_maps(2, 12)
    small = [m[:80, :100].copy() for m in grown]  # another map size: the workspace is sliced
    _, large = growing_maps(3, 20)
    for known in large[4:] + small[4:] + large[4:]:
        space = grid.configuration_space(known)
        free = np.argwhere(space)
        if len(free) < 2:
            continue
        picks = free[rng.choice(len(free), size=min(6, len(free)), replace=False)]
        src = (int(picks[0, 0]), int(picks[0, 1]))
        field = grid.distance_field(space, src)
        assert np.array_equal(grid.field_at(space, src, picks), field[picks[:, 0], picks[:, 1]])
        grid.nearest_reachable_unseen(known, src, local_first_m=None)
        goal = (int(picks[-1, 0]), int(picks[-1, 1]))
        path = grid.plan(space, src, goal)
        far = field[goal]
        assert (path is None) == np.isinf(far)
        if path is not None:
            steps = np.hypot(*np.diff(path, axis=0).T).sum() * CELL_M
            assert steps == pytest.approx(far, abs=1e-4)
        targets = np.zeros_like(space)
        targets[goal] = True
        found = grid.nearest_reachable(space, src, targets)
        assert (found is None) == (path is None)
        assert np.isinf(_WORK.inf).all() and not _WORK.marks.any()


def test_unpack_bits_spreads_each_bit_to_a_byte_in_packbits_order() -> None:
    rng = np.random.default_rng(4)
    for n in (1, 7, 8, 9, 64, 1001):
        values = rng.integers(0, 2, n).astype(np.uint8)
        out = np.full(n, 7, np.uint8)
        kept.unpack_bits(np.packbits(values, bitorder="little"), out)
        assert np.array_equal(out, values), n
