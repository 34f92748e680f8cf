"""Hopf curves of straight rolling in the (V, Fz) plane, with their generalised Hopf points.

Start points come from the eigenvalue scan (:func:`shimmy.analyses.core.stability.hopf_points`) on
``n_slices`` loads spread over the Fz range; each Hopf point not already on a computed
curve is continued both ways in (V, Fz) by :func:`shimmy.continuation.hopf.hopf_curve`
until the curve leaves the box, closes, or reaches omega = 0. Generalised Hopf (GH)
points are where the first Lyapunov coefficient changes sign; configurations with the
particle damper are not smooth at x = 0 (|dpsi|^(1/2) dpsi), so l1 and GH points are not
defined there and are not reported.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from ...version import __version__
from ...model.configurations import Configuration
from ...continuation import ContinuationOptions, HopfCurve, PointKind, TwoParameterField, hopf_curve
from ...model.equations import build_model, field_and_derivatives, jacobian, parameter_jacobian, rhs
from ...model.parameters import FZ_RANGE, V_RANGE, Parameters, check_number, check_range
from ...model.units import kn
from ..core.polylines import near_polyline
from ..core.response import Mode, dominant_mode, torsional_share
from ..core.stability import hopf_points
from .summaries import hopf_curves_summary

V_SCALE = 10.0  # m/s
FZ_SCALE = 1.0e4  # N
#: A double-Hopf point located on each of its two curves is one point where the two lie within this
#: fraction of the scales (0.01 m/s, 10 N): each curve locates it to its own tolerance (0.13 N apart
#: was seen at nes, e_p = 3 mm, 283 kN, where 1e-5 of the scales listed it twice); two distinct
#: points are far farther apart.
SAME_POINT = 1e-3
X_SCALE = np.array([0.05, 5.0, 0.005, 0.5, 0.01, 0.05, 5.0])


@dataclass
class HopfCurvesResult:
    config: Configuration
    params: Parameters
    v_range: tuple[float, float]
    fz_range: tuple[float, float]
    curves: list[HopfCurve]
    elapsed_s: float
    warnings: list[str] = field(default_factory=list)

    @staticmethod
    def _lowest(curves: list[HopfCurve]) -> dict[str, float] | None:
        """The lowest load on the curves: a located turning point, or an end of a curve."""
        best = None
        for c in curves:
            if c.p.size == 0:
                continue
            ends = [(c.p[i].tolist(), float(c.omega[i])) for i in (0, -1)]
            for p, omega in [(t.p, t.data["omega"]) for t in c.points_of(PointKind.P2_TURN)] + ends:
                if best is None or p[1] < best["Fz"]:
                    best = {"V": p[0], "Fz": p[1], "frequency_hz": omega / (2 * math.pi)}
        return best

    @property
    def fz_minimum(self) -> dict[str, float] | None:
        """The lowest load on any Hopf curve (located turning point, or a box edge)."""
        return self._lowest(self.curves)

    @property
    def gh_points(self) -> list[dict[str, float]]:
        return [_gh_point(g) for c in self.curves for g in c.points_of(PointKind.GENERALISED_HOPF)]

    def mode_of_curve(self, curve: HopfCurve) -> Mode:
        """"torsional" or "lateral": the larger share of elastic energy in the critical eigenvector
        (psi against delta, weighted by k_psi and k_delta) at the curve's middle point."""
        model = build_model(self.config, self.params)
        i = len(curve.p) // 2
        V, Fz = curve.p[i]
        ev, vectors = np.linalg.eig(jacobian(model, np.zeros(model.n_states), V, Fz))
        q = vectors[:, int(np.argmin(np.abs(ev - 1j * curve.omega[i])))]
        share = torsional_share(abs(q[0]), abs(q[2]), self.params.gear.k_psi, self.params.gear.k_delta)
        return dominant_mode(share)

    @property
    def lateral_minimum(self) -> dict[str, float] | None:
        """The lowest load on a lateral Hopf curve (its located turning point, or a box edge): the
        lateral bending boundary's lowest point."""
        return self._lowest([c for c in self.curves if c.p.size and self.mode_of_curve(c) == Mode.LATERAL])

    @property
    def double_hopf_points(self) -> list[dict[str, float]]:
        """Points where a second pair of eigenvalues is on the imaginary axis (two Hopf curves
        cross there); each listed once although it lies on two curves."""
        out: list[dict[str, float]] = []
        for c in self.curves:
            for g in c.points_of(PointKind.DOUBLE_HOPF):
                entry = _double_hopf_point(g)
                if not any(abs(e["V"] - entry["V"]) <= SAME_POINT * V_SCALE
                           and abs(e["Fz"] - entry["Fz"]) <= SAME_POINT * FZ_SCALE for e in out):
                    out.append(entry)
        return out

    def to_dict(self) -> dict[str, Any]:
        curves = []
        for c in self.curves:
            lyap = [None if not math.isfinite(v) else float(v) for v in c.lyapunov]
            curves.append({
                "points": [{"V": float(p[0]), "Fz": float(p[1]), "frequency_hz": float(w / (2 * math.pi)),
                            "lyapunov": l1} for p, w, l1 in zip(c.p, c.omega, lyap, strict=True)],
                "gh_points": [_gh_point(g) for g in c.points_of(PointKind.GENERALISED_HOPF)],
                "fz_extrema": [{"V": e.p[0], "Fz": e.p[1]} for e in c.points_of(PointKind.P2_TURN)],
                "double_hopf_points": [_double_hopf_point(g) for g in c.points_of(PointKind.DOUBLE_HOPF)],
                "zero_hopf_points": [{"V": g.p[0], "Fz": g.p[1]} for g in c.points_of(PointKind.ZERO_HOPF)],
                "closed": c.closed, "stop_reasons": c.stop_reasons, "steps": c.steps})
        return {"config": self.config.value, "params": self.params.to_dict(),
                "v_range": list(self.v_range), "fz_range": list(self.fz_range), "curves": curves,
                "gh_points": self.gh_points, "double_hopf_points": self.double_hopf_points,
                "lateral_minimum": self.lateral_minimum,
                "fz_minimum": self.fz_minimum, "warnings": list(self.warnings), "elapsed_s": self.elapsed_s,
                "version": __version__}

    def summary_text(self) -> str:
        """The short table ``python -m shimmy hopf-curves`` prints
        (:func:`~shimmy.analyses.diagrams.summaries.hopf_curves_summary`)."""
        return hopf_curves_summary(self.to_dict())


