"""The largest stable torsional amplitude at a load as a curve in a design parameter.

``max_psi`` of a study is the largest |psi| over the stable limit cycles of the one-parameter
bifurcation diagram in V at the study's load (:func:`shimmy.analyses.diagrams.bifurcation.bifurcation`:
the cycles continued by collocation, the maximum refined along its branch). The curve is made in two
passes:

1. **Grid**: a full diagram at :data:`N_GRID` values of theta evenly over its whole range (the ends
   included), the sampled study's values and the base design's, with the sampled study's own
   options: at the sampled values the curve's value *is* the sampled row's.
2. **Followed between grid values** (:func:`follow_maximum`): where a grid diagram's maximum lies
   inside a stable stretch of its branch (d max|psi| / ds = 0 there), that cycle is followed towards
   the next grid value in :data:`SUBSTEPS` steps of theta: at each step the cycle is corrected by
   Newton at the new design on the same collocation mesh at fixed V, and the maximum of max|psi| along
   the branch is located again by a bounded search in arclength (to 1e-5 of the search span, each
   orbit's maximum on its collocation polynomial, as the diagram does). Every followed point is thus a
   located maximum of a stable cycle, exact to the diagram's tolerances (it equals a full diagram of
   that design to 2e-12-2e-9 relative where the diagram's maximum is the same one). The follow arriving at
   the next grid value must reproduce that diagram's value to :data:`AGREE`; where it does not (the
   largest amplitude has moved to another branch or hump), the next grid value's maximum is followed
   back, and at each step the larger of the two stable values is the curve's.

Where the picture changes (special points, ``"kind": "switch"``, not located: ``"located": false``
with the ``bracket`` of theta, as narrow as the points on either side): the speed of the maximum jumps
by more than :data:`SWITCH_JUMP` of the study's speed range between two neighbouring points (the
maximum moves to another branch or another hump of its branch), or stable cycles appear or vanish
(max_psi 0 on one side). A followed maximum is a local one: a third branch whose stable cycles rise
above it only between two grid values and fall below it again at both is not seen.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from ...continuation.errors import ContinuationError as EngineError
from ...errors import ShimmyError
from ...model.configurations import Configuration
from ...model.parameters import Parameters
from .study_curves import SNAP, StudyCurve, is_count, parameter_range

#: Grid values of theta over its whole range, the ends included (plus the sampled and base values).
N_GRID = 9
#: A jump of the maximum's speed by more than this fraction of the study's speed range between two
#: neighbouring points marks a switch of the maximum (to another branch or hump).
SWITCH_JUMP = 0.1
#: Steps of theta from one grid value to the next when a maximum is followed (the last one lands on
#: the next grid value, where the follow is checked against that value's diagram).
SUBSTEPS = 6
#: A followed maximum arriving at a grid value is the diagram's maximum there if it agrees to this
#: (relative); followed and diagram values agree to 2e-12-2e-9 where the maximum is the same one.
AGREE = 1e-6
#: Arclength half-width (the diagram's metric) of the search for the maximum along the branch at each
#: followed value; re-centred (at most :data:`RECENTRES` times) while the maximum is at its edge.
SEARCH_SPAN = 0.1
#: How many times the search for the maximum is re-centred before a follow stops.
RECENTRES = 6


def grid(parameter: str, params: Parameters, values: Sequence[float] = ()) -> list[float]:
    """theta's grid: :data:`N_GRID` values evenly over its whole range, the base design's value and
    ``values``; values closer than :data:`~.study_curves.SNAP` of the range are one."""
    lo, hi = parameter_range(parameter, params)
    base = float(getattr(params, parameter))
    even = np.linspace(lo, hi, N_GRID)
    if is_count(parameter):  # a count takes whole values only
        even = np.unique(np.round(even))
    wanted = sorted(set(even.tolist()) | {float(v) for v in values} | ({base} if lo <= base <= hi else set()))
    out: list[float] = []
    for theta in wanted:
        if out and abs(theta - out[-1]) <= SNAP * (hi - lo):
            if theta in values:  # an asked-for value wins: the sampled row is at it exactly
                out[-1] = theta
            continue
        out.append(theta)
    return out


def substeps(a: float, b: float, parameter: str | None = None) -> list[float]:
    """The values of theta a follow from grid value a towards b visits, b last (exactly): the same
    numbers either way (interpolated from the lower end), so that followed points from both ends of an
    interval meet at equal theta; for an integer ``parameter`` (a count) the whole values among them."""
    lo, hi = min(a, b), max(a, b)
    inner = [lo + (hi - lo) * k / SUBSTEPS for k in range(1, SUBSTEPS)]
    if parameter is not None and is_count(parameter):  # the whole values between, at most as many
        inner = sorted({float(round(x)) for x in inner} - {lo, hi})
    return [*(inner if a < b else inner[::-1]), b]


def orbit_of(result) -> tuple[np.ndarray, int, np.ndarray] | None:
    """What a follow starts from: the diagram's maximum's cycle (mesh points, ncol, unknowns) when
    that maximum lies inside a stable stretch of its branch, else None."""
    orbit = result.max_psi_orbit
    if orbit is None or not orbit.interior:
        return None
    return orbit.mesh, orbit.ncol, orbit.u


def follow_maximum(task: tuple) -> dict[str, Any]:
    """One unit of work: the maximum's cycle of one grid diagram followed through ``thetas``.

    ``task`` = (config, Fz, parameter, base params, orbit (mesh points, ncol, u), thetas, options,
    (v_min, v_max)). Returns ``{"config", "points": [{"p", "value", "V"}], "stopped": None or why}``:
    the points up to where the follow stopped (the cycle no longer converges at the next value, the
    maximum is no longer found in the search or not a maximum of its neighbours, the cycle of the
    maximum is no longer stable, or the maximum leaves the speed range, where a diagram would no
    longer see it)."""
    from ...continuation import ContinuationOptions

    config, Fz, parameter, params, (mesh_points, ncol, u), thetas, options, (v_min, v_max) = task
    copts = ContinuationOptions(ds=options.ds, ds_max=options.ds_max)
    points: list[dict[str, float]] = []
    for theta in thetas:
        try:
            found = _maximum_at(config, Fz, parameter, params, theta, mesh_points, ncol, u, options, copts)
        except (np.linalg.LinAlgError, ShimmyError, EngineError) as exc:  # the follow stops; the grid stands
            return {"config": config, "points": points, "stopped": f"at {theta:.6g}: {exc}"}
        if isinstance(found, str):
            return {"config": config, "points": points, "stopped": f"{found} at {theta:.6g}"}
        amplitude, u = found
        if not v_min <= u[-1] <= v_max:
            return {"config": config, "points": points,
                    "stopped": f"the maximum leaves the speed range at {theta:.6g} (V = {u[-1]:.6g} m/s)"}
        points.append({"p": float(theta), "value": float(amplitude), "V": float(u[-1])})
    return {"config": config, "points": points, "stopped": None}


def _maximum_at(config, Fz, parameter, params, theta, mesh_points, ncol, u, options, copts):
    """(amplitude, cycle unknowns) of the maximum of max|psi| along the branch through the cycle u
    corrected at design theta, or why there is none (a string)."""
    from ...continuation import step
    from ...continuation.collocation import Mesh, PeriodicProblem
    from ...model.equations import build_model
    from ..diagrams.bifurcation import (STATE_SCALE, T_SCALE, V_SCALE, at_fixed_speed, gear_field,
                                        largest_peak_along)

    model = build_model(Configuration.parse(config), params.with_overrides({parameter: theta}),
                        exact_nes=options.exact_nes)
    problem = PeriodicProblem(gear_field(model, Fz), Mesh(mesh_points, ncol), STATE_SCALE[:model.n_states],
                              T_SCALE, V_SCALE)
    problem.accept(u)
    centre = at_fixed_speed(problem, u, copts)
    if centre is None:
        return "the cycle does not converge"
    problem.accept(centre.u)
    found = None
    for _ in range(RECENTRES):
        h, amplitude, point = largest_peak_along(problem, centre, -SEARCH_SPAN, SEARCH_SPAN, copts,
                                                 xatol=1e-5 * SEARCH_SPAN)
        if point is None:
            break
        if abs(h) < 0.9 * SEARCH_SPAN:
            found = (amplitude, point, h)
            break
        centre = step(problem, centre, h, copts)  # the maximum lies beyond the span: search from there
        if centre is None:
            break
        problem.accept(centre.u)
    if found is None:
        return "no maximum along the branch"
    amplitude, point, h = found
    for side in (-1.0, 1.0):  # a maximum of its neighbours, not the edge of where steps fail
        near = step(problem, centre, h + side * 1e-3 * SEARCH_SPAN, copts, with_tangent=False)
        if near is None or problem.peak(near.u, 0)[2] > amplitude * (1.0 + 1e-12):
            return "no maximum along the branch (not a maximum of its neighbours)"
    multipliers = problem.multipliers(point.u)
    if not np.all(np.abs(multipliers[1:]) < 1.0):
        return "the cycle of the maximum is unstable"
    return amplitude, point.u.copy()


def arrives(follow: dict[str, Any] | None, theta: float, value: float | None) -> bool:
    """Whether a follow reached grid value theta with the diagram's value there (to :data:`AGREE`)."""
    if follow is None or not follow["points"] or value is None:
        return False
    end = follow["points"][-1]
    return end["p"] == theta and abs(end["value"] - value) <= AGREE * max(abs(value), 1e-12)


