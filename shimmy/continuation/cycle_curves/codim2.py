"""Codimension-2 points along a curve of cycle bifurcations: detected by sign changes of their test
functions between consecutive points, located by the secant method (``locate_between`` of
:mod:`shimmy.continuation.core`), or, where the test function is an unknown minus a value (the torus
curve's resonances: kappa), by one Newton solve with the unknown held there (``point_at``).

Two families of test function: a further multiplier crossing the unit circle (every curve type;
``crossing_value``, which multipliers the curve's own condition holds at left out), and the
curve type's own (``DefiningSystem.own_monitors``: the fold's cusp, the
torus's strong resonances).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Callable

import numpy as np

from ..core import ContinuationOptions, CurvePoint, locate_between, point_at, weighted_norm
from ..periodic_orbits import multiplier_crossing_test
from ..results import SpecialPoint

if TYPE_CHECKING:
    from .bordered import CycleCurveProblem

#: |test function| accepted at a located point: tangent slopes and kappa to 1e-8 (the tangent
#: carries the finite-difference error of the Newton matrix, ~1e-10); ln |mu| to 1e-5: where a
#: multiplier crosses +1 on a torus curve it meets the trivial one, and a double eigenvalue is
#: only accurate to the square root of the monodromy matrix's error (~1e-6 for the gear)
LOCATE_TOL = 1e-8
MULTIPLIER_TOL = 1e-5
#: A multiplier crossing's test jumps where the crossing multiplier meets another within their
#: accuracy and the two leave the real axis as a pair (pd's torus curve: 1.00021 meets the trivial
#: multiplier, 1.00003, and the test goes from -2e-4 to +3.4): no zero to locate. Its search ends
#: once its bracket is narrower than this fraction of the step (the zero's place, where there is
#: one, is known to ~1e-2 of the step at MULTIPLIER_TOL); such a point is told unlocated (it took
#: 217 trial steps, 1.2 s, to find that out).
CROSSING_X_TOL = 1e-4


def monitors(problem: CycleCurveProblem, point: CurvePoint, mu: np.ndarray, reference: np.ndarray) -> dict:
    """Test functions of the codimension-2 points of this curve type at a point (``mu``: its
    multipliers; ``reference``: the curve's direction in the parameter plane at the last point)."""
    kappa = problem.kappa(point.u)
    out = problem.defining.own_monitors(problem, point, reference)
    for name, which in problem.defining.crossings.items():
        out[name] = crossing_value(problem, which, mu, kappa)
    return out


def crossing_value(problem: CycleCurveProblem, which: str, mu: np.ndarray, kappa: float,
                   guard: bool = True) -> float:
    """(-1)^(noncritical multipliers of one kind outside the unit circle) times the smallest
    |ln |mu|| among them (a complex pair counted once): continuous, zero exactly where one of
    them is on the circle, and of the other sign after it crossed; multipliers far from the
    circle (tiny ones flip between real kinds on rounding) do not change it. NaN where the
    crossing multiplier is within the multipliers' accuracy (10 |mu_trivial - 1|, at least 1e-6)
    of the circle: near a zero-amplitude end the cycle's radial multiplier tends to 1 and its
    side is not resolved."""
    keep = np.ones(mu.size, bool)
    keep[problem.defining.critical(mu, kappa)] = False
    return multiplier_crossing_test(mu[keep], which, max(10.0 * abs(mu[0] - 1.0), 1e-6) if guard else 0.0)


def _crossing_test(problem: CycleCurveProblem, which: str) -> Callable[[CurvePoint], float]:
    def g(q: CurvePoint) -> float:
        return crossing_value(problem, which, problem.multipliers(q.u), problem.kappa(q.u), guard=False)
    return g


def codim2_points(problem: CycleCurveProblem, prev: CurvePoint, new: CurvePoint, before: dict, after: dict,
                  reference: np.ndarray, index: int, copts: ContinuationOptions,
                  carried: frozenset = frozenset()) -> list[SpecialPoint]:
    """The codimension-2 points in the step from ``prev`` to ``new`` (the test functions at both,
    ``before`` and ``after``), each located (or said not to be), as point ``index`` of the curve, in
    their order along the step (two in one step came in the order of the tests: the nes map's R4 and
    LPNS, a larger step apart, listed the other way round than the trace with smaller steps, and its
    arrangement check failed).
    ``carried``: the multiplier tests whose value in ``before`` is an earlier point's, unresolved at
    ``prev``: a crossing of one is told at ``new``, unlocated, and listed after the step's located ones."""
    found = []
    along = []  # each point's distance from prev (weighted), for their order along the step
    defining = problem.defining
    for name, a in before.items():
        b = after[name]
        if not (np.isfinite(a) and np.isfinite(b)) or a * b > 0 or a == b:
            continue
        if name in carried:
            # the test was unresolved since an earlier point (its value there): the crossing lies in a stretch
            # where the multipliers do not tell the side, and a search there is noise (nes_pd's torus curve's LPNS
            # near 15 m/s: 2 s of failed trials). Told where the test is resolved again, unlocated.
            found.append(problem.special_point(name, new.u, index, located=False))
            along.append(weighted_norm(new.u - prev.u, problem.weights))
            continue
        level = None if name in defining.crossings else defining.own_level(problem, name)
        hit = None
        if level is not None and (prev.u[level[0]] - level[1]) * (new.u[level[0]] - level[1]) < 0:
            # an unknown's value (a torus curve's kappa), crossed between the two points (``before`` may be
            # an earlier point's: a new mesh moves kappa by up to ~6e-6): one Newton solve with it held there
            at = point_at(problem, prev, new, *level, copts, with_tangent=name in defining.tangent_tests)
            hit = None if at is None else (at, 0.0)
        if hit is None:
            if name in defining.crossings:
                g, tolerance, x_tol = _crossing_test(problem, defining.crossings[name]), MULTIPLIER_TOL, CROSSING_X_TOL
            else:
                g, tolerance, x_tol = defining.own_test(problem, name, reference), LOCATE_TOL, None
            hit = locate_between(problem, prev, new, g, a, b, copts, tolerance,
                                 with_tangent=name in defining.tangent_tests, x_tol=x_tol)
        at = hit[0] if hit is not None else new
        found.append(problem.special_point(name, at.u, index, located=hit is not None))
        along.append(weighted_norm(at.u - prev.u, problem.weights))
    problem.cycle_u(new.u)
    return [found[k] for k in sorted(range(len(found)), key=lambda k: along[k])]  # stable for equal ones
