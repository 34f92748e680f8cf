"""Where a stable cycle's mode changes, located exactly on its branch.

A cycle is torsional where its torsional share of elastic energy, k_psi A_psi^2 / (k_psi A_psi^2 +
k_delta A_delta^2) with A the half peak-to-peak amplitudes of psi and delta over the orbit, is at least
0.8, lateral where it is at most 0.2, both in between (:func:`~shimmy.analyses.core.response.mode_of`).
A diagram gives the mode at its continuation points, 2-4 m/s apart where the mode changes; a map that
put the change halfway between two points (or at a fine grid point) was off by up to half a step, and
a map warmed from it could not tell how the change moved with the design.

:func:`locate_mode_changes` finds each change on a diagram's stable stretches: the arclength along the
branch, from the computed point before it, at which the share equals the threshold (Brent's method on
points corrected by the continuation's own corrector, ends known from the diagram). :func:`relocate`
finds the same change at a nearby design: the cycle of the change corrected at its speed (Newton with V
held), then the root of the share along the new branch by the secant method. Both converge the speed
to :data:`V_TOL` (m/s). The amplitudes are the orbit's extremes on its collocation polynomial
(:meth:`~shimmy.continuation.collocation.PeriodicProblem.extremes`), not its samples, so that the speed
found does not depend on the mesh beyond the collocation's own error: located at a design from that
design's diagram and relocated there from a nearby design's, one change agrees to 1e-7 m/s, at worst
7e-6 m/s (pd, a_p 0.9 -> 0.81: other meshes).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np
from scipy.optimize import brentq

from ...continuation import ContinuationOptions, CurvePoint
from ...continuation.collocation import Mesh, PeriodicProblem
from ...continuation.cycle_curves.guide import decode, encode
from ...continuation.core import step
from ...model.configurations import Configuration
from ...model.equations import build_model
from ...model.parameters import Parameters
from ..core.response import LATERAL_SHARE, TORSION_SHARE, torsional_share
from .bifurcation import (STATE_SCALE, T_SCALE, V_SCALE, BifurcationResult, at_fixed_speed, gear_field,
                          restore_point)

#: The speed of a located change is converged to this (m/s).
V_TOL = 1e-7
#: Trials of the secant method of :func:`relocate` at most (each one a corrector run).
MAX_TRIALS = 16
THRESHOLDS = (TORSION_SHARE, LATERAL_SHARE)


@dataclass(frozen=True, eq=False)
class ModeChange:
    """A stable cycle's mode change at (V, Fz): the share crosses ``threshold`` there; ``mesh``, ``ncol``
    and ``u`` (X, T, V) its cycle; ``span`` the arclength of the diagram's step it lay in (the scale of a
    relocation's trial steps)."""

    V: float
    Fz: float
    threshold: float
    mesh: np.ndarray
    ncol: int
    u: np.ndarray
    span: float

    #: the speeds of the diagram's two points it lies between (the change itself where it was relocated)
    bracket: tuple[float, float] = (math.nan, math.nan)

    def to_dict(self, compact: bool = False) -> dict[str, Any]:
        """JSON-ready; ``compact``: the cycle as base64 float32 (a start for :func:`relocate`, which corrects
        it: a quarter of the size as text; the mesh exact)."""
        cycle = {"mesh": self.mesh.tolist(), "u": encode(self.u) if compact else self.u.tolist()}
        return {"V": self.V, "Fz": self.Fz, "threshold": self.threshold, **cycle, "ncol": self.ncol,
                "span": self.span, "bracket": list(self.bracket)}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> ModeChange:
        def array(x) -> np.ndarray:
            return decode(x) if isinstance(x, str) else np.asarray(x, float)

        return cls(float(d["V"]), float(d["Fz"]), float(d["threshold"]), array(d["mesh"]), int(d["ncol"]),
                   array(d["u"]), float(d["span"]), tuple(float(v) for v in d.get("bracket", (d["V"], d["V"]))))