def max_psi_curve(config: str, parameter: str, rows: Sequence[dict[str, Any]],
                  v_range: tuple[float, float],
                  follows: dict[tuple[float, float], dict[str, Any]] | None = None) -> StudyCurve:
    """The curve from one diagram's row per grid value (as the study's units of work make them:
    ``max_psi``, ``max_psi_V`` and the parameter's value), sorted by theta, with the followed points
    between them (``follows[(a, b)]``: the follow from grid value a towards b, as
    :func:`follow_maximum` returns it) and its switches."""
    ordered = sorted(rows, key=lambda r: r[parameter])
    follows = follows or {}
    p: list[float] = []
    values: list[float | None] = []
    speeds: list[float | None] = []
    for k, row in enumerate(ordered):
        p.append(float(row[parameter]))
        values.append(None if row["max_psi"] is None else float(row["max_psi"]))
        speeds.append(row.get("max_psi_V"))
        if k + 1 == len(ordered):
            break
        a, b = p[-1], float(ordered[k + 1][parameter])
        ahead = follows.get((a, b))
        back = follows.get((b, a))
        between = {}
        for follow in (ahead, back):
            for q in (follow or {"points": []})["points"]:
                if q["p"] not in (a, b) and (q["p"] not in between or q["value"] > between[q["p"]]["value"]):
                    between[q["p"]] = q
        for theta in sorted(between):
            p.append(theta)
            values.append(between[theta]["value"])
            speeds.append(between[theta]["V"])
    jump = SWITCH_JUMP * (v_range[1] - v_range[0])
    special = []
    for k in range(len(p) - 1):
        a, b = speeds[k], speeds[k + 1]
        appears = (a is None) != (b is None)
        if appears or (a is not None and b is not None and abs(b - a) > jump):
            special.append({"kind": "switch", "p": 0.5 * (p[k] + p[k + 1]), "value": None, "located": False,
                            "bracket": [p[k], p[k + 1]],
                            "why": "stable cycles appear or vanish" if appears else
                                   f"the maximum's speed jumps from {a:.4g} to {b:.4g} m/s"})
    return StudyCurve(config, "max_psi", parameter, p, values, special)
