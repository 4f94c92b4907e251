"""TNF's compiled scoring (algorithms.tnf_kernels, algorithms.tnf_utility) equals the numpy form it
replaced (tests/algorithms/tnf_oracle.py) bit for bit: frontier clusters, information gain, targets and
every utility term, on maps grown by random sequences of lidar writes and merges, in both variants, with
exclusions, size limits, destinations and sensed robots."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from algorithms.tnf_utility import (best_frontier, cell_information, frontier_targets, frontiers,
                                    score_frontiers)
from maps import generate
from swarm.api import FREE, SOLID, UNSEEN, grid

from . import tnf_oracle as oracle


def grown_map(seed: int, steps: int, size: int = 40) -> np.ndarray:
    """A robot's map after ``steps`` updates: lidar-like discs of truth around a wandering point, merges
    of another robot's scattered cells (cell-wise maximum) and now and then a FREE cell turned SOLID."""
    rng = np.random.default_rng(seed)
    truth = generate(("building", "cave")[seed % 2], size, seed).solid
    h, w = truth.shape
    known = np.zeros((h, w), np.uint8)
    rows, cols = np.indices((h, w))
    centre = rng.integers(0, (h, w))
    for _ in range(steps):
        centre = np.clip(centre + rng.integers(-8, 9, size=2), 0, (h - 1, w - 1))
        seen = (rows - centre[0]) ** 2 + (cols - centre[1]) ** 2 <= int(rng.integers(3, 16)) ** 2
        if rng.random() < 0.3:   # a merge: another robot's patch somewhere else
            other = rng.integers(0, (h, w))
            seen |= (rows - other[0]) ** 2 + (cols - other[1]) ** 2 <= int(rng.integers(2, 10)) ** 2
        seen &= rng.random((h, w)) < rng.choice([0.7, 1.0])   # rays that missed cells
        known = np.maximum(known, np.where(seen, np.where(truth, SOLID, FREE), UNSEEN).astype(np.uint8))
        if rng.random() < 0.2:
            free = np.flatnonzero(known == FREE)
            known.flat[rng.choice(free, min(3, free.size), replace=False)] = SOLID
    return known


def exclusion(known: np.ndarray, rng: np.random.Generator) -> np.ndarray | None:
    if rng.random() < 0.4:
        return None
    ex = np.zeros(known.shape, bool)
    for r, c in rng.integers(0, known.shape, size=(int(rng.integers(1, 4)), 2)):
        ex[max(r - 2, 0):r + 3, max(c - 2, 0):c + 3] = True
    return ex


def same_frontiers(a, b) -> None:
    for name in ("cells", "owner", "sizes", "representative"):
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype and np.array_equal(x, y), name


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10_000), steps=st.integers(1, 25), min_size=st.integers(1, 6))
def test_frontiers_and_information_equal_the_numpy_form(seed: int, steps: int, min_size: int) -> None:
    known = grown_map(seed, steps)
    ex = exclusion(known, np.random.default_rng(seed))
    ours, theirs = frontiers(known, ex, min_size), oracle.frontiers(known, ex, min_size)
    same_frontiers(ours, theirs)
    assert np.array_equal(cell_information(known, ours.cells), oracle.cell_information(known, theirs.cells))


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10_000), steps=st.integers(1, 25), reach=st.integers(0, 3))
def test_targets_equal_the_numpy_form(seed: int, steps: int, reach: int) -> None:
    known = grown_map(seed, steps)
    rng = np.random.default_rng(seed)
    ex = exclusion(known, rng)
    space = grid.configuration_space(known)
    cells = np.argwhere(space)
    if not len(cells):
        return
    here = tuple(int(v) for v in cells[rng.integers(len(cells))])
    fr = oracle.frontiers(known, ex)
    field = grid.distance_field(space, here)
    if ex is not None:
        field[ex] = np.inf
    want = oracle.targets_of(known, fr, field, reach)
    got, dist = frontier_targets(known, fr, space, here, reach, ex)
    assert np.array_equal(got, want)
    has = want[:, 0] >= 0
    assert np.array_equal(dist[has], field[want[has, 0], want[has, 1]])
    assert np.isinf(dist[~has]).all()


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10_000), steps=st.integers(1, 30), variant=st.sampled_from(["swarm", "maes"]),
       n_dest=st.integers(0, 5), beta=st.sampled_from([1.0, 8.0, 10.0]))
def test_scores_equal_the_numpy_form(seed: int, steps: int, variant: str, n_dest: int, beta: float) -> None:
    known = grown_map(seed, steps)
    rng = np.random.default_rng(seed)
    ex = exclusion(known, rng)
    free = np.argwhere(known == FREE)
    if not len(free):
        return
    start = tuple(int(v) for v in free[rng.integers(len(free))])
    dest = rng.integers(0, known.shape, size=(n_dest, 2))
    sensed = rng.uniform(0, 20, size=(n_dest, 2))
    kw = dict(alpha=1.0, beta=beta, robot_radius_m=0.3, penalty_radius_m=float(rng.choice([0.0, 3.0, 7.0])),
              reach=2, exclude=ex, min_size=int(rng.integers(1, 4)), variant=variant,
              position_m=(start[1] * 0.5 + 0.1, start[0] * 0.5 + 0.3), sensed_m=sensed)
    want = oracle.score_frontiers(known, start, dest, **kw)
    assert score_frontiers(known, start, dest, **kw) == want    # dataclass equality: every float exact
    assert best_frontier(known, start, dest, **kw) == (want[0] if want else None)


def test_clusters_touching_at_a_corner_and_at_the_map_edge() -> None:
    """Hand-made: two frontier runs meeting diagonally form one cluster; frontier cells on the map's
    border count (outside the map is not unseen)."""
    k = np.full((12, 12), FREE, np.uint8)
    k[0:3, 0:3] = UNSEEN          # frontier around the bottom-left corner, on the border
    k[6:9, 6:9] = UNSEEN          # a hole: frontier ring around it
    k[9, 9] = UNSEEN              # touches the ring's corner diagonally
    same_frontiers(frontiers(k), oracle.frontiers(k))
    assert frontiers(k).count == 2


@pytest.mark.parametrize("seed", range(4))
def test_field_at_equals_the_distance_field(seed: int) -> None:
    """Unbounded and bounded (searched per group of sources on windows), with limits just under a
    whole number of cells, sources in clumps and alone, cells near and far."""
    known = grown_map(seed, 30, size=60)
    rng = np.random.default_rng(seed)
    for open_ in (grid.configuration_space(known), known != SOLID):
        cells = np.argwhere(open_)
        sources = cells[rng.integers(len(cells), size=int(rng.integers(1, 16)))]
        at = np.concatenate((np.argwhere(np.ones(known.shape, bool))[rng.integers(known.size, size=50)],
                             np.clip(sources + rng.integers(-8, 9, size=sources.shape), 0, 119)))
        for limit in (None, 1.0, 3.0, 7.0 - 1e-10, 7.0, 10.0, 500.0):
            field = grid.distance_field(open_, sources, max_dist_m=limit)
            got = grid.field_at(open_, sources, at, max_dist_m=limit)
            assert got.dtype == np.float32 and np.array_equal(got, field[at[:, 0], at[:, 1]])
    assert grid.field_at(open_, sources, np.zeros((0, 2), np.int64)).shape == (0,)