def share_of(problem: PeriodicProblem, u: np.ndarray, k_psi: float, k_delta: float) -> float:
    """The torsional share of the cycle ``u``, its amplitudes as the diagram measures them."""
    psi_max, psi_min = problem.extremes(u, 0)
    delta_max, delta_min = problem.extremes(u, 2)
    return float(torsional_share(0.5 * (psi_max - psi_min), 0.5 * (delta_max - delta_min), k_psi, k_delta))


def _system(config: Configuration, params: Parameters, Fz: float, exact_nes: bool):
    model = build_model(config, params, exact_nes=exact_nes)
    return gear_field(model, Fz), STATE_SCALE[:model.n_states]


def _options(result: BifurcationResult) -> ContinuationOptions:
    return ContinuationOptions(ds=result.options.ds, ds_max=result.options.ds_max)


def locate_mode_changes(result: BifurcationResult) -> list[ModeChange]:
    """Every change of mode between two consecutive stable points of the diagram's periodic branches
    (a loop's closing step left out), by speed; a step whose change does not converge is left out (its
    points' modes stand, as before)."""
    system, scale = _system(result.config, result.params, result.Fz, result.options.exact_nes)
    gear = result.params.gear
    copts = _options(result)
    found = []
    for b in result.branches:
        raw = b.raw
        if b.kind != "periodic" or raw is None or raw.p.size < 2:
            continue
        share = torsional_share(0.5 * (raw.x_max[:, 0] - raw.x_min[:, 0]), 0.5 * (raw.x_max[:, 2] - raw.x_min[:, 2]),
                                gear.k_psi, gear.k_delta)
        for i in range(raw.p.size - 1):
            if not (raw.stable[i] and raw.stable[i + 1]) or not np.isfinite(share[i:i + 2]).all():
                continue
            for threshold in THRESHOLDS:
                g0, g1 = share[i] - threshold, share[i + 1] - threshold
                if g0 * g1 >= 0.0 or g0 == g1:
                    continue
                change = _on_step(system, scale, raw, i, threshold, copts, gear, result.Fz)
                if change is not None:
                    found.append(change)
    return sorted(found, key=lambda c: c.V)


def _on_step(system, scale, raw, i: int, threshold: float, copts, gear, Fz: float) -> ModeChange | None:
    """The change in the diagram's step from point i (a step whose points' sampled shares lie either side
    of the threshold). The search's own ends are the start's share and the share at the step's full length
    along its tangent, on the polynomial extremes as every trial (the samples differ from them by up to
    ~1e-5): a step whose ends do not bracket the threshold so measured has no change (None; its interval end
    stays at the fine-grid midpoint)."""
    problem, start, span = restore_point(system, raw, i, scale)
    if span <= 0.0:
        return None
    tried: dict[float, CurvePoint] = {}

    def g(h: float) -> float:
        point = start if h == 0.0 else step(problem, start, h, copts, with_tangent=False)
        if point is None:
            raise _NoPoint
        tried[h] = point
        return share_of(problem, point.u, gear.k_psi, gear.k_delta) - threshold

    # the speed moves at most |dV/ds| h: a tolerance in h that is one of V_TOL in V
    rate = abs(raw.p[i + 1] - raw.p[i]) / span
    try:
        h = brentq(g, 0.0, span, xtol=V_TOL / max(rate, 1e-12) / 4.0, rtol=4 * np.finfo(float).eps, maxiter=60)
    except (_NoPoint, RuntimeError, ValueError):
        return None
    point = tried.get(h) or step(problem, start, h, copts, with_tangent=False)
    if point is None or not 0.0 < h < span:
        return None
    return ModeChange(float(point.u[-1]), float(Fz), float(threshold), problem.mesh.points.copy(), raw.ncol,
                      point.u.copy(), float(span), (float(raw.p[i]), float(raw.p[i + 1])))


class _NoPoint(Exception):
    """A trial step's corrector did not converge."""


