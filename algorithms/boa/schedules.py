"""Per-generation parameter schedules of the BOA family (docs/boa.md sections 3.1, 3.4, 3.6, 3.7, 3.9).

All are pure functions of the generation counter ``t`` (1-based, as the reference code's ``set_iter``) and
the planned number of generations ``T`` (``max_gen``, also when early stopping ends a run sooner:
decision 8 of docs/boa.md section 6).
"""

from __future__ import annotations

import math


def arora_c(c: float, max_gen: int) -> float:
    """One update of the sensor modality, xBOA paper Eq. 4 (Arora & Singh 2016): ``c + 0.025 / (c * T)``.

    The sign is plus (c grows), as in Arora's MATLAB code and the reference repository. From c0 = 0.01,
    T = 30: 0.0933333 after one update, 0.240522 after thirty. c = 0 (no fragrance at all) is kept as a
    fixed point instead of dividing by zero.
    """
    return c + 0.025 / (c * max_gen) if c > 0 else c


def aboa_value(t: int, max_gen: int, mu: float = 2.0, a0: float = 0.1, a1: float = 0.3) -> float:
    """Zhang et al.'s nonlinear rule as the reference code applies it after generation ``t`` (section 3.4).

    ``a0 - (a0 - a1) * sin(pi / mu * (t / T) ** 2)`` with the code's hard-coded a0 = 0.1, a1 = 0.3. With
    mu = 2 it rises from 0.1 to 0.3 at t = T (0.176537 at T/2); with mu = 1.356 (Table 2) it ends at 0.2469.
    The xBOA paper's section 3.3 says the rule drives the power exponent a; the code drives c (our default,
    ``BOAParams.aboa_target``).
    """
    return a0 - (a0 - a1) * math.sin(math.pi / mu * (t / max_gen) ** 2)


def levy_inertia(t: float, max_gen: int, w_min: float = 0.4, w_max: float = 0.95, theta: float = 10.0) -> float:
    """Nonlinear decreasing inertia weight of IBOA-Levy (IBOA (Lévy) Eq. 8, corrected; docs/boa.md section 3.7).

    Deliberate departure from the paper: Eq. 8 as printed, ``w_min * (w_max / w_min) ** ((1 + theta * t) / T)``,
    *increases* to about 2351 at t = T although the text calls it decreasing. We use the cited source's
    form (Chen Guimin et al. 2006), ``w_min * (w_max / w_min) ** (1 / (1 + theta * t / T))``:
    W(0) = 0.95, W(T) = 0.432724, strictly decreasing.
    """
    return w_min * (w_max / w_min) ** (1.0 / (1.0 + theta * t / max_gen))


def levy_inertia_as_printed(t: float, max_gen: int, w_min: float = 0.4, w_max: float = 0.95,
                            theta: float = 10.0) -> float:
    """IBOA (Lévy) Eq. 8 exactly as printed; kept only to document (and test) why it is not used."""
    return w_min * (w_max / w_min) ** ((1.0 + theta * t) / max_gen)


def kent_weight(t: float, max_gen: int, amplitude: float = 2.5, power: float = 0.8) -> float:
    """Adaptive weight of IBOA-Kent, IBOA (Kent) Eq. 6, read as ``2.5 * sin(pi/2 * (t/T) ** 0.8) ** 3``.

    The extracted text is garbled ("w = 2.5 ( sin ( pi 2 ( t N_iter ) 0.8 ) 3 )"); the cube reading gives
    w(0) = 0, w(T/2) = 1.2079, w(T) = 2.5. The other reading, ``sin(...) - 3``, gives w in [-7.5, -5] and
    is rejected as nonsensical (section 3.6).
    """
    return amplitude * math.sin(math.pi / 2.0 * (t / max_gen) ** power) ** 3
