"""Branches of periodic orbits: start at a Hopf point or from a sampled orbit, continue in p,
compute Floquet multipliers, detect and locate folds (LPC), tori (NS), period doubling (PD)
and branch points of cycles (BPC).

Generic (any :class:`~shimmy.continuation.VectorField`). Detection, between two
consecutive branch points:

* LPC: the parameter component of the tangent changes sign; located by the secant
  method on it (so a fold is found even where the stability does not change);
* the number of nontrivial multipliers outside the unit circle changes: the multiplier
  that crossed is the one of the more unstable point closest to the circle: a complex
  pair -> NS, real negative -> PD, real positive without a fold -> BPC. Located by the
  secant method on |mu| - 1 of the multipliers of that kind.

Stop rules, each a :class:`~shimmy.continuation.Stop` in ``stops``: a parameter bound (the end point is
located on the bound, kind EP); the step budget; the step size underflowing (Newton
failure); the period above ``period_max`` (approach to a homoclinic orbit or a
period blow-up); the caller's ``limits`` check (e.g. amplitude outside the model's
validity); the amplitude shrinking back to zero (the branch ends at a Hopf point of
the equilibrium). The mesh is re-adapted every ``adapt_every`` steps
(:meth:`PeriodicProblem.adapted_mesh`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from .collocation import Mesh, PeriodicProblem
from .core import ContinuationOptions, CurvePoint, Tracer, locate, step, tangent, weighted_norm
from .errors import ConvergenceError, InvalidInputError
from .fields import VectorField
from .kinds import PointKind, Stop, StopReason
from .results import ContinuationResult, SpecialPoint

COMPLEX_TOL = 1e-7  # |Im mu| below this (relative) counts as a real multiplier
#: At a fold of cycles the multiplier passing +1 meets the trivial one at +1; the two can come out of
#: the eigenvalue solver as a complex pair a hair off the real axis, which would count as a torus
#: crossing: a "torus" point whose pair is within this angle (rad) of +1 is no torus (nes_pd at
#: 278.5 kN: its fold at 130.25 m/s was also reported as a torus point, its pair at 6.6e-6 rad)
FOLD_PAIR_ANGLE = 1e-4


@dataclass(frozen=True)
class PeriodicOptions:
    ntst: int = 40
    ncol: int = 4
    adapt_every: int = 5
    period_max: float = math.inf
    amplitude_min: float = 0.05  # end at x*: amplitude below this fraction of the first orbit's (Hopf starts)
    continuation: ContinuationOptions = field(default_factory=ContinuationOptions)
    stop_at: tuple[PointKind, ...] = ()  # kinds of special point at which to end the branch (e.g. the first LPC)

    def __post_init__(self):
        if not (isinstance(self.ntst, int) and 4 <= self.ntst <= 2000):
            raise InvalidInputError("ntst", self.ntst, "an integer in [4, 2000]")
        if not (isinstance(self.ncol, int) and 2 <= self.ncol <= 7):
            raise InvalidInputError("ncol", self.ncol, "an integer in [2, 7]")


@dataclass
class PeriodicBranch(ContinuationResult):
    """Points of a branch of periodic orbits (one row per point) and its special points; one stop
    (two where a caller joins the branches continued both ways)."""

    p: np.ndarray
    period: np.ndarray
    x_max: np.ndarray  # (points, n) max over the orbit of every state
    x_min: np.ndarray
    stable: np.ndarray
    multipliers: np.ndarray  # (points, n) trivial first, then by decreasing modulus
    ntst: int
    ncol: int
    solutions: list[tuple[np.ndarray, np.ndarray]]  # (mesh points, u) per point
    trivial_error: float  # max |mu_trivial - 1| over the branch: accuracy check
    #: (points, 2 + 2n): derivatives along the branch, per unit arclength (the weighted norm), of
    #: p, T, x_max and x_min at each point, from its tangent (a state's max over the orbit moves
    #: like the tangent at the instant of that max); None where they are not known
    rates: np.ndarray | None = None
    #: (points,): arclength (weighted chord) from the previous point to each point, 0 at the first
    lengths: np.ndarray | None = None

    def to_dict(self) -> dict[str, Any]:
        return {"p": self.p.tolist(), "period": self.period.tolist(), "x_max": self.x_max.tolist(),
                "x_min": self.x_min.tolist(), "stable": self.stable.tolist(),
                "multipliers_abs": np.abs(self.multipliers).tolist(), "ntst": self.ntst, "ncol": self.ncol,
                "trivial_error": self.trivial_error, **super().to_dict()}

    def between(self, i, sigma) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """p, T, x_max and x_min (rows: one per sigma) between point i (sigma = 0) and i + 1
        (sigma = 1) on the cubic Hermite polynomial, in arclength, through both points' values and
        rates (``i`` an index, or one per sigma). In arclength the branch is smooth where it is
        steep in p (at a Hopf point the amplitude grows linearly in s, p like s^2), so points taken
        from it are where a straight segment in p is not (p^(1/2) there)."""
        if self.rates is None or self.lengths is None:
            raise InvalidInputError("rates", None, "a branch with its rates and lengths")
        sigma = np.asarray(sigma, float).ravel()
        i = np.broadcast_to(np.asarray(i, int), sigma.shape)
        table = np.column_stack([self.p, self.period, self.x_max, self.x_min])
        h = self.lengths[i + 1][:, None]
        sigma = sigma[:, None]
        s2, s3 = sigma * sigma, sigma ** 3
        q = ((2 * s3 - 3 * s2 + 1) * table[i] + (s3 - 2 * s2 + sigma) * h * self.rates[i]
             + (3 * s2 - 2 * s3) * table[i + 1] + (s3 - s2) * h * self.rates[i + 1])
        n = self.x_max.shape[1]
        return q[:, 0], q[:, 1], q[:, 2:2 + n], q[:, 2 + n:]

    def orbit(self, i: int, system: VectorField, per_interval: int = 12) -> tuple[np.ndarray, np.ndarray]:
        """t (s) and x (k, n) of point i over one period."""
        mesh_points, u = self.solutions[i]
        problem = PeriodicProblem(system, Mesh(mesh_points, self.ncol), np.ones(system.n), 1.0, 1.0)
        tau, x = problem.sample(u, per_interval)
        return tau * self.period[i], x


@dataclass(frozen=True)
class OrbitGuess:
    """An approximate periodic orbit: node values x(tau) on a mesh, period and parameter."""

    mesh: Mesh
    X: np.ndarray  # (n_nodes, n)
    T: float
    p: float


def hopf_guess(x_star: np.ndarray, p_star: float, omega: float, q: np.ndarray, mesh: Mesh,
               amplitude: float) -> tuple[OrbitGuess, np.ndarray]:
    """Small orbit x* + amplitude Re(q e^(2 pi i tau)) at a Hopf point, and the direction Re(q e^...)."""
    tau = mesh.node_times
    q = q / np.abs(q).max()
    phi = np.real(q[None, :] * np.exp(2j * np.pi * tau)[:, None])
    X = np.asarray(x_star, float)[None, :] + amplitude * phi
    return OrbitGuess(mesh, X, 2.0 * np.pi / omega, float(p_star)), phi


def orbit_from_samples(t: np.ndarray, x: np.ndarray, period: float, p: float, mesh: Mesh) -> OrbitGuess:
    """A guess from one period of a sampled trajectory (t from t[0] to t[0] + period, x (k, n))."""
    tau = (np.asarray(t) - t[0]) / period
    X = np.column_stack([np.interp(mesh.node_times, tau, x[:, i]) for i in range(x.shape[1])])
    X[-1] = X[0]
    return OrbitGuess(mesh, X, float(period), float(p))


def _orbit_measures(problem: PeriodicProblem, u: np.ndarray):
    _, x = problem.sample(u)
    return x.max(axis=0), x.min(axis=0)


def _orbit_rates(problem: PeriodicProblem, point: CurvePoint, x: np.ndarray) -> np.ndarray:
    """d/ds of (p, T, x_max, x_min) at a point from its unit tangent (``x``: the orbit sampled by
    ``problem.sample``): a state's extreme over the orbit moves like the tangent's state part at
    the (sampled) instant of that extreme."""
    _, dx = problem.sample(point.tangent)
    columns = np.arange(x.shape[1])
    t = point.tangent
    return np.concatenate([[t[-1], t[-2]], dx[x.argmax(axis=0), columns], dx[x.argmin(axis=0), columns]])


def _amplitude(problem: PeriodicProblem, x_max, x_min) -> float:
    return float(np.max(0.5 * (x_max - x_min) / problem.scale))


def _count_unstable(mu: np.ndarray) -> int:
    return int((np.abs(mu[1:]) > 1.0).sum())


def _kind_of_crossing(mu_a: np.ndarray, mu_b: np.ndarray) -> PointKind:
    """The kind of the multiplier that crossed the unit circle between a and b, from which kind's
    count outside changed (complex pair -> NS, real negative -> PD, real positive -> BPC)."""
    ra, na, ca = _outside_by_kind(mu_a)
    rb, nb, cb = _outside_by_kind(mu_b)
    if cb != ca:
        return PointKind.TORUS
    if nb != na:
        return PointKind.PERIOD_DOUBLING
    return PointKind.BRANCH_POINT_OF_CYCLES


def multiplier_crossing_test(mu: np.ndarray, which: str, accuracy: float = 0.0) -> float:
    """Test function of a crossing of the unit circle by one multiplier of a kind
    ("positive" / "negative" real, "complex", a pair counted once) among ``mu``:
    (-1)^(how many of that kind lie outside) times the smallest |ln |mu|| among them.
    Continuous, zero exactly when one of them is on the circle, of the other sign once it has
    crossed; multipliers far from the circle (tiny ones flip between real kinds on rounding) do
    not change it. NaN when there is none of that kind, or when the nearest is closer to the
    circle than ``accuracy`` (its side is not resolved)."""
    real = np.abs(mu.imag) <= COMPLEX_TOL * np.abs(mu)
    sel = {"positive": mu[real & (mu.real > 0)], "negative": mu[real & (mu.real < 0)],
           "complex": mu[~real & (mu.imag > 0)]}[which]
    if sel.size == 0:
        return math.nan
    log_abs = np.log(np.maximum(np.abs(sel), 1e-300))
    nearest = float(np.min(np.abs(log_abs)))
    if nearest < accuracy:
        return math.nan
    return (-1.0) ** int((log_abs > 0).sum()) * nearest


def _crossing_test(kind: PointKind) -> Callable[[np.ndarray], float]:
    which = {PointKind.TORUS: "complex", PointKind.PERIOD_DOUBLING: "negative"}.get(kind, "positive")

    def g(mu: np.ndarray) -> float:
        return multiplier_crossing_test(mu[1:], which)
    return g


def periodic_branch(system: VectorField, guess: OrbitGuess, *, p_range: tuple[float, float],
                    options: PeriodicOptions | None = None, scale: np.ndarray | None = None, p_scale: float = 1.0,
                    direction: np.ndarray | None = None, p_direction: int = 1,
                    limits: Callable[[np.ndarray, np.ndarray, float, float], str | None] | None = None,
                    progress: Callable[[float], None] | None = None) -> PeriodicBranch:
    """Continue the periodic orbit near ``guess`` in p over ``p_range`` = (p_min, p_max).

    ``scale`` (n,) and ``p_scale`` set the size of a unit step in the states and p (the period's is
    the guess's period). ``direction`` (n_nodes, n): for a Hopf start, the emerging orbit shape
    (the first step moves along it with p and T free, so the orbit grows away from the
    equilibrium); otherwise the first correction holds p fixed and the branch follows
    ``p_direction`` (+1 increasing p). ``limits(x_max, x_min, T, p)`` returns a message
    to stop the branch. ``progress`` receives the covered fraction of [p_min, p_max].
    """
    p_min, p_max = p_range
    options = options or PeriodicOptions()
    scale = np.ones(system.n) if scale is None else scale
    copts = options.continuation
    mesh = guess.mesh if guess.mesh.ncol == options.ncol and guess.mesh.ntst == options.ntst \
        else Mesh.uniform(options.ntst, options.ncol)
    problem = PeriodicProblem(system, mesh, scale, guess.T, p_scale)
    if mesh is not guess.mesh:
        src = PeriodicProblem(system, guess.mesh, scale, guess.T, p_scale)
        X0 = src.evaluate(guess.X, mesh.node_times)
        D0 = None if direction is None else src.evaluate(direction, mesh.node_times)
    else:
        X0, D0 = guess.X, direction
    u_base = problem.pack(X0, guess.T, guess.p)
    problem.accept(u_base)
    w = problem.weights
    if D0 is not None:  # Hopf start: step of length ds along the orbit shape
        t0 = problem.pack(D0, 0.0, 0.0)
        t0 /= weighted_norm(t0, w)
        problem.accept(u_base + copts.ds * t0)  # phase reference: the predicted small orbit
        first = step(problem, CurvePoint(u_base, t0), copts.ds, copts)
        hopf_start = True
    else:
        t0 = np.zeros_like(u_base)
        t0[-1] = 1.0
        t0 /= weighted_norm(t0, w)
        first = step(problem, CurvePoint(u_base, t0), 0.0, copts)
        if first is not None:  # orient along p_direction
            t = first.tangent if first.tangent[-1] * p_direction >= 0 else -first.tangent
            first = CurvePoint(first.u, t, first.iterations)
        hopf_start = False
    if first is None:
        raise ConvergenceError("no periodic orbit converged near the starting guess "
                               f"(p = {guess.p:g}, T = {guess.T:g})")
    if not hopf_start:
        x_first = problem.unpack(first.u)[0]
        spread_first = np.ptp(x_first, axis=0) / problem.scale
        spread_guess = np.ptp(X0, axis=0) / problem.scale
        if spread_first.max() < 1e-3 * spread_guess.max():
            raise ConvergenceError(f"the orbit guess at p = {guess.p:g} collapsed onto an equilibrium "
                                   "(amplitude -> 0): no periodic orbit there")
    problem.accept(first.u)
    tracer = Tracer(problem, first, copts)

    mu0 = problem.multipliers(first.u)
    _, x0 = problem.sample(first.u)
    xmax0, xmin0 = x0.max(axis=0), x0.min(axis=0)
    rows: dict[str, list] = {"p": [first.u[-1]], "T": [first.u[-2]], "xmax": [xmax0], "xmin": [xmin0],
                             "mu": [mu0], "rate": [_orbit_rates(problem, first, x0)], "length": [0.0]}
    solutions = [(mesh.points.copy(), first.u.copy())]
    special: list[SpecialPoint] = []
    amp_first = _amplitude(problem, xmax0, xmin0)
    amp_peak = amp_last = amp_first
    stop = Stop(StopReason.STEP_BUDGET, f"step budget of {copts.max_steps} steps used")
    steps = 0
    span = p_max - p_min
    for steps in range(1, copts.max_steps + 1):  # noqa: B007 (steps is reported)
        out = tracer.advance_within(p_min, p_max)
        if out is None:
            stop = tracer.failed
            break
        prev, new, h, bound = out
        if bound is not None:
            if new is not None:
                _record(problem, rows, solutions, new, prev)
                special.extend(_detect(problem, rows, prev, new, copts))
                special.append(_special(problem, PointKind.END, new, rows))
            stop = Stop(StopReason.BOUND, f"reached the parameter bound p = {bound:g}")
            break
        p_new, T_new = new.u[-1], new.u[-2]
        if progress is not None:
            progress(min(1.0, abs(p_new - guess.p) / span))
        if T_new > options.period_max:
            stop = Stop(StopReason.PERIOD_LIMIT, f"period {T_new:.4g} at p = {p_new:.6g} above the limit "
                        f"{options.period_max:.4g} (homoclinic approach?); the branch ends at the last orbit below it")
            break
        if T_new <= 0:
            stop = Stop(StopReason.NONPOSITIVE_PERIOD, "period became non-positive: the continuation left the branch")
            break
        _record(problem, rows, solutions, new, prev)
        found = _detect(problem, rows, prev, new, copts)
        zero = amp_first if hopf_start else 1e-3 * amp_peak  # below this a cycle's amplitude counts as zero
        ends = [s for s in found if s.kind == PointKind.FOLD_OF_CYCLES
                and _amplitude(problem, np.array(s.data["x_max"]), np.array(s.data["x_min"])) < zero]
        if ends:  # a 'fold' at zero amplitude: the branch passed through the equilibrium
            for key in rows:
                rows[key].pop()
            solutions.pop()
            p_end = float(rows["p"][-1])
            special.append(SpecialPoint(PointKind.HOPF, p_end, len(rows["p"]) - 1, {"amplitude": amp_last}))
            stop = Stop(StopReason.ZERO_AMPLITUDE,
                        f"amplitude returned to zero near p = {p_end:.6g}: the branch ends at a Hopf point")
            break
        special.extend(found)
        wanted = [s.kind for s in found if s.kind in options.stop_at]
        if wanted:
            stop = Stop(StopReason.REQUESTED_POINT, f"stopped at the first {wanted[0]} point, as asked")
            break
        if _closed(problem, rows):
            stop = Stop(StopReason.CLOSED, "closed branch: the orbits returned to the first one (a loop of periodic "
                        "orbits, traversed once)")
            break
        amp = _amplitude(problem, rows["xmax"][-1], rows["xmin"][-1])
        amp_peak = max(amp_peak, amp)
        amp_stop = options.amplitude_min * amp_first if hopf_start else 1e-3 * amp_peak
        if limits is not None:
            message = limits(rows["xmax"][-1], rows["xmin"][-1], T_new, p_new)
            if message:
                stop = Stop(StopReason.LIMITS, message)
                break
        # Shrinking: approach x* with care (a Hopf start only once it has grown; a branch started
        # from an orbit may start at its largest one)
        if amp < amp_last and (amp_peak > 2.0 * amp_first or not hopf_start):
            if amp < amp_stop:
                special.append(SpecialPoint(PointKind.HOPF, float(p_new), len(rows["p"]) - 1, {"amplitude": amp}))
                stop = Stop(StopReason.ZERO_AMPLITUDE,
                            f"amplitude returned to zero near p = {p_new:.6g}: the branch ends at a Hopf point")
                break
            tracer.limit_step(0.7 * amp * h / (amp_last - amp))  # do not jump through zero amplitude
        amp_last = amp
        if options.adapt_every and steps % options.adapt_every == 0:
            new_mesh = problem.adapted_mesh(new.u)
            new_problem = PeriodicProblem(system, new_mesh, scale, problem.T_scale, p_scale)
            u_t = problem.transfer(new_problem, new.u)
            t_t = problem.transfer(new_problem, new.tangent)
            t_t /= weighted_norm(t_t, new_problem.weights)
            new_problem.accept(u_t)
            # Re-converge on the new mesh before going on (holding the parameter fixed).
            fixed = step(new_problem, CurvePoint(u_t, _p_direction(new_problem, u_t)), 0.0, copts)
            if fixed is not None:
                problem = new_problem
                t_new = tangent(problem, fixed.u, t_t)
                problem.accept(fixed.u)
                tracer.problem = problem
                tracer.point = CurvePoint(fixed.u, t_new)
    mu = np.array(rows["mu"])
    trivial = float(np.max(np.abs(mu[:, 0] - 1.0)))
    return PeriodicBranch(np.array(rows["p"]), np.array(rows["T"]), np.array(rows["xmax"]),
                          np.array(rows["xmin"]), np.abs(mu[:, 1:]).max(axis=1, initial=0.0) < 1.0, mu,
                          problem.mesh.ntst, problem.mesh.ncol, solutions, trivial, np.array(rows["rate"]),
                          np.array(rows["length"]), special_points=special, stops=[stop], steps=steps,
                          closed=stop.reason is StopReason.CLOSED)


def _measures(problem: PeriodicProblem, rows) -> np.ndarray:
    """Phase-free description of every point (one row each): p, T and every state's max and min, scaled."""
    return np.column_stack([np.asarray(rows["p"]) / problem.p_scale, np.asarray(rows["T"]) / problem.T_scale,
                            np.asarray(rows["xmax"]) / problem.scale, np.asarray(rows["xmin"]) / problem.scale])


def _closed(problem: PeriodicProblem, rows) -> bool:
    """Whether the last step passed the first orbit again (the branch is a closed loop).

    Orbits are compared by phase-free measures (p, T, extremes of every state): the step from
    the previous to the last point must pass the first point closer than a third of its
    length, after the branch has gone at least five steps away from it.
    """
    k = len(rows["p"])
    if k < 8:
        return False
    measures = _measures(problem, rows)
    first, prev, last = measures[0], measures[-2], measures[-1]
    seg = last - prev
    length = float(np.linalg.norm(seg))
    if length == 0.0:
        return False
    far = float(np.linalg.norm(measures - first, axis=1).max())
    if far < 5.0 * length:
        return False
    s = float(np.clip(np.dot(first - prev, seg) / length ** 2, 0.0, 1.0))
    return float(np.linalg.norm(prev + s * seg - first)) < length / 3.0


def _p_direction(problem: PeriodicProblem, u: np.ndarray) -> np.ndarray:
    t = np.zeros_like(u)
    t[-1] = 1.0
    return t / weighted_norm(t, problem.weights)


def _record(problem: PeriodicProblem, rows, solutions, point: CurvePoint, prev: CurvePoint) -> None:
    """Append a point; ``prev`` is the point its step started from (on the same mesh)."""
    _, x = problem.sample(point.u)
    xmax, xmin = x.max(axis=0), x.min(axis=0)
    rows["rate"].append(_orbit_rates(problem, point, x))
    rows["length"].append(weighted_norm(point.u - prev.u, problem.weights))
    rows["p"].append(point.u[-1])
    rows["T"].append(point.u[-2])
    rows["xmax"].append(xmax)
    rows["xmin"].append(xmin)
    rows["mu"].append(problem.multipliers(point.u))
    solutions.append((problem.mesh.points.copy(), point.u.copy()))


def _special(problem: PeriodicProblem, kind: PointKind, point: CurvePoint, rows, mu=None) -> SpecialPoint:
    xmax, xmin = _orbit_measures(problem, point.u)
    mu = problem.multipliers(point.u) if mu is None else mu
    data: dict[str, Any] = {"period": float(point.u[-2]), "x_max": xmax.tolist(), "x_min": xmin.tolist(),
                            "multipliers_abs": np.abs(mu[1:]).tolist()}
    if kind is PointKind.TORUS:
        rest = mu[1:]
        cand = rest[np.abs(rest.imag) > COMPLEX_TOL * np.abs(rest)]
        if cand.size:
            crit = cand[np.argmin(np.abs(np.abs(cand) - 1.0))]
            data["torus_angle"] = float(abs(np.angle(crit)))  # rad per period: the second frequency
    return SpecialPoint(kind, float(point.u[-1]), len(rows["p"]) - 1, data,
                        solution=(problem.mesh.points.copy(), point.u.copy()))


MAX_SPLITS = 8  # a step holding several crossings is halved at most this many times


def _outside_by_kind(mu: np.ndarray) -> tuple[int, int, int]:
    """Nontrivial multipliers outside the unit circle: (real positive, real negative, complex)."""
    rest = mu[1:]
    outside = rest[np.abs(rest) > 1.0]
    real = np.abs(outside.imag) <= COMPLEX_TOL * np.abs(outside)
    return int((real & (outside.real > 0)).sum()), int((real & (outside.real < 0)).sum()), int((~real).sum())


def _single_event(fold: bool, mu_a: np.ndarray, mu_b: np.ndarray) -> bool:
    """Whether the step holds at most one event: a fold (its real multiplier through +1), or one
    real multiplier through +1 or -1, or one complex pair through the circle."""
    ra, na, ca = _outside_by_kind(mu_a)
    rb, nb, cb = _outside_by_kind(mu_b)
    dr, dn, dc = rb - ra, nb - na, cb - ca
    if fold:
        return dn == 0 and dc == 0 and abs(dr) <= 1
    if dr + dn + dc == 0:  # multipliers changing kind outside the circle: no crossing
        return True
    changed = [d for d in (dr, dn, dc) if d]
    return len(changed) == 1 and (abs(dr) == 1 or abs(dn) == 1 or abs(dc) == 2)


def _detect(problem: PeriodicProblem, rows, prev: CurvePoint, new: CurvePoint,
            copts: ContinuationOptions) -> list[SpecialPoint]:
    """Special points between the last two recorded points (prev -> new), in order along the step.

    A step that holds more than one event (a fold and a torus point, two crossings) is halved,
    each half on the curve, until every event is alone in its piece (at most MAX_SPLITS times).
    """
    found = _events(problem, rows, prev, new, rows["mu"][-2], rows["mu"][-1], copts, MAX_SPLITS)
    return [s for _, s in sorted(found, key=lambda item: item[0])]


def _events(problem: PeriodicProblem, rows, a: CurvePoint, b: CurvePoint, mu_a: np.ndarray, mu_b: np.ndarray,
            copts: ContinuationOptions, splits: int, offset: float = 0.0) -> list[tuple[float, SpecialPoint]]:
    fold = a.tangent[-1] * b.tangent[-1] < 0
    h = weighted_norm(b.u - a.u, problem.weights)
    if splits > 0 and not _single_event(fold, mu_a, mu_b):
        mid = step(problem, a, 0.5 * h, copts)
        if mid is not None and mid.tangent @ (problem.weights * a.tangent) > 0:
            mu_mid = problem.multipliers(mid.u)
            h_mid = weighted_norm(mid.u - a.u, problem.weights)
            return (_events(problem, rows, a, mid, mu_a, mu_mid, copts, splits - 1, offset)
                    + _events(problem, rows, mid, b, mu_mid, mu_b, copts, splits - 1, offset + h_mid))
    found: list[tuple[float, SpecialPoint]] = []
    if fold:
        hit = locate(problem, a, h, lambda q: q.tangent[-1], a.tangent[-1], b.tangent[-1], copts)
        at = hit[0] if hit is not None else b
        found.append((offset + weighted_norm(at.u - a.u, problem.weights),
                      _special(problem, PointKind.FOLD_OF_CYCLES, at, rows)))
    if _count_unstable(mu_a) != _count_unstable(mu_b):
        kind = _kind_of_crossing(mu_a, mu_b)
        if not (kind is PointKind.BRANCH_POINT_OF_CYCLES and fold):
            g_mu = _crossing_test(kind)
            ga, gb = g_mu(mu_a), g_mu(mu_b)
            at = b
            if np.isfinite(ga) and np.isfinite(gb) and ga * gb < 0:
                hit = locate(problem, a, h, lambda q: g_mu(problem.multipliers(q.u)), ga, gb, copts)
                if hit is not None:
                    at = hit[0]
            point = _special(problem, kind, at, rows)
            if kind is PointKind.TORUS and point.data.get("torus_angle", math.pi) < FOLD_PAIR_ANGLE:
                return found  # a pair at +1 (a fold's multiplier beside the trivial one): not a torus
            found.append((offset + weighted_norm(at.u - a.u, problem.weights), point))
    return found
