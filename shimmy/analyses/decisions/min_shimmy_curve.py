"""The minimum shimmy load as a curve in a design parameter: the lowest point of the Hopf curves of
x = 0 in (V, Fz), continued in theta over its whole range.

The lowest point of a Hopf curve is a turning point of the curve in Fz: Re lambda = 0 and
d Re lambda / dV = 0 at (V, Fz) (along the curve, dFz/dV = -(d Re lambda/dV)/(d Re lambda/dFz) = 0).
For each such minimum of the Hopf curves at the base design
(:func:`shimmy.analyses.diagrams.hopf_curves.hopf_curves`, its located P2_TURN points that are
minima in Fz), the two equations are solved at every grid value of theta by Newton's method
(:func:`shimmy.analyses.decisions.sensitivity.polish_lowest_point`, to 1e-10 of the scales 10 m/s
and 100 kN), stepping from the base value to either end, each step started from the last two
solutions' secant. ``min_shimmy_Fz`` is the lowest of the minima at each theta; where the lowest
switches from one minimum to another the switch is located (bisection on theta of their
difference, to 1e-10 of the range: a special point, ``"kind": "switch"``); where a minimum stops
converging (it merges with a maximum of its curve: the curve's dip flattens out) its end is a
special point (``"kind": "end"``).

Independent checks in the tests: the Hopf curves' own located lowest point at sampled values of
theta, and the slope at the base design against the sensitivity's dFz/dtheta. The minima of the
base design's curves are what is followed: a Hopf curve that appears elsewhere in the range with a
lower minimum is not seen; the range's two ends are checked against the Hopf curves computed
there, and a disagreement is reported in the warnings.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from ...continuation import PointKind
from ...errors import ConvergenceError
from ...model.configurations import Configuration
from ...model.parameters import DIAGRAM_V_RANGE, FZ_RANGE, Parameters
from ...model.units import kn
from ..diagrams.hopf_curves import hopf_curves
from .sensitivity import model_with, polish_lowest_point
from .study_curves import StudyCurve, is_count, on_whole_values, parameter_range, whole_values

#: Grid values of theta over its range (plus the base value and any asked for).
N_GRID = 41
#: A switch between two minima is located to this fraction of theta's range.
SWITCH_TOL = 1e-10


def _minima(hopf) -> list[tuple[float, float]]:
    """(V, Fz) of the located turning points of the Hopf curves that are minima in Fz."""
    out = []
    for c in hopf.curves:
        for s in c.points_of(PointKind.P2_TURN):
            near = c.p[max(s.index - 2, 0):s.index + 3, 1]
            if near.size and near.min() >= s.p[1] - 1e-9 * abs(s.p[1]):
                out.append((float(s.p[0]), float(s.p[1])))
    return out


def min_shimmy_curve(config: Configuration | str, parameter: str, *, params: Parameters | None = None,
                     v_range: tuple[float, float] = DIAGRAM_V_RANGE, fz_range: tuple[float, float] = FZ_RANGE,
                     values: Sequence[float] = (), n: int = N_GRID, hopf=None) -> tuple[StudyCurve, list[str]]:
    """The curve ``min_shimmy_Fz`` (N) of ``config`` against ``parameter`` over its whole range, and
    warnings (see the module). ``hopf``: the base design's Hopf curves in this box, if computed already."""
    config = Configuration.parse(config)
    params = params if params is not None else Parameters()
    lo, hi = parameter_range(parameter, params)
    base = float(getattr(params, parameter))
    warnings: list[str] = []
    starts = _minima(hopf or hopf_curves(config, params=params, v_range=v_range, fz_range=fz_range))
    if not starts:
        raise ConvergenceError(f"{config.value}: the Hopf curves have no lowest point inside the box at "
                               f"{parameter} = {base:g}: no minimum shimmy load to follow")
    spread = whole_values(lo, hi) if is_count(parameter) else np.linspace(lo, hi, n)  # a count: its whole values
    grid = sorted({float(t) for t in spread} | {base} | {float(v) for v in values if lo <= v <= hi})
    k0 = grid.index(base)
    # solutions[j][k]: (V, Fz) of minimum j at grid[k], or None past its end
    solutions: list[list[tuple[float, float] | None]] = [[None] * len(grid) for _ in starts]
    special: list[dict] = []
    for j, start in enumerate(starts):
        solutions[j][k0] = polish_lowest_point(model_with(config, params, parameter, base), *start)[:2]
        for order in (range(k0 + 1, len(grid)), range(k0 - 1, -1, -1)):
            path = [k0]
            for k in order:
                guess = _predict(grid, solutions[j], path, k)
                try:
                    V, Fz, _ = polish_lowest_point(model_with(config, params, parameter, grid[k]), *guess)
                except ConvergenceError:
                    special.append({"kind": "end", "p": grid[path[-1]], "value": solutions[j][path[-1]][1],
                                    "V": solutions[j][path[-1]][0]})
                    break
                if not (v_range[0] <= V <= v_range[1] and fz_range[0] <= Fz <= fz_range[1]):
                    special.append({"kind": "end", "p": grid[path[-1]], "value": solutions[j][path[-1]][1],
                                    "V": solutions[j][path[-1]][0], "reason": "left the box"})
                    break
                solutions[j][k] = (V, Fz)
                path.append(k)
    lowest: list[int | None] = []
    for k in range(len(grid)):
        live = [(solutions[j][k][1], j) for j in range(len(starts)) if solutions[j][k] is not None]
        lowest.append(min(live)[1] if live else None)
    switches = []
    for k in range(len(grid) - 1):
        a, b = lowest[k], lowest[k + 1]
        if a is not None and b is not None and a != b and solutions[a][k + 1] and solutions[b][k]:
            switches.append(_switch(config, params, parameter, grid, k, solutions[a], solutions[b]))
    special += switches
    curve_values = [None if j is None else solutions[j][k][1] for k, j in enumerate(lowest)]
    if None in curve_values:
        gone = [grid[k] for k, v in enumerate(curve_values) if v is None]
        warnings.append(f"no followed lowest point of the Hopf curves at {parameter} = {gone[0]:g}..{gone[-1]:g} "
                        "(every one ended there); the value there is left out, not zero")
    # the located switches are points of the curve too (its corners)
    for q in switches:
        if q.get("located", True):
            at = int(np.searchsorted(grid, q["p"]))
            grid.insert(at, q["p"])
            curve_values.insert(at, q["value"])
    for k in (0, len(grid) - 1):  # the range's ends against the Hopf curves computed there
        there = hopf_curves(config, params=params.with_overrides({parameter: grid[k]}), v_range=v_range,
                            fz_range=fz_range).fz_minimum
        if there is not None and curve_values[k] is not None and there["Fz"] < curve_values[k] * (1 - 1e-6):
            warnings.append(f"at {parameter} = {grid[k]:g} the Hopf curves reach down to Fz = {kn(there['Fz'])} "
                            f"(V = {there['V']:.5g} m/s), below the followed minimum {kn(curve_values[k])}: a "
                            "lower point not followed from the base design")
    curve = StudyCurve(config.value, "min_shimmy_Fz", parameter, grid, curve_values,
                       sorted(special, key=lambda s: s["p"]))
    return on_whole_values(curve), warnings


