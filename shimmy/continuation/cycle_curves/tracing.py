"""Tracing a curve of cycle bifurcations: :func:`cycle_curve` from a located point of a
one-parameter branch, both ways, and :func:`start_beside` for a start next to a codimension-2
point of an equilibrium.

Each direction is traced by the :class:`~shimmy.continuation.Tracer` on the curve's
``CycleCurveProblem``, the drawn polyline's chord held within ``chord_tol`` of
each parameter, the mesh re-adapted every ``adapt_every`` steps. Along the way: turning points
in p2 and crossings of marked p2 values (P2_TURN, P2_MARK), and the codimension-2 points
(:mod:`.codim2`). Stops, each a :class:`~shimmy.continuation.Stop`: the parameter box (end point located on
it), a closed curve, the amplitude shrinking to zero (the curve ends at a codimension-2 point of
the equilibrium: GH for a fold curve, a double-Hopf or zero-Hopf point for a torus curve), kappa
leaving [-1, 1] (past R1/R2 the torus condition describes neutral saddle cycles, not tori), the
period limit, step underflow, the step budget.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any, Callable

import numpy as np

from ..collocation import Mesh
from ..core import (GUIDED_CAP, ContinuationOptions, CurvePoint, Tracer, locate_between, point_at, step, tangent,
                    weighted_norm)
from ..errors import ContinuationError, ConvergenceError, InvalidInputError
from ..fields import TwoParameterField
from ..kinds import PointKind, Stop, StopReason
from ..lyapunov import hopf_eigenvectors
from ..periodic_orbits import PeriodicOptions, hopf_guess, periodic_branch
from ..results import ContinuationResult, SpecialPoint
from . import codim2
from .bordered import CycleCurveProblem, defining_system
from .guide import Guide


@dataclass(frozen=True)
class CycleCurveOptions:
    adapt_every: int = 10
    period_max: float = math.inf
    amplitude_min: float = 0.02  # end: amplitude below this fraction of the curve's largest
    #: ... and below this (in the problem's state scales): a trace that must reach at least as far
    #: towards an end as another trace of the same curve did (whose largest amplitude, and so whose
    #: end, depended on where it began) goes on to half that trace's end amplitude
    amplitude_end_below: float = math.inf
    #: the drawn polyline in (p1, p2): each step's chord strays from the curve (the midpoint of
    #: the cubic through both points with their tangents) by at most this fraction of each
    #: parameter (at least a tenth of its scale)
    chord_tol: float = 5e-3
    kappa_weight: float = 1.0
    continuation: ContinuationOptions = field(default_factory=lambda: ContinuationOptions(ds=0.05, ds_max=0.5,
                                                                                         max_steps=300))

    def __post_init__(self):
        if not (isinstance(self.adapt_every, int) and self.adapt_every >= 0):
            raise InvalidInputError("adapt_every", self.adapt_every, "an integer >= 0 (0: never)")
        if not (isinstance(self.chord_tol, (int, float)) and 0.0 < self.chord_tol <= 1.0):
            raise InvalidInputError("chord_tol", self.chord_tol, "a number in (0, 1]")
        if not 0.0 < self.amplitude_min < 1.0:
            raise InvalidInputError("amplitude_min", self.amplitude_min, "a number in (0, 1)")
        if not self.amplitude_end_below > 0.0:
            raise InvalidInputError("amplitude_end_below", self.amplitude_end_below, "a number > 0")


@dataclass
class CycleCurve(ContinuationResult):
    """Points of a curve of cycle bifurcations (one row per point) and its special points (p1 in
    ``p``, p2 in their data)."""

    kind: PointKind
    p: np.ndarray  # (points, 2)
    period: np.ndarray
    x_max: np.ndarray  # (points, n)
    x_min: np.ndarray
    kappa: np.ndarray  # NS: cos of the torus angle; nan otherwise
    multipliers: np.ndarray  # (points, n), trivial first, then by decreasing modulus
    solutions: list[tuple[np.ndarray, np.ndarray]]  # (mesh points, cycle u = (x, T, p1)) per point
    guided: int = 0  # points predicted from a nearby curve's (:mod:`.guide`)

    def to_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, "p": self.p.tolist(), "period": self.period.tolist(),
                "x_max": self.x_max.tolist(), "x_min": self.x_min.tolist(),
                "kappa": [None if not np.isfinite(k) else float(k) for k in self.kappa], **super().to_dict()}


def cycle_curve(system: TwoParameterField, kind: PointKind | str, start: tuple[np.ndarray, np.ndarray],
                p2: float, *, box: tuple[tuple[float, float], tuple[float, float]],
                options: CycleCurveOptions | None = None, scale: np.ndarray | None = None,
                p_scale: tuple[float, float] = (1.0, 1.0), kappa: float | None = None, ncol: int = 4,
                directions: tuple[int, ...] = (1, -1), p2_marks: tuple[float, ...] = (),
                progress: Callable[[float], None] | None = None, guides: dict[int, Guide] | None = None) -> CycleCurve:
    """Continue a fold (LPC), period doubling (PD) or torus (NS) point of a cycle in (p1, p2).

    ``start`` = (mesh points, cycle u = (x at the nodes, T, p1)): a located special point of a
    one-parameter branch in p1 at ``p2`` (``PeriodicBranch.solutions`` at its index); for NS,
    ``kappa`` = cos of the torus angle there. ``box`` bounds (p1, p2); ``scale`` (n,) and ``p_scale``
    set the size of a unit step in the states and in (p1, p2). Traced in both directions
    (``directions``: +1 first increases p2); the two halves are joined into one curve. Where the
    curve turns in p2 a ``P2_TURN`` point is located, and where it crosses a value of ``p2_marks``
    a ``P2_MARK`` point (both with the cycle's period and extremes). ``guides``: {direction: the
    points of the same curve at a nearby design that half follows (:class:`~.guide.Guide`, its first
    point the one ``start`` is)}.
    """
    defining = defining_system(kind)
    kind = defining.kind
    options = options or CycleCurveOptions()
    if defining.has_kappa and (kappa is None or not -1.0 < kappa < 1.0):
        raise InvalidInputError("kappa", kappa, "cos of the torus angle, in (-1, 1)")
    for name, (low, high) in zip(("p1 range", "p2 range"), box, strict=True):
        if not (math.isfinite(low) and math.isfinite(high) and low < high):
            raise InvalidInputError(name, (low, high), "finite bounds, low < high")
    mesh_points, cu = start
    mesh = Mesh(np.asarray(mesh_points, float), ncol)
    scale = np.ones(system.n) if scale is None else scale
    problem = CycleCurveProblem(system, kind, mesh, scale, float(cu[-2]), np.asarray(p_scale, float),
                                options.kappa_weight)
    u0 = np.concatenate([cu, [p2]] + ([[kappa]] if defining.has_kappa else []))
    problem.cycle.accept(problem.cycle_u(u0))
    problem.update_borders(u0, sweeps=3)
    problem.choose_entries(u0)
    problem.update_borders(u0, sweeps=1)
    copts = options.continuation
    e2 = np.zeros(problem.size)
    e2[problem.n_x + 2] = 1.0
    first = step(problem, CurvePoint(u0, e2 / weighted_norm(e2, problem.weights)), 0.0, copts)
    if first is None:
        raise ConvergenceError(f"no {kind} point converged near the start (p = ({cu[-1]:g}, {p2:g}))")
    halves, stops, steps_total = [], [], 0
    for direction in directions:
        half_problem = problem if not halves else _fresh(problem, first.u)
        t = first.tangent if first.tangent[problem.n_x + 2] * direction >= 0 else -first.tangent
        rows, special, stop, steps = _trace(half_problem, CurvePoint(first.u.copy(), t), box, options,
                                            tuple(p2_marks), progress, (guides or {}).get(direction))
        on_mark = [m for m in p2_marks if abs(p2 - m) <= 1e-9 * problem.p_scale[1]]
        if direction > 0 and on_mark:
            # a start on a marked value (a slice's point, traced from its diagram) crosses it there;
            # the steps see only the crossings between points (told once: by the half along +p2; a
            # closed curve's last step, back onto its start, does not tell it again)
            last = len(rows["p"]) - 1
            if stop.reason is StopReason.CLOSED:
                special = [q for q in special if not (q.kind == PointKind.P2_MARK and q.index == last
                                                      and abs(q.data["p2"] - on_mark[0]) <= 1e-6 * problem.p_scale[1])]
            special.insert(0, half_problem.special_point(PointKind.P2_MARK, first.u, 0))
        halves.append((rows, special))
        stops.append(stop)
        steps_total += steps
        if stop.reason is StopReason.CLOSED:
            break
    curve = _join(kind, halves, stops, steps_total)
    curve.guided = sum(guides[d].taken for d in directions[:len(halves)] if d in (guides or {}))
    return curve


def start_beside(system: TwoParameterField, kind: PointKind | str, x_star: np.ndarray, p: np.ndarray, *,
                 p_range: tuple[float, float], options: PeriodicOptions | None = None,
                 scale: np.ndarray | None = None, p_scale: float = 1.0,
                 limits=None) -> tuple[SpecialPoint | None, int]:
    """A start for :func:`cycle_curve` near a codimension-2 point of an equilibrium: the first
    ``kind`` point of the cycle branch born at the Hopf point (x_star, p) (continued in p1 over
    ``p_range`` at p2 = p[1], with :func:`~.periodic_orbits.periodic_branch`'s ``scale``,
    ``p_scale`` and ``limits``). Beside a generalised Hopf point that is the small-amplitude fold
    of the fold curve born there; beside a double-Hopf point, the torus point of a torus curve born there. Returns
    (the located point with its solution, or None; the collocation degree of its mesh)."""
    kind = defining_system(kind).kind
    options = replace(options or PeriodicOptions(), stop_at=(kind,))
    field_ = system.at(float(p[1]))
    x_star = np.asarray(x_star, float)
    omega, q, _ = hopf_eigenvectors(field_.dfdx(x_star, float(p[0])))
    guess, shape = hopf_guess(x_star, float(p[0]), omega, q, Mesh.uniform(options.ntst, options.ncol), 0.0)
    try:
        branch = periodic_branch(field_, guess, p_range=p_range, options=options, scale=scale, p_scale=p_scale,
                                 direction=shape, limits=limits)
    except ContinuationError:
        return None, options.ncol
    found = [s for s in branch.special_points if s.kind == kind]
    return (found[0] if found else None), branch.ncol


def _fresh(problem: CycleCurveProblem, u: np.ndarray) -> CycleCurveProblem:
    other = problem.rebuilt(problem.mesh)
    other.B, other.C = problem.B.copy(), problem.C.copy()
    other.cycle.accept(other.cycle_u(u))
    other.update_borders(u, sweeps=2)
    return other


def _record(problem: CycleCurveProblem, rows: dict, point: CurvePoint) -> np.ndarray:
    mu = problem.multipliers(point.u)
    xmax, xmin = problem.extremes(point.u)
    n_x = problem.n_x
    rows["p"].append(point.u[n_x + 1:n_x + 3].copy())
    rows["T"].append(float(point.u[n_x]))
    rows["xmax"].append(xmax)
    rows["xmin"].append(xmin)
    rows["kappa"].append(problem.kappa(point.u))
    rows["mu"].append(mu)
    rows["solutions"].append((problem.mesh.points.copy(), point.u[:n_x + 2].copy()))
    return mu


#: Below ``amplitude_min`` of a curve's largest amplitude (near a zero-amplitude end) a step is halved at
#: most down to this fraction of the largest step taken there; if Newton still gives out and the amplitude
#: was falling, the curve ends there as at a zero-amplitude end.
END_ZONE_STEPS = 1.0 / 64.0


def _zero_amplitude_end(problem: CycleCurveProblem, special: list[SpecialPoint], rows: dict, p: np.ndarray,
                        amp: float, how: str = "") -> tuple[Stop, list[SpecialPoint]]:
    """The stop and the special points of a curve ending where its cycles shrink onto the equilibrium
    (at its last recorded point p, amplitude ``amp``).

    The step into that end crossed where the curve degenerates (the cycle shrinks onto the equilibrium's
    GH or double-Hopf point, which the Hopf curves locate): a test that changed sign over it and could
    not be located is that end, not a point of the curve. (The nes map's low-speed fold curve traced
    again from its seed at the same design reported an unlocated cusp at its end, 4.584 m/s, 480.2 kN,
    which the cold trace did not, and the warm map went cold.) A crossing carried over an unresolved
    stretch and told in that step goes with them: it is as unresolved as the end."""
    where = f"near p = ({p[0]:.6g}, {p[1]:.6g})" + (f", {how}" if how else "")
    stop = Stop(StopReason.ZERO_AMPLITUDE, f"amplitude shrank to {'zero' if not how else f'{amp:.3g}'} {where}: "
                "the curve ends at a codimension-2 point of the equilibrium")
    last = len(rows["p"]) - 1
    kept = [q for q in special if not (q.index == last and q.kind in problem.defining.codim2 and q.located is False)]
    kept.append(SpecialPoint(PointKind.ZERO_AMPLITUDE, float(p[0]), last, {"p2": float(p[1]), "amplitude": amp}))
    return stop, kept


def _amplitude(problem: CycleCurveProblem, xmax, xmin) -> float:
    return float(np.max(0.5 * (np.asarray(xmax) - np.asarray(xmin)) / problem.cycle.scale))


#: A warm trace passes over the old curve's points (:meth:`~.guide.Guide.next`) where the tracer's own
#: limits would let one step do it with this much to spare: the step's chord (:func:`_chord_ratio`) and its
#: turn at most PASS_SHARE of their limits, its length at most PASS_SHARE of the longest step. The cold
#: trace's steps grew slowly (1.4x a step) and were shortened where Newton struggled, so that most of its
#: chords stray far less than allowed (nes, e_p + 10 %: median 0.09 of the tolerance).
PASS_SHARE = 0.7


def _passes(problem_of: Callable[[], CycleCurveProblem], tracer: Tracer, guide: Guide, chord_tol: float):
    """The test whether a guided step may go from old point a (where the trace is) straight to old point b,
    passing over the points between (see ``PASS_SHARE``): the tangent at a the trace's own, the one at b
    the old points' central difference there (exact on a uniformly curving stretch; b the old curve's last
    point: not passed to)."""
    def passes(a: int, b: int) -> bool:
        if b + 1 >= len(guide.points):
            return False
        problem = problem_of()
        w = problem.weights
        u = guide.olds(a, b + 1, problem.mesh)
        h = weighted_norm(u[-2] - u[0], w)
        limit = min(tracer.options.ds_max, GUIDED_CAP * tracer.cap)
        if not 0.0 < h <= PASS_SHARE * limit:
            return False
        t_b = u[-1] - u[-3]
        size = weighted_norm(t_b, w)
        if not size > 0.0:
            return False
        end = CurvePoint(u[-2], t_b / size)
        if tracer._turn(end) > PASS_SHARE * tracer.options.max_angle:  # the tracer's own measure of a turn
            return False
        return _chord_ratio(problem, CurvePoint(u[0], tracer.point.tangent), end, h, chord_tol) <= PASS_SHARE
    return passes


def _trace(problem: CycleCurveProblem, start: CurvePoint, box, options: CycleCurveOptions, marks, progress,
           guide: Guide | None = None):
    copts = options.continuation
    n_x = problem.n_x
    rows: dict[str, list] = {k: [] for k in ("p", "T", "xmax", "xmin", "kappa", "mu", "solutions")}
    problem.accept(start.u)
    mu = _record(problem, rows, start)
    tracer = Tracer(problem, start, copts, chord=lambda pr, a, b, h: _chord_ratio(pr, a, b, h, options.chord_tol))
    special: list[SpecialPoint] = []
    if guide is not None:
        guide.anchor(start, problem.mesh)
        passes = _passes(lambda: problem, tracer, guide, options.chord_tol)

    def p_direction(point):
        t_p = point.tangent[n_x + 1:n_x + 3] * np.sqrt(problem.weights[n_x + 1:n_x + 3])
        return t_p / max(np.linalg.norm(t_p), 1e-300)

    reference = p_direction(start)
    monitors = codim2.monitors(problem, start, mu, reference)
    carried: frozenset = frozenset()  # tests whose value in `monitors` is an earlier point's (unresolved since)
    amp_peak = _amplitude(problem, rows["xmax"][0], rows["xmin"][0])
    amp_last = amp_peak
    zone_step = 0.0  # the largest step taken near a zero-amplitude end (below amplitude_min of the peak)
    shrinking = False  # the amplitude fell over the last step
    stop = Stop(StopReason.STEP_BUDGET, f"step budget of {copts.max_steps} steps used")
    steps = 0
    for steps in range(1, copts.max_steps + 1):  # noqa: B007
        prev = tracer.point
        adv = guided = None
        if guide is not None and (guided := guide.next(problem.mesh, passes)) is not None:
            adv = tracer.advance_to(*guided)
            if adv is None and guide.shorter():  # a step over old points refused: to the next one
                adv = tracer.advance_to(*guide.next(problem.mesh))
            if adv is not None:
                guide.took(adv[0], problem.mesh)
        if adv is None:
            adv = tracer.advance()
            if adv is not None and guided is not None:
                guide.skip_behind(adv[0], problem.mesh, problem.weights)
        if adv is None:
            stop = tracer.failed
            if zone_step > 0.0 and shrinking:  # Newton gave out where the cycles shrink onto the end
                p_last = prev.u[n_x + 1:n_x + 3]
                stop, special = _zero_amplitude_end(problem, special, rows, p_last, amp_last,
                                                    "where the continuation could not go on")
            break
        new, h = adv
        p_new = new.u[n_x + 1:n_x + 3]
        outside = [(c, bound) for c in range(2) for bound in box[c]
                   if (bound == box[c][0] and p_new[c] < bound) or (bound == box[c][1] and p_new[c] > bound)]
        if outside:
            c, bound = outside[0]
            index = n_x + 1 + c
            hit = locate_between(problem, prev, new, lambda q: q.u[index] - bound, prev.u[index] - bound,
                                 new.u[index] - bound, copts, 1e-9 * problem.p_scale[c], with_tangent=False)
            if hit is not None:
                special.extend(_p2_points(problem, prev, hit[0], marks, rows, copts))
                problem.accept(hit[0].u)
                _record(problem, rows, hit[0])
                special.append(SpecialPoint(PointKind.END, float(hit[0].u[n_x + 1]), len(rows["p"]) - 1,
                                            {"p2": float(hit[0].u[n_x + 2])}))
            stop = Stop(StopReason.BOUND, f"left the parameter box at p{c + 1} = {bound:g}")
            break
        if new.u[n_x] > options.period_max:
            stop = Stop(StopReason.PERIOD_LIMIT, f"period {new.u[n_x]:.4g} above the limit {options.period_max:.4g}")
            break
        if new.u[n_x] <= 0:
            stop = Stop(StopReason.NONPOSITIVE_PERIOD, "period became non-positive: the continuation left the curve")
            break
        kappa = problem.kappa(new.u)
        if problem.defining.has_kappa and not -1.0 <= kappa <= 1.0:
            stop = Stop(StopReason.PAST_RESONANCE, f"kappa = {kappa:.4g} left [-1, 1] near p = ({p_new[0]:.6g}, "
                        f"{p_new[1]:.6g}): past a strong resonance the condition describes neutral saddle cycles, "
                        "not tori")
            break
        mu = _record(problem, rows, new)
        special.extend(_p2_points(problem, prev, new, marks, rows, copts))
        new_monitors = codim2.monitors(problem, new, mu, reference)
        special.extend(codim2.codim2_points(problem, prev, new, monitors, new_monitors, reference,
                                            len(rows["p"]) - 1, copts, carried))
        monitors, carried = _carry(problem, monitors, new_monitors)
        reference = p_direction(new)
        # the curve type's own tests at `new` against its own direction (the cusp's compares directions)
        monitors.update(problem.defining.own_monitors(problem, new, reference))
        if progress is not None:
            progress(min(1.0, steps / copts.max_steps))
        if _closed(rows):
            stop = Stop(StopReason.CLOSED, "closed curve: returned to its first point")
            break
        amp = _amplitude(problem, rows["xmax"][-1], rows["xmin"][-1])
        amp_peak = max(amp_peak, amp)
        if amp < options.amplitude_min * amp_peak and amp < options.amplitude_end_below and amp < amp_last:
            stop, special = _zero_amplitude_end(problem, special, rows, p_new, amp)
            break
        if amp < amp_last:
            tracer.limit_step(max(0.7 * amp * h / max(amp_last - amp, 1e-300), copts.ds_min))
        # near a zero-amplitude end the system degenerates: there a step is halved at most to END_ZONE_STEPS
        # of the largest step taken since the amplitude fell below amplitude_min of its peak, not down to
        # ds_min (a warm trace of the nes map's fold curve towards its GH end spent 41 failed corrections,
        # 0.5 s, halving towards 1e-7 at amplitude 0.0047, its accepted steps shrinking with the halvings);
        # the last of those halvings is the tracer's last chance (a converged step is taken whatever its turn
        # or chord). Away from the end the options' own ds_min holds again.
        zone_step = max(zone_step, h) if amp < options.amplitude_min * amp_peak else 0.0
        floor = max(copts.ds_min, END_ZONE_STEPS * zone_step)
        if tracer.options.ds_min != floor:
            tracer.options = replace(tracer.options, ds_min=floor)
        shrinking, amp_last = amp < amp_last, amp
        if options.adapt_every and steps % options.adapt_every == 0:
            remeshed = _remesh(problem, tracer, copts)
            if remeshed is not problem:
                # the tests again at the point on its new mesh: the next step compares values of one
                # discretisation, not of two; a test carried (an earlier point's value over an unresolved
                # stretch) stays carried, even where the new mesh resolves it past its crossing
                problem = remeshed
                point = tracer.point
                monitors, carried = _carry(problem, monitors,
                                           codim2.monitors(problem, point, problem.multipliers(point.u), reference),
                                           keep=carried)
    return rows, special, stop, steps


def _carry(problem: CycleCurveProblem, monitors: dict, fresh: dict,
           keep: frozenset = frozenset()) -> tuple[dict, frozenset]:
    """The tests' values at a new point (``fresh``) over those of the last (``monitors``), and the tests
    that keep their last value: those in ``keep``, and a crossing test unresolved at the new point (NaN: a
    multiplier within its accuracy of the circle), so that a crossing over the unresolved stretch is seen
    where the test is resolved again (pd's second torus curve ran from +0.01 through a NaN point to -1e-5
    past its LPNS at 136.3 m/s, which the warm traces lost and the cold one, its points elsewhere, found)."""
    carried = frozenset(k for k, v in fresh.items() if k in keep or (
        k in problem.defining.crossings and not np.isfinite(v) and np.isfinite(monitors.get(k, math.nan))))
    return {k: monitors[k] if k in carried else v for k, v in fresh.items()}, carried


def _chord_ratio(problem: CycleCurveProblem, a: CurvePoint, b: CurvePoint, h: float, tol: float) -> float:
    """How far the step from a to b strays from its chord in the parameter plane, over the
    allowed ``tol`` of each parameter (relative to its size, at least a tenth of its scale): the
    cubic through both points with their tangents (d/ds, s the weighted arclength h) lies
    h/8 (t_a - t_b) from the chord at the middle."""
    i = problem.n_x + 1
    p = np.abs(np.stack([a.u[i:i + 2], b.u[i:i + 2]])).max(axis=0)
    allowed = tol * np.maximum(p, 0.1 * problem.p_scale)
    return float(np.max(np.abs(0.125 * h * (a.tangent[i:i + 2] - b.tangent[i:i + 2])) / allowed))


def _remesh(problem: CycleCurveProblem, tracer: Tracer, copts: ContinuationOptions) -> CycleCurveProblem:
    point = tracer.point
    new_mesh = problem.cycle.adapted_mesh(problem.cycle_u(point.u))
    other = problem.rebuilt(new_mesh)
    u_t = problem.transfer(other, point.u)
    t_t = problem.transfer(other, point.tangent)
    problem.transfer_borders(other)
    other.cycle.accept(other.cycle_u(u_t))
    other.update_borders(u_t, sweeps=2)
    t_t /= weighted_norm(t_t, other.weights)
    fixed = step(other, CurvePoint(u_t, t_t), 0.0, copts)
    if fixed is None:  # keep the old mesh
        problem.cycle_u(point.u)
        return problem
    other.accept(fixed.u)
    tracer.problem = other
    tracer.point = CurvePoint(fixed.u, tangent(other, fixed.u, t_t))
    return other


def _p2_points(problem: CycleCurveProblem, prev: CurvePoint, new: CurvePoint, marks, rows, copts) -> list[SpecialPoint]:
    """Turning points of the curve in p2 and its crossings of the marked p2 values in this step."""
    i2 = problem.n_x + 2
    found = []

    def slope(q):  # p2's share of the curve's direction in the parameter plane (scaled)
        t_p = q.tangent[i2 - 1:i2 + 1] * np.sqrt(problem.weights[i2 - 1:i2 + 1])
        return float(t_p[1] / max(np.linalg.norm(t_p), 1e-300))

    pieces = [(prev, new)]  # stretches of the step on which p2 is monotone
    if prev.tangent[i2] * new.tangent[i2] < 0:
        hit = locate_between(problem, prev, new, slope, slope(prev), slope(new), copts, codim2.LOCATE_TOL)
        at = hit[0] if hit is not None else new
        found.append(problem.special_point(PointKind.P2_TURN, at.u, len(rows["p"]) - 1,
                                           {"turn": "max" if prev.tangent[i2] > 0 else "min"}, hit is not None))
        if hit is not None:  # a mark between the turn's p2 and both ends' is crossed twice in the step
            pieces = [(prev, hit[0]), (hit[0], new)]  # (a turn not located: such a mark is not told, and a
            # warm map that needs that crossing is computed cold)
    tiny = 1e-9 * problem.p_scale[1]
    for mark in marks:
        ends_on = abs(new.u[i2] - mark) <= tiny
        if ends_on:  # the step ends on the mark (a box edge)
            found.append(problem.special_point(PointKind.P2_MARK, new.u, len(rows["p"]) - 1))
        for one, other in pieces:
            if ends_on and other is new:  # told above
                continue
            a, b = one.u[i2] - mark, other.u[i2] - mark
            if not (a * b < 0 and abs(a) > tiny):  # (a step from the mark: told there)
                continue
            at = point_at(problem, one, other, i2, mark, copts)  # p2 held at the mark: one Newton solve
            if at is None:
                hit = locate_between(problem, one, other, lambda q, m=mark: q.u[i2] - m, a, b, copts, tiny,
                                     with_tangent=False)
                at = None if hit is None else hit[0]
            if at is not None:
                found.append(problem.special_point(PointKind.P2_MARK, at.u, len(rows["p"]) - 1))
    problem.cycle_u(new.u)
    return found


def _closed(rows: dict) -> bool:
    k = len(rows["p"])
    if k < 8:
        return False

    def measure(i):
        return np.concatenate([rows["p"][i], [rows["T"][i]], rows["xmax"][i]])

    first, prev, last = measure(0), measure(k - 2), measure(k - 1)
    span = np.ptp(np.array([measure(i) for i in range(k)]), axis=0)
    span[span == 0] = 1.0
    first, prev, last = first / span, prev / span, last / span
    seg = last - prev
    length = float(np.linalg.norm(seg))
    if length == 0.0:
        return False
    far = max(float(np.linalg.norm(measure(i) / span - first)) for i in range(k))
    if far < 5.0 * length:
        return False
    s = float(np.clip(np.dot(first - prev, seg) / length ** 2, 0.0, 1.0))
    return float(np.linalg.norm(prev + s * seg - first)) < length / 3.0


def join_halves(plus: CycleCurve, minus: CycleCurve) -> CycleCurve:
    """The curve :func:`cycle_curve` traces both ways, from its two halves traced apart from the same
    start (``directions=(1,)`` and ``(-1,)``, for example in two processes): the second half
    reversed, then the first, as one curve; the first alone if it closed (the second then retraces
    it). The halves' shared start point is kept once."""
    if plus.kind != minus.kind:
        raise InvalidInputError("minus", minus.kind.value, f"a half of the same {plus.kind} curve")
    if plus.closed:
        return plus
    count = len(minus.p)
    order = np.arange(count - 1, 0, -1, dtype=int)  # reversed, without the shared start point
    # its start: the shared point; reversed, so that two points of one step keep their order along the curve
    special = [replace(s, index=count - 1 - s.index) for s in reversed(minus.special_points)]
    special += [replace(s, index=count - 1 + s.index) for s in plus.special_points]
    special.sort(key=lambda s: s.index)

    def joined(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return np.concatenate([a[order], b]) if count > 1 else b.copy()

    return CycleCurve(plus.kind, joined(minus.p, plus.p), joined(minus.period, plus.period),
                      joined(minus.x_max, plus.x_max), joined(minus.x_min, plus.x_min),
                      joined(minus.kappa, plus.kappa), joined(minus.multipliers, plus.multipliers),
                      [minus.solutions[i] for i in order] + list(plus.solutions), plus.guided + minus.guided,
                      special_points=special, stops=list(plus.stops) + list(minus.stops),
                      steps=plus.steps + minus.steps, closed=minus.closed)


def _join(kind: PointKind, halves, stops, steps) -> CycleCurve:
    """One curve: the second half reversed, then the first (they share the start point)."""
    parts = []
    special: list[SpecialPoint] = []
    offset = 0
    ordered = [halves[1], halves[0]] if len(halves) == 2 else halves
    for h_index, (rows, pts) in enumerate(ordered):
        count = len(rows["p"])
        if len(halves) == 2 and h_index == 0:
            order = list(range(count - 1, 0, -1))  # reversed, without the shared start point
            position = {i: k for k, i in enumerate(order)}
            # one at the start is at the shared point, where the other half begins; reversed, so that two
            # points of one step keep their order along the curve (the sort below is stable)
            for s in reversed(pts):
                special.append(replace(s, index=position.get(s.index, len(order))))
        else:
            order = list(range(count))
            for s in pts:
                special.append(replace(s, index=offset + s.index))
        parts.append((rows, order))
        offset += len(order)

    def gather(key):
        return [rows[key][i] for rows, order in parts for i in order]

    mu = gather("mu")
    special.sort(key=lambda s: s.index)
    return CycleCurve(kind, np.array(gather("p")), np.array(gather("T")), np.array(gather("xmax")),
                      np.array(gather("xmin")), np.array(gather("kappa"), float), np.array(mu), gather("solutions"),
                      special_points=special, stops=stops, steps=steps,
                      closed=any(s.reason is StopReason.CLOSED for s in stops))
