"""Vectorised move operators of the BOA family: each takes whole row blocks and returns new rows.

Pure functions of their inputs (random numbers are drawn by the caller), so the engine can batch a whole
generation and a test can check an operator on hand-made numbers. Equation numbers refer to
docs/boa.md section 3 and the papers cited there.
"""

from __future__ import annotations

import numpy as np


def fragrance_power(F: np.ndarray, c: float, a: float) -> np.ndarray:
    """xBOA paper Eq. 1 as coded: ``c * |F| ** a`` on the *stored*, raw fitness (decision 7).

    Raw, unnormalised fitness on purpose: Table 2 was tuned on it (section 1 item 3). F = 0 gives a zero
    step.
    """
    return c * np.abs(F) ** a


def fragrance_saboa(u: np.ndarray, t: int, max_gen: int) -> np.ndarray:
    """SABOA's self-adaptive fragrance ``u * (1 - t/T)``, u ~ U(0, 1) per individual (section 3.5)."""
    return u * (1.0 - t / max_gen)


def move_global(X: np.ndarray, g: np.ndarray, r: np.ndarray, f: np.ndarray, w: float = 1.0,
                inertia: float = 1.0) -> np.ndarray:
    """Towards the best: ``inertia * x + (r * w * g* - x) * f``.

    BOA Eq. 2 (w = inertia = 1), IBOA-Kent Eq. 7 (adaptive w), IBOA-Levy Eq. 9 (inertia W multiplies only x,
    not the bracket). ``r`` is the r-source factor (r1*r2, r**2 or chaotic r**2).
    """
    return inertia * X + (r[:, None] * w * g[None, :] - X) * f[:, None]


def move_local(X: np.ndarray, Xj: np.ndarray, Xk: np.ndarray, r: np.ndarray, f: np.ndarray,
               w: float = 1.0, form: str = "literal") -> np.ndarray:
    """Random walk, BOA Eq. 3 / IBOA-Kent Eq. 8: ``x + (r * w * x_j - x_k) * f``.

    ``form="literal"`` (default, decision 3): ``r * x_j - x_k`` as printed and as every implementation codes
    it; ``form="difference"``: ``r * w * (x_j - x_k)``, the textbook reading (no pull towards the origin).
    """
    if form == "difference":
        return X + r[:, None] * w * (Xj - Xk) * f[:, None]
    return X + (r[:, None] * w * Xj - Xk) * f[:, None]


def move_local_levy(X: np.ndarray, Xj: np.ndarray, Xk: np.ndarray, levy: np.ndarray, f: np.ndarray) -> np.ndarray:
    """IBOA-Levy Eq. 5: ``x + (Levy(D) * x_j - x_k) * f`` with a Levy step per gene (``levy`` shaped like X)."""
    return X + (levy * Xj - Xk) * f[:, None]


def saboa_global(X: np.ndarray, g: np.ndarray, f: np.ndarray, form: str = "fixed") -> np.ndarray:
    """SABOA global move (section 3.5).

    ``form="fixed"`` (default): ``g* + f * (x - g*)``, the probable intent of Fan et al. ``form="code"``:
    the reference code's ``x + g* + f * (x - g*)`` (almost surely a bug; kept for reproduction).
    """
    out = g[None, :] + f[:, None] * (X - g[None, :])
    return X + out if form == "code" else out


def saboa_local(g: np.ndarray, worst: np.ndarray, f: np.ndarray) -> np.ndarray:
    """SABOA local move as coded: ``0.5 * (g* + x_worst) * f`` (collapses to 0 when f = 0 at t = T)."""
    return 0.5 * (g[None, :] + worst[None, :]) * f[:, None]


def mboa_intensive(g: np.ndarray, r1: np.ndarray, r2: np.ndarray) -> np.ndarray:
    """mBOA "intensive exploitation" trial as coded: ``g* + (r1 - r2) * g*`` (section 3.3)."""
    return g[None, :] + (r1 - r2)[:, None] * g[None, :]


def crossover(Xi: np.ndarray, Xj: np.ndarray, cut: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """xBOA single-point crossover (xBOA paper Algorithm 2): ``child1 = [x_i[:cut], x_j[cut:]]``,
    ``child2 = [x_j[:cut], x_i[cut:]]``, one cut per row.

    Parents [1..5], [6..10], cut 2 -> [1, 2, 8, 9, 10] and [6, 7, 3, 4, 5].
    """
    head = np.arange(Xi.shape[1])[None, :] < np.asarray(cut)[:, None]
    return np.where(head, Xi, Xj), np.where(head, Xj, Xi)


def convex_lens_opposite(x: np.ndarray, lb: np.ndarray, ub: np.ndarray, eta: float) -> np.ndarray:
    """Convex-lens opposition-based learning, IBOA (Kent) Eq. 11: ``(ub+lb)/2 + (ub+lb)/(2 eta) - x/eta``.

    eta = 1 is classic OBL (lb + ub - x). lb = 0, ub = 10, x = 3 -> 7 (eta 1), 6 (eta 2). The result may
    leave the box; the engine applies its bounds rule afterwards.
    """
    mid = (ub + lb) / 2.0
    return mid + mid / eta - x / eta


def random_reset(X: np.ndarray, gene: np.ndarray, value: np.ndarray) -> np.ndarray:
    """GA random-reset mutation: row i gets gene ``gene[i]`` set to ``value[i]`` (IBOA (Kent) section 4.1)."""
    out = X.copy()
    out[np.arange(len(X)), gene] = value
    return out


def neighbour_mean(X: np.ndarray, gene: np.ndarray) -> np.ndarray:
    """Value of a smoothing mutation: the mean of gene ``gene[i]``'s neighbours in row i (one neighbour at
    the ends). For genes that are consecutive waypoints this straightens the path locally."""
    D = X.shape[1]
    rows = np.arange(len(X))
    lo = X[rows, np.maximum(gene - 1, 0)]
    hi = X[rows, np.minimum(gene + 1, D - 1)]
    lo = np.where(gene == 0, hi, lo)
    hi = np.where(gene == D - 1, lo, hi)
    return 0.5 * (lo + hi)


def apply_bounds(X: np.ndarray, lb: np.ndarray, ub: np.ndarray, mode: str = "clip") -> np.ndarray:
    """Keep rows inside [lb, ub]: ``clip`` (reference code's ``force_bounds``, default) or ``reflect``
    (mirror at the walls, periodic for overshoots of more than one box width)."""
    if mode == "clip":
        return np.clip(X, lb, ub)
    width = ub - lb
    safe = np.where(width > 0, width, 1.0)
    y = np.mod(X - lb, 2.0 * safe)
    y = np.where(y > safe, 2.0 * safe - y, y)
    return np.where(width > 0, lb + y, lb)
