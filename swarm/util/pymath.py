"""CPython's own float formulas, compiled, for kernels that must give the same bits as the Python code
they replace.

numba's ``math.hypot`` is the C library's ``hypot``; CPython's ``math.hypot`` and ``math.dist`` (3.10 and
3.11, ``vector_norm`` in ``Modules/mathmodule.c``) are its own algorithm: Veltkamp-Dekker squaring,
compensated sums, and one differential correction of the square root. The two differ in the last bit
for some inputs (``hypot(2.4, 5.76)``: 6.24 against 6.239999999999999), which is enough to change a run,
so compiled code uses the port below in their place. ``atan2``, ``sqrt``, ``cos`` and ``copysign`` need
no port: numba and CPython both call the C library for them (``sqrt`` is exact by IEEE 754).
``tests/swarm/util/test_pymath.py`` checks the port against ``math.hypot`` bit for bit on random and special
inputs under CPython 3.10 / 3.11 (this project's interpreter), and that it is correctly rounded on any.
CPython 3.12 rewrote ``vector_norm`` (fused multiply-add, two accumulators); there the port keeps 3.11's
bits, so the follower computes the same on every interpreter.
"""

from __future__ import annotations

import math

from numba import njit

_T27 = 134217729.0  # Veltkamp's constant 2**27 + 1


@njit(cache=True, inline="always")
def py_hypot(dx: float, dy: float) -> float:  # pragma: no cover - compiled
    """``math.hypot(dx, dy)`` (and ``math.dist`` of two 2-D points: the same norm of the differences)
    exactly as CPython 3.10 / 3.11 computes it, operation for operation."""
    a = abs(dx)
    b = abs(dy)
    mx = 0.0
    if a > mx:
        mx = a
    if b > mx:
        mx = b
    if math.isinf(mx):
        return mx
    if math.isnan(a) or math.isnan(b):
        return math.nan
    if mx == 0.0:
        return mx
    _, max_e = math.frexp(mx)
    csum = 1.0
    frac1 = 0.0
    frac2 = 0.0
    frac3 = 0.0
    if max_e < -1023:  # ldexp(1.0, -max_e) would overflow: divide by the maximum instead
        for v in (a, b):
            x = v / mx
            x = x * x
            old = csum
            csum += x
            frac1 += (old - csum) + x
        return mx * math.sqrt(csum - 1.0 + frac1)
    scale = math.ldexp(1.0, -max_e)
    for v in (a, b):
        x = v * scale
        t = x * _T27
        hi = t - (t - x)
        lo = x - hi
        x = hi * hi
        old = csum
        csum += x
        frac1 += (old - csum) + x
        x = 2.0 * hi * lo
        old = csum
        csum += x
        frac2 += (old - csum) + x
        frac3 += lo * lo
    h = math.sqrt(csum - 1.0 + (frac1 + frac2 + frac3))
    t = h * _T27
    hi = t - (t - h)
    lo = h - hi
    x = -hi * hi
    old = csum
    csum += x
    frac1 += (old - csum) + x
    x = -2.0 * hi * lo
    old = csum
    csum += x
    frac2 += (old - csum) + x
    x = -lo * lo
    old = csum
    csum += x
    frac3 += (old - csum) + x
    x = csum - 1.0 + (frac1 + frac2 + frac3)
    return (h + x / (2.0 * h)) / scale


__all__ = ["py_hypot"]
