"""The largest stable torsional amplitude at a load as a curve in a design parameter.

``max_psi`` of a study is the largest |psi| over the stable limit cycles of the one-parameter
bifurcation diagram in V at the study's load (:func:`shimmy.analyses.diagrams.bifurcation.bifurcation`:
the cycles continued by collocation, the maximum refined along its branch). Here it is computed on a
grid of the design parameter theta over its whole range (:data:`N_GRID` values evenly, the ends
included, with the sampled study's values and the base design's), each value a full diagram with the
sampled study's own options: at the sampled values the curve's value *is* the sampled row's, and at
every grid value it is exact to the diagram's tolerances (the maximum located to 1e-8 of the
branch's arclength). Between grid values the curve is not continued: its polyline joins exact
points.

Where the picture changes between two grid values (special points, ``"kind": "switch"``, not
located: ``"located": false`` with the ``bracket`` of theta): the speed of the maximum jumps by more
than :data:`SWITCH_JUMP` of the study's speed range (the maximum moves to another branch or another
hump of its branch), or stable cycles appear or vanish (max_psi 0 on one side). A maximum that lives
only between two grid values is missed; the grid can be refined by asking for values.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from ...model.parameters import Parameters
from .study_curves import SNAP, StudyCurve, parameter_range

#: Grid values of theta over its whole range, the ends included (plus the sampled and base values).
N_GRID = 9
#: A jump of the maximum's speed by more than this fraction of the study's speed range between two
#: grid values marks a switch of the maximum (to another branch or hump).
SWITCH_JUMP = 0.1


def grid(parameter: str, params: Parameters, values: Sequence[float] = ()) -> list[float]:
    """theta's grid: :data:`N_GRID` values evenly over its whole range, the base design's value and
    ``values``; values closer than :data:`~.study_curves.SNAP` of the range are one."""
    lo, hi = parameter_range(parameter, params)
    base = float(getattr(params, parameter))
    wanted = sorted(set(np.linspace(lo, hi, N_GRID).tolist()) | {float(v) for v in values}
                    | ({base} if lo <= base <= hi else set()))
    out: list[float] = []
    for theta in wanted:
        if out and abs(theta - out[-1]) <= SNAP * (hi - lo):
            if theta in values:  # an asked-for value wins: the sampled row is at it exactly
                out[-1] = theta
            continue
        out.append(theta)
    return out


def max_psi_curve(config: str, parameter: str, rows: Sequence[dict[str, Any]],
                  v_range: tuple[float, float]) -> StudyCurve:
    """The curve from one diagram's row per grid value (as the study's units of work make them:
    ``max_psi``, ``max_psi_V`` and the parameter's value), sorted by theta, with its switches."""
    ordered = sorted(rows, key=lambda r: r[parameter])
    p = [float(r[parameter]) for r in ordered]
    values = [None if r["max_psi"] is None else float(r["max_psi"]) for r in ordered]
    speeds = [r.get("max_psi_V") for r in ordered]
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
