"""Two-parameter continuation of Hopf points of equilibria, with generalised Hopf (GH) points.

Generic (any :class:`~.fields.TwoParameterField`). Unknowns u = (x, a, b, omega, p1, p2) with
q = a + i b the critical eigenvector, and the 3n + 2 equations (the standard extended
system, Kuznetsov 3rd ed., sec. 10.2.2):

    f(x, p) = 0,   J a + omega b = 0,   J b - omega a = 0,   <c, a> = 1,   <c, b> = 0,

c being the previous point's a / |a|^2 (moved at every accepted point). The Jacobian
uses the analytic f_x and f_p; the second derivatives (f_xx a, f_xx b, f_xp a, f_xp b)
are central differences of the analytic Jacobian along a, b and the parameters, with
steps 1e-5 of the respective scales (relative error ~1e-10, far below Newton's needs:
they only enter the Newton matrix, the residual is exact).

Along the curve: double-Hopf points (a second pair of eigenvalues crosses the imaginary axis)
and zero-Hopf points (a real eigenvalue crosses zero), from sign changes of products of the
other eigenvalues' real parts, located by the secant method; the first Lyapunov coefficient
l1 (:mod:`shimmy.continuation.lyapunov`) at every point when the field is smooth; a sign
change is a generalised Hopf (Bautin) point, located by the secant method on l1; turning points
in p2 are located too. Each is a :class:`~shimmy.continuation.SpecialPoint` (GH, HH, ZH, P2_TURN)
at p = (p1, p2). omega falling to zero ends the curve (a Bogdanov-Takens point or a double zero
eigenvalue). The curve also ends where it
leaves the parameter box (end point located on the boundary), returns to its start
(closed curve), or after the step budget.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from . import lyapunov
from .core import ContinuationOptions, CurvePoint, Tracer, correct, locate, tangent, weighted_norm
from .fields import TwoParameterField
from .kinds import PointKind, Stop, StopReason
from .results import ContinuationResult, SpecialPoint


class HopfCurveProblem:
    def __init__(self, system: TwoParameterField, x_scale: np.ndarray, p_scale: np.ndarray):
        self.system = system
        n = system.n
        self.n = n
        self.x_scale = np.asarray(x_scale, float)
        self.p_scale = np.asarray(p_scale, float)
        # Eigenvector entries are normalised by <c, a> = 1: unit scale in the metric, small weight.
        self.weights = np.concatenate([1.0 / self.x_scale ** 2, np.full(2 * n, 1e-2 / n), [1e-2],
                                       1.0 / self.p_scale ** 2])
        self.c = np.zeros(n)

    def split(self, u):
        n = self.n
        return u[:n], u[n:2 * n], u[2 * n:3 * n], u[3 * n], u[3 * n + 1:3 * n + 3]

    def accept(self, u):
        _, a, _, _, _ = self.split(u)
        self.c = a / float(a @ a)

    def residual(self, u):
        x, a, b, omega, p = self.split(u)
        J = self.system.dfdx(x, p)
        return np.concatenate([self.system.f(x, p), J @ a + omega * b, J @ b - omega * a,
                               [self.c @ a - 1.0, self.c @ b]])

    def jacobian(self, u):
        n = self.n
        x, a, b, omega, p = self.split(u)
        s = self.system
        J = s.dfdx(x, p)

        def along(v):  # d/de J(x + e v) (central difference)
            h = 1e-5 / max(float(np.max(np.abs(v) / self.x_scale)), 1e-300)
            return (s.dfdx(x + h * v, p) - s.dfdx(x - h * v, p)) / (2.0 * h)

        def in_p(k):  # d/dp_k J
            h = 1e-5 * self.p_scale[k]
            e = np.zeros(2)
            e[k] = h
            return (s.dfdx(x, p + e) - s.dfdx(x, p - e)) / (2.0 * h)

        Ja, Jb = along(a), along(b)
        Jp = [in_p(0), in_p(1)]
        fp = s.dfdp(x, p).T  # (n, 2)
        out = np.zeros((3 * n + 2, 3 * n + 3))
        eye = np.eye(n)
        out[:n, :n], out[:n, 3 * n + 1:] = J, fp
        out[n:2 * n, :n] = Ja
        out[n:2 * n, n:2 * n] = J
        out[n:2 * n, 2 * n:3 * n] = omega * eye
        out[n:2 * n, 3 * n] = b
        out[n:2 * n, 3 * n + 1] = Jp[0] @ a
        out[n:2 * n, 3 * n + 2] = Jp[1] @ a
        out[2 * n:3 * n, :n] = Jb
        out[2 * n:3 * n, n:2 * n] = -omega * eye
        out[2 * n:3 * n, 2 * n:3 * n] = J
        out[2 * n:3 * n, 3 * n] = -a
        out[2 * n:3 * n, 3 * n + 1] = Jp[0] @ b
        out[2 * n:3 * n, 3 * n + 2] = Jp[1] @ b
        out[3 * n, n:2 * n] = self.c
        out[3 * n + 1, 2 * n:3 * n] = self.c
        return out

    def lyapunov(self, u) -> float:
        x, _, _, _, p = self.split(u)
        columns = (lambda Z: self.system.dfdx(x[:, None] + Z, p)) if self.system.complex_columns else None
        return lyapunov.first_lyapunov_coefficient(lambda z: self.system.dfdx(x + z, p), self.n, columns=columns)


@dataclass
class HopfCurve(ContinuationResult):
    """Points of a Hopf curve (one row per point) and its special points, each at p = (p1, p2) with
    the critical frequency ``omega`` in its data: generalised Hopf (GH, with its ``lyapunov``),
    double Hopf (HH, with the other pair's ``omega2``), zero-Hopf (ZH) and the turning points in p2
    (P2_TURN)."""

    p: np.ndarray  # (points, 2)
    x: np.ndarray  # (points, n)
    omega: np.ndarray
    lyapunov: np.ndarray  # nan where the field is not smooth

    def to_dict(self) -> dict[str, Any]:
        return {"p": self.p.tolist(), "x": self.x.tolist(), "omega": self.omega.tolist(),
                "lyapunov": [None if not math.isfinite(v) else float(v) for v in self.lyapunov],
                **super().to_dict()}


def hopf_start(x: np.ndarray, p: np.ndarray, J: np.ndarray) -> tuple[np.ndarray, float]:
    """(u0 without parameters, omega) from an equilibrium x at a Hopf point with Jacobian J."""
    ev, vecs = np.linalg.eig(J)
    i = int(np.argmin(np.abs(ev.real) + np.where(ev.imag > 0, 0.0, np.inf)))
    q = vecs[:, i]
    q = q / q[np.argmax(np.abs(q))]  # a has a 1 where |q| is largest, b a 0 there
    return np.concatenate([x, q.real, q.imag]), float(ev[i].imag)


def hopf_curve(system: TwoParameterField, x0: np.ndarray, p0: np.ndarray, *,
               box: tuple[tuple[float, float], tuple[float, float]], options: ContinuationOptions | None = None,
               scale: np.ndarray | None = None, p_scale: tuple[float, float] = (1.0, 1.0)) -> HopfCurve:
    """Continue the Hopf point (x0, p0) both ways until it leaves ``box`` ((p1 range), (p2 range)).

    ``scale`` (n,) and ``p_scale`` set the size of a unit step in the states and in (p1, p2)."""
    options = options or ContinuationOptions(ds=0.05, ds_max=2.0, max_steps=400)
    problem = HopfCurveProblem(system, np.ones(system.n) if scale is None else scale, p_scale)
    p0 = np.asarray(p0, float)
    head, omega0 = hopf_start(np.asarray(x0, float), p0, system.dfdx(np.asarray(x0, float), p0))
    u0 = np.concatenate([head, [omega0], p0])
    problem.accept(u0)
    guess = np.zeros_like(u0)
    guess[-1] = 1.0  # first correction at fixed p2
    out = correct(problem, u0, guess / weighted_norm(guess, problem.weights), options)
    if out is None:
        raise ValueError(f"no Hopf point converged near p = {p0.tolist()}")
    u0 = out[0]
    problem.accept(u0)
    t0 = tangent(problem, u0, guess)
    halves, stops, steps, closed = [], [], 0, False
    for sign in (1.0, -1.0):
        problem.accept(u0)
        part, stop, n_steps = _trace(problem, CurvePoint(u0, sign * t0), box, options, u0)
        halves.append(part)
        stops.append(stop)
        steps += n_steps
        if stop.reason is StopReason.CLOSED:
            closed = True
            break
    points = halves[-1] if closed else halves[1][::-1] + halves[0][1:]  # the half that closed is the loop
    U = np.array([q.u for q in points])
    n = system.n
    l1 = np.array([problem.lyapunov(u) if system.smooth else math.nan for u in U])
    special = []
    if system.smooth:
        for i in range(len(points) - 1):
            if np.isfinite(l1[i]) and np.isfinite(l1[i + 1]) and l1[i] * l1[i + 1] < 0:
                special.append(_locate_gh(problem, points[i], points[i + 1], l1[i], l1[i + 1], options, i + 1))
    special += _other_crossings(problem, points, options)
    for i in range(len(points) - 1):
        ta, tb = points[i].tangent[-1], points[i + 1].tangent[-1]
        if ta * tb < 0 and np.dot(points[i].tangent, problem.weights * points[i + 1].tangent) > 0:
            a = _toward(problem, points[i], points[i + 1])
            problem.accept(a.u)
            h = weighted_norm(points[i + 1].u - a.u, problem.weights)
            sign = 1.0 if a.tangent[-1] == ta else -1.0  # the test along the step's direction
            hit = locate(problem, a, h, lambda q: q.tangent[-1], sign * ta, sign * tb, options)
            at = hit[0] if hit is not None else points[i]
            special.append(_special(problem, PointKind.P2_TURN, at, i + 1, hit is not None))
    special.sort(key=lambda s: s.index)
    return HopfCurve(U[:, 3 * n + 1:], U[:, :n], U[:, 3 * n], l1, special_points=special, stops=stops, steps=steps,
                     closed=closed)


def _special(problem: HopfCurveProblem, kind: PointKind, at: CurvePoint, index: int, located: bool,
             **data: float) -> SpecialPoint:
    """A special point of a Hopf curve at the curve point ``at``: p = (p1, p2), omega and ``data``."""
    n = problem.n
    return SpecialPoint(kind, tuple(at.u[3 * n + 1:].tolist()), index, {"omega": float(at.u[3 * n]), **data},
                        located)


def _other_eigenvalues(problem: HopfCurveProblem, u: np.ndarray) -> np.ndarray:
    """Eigenvalues of f_x at a Hopf-curve point without the critical pair +-i omega."""
    x, _, _, omega, p = problem.split(u)
    ev = np.linalg.eigvals(problem.system.dfdx(x, p))
    keep = np.ones(ev.size, bool)
    for target in (1j * omega, -1j * omega):
        d = np.where(keep, np.abs(ev - target), np.inf)
        keep[int(np.argmin(d))] = False
    return ev[keep]


def _crossing_tests(problem: HopfCurveProblem, u: np.ndarray) -> tuple[float, float]:
    """(double Hopf, zero Hopf) test functions: the products of tanh(Re lambda / |omega|) over the
    other complex pairs (one of each) and over the real eigenvalues; each changes sign where one
    of its eigenvalues crosses the imaginary axis."""
    ev = _other_eigenvalues(problem, u)
    omega = abs(float(problem.split(u)[3]))
    scale = max(omega, 1e-12)
    real = np.abs(ev.imag) <= 1e-9 * np.maximum(np.abs(ev), 1e-300)
    pairs = ev[~real & (ev.imag > 0)]
    hh = float(np.prod(np.tanh(pairs.real / scale))) if pairs.size else math.nan
    zh = float(np.prod(np.tanh(ev[real].real / scale))) if real.any() else math.nan
    return hh, zh


def _other_crossings(problem: HopfCurveProblem, points: list[CurvePoint],
                     options: ContinuationOptions) -> list[SpecialPoint]:
    """Double-Hopf (a second pair on the imaginary axis) and zero-Hopf (a zero eigenvalue) points
    along the curve, each located by the secant method on its test function."""
    tests = np.array([_crossing_tests(problem, q.u) for q in points])
    found = []
    for which in (0, 1):
        g = tests[:, which]
        for i in range(len(points) - 1):
            if not (np.isfinite(g[i]) and np.isfinite(g[i + 1]) and g[i] * g[i + 1] < 0):
                continue
            a = _toward(problem, points[i], points[i + 1])
            problem.accept(a.u)
            h = weighted_norm(points[i + 1].u - a.u, problem.weights)
            hit = locate(problem, a, h, lambda q, w=which: _crossing_tests(problem, q.u)[w], g[i], g[i + 1], options)
            at = hit[0] if hit is not None else points[i + 1]
            if which == 0:
                ev = _other_eigenvalues(problem, at.u)
                pair = ev[ev.imag > 0]
                omega2 = float(pair[np.argmin(np.abs(pair.real))].imag) if pair.size else math.nan
                found.append(_special(problem, PointKind.DOUBLE_HOPF, at, i + 1, hit is not None, omega2=omega2))
            else:
                found.append(_special(problem, PointKind.ZERO_HOPF, at, i + 1, hit is not None))
    return found


def _trace(problem: HopfCurveProblem, start: CurvePoint, box, options: ContinuationOptions, u0):
    tracer = Tracer(problem, start, options)
    points = [start]
    n = problem.n
    (lo1, hi1), (lo2, hi2) = box
    travelled = 0.0
    for k in range(1, options.max_steps + 1):
        prev = tracer.point
        adv = tracer.advance()
        if adv is None:
            return points, tracer.failed, k
        new, h = adv
        travelled += h
        p1, p2 = new.u[3 * n + 1], new.u[3 * n + 2]
        for idx, lo, hi in ((3 * n + 1, lo1, hi1), (3 * n + 2, lo2, hi2)):
            value = new.u[idx]
            if not lo <= value <= hi:
                bound = hi if value > hi else lo
                hit = locate(problem, prev, h, lambda q, i=idx, b=bound: q.u[i] - b, prev.u[idx] - bound,
                             value - bound, options)
                if hit is not None:
                    points.append(hit[0])
                return points, Stop(StopReason.BOUND,
                                    f"left the parameter box at p{1 if idx == 3 * n + 1 else 2} = {bound:g}"), k
        if new.u[3 * n] <= 1e-6 * max(abs(start.u[3 * n]), 1.0):
            points.append(new)
            return points, Stop(StopReason.ZERO_FREQUENCY,
                                f"omega fell to zero at p = ({p1:.6g}, {p2:.6g}): Bogdanov-Takens point"), k
        points.append(new)
        # Closed curve: back at the start, heading the same way.
        if travelled > 4 * options.ds_max and weighted_norm(new.u - u0, problem.weights) < 0.5 * h \
                and new.tangent @ (problem.weights * start.tangent) > 0:
            points.append(CurvePoint(u0, start.tangent))
            return points, Stop(StopReason.CLOSED, "closed curve: returned to its start"), k
    return points, Stop(StopReason.STEP_BUDGET, f"step budget of {options.max_steps} steps used"), options.max_steps


def _toward(problem: HopfCurveProblem, a: CurvePoint, b: CurvePoint) -> CurvePoint:
    """``a`` with its tangent pointing to ``b`` (the curve's first half is stored reversed, its
    tangents pointing away from the next point)."""
    if np.dot(a.tangent, problem.weights * (b.u - a.u)) >= 0:
        return a
    return CurvePoint(a.u, -a.tangent, a.iterations)


def _locate_gh(problem: HopfCurveProblem, a: CurvePoint, b: CurvePoint, la: float, lb: float,
               options: ContinuationOptions, index: int) -> SpecialPoint:
    a = _toward(problem, a, b)
    problem.accept(a.u)
    h = weighted_norm(b.u - a.u, problem.weights)
    hit = locate(problem, a, h, lambda q: problem.lyapunov(q.u), la, lb, options)
    at = hit[0] if hit is not None else b
    return _special(problem, PointKind.GENERALISED_HOPF, at, index, hit is not None,
                    lyapunov=float(problem.lyapunov(at.u)))
