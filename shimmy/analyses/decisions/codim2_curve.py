"""The generalised Hopf (GH) and double-Hopf points of straight rolling as curves in a design parameter.

At a design, the Hopf curves of x = 0 in (V, Fz) carry codimension-2 points
(:func:`shimmy.analyses.diagrams.hopf_curves.hopf_curves` locates them along the curves):

* **GH**: the first Lyapunov coefficient l1 changes sign along a Hopf curve: on one side the onset
  of shimmy is soft (supercritical: small stable cycles), on the other hard (subcritical: a jump to
  a large cycle, with hysteresis). Smooth configurations only (``original``, ``nes``): the particle
  damper's torque is not smooth at rest, so l1 is not defined there.
* **Double Hopf**: two Hopf curves cross: two pairs of eigenvalues on the imaginary axis at once (the
  lateral and the torsional mode lose stability together); torus curves of cycles are born there.

Each is a zero of two equations in (V, Fz) at fixed design theta:

* GH: Re lambda(V, Fz) = 0 and l1(V, Fz) = 0, l1 evaluated with the followed pair's vectors
  (:func:`shimmy.continuation.first_lyapunov_coefficient` with a frequency hint; off the Hopf curve
  the same formula is a smooth test function equal to l1 on it), scaled by the base point's |dl1/dFz|;
* double Hopf: Re lambda_a(V, Fz) = 0 and Re lambda_b(V, Fz) = 0, the two pairs followed by their
  frequencies.

Every point of the base design is followed over theta's whole range as the minimum shimmy load is
(:mod:`.min_shimmy_curve`): solved by Newton's method at every grid value (to 1e-10 of the scales
10 m/s and 100 kN; evenly spaced, and geometrically too over a range of more than a decade),
stepping from the base value to either end, each step started from the last two solutions' secant
and halved where Newton does not converge from it (the halved steps' solutions are points of the
curve too). Where a point stops converging however short the step (GH: l1 no longer changes sign
along the curve, the point merges with another; double Hopf: the two frequencies meet) or leaves
the box, its end is a special point (``"kind": "end"``, with the bracket of theta it lies in, at
most ``END_TOL`` of the range wide, and why). Each followed point gives
two curves, its load (``gh_Fz`` / ``double_hopf_Fz``, N) and speed (``gh_V`` / ``double_hopf_V``,
m/s), numbered by ``point`` (1, 2, ... by speed at the base design).

Checked in the tests against the points the Hopf-curve continuation locates (an independent
method: a test function's sign change along a continued curve) at designs of the grid.
"""

from __future__ import annotations

import math
from typing import Any, Callable, Sequence

import numpy as np

from ...errors import ConvergenceError
from ...model.configurations import Configuration
from ...model.equations import Model
from ...model.parameters import DIAGRAM_V_RANGE, FZ_RANGE, Parameters
from ..core.stability import Linearisation, first_lyapunov_coefficient
from ..diagrams.hopf_curves import hopf_curves
from .min_shimmy_curve import N_GRID
from .sensitivity import critical_pair, model_with, newton_in_plane
from .study_curves import StudyCurve, is_count, on_whole_values, parameter_range, value_grid, whole_values

#: Newton's method is converged when a step is below this fraction of the scales (10 m/s, 100 kN).
TOL = 1e-10
SCALES = (10.0, 1e5)
#: Newton steps allowed per point (from the secant it converges in 3-6; a failed step is halved)
MAX_NEWTON = 12
#: A point whose frequency moved more than this fraction from the last point's is refused (the step is
#: halved): Newton followed another pair of eigenvalues.
FREQUENCY_JUMP = 0.05
#: A point's end (where Newton stops converging, or it leaves the box) is bracketed to this fraction of
#: theta's range.
END_TOL = 1e-6
#: The kinds followed, with the names of their two curves.
QUANTITIES = {"gh": ("gh_Fz", "gh_V"), "double_hopf": ("double_hopf_Fz", "double_hopf_V")}


def gh_equations(model: Model, omega: float, l1_scale: float) -> Callable[[float, float], np.ndarray]:
    """(Re lambda, l1 / l1_scale) at (V, Fz) for the pair followed from frequency ``omega`` (rad/s;
    updated as it is followed)."""
    state = {"omega": omega}

    def g(V: float, Fz: float) -> np.ndarray:
        eig = critical_pair(Linearisation(model, Fz).at(V), state["omega"])
        state["omega"] = eig.lam.imag
        l1 = first_lyapunov_coefficient(model, V, Fz, omega_hint=state["omega"])
        return np.array([eig.lam.real, l1 / l1_scale])

    g.state = state  # type: ignore[attr-defined]
    return g


