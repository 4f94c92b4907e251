"""Wall crossings: runs of solid cells, graze tolerance, boundaries, angles, and the fast walk's exactness."""

from __future__ import annotations

import math

import numpy as np
import pytest

from maps import generate
from radio import RadioConfig, build_link_model
from radio.blocks import uniform_blocks
from radio.crossings import WallRaster

from .plans import Plan, vertical_wall

TOL = 0.05


def walls(m, p, q, **config):
    return build_link_model(m, RadioConfig(**config)).trace(p, q)


def test_one_wall_of_each_material():
    for material in ("concrete", "wood", "brick"):
        crossed = walls(vertical_wall(material), (10.0, 20.25), (30.0, 20.25))
        # one 1 m wall at x in [20, 21): starts 10 m along the segment, 1 m of that material
        assert len(crossed) == 1
        assert crossed[0].start_m == pytest.approx(10.0) and crossed[0].end_m == pytest.approx(11.0)
        assert crossed[0].materials == ((material, pytest.approx(1.0)),)


def test_two_walls_and_a_run_through_two_materials():
    two = Plan(40, 40).wall(15, 0.5, 16, 39.5, "concrete").wall(25, 0.5, 26, 39.5, "wood").build()
    assert [w.materials[0][0] for w in walls(two, (10, 20.25), (30, 20.25))] == ["concrete", "wood"]
    # concrete [19, 20) touching wood [20, 21): one wall, charged as a crossing of each (15 + 6.7 dB)
    joined = Plan(40, 40).wall(19, 0.5, 20, 39.5, "concrete").wall(20, 0.5, 21, 39.5, "wood").build()
    (wall,) = walls(joined, (10, 20.25), (30, 20.25))
    assert wall.charged == ("concrete", "wood") and wall.db == pytest.approx(21.7)


def test_the_same_wall_at_every_angle_and_raster_offset_is_one_crossing():
    m = vertical_wall("concrete")
    model = build_link_model(m)
    for pivot in ((20.5, 20.0), (20.5, 20.13), (20.2, 20.25), (20.9, 20.4)):
        for degrees in (0, 15, 30, 45, 60, 75):
            a = math.radians(degrees)
            dx, dy = 8 * math.cos(a), 8 * math.sin(a)
            p, q = (pivot[0] - dx, pivot[1] - dy), (pivot[0] + dx, pivot[1] + dy)
            crossed = model.trace(p, q)
            # one wall, 1 m thick: 1 / cos(angle) metres of concrete, charged 15 dB whatever the angle
            assert len(crossed) == 1, (pivot, degrees)
            assert crossed[0].materials[0][1] == pytest.approx(1 / math.cos(a), abs=1e-9)
            assert crossed[0].db == 15.0


def test_corner_grazes_within_the_tolerance_are_ignored():
    pillar = Plan(40, 40).wall(20, 10, 21, 11, "brick").build()
    # lines y = x - 11 + c pass the pillar's lower-right corner (21, 10) and cut a chord of c * sqrt(2)
    for c, expected in ((-0.1, 0), (0.0, 0), (0.02, 0), (0.1, 1)):  # chords 0, 0, 0.028 (< 0.05), 0.141 m
        p, q = (15.0, 4.0 + c), (27.0, 16.0 + c)
        assert len(walls(pillar, p, q)) == expected, c


def test_gaps_within_the_tolerance_do_not_split_a_wall():
    # two brick blocks separated by a 0.5 m free column: crossed straight, that is 0.5 m of gap -> 2 walls
    m = Plan(40, 40).wall(20, 0.5, 21, 39.5, "brick").wall(21.5, 0.5, 22.5, 39.5, "brick").build()
    assert len(walls(m, (10, 20.25), (30, 20.25))) == 2
    # a tolerance is a strict bound: at 0.25 (the largest allowed) the 0.5 m gap still separates them
    assert len(walls(m, (10, 20.25), (30, 20.25), graze_tolerance_m=0.25)) == 2


def test_segments_along_a_wall_face_do_not_cross_it():
    block = Plan(40, 40).wall(20, 10, 30, 11, "concrete").build()
    # along the top face y = 11 and the bottom face y = 10 (a grid line of the wall's own cells): no wall
    assert walls(block, (15, 11.0), (35, 11.0)) == []
    assert walls(block, (15, 10.0), (35, 10.0)) == []
    # along the internal grid line y = 10.5: inside the wall for its whole 10 m length -> one wall
    (inside,) = walls(block, (15, 10.5), (35, 10.5))
    assert inside.materials == (("concrete", pytest.approx(10.0)),)
    # the same for vertical segments on the faces x = 20 and x = 30, and inside at x = 25
    assert walls(block, (20.0, 5), (20.0, 15)) == []
    assert walls(block, (30.0, 15), (30.0, 5)) == []
    assert len(walls(block, (25.0, 5), (25.0, 15))) == 1


