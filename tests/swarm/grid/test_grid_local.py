"""The navigator's shortcuts to the whole-map plan, each checked against it bit for bit: local-first
planning (:mod:`swarm.grid.local`), which must also decide every short plan (else it saves nothing), and
the far target search's remembered path (:mod:`swarm.grid.memo`)."""

from __future__ import annotations

import numpy as np
import pytest

from maps import generate
from swarm import grid
from swarm.api import FREE, SOLID, UNSEEN
from swarm.grid import memo
from swarm.grid.local import PLAN_WINDOW_CELLS, erosion_depth, plan_local_first
from swarm.navigation.navigator import SNAP_RADIUS_CELLS


def whole_map_plan(known: np.ndarray, start: tuple[int, int], goal: tuple[int, int], radius: float, margin: float,
                   unseen_ok: bool) -> tuple[np.ndarray, bool, float] | None:
    """What the navigator does without the window: plan on the whole map's configuration space. Also
    returns the grid path's length in cells."""
    space = grid.configuration_space(known, radius, margin, unseen_ok)
    s = grid.nearest_in(space, start, SNAP_RADIUS_CELLS)
    g = grid.nearest_in(space, goal, SNAP_RADIUS_CELLS)
    path = None if s is None or g is None else grid.plan(space, s, g)
    if path is None:
        return None
    steps = np.abs(np.diff(path, axis=0)).sum(axis=1)
    cells = float(np.sum(steps == 1) + np.sqrt(2.0) * np.sum(steps == 2))
    return grid.simplify(space, path), bool(space[goal]), cells


def partly_known_building(seed: int) -> np.ndarray:
    """A building seen in patches: walls, free space, scattered and large unknown regions."""
    truth = generate("building", 60, seed)
    rng = np.random.default_rng(seed)
    known = np.where(truth.solid, SOLID, FREE).astype(np.uint8)
    known[rng.random(known.shape) < 0.03] = UNSEEN
    r, c = rng.integers(0, known.shape[0] - 30, size=2)
    known[r:r + 30, c:c + 30] = UNSEEN
    return known


@pytest.mark.parametrize("radius, margin, unseen_ok", [(0.3, 0.05, False), (0.3, 0.05, True), (0.6, 0.05, False),
                                                       (0.9, 0.1, True), (0.0, 0.0, False)])
def test_a_local_plan_is_the_whole_map_plan(radius: float, margin: float, unseen_ok: bool) -> None:
    must_decide = PLAN_WINDOW_CELLS - erosion_depth(radius, margin) - SNAP_RADIUS_CELLS - 2  # cells, with a margin
    decided = 0
    for seed in range(3):
        known = partly_known_building(seed)
        rng = np.random.default_rng(100 + seed)
        for _ in range(60):
            start = tuple(int(v) for v in rng.integers(0, known.shape[0], size=2))
            goal = tuple(int(v) for v in np.clip(np.array(start) + rng.integers(-38, 39, size=2), 0,
                                                 known.shape[0] - 1))
            local = plan_local_first(known, start, goal, radius, margin, unseen_ok, SNAP_RADIUS_CELLS)
            whole = whole_map_plan(known, start, goal, radius, margin, unseen_ok)
            if local is None:  # only plans that may leave the window's exact region go to the whole map
                assert whole is None or whole[2] > must_decide, (seed, start, goal)
                continue
            decided += 1
            assert whole is not None, (seed, start, goal)
            assert local[0].tobytes() == whole[0].tobytes(), (seed, start, goal)
            assert local[1] == whole[1]
    assert decided >= 10


def test_a_path_that_leaves_the_window_goes_to_the_whole_map() -> None:
    # A wall across the window with its gap far outside: the goal is near, its path is long.
    known = np.full((200, 200), FREE, dtype=np.uint8)
    known[100, :190] = SOLID
    start, goal = (95, 50), (105, 50)
    assert plan_local_first(known, start, goal, 0.3, 0.05, False, SNAP_RADIUS_CELLS) is None
    whole = whole_map_plan(known, start, goal, 0.3, 0.05, False)
    assert whole is not None and grid.path_length_m(whole[0]) > 60.0
    known[100, 60:64] = FREE  # a door nearby: now the window decides, and agrees
    local = plan_local_first(known, start, goal, 0.3, 0.05, False, SNAP_RADIUS_CELLS)
    whole = whole_map_plan(known, start, goal, 0.3, 0.05, False)
    assert local is not None and whole is not None
    assert local[0].tobytes() == whole[0].tobytes()


