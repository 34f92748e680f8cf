"""Pseudo-arclength continuation of F(u) = 0 with F: R^(N+1) -> R^N, and equilibrium branches.

Generic: nothing here knows the landing gear. A *curve problem* supplies

* ``residual(u)`` -> (N,) and ``jacobian(u)`` -> (N, N+1), dense or scipy.sparse;
* ``weights`` (N+1,): the diagonal of the inner product <a, b>_w = sum w a b used for the
  arclength, so that unknowns of very different size (states, period, speed) count alike;
* ``accept(u)``: called once a point is accepted (the periodic-orbit problem moves its
  phase reference there);
* optionally ``factor_bordered(u, row)``: factors of [F_u(u); row] (``solve``, ``row``) built
  without assembling F_u (the periodic-orbit problem condenses its collocation blocks directly).

Each step: predictor u_pred = u + h t + h^2/2 dt/ds (t the unit tangent in the w-norm; the
curvature term from the last step, orthogonal to t: :meth:`Tracer.curvature`), corrector =
Newton on [F(u); <t, u - u_pred>_w] = 0 with the bordered Jacobian [F_u; (w t)^T]
(sparse LU when F_u is sparse). Converged when the w-norm of the Newton correction is
below ``tol`` and |F|_inf below ``residual_tol`` (at the corrected point, or already at the point
the correction starts from: F is then not evaluated again); chord iterations, the Jacobian refactored
when a correction fails to halve, at most ``max_newton`` factorisations and 3 ``max_newton``
iterations. Step control: h grows by ``grow`` after a step that converged in <= 4
iterations with the tangent turned by at most half of ``max_angle``, shrinks by ``shrink``
on failure, and the branch stops (with a :class:`~.kinds.Stop`) when h would
fall below ``ds_min``. Special points are located by :func:`locate`: the secant
(Illinois) method on the step length from the last point, every trial point being a
converged point of the curve.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from dataclasses import dataclass, replace
from typing import Any, Callable, Protocol

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from .condensed_lu import CondensedLU
from .errors import InvalidInputError
from .kinds import Stop, StopReason


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
    #: Curvature control: a step whose tangent turns by more than this (rad, in the weighted
    #: inner product) is refused and retried shorter; the step grows only below half of it.
    max_angle: float = math.inf
    #: A corrected point farther from its predictor than this times the step (weighted norm) is
    #: refused and the step retried shorter: Newton jumped to another branch (a corrector on the
    #: curve moves ~ curvature h^2 / 2). Off by default; the Hopf curves of the gear use 1.
    max_correction: float = math.inf

    def __post_init__(self):
        for name in ("ds", "ds_min", "ds_max", "tol", "residual_tol", "locate_tol", "max_angle", "max_correction"):
            value = getattr(self, name)
            unbounded = name in ("max_angle", "max_correction")  # inf: no limit
            if not (isinstance(value, (int, float)) and (math.isfinite(value) or unbounded) and value > 0):
                raise InvalidInputError(name, value, "a positive finite number")
        if not self.ds_min <= self.ds <= self.ds_max:
            raise InvalidInputError("ds", self.ds, f"[{self.ds_min:g}, {self.ds_max:g}]",
                                        "must lie between ds_min and ds_max")
        for name in ("max_steps", "max_newton", "max_locate"):
            value = getattr(self, name)
            if not (isinstance(value, int) and value >= 1):
                raise InvalidInputError(name, value, "an integer >= 1")


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
        self.row = row
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


def condensed_factors(layout, parts: tuple[np.ndarray, np.ndarray], row: np.ndarray,
                      assembled: Callable[[], Any]):
    """Factors of a bordered collocation matrix [jacobian; row] condensed from its ``parts`` (link
    blocks and global rows, see :class:`~.condensed_lu.CondensedLU`), ``row`` kept as an attribute;
    on a zero pivot of the condensation, SuperLU on ``assembled()`` (the sparse jacobian)."""
    try:
        lu = CondensedLU(None, layout, parts=parts)
    except np.linalg.LinAlgError:
        return _Bordered(assembled(), row)
    lu.row = row
    return lu


def weighted_norm(v: np.ndarray, w: np.ndarray) -> float:
    return float(np.sqrt(np.sum(w * v * v)))


def _unit_last(size: int) -> np.ndarray:
    e = np.zeros(size)
    e[-1] = 1.0
    return e


#: Refinement of a tangent on nearby factors: the residual of [F_u; (w t_prev)^T] t = e_last is
#: driven below this (relative to |t|), else the matrix is factored afresh.
TANGENT_REFINE_TOL = 1e-13


def tangent(problem: CurveProblem, u: np.ndarray, previous: np.ndarray,
            near: Any = None) -> np.ndarray:
    """Unit tangent (w-norm) of the curve at u, oriented along ``previous``.

    A problem with ``factor_bordered`` (collocation: factored without assembling F_u, cheaper
    than assembling it for a refinement) is factored afresh at u. Otherwise ``near``: factors
    (as :func:`correct` returns them) of the same system at a nearby point with the same
    bordering row (the corrector's last chord matrix): the tangent is found by iterative
    refinement on them (``refine``: a solve and a product per sweep, at most 5 sweeps, each
    required to shrink the residual 4x) to ``TANGENT_REFINE_TOL``; only if that fails is the
    matrix factored here.
    """
    w = problem.weights
    row = w * previous
    e = _unit_last(u.size)
    factor = getattr(problem, "factor_bordered", None)
    if factor is not None:  # factoring without assembly costs less than assembling for refinement
        t = factor(u, row).solve(e)
        return t / weighted_norm(t, w)
    jac = problem.jacobian(u)
    t = None
    if near is not None and np.array_equal(near.row, row):
        t = refine(near.solve, lambda z: np.append(jac @ z, row @ z), e,
                   lambda z: TANGENT_REFINE_TOL * float(np.abs(z).max()), 5)
    if t is None:
        t = _Bordered(jac, row).solve(e)
    return t / weighted_norm(t, w)


def refine(solve: Callable[[np.ndarray], np.ndarray], apply: Callable[[np.ndarray], np.ndarray],
           rhs: np.ndarray, tolerance: Callable[[np.ndarray], float], sweeps: int) -> np.ndarray | None:
    """A^-1 rhs by iterative refinement with ``solve`` (factors of a nearby matrix) and ``apply``
    (A times a vector): the residual max |rhs - A z| is checked at most ``sweeps`` times, a
    correction solved after each check it fails, until it is <= tolerance(z); None if that is not
    reached, the residual is not finite, or a sweep shrinks it less than 4x (the factors are too
    far off: better refactor)."""
    z = solve(rhs)
    last = math.inf
    for sweep in range(sweeps):
        r = rhs - apply(z)
        size = float(np.abs(r).max())
        if not math.isfinite(size):
            return None
        if size <= tolerance(z):
            return z
        if size > 0.25 * last or sweep == sweeps - 1:
            return None
        last = size
        z = z + solve(r)
    return None


#: Newton has reached the noise floor when a correction with a fresh Jacobian does not shrink against
#: the previous one with a fresh Jacobian, is below NOISE_CORRECTION times ``tol``, and |F|_inf is
#: already below NOISE_RESIDUAL times ``residual_tol``: the point is taken as converged. (A nearly
#: flat equation turns rounding noise in F into corrections above ``tol``: a fold-of-cycles test
#: function near a Hopf point, where the cycle's amplitude goes to zero, gave |F| ~ 2e-16 and
#: corrections ~1.6e-9 that never shrank. Larger stalled corrections are not noise: accepting those
#: up to 1e-4 left points too far off the curve for the secant location of special points, which
#: then took all its trials.)
NOISE_RESIDUAL = 1e-3
NOISE_CORRECTION = 10.0
#: ... "does not shrink": by less than this factor. Fresh corrections shrinking at rate 1/2 are
#: linear convergence at a double root (a fold of the augmented system), not noise.
NOISE_STALL = 0.9


def correct(problem: CurveProblem, u_pred: np.ndarray, t: np.ndarray,
            options: ContinuationOptions) -> tuple[np.ndarray, int, Any] | None:
    """Newton on [F(u); <t, u - u_pred>_w] = 0 from u_pred; None if it does not converge.

    Chord iterations: the bordered Jacobian is factored at the predictor and refreshed
    only when a correction fails to shrink by half. Converged when the correction is below
    ``tol`` and |F| below ``residual_tol`` (after the correction, or before it), or at the noise floor
    (``NOISE_RESIDUAL``, ``NOISE_CORRECTION``, ``NOISE_STALL``). Returns the solution, the number of iterations and
    the last factors (a nearby matrix for the tangent's refinement).
    """
    w = problem.weights
    u = u_pred.copy()
    row = w * t
    F = problem.residual(u)
    lu, fresh, last, factorisations = None, False, np.inf, 0
    last_fresh = np.inf
    for it in range(1, 3 * options.max_newton + 1):
        if not np.all(np.isfinite(F)):
            return None
        G = np.append(F, row @ (u - u_pred))
        if lu is None:
            if factorisations == options.max_newton:
                return None
            try:
                factor = getattr(problem, "factor_bordered", None)
                lu = factor(u, row) if factor is not None else _Bordered(problem.jacobian(u), row)
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
        if fresh and size > NOISE_STALL * last_fresh and size <= NOISE_CORRECTION * options.tol \
                and np.max(np.abs(F)) <= NOISE_RESIDUAL * options.residual_tol:
            return u, it, lu  # at the noise floor: the corrections are rounding noise, F is zero already
        if size > 2.0 * last:  # diverging even with a fresh Jacobian
            return None
        if fresh:
            last_fresh = size
        fresh, last = False, size
        u = u + du
        if size <= options.tol and np.max(np.abs(F)) <= options.residual_tol:
            # F was within tolerance before this correction, and the correction is: the corrected u
            # is nearer still, and F there need not be evaluated (one residual of the ~4 a step takes)
            return u, it, lu
        F = problem.residual(u)
        if size <= options.tol and np.all(np.isfinite(F)) and np.max(np.abs(F)) <= options.residual_tol:
            return u, it, lu
    return None


def step(problem: CurveProblem, point: CurvePoint, h: float, options: ContinuationOptions,
         with_tangent: bool = True, curvature: np.ndarray | None = None) -> CurvePoint | None:
    """One predictor-corrector step of length h from ``point`` (None if Newton fails, or if the
    corrected point lies farther than ``options.max_correction * h`` from the predictor).

    ``with_tangent=False`` skips the new tangent (one factorisation) for trial points whose
    tangent is not needed; the returned point then carries the old one. ``curvature``: an
    estimate of dt/ds orthogonal to the tangent (:meth:`Tracer.curvature`); the predictor then
    is u + h t + h^2/2 dt/ds, which starts Newton nearer the curve. The corrector's hyperplane
    <t, u - u_pred>_w = 0 is the same with or without it (the added term is orthogonal to t),
    so it changes the point found only within the Newton tolerance.
    """
    predictor = point.u + h * point.tangent
    if curvature is not None:
        predictor = predictor + (0.5 * h * h) * curvature
    out = correct(problem, predictor, point.tangent, options)
    if out is None:
        return None
    u, iterations, factors = out
    if math.isfinite(options.max_correction) and \
            weighted_norm(u - predictor, problem.weights) > options.max_correction * abs(h):
        return None
    if not with_tangent:
        return CurvePoint(u, point.tangent, iterations)
    try:
        t = tangent(problem, u, point.tangent, factors)
    except (RuntimeError, ValueError, np.linalg.LinAlgError):
        return None
    if not np.all(np.isfinite(t)):
        return None
    return CurvePoint(u, t, iterations)


#: A guided step (:meth:`Tracer.advance_to`) may be this much longer than a limit set on the tracer's
#: next step (:meth:`Tracer.limit_step`): a step's h is its predictor's length, a guided one's the
#: distance it went, and the nearby curve's points kept the limit as h (at 1.0, nes's torus curves
#: took 56 points where the nearby curve had 47, their guides refused there).
GUIDED_CAP = 1.5


class Tracer:
    """Successive points of a curve with step-size control.

    ``chord(problem, a, b, h)``, optional: the error of drawing the step from point a to point b
    (arclength h) as a straight segment, over what the caller allows (for example the deviation
    of the cubic through both points and tangents from their chord, in the coordinates that are
    drawn). A step with a ratio above 1 is refused and retried shorter (the error grows like
    h^2); the step grows only while the ratio is at most 0.5."""

    def __init__(self, problem: CurveProblem, start: CurvePoint, options: ContinuationOptions,
                 chord: Callable[[Any, CurvePoint, CurvePoint, float], float] | None = None):
        self.problem, self.options = problem, options
        self.chord = chord
        self.point = start
        self.h = options.ds
        self.failed: Stop | None = None
        self.cap = math.inf  # the next step's limit (limit_step), for a guided step
        #: (problem, point, previous tangent, step between them) after an accepted step: the
        #: curvature estimate's data, valid while the problem and the point are those
        self._last: tuple | None = None

    def curvature(self) -> np.ndarray | None:
        """dt/ds at the current point, orthogonal to its tangent (weighted), from the tangents
        before and after the last step; None without a last step on this problem (the start, or
        a point or problem set from outside: a new mesh). Capped so that the predictor's bend
        over the step is at most 0.3 h (a turn of ~17 degrees over the step)."""
        if not self._current():
            return None
        _, point, before, h_last = self._last
        w = self.problem.weights
        t = point.tangent
        c = (t - before) / h_last
        c = c - float(np.sum(w * c * t)) * t
        size = weighted_norm(c, w)
        if not math.isfinite(size):
            return None
        cap = 0.6 / max(self.h, 1e-300)  # |h^2/2 c| <= 0.3 h
        return c if size <= cap else c * (cap / size)

    def _current(self) -> bool:
        return self._last is not None and self._last[0] is self.problem and self._last[1] is self.point

    def advance(self) -> tuple[CurvePoint, float] | None:
        """The next point and the step that reached it; None (with ``failed`` set) if h < ds_min.

        The predictor follows the curvature of the last step (:meth:`curvature`); a step whose
        corrector fails from it is tried once from the straight predictor before it is shortened."""
        opts = self.options
        while True:
            bend = self.curvature()
            new = step(self.problem, self.point, self.h, opts, curvature=bend)
            if new is None and bend is not None:
                new = step(self.problem, self.point, self.h, opts)
            angle = self._turn(new) if new is not None else 0.0
            chord = self.chord(self.problem, self.point, new, self.h) if new is not None and self.chord else 0.0
            last_chance = self.h * opts.shrink < opts.ds_min
            if new is not None and ((angle <= opts.max_angle and chord <= 1.0) or last_chance):
                taken = self.h
                if new.iterations <= 4 and angle <= 0.5 * opts.max_angle and chord <= 0.5:
                    self.h = min(self.h * opts.grow, opts.ds_max)
                return self._take(new, taken)
            if new is not None and angle <= opts.max_angle:  # refused for its chord: to ~0.8 of the limit
                self.h *= min(opts.shrink, max(0.2, 0.9 / math.sqrt(chord)))
            else:
                self.h *= opts.shrink
            if self.h < opts.ds_min:
                self.failed = Stop(StopReason.NEWTON_FAILED, f"Newton did not converge with step "
                                   f"{self.h / opts.shrink:.2g} (minimum {opts.ds_min:g})")
                return None

    def advance_to(self, predictor: np.ndarray, direction: np.ndarray) -> tuple[CurvePoint, float] | None:
        """The next point from a given predictor (a guide's: a point of a nearby curve moved by the
        last shift, :mod:`~shimmy.continuation.cycle_curves.guide`) and a direction (that curve's
        chord there): Newton on the hyperplane through the predictor normal to the direction. Taken
        as :meth:`advance` takes a step (converged, ahead of the current point, within
        ``max_correction`` of the predictor, turned and off its chord within the limits, no longer
        than ``ds_max`` or ``GUIDED_CAP`` times the step :meth:`limit_step` set) and then
        returned with its step, the next step length being this one; else None, the tracer unchanged."""
        opts, problem = self.options, self.problem
        w = problem.weights
        size = weighted_norm(direction, w)
        if not (math.isfinite(size) and size > 0.0):
            return None
        t = direction / size
        out = correct(problem, predictor, t, opts)
        if out is None:
            return None
        u, iterations, _ = out
        d = u - self.point.u
        h = weighted_norm(d, w)
        # ahead, and within the tracer's limits on its own steps (ds_max; a step limited near an end,
        # with room for the distance between points being longer than the step that predicted them)
        if not (h > 0.0 and float(np.sum(w * d * self.point.tangent)) > 0.0
                and h <= min(opts.ds_max, GUIDED_CAP * self.cap)):
            return None
        if math.isfinite(opts.max_correction) and weighted_norm(u - predictor, w) > opts.max_correction * h:
            return None
        try:
            t_new = tangent(problem, u, t)
        except (RuntimeError, ValueError, np.linalg.LinAlgError):
            return None
        if not np.all(np.isfinite(t_new)):
            return None
        new = CurvePoint(u, t_new, iterations)
        strays = self.chord is not None and self.chord(problem, self.point, new, h) > 1.0
        if self._turn(new) > opts.max_angle or strays:
            return None
        self.h = min(max(h, opts.ds_min), opts.ds_max)
        return self._take(new, h)

    def _take(self, new: CurvePoint, h: float) -> tuple[CurvePoint, float]:
        """``new`` (reached by a step h) is the curve's next point."""
        self.problem.accept(new.u)
        self._last = (self.problem, new, self.point.tangent, h)
        self.point = new
        self.cap = math.inf
        return new, h

    def _turn(self, new: CurvePoint) -> float:
        """Angle (rad) between the tangents before and after a step, in the weighted inner product."""
        if not math.isfinite(self.options.max_angle):
            return 0.0
        w = self.problem.weights
        c = float(np.sum(w * self.point.tangent * new.tangent))
        c /= max(weighted_norm(self.point.tangent, w) * weighted_norm(new.tangent, w), 1e-300)
        return math.acos(max(-1.0, min(1.0, c)))

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
        crossed = (prev.u[index] - bound) * (value - bound) < 0  # not when the step started outside
        at = point_at(self.problem, prev, new, index, bound, self.options, with_tangent=True) if crossed else None
        if at is None:
            hit = locate(self.problem, prev, h, lambda q: q.u[index] - bound, prev.u[index] - bound, value - bound,
                         self.options)
            at = None if hit is None else hit[0]
        return prev, at, h, bound

    def limit_step(self, h_max: float) -> None:
        """The next step at most h_max (at least ``ds_min``), a guided one (:meth:`advance_to`) too."""
        self.h = max(min(self.h, h_max), self.options.ds_min)
        self.cap = max(h_max, self.options.ds_min)


#: In a search whose g may jump (:func:`locate` with ``report``): a trial whose |g| is over this many
#: times both ends' of the step is across a jump (the pd torus curve's multiplier test: ends -5.7e-4
#: and +2.7e-4, a trial +3.5), and so is a step with one end over this many times the other's and
#: over JUMP_SIZE (a half of a split step ending inside the jump: -9e-4 and +3.77). A g that stays
#: within its ends' size is searched as any other.
JUMP_RATIO = 100.0
JUMP_SIZE = 0.1


def locate(problem: CurveProblem, start: CurvePoint, h_end: float, g: Callable[[CurvePoint], float],
           g_start: float, g_end: float, options: ContinuationOptions,
           with_tangent: bool = True, x_tol: float = 1e-4,
           report: dict | None = None) -> tuple[CurvePoint, float] | None:
    """Zero of g between ``start`` (h = 0) and the point at step h_end (Illinois secant on h).

    Returns (point, g at it), or None if a trial step fails to converge. ``with_tangent=False``
    when g does not read the tangent: the trial points then carry the start's (one
    factorisation fewer per trial).

    With ``report`` (a dict; a g that may jump, whose sign change then has no zero to reach):
    once a trial finds a jump (``JUMP_RATIO``) the search bisects (the secant creeps towards a
    jump: a bracket from -2e-4 to +3.4 took 15 trials to move off its near end) and ends, with
    ``report["collapsed"] = True``, once the bracket is narrower than ``x_tol`` times h_end.
    """
    a, b, ga, gb = 0.0, h_end, g_start, g_end
    best = None
    side = 0
    big = JUMP_RATIO * max(abs(g_start), abs(g_end))
    small, large = sorted((abs(g_start), abs(g_end)))
    # g jumping (searched with ``report`` only): a trial found it, or one end is on the far side of a jump
    jump = report is not None and large > max(JUMP_RATIO * small, JUMP_SIZE)
    if math.isfinite(options.max_correction):  # bracketed by two accepted points: no branch to jump to
        options = dataclasses.replace(options, max_correction=math.inf)
    for _ in range(options.max_locate):
        h = b - gb * (b - a) / (gb - ga) if gb != ga else 0.5 * (a + b)
        if not (min(a, b) < h < max(a, b)) or jump:
            h = 0.5 * (a + b)
        trial = step(problem, start, h, options, with_tangent)
        if trial is None:  # e.g. landed exactly on a singular point (a branch point): nudge off it
            trial = step(problem, start, h * (1.0 + 1e-7), options, with_tangent) \
                or step(problem, start, h * (1.0 - 1e-7), options, with_tangent)
        if trial is None:
            return best
        gh = g(trial)
        best = (trial, gh)
        if abs(gh) <= options.locate_tol:
            return best
        jump = jump or (report is not None and abs(gh) > big)
        if jump and abs(b - a) <= x_tol * abs(h_end):
            report["collapsed"] = True
            return best
        if abs(b - a) <= 1e-13 * abs(h_end):
            return best
        if gh * gb < 0:
            a, ga = b, gb
            side = 0
        else:
            ga = ga * 0.5 if side == 1 else ga  # Illinois: halve the retained end's value
            side = 1
        b, gb = h, gh
    return best


def point_at(problem: CurveProblem, a: CurvePoint, b: CurvePoint, index: int, value: float,
             options: ContinuationOptions, with_tangent: bool = False) -> CurvePoint | None:
    """The point of the curve between two of its points a and b where unknown ``index`` equals
    ``value`` (which it crosses between them): one Newton solve with that unknown held at the value
    (the corrector with the bordering row e_index), from the cubic through a and b with their
    tangents (``_hermite_at``; from the chord between them where that fails). Cheaper than a
    secant search (:func:`locate`), which corrects a whole trial step per iteration. None if Newton
    does not converge, or converges farther from the chord than the distance from a to b (another
    part of the curve, or one where it is tangent to the level): callers then :func:`locate`.
    The point carries its own tangent (oriented along a's) with ``with_tangent``, else a's."""
    ga, gb = a.u[index] - value, b.u[index] - value
    if not ga * gb < 0:
        raise InvalidInputError("value", value, f"a value of unknown {index} crossed between the two points "
                                f"({a.u[index]:g} and {b.u[index]:g})")
    w = problem.weights
    hold = np.zeros_like(a.u)
    hold[index] = 1.0 / w[index]  # bordering row w * hold = e_index: u[index] = value
    chord = ga / (ga - gb)
    out = None
    for guess in (_hermite_at(a, b, index, value, chord, w), a.u + chord * (b.u - a.u)):
        if guess is None:
            continue
        guess[index] = value
        out = correct(problem, guess, hold, options)
        if out is not None and weighted_norm(out[0] - guess, w) <= weighted_norm(b.u - a.u, w):
            break
        out = None
    if out is None:
        return None
    u, iterations, _ = out
    if not with_tangent:
        return CurvePoint(u, a.tangent, iterations)
    try:
        t = tangent(problem, u, a.tangent)
    except (RuntimeError, ValueError, np.linalg.LinAlgError):
        return None
    return CurvePoint(u, t, iterations) if np.all(np.isfinite(t)) else None


def _hermite_at(a: CurvePoint, b: CurvePoint, index: int, value: float, theta: float,
                w: np.ndarray) -> np.ndarray | None:
    """The point where unknown ``index`` equals ``value`` on the cubic through a and b with their
    tangents (arclength the chord's, weighted): nearer the curve than the chord (its error ~h^4,
    the chord's ~h^2), so Newton from it takes fewer iterations. ``theta`` (the chord's fraction)
    starts a scalar Newton on the cubic's ``index`` component; None where that leaves [0, 1] or
    the tangents point against the chord (a tangent carried from an earlier point)."""
    d = b.u - a.u
    h = weighted_norm(d, w)
    if not (h > 0.0 and np.sum(w * d * a.tangent) > 0.0 and np.sum(w * d * b.tangent) > 0.0):
        return None
    ends = (a.u, h * a.tangent, b.u, h * b.tangent)  # the cubic's values and slopes at theta = 0 and 1

    def cubic(theta, k=slice(None), slope=False):  # the cubic (or its slope in theta) at theta
        t2 = theta * theta
        basis = ((6 * t2 - 6 * theta, 3 * t2 - 4 * theta + 1, 6 * theta - 6 * t2, 3 * t2 - 2 * theta) if slope else
                 (2 * t2 * theta - 3 * t2 + 1, t2 * theta - 2 * t2 + theta, 3 * t2 - 2 * t2 * theta, t2 * theta - t2))
        return sum(c * e[k] for c, e in zip(basis, ends, strict=True))

    for _ in range(8):
        df = cubic(theta, index, slope=True)
        if df == 0.0:
            return None
        theta -= (cubic(theta, index) - value) / df
        if not 0.0 <= theta <= 1.0:
            return None
    return cubic(theta)


def locate_between(problem: CurveProblem, a: CurvePoint, b: CurvePoint, g: Callable[[CurvePoint], float],
                   g_a: float, g_b: float, options: ContinuationOptions, tolerance: float,
                   splits: int = 6, with_tangent: bool = True,
                   x_tol: float | None = None) -> tuple[CurvePoint, float] | None:
    """Zero of g between two points of a curve, to |g| <= ``tolerance``: :func:`locate` from a;
    where a trial step fails (a long step across a sharp bend), the step is halved on the curve
    and the half that holds the sign change is searched, at most ``splits`` times.

    ``x_tol``: for a g that may jump (its sign change then no zero), the search ends, None, once
    its bracket is narrower than this fraction of the step, and is not split again (the split
    halves would only close in on the jump again)."""
    h = weighted_norm(b.u - a.u, problem.weights)
    if options.locate_tol != tolerance:
        options = replace(options, locate_tol=tolerance)
    report: dict = {}
    hit = locate(problem, a, h, g, g_a, g_b, options, with_tangent,
                 **({} if x_tol is None else {"x_tol": x_tol, "report": report}))
    if hit is not None and abs(hit[1]) <= tolerance:
        return hit
    if splits == 0 or report.get("collapsed"):
        return None
    mid = step(problem, a, 0.5 * h, options)
    if mid is None:
        return None
    g_mid = g(mid)
    if not math.isfinite(g_mid):
        return None
    if abs(g_mid) <= tolerance:
        return mid, g_mid
    if g_a * g_mid < 0:
        return locate_between(problem, a, mid, g, g_a, g_mid, options, tolerance, splits - 1, with_tangent, x_tol)
    return locate_between(problem, mid, b, g, g_mid, g_b, options, tolerance, splits - 1, with_tangent, x_tol)
