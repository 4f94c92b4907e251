"""Knowledge maps (merge, counts, log-odds classification) and the ground-truth coverage tracker."""

from __future__ import annotations

import numpy as np
import pytest

from maps import InvalidInput, Map
from swarm.api import FREE, SOLID, UNSEEN
from swarm.knowledge.maps import (
    ExplorationTracker, LogOddsGrid, active_flags, classify_logodds, count_cells, count_known, empty_knowledge,
    merge, merge_cells, merge_cells_many_changed, merge_cells_many_counted, sync_box, sync_boxes_flat, sync_changes,
    sync_regions, sync_regions_flat,
)


def make_map(solid: np.ndarray) -> Map:
    return Map(solid=solid, material=solid.astype(np.uint8), materials=("air", "concrete"))


def room(rows: int, cols: int) -> np.ndarray:
    solid = np.ones((rows, cols), dtype=bool)
    solid[1:-1, 1:-1] = False
    return solid


# --------------------------------------------------------------------------------------- ternary maps
def test_merge_is_an_in_place_maximum_and_counts_what_changed() -> None:
    rng = np.random.default_rng(0)
    a = rng.integers(0, 3, (30, 40), dtype=np.uint8)
    b = rng.integers(0, 3, (30, 40), dtype=np.uint8)
    expected = np.maximum(a, b)
    changed = int((b > a).sum())
    before = b.copy()
    assert merge(a, b) == changed > 0
    assert np.array_equal(a, expected) and np.array_equal(b, before)
    assert merge(a, b) == 0


def test_merge_keeps_solid_over_free_and_accepts_read_only_maps() -> None:
    mine = np.array([[SOLID, FREE, UNSEEN]], dtype=np.uint8)
    theirs = np.array([[FREE, SOLID, FREE]], dtype=np.uint8)
    theirs.setflags(write=False)
    merge(mine, theirs)
    assert mine.tolist() == [[SOLID, SOLID, FREE]]


def test_merge_refuses_mismatched_maps() -> None:
    a = empty_knowledge((4, 5))
    for other, field in ((empty_knowledge((5, 4)), "other"), (np.zeros((4, 5), np.int64), "other"),
                         (empty_knowledge((4, 5), 2), "other")):
        with pytest.raises(InvalidInput) as err:
            merge(a, other)
        assert err.value.field == field
    ro = empty_knowledge((4, 5))
    ro.setflags(write=False)
    with pytest.raises(InvalidInput) as err:
        merge(ro, a)
    assert err.value.field == "into"


def test_merge_cells_equals_maximum_at_with_repeated_indices() -> None:
    rng = np.random.default_rng(4)
    for _ in range(20):
        known = rng.integers(0, 3, size=(9, 13), dtype=np.uint8)
        idx = rng.integers(0, known.size, size=60)
        values = rng.integers(0, 3, size=60, dtype=np.uint8)
        expected = known.copy()
        np.maximum.at(expected.reshape(-1), idx, values)
        merge_cells(known, idx, values)
        assert np.array_equal(known, expected)
    ro = empty_knowledge((3, 3))
    ro.setflags(write=False)
    with pytest.raises(InvalidInput) as err:
        merge_cells(ro, np.array([0]), np.array([1], np.uint8))
    assert err.value.field == "known"


def test_sync_changes_reports_the_changed_cells_and_brings_last_up_to_date() -> None:
    rng = np.random.default_rng(5)
    current = rng.integers(0, 3, size=(7, 11), dtype=np.uint8)
    last = current.copy()
    last[rng.random(last.shape) < 0.2] = 0
    expected = np.flatnonzero(current != last)
    got = sync_changes(current, last)
    assert got.tolist() == expected.tolist() and len(got) > 0
    assert np.array_equal(last, current)
    assert sync_changes(current, last).size == 0