def test_a_larger_window_decides_a_longer_path_exactly() -> None:
    """On a large map a path too long for the first window is decided by a wider one (each twice as wide),
    bit for bit the whole map's; one too long for any window small enough to try is left to the whole map."""
    known = np.full((600, 600), FREE, dtype=np.uint8)
    known[300, 200:400] = SOLID
    start, goal = (295, 300), (305, 300)
    for gap, decided in ((270, True), (330, True), (230, False)):
        wall = known.copy()
        wall[300, gap:gap + 4] = FREE
        local = plan_local_first(wall, start, goal, 0.3, 0.05, False, SNAP_RADIUS_CELLS)
        whole = whole_map_plan(wall, start, goal, 0.3, 0.05, False)
        assert whole is not None
        assert (local is not None) == decided, gap
        if decided:
            assert local[0].tobytes() == whole[0].tobytes() and local[1] == whole[1]
            assert grid.path_length_m(whole[0]) > PLAN_WINDOW_CELLS * 0.5  # longer than the first window decides


def test_a_window_covering_the_whole_map_is_left_to_the_whole_map_plan() -> None:
    known = np.full((30, 30), FREE, dtype=np.uint8)
    assert plan_local_first(known, (5, 5), (20, 20), 0.3, 0.05, False, SNAP_RADIUS_CELLS) is None


def test_erosion_depth_follows_the_inflation_offsets() -> None:
    assert erosion_depth(0.3, 0.05) == 1
    assert erosion_depth(0.0, 0.0) == 0
    assert erosion_depth(0.6, 0.05) == 2


def brute_force_nearest(space: np.ndarray, cell: tuple[int, int], limit: int | None) -> tuple[int, int] | None:
    """The True cell nearest ``cell`` (squared distance, ties to the lowest row, then column), if within
    ``limit``."""
    rows, cols = np.nonzero(space)  # row-major: the first minimum is the lowest row, then column
    if rows.size == 0:
        return None
    d2 = (rows - cell[0]) ** 2 + (cols - cell[1]) ** 2
    i = int(np.argmin(d2))
    return None if limit is not None and d2[i] > limit * limit else (int(rows[i]), int(cols[i]))


@pytest.mark.parametrize("limit", [0, 1, 3, 4, 9, None, 10**12])
def test_nearest_in_is_the_nearest_cell_within_the_radius(limit: int | None) -> None:
    # nearest_in's compiled window search (grid_snap) serves the navigator, the target search and the
    # window kernels alike
    rng = np.random.default_rng(0 if limit is None else min(limit, 99))
    for _ in range(200):
        h, w = (int(v) for v in rng.integers(1, 25, size=2))
        space = rng.random((h, w)) < rng.uniform(0.0, 0.2)
        cell = (int(rng.integers(0, h)), int(rng.integers(0, w)))
        assert grid.nearest_in(space, cell, limit) == brute_force_nearest(space, cell, limit), (space.astype(int), cell)


@pytest.mark.parametrize("unseen_ok", [False, True])
def test_a_far_target_search_remembers_the_plan_to_its_target(unseen_ok: bool) -> None:
    params = (0.3, 0.05, unseen_ok)
    recalled = 0
    for seed in range(3):
        known = partly_known_building(seed)
        rng = np.random.default_rng(200 + seed)
        memo.forget_all()
        for cell in np.argwhere(known == FREE)[rng.choice(int(np.sum(known == FREE)), 25, replace=False)]:
            start = (int(cell[0]), int(cell[1]))
            found = grid.nearest_reachable_unseen(known, start, *params[:1], unseen_ok, margin_m=params[1],
                                                  local_first_m=None)
            entry = memo.recall(known, params, start, found[0]) if found is not None else None
            if entry is None:
                continue
            recalled += 1
            space = grid.configuration_space(known, *params)
            assert np.array_equal(entry.space, space)
            assert entry.start == grid.nearest_in(space, start, 3)
            expected = grid.plan(space, entry.start, entry.goal)
            assert expected is not None and entry.path.tobytes() == expected.tobytes(), (seed, start)
    assert recalled >= 40