def test_crossings_are_the_same_both_ways():
    m = generate("building", 40, seed=3)
    model = build_link_model(m)
    rng = np.random.default_rng(0)
    for _ in range(50):
        p, q = rng.uniform(1, 39, 2), rng.uniform(1, 39, 2)
        forward = model.crossings(p, q)
        backward = model.crossings(q, p)
        assert sorted(n for n, _ in forward) == sorted(n for n, _ in backward)
        assert sum(x for _, x in forward) == pytest.approx(sum(x for _, x in backward), abs=1e-9)


def _uniform(block: np.ndarray, v: int) -> bool:
    return block.size > 0 and bool((block == v).all())


def test_uniform_blocks_match_brute_force():
    rng = np.random.default_rng(1)
    mat = (rng.random((23, 31)) < 0.25).astype(np.uint8) * rng.integers(1, 3, (23, 31)).astype(np.uint8)
    mat[5:15, 3:20] = 0  # a room, so that some blocks are large
    blocks = uniform_blocks(mat)
    rows, cols = mat.shape
    for r in range(rows):
        for c in range(cols):
            v, k, wide, tall = (int(x) for x in blocks[0, r, c])
            assert v == mat[r, c]
            # the k x k square at (r, c) is one material, and the (k+1) square is not (or leaves the raster)
            assert _uniform(mat[r:r + k, c:c + k], v) and mat[r:r + k, c:c + k].shape == (k, k)
            bigger = mat[r:r + k + 1, c:c + k + 1]
            assert bigger.shape != (k + 1, k + 1) or not _uniform(bigger, v)
            # wide: the k-tall strip extends exactly `wide` cells along x; tall: the k-wide strip along y
            assert _uniform(mat[r:r + k, c:c + wide], v) and mat[r:r + k, c:c + wide].shape == (k, wide)
            assert c + wide == cols or not _uniform(mat[r:r + k, c:c + wide + 1], v)
            assert _uniform(mat[r:r + tall, c:c + k], v) and mat[r:r + tall, c:c + k].shape == (tall, k)
            assert r + tall == rows or not _uniform(mat[r:r + tall + 1, c:c + k], v)
    # quadrant 3 (-x, -y) is the mirrored programme: its blocks open down and to the left
    v, k, wide, tall = (int(x) for x in blocks[3, 12, 15])
    assert _uniform(mat[12 - k + 1:13, 15 - wide + 1:16], v) and k >= 5


def _reference_walls(m, p, q, tol=TOL, step=0.001):
    """Dense sampling every 1 mm: solid runs, gaps <= tol bridged, runs <= tol dropped."""
    n = max(2, int(math.hypot(q[0] - p[0], q[1] - p[1]) / step))
    t = (np.arange(n) + 0.5) / n
    x = p[0] + t * (q[0] - p[0])
    y = p[1] + t * (q[1] - p[1])
    solid = m.solid[(y / 0.5).astype(int), (x / 0.5).astype(int)]
    seg = math.hypot(q[0] - p[0], q[1] - p[1]) / n
    runs, gap, run, inside, margins = 0, 0.0, 0.0, False, []
    for s in solid:
        if s:
            if inside and gap:
                margins.append(abs(gap - tol))
            inside, gap, run = True, 0.0, (run if inside else 0.0) + seg
        elif inside:
            gap += seg
            if gap > tol:
                runs += run > tol
                margins.append(abs(run - tol))
                inside = False
    if inside:
        runs += run > tol
        margins.append(abs(run - tol))
    return runs, min(margins, default=1.0)


@pytest.mark.parametrize("kind, seed", [("building", 5), ("cave", 6)])
def test_walk_matches_dense_sampling(kind, seed):
    m = generate(kind, 30, seed=seed)
    raster = WallRaster.from_map(m)
    rng = np.random.default_rng(seed)
    checked = crossed = 0
    for _ in range(40):
        p, q = rng.uniform(0.6, 29.4, 2), rng.uniform(0.6, 29.4, 2)
        expected, margin = _reference_walls(m, p, q)
        if margin < 0.01:  # within sampling error of the tolerance: not a fair comparison
            continue
        start, _, _ = raster.trace(p, q, TOL)
        assert len(start) == expected, (p, q)
        checked += 1
        crossed += expected
    assert checked >= 30 and crossed >= 30  # most pairs were compared, and they crossed walls


@pytest.mark.parametrize("kind, seed", [("building", 11), ("cave", 12)])
def test_empty_space_skipping_changes_nothing(kind, seed):
    m = generate(kind, 60, seed=seed)
    fast, plain = WallRaster.from_map(m), WallRaster.from_map(m, skip_empty_space=False)
    rng = np.random.default_rng(seed)
    free = np.argwhere(m.free)
    xy = (free[rng.choice(len(free), 24)][:, ::-1] + rng.random((24, 2))) * 0.5
    cross = np.array([0.0, 15.0, 6.7, 5.5][:len(m.materials)] + [3.0] * max(0, len(m.materials) - 4))
    for per_metre in (False, True):
        a = fast.all_pairs(xy, TOL, cross, cross, per_metre)
        b = plain.all_pairs(xy, TOL, cross, cross, per_metre)
        assert np.array_equal(a[1], b[1]) and np.array_equal(a[3], b[3])
        assert np.allclose(a[2], b[2], rtol=0, atol=1e-9)
    assert a[1].sum() > 100  # the pairs do cross walls