def relocate(change: ModeChange, config: Configuration, params: Parameters, *, exact_nes: bool = False,
             options: ContinuationOptions | None = None) -> ModeChange | None:
    """The mode change ``change`` (located at a nearby design) at the design ``params``, same load and
    threshold: its cycle corrected with V held, then the secant method along the new branch to V_TOL;
    None if a correction fails or the secant method does not converge in MAX_TRIALS trials or strays
    more than four of the diagram's steps from where it began (the change is then no longer that one)."""
    system, scale = _system(config, params, change.Fz, exact_nes)
    problem = PeriodicProblem(system, Mesh(change.mesh, change.ncol), scale, T_SCALE, V_SCALE)
    problem.accept(change.u)
    copts = options or ContinuationOptions()
    start = at_fixed_speed(problem, change.u, copts)
    if start is None:
        return None
    problem.accept(start.u)
    gear = params.gear

    def g(point: CurvePoint) -> float:
        return share_of(problem, point.u, gear.k_psi, gear.k_delta) - change.threshold

    root = _secant(lambda h: step(problem, start, h, copts, with_tangent=False), g, start, change.span)
    if root is None:
        return None
    V = float(root.u[-1])
    return ModeChange(V, change.Fz, change.threshold, change.mesh, change.ncol, root.u.copy(), change.span, (V, V))


def _secant(at: Callable[[float], CurvePoint | None], g: Callable[[CurvePoint], float], start: CurvePoint,
            span: float) -> CurvePoint | None:
    """The point at arclength h from ``start`` where g = 0, by the secant method from h = 0 and span / 64;
    converged when a step moves V by at most V_TOL."""
    h0, g0 = 0.0, g(start)
    if g0 == 0.0:
        return start
    h1 = span / 64.0
    p1 = at(h1)
    if p1 is None:
        return None
    g1 = g(p1)
    for _ in range(MAX_TRIALS):
        if g1 == 0.0:
            return p1
        if g1 == g0:
            return None
        h2 = h1 - g1 * (h1 - h0) / (g1 - g0)
        if not abs(h2) <= 4.0 * span:
            return None
        p2 = at(h2)
        if p2 is None:
            return None
        if abs(p2.u[-1] - p1.u[-1]) <= V_TOL:
            return p2
        h0, g0 = h1, g1
        h1, g1, p1 = h2, g(p2), p2
    return None


#: :func:`follow_load`: the largest deviation (m/s) of the true curve of a change from the chord between two
#: of its points (estimated from the secant predictor's error)
CHORD_TOL = 0.02
#: ... a step whose chord errs by more than this many times CHORD_TOL is taken again, shorter
CHORD_REFUSE = 2.0
#: ... the steps at most (a change that needs more is given up: None)
MAX_LOAD_STEPS = 64
#: ... and the shortest step, as a share of the way: a change whose relocation fails, or whose chord stays
#: too curved, at a step this short is given up (None). At 1/64 a change followed from 248.7 kN down to
#: 233.7 kN on nes_pd (a_p 0.95) was lost 153 N short of its end, where its curve steepens towards a turn
#: in the load (dV/dFz -0.7 -> -4 m/s per kN), which a follow from 238.7 kN (a shorter way) reached.
MIN_STEP_SHARE = 1.0 / 256.0


def follow_load(change: ModeChange, Fz_to: float, config: Configuration, params: Parameters, *,
                exact_nes: bool = False, chord: float = CHORD_TOL) -> list[ModeChange] | None:
    """The mode change ``change`` followed in the load, at the same design, from its load to ``Fz_to``: the
    curve of the change in (V, Fz) by natural continuation in Fz, each point the change relocated at the next
    load (:func:`relocate`) from a secant predictor of its cycle (the two points before it extrapolated to
    the new load). The step is set so that the curve deviates from the chord between two points by about
    ``chord`` m/s: the secant predictor's error in V is ~V''/2 h (h + h_before), the chord's ~V''/8 h^2; a
    step whose estimate exceeds CHORD_REFUSE x ``chord`` is taken again at half its length. The first step
    is an eighth of the way, its chord checked once the second is taken (a midpoint put in where needed).
    Returns the points after ``change``, the last at ``Fz_to``; None where a relocation fails, or the chord's
    estimate stays too large, at a step of MIN_STEP_SHARE of the way or less (the change turns back in the
    load, or its cycle ends between), or after MAX_LOAD_STEPS steps."""
    points, reached = follow_as_far(change, Fz_to, config, params, exact_nes=exact_nes, chord=chord)
    return points if reached else None