def test_a_remembered_search_is_not_recalled_for_another_map_or_robot() -> None:
    memo.forget_all()
    known = partly_known_building(0)
    start = tuple(int(v) for v in np.argwhere(known == FREE)[0])
    found = grid.nearest_reachable_unseen(known, start, local_first_m=None)
    assert found is not None
    params = (0.3, 0.05, False)
    assert memo.recall(known.copy(), params, start, found[0]) is not None
    changed = known.copy()
    changed[changed == UNSEEN] = FREE
    assert memo.recall(changed, params, start, found[0]) is None            # the map has changed since
    assert memo.recall(known, (0.35, 0.05, False), start, found[0]) is None  # another robot size
    assert memo.recall(known, params, (start[0], start[1] + 1), found[0]) is None
    with pytest.raises(ValueError):
        memo.recall(known, params, start, found[0]).space[0, 0] = True      # shared with the navigator: read-only


@pytest.mark.parametrize("radius, unseen_ok", [(0.3, False), (0.3, True), (0.6, False), (0.0, False)])
def test_the_compiled_window_target_search_equals_the_whole_map_search(radius: float, unseen_ok: bool) -> None:
    local_hits = 0
    for seed in range(3):
        known = partly_known_building(seed)
        rng = np.random.default_rng(300 + seed)
        exclude = rng.random(known.shape) < 0.01    # given-up targets and frontiers, as the explorers pass
        free = np.argwhere(known == FREE)
        for cell in free[rng.choice(len(free), 30, replace=False)]:
            start = (int(cell[0]), int(cell[1]))
            for ex in (None, exclude):
                local = grid.nearest_reachable_unseen(known, start, radius, unseen_ok, ex)
                whole = grid.nearest_reachable_unseen(known, start, radius, unseen_ok, ex, local_first_m=None)
                assert local == whole, (seed, start)
                local_hits += local is not None and local[1] <= 15.0
    assert local_hits >= 20


def test_the_memo_holds_one_map_size_at_a_time() -> None:
    memo.forget_all()
    small, big = partly_known_building(0), partly_known_building(1)
    big = np.pad(big, 5, constant_values=SOLID)
    for known in (small, big):
        start = tuple(int(v) for v in np.argwhere(known == FREE)[0])
        found = grid.nearest_reachable_unseen(known, start, local_first_m=None)
        assert found is not None
        assert memo.recall(known, (0.3, 0.05, False), start, found[0]) is not None
    assert {entry.shape for entry in memo._MEMO.entries.values()} == {big.shape}


def test_nearest_reachable_by_windows_is_the_whole_map_search(monkeypatch: pytest.MonkeyPatch) -> None:
    """Random spaces and targets (sparse ones force the windows to grow; walls force detours that leave a
    window), random first windows: the answer, its length and the tie-break are the whole map's."""
    from swarm.grid import search

    rng = np.random.default_rng(0)
    grew = 0
    for _ in range(400):
        h, w = int(rng.integers(5, 160)), int(rng.integers(5, 160))
        space = rng.random((h, w)) < rng.uniform(0.55, 0.9)
        targets = rng.random((h, w)) < rng.choice([0.0005, 0.003, 0.03])
        start = (int(rng.integers(0, h)), int(rng.integers(0, w)))
        monkeypatch.setattr(search, "NEAREST_WINDOW_CELLS", 10**6)
        want = grid.nearest_reachable(space, start, targets)
        half = int(rng.integers(1, 30))
        monkeypatch.setattr(search, "NEAREST_WINDOW_CELLS", half)
        assert grid.nearest_reachable(space, start, targets) == want
        grew += want is not None and want[1] / 0.5 > half
    assert grew > 20, "the cases must include answers beyond the first window"