def _gh_point(g) -> dict[str, float]:
    return {"V": g.p[0], "Fz": g.p[1], "frequency_hz": g.data["omega"] / (2 * math.pi)}


def _double_hopf_point(g) -> dict[str, float]:
    return {"V": g.p[0], "Fz": g.p[1], "frequency_hz": g.data["omega"] / (2 * math.pi),
            "frequency2_hz": g.data["omega2"] / (2 * math.pi)}


def gear_two_parameter_field(config: Configuration, params: Parameters) -> TwoParameterField:
    """The gear's vector field in (V, Fz), vectorised over columns, analytic derivatives."""
    model = build_model(config, params)

    def evaluate(x, p):
        f, J, dV, dFz = field_and_derivatives(model, x, p[0], p[1])
        return f, J, np.stack([dV, dFz])
    return TwoParameterField(model.n_states, lambda x, p: rhs(model, x, p[0], p[1]),
                             lambda x, p: jacobian(model, x, p[0], p[1]),
                             lambda x, p: np.stack(parameter_jacobian(model, x, p[0], p[1])),
                             f"{config.value} in (V, Fz)", evaluate, smooth=config.is_smooth, complex_columns=True)


def hopf_curves(config: Configuration | str, *, params: Parameters | None = None,
                v_range: tuple[float, float] = V_RANGE, fz_range: tuple[float, float] = FZ_RANGE,
                n_slices: int = 12, progress: Callable[[float, str], None] | None = None) -> HopfCurvesResult:
    """All Hopf curves of x = 0 that cross the box v_range x fz_range (m/s, N)."""
    clock = time.perf_counter()
    config = Configuration.parse(config)
    params = params if params is not None else Parameters()
    v_lo, v_hi = check_range("v", v_range, V_RANGE, "m/s")
    f_lo, f_hi = check_range("fz", fz_range, FZ_RANGE, "N")
    n_slices = int(check_number("n_slices", n_slices, 2, 200, integer=True))
    report = progress or (lambda fraction, message: None)
    system = gear_two_parameter_field(config, params)
    n = system.n
    box = ((v_lo, v_hi), (f_lo, f_hi))
    # max_correction: a Newton jump to another branch is refused (a loop of a corner NES design was cut).
    options = ContinuationOptions(ds=0.05, ds_max=1.0, max_steps=2000, max_correction=1.0)
    curves: list[HopfCurve] = []
    warnings: list[str] = []
    slices = np.linspace(f_lo, f_hi, n_slices)
    for k, Fz in enumerate(slices):
        report(k / n_slices, f"Hopf points at Fz = {Fz / 1e3:.4g} kN")
        for h in hopf_points(config, float(Fz), params=params, v_range=(v_lo, v_hi)).hopf_points:
            if any(_on_curve(c, h.V, float(Fz)) for c in curves):
                continue
            try:
                curve = hopf_curve(system, np.zeros(n), np.array([h.V, float(Fz)]), box=box, options=options,
                                   scale=X_SCALE[:n], p_scale=np.array([V_SCALE, FZ_SCALE]))
            except ValueError as exc:
                warnings.append(f"Hopf point V = {h.V:.6g} m/s, Fz = {kn(Fz)} not continued: {exc}")
                continue
            curves.append(curve)
    report(1.0, "done")
    return HopfCurvesResult(config, params, (v_lo, v_hi), (f_lo, f_hi), curves, time.perf_counter() - clock,
                            warnings)


def _on_curve(curve: HopfCurve, V: float, Fz: float) -> bool:
    """Whether (V, Fz) lies on a computed curve: within a fifth of the local step of its polyline
    (in the scaled metric), far above the chord error of the polyline at its step sizes."""
    scale = np.array([V_SCALE, FZ_SCALE])
    return near_polyline(curve.p / scale, np.array([V, Fz]) / scale) is not None