def double_hopf_equations(model: Model, omega_a: float, omega_b: float) -> Callable[[float, float], np.ndarray]:
    """(Re lambda_a, Re lambda_b) at (V, Fz), the two pairs followed from their frequencies (rad/s)."""
    state = {"omega": [omega_a, omega_b]}

    def g(V: float, Fz: float) -> np.ndarray:
        J = Linearisation(model, Fz).at(V)
        a, b = (critical_pair(J, w) for w in state["omega"])
        if abs(a.lam - b.lam) <= 1e-9 * abs(a.lam):
            raise ConvergenceError(f"the two pairs of the double-Hopf point met (1:1 resonance) at V = {V:.6g} m/s")
        state["omega"] = [a.lam.imag, b.lam.imag]
        return np.array([a.lam.real, b.lam.real])

    g.state = state  # type: ignore[attr-defined]
    return g


def _l1_scale(model: Model, V: float, Fz: float, omega: float) -> float:
    """|dl1/dFz| at the base point times 100 kN: l1 / this is of the order of a load step in units of
    100 kN (so that its tolerance matches the load's)."""
    h = 1e-4 * SCALES[1]
    slope = (first_lyapunov_coefficient(model, V, Fz + h, omega_hint=omega)
             - first_lyapunov_coefficient(model, V, Fz - h, omega_hint=omega)) / (2 * h)
    return max(abs(slope) * SCALES[1], 1e-300)


def polish(kind: str, model: Model, V: float, Fz: float, frequencies: Sequence[float],
           l1_scale: float = 1.0) -> tuple[float, float, list[float]]:
    """(V, Fz, frequencies in rad/s) of the ``kind`` ("gh" or "double_hopf") point near (V, Fz)."""
    if kind == "gh":
        g = gh_equations(model, frequencies[0], l1_scale)
        what = "the generalised Hopf point"
    else:
        g = double_hopf_equations(model, *frequencies)
        what = "the double-Hopf point"
    with np.errstate(all="ignore"):  # a value that is not finite is refused by Newton's method
        z = newton_in_plane(g, (V, Fz), SCALES, TOL, what, max_steps=MAX_NEWTON, stop_diverging=True)
    omega = g.state["omega"]  # type: ignore[attr-defined]
    found = list(omega) if isinstance(omega, list) else [omega]
    # the same pair(s) as at the start: a frequency that jumped is another pair's point
    for before, after in zip(frequencies, found, strict=True):
        if abs(after - before) > FREQUENCY_JUMP * abs(before):
            raise ConvergenceError(f"{what} near V = {V:.6g} m/s, Fz = {Fz:.6g} N converged on another pair "
                                   f"(frequency {before / (2 * np.pi):.4g} -> {after / (2 * np.pi):.4g} Hz)")
    return float(z[0]), float(z[1]), found


def _follow(solve: Callable[[float, tuple[float, float], list[float]], tuple[float, float, list[float]]],
            grid: list[float], k0: int, z0: tuple[float, float], f0: list[float], inside: Callable[[float, float], bool],
            end_tol: float) -> tuple[dict[float, tuple[float, float]], list[dict[str, Any]]]:
    """Natural-parameter continuation of a point from grid[k0] to both ends of ``grid``: each step
    started from the secant through the last two solutions; a step that does not converge, or lands
    outside the box, is halved until it does, down to ``end_tol``, where the point's end is taken
    (bracketed to ``end_tol``). Returns {theta: (V, Fz)} of every solved value (the grid's and the
    halved steps') and the ends."""
    solved = {grid[k0]: z0}
    ends: list[dict[str, Any]] = []
    for order in (grid[k0 + 1:], grid[:k0][::-1]):
        path = [(grid[k0], z0, f0)]
        h = math.inf  # the longest step tried next: twice the last one that converged after a halving
        ended = False
        for target in order:
            t, why = target, ""
            while not ended:
                (t1, z1, f1) = path[-1]
                if abs(t - t1) > h:
                    t = t1 + math.copysign(h, t - t1)
                if len(path) > 1:
                    t2, z2, _ = path[-2]
                    w = (t - t1) / (t1 - t2)
                    guess = (z1[0] + w * (z1[0] - z2[0]), z1[1] + w * (z1[1] - z2[1]))
                else:
                    guess = z1
                try:
                    V, Fz, f = solve(t, guess, f1)
                    ok = inside(V, Fz)
                    why = why if ok else "left the box"
                except ConvergenceError as exc:
                    ok, why = False, str(exc)
                if ok:
                    path.append((t, (V, Fz), f))
                    solved[t] = (V, Fz)
                    if math.isfinite(h):
                        h *= 2.0
                    if t == target:
                        break
                    t = target
                    continue
                if abs(t - t1) <= end_tol:
                    ends.append({"kind": "end", "p": t1, "V": z1[0], "Fz": z1[1], "bracket": sorted([t1, t]),
                                 "why": why})
                    ended = True
                h = 0.5 * abs(t - t1)
                t = t1 + 0.5 * (t - t1)
            if ended:
                break
    return solved, ends


