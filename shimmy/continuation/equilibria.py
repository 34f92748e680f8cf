"""Equilibrium branches of x' = f(x, p) by pseudo-arclength continuation.

Equilibria (:func:`equilibrium_branch`): u = (x, p), stability from the eigenvalues
of f_x; a change in the number of eigenvalues with positive real part is a Hopf
point (complex pair), a fold LP (the parameter component of the tangent changes
sign) or a branch point BP (real eigenvalue, no fold). Each is located to
``locate_tol`` in the test function.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import scipy.linalg as la

from .core import ContinuationOptions, CurvePoint, Tracer, correct, locate, step, tangent, weighted_norm
from .fields import VectorField
from .kinds import PointKind, Stop, StopReason
from .results import ContinuationResult, SpecialPoint


@dataclass
class EquilibriumProblem:
    system: VectorField
    weights: np.ndarray

    def residual(self, u):
        return self.system.f(u[:-1], u[-1])

    def jacobian(self, u):
        x, p = u[:-1], u[-1]
        return np.column_stack([self.system.dfdx(x, p), self.system.dfdp(x, p)])

    def accept(self, u):
        pass


@dataclass
class EquilibriumBranch(ContinuationResult):
    """Points of an equilibrium branch (one row per point), traced one way: one stop, never closed."""

    p: np.ndarray
    x: np.ndarray  # (points, n)
    eigenvalues: np.ndarray  # (points, n), sorted by decreasing real part
    stable: np.ndarray

    @property
    def n_unstable(self) -> np.ndarray:
        return (self.eigenvalues.real > 0).sum(axis=1)

    def to_dict(self) -> dict[str, Any]:
        return {"p": self.p.tolist(), "x": self.x.tolist(), "eigenvalues_real": self.eigenvalues.real.tolist(),
                "eigenvalues_imag": self.eigenvalues.imag.tolist(), "stable": self.stable.tolist(),
                **super().to_dict()}


def _sorted_eigenvalues(A: np.ndarray) -> np.ndarray:
    ev = np.linalg.eigvals(A)
    return ev[np.argsort(-ev.real, kind="stable")]


def equilibrium_branch(system: VectorField, x0: np.ndarray, p0: float, *, p_range: tuple[float, float],
                       options: ContinuationOptions | None = None, scale: np.ndarray | None = None,
                       p_scale: float = 1.0, direction: int = 1) -> EquilibriumBranch:
    """Continue the equilibrium through (x0, p0) in p over ``p_range`` = (p_min, p_max).

    ``scale`` (n,) and ``p_scale`` set the size of a unit step in each unknown; ``direction``
    +1 follows increasing p first. Stops at the parameter bounds (exactly, as an EP point),
    after ``max_steps`` or when the step size underflows.
    """
    p_min, p_max = p_range
    options = options or ContinuationOptions()
    n = system.n
    scale = np.ones(n) if scale is None else np.asarray(scale, float)
    weights = np.append(1.0 / scale ** 2, 1.0 / p_scale ** 2) / (n + 1)
    problem = EquilibriumProblem(system, weights)
    u0 = np.append(np.asarray(x0, float), float(p0))
    guess = np.zeros(n + 1)
    guess[-1] = direction
    out = correct(problem, u0, guess / weighted_norm(guess, weights), options)
    if out is None:
        raise ValueError(f"no equilibrium near the start point at p = {p0:g}")
    u0 = out[0]
    t0 = tangent(problem, u0, guess)
    tracer = Tracer(problem, CurvePoint(u0, t0), options)

    points = [tracer.point]
    eigs = [_sorted_eigenvalues(system.dfdx(u0[:-1], u0[-1]))]
    special: list[SpecialPoint] = []
    stop = Stop(StopReason.STEP_BUDGET, f"step budget of {options.max_steps} steps used")
    steps = 0
    for steps in range(1, options.max_steps + 1):  # noqa: B007 (steps is reported)
        out = tracer.advance_within(p_min, p_max)
        if out is None:
            stop = tracer.failed
            break
        prev, new, _, bound = out
        if new is not None:
            _append_equilibrium(system, points, eigs, special, prev, new, problem, options)
        if bound is not None:
            if new is not None:
                special.append(SpecialPoint(PointKind.END, float(new.u[-1]), len(points) - 1))
            stop = Stop(StopReason.BOUND, f"reached the parameter bound p = {bound:g}")
            break
    u = np.array([q.u for q in points])
    ev = np.array(eigs)
    return EquilibriumBranch(u[:, -1], u[:, :-1], ev, ev[:, 0].real < 0, special_points=special, stops=[stop],
                             steps=steps)


def _eigen_slopes(A: np.ndarray, dA: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eigenvalues of A and their first-order change d(lambda) = w^H dA v / w^H v (simple ones)."""
    lam, w, v = la.eig(A, left=True, right=True)
    den = np.einsum("ij,ij->j", w.conj(), v)
    num = np.einsum("ij,ij->j", w.conj(), dA @ v)
    with np.errstate(divide="ignore", invalid="ignore"):
        slope = np.where(np.abs(den) > 1e-12 * np.abs(num).max(initial=1e-300), num / den, np.nan)
    return lam, slope


def _jacobian_along(system, point: CurvePoint, h: float) -> np.ndarray:
    """Derivative of df/dx over a step h along the point's tangent (central differences)."""
    u, d = point.u, 1e-4 * h * point.tangent
    A_plus, A_minus = system.dfdx(u[:-1] + d[:-1], u[-1] + d[-1]), system.dfdx(u[:-1] - d[:-1], u[-1] - d[-1])
    return (A_plus - A_minus) / 2e-4