def test_sync_box_equals_sync_changes_when_the_changes_are_in_the_box_or_listed() -> None:
    rng = np.random.default_rng(8)
    for case in range(300):
        h, w = (int(v) for v in rng.integers(1, 40, 2))
        r0, r1 = sorted(int(v) for v in rng.integers(-3, h + 4, 2))
        c0, c1 = sorted(int(v) for v in rng.integers(-3, w + 4, 2))
        last = rng.integers(0, 3, (h, w), dtype=np.uint8)
        current = last.copy()
        inside = np.zeros((h, w), dtype=bool)
        inside[max(r0, 0):max(r1, 0), max(c0, 0):max(c1, 0)] = True
        current[inside & (rng.random((h, w)) < 0.3)] += 1      # changes in the box ...
        extra = rng.integers(0, h * w, int(rng.integers(0, 12)))
        current.reshape(-1)[extra] = rng.integers(0, 3, len(extra))  # ... and at listed cells (repeats too)
        current %= 3
        expected_last = last.copy()
        want = sync_changes(current, expected_last)
        got = sync_box(current, last, (r0, r1, c0, c1), extra)
        assert got.tolist() == want.tolist(), case
        assert np.array_equal(last, current), case


def test_sync_box_ignores_changes_outside_its_promise_and_checks_its_cells() -> None:
    current = np.zeros((6, 6), dtype=np.uint8)
    last = current.copy()
    current[0, 0] = current[5, 5] = current[2, 3] = FREE
    assert sync_box(current, last, (1, 4, 1, 4), np.array([35])).tolist() == [15, 35]
    assert last[0, 0] == UNSEEN  # outside the box and the list: not looked at
    with pytest.raises(InvalidInput) as err:
        sync_box(current, last, (0, 6, 0, 6), np.array([36]))
    assert err.value.field == "extra"


def test_sync_regions_sees_the_window_and_the_listed_cells_only() -> None:
    rng = np.random.default_rng(6)
    current = rng.integers(0, 3, size=(1, 12, 10), dtype=np.uint8)
    last = np.zeros_like(current)
    listed = np.array([5, 5, 113, 0, 47])
    got = sync_regions(current, last, np.array([[5, 4]]), 2, [[listed]], np.array([True]))[0]
    window = np.zeros(current.shape[1:], dtype=bool)
    window[3:8, 2:7] = True                       # rows 5 +- 2, cols 4 +- 2
    flat = current[0].reshape(-1)
    expected = np.union1d(np.flatnonzero(window & (current[0] != 0)), listed[flat[listed] != 0])
    assert got.tolist() == expected.tolist()
    assert np.array_equal(last[0].reshape(-1)[expected], flat[expected])
    others = np.setdiff1d(np.arange(flat.size), expected)
    assert not last[0].reshape(-1)[others].any()  # nothing outside the window and the list was copied
    assert sync_regions(current, last, np.array([[5, 4]]), 2, [[listed]], np.array([True]))[0].size == 0


def _sync_reference(current: np.ndarray, last: np.ndarray, rows: tuple[int, int], cols: tuple[int, int],
                    extra: np.ndarray | None) -> np.ndarray:
    """The changed cells of a window plus listed cells, ascending, copied into ``last`` (plain numpy)."""
    window = np.zeros(current.shape, dtype=bool)
    window[rows[0]:rows[1], cols[0]:cols[1]] = True
    if extra is not None:
        window.reshape(-1)[extra] = True
    changed = np.flatnonzero(window & (current != last))
    last.reshape(-1)[changed] = current.reshape(-1)[changed]
    return changed


def test_sync_regions_equals_the_window_rule_per_map_and_skips_inactive_maps() -> None:
    rng = np.random.default_rng(7)
    current = rng.integers(0, 3, size=(4, 30, 25), dtype=np.uint8)
    last, expected_last = np.zeros_like(current), np.zeros_like(current)
    centres = np.array([[0, 0], [15, 12], [29, 24], [10, 3]])
    cells = [[np.array([700, 3, 3])], [], [np.array([1, 2]), np.array([0, 749])], [np.array([5])]]
    active = np.array([True, True, True, False])
    got = sync_regions(current, last, centres, 4, cells, active)
    for k in range(3):
        r, c = centres[k]
        extra = np.concatenate(cells[k]) if cells[k] else None
        want = _sync_reference(current[k], expected_last[k], (max(r - 4, 0), min(r + 5, 30)),
                               (max(c - 4, 0), min(c + 5, 25)), extra)
        assert got[k].tolist() == want.tolist() and len(want) > 0
    assert got[3] is None
    assert np.array_equal(last, expected_last) and not last[3].any()
    assert all(a.size == 0 for a in sync_regions(current, last, centres, 4, cells, active)[:3])