def _predict(grid, solutions, path, k) -> tuple[float, float]:
    """The secant through the last two solutions on the path, at grid[k] (the last one alone at first)."""
    last = solutions[path[-1]]
    if len(path) < 2:
        return last
    prev = solutions[path[-2]]
    w = (grid[k] - grid[path[-1]]) / (grid[path[-1]] - grid[path[-2]])
    return last[0] + w * (last[0] - prev[0]), last[1] + w * (last[1] - prev[1])


def _switch(config, params, parameter, grid, k, a_sol, b_sol) -> dict:
    """Where the lowest minimum switches from curve a to curve b between grid[k] and grid[k + 1]."""
    t0, t1 = grid[k], grid[k + 1]
    za0, za1, zb0, zb1 = a_sol[k], a_sol[k + 1], b_sol[k], b_sol[k + 1]
    fa = fb = None
    for _ in range(200):
        t = 0.5 * (t0 + t1)
        w = (t - grid[k]) / (grid[k + 1] - grid[k])
        model = model_with(config, params, parameter, t)
        try:
            fa = polish_lowest_point(model, za0[0] + w * (za1[0] - za0[0]), za0[1] + w * (za1[1] - za0[1]))
            fb = polish_lowest_point(model, zb0[0] + w * (zb1[0] - zb0[0]), zb0[1] + w * (zb1[1] - zb0[1]))
        except ConvergenceError:  # the bracket is all that is known
            return {"kind": "switch", "p": 0.5 * (t0 + t1), "value": None, "located": False,
                    "bracket": [t0, t1]}
        if fa[1] < fb[1]:
            t0 = t
        else:
            t1 = t
        if t1 - t0 <= SWITCH_TOL * (grid[-1] - grid[0]):
            break
    return {"kind": "switch", "p": 0.5 * (t0 + t1), "value": min(fa[1], fb[1]), "V": [fa[0], fb[0]]}
