"""Scalar root finding and minimisation on an interval, without importing scipy.optimize.

``scipy.optimize`` costs about 0.4 s to import (it loads its whole package: linear programming,
least squares, ...), more than the Hopf scan it served takes to compute; a command answering in a
few tenths of a second cannot afford it. Two classic algorithms are all the engine and the
analyses need:

* :func:`root_in` : Brent's method (R. P. Brent, *Algorithms for Minimization without
  Derivatives*, 1973, ch. 4, "zeroin"): inverse quadratic interpolation or the secant step
  where it stays inside the bracket and shrinks it fast enough, bisection otherwise. Converges
  when the bracket is below ``xtol + rtol |x|``; never leaves the bracket.
* :func:`minimum_in`: Brent's minimiser on a bounded interval (ch. 5, "localmin"; G. E.
  Forsythe, M. A. Malcolm, C. B. Moler, *Computer Methods for Mathematical Computations*, 1977,
  "fmin"): golden-section steps, parabolic ones where they are trusted; converges when the
  point is known to within ``xatol`` (plus sqrt(eps) relative).

Both are tested against ``scipy.optimize.brentq`` and ``fminbound`` on functions with known
answers (tests/continuation/test_scalar.py).
"""

from __future__ import annotations

import math
from typing import Callable

from .errors import ConvergenceError, InvalidInputError

EPS = 2.220446049250313e-16
GOLDEN = 0.5 * (3.0 - math.sqrt(5.0))  # the golden section's smaller part, 0.381966...


def root_in(f: Callable[[float], float], a: float, b: float, *, xtol: float, rtol: float = 4.0 * EPS,
            max_iter: int = 500) -> float:
    """A zero of ``f`` in [a, b], where f(a) and f(b) differ in sign, to ``xtol + rtol |x|``.

    A simple zero takes a handful of steps; a multiple one converges linearly (a triple zero from
    a bracket of 5 to 1e-12: about 100 steps; Brent's bound is (log2 of the bracket over the
    tolerance)^2).

    Raises :class:`~shimmy.continuation.errors.InvalidInputError` if f(a) and f(b) have the same
    sign, :class:`~shimmy.continuation.errors.ConvergenceError` after ``max_iter`` steps."""
    fa, fb = float(f(a)), float(f(b))
    if fa == 0.0:
        return float(a)
    if fb == 0.0:
        return float(b)
    if math.copysign(1.0, fa) == math.copysign(1.0, fb):
        raise InvalidInputError("bracket", (a, b), "an interval where f changes sign",
                                f"f = {fa:.3g} and {fb:.3g} at its ends: no sign change")
    # b: the best estimate; a: the one before; c: the other end of the bracket around the zero
    c, fc = a, fa
    step = before = b - a
    for _ in range(max_iter):
        if (fb > 0.0) == (fc > 0.0):  # the zero lies between a and b: a becomes the bracket's end
            c, fc = a, fa
            step = before = b - a
        if abs(fc) < abs(fb):  # b the end with the smaller |f|
            a, b, c = b, c, b
            fa, fb, fc = fb, fc, fb
        tol = 0.5 * (xtol + rtol * abs(b))
        half = 0.5 * (c - b)
        if abs(half) <= tol or fb == 0.0:
            return float(b)
        if abs(before) >= tol and abs(fa) > abs(fb):
            s = fb / fa
            if a == c:  # two points: the secant
                p, q = 2.0 * half * s, 1.0 - s
            else:  # three: inverse quadratic interpolation
                q, r = fa / fc, fb / fc
                p = s * (2.0 * half * q * (q - r) - (b - a) * (r - 1.0))
                q = (q - 1.0) * (r - 1.0) * (s - 1.0)
            if p > 0.0:
                q = -q
            p = abs(p)
            if 2.0 * p < min(3.0 * half * q - abs(tol * q), abs(before * q)):  # inside, and fast enough
                before, step = step, p / q
            else:
                step = before = half
        else:
            step = before = half
        a, fa = b, fb
        b += step if abs(step) > tol else math.copysign(tol, half)
        fb = float(f(b))
    raise ConvergenceError(f"no zero to {xtol:g} in {max_iter} steps of Brent's method (last x = {b:.17g})")


def minimum_in(f: Callable[[float], float], a: float, b: float, *, xatol: float,
               max_iter: int = 500) -> tuple[float, float]:
    """(x, f(x)) at a local minimum of ``f`` on [a, b] (a < b), x known to ``xatol`` plus sqrt(eps)
    relative; the interval's ends are not evaluated. Raises
    :class:`~shimmy.continuation.errors.ConvergenceError` after ``max_iter`` steps."""
    if not a < b:
        raise InvalidInputError("bounds", (a, b), "an interval a < b")
    sqrt_eps = math.sqrt(EPS)
    x = w = v = a + GOLDEN * (b - a)  # the best point, the second best, the one before it
    fx = fw = fv = float(f(x))
    step = before = 0.0
    for _ in range(max_iter):
        middle = 0.5 * (a + b)
        tol = sqrt_eps * abs(x) + xatol / 3.0
        if abs(x - middle) <= 2.0 * tol - 0.5 * (b - a):
            return float(x), fx
        golden = True
        if abs(before) > tol:  # a parabola through x, w, v
            r = (x - w) * (fx - fv)
            q = (x - v) * (fx - fw)
            p = (x - v) * q - (x - w) * r
            q = 2.0 * (q - r)
            if q > 0.0:
                p = -p
            q = abs(q)
            if abs(p) < abs(0.5 * q * before) and q * (a - x) < p < q * (b - x):  # trusted: inside, shrinking
                before, step = step, p / q
                u = x + step
                if u - a < 2.0 * tol or b - u < 2.0 * tol:  # not too near an end
                    step = math.copysign(tol, middle - x)
                golden = False
        if golden:
            before = (b if x < middle else a) - x
            step = GOLDEN * before
        u = x + (step if abs(step) >= tol else math.copysign(tol, step))
        fu = float(f(u))
        if fu <= fx:
            if u < x:
                b = x
            else:
                a = x
            v, fv, w, fw, x, fx = w, fw, x, fx, u, fu
        else:
            if u < x:
                a = u
            else:
                b = u
            if fu <= fw or w == x:
                v, fv, w, fw = w, fw, u, fu
            elif fu <= fv or v == x or v == w:
                v, fv = u, fu
    raise ConvergenceError(f"no minimum to {xatol:g} in {max_iter} steps of Brent's minimiser (last x = {x:.17g})")