def test_sync_regions_flat_is_sync_regions_robot_after_robot() -> None:
    rng = np.random.default_rng(8)
    current = rng.integers(0, 3, size=(4, 30, 25), dtype=np.uint8)
    last_a, last_b = np.zeros_like(current), np.zeros_like(current)
    centres = np.array([[3, 5], [15, 12], [29, 24], [10, 3]])
    cells = [[np.array([700, 3])], [], [np.array([0, 749])], [np.array([5])]]
    active = np.array([True, False, True, True])
    per_map = sync_regions(current, last_a, centres, 3, cells, active)
    flat, ends = sync_regions_flat(current, last_b, centres, 3, cells, active)
    bounds = [0, *ends.tolist()]
    for k in range(4):
        got = flat[bounds[k]:bounds[k + 1]].tolist()
        assert got == (per_map[k].tolist() if active[k] else [])
    assert np.array_equal(last_a, last_b)


def test_empty_knowledge_and_counts() -> None:
    stack = empty_knowledge((3, 4), 2)
    assert stack.shape == (2, 3, 4) and stack.dtype == np.uint8 and stack.flags.c_contiguous
    stack[0, 0, :2] = FREE
    stack[1, 2, 3] = SOLID
    assert count_known(stack) == 3 and count_known(stack[0]) == 2
    assert count_cells(stack, FREE) == 2 and count_cells(stack, SOLID) == 1 and count_cells(stack, UNSEEN) == 21
    with pytest.raises(InvalidInput):
        count_cells(stack, 3)


# ------------------------------------------------------------------------------------------ log-odds
def test_classification_follows_eq8_with_thresholds() -> None:
    values = np.array([-1.0, -0.1, 0.0, 0.1, 2.0], dtype=np.float32)
    assert classify_logodds(values).tolist() == [FREE, FREE, UNSEEN, SOLID, SOLID]
    assert classify_logodds(values, occupied_above=1.0, free_below=-0.5).tolist() == [FREE, UNSEEN, UNSEEN,
                                                                                     UNSEEN, SOLID]


def test_logodds_grid_starts_at_the_prior_and_classifies_per_robot() -> None:
    grid = LogOddsGrid(2, (3, 3))
    assert grid.values.dtype == np.float32 and not grid.values.any() and grid.n_robots == 2
    grid.values[1, 0, 0] = 0.85
    grid.values[1, 2, 2] = -0.4
    assert grid.classify(0).tolist() == [[UNSEEN] * 3] * 3
    assert grid.classify(1)[0, 0] == SOLID and grid.classify(1)[2, 2] == FREE
    assert grid.classify().shape == (2, 3, 3)
    with pytest.raises(InvalidInput):
        LogOddsGrid(1, (3, 3), occupied_above=-1.0, free_below=0.0)


# ----------------------------------------------------------------------------------------- coverage
def test_coverage_marks_the_free_part_of_the_3x3_block_around_each_robot() -> None:
    solid = room(10, 10)
    solid[4, 5] = True
    truth = make_map(solid)
    tracker = ExplorationTracker(truth)
    assert tracker.coverage == 0.0 and tracker.explored == 0.0
    new = tracker.update_coverage(np.array([[2.4, 2.1]]))       # cell (4, 4): block rows 3..5, cols 3..5
    expected = np.zeros(truth.shape, dtype=bool)
    expected[3:6, 3:6] = True
    expected[4, 5] = False
    assert new == 8 and np.array_equal(tracker.covered, expected)
    assert tracker.coverage == 8 / truth.free_cells
    assert tracker.update_coverage(np.array([[2.4, 2.1], [2.3, 2.2]])) == 0   # nothing twice


def test_coverage_next_to_the_outer_wall_covers_only_free_cells() -> None:
    truth = make_map(room(8, 8))
    tracker = ExplorationTracker(truth)
    assert tracker.update_coverage(np.array([[0.6, 0.6]])) == 4     # cell (1, 1): only 2 x 2 of the block free
    assert not tracker.covered[truth.solid].any()


