"""Studies as curves: the Hopf speeds at a load, continued in a design parameter over its whole range.

A sampled study (:mod:`shimmy.analyses.decisions.studies`) computes one diagram per value of a
design parameter theta. Here the Hopf points of straight rolling x = 0 at the study's load Fz are
continued as curves in the plane (V, theta) by the engine's two-parameter Hopf continuation
(:func:`shimmy.continuation.hopf_curve`, the standard extended system) on
:func:`design_two_parameter_field`: the gear's field with p = (V, theta) at fixed Fz. The model's
derivative in theta is not analytic (theta enters through the model's coefficients, some of them
fitted curves of the NES geometry): it is a central difference of the right-hand side in theta
(relative step :data:`THETA_STEP` of theta's range). That only enters the Newton matrix and the
tangent; the residual, the Hopf condition itself, is exact, so every continued point is an exact
Hopf point.

Curves start from the eigenvalue scan (:func:`shimmy.analyses.core.stability.hopf_points`) at
:data:`N_STARTS` values evenly over theta's range and at the base design's value, and run both
ways until they leave the box (speed range) x (theta range), close, or reach omega = 0. At every
value of theta of the reported grid (the curves' points, their special points, the range's ends and
any values asked for, e.g. a sampled study's) the Hopf speeds are the crossings of the curves with
that theta, each polished by Newton's method on Re lambda(V) = 0 at fixed theta with the exact
dJ/dV of J(V) = J0 + V J1 + J2/V (to 1e-12 of V). ``hopf_V_start`` is the lowest of them,
``hopf_V_end`` the highest (m/s), as the sampled study's ``hopf_start`` and ``hopf_end``.

Where the picture changes (special points): a curve turning in theta (a pair of Hopf points is born
or dies: P2_TURN), two curves crossing (two pairs on the imaginary axis at once, the lowest or
highest switching from one curve to the other: HH), and a curve leaving through a speed edge (a
Hopf point enters or leaves the speed range: EP); each is listed for a quantity when its speed is
that quantity's value there.

A curve (an isola in (V, theta)) that no start meets is missed; the starts are spread over the
range so a missed one lies between two starts. Parameters of the particle damper's material and
packing (a_p, rho_p, ...) leave the linearisation unchanged: their curves are lines of constant
speed.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np
import scipy.linalg

from ...continuation import ContinuationOptions, HopfCurve, PointKind, TwoParameterField, hopf_curve
from ...continuation.scalar import root_in
from ...errors import ConvergenceError, InvalidParameterError
from ...model.configurations import Configuration
from ...model.equations import Model, field_and_derivatives, jacobian, rhs
from ...model.parameters import (DEFAULT_FZ, DIAGRAM_V_RANGE, FZ_RANGE, PARAMETER_SPECS, V_RANGE, Parameters,
                                 check_number, check_range, unknown_name_error)
from ...model.units import kn
from ..core.polylines import near_polyline
from ..core.stability import Linearisation, hopf_points
from .sensitivity import model_with

#: The quantities a study curve can follow, with their units.
CURVE_QUANTITIES = {"hopf_V_start": "m/s", "hopf_V_end": "m/s", "min_shimmy_Fz": "N", "max_psi": "rad",
                    "gh_Fz": "N", "gh_V": "m/s", "double_hopf_Fz": "N", "double_hopf_V": "m/s"}
#: Central-difference step of the field's derivative in theta, relative to theta's range.
THETA_STEP = 1e-6
#: Start values of theta over its range (plus the base design's value): evenly, and geometrically
#: too where the range spans more than a decade.
N_STARTS = 9
#: Values of theta on which the speed edges are scanned for curves entering through them.
N_EDGE_SCAN = 200
V_SCALE = 10.0  # m/s: a unit step of the continuation in V
X_SCALE = np.array([0.05, 5.0, 0.005, 0.5, 0.01, 0.05, 5.0])
#: Newton on Re lambda(V) = 0 at fixed theta: converged when a step is below this of V.
V_TOL = 1e-12
#: Margin kept from where the NES roller would leave its track (relative to the parameter's range).
TRACK_MARGIN = 1e-3
#: Values of theta closer than this (relative to its range) are one grid value (a curve's end located
#: on a range end lies within the location tolerance of it).
SNAP = 1e-8


def parameter_range(name: str, params: Parameters) -> tuple[float, float]:
    """theta's whole range: its design range, narrowed for r1, r2, r3 to where the NES roller stays on
    its track (r2 + r3 > (sqrt(3)/4)(r1 + r2)) with the other two at their values in ``params``."""
    if name not in PARAMETER_SPECS:
        raise unknown_name_error(name, PARAMETER_SPECS)
    spec = PARAMETER_SPECS[name]
    lo, hi = float(spec.low), float(spec.high)
    k = math.sqrt(3.0) / 4.0
    r1, r2, r3 = params.nes.r1, params.nes.r2, params.nes.r3
    margin = TRACK_MARGIN * (hi - lo)
    if name == "r1":
        hi = min(hi, (r2 + r3) / k - r2 - margin)
    elif name == "r2":
        lo = max(lo, (k * r1 - r3) / (1.0 - k) + margin)
    elif name == "r3":
        lo = max(lo, k * (r1 + r2) - r2 + margin)
    if not lo < hi:
        raise InvalidParameterError(name, getattr(params, name), "a range where the NES roller stays on its track",
                                    "has no such range with the other NES radii of this design")
    return lo, hi


def design_two_parameter_field(config: Configuration, params: Parameters, name: str, Fz: float,
                               span: float) -> TwoParameterField:
    """The gear's field at load Fz (N) in p = (V, theta), theta the parameter ``name``: analytic in x
    and V, a central difference in theta (step THETA_STEP * span) of the right-hand side."""
    cache: dict[float, Model] = {}

    def model(theta: float) -> Model:
        theta = float(theta)
        m = cache.get(theta)
        if m is None:
            if len(cache) > 64:
                cache.clear()
            m = cache[theta] = model_with(config, params, name, theta)
        return m

    h = THETA_STEP * span

    def d_theta(x, p):
        return (rhs(model(p[1] + h), x, p[0], Fz) - rhs(model(p[1] - h), x, p[0], Fz)) / (2.0 * h)

    def evaluate(x, p):
        f, J, dV, _ = field_and_derivatives(model(p[1]), x, p[0], Fz)
        return f, J, np.stack([dV, d_theta(x, p)])

    def dfdp(x, p):
        return evaluate(x, p)[2]

    return TwoParameterField(config.n_states, lambda x, p: rhs(model(p[1]), x, p[0], Fz),
                             lambda x, p: jacobian(model(p[1]), x, p[0], Fz), dfdp,
                             f"{config.value} in (V, {name}) at Fz = {kn(Fz)}", evaluate, smooth=False)


@dataclass
class StudyCurve:
    """One quantity of one configuration against one parameter: exact values on a grid of p, with the
    special points where the picture changes."""

    config: str
    quantity: str
    param: str
    p: list[float]
    values: list[float | None]
    special_points: list[dict[str, Any]]
    #: which point of the base design a codimension-2 point's curves follow (1, 2, ... by speed); None otherwise
    point: int | None = None

    def value_at(self, theta: float) -> float | None:
        """The value at a grid value of p (exact there); KeyError off the grid."""
        for p, v in zip(self.p, self.values, strict=True):
            if p == theta:
                return v
        raise KeyError(theta)

    def to_dict(self) -> dict[str, Any]:
        return {"config": self.config, "quantity": self.quantity, "param": self.param, "p": list(self.p),
                "values": list(self.values), "special_points": list(self.special_points),
                "unit": CURVE_QUANTITIES[self.quantity], **({} if self.point is None else {"point": self.point})}


def _critical(J: np.ndarray, omega: float):
    ev, vl, vr = scipy.linalg.eig(J, left=True, right=True)
    i = int(np.argmin(np.abs(ev - 1j * abs(omega))))
    q, w = vr[:, i], vl[:, i]
    return complex(ev[i]), q, w / np.conj(np.conj(w) @ q)


def polish_hopf_speed(lin: Linearisation, V: float, omega: float) -> tuple[float, float]:
    """(V, omega) with Re lambda(V) = 0 near V for the eigenvalue nearest i omega, by Newton's method
    with d lambda/dV = w^H (J1 - J2/V^2) q / (w^H q); ConvergenceError if it does not converge."""
    for _ in range(30):
        lam, q, w = _critical(lin.at(V), omega)
        omega = lam.imag
        slope = (np.conj(w) @ (lin.J1 - lin.J2 / (V * V)) @ q).real
        if slope == 0.0:
            break
        step = -lam.real / slope
        V += step
        if abs(step) <= V_TOL * max(abs(V), 1.0):
            return V, _critical(lin.at(V), omega)[0].imag
    raise ConvergenceError(f"the Hopf speed near V = {V:.6g} m/s did not converge")


@dataclass
class HopfSpeedCurves:
    """The Hopf curves of x = 0 in (V, theta) at one load, and the Hopf speeds they give at any theta."""

    config: Configuration
    param: str
    Fz: float
    params: Parameters
    v_range: tuple[float, float]
    p_range: tuple[float, float]
    curves: list[HopfCurve]
    elapsed_s: float
    warnings: list[str] = field(default_factory=list)

    def linearisation(self, theta: float) -> Linearisation:
        model = model_with(self.config, self.params, self.param, theta)
        return Linearisation(model, self.Fz)

    def speeds_at(self, theta: float) -> list[float]:
        """Every Hopf speed (m/s) in the speed range at theta, sorted: each crossing of a curve with
        theta polished by Newton at fixed theta (turning points and ends taken as located)."""
        lin = self.linearisation(theta)
        tol = 1e-12 * (self.p_range[1] - self.p_range[0])
        snap = SNAP * (self.p_range[1] - self.p_range[0])
        found: list[float] = []
        for c in self.curves:
            for s in c.points_of(PointKind.P2_TURN):
                if abs(s.p[1] - theta) <= tol:
                    found.append(float(s.p[0]))
            polished: list[tuple[float, float]] = []
            P, omegas = _polyline(c)
            th = P[:, 1]
            last = len(th) - 2
            for i in range(len(th) - 1):
                a, b = th[i], th[i + 1]
                # the curve's end points are located on the range's ends to the location tolerance
                lo_i = min(a, b) - (snap if i in (0, last) else 0.0)
                hi_i = max(a, b) + (snap if i in (0, last) else 0.0)
                if not lo_i <= theta <= hi_i or a == b:
                    continue
                if theta == b and i < last:
                    continue  # counted on the next segment
                s = (theta - a) / (b - a)
                V0 = (1 - s) * P[i, 0] + s * P[i + 1, 0]
                omega0 = (1 - s) * omegas[i] + s * omegas[i + 1]
                if self._near_located(c, theta, V0, tol):
                    continue
                try:
                    V, _ = polish_hopf_speed(lin, V0, omega0)
                except ConvergenceError:
                    V = self._scanned_speed(theta, V0)
                if any(abs(V - W) <= 1e-9 * max(V, 1.0) and abs(V0 - W0) > 1e-6 * max(V0, 1.0)
                       for W, W0 in polished):
                    V = self._scanned_speed(theta, V0)  # two chords converged to one root: near a turn
                polished.append((V, V0))
            found.extend(V for V, _ in polished)
        lo, hi = self.v_range
        out: list[float] = []
        for V in sorted(found):
            if lo - 1e-9 * hi <= V <= hi + 1e-9 * hi and not (out and abs(V - out[-1]) <= 1e-9 * max(V, 1.0)):
                out.append(V)
        return out

    def _scanned_speed(self, theta: float, V0: float) -> float:
        """The Hopf speed nearest V0 from the eigenvalue scan near it (where Newton's method does not
        converge: near a turn in theta, or where another eigenvalue comes close to the critical one)."""
        design = self.params.with_sampled({self.param: theta})
        lo, hi = self.v_range
        window = (max(lo, 0.8 * V0), min(hi, 1.25 * V0))
        found = hopf_points(self.config, self.Fz, params=design, v_range=window).hopf_points
        if not found:
            raise ConvergenceError(f"no Hopf speed near V = {V0:.6g} m/s at {self.param} = {theta:.6g}")
        return min((h.V for h in found), key=lambda V: abs(V - V0))

    @staticmethod
    def _near_located(c: HopfCurve, theta: float, V: float, tol: float) -> bool:
        """Whether a crossing at (V, theta) is a located turning point (taken as located)."""
        return any(abs(s.p[1] - theta) <= tol and abs(s.p[0] - V) <= 0.5 * V_SCALE
                   for s in c.points_of(PointKind.P2_TURN))

    def _second_pair_on_axis(self, s) -> bool:
        """Whether a double-Hopf point has a second pair on the imaginary axis (the engine's test also
        changes sign where two real eigenvalues of the other modes meet and turn complex, far from it)."""
        ev = np.linalg.eigvals(self.linearisation(s.p[1]).at(s.p[0]))
        omega = abs(s.data["omega"])
        others = ev[(ev.imag > 0) & (np.abs(ev - 1j * omega) > 1e-6 * omega)]
        return bool(others.size) and float(np.min(np.abs(others.real))) <= 1e-5 * omega

    def events(self) -> list[dict[str, Any]]:
        """Where the picture changes: turns in theta, crossings of two curves, ends on a speed edge."""
        out = []
        for c in self.curves:
            for s in c.special_points:
                if s.kind is PointKind.DOUBLE_HOPF and not self._second_pair_on_axis(s):
                    continue
                if s.kind in (PointKind.P2_TURN, PointKind.DOUBLE_HOPF):
                    out.append({"kind": s.kind, "p": float(s.p[1]), "V": float(s.p[0]), "located": s.located})
            if c.closed or c.p.size == 0:
                continue
            for end in (c.p[0], c.p[-1]):  # an end on a speed edge: a Hopf point enters or leaves the range
                if min(abs(end[0] - e) for e in self.v_range) <= 1e-9 * self.v_range[1]:
                    out.append({"kind": PointKind.END, "p": float(end[1]), "V": float(end[0]), "located": True})
        out.sort(key=lambda e: e["p"])
        return out

    def study_curves(self, values: Sequence[float] = ()) -> list[StudyCurve]:
        """hopf_V_start and hopf_V_end on the grid: the curves' points, the events, the range's ends
        and ``values``."""
        lo, hi = self.p_range
        events = self.events()
        fixed = sorted({lo, hi, *(float(v) for v in values)})
        if is_count(self.param):  # a count: its whole values only (the events snap to them, not located)
            fixed = sorted(set(fixed) | set(whole_values(lo, hi)))
            for e in events:
                e["located"] = False
        grid = list(fixed)
        candidates = [] if is_count(self.param) else \
            sorted([e["p"] for e in events] + [float(t) for c in self.curves for t in c.p[:, 1]])
        snap = SNAP * (hi - lo)
        for t in candidates:
            if lo <= t <= hi and all(abs(t - g) > snap for g in fixed) and (len(grid) == len(fixed) or
                                                                           abs(t - grid[-1]) > snap):
                grid.append(t)
        grid.sort()
        for e in events:  # an event on a range end or an asked-for value is reported there
            e["p"] = min(grid, key=lambda g: abs(g - e["p"]))
        speeds = [self.speeds_at(t) for t in grid]
        out = []
        for quantity, pick in (("hopf_V_start", min), ("hopf_V_end", max)):
            vals = [pick(s) if s else None for s in speeds]
            special = []
            for e in events:
                here = speeds[grid.index(e["p"])] if e["p"] in grid else []
                if here and abs(pick(here) - e["V"]) <= 1e-6 * max(e["V"], 1.0):
                    special.append({"kind": str(e["kind"]), "p": e["p"], "value": e["V"], "located": e["located"]})
            out.append(StudyCurve(self.config.value, quantity, self.param, grid, vals, special))
        return [on_whole_values(c) for c in out]


def is_count(parameter: str) -> bool:
    """Whether ``parameter`` is a count (an integer parameter: the particle damper's segments ``n``): its
    study curves take its whole values only."""
    spec = PARAMETER_SPECS.get(parameter)
    return bool(spec is not None and spec.integer)


def whole_values(lo: float, hi: float) -> list[float]:
    """The whole values in [lo, hi]."""
    return [float(k) for k in range(math.ceil(lo), math.floor(hi) + 1)]


def on_whole_values(curve: "StudyCurve") -> "StudyCurve":
    """A curve in a count at its whole values only: its points at whole p (each exact there: the curves
    are continued in the count as a real number, but only the whole ones are designs); a special point
    between two whole values is reported at the next one (the last, past the end), not located, with the
    two whole values it lies between and the value there. A curve in any other parameter as it is."""
    if not is_count(curve.param):
        return curve
    points = [(p, v) for p, v in zip(curve.p, curve.values, strict=True) if float(p).is_integer()]
    at = dict(points)
    special = []
    for q in curve.special_points:
        if float(q["p"]).is_integer():
            special.append(q)
            continue
        whole = min(float(math.ceil(q["p"])), points[-1][0]) if points else float(math.ceil(q["p"]))
        special.append({**q, "p": whole, "value": at.get(whole), "located": False,
                        "between": [float(math.floor(q["p"])), float(math.ceil(q["p"]))]})
    return StudyCurve(curve.config, curve.quantity, curve.param, [p for p, _ in points], [v for _, v in points],
                      sorted(special, key=lambda q: q["p"]), curve.point)


def value_grid(lo: float, hi: float, n: int) -> np.ndarray:
    """n values evenly over [lo, hi], and n geometrically spaced too if lo > 0 and hi > 10 lo."""
    even = np.linspace(lo, hi, n)
    if lo > 0 and hi > 10 * lo:
        return np.unique(np.concatenate([even, np.geomspace(lo, hi, n)]))
    return even


def _polyline(c: HopfCurve) -> tuple[np.ndarray, np.ndarray]:
    """The curve's points in (V, theta) and omega, with its located turning points in theta inserted
    (so that the chords reach the tip of each turn)."""
    P, omega = list(c.p), list(c.omega)
    for s in sorted(c.points_of(PointKind.P2_TURN), key=lambda s: -s.index):
        if s.located and 0 < s.index < len(c.p):
            P.insert(s.index, np.array(s.p))
            omega.insert(s.index, s.data["omega"])
    return np.array(P), np.array(omega)


def _edge_starts(config: Configuration, params: Parameters, name: str, Fz: float, V: float,
                 thetas: np.ndarray) -> list[float]:
    """Values of theta where a Hopf curve crosses the speed edge V: sign changes of the ordered real
    parts of J(V; theta) on ``thetas``, refined by Brent's method (curves entering through a speed edge
    between the starts are continued from there)."""
    def ordered(theta: float) -> np.ndarray:
        model = model_with(config, params, name, theta)
        return np.sort(np.linalg.eigvals(Linearisation(model, Fz).at(V)).real)[::-1]

    re = np.array([ordered(t) for t in thetas])
    count = (re > 0).sum(axis=1)
    out = []
    for i in np.nonzero(count[:-1] != count[1:])[0]:
        k = int(min(count[i], count[i + 1]))
        out.append(root_in(lambda t: ordered(t)[k], thetas[i], thetas[i + 1], xtol=1e-12 * abs(thetas[-1])))
    return out


def hopf_speed_curves(config: Configuration | str, parameter: str, *, Fz: float = DEFAULT_FZ,
                      params: Parameters | None = None, v_range: tuple[float, float] = DIAGRAM_V_RANGE,
                      p_range: tuple[float, float] | None = None) -> HopfSpeedCurves:
    """The Hopf curves of x = 0 at load ``Fz`` (N) in (V, theta), theta = ``parameter`` over
    ``p_range`` (default: its whole range, :func:`parameter_range`), V over ``v_range`` (m/s)."""
    clock = time.perf_counter()
    config = Configuration.parse(config)
    params = params if params is not None else Parameters()
    Fz = check_number("Fz", Fz, *FZ_RANGE, "N")
    v_lo, v_hi = check_range("v", v_range, V_RANGE, "m/s")
    whole = parameter_range(parameter, params)
    p_lo, p_hi = whole if p_range is None else check_range("p", p_range, whole, PARAMETER_SPECS[parameter].unit)
    span = p_hi - p_lo
    system = design_two_parameter_field(config, params, parameter, Fz, span)
    n = system.n
    options = ContinuationOptions(ds=0.05, ds_max=0.5, max_steps=2000, max_correction=1.0)
    box = ((v_lo, v_hi), (p_lo, p_hi))
    p_scale = np.array([V_SCALE, span / 10.0])
    thetas = value_grid(p_lo, p_hi, N_STARTS)
    starts = [(None, float(t)) for t in thetas]
    nominal = float(getattr(params, parameter))
    if p_lo < nominal < p_hi:
        starts.append((None, nominal))
    fine = value_grid(p_lo, p_hi, N_EDGE_SCAN)
    starts += [(V, t) for V in (v_lo, v_hi) for t in _edge_starts(config, params, parameter, Fz, V, fine)]
    curves: list[HopfCurve] = []
    warnings: list[str] = []
    for V_edge, theta in starts:
        design = params.with_sampled({parameter: theta})
        if V_edge is None:
            points = [h.V for h in hopf_points(config, Fz, params=design, v_range=(v_lo, v_hi)).hopf_points]
        else:
            points = [V_edge]
        for V in points:
            q = np.array([V, theta]) / p_scale
            if any(near_polyline(c.p / p_scale, q) is not None for c in curves):
                continue
            try:
                curve = hopf_curve(system, np.zeros(n), np.array([V, theta]), box=box, options=options,
                                   scale=X_SCALE[:n], p_scale=p_scale)
            except ValueError as exc:
                warnings.append(f"Hopf point V = {V:.6g} m/s at {parameter} = {theta:.6g} not continued: {exc}")
                continue
            curves.append(curve)
    return HopfSpeedCurves(config, parameter, Fz, params, (v_lo, v_hi), (p_lo, p_hi), curves,
                           time.perf_counter() - clock, warnings)
