"""Brent's root finder and bounded minimiser (shimmy.continuation.scalar) against closed-form
answers and against scipy.optimize's brentq and fminbound on the same functions."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq, fminbound

from shimmy.continuation.errors import ConvergenceError, InvalidInputError
from shimmy.continuation.scalar import minimum_in, root_in

ROOTS = [  # f, bracket, the zero
    (lambda x: x * x - 2.0, (0.0, 2.0), math.sqrt(2.0)),
    (lambda x: math.cos(x) - x, (0.0, 1.0), 0.7390851332151607),
    (lambda x: (x - 1.0) ** 3, (-2.0, 3.5), 1.0),  # a triple zero: flat, slow for interpolation
    (lambda x: math.exp(x) - 1e-3, (-20.0, 5.0), math.log(1e-3)),
    (lambda x: math.atan(50.0 * (x - 0.3)), (-1.0, 1.0), 0.3),
    (lambda x: x ** 9, (-1.0, 0.5), 0.0),
    (lambda x: 1e-12 * (x - 7.25), (0.0, 100.0), 7.25),  # tiny values
    (lambda x: -1.0 if x < 0.123456789 else 1.0, (0.0, 1.0), 0.123456789),  # a jump: bisection's case
]


@pytest.mark.parametrize("k", range(len(ROOTS)))
@pytest.mark.parametrize("xtol", [1e-12, 1e-9, 1e-5])
def test_roots_within_the_tolerance_as_scipys_brentq(k, xtol):
    f, (a, b), zero = ROOTS[k]
    x = root_in(f, a, b, xtol=xtol)
    slack = xtol + 4 * np.finfo(float).eps * abs(zero)
    if k == 2:  # (x - 1)^3 rounds to 0 within 1e-5.3 of the zero: any such x is a zero of the computed f
        slack = max(slack, 1e-5)
    if k == 5:
        slack = max(slack, 1e-33 ** (1 / 9))
    assert abs(x - zero) <= slack, (x, zero)
    assert a <= x <= b
    ours, theirs = x, brentq(f, a, b, xtol=xtol, maxiter=500)
    assert abs(ours - theirs) <= 2 * slack


def test_ends_and_refusals():
    assert root_in(lambda x: x, 0.0, 1.0, xtol=1e-12) == 0.0
    assert root_in(lambda x: x - 1.0, 0.0, 1.0, xtol=1e-12) == 1.0
    assert root_in(lambda x: x - 0.5, 1.0, 0.0, xtol=1e-12) == pytest.approx(0.5, abs=1e-12)  # reversed bracket
    with pytest.raises(InvalidInputError, match="bracket"):
        root_in(lambda x: x * x + 1.0, -1.0, 1.0, xtol=1e-9)
    with pytest.raises(ConvergenceError, match="Brent"):
        root_in(lambda x: math.cos(x) - x, 0.0, 1.0, xtol=1e-15, max_iter=2)
    with pytest.raises(InvalidInputError, match="bounds"):
        minimum_in(lambda x: x, 1.0, 1.0, xatol=1e-9)
    with pytest.raises(ConvergenceError, match="minimiser"):
        minimum_in(lambda x: (x - 0.3) ** 2, 0.0, 1.0, xatol=1e-12, max_iter=3)


MINIMA = [  # f, bounds, the minimiser
    (lambda x: (x - 0.3) ** 2, (0.0, 1.0), 0.3),
    (lambda x: -math.sin(x), (0.0, 3.0), math.pi / 2),
    (lambda x: math.cosh(x - 2.0), (-5.0, 10.0), 2.0),
    (lambda x: abs(x - 0.7), (0.0, 1.0), 0.7),  # a kink: golden sections
    (lambda x: x * x * x * x - x, (0.0, 2.0), 0.25 ** (1 / 3)),
    (lambda x: x, (0.0, 1.0), 0.0),  # at an end: approached, not evaluated
]


@pytest.mark.parametrize("k", range(len(MINIMA)))
@pytest.mark.parametrize("xatol", [1e-10, 1e-6, 1e-3])
def test_minima_within_the_tolerance_and_as_scipys_fminbound(k, xatol):
    f, (a, b), best = MINIMA[k]
    x, fx = minimum_in(f, a, b, xatol=xatol)
    assert fx == f(x) and a < x < b
    # known to xatol plus sqrt(eps) relative; a smooth minimum is flat to sqrt(eps): f cannot tell more
    relative = 2 * math.sqrt(np.finfo(float).eps) * max(abs(best), 1.0 if k in (0, 1, 2, 4) else abs(best))
    assert abs(x - best) <= xatol + relative + (2e-8 if k == 5 else 0.0)
    # the same algorithm as scipy's bounded minimiser: the same point
    assert x == pytest.approx(fminbound(f, a, b, xtol=xatol), abs=1e-13 + 1e-12 * abs(best))