def test_inactive_robots_cover_nothing_and_bad_positions_are_refused() -> None:
    truth = make_map(room(10, 10))
    tracker = ExplorationTracker(truth)
    positions = np.array([[1.2, 1.2], [3.7, 3.7]])
    assert tracker.update_coverage(positions, active=np.array([False, True])) == 9
    assert not tracker.covered[2, 2]
    for bad in ([[1.0, 1.0], [5.0, 1.0]], [[1.0, 1.0], [np.nan, 1.0]], [[1.0, 1.0], [1.0, -0.01]]):
        with pytest.raises(InvalidInput) as err:
            tracker.update_coverage(np.array(bad))
        assert err.value.field == "positions[1]"
    assert tracker.covered_cells == 9
    with pytest.raises(InvalidInput):
        tracker.update_coverage(np.zeros((2, 3)))
    with pytest.raises(InvalidInput):
        tracker.update_coverage(positions, active=np.ones(3, bool))


def test_tracker_arrays_are_read_only_views() -> None:
    tracker = ExplorationTracker(make_map(room(6, 6)))
    with pytest.raises(ValueError):
        tracker.covered[2, 2] = True
    with pytest.raises(ValueError):
        tracker.seen[2, 2] = True


def test_active_flags() -> None:
    assert active_flags(3, None).tolist() == [True, True, True]
    assert active_flags(2, [1, 0]).tolist() == [True, False]


def test_sync_regions_flat_equals_the_window_rule_on_random_maps_and_windows() -> None:
    """The windows' scan skips rows whose 8-byte words are equal: the same cells as the plain rule, whatever
    the map width (rows not word-aligned, a tail after the last whole word) and wherever the windows are."""
    rng = np.random.default_rng(9)
    for rows, cols in ((30, 25), (17, 13), (40, 64), (3, 2)):
        current = rng.integers(0, 3, size=(5, rows, cols), dtype=np.uint8)
        last = current.copy()
        expected_last = current.copy()
        for _ in range(20):
            changes = rng.integers(0, current.size, size=int(rng.integers(0, 40)))
            current.reshape(-1)[changes] = rng.integers(0, 3, size=changes.size, dtype=np.uint8)
            centres = np.stack([rng.integers(-3, rows + 3, 5), rng.integers(-3, cols + 3, 5)], axis=1)
            reach = int(rng.integers(0, 6))
            cells = [[rng.integers(0, rows * cols, size=int(rng.integers(0, 3)))] if rng.random() < 0.3 else []
                     for _ in range(5)]
            active = rng.random(5) < 0.8
            flat, ends = sync_regions_flat(current, last, centres, reach, cells, active)
            bounds = [0, *ends.tolist()]
            for k in range(5):
                if not active[k]:
                    assert bounds[k] == bounds[k + 1]
                    continue
                r, c = centres[k]
                extra = np.concatenate(cells[k]) if cells[k] else None
                span = lambda at, size: (max(at - reach, 0), max(min(at + reach + 1, size), 0))  # noqa: E731
                want = _sync_reference(current[k], expected_last[k], span(r, rows), span(c, cols), extra)
                assert flat[bounds[k]:bounds[k + 1]].tolist() == want.tolist()
            assert np.array_equal(last, expected_last)