def test_nearest_reachable_window_decides_only_what_the_rest_of_the_map_cannot_change() -> None:
    """A target beyond a cut side is not the window's to decide; the same window with the side being the
    map's edge decides; a closed room decides None; a bad ``cut`` is one clear error."""
    from swarm.base.errors import InvalidInput

    space = np.ones((20, 20), bool)
    targets = np.zeros((20, 20), bool)
    targets[10, 0] = True      # 10 cells west: as far as the nearest cell beyond the east and south sides
    assert grid.nearest_reachable_window(space, (10, 10), targets, (True, True, True, True)) == (None, False)
    found, decided = grid.nearest_reachable_window(space, (10, 10), targets, (False, False, False, False))
    assert decided and found == ((10, 0), 5.0)
    targets[10, 12] = True                           # 2 cells away: nearer than every cut side
    assert grid.nearest_reachable_window(space, (10, 10), targets, (True, True, True, True)) == (((10, 12), 1.0), True)
    room = np.zeros((20, 20), bool)
    room[8:13, 8:13] = True                          # closed: the search ends before any cut side
    assert grid.nearest_reachable_window(room, (10, 10), targets & ~room, (True,) * 4) == (None, True)
    with pytest.raises(InvalidInput, match="cut"):
        grid.nearest_reachable_window(space, (10, 10), targets, (True, True))


