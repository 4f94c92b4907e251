"""Random factors of the BOA moves: the r-sources (r1*r2, r**2, Kent chaos) and Levy-flight steps.

Every draw comes from the ``numpy.random.Generator`` passed in; nothing here touches a global RNG.
References: docs/boa.md sections 3.1 (r), 3.6 (Kent map), 3.7 (Levy), decision 2 and 18.
"""

from __future__ import annotations

import math

import numpy as np

#: Mantegna's scale for alpha = 1.5 (IBOA (Lévy) Eq. 7): 0.6965745025576967.
LEVY_RHO_15 = 0.6965745025576967


def kent_map(r: np.ndarray | float, u: float = 0.6) -> np.ndarray:
    """One iteration of the skew-tent (Kent) map, IBOA (Kent) Eq. 5: ``r/u`` if ``r < u`` else ``(1-r)/(1-u)``.

    Deliberate departure from the extracted text, which lists the branches the other way round; read
    literally that leaves [0, 1] (0.2 -> 2.0). We use the standard skew-tent map (section 3.6):
    kent([0.12, 0.3, 0.6, 0.8, 0.9]) == [0.2, 0.5, 1.0, 0.5, 0.25]; fixed point 1 / (2 - u).
    """
    r = np.asarray(r, dtype=float)
    return np.where(r < u, r / u, (1.0 - r) / (1.0 - u))


def kent_step(state: np.ndarray, u: float, rng: np.random.Generator) -> np.ndarray:
    """Iterate the Kent map and reseed iterates that reached 0 or 1 (0 is absorbing, 1 maps to 0).

    The papers leave this open; reseeding from ``rng`` keeps every value strictly inside (0, 1).
    """
    nxt = kent_map(state, u)
    bad = (nxt <= 0.0) | (nxt >= 1.0)
    while bad.any():
        nxt[bad] = rng.random(int(bad.sum()))
        bad = (nxt <= 0.0) | (nxt >= 1.0)
    return nxt


def mantegna_rho(alpha: float) -> float:
    """IBOA (Lévy) Eq. 7: ``[G(1+a) sin(pi a / 2) / (G((1+a)/2) a 2^((a-1)/2))]^(1/a)``."""
    num = math.gamma(1.0 + alpha) * math.sin(math.pi * alpha / 2.0)
    den = math.gamma((1.0 + alpha) / 2.0) * alpha * 2.0 ** ((alpha - 1.0) / 2.0)
    return (num / den) ** (1.0 / alpha)


def levy_steps(rng: np.random.Generator, shape: tuple[int, ...], alpha: float = 1.5, scale: float = 0.01,
               draw: str = "mantegna") -> np.ndarray:
    """Levy-flight steps, IBOA (Lévy) Eq. 6: ``scale * R1 * rho / |R2| ** (1/alpha)``.

    ``draw="mantegna"`` (default, decision 18): R1, R2 ~ N(0, 1), the standard Mantegna algorithm with
    symmetric steps and tail index alpha. ``draw="uniform"``: the text's literal "random numbers in
    [0, 1]", which makes every step positive (mean about 0.0103 at scale 0.01). R2 is drawn from (0, 1] in
    that mode so a zero never divides.
    """
    rho = mantegna_rho(alpha)
    if draw == "mantegna":
        r1 = rng.standard_normal(shape)
        r2 = rng.standard_normal(shape)
    elif draw == "uniform":
        r1 = rng.random(shape)
        r2 = 1.0 - rng.random(shape)
    else:
        raise ValueError(f"unknown Levy draw {draw!r}")
    return scale * r1 * rho / np.abs(r2) ** (1.0 / alpha)


class RSource:
    """The random factor that multiplies g* (Eq. 2) and x_j (Eq. 3): one value per individual per move.

    Subclasses return the *factor* (already squared or multiplied), so moves never care how it was made.
    """

    def factor(self, t: int, max_gen: int, rows: np.ndarray, n_pop: int, rng: np.random.Generator) -> np.ndarray:
        raise NotImplementedError


class ProductR(RSource):
    """The reference code's ``r1 * r2`` (two independent U(0,1) draws; section 5 item 2)."""

    def factor(self, t, max_gen, rows, n_pop, rng):
        return rng.random(len(rows)) * rng.random(len(rows))


class SquareR(RSource):
    """The papers' ``r ** 2`` with one U(0,1) draw."""

    def factor(self, t, max_gen, rows, n_pop, rng):
        return rng.random(len(rows)) ** 2


class KentR(RSource):
    """IBOA-Kent's chaotic r (IBOA (Kent) section 3.1), squared as Eqs. 7/8 keep ``r**2``.

    Choices the paper leaves open (decision 18): the state is per individual; r0 ~ U(0, 1) from the
    generator at the first chaotic draw; iterates reaching 0 or 1 are reseeded; the chaotic r is used for
    generations ``t <= fraction * T`` (the "first 1/3 of the iterations") and plain ``r**2`` afterwards.
    """

    def __init__(self, u: float = 0.6, fraction: float = 1.0 / 3.0) -> None:
        self.u = u
        self.fraction = fraction
        self.state: np.ndarray | None = None

    def factor(self, t, max_gen, rows, n_pop, rng):
        if t <= self.fraction * max_gen:
            return self.chaotic(rows, n_pop, rng) ** 2
        return rng.random(len(rows)) ** 2

    def chaotic(self, rows: np.ndarray, n_pop: int, rng: np.random.Generator) -> np.ndarray:
        """Advance the Kent state of ``rows`` by one iteration and return the new r values."""
        if self.state is None:
            self.state = rng.random(n_pop)
            self.state = np.where(self.state <= 0.0, 0.5, self.state)
        self.state[rows] = kent_step(self.state[rows], self.u, rng)
        return self.state[rows].copy()
