"""Every tunable and every ambiguity of the BOA family as one validated, frozen parameter set.

Each field is one of the decisions in docs/boa.md section 6 (numbers in brackets below) or a paper
constant; the default is the recommended reading. ``"variant"`` means "what the variant's own definition
says" (see ``variants.py``).
"""

from __future__ import annotations

from dataclasses import dataclass

from swarm.api import check_bool, check_choice, check_float, check_int


@dataclass(frozen=True)
class BOAParams:
    """Parameters of one BOA-family optimiser run (the population size and generation budget are given to
    the engine separately, see ``engine.Optimizer``)."""

    # xBOA paper Eq. 1 / code defaults (params.yaml): sensor modality, power exponent, switch probability.
    c: float = 0.01
    a: float = 0.1
    p: float = 0.8
    mu: float = 2.0                   # ABOA's mu (section 3.4)
    # [1] switch convention: "paper" = global move / crossover when u < p (Algorithms 1 and 3, Arora's code);
    #     "code" = when u > p (the reference repository; Table 2 was tuned with it, so presets use it).
    switch: str = "paper"
    # [2] r factor: "variant" (r1*r2 for the paper-000 variants as coded, r**2 for IBOA-Levy, Kent chaos
    #     for IBOA-Kent) | "product" (r1*r2) | "square" (r**2) | "kent".
    r_mode: str = "variant"
    # [3] local move: "literal" x + (r * x_j - x_k) * f as every implementation codes Eq. 3 (default) |
    #     "difference" x + r * (x_j - x_k) * f, the textbook reading.
    local_form: str = "literal"
    # [4] j, k of the local move: "replace" (with replacement, may equal i or each other: code) |
    #     "distinct" (j != k, either may equal i: Arora's permutation).
    pairing: str = "replace"
    # [10] bounds rule after each move: "clip" (code's force_bounds) | "reflect".
    bounds_mode: str = "clip"
    # [5] True: one vectorised batch per generation (moves read the population at the generation start).
    #     False: per-individual order as in the reference code (later individuals see earlier updates).
    sync: bool = True
    # [6] acceptance of the local move: "variant" (xBOA: always, as the paper says, with the true fitness;
    #     others greedy) | "greedy" | "always". The reference code's stale-fitness bug is never reproduced.
    local_accept: str = "variant"
    # [9] what ABOA's sine rule drives: "c" (code, README) | "a" (the xBOA paper, section 3.3).
    aboa_target: str = "c"
    # [18] IBOA-Kent: Kent parameter u, chaotic fraction of the run, adaptive weight amplitude/power
    #      (sin^3 reading of Eq. 6), convex-lens scale eta (not given by the paper; 2 chosen, see engine).
    kent_u: float = 0.6
    kent_fraction: float = 1.0 / 3.0
    w_amplitude: float = 2.5
    w_power: float = 0.8
    eta: float = 2.0
    # [18] IBOA-Levy: Levy alpha and scale, "mantegna" (normal R1, R2) | "uniform" (the text's literal
    #      [0, 1] draws); which population member Eq. 5 multiplies ("j" as BOA, or "i" as printed);
    #      inertia weight bounds and acceleration (corrected Eq. 8).
    levy_alpha: float = 1.5
    levy_scale: float = 0.01
    levy_draw: str = "mantegna"
    levy_partner: str = "j"
    w_min: float = 0.4
    w_max: float = 0.95
    w_theta: float = 10.0
    # [18] IBOA-Levy inertia: "corrected" W_min (W_max/W_min)^(1/(1 + theta t/T)) (decreasing, the cited
    #      source) | "printed" Eq. 8 as printed (increases to ~2351; for reproduction only).
    inertia_form: str = "corrected"
    # SABOA global move: "fixed" (g* + f(x - g*)) | "code" (x + g* + f(x - g*), the reference's form).
    saboa_global: str = "fixed"
    # GA mutation per individual per generation (IBOA path planning, IBOA (Kent) section 4.1; operator not given):
    # "reset" = one gene redrawn uniformly in its bounds; "smooth" = one gene set to the mean of its
    # neighbouring genes (removes a detour when genes are consecutive waypoints).
    mutation_rate: float = 0.0
    mutation_kind: str = "reset"
    # [20] a generation "improves" when best < previous best - early_tol (0 reproduces the code).
    early_tol: float = 0.0

    def __post_init__(self) -> None:
        check_float("c", self.c, 0.0)
        check_float("a", self.a, 0.0)
        check_float("p", self.p, 0.0, 1.0)
        check_float("mu", self.mu, 0.0, lo_open=True)
        check_choice("switch", self.switch, ("paper", "code"))
        check_choice("r_mode", self.r_mode, ("variant", "product", "square", "kent"))
        check_choice("local_form", self.local_form, ("literal", "difference"))
        check_choice("pairing", self.pairing, ("replace", "distinct"))
        check_choice("bounds_mode", self.bounds_mode, ("clip", "reflect"))
        check_bool("sync", self.sync)
        check_choice("local_accept", self.local_accept, ("variant", "greedy", "always"))
        check_choice("aboa_target", self.aboa_target, ("c", "a"))
        check_float("kent_u", self.kent_u, 0.0, 1.0, lo_open=True, hi_open=True)
        check_float("kent_fraction", self.kent_fraction, 0.0, 1.0)
        check_float("w_amplitude", self.w_amplitude, 0.0)
        check_float("w_power", self.w_power, 0.0, lo_open=True)
        check_float("eta", self.eta, 0.0, lo_open=True)
        check_float("levy_alpha", self.levy_alpha, 0.0, 2.0, lo_open=True)
        check_float("levy_scale", self.levy_scale, 0.0, lo_open=True)
        check_choice("levy_draw", self.levy_draw, ("mantegna", "uniform"))
        check_choice("levy_partner", self.levy_partner, ("j", "i"))
        check_float("w_min", self.w_min, 0.0, lo_open=True)
        check_float("w_max", self.w_max, self.w_min)
        check_float("w_theta", self.w_theta, 0.0)
        check_choice("inertia_form", self.inertia_form, ("corrected", "printed"))
        check_choice("saboa_global", self.saboa_global, ("fixed", "code"))
        check_float("mutation_rate", self.mutation_rate, 0.0, 1.0)
        check_choice("mutation_kind", self.mutation_kind, ("reset", "smooth"))
        check_float("early_tol", self.early_tol, 0.0)


def check_budget(pop_size: int, max_gen: int, early_stop: int | None, max_fev: int | None) -> None:
    """Validate the run budget given to the engine."""
    check_int("pop_size", pop_size, 1, 1_000_000)
    check_int("max_gen", max_gen, 0, 10_000_000)
    if early_stop is not None:
        check_int("early_stop", early_stop, 1, 10_000_000)
    if max_fev is not None:
        check_int("max_fev", max_fev, 1)
