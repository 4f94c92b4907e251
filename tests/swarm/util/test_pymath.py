"""The compiled port of CPython's hypot must give the interpreter's bits, or compiled kernels that use it
(the waypoint follower) would change every run."""

from __future__ import annotations

import math
import sys
from decimal import Decimal, getcontext

import numpy as np
import pytest
from numba import njit

from swarm.util.pymath import py_hypot


@njit(cache=False)
def _hypots(a: np.ndarray, b: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover - compiled
    for i in range(a.shape[0]):
        out[i] = py_hypot(a[i], b[i])


def _same_bits(a: np.ndarray, b: np.ndarray) -> None:
    out = np.empty_like(a)
    _hypots(a, b, out)
    want = np.array([math.hypot(x, y) for x, y in zip(a.tolist(), b.tolist())])
    same = (out.view(np.int64) == want.view(np.int64)) | (np.isnan(out) & np.isnan(want))
    bad = np.flatnonzero(~same)[:5]
    assert same.all(), [(float(a[i]), float(b[i]), float(out[i]), float(want[i])) for i in bad]


CPYTHON_311 = pytest.mark.skipif(sys.version_info[:2] not in ((3, 10), (3, 11)),
                                 reason="the port is of CPython 3.10/3.11's vector_norm; 3.12 rewrote it")


@CPYTHON_311
@pytest.mark.parametrize("kind", ["metres", "grid", "exponents", "extremes"])
def test_py_hypot_equals_math_hypot_bit_for_bit(kind: str) -> None:
    rng = np.random.default_rng(["metres", "grid", "exponents", "extremes"].index(kind))
    n = 100_000
    if kind == "metres":      # what the follower sees: differences of positions on a 75 m map
        a, b = rng.uniform(-80, 80, n), rng.normal(0, 3, n)
    elif kind == "grid":      # short decimals, where a plain sqrt(a*a + b*b) is often one ulp off
        a, b = np.round(rng.normal(0, 20, n), 1), np.round(rng.normal(0, 20, n), 2)
    elif kind == "exponents":
        a = np.ldexp(rng.uniform(-1, 1, n), rng.integers(-80, 80, n))
        b = np.ldexp(rng.uniform(-1, 1, n), rng.integers(-80, 80, n))
    else:                     # subnormals to near overflow (CPython's divide-by-max branch included)
        a = np.ldexp(rng.uniform(0.5, 1, n), rng.integers(-1074, 1023, n))
        b = np.ldexp(rng.uniform(-1, 1, n), rng.integers(-1074, 1023, n))
    _same_bits(a, b)


@CPYTHON_311
def test_py_hypot_special_values() -> None:
    special = [0.0, -0.0, math.inf, -math.inf, math.nan, 5e-324, 2.2250738585072014e-308, 1.7976931348623157e308,
               1.0, -3.0, 2.4, 5.76]
    a, b = np.array([(x, y) for x in special for y in special]).T
    _same_bits(np.ascontiguousarray(a), np.ascontiguousarray(b))


def test_py_hypot_is_correctly_rounded() -> None:
    """On any interpreter: the port rounds the exact root correctly (checked with 60-digit decimals),
    as CPython's algorithm does for all but vanishingly rare inputs."""
    getcontext().prec = 60
    rng = np.random.default_rng(7)
    a, b = np.round(rng.normal(0, 20, 3000), 2), rng.uniform(-80, 80, 3000)
    out = np.empty_like(a)
    _hypots(a, b, out)
    for x, y, got in zip(a.tolist(), b.tolist(), out.tolist()):
        exact = (Decimal(x) ** 2 + Decimal(y) ** 2).sqrt()
        below, above = math.nextafter(got, 0.0), math.nextafter(got, math.inf)
        assert abs(Decimal(got) - exact) <= min(abs(Decimal(below) - exact), abs(Decimal(above) - exact))


@CPYTHON_311
def test_a_plain_sqrt_would_not_do() -> None:
    """The port is needed: on these inputs the naive formula (and the C library on some platforms)
    differs from CPython in the last bit."""
    assert math.hypot(2.4, 5.76) != math.sqrt(2.4 * 2.4 + 5.76 * 5.76)
    out = np.empty(1)
    _hypots(np.array([2.4]), np.array([5.76]), out)
    assert out[0] == math.hypot(2.4, 5.76)
