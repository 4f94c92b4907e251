"""The compiled select and optimisation barrier: both give exactly the values of plain code."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from swarm.util.jitops import opaque, select


@njit(cache=False)
def _pick(cond: bool, a: float, b: float, i: int, j: int) -> tuple[float, int]:
    return select(cond, a, b), select(cond, i, j)


@njit(cache=False)
def _through(values: np.ndarray) -> np.ndarray:
    out = np.empty_like(values)
    for k in range(values.shape[0]):
        out[k] = opaque(values[k] + 0.0) - 0.0
    return out


def test_select_picks_the_first_value_when_true_and_the_second_when_false() -> None:
    assert _pick(True, 1.5, -2.0, 3, 4) == (1.5, 3)
    assert _pick(False, 1.5, -2.0, 3, 4) == (-2.0, 4)
    assert math.copysign(1.0, _pick(False, 0.0, -0.0, 0, 0)[0]) == -1.0


def test_opaque_changes_no_bit() -> None:
    values = np.array([0.0, -0.0, 1e-310, -3.25, math.inf, -math.inf, 1.0 / 3.0, 2.0 ** 1000])
    want = np.array([v + 0.0 - 0.0 for v in values.tolist()])
    assert np.array_equal(_through(values).view(np.uint64), want.view(np.uint64))
    assert math.isnan(_through(np.array([math.nan]))[0])