def codim2_curves(config: Configuration | str, parameter: str, *, params: Parameters | None = None,
                  v_range: tuple[float, float] = DIAGRAM_V_RANGE, fz_range: tuple[float, float] = FZ_RANGE,
                  values: Sequence[float] = (), n: int = N_GRID, hopf=None) -> tuple[list[StudyCurve], list[str]]:
    """The curves ``gh_Fz``, ``gh_V``, ``double_hopf_Fz`` and ``double_hopf_V`` of ``config`` against
    ``parameter`` over its whole range (one pair per point of the base design, see the module) and
    warnings. ``hopf``: the base design's Hopf curves in this box, if computed already."""
    config = Configuration.parse(config)
    params = params if params is not None else Parameters()
    lo, hi = parameter_range(parameter, params)
    base = float(getattr(params, parameter))
    hopf = hopf or hopf_curves(config, params=params, v_range=v_range, fz_range=fz_range)
    starts: list[tuple[str, dict[str, Any]]] = [("gh", g) for g in sorted(hopf.gh_points, key=lambda g: g["V"])]
    starts += [("double_hopf", g) for g in sorted(hopf.double_hopf_points, key=lambda g: g["V"])]
    spread = whole_values(lo, hi) if is_count(parameter) else value_grid(lo, hi, n)  # a count: its whole values
    grid = sorted({float(t) for t in spread} | {base} | {float(v) for v in values if lo <= v <= hi})
    k0 = grid.index(base)
    base_model = model_with(config, params, parameter, base)
    curves: list[StudyCurve] = []
    warnings: list[str] = []
    numbers = {"gh": 0, "double_hopf": 0}

    def inside(V: float, Fz: float) -> bool:
        return v_range[0] <= V <= v_range[1] and fz_range[0] <= Fz <= fz_range[1]

    for kind, start in starts:
        numbers[kind] += 1
        label = f"{'GH' if kind == 'gh' else 'double-Hopf'} point {numbers[kind]}"
        freqs = [2 * np.pi * start["frequency_hz"]] + ([2 * np.pi * start["frequency2_hz"]]
                                                       if kind == "double_hopf" else [])
        scale = _l1_scale(base_model, start["V"], start["Fz"], freqs[0]) if kind == "gh" else 1.0
        try:
            V, Fz, freqs = polish(kind, base_model, start["V"], start["Fz"], freqs, scale)
        except ConvergenceError as exc:
            warnings.append(f"{label} (V = {start['V']:.5g} m/s, Fz = {start['Fz'] / 1e3:.5g} kN) not followed: {exc}")
            continue

        def solve(t, guess, f, kind=kind, scale=scale):
            return polish(kind, model_with(config, params, parameter, t), *guess, f, scale)

        solved, ends = _follow(solve, grid, k0, (V, Fz), freqs, inside, END_TOL * (hi - lo))
        thetas = sorted(set(grid) | set(solved))
        fz_name, v_name = QUANTITIES[kind]
        for quantity, column in ((fz_name, 1), (v_name, 0)):
            marks = [dict(e, value=e["Fz"] if column else e["V"]) for e in ends]
            curve = StudyCurve(config.value, quantity, parameter, thetas,
                               [solved[t][column] if t in solved else None for t in thetas],
                               sorted(marks, key=lambda e: e["p"]), point=numbers[kind])
            curves.append(on_whole_values(curve))
        for e in ends:
            side = "below" if e["p"] < base else "above"
            warnings.append(f"{label} ends {side} {parameter} = {e['p']:.8g} ({e['why']}); no value past it, not zero")
    return curves, warnings