def test_sync_boxes_flat_finds_every_change_inside_the_boxes_and_the_listed_cells() -> None:
    """The boxes' scan (the runtime's per-robot box of lidar changes) against the plain rule: the cells
    that differ inside each clipped box or at its listed cells, copied into ``last``; inactive maps alone."""
    rng = np.random.default_rng(12)
    for rows, cols in ((30, 25), (17, 13), (3, 2)):
        current = rng.integers(0, 3, size=(4, rows, cols), dtype=np.uint8)
        last, expected_last = current.copy(), current.copy()
        for _ in range(30):
            changes = rng.integers(0, current.size, size=int(rng.integers(0, 30)))
            current.reshape(-1)[changes] = rng.integers(0, 3, size=changes.size, dtype=np.uint8)
            r0, c0 = rng.integers(-3, rows + 1, 4), rng.integers(-3, cols + 1, 4)
            boxes = np.stack([r0, r0 + rng.integers(-1, 8, 4), c0, c0 + rng.integers(-1, 8, 4)], axis=1)
            cells = [[rng.integers(0, rows * cols, size=int(rng.integers(0, 4)))] if rng.random() < 0.4 else []
                     for _ in range(4)]
            active = rng.random(4) < 0.8
            flat, ends = sync_boxes_flat(current, last, boxes, cells, active)
            bounds = [0, *ends.tolist()]
            for k in range(4):
                if not active[k]:
                    assert bounds[k] == bounds[k + 1]
                    continue
                clip = lambda a, b, size: (min(max(a, 0), size), max(min(b, size), 0))  # noqa: E731
                extra = np.concatenate(cells[k]) if cells[k] else None
                want = _sync_reference(current[k], expected_last[k], clip(boxes[k, 0], boxes[k, 1], rows),
                                       clip(boxes[k, 2], boxes[k, 3], cols), extra)
                assert flat[bounds[k]:bounds[k + 1]].tolist() == want.tolist()
            assert np.array_equal(last, expected_last)
    with pytest.raises(InvalidInput, match="boxes"):
        sync_boxes_flat(current, last, np.zeros((3, 4), np.int64), [[]] * 4, None)


def test_merge_cells_many_changed_lists_exactly_the_cells_each_merge_raised() -> None:
    rng = np.random.default_rng(5)
    stack = rng.integers(0, 3, size=(5, 12, 9), dtype=np.uint8)
    before = stack.copy()
    idx = np.sort(rng.choice(12 * 9, 40, replace=False)).astype(np.int64)
    values = rng.integers(0, 3, 40).astype(np.uint8)
    rows = np.array([3, 0, 4], dtype=np.int64)
    out, ends = np.empty(3 * 40, np.int64), np.empty(3, np.int64)
    merge_cells_many_changed(stack, rows, idx, values, out, ends)
    start = 0
    for k, row in enumerate(rows.tolist()):
        expected = before[row].copy().reshape(-1)
        expected[idx] = np.maximum(expected[idx], values)
        assert np.array_equal(stack[row].reshape(-1), expected)
        assert out[start:ends[k]].tolist() == np.flatnonzero(expected != before[row].reshape(-1)).tolist()
        start = ends[k]
    assert np.array_equal(stack[[1, 2]], before[[1, 2]])


def test_merge_cells_many_changed_counts_free_cells_as_the_counted_merge_does() -> None:
    """With ``freed`` the raised cells are listed as without it and each robot's count of FREE cells changes
    as :func:`merge_cells_many_counted` changes it (UNSEEN -> FREE adds one, FREE -> SOLID takes one)."""
    rng = np.random.default_rng(9)
    stack = rng.integers(0, 3, size=(6, 10, 11), dtype=np.uint8)
    idx = np.sort(rng.choice(10 * 11, 50, replace=False)).astype(np.int64)
    values = rng.integers(0, 3, 50).astype(np.uint8)
    rows = np.array([5, 1, 2], dtype=np.int64)
    robots = np.array([7, 0, 3], dtype=np.int64)  # the robot of each map need not be its row
    plain, counted, listed = stack.copy(), stack.copy(), stack.copy()
    want = np.full(8, 4, np.int64)
    merge_cells_many_counted(counted, rows, idx, values, robots, want)
    out, ends = np.empty(3 * 50, np.int64), np.empty(3, np.int64)
    merge_cells_many_changed(plain, rows, idx, values, out, ends)
    out2, ends2, got = np.empty(3 * 50, np.int64), np.empty(3, np.int64), np.full(8, 4, np.int64)
    merge_cells_many_changed(listed, rows, idx, values, out2, ends2, robots, got)
    assert np.array_equal(listed, counted) and np.array_equal(listed, plain)
    assert ends2.tolist() == ends.tolist() and out2[:ends[-1]].tolist() == out[:ends[-1]].tolist()
    assert got.tolist() == want.tolist()
    for k, row in enumerate(rows.tolist()):
        assert got[robots[k]] - 4 == int((listed[row] == FREE).sum()) - int((stack[row] == FREE).sum())
    assert (got != 4).any(), "some merge changed a count"
