"""swarm.grid: configuration space, plans, shortcuts, distance fields, frontiers, Greed targets.

Answers come from hand-made grids or from independent references (scipy's Dijkstra on an explicit
graph, exact segment-to-square geometry), never from the code under test.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from swarm import grid
from swarm.api import CELL_M, FREE, ROBOT_RADIUS_M, SOLID, UNSEEN
from swarm.base.errors import InvalidInput
from swarm.grid import kept
from swarm.grid.cspace import DEFAULT_MARGIN_M
from swarm.grid.targets import LOCAL_FIRST_M, default_view_reach_cells

SQRT2 = math.sqrt(2.0)
CELL = 0.5


# ------------------------------------------------------------------------------------------ helpers ----
def room(h: int, w: int) -> np.ndarray:
    """A knowledge map: FREE inside a one-cell SOLID ring."""
    k = np.full((h, w), SOLID, dtype=np.uint8)
    k[1:-1, 1:-1] = FREE
    return k


def from_rows(*rows: str) -> np.ndarray:
    """Build a bool mask from strings, first string = top row (so the picture reads north up)."""
    return np.array([[ch in "#1" for ch in row] for row in reversed(rows)], dtype=bool)


def random_known(rng: np.random.Generator, h: int, w: int, density: float) -> np.ndarray:
    k = np.where(rng.random((h, w)) < density, SOLID, FREE).astype(np.uint8)
    k[0, :] = k[-1, :] = k[:, 0] = k[:, -1] = SOLID
    return k


def random_space(rng: np.random.Generator, h: int, w: int, density: float) -> np.ndarray:
    """A random configuration space (blocks of blocked cells, so there are corridors and corners)."""
    coarse = rng.random(((h + 1) // 2, (w + 1) // 2)) < density
    blocked = np.kron(coarse, np.ones((2, 2), dtype=bool))[:h, :w]
    blocked |= rng.random((h, w)) < density / 4
    return ~blocked


def reference_distances(space: np.ndarray, sources: list[tuple[int, int]]) -> np.ndarray:
    """Octile shortest-path lengths (m) by scipy's Dijkstra on an explicit graph with the same rules."""
    h, w = space.shape
    idx = np.arange(h * w).reshape(h, w)
    rows, cols, weights = [], [], []
    for dr, dc in [(0, 1), (1, 0), (1, 1), (1, -1)]:
        a = np.zeros_like(space)
        r0, r1 = 0, h - dr
        c0, c1 = max(0, -dc), min(w, w - dc)
        ok = space[r0:r1, c0:c1] & space[r0 + dr:r1 + dr, c0 + dc:c1 + dc]
        if dr and dc:  # no corner cutting: both orthogonal cells free
            ok &= space[r0 + dr:r1 + dr, c0:c1] & space[r0:r1, c0 + dc:c1 + dc]
        a[r0:r1, c0:c1] = ok
        src = idx[r0:r1, c0:c1][ok]
        dst = idx[r0 + dr:r1 + dr, c0 + dc:c1 + dc][ok]
        cost = CELL * (SQRT2 if dr and dc else 1.0)
        rows += [src, dst]
        cols += [dst, src]
        weights += [np.full(src.size, cost), np.full(src.size, cost)]
    graph = coo_matrix((np.concatenate(weights), (np.concatenate(rows), np.concatenate(cols))),
                       shape=(h * w, h * w)).tocsr()
    d = dijkstra(graph, indices=[r * w + c for r, c in sources], min_only=True)
    d = d.reshape(h, w)
    d[~space] = np.inf
    return d


def octile_m(path: np.ndarray) -> float:
    steps = np.abs(np.diff(path, axis=0))
    return CELL * float(np.where(steps.sum(axis=1) == 2, SQRT2, 1.0).sum())


def assert_valid_path(space: np.ndarray, path: np.ndarray) -> None:
    assert space[path[:, 0], path[:, 1]].all(), "path leaves the space"
    steps = np.diff(path, axis=0)
    assert (np.abs(steps).max(axis=1) == 1).all(), "steps must be between 8-neighbours"
    for (r, c), (dr, dc) in zip(path[:-1], steps):
        if dr and dc:
            assert space[r + dr, c] and space[r, c + dc], f"diagonal step at {(r, c)} cuts a corner"


def blocked_boxes(space: np.ndarray) -> np.ndarray:
    """Squares (x0, y0, x1, y1) m of every cell not in ``space``, including a ring outside the map."""
    h, w = space.shape
    ring = np.ones((h + 2, w + 2), dtype=bool)
    ring[1:-1, 1:-1] = ~space
    r, c = np.nonzero(ring)
    r, c = r - 1, c - 1
    return np.column_stack((c * CELL, r * CELL, (c + 1) * CELL, (r + 1) * CELL)).astype(float)


