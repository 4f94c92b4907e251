"""One ask/tell engine for the whole BOA family, and ``minimize`` as a thin loop around it.

Design (docs/boa.md section 10): the caller evaluates whole batches (``fun_batch(X: (m, D)) -> (m,)``),
so the cost of a generation is one vectorised call; a best-so-far archive gives pygmo "champion"
semantics; the population's x and F are replaced together from copies, so the reference code's in-place
bug (x moved, fitness stale; section 1 item 2) cannot happen. No global RNG: every draw comes from the
``numpy.random.Generator`` passed in, so a seed gives bitwise-identical runs.

A generation (t = 1..T) in synchronous mode: draw the switch mask, r factors, partners and Levy steps for
all N individuals; build every candidate row (global/local trial, or the two crossover children, plus the
mBOA intensive trial or a mutation); evaluate them in one batch; per individual keep its best candidate
(ties: the earlier one, which makes crossover child 2 win ties and mBOA keep its BOA trial); accept it
greedily (strict <) or always (xBOA's local move, xBOA paper section 3.2); then, for IBOA-Kent, one more
batch with the convex-lens opposite of the best (replaces the best only if better); then the c/a
schedule. Asynchronous mode (``sync=False``) asks one individual at a time, so later individuals see
earlier ones' updates and the best, as the reference code's loop does.

Deliberate choices (decisions of section 6): moves read the *population* best g*, not the archive (they
are equal for greedy variants); the archive is updated from every evaluated row; the convex-lens scale
eta is not given by the IBOA (Kent) paper, we use 2 (a milder jump than classic OBL's eta = 1; section 12 test 9
checks both); the SABOA reference quirk that re-points the worst index at rejected trials is not
reproduced (the worst is always the population's worst).

Origin bias (docs/boa.md section 1 item 5), documented rather than tested: the terms r*g* - x,
r*x_j - x_k, SABOA's 0.5 (g* + x_worst) f, mBOA's g* (1 + r1 - r2) and IBOA-Levy's W x all contract towards
0, so on the *un-shifted* 10-D sphere (pop 20, 100 generations, code switch) this implementation reaches
exactly 0.0 with SABOA and 1e-111 to 1e-123 with mBOA, against about 0.01 with BOA. Tests use shifted
functions.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping

import numpy as np

from swarm.api import InvalidInput, from_mapping

from . import operators as op
from .draws import KentR, ProductR, RSource, SquareR, levy_steps
from .params import BOAParams, check_budget
from .schedules import aboa_value, arora_c, kent_weight, levy_inertia, levy_inertia_as_printed
from .variants import Variant, get_variant

FunBatch = Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True)
class Result:
    """What ``minimize`` returns: the archive's best pair and the run's accounting."""

    x: np.ndarray
    f: float
    nfev: int
    ngen: int
    history: np.ndarray          # best-so-far after the initial population and after each generation
    stop_reason: str             # "max_gen" | "early" | "max_fev"
    population: np.ndarray = field(repr=False)
    fitness: np.ndarray = field(repr=False)


@dataclass
class _Batch:
    """Candidates asked for ``rows`` of the population, and how to resolve them on ``tell``."""

    kind: str                    # "init" | "move" | "obl"
    rows: np.ndarray             # population rows concerned (n,)
    X: np.ndarray                # candidate rows (m, D)
    owner: np.ndarray            # (m,) position in ``rows`` each candidate belongs to
    rank: np.ndarray             # (m,) tie-break order among one owner's candidates (lower wins ties)
    greedy: np.ndarray           # (n,) accept only if strictly better than the stored fitness


def _check_bounds(bounds: Any) -> tuple[np.ndarray, np.ndarray]:
    b = np.asarray(bounds, dtype=float)
    if b.ndim != 2 or b.shape[1] != 2 or b.shape[0] < 1 or not np.isfinite(b).all() or (b[:, 0] > b[:, 1]).any():
        raise InvalidInput("bounds", bounds, "a sequence of (low, high) pairs, one per dimension, finite, low <= high")
    return b[:, 0].copy(), b[:, 1].copy()


def draw_partners(rng: np.random.Generator, rows: np.ndarray, n_pop: int) -> np.ndarray:
    """xBOA crossover partners: uniform over the population without the individual itself (j != i when
    N > 1; the code redraws until j != i, which is the same distribution). With N = 1 the partner is i."""
    if n_pop < 2:
        return np.asarray(rows).copy()
    j = rng.integers(0, n_pop - 1, len(rows))
    return j + (j >= rows)


def draw_cuts(rng: np.random.Generator, n: int, dim: int) -> np.ndarray:
    """Single-point crossover cuts, uniform in {1, ..., D-1} (always 1 for D = 2; 1 for D = 1, where the
    children are the two parents)."""
    return rng.integers(1, max(dim - 1, 1) + 1, n)


def _make_rsource(mode: str, params: BOAParams) -> RSource:
    if mode == "product":
        return ProductR()
    if mode == "square":
        return SquareR()
    return KentR(params.kent_u, params.kent_fraction)


class Optimizer:
    """Ask/tell BOA-family optimiser.

    >>> opt = Optimizer("xBOA", [(0, 23), (0, 23)], pop_size=20, max_gen=30, rng=np.random.default_rng(1))
    >>> while not opt.done:
    ...     X = opt.ask()
    ...     opt.tell(fun_batch(X))          # doctest: +SKIP

    ``ask`` returns the rows to evaluate now (the initial population first; then one generation's
    candidates in synchronous mode, or one individual's in asynchronous mode; then the OBL row for
    IBOA-Kent). ``tell`` takes their fitness (finite floats, minimised) in the same order.
    """

    def __init__(self, variant: str | Variant, bounds: Any, *, rng: np.random.Generator, pop_size: int = 20,
                 max_gen: int = 30, early_stop: int | None = 10, max_fev: int | None = None,
                 params: BOAParams | Mapping[str, Any] | None = None, x0: np.ndarray | None = None,
                 r_source: RSource | None = None) -> None:
        if not isinstance(rng, np.random.Generator):
            raise InvalidInput("rng", rng, "a numpy.random.Generator (no global RNG)")
        check_budget(pop_size, max_gen, early_stop, max_fev)
        if params is None:
            params = BOAParams()
        elif not isinstance(params, BOAParams):
            params = from_mapping(BOAParams, params)
        self.variant = get_variant(variant)
        self.params = params
        self.lb, self.ub = _check_bounds(bounds)
        self.dim = len(self.lb)
        self.pop_size = pop_size
        self.max_gen = max_gen
        self.early_stop = early_stop
        self.max_fev = max_fev
        self.rng = rng
        r_mode = self.variant.r_source if params.r_mode == "variant" else params.r_mode
        self.r_source = r_source if r_source is not None else _make_rsource(r_mode, params)
        self.local_accept = self.variant.local_accept if params.local_accept == "variant" else params.local_accept
        self.c = params.c
        self.a = params.a
        if x0 is not None:
            x0 = np.asarray(x0, dtype=float)
            if x0.shape != (pop_size, self.dim) or not np.isfinite(x0).all():
                raise InvalidInput("x0", x0.shape, f"a finite array of shape ({pop_size}, {self.dim})")
        self._x0 = x0
        self.X: np.ndarray | None = None
        self.F: np.ndarray | None = None
        self.best_x: np.ndarray | None = None
        self.best_f = np.inf
        self.nfev = 0
        self.gen = 0
        self.history: list[float] = []
        self.stop_reason: str | None = None
        self._pending: _Batch | None = None
        self._cursor = 0
        self._gen_start_best = np.inf
        self._stall = 0

    # ----------------------------------------------------------------- public protocol
    @property
    def done(self) -> bool:
        return self.stop_reason is not None

    def ask(self) -> np.ndarray:
        """The rows to evaluate now (a copy; changing it does not change the optimiser)."""
        if self.done:
            raise RuntimeError(f"the run has finished ({self.stop_reason})")
        if self._pending is None:
            if self.X is None:
                self._pending = self._initial()
            elif self._cursor < 0:
                self._pending = self._obl()
            else:
                rows = np.arange(self.pop_size) if self.params.sync else np.array([self._cursor])
                self._pending = self._propose(rows)
        return self._pending.X.copy()

    def tell(self, F: Any) -> None:
        """Fitness of the rows from the last ``ask``, same order."""
        batch = self._pending
        if batch is None:
            raise RuntimeError("tell() without a pending ask()")
        F = np.asarray(F, dtype=float).reshape(-1)
        if F.shape != (len(batch.X),) or not np.isfinite(F).all():
            raise InvalidInput("fitness", F.shape, f"{len(batch.X)} finite values, one per asked row")
        self._pending = None
        self.nfev += len(F)
        k = int(np.argmin(F))
        if F[k] < self.best_f:
            self.best_f = float(F[k])
            self.best_x = batch.X[k].copy()
        if batch.kind == "init":
            self.X = batch.X.copy()
            self.F = F.copy()
            self.history.append(self.best_f)
            self._check_stop()
            return
        if batch.kind == "obl":
            ib = int(batch.rows[0])
            if F[0] < self.F[ib]:
                self.X[ib] = batch.X[0]
                self.F[ib] = F[0]
            self._end_generation()
            return
        self._select(batch, F)
        if self.params.sync:
            self._after_moves()
        else:
            self._cursor += 1
            if self._cursor >= self.pop_size:
                self._after_moves()

    def result(self) -> Result:
        if self.best_x is None:
            raise RuntimeError("no evaluation yet")
        return Result(x=self.best_x.copy(), f=self.best_f, nfev=self.nfev, ngen=self.gen,
                      history=np.asarray(self.history), stop_reason=self.stop_reason or "running",
                      population=self.X.copy(), fitness=self.F.copy())

    # ----------------------------------------------------------------- generation pieces
    def _initial(self) -> _Batch:
        n, d = self.pop_size, self.dim
        X = self._x0.copy() if self._x0 is not None else self.lb + self.rng.random((n, d)) * (self.ub - self.lb)
        X = op.apply_bounds(X, self.lb, self.ub, self.params.bounds_mode)
        idx = np.arange(n)
        return _Batch("init", idx, X, idx, np.zeros(n, int), np.zeros(n, bool))

    def _bound(self, X: np.ndarray) -> np.ndarray:
        return op.apply_bounds(X, self.lb, self.ub, self.params.bounds_mode)

    def _propose(self, rows: np.ndarray) -> _Batch:
        v, prm, rng = self.variant, self.params, self.rng
        X, F = self.X, self.F
        N, D, n = self.pop_size, self.dim, len(rows)
        t, T = self.gen + 1, self.max_gen
        Xi = X[rows]
        g = X[int(np.argmin(F))]
        u = rng.random(n)
        is_global = u < prm.p if prm.switch == "paper" else u > prm.p
        if v.fragrance == "power":
            f = op.fragrance_power(F[rows], self.c, self.a)
        else:
            f = op.fragrance_saboa(rng.random(n), t, T)
        w = kent_weight(t, T, prm.w_amplitude, prm.w_power) if v.weight == "kent" else 1.0
        inertia = 1.0
        if v.weight == "levy":
            form = levy_inertia if prm.inertia_form == "corrected" else levy_inertia_as_printed
            inertia = form(t, T, prm.w_min, prm.w_max, prm.w_theta)
        r = self.r_source.factor(t, T, rows, N, rng) if v.global_move != "saboa" else np.zeros(n)
        j, k = self._pairs(n)

        if v.local_move == "boa":
            L = op.move_local(Xi, X[j], X[k], r, f, w, prm.local_form)
        elif v.local_move == "levy":
            steps = levy_steps(rng, (n, D), prm.levy_alpha, prm.levy_scale, prm.levy_draw)
            L = op.move_local_levy(Xi, X[j] if prm.levy_partner == "j" else Xi, X[k], steps, f)
        else:
            L = op.saboa_local(g, X[int(np.argmax(F))], f)

        cands, owner, rank = [], [], []
        if v.global_move == "crossover":
            partner = draw_partners(rng, rows, N)
            cut = draw_cuts(rng, n, D)
            c1, c2 = op.crossover(Xi, X[partner], cut)
            loc = np.flatnonzero(~is_global)
            glo = np.flatnonzero(is_global)
            cands += [self._bound(L[loc]), self._bound(c2[glo]), self._bound(c1[glo])]
            owner += [loc, glo, glo]
            rank += [np.zeros(len(loc), int), np.zeros(len(glo), int), np.ones(len(glo), int)]
        else:
            if v.global_move == "boa":
                G = op.move_global(Xi, g, r, f, w, inertia)
            else:
                G = op.saboa_global(Xi, g, f, prm.saboa_global)
            cands.append(self._bound(np.where(is_global[:, None], G, L)))
            owner.append(np.arange(n))
            rank.append(np.zeros(n, int))

        if v.post == "mboa":
            extra = np.flatnonzero(rng.random(n) < prm.p)
            r1, r2 = rng.random(n), rng.random(n)
            cands.append(self._bound(op.mboa_intensive(g, r1[extra], r2[extra])))
            owner.append(extra)
            rank.append(np.full(len(extra), 2))
        if prm.mutation_rate > 0:
            mut = np.flatnonzero(rng.random(n) < prm.mutation_rate)
            gene = rng.integers(0, D, n)[mut]
            value = self.lb[gene] + rng.random(n)[mut] * (self.ub - self.lb)[gene]
            if prm.mutation_kind == "smooth":
                value = op.neighbour_mean(Xi[mut], gene)
            cands.append(self._bound(op.random_reset(Xi[mut], gene, value)))
            owner.append(mut)
            rank.append(np.full(len(mut), 3))

        greedy = is_global | (self.local_accept == "greedy")
        return _Batch("move", rows, np.concatenate(cands), np.concatenate(owner), np.concatenate(rank), greedy)

    def _pairs(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        N = self.pop_size
        if self.params.pairing == "replace" or N < 2:
            jk = self.rng.integers(0, N, (2, n))
            return jk[0], jk[1]
        j = self.rng.integers(0, N, n)
        k = self.rng.integers(0, N - 1, n)
        return j, k + (k >= j)

    def _select(self, batch: _Batch, F: np.ndarray) -> None:
        order = np.lexsort((batch.rank, F, batch.owner))
        own_sorted = batch.owner[order]
        first = order[np.r_[True, own_sorted[1:] != own_sorted[:-1]]]
        own = batch.owner[first]
        rows = batch.rows[own]
        fbest = F[first]
        accept = ~batch.greedy[own] | (fbest < self.F[rows])
        self.X[rows[accept]] = batch.X[first[accept]]
        self.F[rows[accept]] = fbest[accept]

    def _after_moves(self) -> None:
        if self.variant.post == "obl":
            self._cursor = -1           # one more ask: the lens-opposite of the best
        else:
            self._end_generation()

    def _obl(self) -> _Batch:
        ib = int(np.argmin(self.F))
        x = op.convex_lens_opposite(self.X[ib], self.lb, self.ub, self.params.eta)
        return _Batch("obl", np.array([ib]), self._bound(x[None, :]), np.zeros(1, int), np.zeros(1, int),
                      np.ones(1, bool))

    def _end_generation(self) -> None:
        t, T = self.gen + 1, self.max_gen
        sched = self.variant.schedule
        if sched == "arora":
            self.c = arora_c(self.c, T)
        elif sched == "aboa":
            value = aboa_value(t, T, self.params.mu)
            if self.params.aboa_target == "c":
                self.c = value
            else:
                self.a = value
        self.gen = t
        self._cursor = 0
        improved = self.best_f < self._gen_start_best - self.params.early_tol
        self._stall = 0 if improved else self._stall + 1
        self.history.append(self.best_f)
        self._check_stop()

    def _check_stop(self) -> None:
        if self.early_stop is not None and self._stall >= self.early_stop:
            self.stop_reason = "early"
        elif self.max_fev is not None and self.nfev >= self.max_fev:
            self.stop_reason = "max_fev"
        elif self.gen >= self.max_gen:
            self.stop_reason = "max_gen"
        self._gen_start_best = self.best_f


def minimize(fun_batch: FunBatch, bounds: Any, *, rng: np.random.Generator, variant: str | Variant | None = None,
             preset: str | None = None, pop_size: int | None = None, max_gen: int = 30,
             early_stop: int | None = 10, max_fev: int | None = None, x0: np.ndarray | None = None,
             params: BOAParams | Mapping[str, Any] | None = None, **overrides: Any) -> Result:
    """Minimise ``fun_batch`` over the box ``bounds`` (one (low, high) pair per dimension).

    ``preset`` (e.g. ``"xBOA-pop20"``, see ``presets.py``) supplies the variant, population size and
    parameters; explicit ``variant``, ``pop_size``, ``params`` and keyword ``overrides`` (fields of
    :class:`BOAParams`) win over it. Without either, the variant is xBOA with the code defaults.
    """
    from .presets import get_preset

    base: dict[str, Any] = {}
    if preset is not None:
        pr = get_preset(preset)
        variant = variant if variant is not None else pr.variant
        pop_size = pop_size if pop_size is not None else pr.pop_size
        base = dict(pr.params)
    if params is not None:
        base.update(dataclasses.asdict(params) if isinstance(params, BOAParams) else dict(params))
    base.update(overrides)
    prm = from_mapping(BOAParams, base)
    opt = Optimizer(variant if variant is not None else "xBOA", bounds, rng=rng,
                    pop_size=pop_size if pop_size is not None else 20, max_gen=max_gen,
                    early_stop=early_stop, max_fev=max_fev, params=prm, x0=x0)
    while not opt.done:
        X = opt.ask()
        opt.tell(fun_batch(X))
    return opt.result()
