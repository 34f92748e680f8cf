"""Pseudo-arclength continuation of F(u) = 0 with F: R^(N+1) -> R^N, and equilibrium branches.

Generic: nothing here knows the landing gear. A *curve problem* supplies

* ``residual(u)`` -> (N,) and ``jacobian(u)`` -> (N, N+1), dense or scipy.sparse;
* ``weights`` (N+1,): the diagonal of the inner product <a, b>_w = sum w a b used for the
  arclength, so that unknowns of very different size (states, period, speed) count alike;
* ``accept(u)``: called once a point is accepted (the periodic-orbit problem moves its
  phase reference there).

Each step: predictor u_pred = u + h t (t the unit tangent in the w-norm), corrector =
Newton on [F(u); <t, u - u_pred>_w] = 0 with the bordered Jacobian [F_u; (w t)^T]
(sparse LU when F_u is sparse). Converged when the w-norm of the Newton correction is
below ``tol`` and |F|_inf below ``residual_tol``; at most ``max_newton`` iterations.
Step control: h grows by ``grow`` after a step that converged in <= 3 iterations,
shrinks by ``shrink`` on failure, and the branch stops (with a message) when h would
fall below ``ds_min``. Special points are located by :func:`locate`: the secant
(Illinois) method on the step length from the last point, every trial point being a
converged point of the curve.

Equilibria (:func:`equilibrium_branch`): u = (x, p), stability from the eigenvalues
of f_x; a change in the number of eigenvalues with positive real part is a Hopf
point (complex pair), a fold LP (the parameter component of the tangent changes
sign) or a branch point BP (real eigenvalue, no fold). Each is located to
``locate_tol`` in the test function.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import Any, Callable, Protocol

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from .errors import InvalidParameterError


@dataclass(frozen=True)
class ContinuationOptions:
    """Step control and convergence settings (arclength in the weighted norm)."""

    ds: float = 0.02
    ds_min: float = 1e-7
    ds_max: float = 0.5
    max_steps: int = 400
    tol: float = 1e-9
    residual_tol: float = 1e-8
    max_newton: int = 8
    grow: float = 1.4
    shrink: float = 0.5
    locate_tol: float = 1e-9
    max_locate: int = 30

    def __post_init__(self):
        for name in ("ds", "ds_min", "ds_max", "tol", "residual_tol", "locate_tol"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise InvalidParameterError(name, value, "a positive finite number")
        if not self.ds_min <= self.ds <= self.ds_max:
            raise InvalidParameterError("ds", self.ds, f"[{self.ds_min:g}, {self.ds_max:g}]",
                                        "must lie between ds_min and ds_max")
        for name in ("max_steps", "max_newton", "max_locate"):
            value = getattr(self, name)
            if not (isinstance(value, int) and value >= 1):
                raise InvalidParameterError(name, value, "an integer >= 1")


class CurveProblem(Protocol):
    weights: np.ndarray

    def residual(self, u: np.ndarray) -> np.ndarray: ...

    def jacobian(self, u: np.ndarray): ...

    def accept(self, u: np.ndarray) -> None: ...


@dataclass
class CurvePoint:
    u: np.ndarray
    tangent: np.ndarray
    iterations: int = 0


class _Bordered:
    """LU factors of the square matrix [jac; row] (jac dense, or scipy.sparse CSR).

    Sparse: the CSR arrays of [jac; row] are the CSC arrays of its transpose, which SuperLU
    factors (ordering MMD on A^T + A, the best of SuperLU's orderings on collocation
    matrices) and solves with ``trans="T"``: no format conversion.
    """

    def __init__(self, jac, row: np.ndarray):
        if sp.issparse(jac):
            jac = jac.tocsr()
            size = row.size
            data = np.concatenate([jac.data, row])
            indices = np.concatenate([jac.indices, np.arange(size, dtype=jac.indices.dtype)])
            indptr = np.append(jac.indptr, jac.indptr[-1] + size)
            transpose = sp.csc_matrix((data, indices, indptr), shape=(size, size))
            lu = splu(transpose, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.1)
            self.solve = lambda rhs: lu.solve(rhs, trans="T")
        else:
            with warnings.catch_warnings():
                warnings.simplefilter("error", la.LinAlgWarning)  # exactly singular: raise, do not warn
                try:
                    factors = la.lu_factor(np.vstack([jac, row[None, :]]), check_finite=False)
                except la.LinAlgWarning as exc:
                    raise np.linalg.LinAlgError(str(exc)) from None
            self.solve = lambda rhs: la.lu_solve(factors, rhs, check_finite=False)


def weighted_norm(v: np.ndarray, w: np.ndarray) -> float:
    return float(np.sqrt(np.sum(w * v * v)))


def _unit_last(size: int) -> np.ndarray:
    e = np.zeros(size)
    e[-1] = 1.0
    return e


def tangent(problem: CurveProblem, u: np.ndarray, previous: np.ndarray) -> np.ndarray:
    """Unit tangent (w-norm) of the curve at u, oriented along ``previous``."""
    w = problem.weights
    t = _Bordered(problem.jacobian(u), w * previous).solve(_unit_last(u.size))
    return t / weighted_norm(t, w)


def correct(problem: CurveProblem, u_pred: np.ndarray, t: np.ndarray,
            options: ContinuationOptions) -> tuple[np.ndarray, int] | None:
    """Newton on [F(u); <t, u - u_pred>_w] = 0 from u_pred; None if it does not converge.

    Chord iterations: the bordered Jacobian is factored at the predictor and refreshed
    only when a correction fails to shrink by half. Returns the solution and the number
    of iterations.
    """
    w = problem.weights
    u = u_pred.copy()
    row = w * t
    F = problem.residual(u)
    lu, fresh, last, factorisations = None, False, np.inf, 0
    for it in range(1, 3 * options.max_newton + 1):
        if not np.all(np.isfinite(F)):
            return None
        G = np.append(F, row @ (u - u_pred))
        if lu is None:
            if factorisations == options.max_newton:
                return None
            try:
                lu = _Bordered(problem.jacobian(u), row)
            except (RuntimeError, ValueError, np.linalg.LinAlgError):  # singular matrix
                return None
            fresh, factorisations = True, factorisations + 1
        du = lu.solve(-G)
        size = weighted_norm(du, w)
        if not np.isfinite(size):
            return None
        if size > 0.5 * last and not fresh:  # the chord stalls: refactor here and redo
            lu = None
            continue
        if size > 2.0 * last:  # diverging even with a fresh Jacobian
            return None
        fresh, last = False, size
        u = u + du
        F = problem.residual(u)
        if size <= options.tol and np.all(np.isfinite(F)) and np.max(np.abs(F)) <= options.residual_tol:
            return u, it
    return None


def step(problem: CurveProblem, point: CurvePoint, h: float, options: ContinuationOptions,
         with_tangent: bool = True) -> CurvePoint | None:
    """One predictor-corrector step of length h from ``point`` (None if Newton fails).

    ``with_tangent=False`` skips the new tangent (one factorisation) for trial points whose
    tangent is not needed; the returned point then carries the old one.
    """
    out = correct(problem, point.u + h * point.tangent, point.tangent, options)
    if out is None:
        return None
    u, iterations = out
    if not with_tangent:
        return CurvePoint(u, point.tangent, iterations)
    try:
        t = tangent(problem, u, point.tangent)
    except (RuntimeError, ValueError, np.linalg.LinAlgError):
        return None
    if not np.all(np.isfinite(t)):
        return None
    return CurvePoint(u, t, iterations)


class Tracer:
    """Successive points of a curve with step-size control."""

    def __init__(self, problem: CurveProblem, start: CurvePoint, options: ContinuationOptions):
        self.problem, self.options = problem, options
        self.point = start
        self.h = options.ds
        self.failed: str | None = None

    def advance(self) -> tuple[CurvePoint, float] | None:
        """The next point and the step that reached it; None (with ``failed`` set) if h < ds_min."""
        opts = self.options
        while True:
            new = step(self.problem, self.point, self.h, opts)
            if new is not None:
                taken = self.h
                if new.iterations <= 4:
                    self.h = min(self.h * opts.grow, opts.ds_max)
                self.problem.accept(new.u)
                self.point = new
                return new, taken
            self.h *= opts.shrink
            if self.h < opts.ds_min:
                self.failed = (f"Newton did not converge with step {self.h / opts.shrink:.2g} "
                               f"(minimum {opts.ds_min:g})")
                return None

    def advance_within(self, low: float, high: float, index: int = -1):
        """Like :meth:`advance`, keeping unknown ``index`` in [low, high].

        Returns (previous point, new point, step, bound): ``bound`` is None inside the
        interval; if the step left it, the new point is the one located on the bound (or None
        if locating failed) and ``bound`` the value crossed. None when the step underflows.
        """
        prev = self.point
        adv = self.advance()
        if adv is None:
            return None
        new, h = adv
        value = new.u[index]
        if low <= value <= high:
            return prev, new, h, None
        bound = high if value > high else low
        hit = locate(self.problem, prev, h, lambda q: q.u[index] - bound, prev.u[index] - bound, value - bound,
                     self.options)
        return prev, (hit[0] if hit is not None else None), h, bound

    def limit_step(self, h_max: float) -> None:
        self.h = max(min(self.h, h_max), self.options.ds_min)


def locate(problem: CurveProblem, start: CurvePoint, h_end: float, g: Callable[[CurvePoint], float],
           g_start: float, g_end: float, options: ContinuationOptions) -> tuple[CurvePoint, float] | None:
    """Zero of g between ``start`` (h = 0) and the point at step h_end (Illinois secant on h).

    Returns (point, g at it), or None if a trial step fails to converge.
    """
    a, b, ga, gb = 0.0, h_end, g_start, g_end
    best = None
    side = 0
    for _ in range(options.max_locate):
        h = b - gb * (b - a) / (gb - ga) if gb != ga else 0.5 * (a + b)
        if not (min(a, b) < h < max(a, b)):
            h = 0.5 * (a + b)
        trial = step(problem, start, h, options)
        if trial is None:  # e.g. landed exactly on a singular point (a branch point): nudge off it
            trial = step(problem, start, h * (1.0 + 1e-7), options) or step(problem, start, h * (1.0 - 1e-7),
                                                                             options)
        if trial is None:
            return best
        gh = g(trial)
        best = (trial, gh)
        if abs(gh) <= options.locate_tol or abs(b - a) <= 1e-13 * abs(h_end):
            return best
        if gh * gb < 0:
            a, ga = b, gb
            side = 0
        else:
            ga = ga * 0.5 if side == 1 else ga  # Illinois: halve the retained end's value
            side = 1
        b, gb = h, gh
    return best


# --------------------------------------------------------------------------- equilibria


@dataclass(frozen=True)
class VectorField:
    """x' = f(x, p) with analytic derivatives, vectorised over columns.

    ``f(x, p)``: x (n,) or (n, m) -> same shape; ``dfdx(x, p)``: (n, n) or (m, n, n);
    ``dfdp(x, p)``: like f. ``p`` is a scalar (the continuation parameter).
    """

    n: int
    f: Callable[[np.ndarray, float], np.ndarray]
    dfdx: Callable[[np.ndarray, float], np.ndarray]
    dfdp: Callable[[np.ndarray, float], np.ndarray]
    name: str = "system"


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


@dataclass(frozen=True)
class SpecialPoint:
    """A bifurcation point located on a branch."""

    kind: str  # H, LP, BP (equilibria); LPC, NS, PD, BPC (cycles); EP end point
    p: float
    index: int  # position in the branch's point list
    data: dict[str, Any] = field(default_factory=dict)

    def to_dict(self, parameter: str = "p") -> dict[str, Any]:
        return {"kind": self.kind, parameter: self.p, **self.data}


@dataclass
class EquilibriumBranch:
    p: np.ndarray
    x: np.ndarray  # (points, n)
    eigenvalues: np.ndarray  # (points, n), sorted by decreasing real part
    stable: np.ndarray
    special_points: list[SpecialPoint]
    stop_reason: str
    steps: int

    @property
    def n_unstable(self) -> np.ndarray:
        return (self.eigenvalues.real > 0).sum(axis=1)


def _sorted_eigenvalues(A: np.ndarray) -> np.ndarray:
    ev = np.linalg.eigvals(A)
    return ev[np.argsort(-ev.real, kind="stable")]


def equilibrium_branch(system: VectorField, x0: np.ndarray, p0: float, p_min: float, p_max: float,
                       options: ContinuationOptions | None = None, scale: np.ndarray | None = None,
                       p_scale: float = 1.0, direction: int = 1) -> EquilibriumBranch:
    """Continue the equilibrium through (x0, p0) in p over [p_min, p_max].

    ``scale`` (n,) and ``p_scale`` set the size of a unit step in each unknown; ``direction``
    +1 follows increasing p first. Stops at the parameter bounds (exactly, as an EP point),
    after ``max_steps`` or when the step size underflows.
    """
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
    stop = f"step budget of {options.max_steps} steps used"
    steps = 0
    for steps in range(1, options.max_steps + 1):  # noqa: B007 (steps is reported)
        out = tracer.advance_within(p_min, p_max)
        if out is None:
            stop = tracer.failed or "failed"
            break
        prev, new, _, bound = out
        if new is not None:
            _append_equilibrium(system, points, eigs, special, prev, new, problem, options)
        if bound is not None:
            if new is not None:
                special.append(SpecialPoint("EP", float(new.u[-1]), len(points) - 1))
            stop = f"reached the parameter bound p = {bound:g}"
            break
    u = np.array([q.u for q in points])
    ev = np.array(eigs)
    return EquilibriumBranch(u[:, -1], u[:, :-1], ev, ev[:, 0].real < 0, special, stop, steps)


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
                      SpecialPoint("LP", float(at.u[-1]), -1, {"x": at.u[:-1].tolist(), "located": hit is not None})))
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
            found.append((where, SpecialPoint("H", float(q.u[-1]), -1,
                                              {"omega": float(abs(crit.imag)), "x": q.u[:-1].tolist(),
                                               "located": hit is not None})))
            j += 2  # its conjugate crosses with it
            continue
        if not any(s.kind == "LP" for _, s in found):
            found.append((where, SpecialPoint("BP", float(q.u[-1]), -1,
                                              {"x": q.u[:-1].tolist(), "located": hit is not None})))
        j += 1
    points.append(new)
    eigs.append(ev_new)
    for _, sp_ in sorted(found, key=lambda item: item[0]):
        special.append(SpecialPoint(sp_.kind, sp_.p, len(points) - 1, sp_.data))