def point_box_distance(p: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """(P, B) distances from points (P, 2) to boxes (B, 4)."""
    x, y = p[:, :1], p[:, 1:]
    dx = np.maximum(np.maximum(boxes[:, 0] - x, 0), x - boxes[:, 2])
    dy = np.maximum(np.maximum(boxes[:, 1] - y, 0), y - boxes[:, 3])
    return np.hypot(dx, dy)


def segment_box_distance(a: np.ndarray, b: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """(P, B) exact distances from segments a->b (P, 2 each) to boxes: 0 when they meet, otherwise the
    minimum over the segment's endpoints and the box's corners (disjoint convex sets)."""
    d = np.minimum(point_box_distance(a, boxes), point_box_distance(b, boxes))
    v = b - a
    vv = np.maximum((v * v).sum(axis=1, keepdims=True), 1e-300)
    for cx, cy in ((0, 1), (0, 3), (2, 1), (2, 3)):
        corner_x, corner_y = boxes[:, cx], boxes[:, cy]
        t = np.clip(((corner_x - a[:, :1]) * v[:, :1] + (corner_y - a[:, 1:]) * v[:, 1:]) / vv, 0, 1)
        d = np.minimum(d, np.hypot(a[:, :1] + t * v[:, :1] - corner_x, a[:, 1:] + t * v[:, 1:] - corner_y))
    lo, hi = np.zeros_like(d), np.ones_like(d)
    with np.errstate(divide="ignore", invalid="ignore"):
        for axis, (i0, i1) in enumerate(((0, 2), (1, 3))):
            va, pa = v[:, axis:axis + 1], a[:, axis:axis + 1]
            t0, t1 = (boxes[:, i0] - pa) / va, (boxes[:, i1] - pa) / va
            flat = va == 0
            inside = (boxes[:, i0] <= pa) & (pa <= boxes[:, i1])
            lo = np.maximum(lo, np.where(flat, np.where(inside, -np.inf, np.inf), np.minimum(t0, t1)))
            hi = np.minimum(hi, np.where(flat, np.where(inside, np.inf, -np.inf), np.maximum(t0, t1)))
    return np.where(lo <= hi, 0.0, d)


def centres(cells: np.ndarray) -> np.ndarray:
    return np.column_stack(((cells[:, 1] + 0.5) * CELL, (cells[:, 0] + 0.5) * CELL))


# ------------------------------------------------------------------------------ passable / C-space ----
def test_passable_pessimistic_and_optimistic() -> None:
    k = np.array([[UNSEEN, FREE, SOLID]], dtype=np.uint8)
    assert grid.passable(k).tolist() == [[False, True, False]]
    assert grid.passable(k, unseen_traversable=True).tolist() == [[True, True, False]]


def test_configuration_space_removes_cells_4_adjacent_to_an_obstacle_not_diagonal_ones() -> None:
    k = room(9, 9)
    k[4, 4] = SOLID
    expected = from_rows(
        ".........",
        ".........",
        "..#####..",
        "..##.##..",
        "..#...#..",
        "..##.##..",
        "..#####..",
        ".........",
        ".........",
    )
    assert (grid.configuration_space(k) == expected).all()


def test_configuration_space_needs_three_cell_corridors() -> None:
    k = np.full((9, 12), SOLID, dtype=np.uint8)
    k[1:4, 1:-1] = FREE      # 3 cells wide: one drivable row
    k[5:7, 1:-1] = FREE      # 2 cells wide: nothing drivable
    space = grid.configuration_space(k)
    assert space[2, 2:-2].all() and not space[1].any() and not space[3].any()
    assert not space[5:7].any()


def test_configuration_space_treats_outside_the_map_as_blocked_and_unseen_by_mode() -> None:
    k = np.full((5, 5), FREE, dtype=np.uint8)
    k[2, 4] = UNSEEN
    pess = grid.configuration_space(k)
    assert not pess[0].any() and not pess[:, 0].any()
    assert pess[2, 2] and not pess[2, 3]           # 4-adjacent to UNSEEN when pessimistic
    assert grid.configuration_space(k, unseen_traversable=True)[2, 3]


@pytest.mark.parametrize("radius, margin", [(0.3, 0.05), (0.3, 0.0), (0.2, 0.05), (0.45, 0.05), (0.6, 0.05)])
def test_configuration_space_cell_centres_keep_the_disc_clear(radius: float, margin: float) -> None:
    rng = np.random.default_rng(7)
    for _ in range(20):
        k = random_known(rng, 16, 16, rng.uniform(0.05, 0.3))
        k[rng.random(k.shape) < 0.05] = UNSEEN
        space = grid.configuration_space(k, radius_m=radius, margin_m=margin)
        cells = np.argwhere(space)
        if cells.size == 0:
            continue
        d = point_box_distance(centres(cells), blocked_boxes(grid.passable(k)))
        assert d.min() >= radius + margin - 1e-12


@pytest.mark.parametrize("radius, margin", [(0.3, 0.05), (0.0, 0.0), (0.1, 0.0), (0.45, 0.05), (1.0, 0.3), (2.0, 0.0)])
def test_configuration_space_is_exactly_the_erosion_by_the_inflation_offsets(radius: float, margin: float) -> None:
    """Not only safe (above) but not over-cautious: a passable cell is in the space iff no offset of
    inflation_offsets lands on a blocked or off-map cell. Tiny and thin maps included (runs wider than
    the map)."""
    rng = np.random.default_rng(5)
    offsets = grid.inflation_offsets(radius, margin)
    for _ in range(60):
        h, w = (int(v) for v in rng.integers(1, 21, 2))
        k = np.where(rng.random((h, w)) < rng.uniform(0.0, 0.3), SOLID, FREE).astype(np.uint8)  # open borders
        k[rng.random(k.shape) < 0.05] = UNSEEN
        for optimistic in (False, True):
            free = grid.passable(k, optimistic)
            expected = free.copy()
            for r, c in np.argwhere(free):
                expected[r, c] = all(0 <= r + dr < h and 0 <= c + dc < w and free[r + dr, c + dc]
                                     for dr, dc in offsets)
            assert np.array_equal(grid.configuration_space(k, radius, margin, optimistic), expected)


@pytest.mark.parametrize("radius, margin", [(0.3, 0.05), (0.3, 0.0), (0.2, 0.05), (0.45, 0.05), (0.6, 0.05)])
def test_segments_through_the_configuration_space_keep_the_disc_clear(radius: float, margin: float) -> None:
    """The waypoint follower drives straight between cell centres: every point of every segment that
    simplify may produce (supercover inside the space) must keep the disc off every wall."""
    rng = np.random.default_rng(11)
    checked = 0
    for _ in range(25):
        k = random_known(rng, 14, 14, rng.uniform(0.03, 0.25))
        space = grid.configuration_space(k, radius_m=radius, margin_m=margin)
        cells = np.argwhere(space)
        if len(cells) < 2:
            continue
        i, j = rng.integers(0, len(cells), size=(2, 600))
        a, b = cells[i], cells[j]
        clear = np.array([grid.segment_clear(space, tuple(p), tuple(q)) for p, q in zip(a, b)])
        if not clear.any():
            continue
        d = segment_box_distance(centres(a[clear]), centres(b[clear]), blocked_boxes(grid.passable(k)))
        assert d.min() >= radius + margin - 1e-9
        checked += int(clear.sum())
    assert checked > 1000


def test_inflation_offsets_default_is_the_cross() -> None:
    assert sorted(grid.inflation_offsets(0.3, 0.05)) == [(-1, 0), (0, -1), (0, 0), (0, 1), (1, 0)]


@pytest.mark.parametrize("kwargs", [{"radius_m": -0.1}, {"margin_m": float("nan")}, {"radius_m": "big"}])
def test_configuration_space_rejects_bad_lengths(kwargs: dict) -> None:
    with pytest.raises(InvalidInput):
        grid.configuration_space(room(5, 5), **kwargs)


@pytest.mark.parametrize("known", [np.zeros((3, 3), dtype=float), np.zeros(5, dtype=np.uint8),
                                   np.full((3, 3), 3, dtype=np.uint8)])
def test_bad_knowledge_maps_are_rejected(known: np.ndarray) -> None:
    with pytest.raises(InvalidInput):
        grid.configuration_space(known)


def test_vouched_runtime_view_is_not_rescanned_but_nothing_else_is_trusted() -> None:
    from swarm.grid._validate import check_known, vouch_known

    base = room(6, 6)
    view = base.view()
    view.flags.writeable = False
    assert vouch_known(view) is view
    base[2, 2] = 7  # only the owner can write behind the view; the mark means "not scanned again"
    assert check_known(view) is view
    for other in (view.copy(), base, base.view()):  # a copy or another view of the same memory is checked
        with pytest.raises(InvalidInput):
            check_known(other)
    view.flags.writeable = True  # a view made writable again is no longer vouched for
    with pytest.raises(InvalidInput):
        check_known(view)
    writable = room(4, 4)
    with pytest.raises(InvalidInput, match="read-only"):
        vouch_known(writable)
    bad = np.full((3, 3), 3, dtype=np.uint8)
    bad.flags.writeable = False
    with pytest.raises(InvalidInput):
        vouch_known(bad)


def test_new_zero_maps_are_vouched_for_without_a_scan_but_still_shape_checked() -> None:
    from swarm.grid._validate import check_known, vouch_known

    fresh = np.zeros((5, 7), dtype=np.uint8)
    view = fresh.view()
    view.flags.writeable = False
    assert vouch_known(view, trusted=True) is view and check_known(view) is view
    for bad in (np.zeros((5, 7), dtype=np.uint8), np.zeros(5, dtype=np.uint8), np.zeros((2, 2), dtype=np.int16)):
        with pytest.raises(InvalidInput, match="view"):
            vouch_known(bad, trusted=True)  # writable, not 2-D, not uint8: refused before anything is trusted


# -------------------------------------------------------------------------------------------- plan ----
def test_plan_in_open_space_has_the_octile_length() -> None:
    space = np.ones((20, 30), dtype=bool)
    rng = np.random.default_rng(1)
    for _ in range(50):
        s = tuple(int(v) for v in rng.integers(0, (20, 30)))
        g = tuple(int(v) for v in rng.integers(0, (20, 30)))
        path = grid.plan(space, s, g)
        assert path is not None
        assert tuple(path[0]) == s and tuple(path[-1]) == g
        dr, dc = abs(g[0] - s[0]), abs(g[1] - s[1])
        assert octile_m(path) == pytest.approx(CELL * (max(dr, dc) + (SQRT2 - 1) * min(dr, dc)), abs=1e-9)
        assert_valid_path(space, path)


def test_plan_around_a_wall_has_the_known_length() -> None:
    space = ~from_rows(   # '#' = blocked
        "#######",
        "#.....#",
        "#.###.#",
        "#.#.#.#",
        "#######",
    )
    assert grid.plan(space, (1, 3), (3, 3)) is None   # the pocket is closed; only corner gaps lead out
    path = grid.plan(space, (1, 1), (1, 5))
    assert path is not None
    # up, across, down: every diagonal shortcut would clip a '#' corner, so 8 straight steps = 4 m
    assert octile_m(path) == pytest.approx(4.0)
    assert path.tolist() == [[1, 1], [2, 1], [3, 1], [3, 2], [3, 3], [3, 4], [3, 5], [2, 5], [1, 5]]


def test_plan_never_cuts_a_corner() -> None:
    squeeze = ~from_rows(
        ".#",
        "#.",
    )
    assert grid.plan(squeeze, (0, 1), (1, 0)) is None   # only a diagonal squeeze between two blocked cells
    ring = np.ones((3, 3), dtype=bool)
    ring[1, 1] = False
    path = grid.plan(ring, (0, 0), (2, 2))
    assert path is not None
    assert_valid_path(ring, path)
    # every diagonal step here would touch the blocked centre: 4 straight steps
    assert octile_m(path) == pytest.approx(2.0)


def test_plan_returns_none_when_unreachable_or_outside_the_space() -> None:
    space = np.ones((5, 9), dtype=bool)
    space[:, 4] = False
    assert grid.plan(space, (2, 1), (2, 7)) is None
    assert grid.plan(space, (2, 4), (2, 1)) is None
    assert grid.plan(space, (2, 1), (2, 4)) is None
    same = grid.plan(space, (2, 1), (2, 1))
    assert same is not None and same.tolist() == [[2, 1]]


def test_plan_is_optimal_against_a_reference_dijkstra() -> None:
    rng = np.random.default_rng(3)
    for _ in range(15):
        space = random_space(rng, 30, 40, rng.uniform(0.1, 0.4))
        cells = np.argwhere(space)
        s = tuple(int(v) for v in cells[rng.integers(len(cells))])
        ref = reference_distances(space, [s])
        for g in cells[rng.integers(0, len(cells), 20)]:
            path = grid.plan(space, s, tuple(g))
            if math.isinf(ref[tuple(g)]):
                assert path is None
            else:
                assert path is not None
                assert_valid_path(space, path)
                assert octile_m(path) == pytest.approx(ref[tuple(g)], abs=1e-9)


def test_plan_is_deterministic() -> None:
    rng = np.random.default_rng(5)
    space = random_space(rng, 40, 40, 0.25)
    cells = np.argwhere(space)
    s, g = tuple(cells[0]), tuple(cells[-1])
    first = grid.plan(space, s, g)
    for _ in range(3):
        again = grid.plan(space.copy(), s, g)
        assert (first is None and again is None) or np.array_equal(first, again)


@pytest.mark.parametrize("start", [(-1, 0), (0, 99), (0.5, 1), "ab", (True, 0)])
def test_plan_rejects_bad_cells(start) -> None:
    with pytest.raises(InvalidInput):
        grid.plan(np.ones((5, 5), dtype=bool), start, (1, 1))


def test_plan_rejects_non_bool_space() -> None:
    with pytest.raises(InvalidInput):
        grid.plan(np.ones((5, 5), dtype=np.uint8), (0, 0), (1, 1))


# ---------------------------------------------------------------------------------------- simplify ----
def test_simplify_straight_and_l_shaped_paths() -> None:
    space = np.ones((5, 12), dtype=bool)
    path = grid.plan(space, (2, 0), (2, 11))
    assert grid.simplify(space, path).tolist() == [[0.25, 1.25], [5.75, 1.25]]
    ell = np.zeros((8, 8), dtype=bool)
    ell[1, 1:7] = True     # a 1-cell-wide L: along row 1, then up column 6
    ell[1:7, 6] = True
    path = grid.plan(ell, (1, 1), (6, 6))
    assert grid.simplify(ell, path).tolist() == [[0.75, 0.75], [3.25, 0.75], [3.25, 3.25]]


def test_segment_clear_tests_all_four_cells_at_a_corner() -> None:
    space = np.ones((3, 3), dtype=bool)
    assert grid.segment_clear(space, (0, 0), (2, 2))
    space[0, 1] = False    # the diagonal passes exactly through the corner this cell touches
    assert not grid.segment_clear(space, (0, 0), (2, 2))
    assert not grid.segment_clear(space, (2, 2), (0, 0))


def test_simplify_is_never_longer_and_stays_in_the_space() -> None:
    rng = np.random.default_rng(9)
    done = 0
    for _ in range(30):
        space = random_space(rng, 40, 50, rng.uniform(0.1, 0.35))
        cells = np.argwhere(space)
        s, g = (tuple(cells[i]) for i in rng.integers(0, len(cells), 2))
        path = grid.plan(space, s, g)
        if path is None:
            continue
        way = grid.simplify(space, path)
        assert way[0].tolist() == grid.cells_to_metres(path[:1])[0].tolist()
        assert way[-1].tolist() == grid.cells_to_metres(path[-1:])[0].tolist()
        assert grid.path_length_m(way) <= octile_m(path) + 1e-9
        kept = np.floor(way[:, ::-1] / CELL).astype(int)   # back to (row, col)
        for a, b in zip(kept[:-1], kept[1:]):
            assert grid.segment_clear(space, tuple(a), tuple(b))
        done += 1
    assert done >= 20


def test_simplify_rejects_broken_paths() -> None:
    space = np.ones((4, 4), dtype=bool)
    with pytest.raises(InvalidInput):
        grid.simplify(space, np.array([[0, 0], [2, 2]]))
    with pytest.raises(InvalidInput):
        grid.simplify(space, np.zeros((0, 2), dtype=int))


def test_path_length_m() -> None:
    assert grid.path_length_m(np.array([[0.0, 0.0], [3.0, 4.0], [3.0, 5.0]])) == pytest.approx(6.0)
    assert grid.path_length_m(np.array([[1.0, 2.0]])) == 0.0


# ---------------------------------------------------------------------------------- distance field ----
def test_distance_field_equals_plan_lengths() -> None:
    rng = np.random.default_rng(2)
    for _ in range(10):
        space = random_space(rng, 30, 30, rng.uniform(0.1, 0.4))
        cells = np.argwhere(space)
        s = tuple(int(v) for v in cells[rng.integers(len(cells))])
        field = grid.distance_field(space, s)
        assert field.dtype == np.float32 and field.shape == space.shape
        assert field[s] == 0.0
        for g in cells[rng.integers(0, len(cells), 25)]:
            path = grid.plan(space, s, tuple(g))
            if path is None:
                assert math.isinf(field[tuple(g)])
            else:
                assert field[tuple(g)] == pytest.approx(octile_m(path), rel=1e-6)
        assert np.isinf(field[~space]).all()


def test_distance_field_many_sources_and_bound() -> None:
    rng = np.random.default_rng(4)
    space = random_space(rng, 40, 40, 0.2)
    cells = np.argwhere(space)
    srcs = cells[rng.integers(0, len(cells), 4)]
    many = grid.distance_field(space, srcs)
    ref = reference_distances(space, [tuple(c) for c in srcs])
    assert np.allclose(many, ref, rtol=1e-6, equal_nan=False)
    each = np.min([grid.distance_field(space, tuple(c)) for c in srcs], axis=0)
    assert np.array_equal(many, each)
    bounded = grid.distance_field(space, srcs, max_dist_m=3.0)
    near = ref <= 3.0
    assert np.allclose(bounded[near], ref[near], rtol=1e-6)
    assert np.isinf(bounded[~near]).all()


def test_distance_field_ignores_sources_outside_the_space() -> None:
    space = np.ones((5, 5), dtype=bool)
    space[2, 2] = False
    assert np.isinf(grid.distance_field(space, (2, 2))).all()
    field = grid.distance_field(space, np.array([[2, 2], [0, 0]]))
    assert field[0, 0] == 0 and field[4, 4] == pytest.approx(CELL * (4 + 2 * SQRT2))  # 2 diagonals, 4 straight


def test_distance_field_rejects_bad_sources() -> None:
    with pytest.raises(InvalidInput):
        grid.distance_field(np.ones((3, 3), dtype=bool), np.array([[0, 5]]))
    with pytest.raises(InvalidInput):
        grid.distance_field(np.ones((3, 3), dtype=bool), (0, 0), max_dist_m=-1)


# ------------------------------------------------------------------------------ nearest_in / reach ----
def test_nearest_in_snaps_to_the_nearest_true_cell() -> None:
    space = np.zeros((9, 9), dtype=bool)
    assert grid.nearest_in(space, (4, 4)) is None
    space[4, 7] = True
    space[1, 4] = True      # 3 away, same as (4, 7): tie goes to the lower row
    assert grid.nearest_in(space, (4, 4)) == (1, 4)
    space[5, 5] = True
    assert grid.nearest_in(space, (4, 4)) == (5, 5)
    assert grid.nearest_in(space, (5, 5)) == (5, 5)
    assert grid.nearest_in(space, (8, 0), max_radius_cells=3) is None
    assert grid.nearest_in(space, (8, 0)) == (5, 5)


def test_nearest_in_matches_brute_force() -> None:
    rng = np.random.default_rng(6)
    for _ in range(200):
        space = rng.random((25, 31)) < rng.uniform(0.001, 0.05)
        cell = tuple(int(v) for v in rng.integers(0, (25, 31)))
        got = grid.nearest_in(space, cell)
        cells = np.argwhere(space)
        if len(cells) == 0:
            assert got is None
            continue
        d2 = ((cells - cell) ** 2).sum(axis=1)
        assert got == tuple(cells[np.argmin(d2)])   # argwhere is row-major: lowest row, then column


def test_nearest_reachable_goes_by_path_not_straight_line() -> None:
    space = np.ones((9, 12), dtype=bool)
    space[1:, 5] = False                        # a wall with a gap at the bottom row only
    targets = np.zeros_like(space)
    targets[8, 6] = True                        # 1 cell across the wall, 17 steps around
    targets[8, 0] = True                        # 6 cells away by line and by path
    cell, dist = grid.nearest_reachable(space, (8, 4), targets)
    assert cell == (8, 0) and dist == pytest.approx(CELL * 4)
    targets[8, 0] = False
    cell, dist = grid.nearest_reachable(space, (8, 4), targets)
    assert cell == (8, 6) and dist == pytest.approx(reference_distances(space, [(8, 4)])[8, 6])


def test_nearest_reachable_ties_and_failures() -> None:
    space = np.ones((5, 5), dtype=bool)
    targets = np.zeros_like(space)
    targets[0, 2] = targets[4, 2] = targets[2, 0] = True
    assert grid.nearest_reachable(space, (2, 2), targets) == ((0, 2), pytest.approx(1.0))
    space[:, 1] = False
    targets[:] = False
    targets[2, 0] = True
    assert grid.nearest_reachable(space, (2, 2), targets) is None
    assert grid.nearest_reachable(space, (2, 1), targets) is None


# ---------------------------------------------------------------------------------------- frontiers ----
def test_frontier_mask_uses_four_neighbours() -> None:
    k = np.full((5, 5), FREE, dtype=np.uint8)
    k[2, 2] = UNSEEN
    k[0, 0] = SOLID
    mask = grid.frontier_mask(k)
    assert np.argwhere(mask).tolist() == [[1, 2], [2, 1], [2, 3], [3, 2]]   # not the diagonals
    assert not grid.frontier_mask(np.full((4, 4), FREE, dtype=np.uint8)).any()   # map edge is not unseen
    rng = np.random.default_rng(4)
    for _ in range(40):  # 1 x 1 to 19 x 19, thin maps included
        h, w = (int(v) for v in rng.integers(1, 20, size=2))
        k = rng.integers(0, 3, (h, w)).astype(np.uint8)
        assert np.array_equal(grid.frontier_mask(k), frontier_brute(k))
        assert np.array_equal(grid.frontier_mask(k.astype(np.int16)), frontier_brute(k))  # any integer dtype


def test_frontier_clusters_on_a_hand_made_map() -> None:
    k = room(10, 12)
    k[1:9, 8:11] = UNSEEN         # an unseen block on the right: frontier is column 7, rows 1..8
    k[1, 1] = UNSEEN              # a single unseen cell in a corner: frontier (2,1) and (1,2)
    clusters = grid.frontier_clusters(k)
    assert [c.size for c in clusters] == [2, 8]
    corner, column = clusters
    assert corner.cells.tolist() == [[1, 2], [2, 1]]      # diagonal neighbours: one 8-connected cluster
    assert corner.centroid == pytest.approx((1.0, 1.0))
    assert corner.representative == (1, 2)                # both equally near; first in row-major order
    assert column.cells.tolist() == [[r, 7] for r in range(1, 9)]
    assert column.centroid == pytest.approx((3.75, 2.5))
    assert column.representative == (4, 7)                # rows 4 and 5 tie; first in row-major order
    assert [c.size for c in grid.frontier_clusters(k, min_size=3)] == [8]
    with pytest.raises(ValueError):
        column.cells[0, 0] = 99
    with pytest.raises(InvalidInput):
        grid.frontier_clusters(k, min_size=0)


# ---------------------------------------------------------------------------- nearest unseen (Greed) ----
def frontier_brute(known: np.ndarray) -> np.ndarray:
    """FREE cells with an UNSEEN 4-neighbour on the map, cell by cell."""
    h, w = known.shape
    out = np.zeros(known.shape, dtype=bool)
    for r in range(h):
        for c in range(w):
            out[r, c] = known[r, c] == FREE and any(
                0 <= r + dr < h and 0 <= c + dc < w and known[r + dr, c + dc] == UNSEEN
                for dr, dc in ((1, 0), (-1, 0), (0, 1), (0, -1)))
    return out


def view_cells_brute(known: np.ndarray, space: np.ndarray, reach: int) -> np.ndarray:
    """Configuration-space cells within ``reach`` 4-steps of a frontier through FREE cells (plain BFS)."""
    frontier = frontier_brute(known)
    out = np.zeros_like(space)
    h, w = known.shape
    for f in map(tuple, np.argwhere(frontier)):
        seen = {f: 0}
        queue = [f]
        while queue:
            cell = queue.pop(0)
            if space[cell]:
                out[cell] = True
            if seen[cell] == reach:
                continue
            for dr, dc in ((1, 0), (-1, 0), (0, 1), (0, -1)):
                n = (cell[0] + dr, cell[1] + dc)
                if 0 <= n[0] < h and 0 <= n[1] < w and known[n] == FREE and n not in seen:
                    seen[n] = seen[cell] + 1
                    queue.append(n)
    return out


def test_view_cells_matches_the_breadth_first_definition() -> None:
    rng = np.random.default_rng(13)
    for trial in range(40):
        h, w = (int(v) for v in rng.integers(1, 30, size=2))
        k = random_known(rng, h, w, rng.uniform(0.05, 0.3)) if min(h, w) > 2 else rng.integers(0, 3, (h, w)).astype(np.uint8)
        k[rng.random(k.shape) < 0.1] = UNSEEN
        reach = int(rng.integers(0, 4))
        everywhere = np.ones(k.shape, dtype=bool)
        assert np.array_equal(grid.view_cells(k, reach), view_cells_brute(k, everywhere, reach)), trial
    k = np.full((5, 7), FREE, dtype=np.uint8)
    k[:, 0] = UNSEEN
    exclude = np.zeros(k.shape, dtype=bool)
    exclude[:3, 1] = True                         # excluded frontier cells seed nothing, but may be passed
    got = grid.view_cells(k, 1, exclude)
    assert got[3:, 1].all() and got[3:, 2].all() and not got[:2, 2].any() and got[2, 1]


def test_nearest_reachable_unseen_prefers_path_distance_over_a_wall() -> None:
    k = np.full((14, 24), SOLID, dtype=np.uint8)
    k[1:13, 1:12] = FREE          # the robot's room
    k[1:13, 13:23] = UNSEEN       # behind the wall (column 12): nearest by straight line, unreachable
    k[11:13, 1:3] = UNSEEN        # far corner of the room: reachable
    start = (2, 10)
    found = grid.nearest_reachable_unseen(k, start)
    assert found is not None
    cell, dist = found
    assert cell[0] >= 8 and cell[1] <= 5, cell        # near the unseen corner, not by the wall
    space = grid.configuration_space(k)
    assert space[cell]
    field = grid.distance_field(space, start)
    views = view_cells_brute(k, space, reach=2)
    assert dist == pytest.approx(field[cell], rel=1e-6)
    assert dist == pytest.approx(field[views].min(), rel=1e-6)


def test_nearest_reachable_unseen_matches_brute_force_on_random_maps() -> None:
    rng = np.random.default_rng(12)
    compared = 0
    for _ in range(30):
        k = random_known(rng, 24, 24, rng.uniform(0.05, 0.2))
        k[rng.random(k.shape) < 0.08] = UNSEEN
        space = grid.configuration_space(k)
        cells = np.argwhere(space)
        if len(cells) == 0:
            continue
        start = tuple(int(v) for v in cells[rng.integers(len(cells))])
        views = view_cells_brute(k, space, reach=2)
        field = grid.distance_field(space, start)
        best = field[views].min() if views.any() else np.inf
        found = grid.nearest_reachable_unseen(k, start)
        if math.isinf(best):
            assert found is None
            continue
        cell, dist = found
        assert views[cell] and dist == pytest.approx(best, rel=1e-6)
        compared += 1
    assert compared >= 10


def test_nearest_reachable_unseen_target_is_drivable_and_sees_the_frontier() -> None:
    k = room(12, 12)
    k[5:7, 10] = UNSEEN           # a hole in the east wall
    cell, _ = grid.nearest_reachable_unseen(k, (5, 3))
    space = grid.configuration_space(k)
    frontier = grid.frontier_mask(k)
    assert space[cell] and not frontier[cell]            # the frontier itself is inflated space
    assert frontier[max(cell[0] - 2, 0):cell[0] + 3, max(cell[1] - 2, 0):cell[1] + 3].any()


def test_nearest_reachable_unseen_exclude_and_done() -> None:
    k = room(12, 20)
    k[5, 0] = UNSEEN               # not adjacent to FREE (wall between): no frontier
    k[6, 1] = UNSEEN               # west end
    k[6, 18] = UNSEEN              # east end
    start = (6, 5)
    cell, _ = grid.nearest_reachable_unseen(k, start)
    assert cell[1] <= 4
    exclude = np.zeros(k.shape, dtype=bool)
    exclude[:, :8] = True
    cell2, _ = grid.nearest_reachable_unseen(k, start, exclude=exclude)
    assert cell2[1] >= 14
    exclude[:] = True
    assert grid.nearest_reachable_unseen(k, start, exclude=exclude) is None
    assert grid.nearest_reachable_unseen(room(12, 20), start) is None


def test_nearest_reachable_unseen_snaps_a_start_in_inflated_space() -> None:
    k = room(12, 12)
    k[6, 10] = UNSEEN
    found = grid.nearest_reachable_unseen(k, (1, 1))      # next to the wall, outside the C-space
    assert found is not None
    snapped = grid.nearest_in(grid.configuration_space(k), (1, 1))
    from_snapped = grid.nearest_reachable_unseen(k, snapped)
    assert found[0] == from_snapped[0]
    assert found[1] == pytest.approx(from_snapped[1] + CELL * math.hypot(snapped[0] - 1, snapped[1] - 1))


def test_nearest_reachable_unseen_optimistic_mode_can_cross_unseen() -> None:
    k = room(10, 20)
    k[1:9, 9] = SOLID
    k[4:6, 9] = UNSEEN             # a gap in the wall seen as unknown
    k[1:9, 17:19] = UNSEEN         # unknown far side
    start = (5, 3)
    pess = grid.nearest_reachable_unseen(k, start)
    opt = grid.nearest_reachable_unseen(k, start, unseen_traversable=True)
    assert pess is not None and opt is not None
    assert pess[0][1] < 9                                  # looks at the gap from this side
    assert k[opt[0]] == FREE


def test_nearest_reachable_unseen_rejects_bad_exclude() -> None:
    with pytest.raises(InvalidInput):
        grid.nearest_reachable_unseen(room(6, 6), (2, 2), exclude=np.zeros((3, 3), dtype=bool))


def test_local_first_search_equals_the_whole_map_search():
    from maps import generate

    truth = generate("building", 100, 5)
    rng = np.random.default_rng(1)
    known = np.where(truth.solid, 2, 1).astype(np.uint8)
    hidden = rng.random(known.shape) < 0.02           # scattered unknown cells: near and far frontiers
    known[hidden] = 0
    known[:, 120:] = 0                                 # and a large unknown region far from some starts
    free = np.argwhere(known == 1)
    for cell in free[rng.choice(len(free), 40, replace=False)]:
        start = (int(cell[0]), int(cell[1]))
        assert grid.nearest_reachable_unseen(known, start) == grid.nearest_reachable_unseen(known, start,
                                                                                            local_first_m=None)


def test_a_target_just_past_the_local_window_is_not_missed():
    """The window must not settle for a target when a nearer one is hidden by its edge: an open room, the
    unknown beyond a column some 30 cells east of the start (its frontier at or past the window's edge),
    and a lone unknown cell at about the same distance elsewhere. A window of half-width 31 cells that
    accepted any target within 15 m answered 4 of these wrongly."""
    checked = 0
    for d in range(28, 37):
        for dr, dc in [(r, c) for r in range(-36, 37, 3) for c in range(-36, 1, 3) if 28 <= max(abs(r), abs(c))]:
            known = np.full((100, 120), FREE, np.uint8)
            start = (50, 40)
            known[:, start[1] + d:] = UNSEEN
            known[start[0] + dr, start[1] + dc] = UNSEEN
            kept.forget_all()  # no hint from an earlier map in this buffer: the window is tried
            whole = grid.nearest_reachable_unseen(known, start, local_first_m=None)
            assert grid.nearest_reachable_unseen(known, start) == whole, (d, dr, dc)
            checked += whole is not None and whole[1] <= LOCAL_FIRST_M
    assert checked >= 500  # most answers lie within the window's length: the window decided them


def test_a_map_remembers_the_window_that_decided_its_last_search_and_still_gets_the_whole_map_answer():
    kept.forget_all()
    known = np.full((100, 120), FREE, np.uint8)
    known[:, 110:] = UNSEEN
    starts = [(50, 10), (50, 100), (50, 101), (20, 15), (80, 98)]   # far, near, near, far, near
    key = kept.key_of(known, ROBOT_RADIUS_M, DEFAULT_MARGIN_M, False,
                      default_view_reach_cells(ROBOT_RADIUS_M, DEFAULT_MARGIN_M))
    hints = []
    for start in starts:
        got = grid.nearest_reachable_unseen(known, start)
        assert got == grid.nearest_reachable_unseen(known, start, local_first_m=None)
        hints.append(kept.last_budget(key))
    first = int(LOCAL_FIRST_M / CELL_M)
    assert hints == [kept.WHOLE_MAP, first, first, kept.WHOLE_MAP, first]


@pytest.mark.parametrize("level", [1, 2, 3])
def test_a_target_just_past_a_larger_window_is_not_missed(level):
    """The larger windows of a search on a large map (each decides searches twice as long as the one before)
    must not settle for a target when a nearer one is hidden by their edge either: unknown beyond a column
    about one window's budget east of the start, and a lone unknown cell at about the same distance."""
    budget = int(LOCAL_FIRST_M / CELL_M) * 2 ** level
    checked = 0
    for d in range(budget - 3, budget + 6, 2):
        for dr, dc in [(-d + 1, -d + 2), (d - 2, -d + 1), (0, -d), (d, 0), (-d, -2)]:
            known = np.full((1200, 1200), FREE, np.uint8)
            start = (600, 500)
            known[:, start[1] + d:] = UNSEEN
            known[start[0] + dr, start[1] + dc] = UNSEEN
            kept.forget_all()  # no hint from an earlier map in this buffer: every window is tried
            whole = grid.nearest_reachable_unseen(known, start, local_first_m=None)
            assert grid.nearest_reachable_unseen(known, start) == whole, (d, dr, dc)
            checked += whole is not None
    assert checked == 25