def explored_corner(seed: int) -> tuple[np.ndarray, tuple[int, int]]:
    """A large map known only in a patch (a crowd that has explored a corner of a building), some with
    holes, and the known FREE cell nearest its centre to start from."""
    rng = np.random.default_rng(seed)
    truth = generate("building", 100, seed)
    known = np.zeros(truth.solid.shape, np.uint8)
    h, w = known.shape
    ph, pw = int(rng.integers(h // 5, h // 2)), int(rng.integers(w // 5, w // 2))
    r, c = int(rng.integers(0, h - ph)), int(rng.integers(0, w - pw))
    known[r:r + ph, c:c + pw] = np.where(truth.solid[r:r + ph, c:c + pw], SOLID, FREE)
    if seed % 4 == 0:  # holes: frontiers inside the patch too
        known[rng.random(known.shape) < 0.02] = UNSEEN
    free = np.argwhere(known == FREE)
    if not len(free):
        return known, (r, c)
    centre = np.array([r + ph // 2, c + pw // 2])  # the free cell nearest the patch's centre: far searches
    start = free[np.argmin(np.abs(free - centre).sum(axis=1))]
    return known, (int(start[0]), int(start[1]))


def swarm_sized_cache(monkeypatch: pytest.MonkeyPatch, shape: tuple[int, int]) -> np.ndarray:
    """Make the kept searches' cache hold one map and fill it with another map of ``shape``: what a swarm
    larger than the cache sees on every search (its map has no entry and one would evict another's).
    Returns that other map: keep it alive, or a new map may take its buffer, and with it its entry."""
    from swarm.grid import kept

    monkeypatch.setattr(kept, "MAX_ENTRIES", 1)
    kept.forget_all()
    other = np.zeros(shape, np.uint8)
    other[:6, :6] = FREE
    grid.nearest_reachable_unseen(other, (2, 2), local_first_m=None)
    return other


@pytest.mark.parametrize("radius, margin", [(0.3, 0.05), (0.6, 0.05), (0.0, 0.0)])
def test_a_far_search_in_a_swarm_runs_on_the_box_of_the_known_cells_with_the_whole_map_answer(
        radius: float, margin: float, monkeypatch: pytest.MonkeyPatch) -> None:
    """Patches of a large map, searched from inside (with and without an exclusion disc, some with no
    reachable frontier) by a swarm whose maps find nothing kept: a search no window decides runs on the box
    of the known cells and gives the whole-map target, distance and tie-break, and a plan no window decides
    runs on its box and is the whole-map plan, waypoint for waypoint."""
    from swarm.grid import kept, local, targets

    boxed = planned = 0
    for seed in range(40):
        known, start = explored_corner(seed)
        exclude = None
        if seed % 3 == 0:
            rr, cc = np.ogrid[:known.shape[0], :known.shape[1]]
            exclude = (rr - start[0]) ** 2 + (cc - start[1]) ** 2 <= int(seed % 7) ** 2
        want = grid.nearest_reachable_unseen(known, start, radius, exclude=exclude, margin_m=margin,
                                             local_first_m=None)
        box = local.known_box(known, (start,), 0)
        calls: list[tuple[int, int, int, int]] = []
        real = targets._TargetSearch.run_window

        def spy(self, k, bounds, s, ex, budget, real=real, calls=calls):
            calls.append(bounds)
            return real(self, k, bounds, s, ex, budget)

        other = swarm_sized_cache(monkeypatch, known.shape)
        monkeypatch.setattr(targets._TargetSearch, "run_window", spy)
        monkeypatch.setattr(targets, "WHOLE_MAP_SHARE", 0.0)  # only a first window, too small to decide
        monkeypatch.setattr(local, "LARGER_WINDOW_SHARE", 0.0)
        got = grid.nearest_reachable_unseen(known.copy(), start, radius, exclude=exclude, margin_m=margin,
                                            local_first_m=1.0)
        assert got == want, seed
        boxed += any(b[0] <= box[0] and b[1] >= box[1] and b[2] <= box[2] and b[3] >= box[3]
                     and (b[1] - b[0]) * (b[3] - b[2]) < known.size for b in calls)
        if want is not None:
            assert kept.rebuilds(known)
            plan = plan_local_first(known, start, want[0], radius, margin, False, SNAP_RADIUS_CELLS, half_cells=2,
                                    boxed=True)
            whole = whole_map_plan(known, start, want[0], radius, margin, False)
            assert (plan is None) == (whole is None)
            if plan is not None:
                assert np.array_equal(plan[0], whole[0]) and plan[1] == whole[1]
                planned += 1
        monkeypatch.undo()
        del other
    assert boxed >= 30, "most patches must be searched in their box"
    assert planned >= 20, "most patches must be planned in their box"


@pytest.mark.parametrize("case", ["swarm", "switched off", "team"])
def test_the_box_serves_only_a_swarm_whose_maps_find_nothing_kept(case: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """A far search (95 m through a walled hall in a large unknown map) runs on the box for a swarm; with
    ``BOXED`` off, or for a team whose maps keep their whole-map inputs (cheaper than a box built from
    scratch), it runs on the whole map, and the plan is the one that search remembered. Same answer."""
    from swarm.grid import kept, local, targets

    known = np.zeros((300, 300), np.uint8)
    known[100:141, 50:251] = SOLID
    known[101:140, 51:250] = FREE
    known[118:123, 250] = FREE  # the hall's one doorway, 190 cells east of the start
    start = (120, 55)
    want = grid.nearest_reachable_unseen(known.copy(), start, local_first_m=None)
    assert want is not None and want[1] > 90
    kept.forget_all()
    memo.forget_all()
    other = swarm_sized_cache(monkeypatch, known.shape) if case == "swarm" else None
    monkeypatch.setattr(targets, "BOXED", case != "switched off")
    monkeypatch.setattr(local, "BOXED", case != "switched off")
    ran: list[str] = []
    real_run = targets._TargetSearch.run

    def whole(self, *args, **kwargs):
        ran.append("whole")
        return real_run(self, *args, **kwargs)

    monkeypatch.setattr(targets._TargetSearch, "run", whole)
    assert grid.nearest_reachable_unseen(known, start) == want
    assert (ran == []) == (case == "swarm")
    remembered = memo.recall(known, (0.3, 0.05, False), start, want[0]) is not None
    assert remembered == (case != "swarm")
    assert kept.rebuilds(known) == (case == "swarm")
    assert (plan_local_first(known, start, want[0], 0.3, 0.05, False, SNAP_RADIUS_CELLS,
                             boxed=kept.rebuilds(known)) is not None) == (case == "swarm")
    del other


def test_known_box_holds_the_known_cells_and_the_given_ones() -> None:
    """Against numpy on random sparse maps of any size (rows of whole words or not), with extra cells and a
    margin clipped to the map; an empty map gives the extra cells' box."""
    from swarm.grid.local import known_box

    rng = np.random.default_rng(5)
    for _ in range(500):
        h, w = (int(v) for v in rng.integers(1, 45, 2))
        w = 8 * (w // 8 + 1) if rng.random() < 0.5 else w  # rows of whole words, or not
        k = np.zeros((h, w), np.uint8)
        for _ in range(int(rng.integers(0, 4))):
            k[rng.integers(h), rng.integers(w)] = rng.integers(1, 3)
        cell = (int(rng.integers(h)), int(rng.integers(w)))
        margin = int(rng.integers(0, 4))
        rows, cols = np.nonzero(k)
        rows, cols = np.append(rows, cell[0]), np.append(cols, cell[1])
        want = (max(rows.min() - margin, 0), min(rows.max() + 1 + margin, h),
                max(cols.min() - margin, 0), min(cols.max() + 1 + margin, w))
        assert known_box(k, (cell,), margin) == want
