"""Bearings between robots, one compiled definition for every transport.

The in-process transport gives algorithms lazily built :class:`~swarm.api.Neighbours` over a bearing
matrix; the zenoh transport packs each robot's neighbour records with bearings computed pair by pair. Both
call :func:`_bearing`, so a neighbour's bearing is the same bits whichever way it travels (numpy's
``arctan2`` could take a SIMD path on some machines that numba's ``atan2`` does not).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def _bearing(px: float, py: float, ptheta: float, qx: float, qy: float) -> float:  # pragma: no cover - compiled
    """Bearing of (qx, qy) from a robot at (px, py) heading ``ptheta``, in [-pi, pi)."""
    return (math.atan2(qy - py, qx - px) - ptheta + math.pi) % (2 * math.pi) - math.pi


@njit(cache=True)
def _bearing_matrix(poses: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover - compiled
    n = poses.shape[0]
    for i in range(n):
        for j in range(n):
            out[i, j] = _bearing(poses[i, 0], poses[i, 1], poses[i, 2], poses[j, 0], poses[j, 1])


def bearings(poses: np.ndarray) -> np.ndarray:
    """``b[i, j]``: bearing from robot i's heading to robot j (rad, in [-pi, pi)) for poses float64[R, 3]."""
    p = np.ascontiguousarray(poses, dtype=np.float64)
    out = np.empty((p.shape[0], p.shape[0]))
    _bearing_matrix(p, out)
    return out


@njit(cache=True)
def _bearing_pairs(poses: np.ndarray, row: int, cols: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover
    for k in range(cols.shape[0]):
        j = cols[k]
        out[k] = _bearing(poses[row, 0], poses[row, 1], poses[row, 2], poses[j, 0], poses[j, 1])


class BearingRows:
    """``bearings(poses)`` read as ``b[row, cols]`` without building the (R, R) matrix: each read computes
    only its pairs, with the same compiled definition (the same bits). A robot in a swarm reads the
    bearings of its few near neighbours; the whole matrix was R^2 arctangents a tick (issue 47)."""

    __slots__ = ("_poses",)

    def __init__(self, poses: np.ndarray) -> None:
        self._poses = np.ascontiguousarray(poses, dtype=np.float64)

    def __getitem__(self, key: tuple[int, np.ndarray]) -> np.ndarray:
        row, cols = key
        cols = np.asarray(cols, dtype=np.int64).reshape(-1)
        out = np.empty(cols.shape[0])
        _bearing_pairs(self._poses, int(row), cols, out)
        return out