def _hidden_crossing(old: tuple[np.ndarray, np.ndarray], new: tuple[np.ndarray, np.ndarray]) -> float | None:
    """Fraction of a step where an eigenvalue may cross the imaginary axis and come back.

    The counts of unstable eigenvalues at the two ends of a step cannot see two crossings
    inside it (a Hopf pair closer than one step). Each eigenvalue's real part is interpolated
    along the step by a cubic Hermite polynomial from its values and slopes at both ends
    (``old``, ``new``: the Jacobian and its derivative along the step at each end; slopes by
    first-order perturbation, eigenvalues matched end to end by the value predicted from the
    start); if the interpolant changes sign although the ends agree, the fraction where it
    is most negative (relative to the ends' sign) is returned for the caller to check with a
    corrected point. None when nothing suggests it.
    """
    lam0, s0 = _eigen_slopes(*old)
    lam1, s1 = _eigen_slopes(*new)
    best, where = 0.0, None
    for i in range(lam0.size):
        if not np.isfinite(s0[i]):
            continue
        j = int(np.argmin(np.abs(lam1 - lam0[i] - 0.5 * (s0[i] + np.nan_to_num(s1)))))
        r0, r1 = lam0[i].real, lam1[j].real
        if r0 * r1 <= 0 or not np.isfinite(s1[j]):
            continue
        sign, d0, d1 = np.sign(r0), s0[i].real, s1[j].real
        # Hermite cubic r(tau) = c3 tau^3 + c2 tau^2 + d0 tau + r0 on [0, 1]; its interior extrema
        c3, c2 = 2 * (r0 - r1) + d0 + d1, 3 * (r1 - r0) - 2 * d0 - d1
        for tau in np.roots([3 * c3, 2 * c2, d0]):
            if abs(tau.imag) > 1e-12 or not 0.0 < tau.real < 1.0:
                continue
            t = tau.real
            value = sign * (((c3 * t + c2) * t + d0) * t + r0)
            if value < -1e-12 * max(abs(lam0[i]), abs(lam1[j]), 1e-300) and value < best:
                best, where = value, float(t)
    return where


def _append_equilibrium(system, points, eigs, special, prev: CurvePoint, new: CurvePoint, problem, options):
    A_new = system.dfdx(new.u[:-1], new.u[-1])
    ev_new = _sorted_eigenvalues(A_new)
    ev_old = eigs[-1]
    count_old, count_new = int((ev_old.real > 0).sum()), int((ev_new.real > 0).sum())
    h = weighted_norm(new.u - prev.u, problem.weights)
    if count_old == count_new:
        A_old = system.dfdx(prev.u[:-1], prev.u[-1])
        tau = _hidden_crossing((A_old, _jacobian_along(system, prev, h)), (A_new, _jacobian_along(system, new, h)))
        mid = step(problem, prev, tau * h, options) if tau is not None else None
        if mid is not None and int((_sorted_eigenvalues(system.dfdx(mid.u[:-1], mid.u[-1])).real > 0).sum()) \
                != count_old:
            # two crossings in one step: split it at the corrected interior point and treat each half
            _append_equilibrium(system, points, eigs, special, prev, mid, problem, options)
            _append_equilibrium(system, points, eigs, special, mid, new, problem, options)
            return
    found: list[tuple[float, SpecialPoint]] = []
    if prev.tangent[-1] * new.tangent[-1] < 0:
        hit = locate(problem, prev, h, lambda q: q.tangent[-1], prev.tangent[-1], new.tangent[-1], options)
        at = hit[0] if hit is not None else (prev if abs(prev.tangent[-1]) < abs(new.tangent[-1]) else new)
        found.append((weighted_norm(at.u - prev.u, problem.weights),
                      SpecialPoint(PointKind.FOLD, float(at.u[-1]), -1, {"x": at.u[:-1].tolist()},
                                   located=hit is not None)))
    # The j-th largest real part changes sign for every j between the two counts: one located
    # point per real eigenvalue or complex pair (several pairs can cross within one step).
    j = min(count_old, count_new)
    while j < max(count_old, count_new):
        def g(q, k=j):
            return _sorted_eigenvalues(system.dfdx(q.u[:-1], q.u[-1]))[k].real

        hit = locate(problem, prev, h, g, ev_old[j].real, ev_new[j].real, options)
        q = hit[0] if hit is not None else (prev if abs(ev_old[j].real) < abs(ev_new[j].real) else new)
        ev = _sorted_eigenvalues(system.dfdx(q.u[:-1], q.u[-1]))
        crit = ev[j]
        scale = max(np.abs(ev).max(), 1e-300)
        where = weighted_norm(q.u - prev.u, problem.weights)
        if abs(crit.imag) > 1e-6 * scale:
            found.append((where, SpecialPoint(PointKind.HOPF, float(q.u[-1]), -1,
                                              {"omega": float(abs(crit.imag)), "x": q.u[:-1].tolist()},
                                              located=hit is not None)))
            j += 2  # its conjugate crosses with it
            continue
        if not any(s.kind is PointKind.FOLD for _, s in found):
            found.append((where, SpecialPoint(PointKind.BRANCH_POINT, float(q.u[-1]), -1,
                                              {"x": q.u[:-1].tolist()}, located=hit is not None)))
        j += 1
    points.append(new)
    eigs.append(ev_new)
    for _, sp_ in sorted(found, key=lambda item: item[0]):
        special.append(replace(sp_, index=len(points) - 1))