def follow_as_far(change: ModeChange, Fz_to: float, config: Configuration, params: Parameters, *,
                  exact_nes: bool = False, chord: float = CHORD_TOL,
                  min_step: float | None = None) -> tuple[list[ModeChange], bool]:
    """:func:`follow_load`'s points after ``change`` as far as the follow got, and whether it reached
    ``Fz_to`` (a follow that gives up also returns the points before the step it gave up on: where a
    warm map resumes it). ``min_step`` (N): the step it gives up at, MIN_STEP_SHARE of the way by default
    (a follow resumed part way keeps the whole way's)."""
    way = float(Fz_to) - change.Fz
    if way == 0.0:
        return [], True
    shortest = abs(way) * MIN_STEP_SHARE if min_step is None else float(min_step)
    h = 0.125 * way
    points = [change]
    for _ in range(MAX_LOAD_STEPS):
        last = points[-1]
        remaining = float(Fz_to) - last.Fz
        if abs(h) >= abs(remaining) or abs(remaining) < 1.3 * abs(h):  # no sliver of a last step
            h = remaining
        Fz = float(Fz_to) if h == remaining else last.Fz + h
        u = last.u
        if len(points) >= 2:  # the secant through the last two points (one mesh: relocate keeps it)
            before = points[-2]
            u = last.u + (Fz - last.Fz) / (last.Fz - before.Fz) * (last.u - before.u)
        new = relocate(dataclasses.replace(last, Fz=Fz, V=float(u[-1]), u=u), config, params, exact_nes=exact_nes)
        # the predictor errs by ~V''/2 h (h + h_before), the chord by ~V''/8 h^2
        deviation = abs(new.V - u[-1]) * abs(h) / (4.0 * (abs(h) + abs(last.Fz - points[-2].Fz))) \
            if new is not None and len(points) >= 2 else 0.0
        if new is None or deviation > CHORD_REFUSE * chord:
            if abs(h) <= shortest:  # (a first point whose chord was not checked: none kept, see below)
                return (points[1:] if len(points) >= 3 else []), False
            h *= 0.5
            continue
        points.append(new)
        if len(points) == 3 and not _first_chord_kept(points, chord, config, params, exact_nes):
            return [], False  # (its first point may be another change's)
        if Fz == float(Fz_to):
            return points[1:], True
        if len(points) >= 3:
            h *= min(max(math.sqrt(chord / max(deviation, 1e-12)), 0.5), 2.0)
    return (points[1:] if len(points) >= 3 else []), False


def _first_chord_kept(points: list[ModeChange], chord: float, config, params, exact_nes: bool) -> bool:
    """The first step of a follow (from a constant predictor: no estimate of its chord's error) checked
    once the second is taken: V'' from the three points' divided differences, the chord's error ~V''/8 h^2;
    above CHORD_REFUSE x ``chord`` its midpoint is relocated and put in (``points`` changed in place). False
    if that relocation fails (the first point may be another change's)."""
    (F0, V0), (F1, V1), (F2, V2) = ((c.Fz, c.V) for c in points)
    curvature = 2.0 * ((V2 - V1) / (F2 - F1) - (V1 - V0) / (F1 - F0)) / (F2 - F0)
    error = abs(curvature) * (F1 - F0) ** 2 / 8.0
    if error <= CHORD_REFUSE * chord:
        return True
    start, end = points[0], points[1]
    u = 0.5 * (start.u + end.u)
    mid = relocate(dataclasses.replace(end, Fz=0.5 * (F0 + F1), V=float(u[-1]), u=u), config, params,
                   exact_nes=exact_nes)
    if mid is None or abs(mid.V - 0.5 * (V0 + V1)) > 2.0 * error + 0.5 * abs(V1 - V0):
        return False
    points.insert(1, mid)
    return True
