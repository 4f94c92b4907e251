"""The xBOA paper's discrete world: 1 m cell truth grid, log-odds belief, noisy 180 degree lidar with votes.

The xBOA paper, sections 4.1 and 5.1-5.2; settings as reconstructed in docs/boa.md section 8.1 (decisions 14
and 15): range noise sigma = 0.05 * d on every beam that hits a wall (the paper's "95 % precision"); per
scan each beam votes "free" for the cells it crossed and "occupied" for the cell its measured end point
falls in, and per cell the majority of the scan's votes wins (plain end-point marking on 1 m cells walls
the robot in on its first scan). The winning update is +0.85 (occupied) or -0.4 (free) log-odds, clamped
at +-5; a tie changes nothing. A cell is occupied if its log-odds > 0, free if < 0, unknown if = 0 (Eq. 8).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from swarm.api import InvalidInput

from .beams import BeamTables

L_OCC, L_FREE, L_MAX = 0.85, -0.4, 5.0


def load_xboa_csv(path: str | Path) -> np.ndarray:
    """The paper's 0/1 CSV (1 = wall) as bool[rows, cols] at its own 1 m resolution, row index = y
    (row 0 at the bottom), exactly as stored. ``maps.io.import_csv`` gives the same map at 0.5 m cells."""
    try:
        rows = [line.strip() for line in Path(path).read_text(encoding="utf-8").splitlines() if line.strip()]
        grid = np.array([[int(v) for v in line.split(",")] for line in rows])
    except (OSError, ValueError) as exc:
        raise InvalidInput("map", str(path), f"a readable 0/1 CSV ({type(exc).__name__})") from None
    if grid.ndim != 2 or not np.isin(grid, (0, 1)).all():
        raise InvalidInput("map", str(path), "rows of equal length with 0/1 values")
    return grid.astype(bool)


def scan(truth: np.ndarray, logodds: np.ndarray, row: int, col: int, heading: int, tables: BeamTables,
         rng: np.random.Generator, noise: float, l_occ: float = L_OCC, l_free: float = L_FREE,
         l_max: float = L_MAX) -> None:
    """One noisy lidar scan from pose (row, col, heading) on ``truth``; updates ``logodds`` in place.

    Draws exactly one normal per beam from ``rng`` (so the noise stream does not depend on the map).
    """
    H, W = truth.shape
    beams = tables.fan[heading]
    rr = row + tables.ray_dr[beams]
    cc = col + tables.ray_dc[beams]
    entry = tables.ray_entry[beams]
    j = np.arange(rr.shape[1])[None, :]
    valid = (j < tables.ray_len[beams][:, None]) & (rr >= 0) & (rr < H) & (cc >= 0) & (cc < W)
    valid &= np.cumsum(~valid, axis=1) == 0
    rrc, ccc = np.clip(rr, 0, H - 1), np.clip(cc, 0, W - 1)
    wall = valid & truth[rrc, ccc]
    wall[:, 0] = False                                   # the robot's own cell
    has = wall.any(axis=1)
    first = np.argmax(wall, axis=1)
    d_true = entry[np.arange(len(beams)), first]
    z = rng.standard_normal(len(beams))
    d_meas = np.where(has, d_true * (1.0 + noise * z), np.inf)
    d_meas = np.maximum(d_meas, 0.0)
    hit = has & (d_meas < tables.range_cells)
    # the measured end point lies in the last cell entered at or before d_meas
    end = np.where(hit, (valid & (entry <= d_meas[:, None])).sum(axis=1) - 1, -1)
    end_ok = hit & (end >= 0) & (end < valid.sum(axis=1))
    free = valid & np.where(hit[:, None], j < end[:, None], True)
    flat = rr * W + cc
    free_votes = np.bincount(flat[free], minlength=H * W)
    occ_idx = flat[np.arange(len(beams))[end_ok], end[end_ok]]
    occ_votes = np.bincount(occ_idx, minlength=H * W)
    upd = np.where(occ_votes > free_votes, l_occ, np.where(free_votes > occ_votes, l_free, 0.0))
    lo = logodds.reshape(-1)
    lo += upd
    np.clip(lo, -l_max, l_max, out=lo)


def known_fraction(logodds: np.ndarray) -> float:
    """Exploration rate: cells with log-odds != 0 over all cells, walls included (the paper's k/576)."""
    return float(np.count_nonzero(logodds)) / logodds.size


def paper_map_path(name: str) -> Path | None:
    """Where the paper's ``map-<name>.csv`` is, if available: ``$XBOA_MAPS`` or ``../shared/data/xboa-maps``
    beside the repository (the CSVs are GPL-3.0 and deliberately not copied into this repository)."""
    import os

    roots = [Path(os.environ["XBOA_MAPS"])] if os.environ.get("XBOA_MAPS") else []
    roots.append(Path(__file__).resolve().parents[3] / "shared" / "data" / "xboa-maps")
    for root in roots:
        p = root / f"map-{name}.csv"
        if p.is_file():
            return p
    return None


def synthetic_house(size: int = 24) -> np.ndarray:
    """A small house-like test map (bool, True = wall) of our own: outer walls, rooms, 2-cell doors.

    Used where the paper's maps may be absent (CI); same size and wall density class as map-house.csv.
    """
    g = np.zeros((size, size), bool)
    g[0, :] = g[-1, :] = g[:, 0] = g[:, -1] = True
    m = size // 2
    g[m, 1:-1] = True
    g[m, 4:6] = g[m, m + 3:m + 5] = False           # doors in the middle wall
    g[1:m, m - 1] = True
    g[3:5, m - 1] = False
    g[m + 1:-1, m + 2] = True
    g[m + 6:m + 8, m + 2] = False
    g[m + 5, 1:6] = True
    g[m + 5, 3] = False
    return g
