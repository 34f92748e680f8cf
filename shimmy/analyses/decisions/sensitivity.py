"""Sensitivities of the shimmy boundaries to every parameter, by implicit differentiation.

At a load Fz, a Hopf point of straight rolling (x = 0, an equilibrium for every parameter set) is a
speed V* where a simple eigenvalue lambda(V, Fz, theta) of the Jacobian J has zero real part.
With q the right and w the left eigenvector (w^H J = lambda w^H),

    d lambda / d s = w^H (dJ/ds) q / (w^H q)          (s = V, Fz or a parameter theta),

and the implicit function theorem on Re lambda(V*(theta), theta) = 0 gives

    dV*/dtheta = -Re(d lambda/d theta) / Re(d lambda/dV),
    d omega/d theta = Im(d lambda/d theta) + Im(d lambda/dV) dV*/dtheta.

Nothing is re-solved per parameter: one eigen-decomposition per Hopf point, and dJ/dtheta for all
parameters from central differences of the model's coefficients (the Jacobian at x = 0 is a
rational function of them; relative step 1e-5 of the parameter, truncation error ~1e-10,
rounding ~1e-11 of J).

The minimum shimmy load on the Hopf curves is the lowest point (V_m, Fz_m) of Re lambda = 0 in the
(V, Fz) plane, where also d Re lambda / dV = 0; by the envelope theorem

    dFz_m/dtheta = -Re(d lambda/d theta) / Re(d lambda/dFz)   at (V_m, Fz_m).

The point is taken from the continued Hopf curves (:func:`shimmy.analyses.diagrams.hopf_curves.hopf_curves`)
and polished by Newton's method on (Re lambda, d Re lambda/dV) = 0 (to 1e-10 of the scales, or the
rounding level of its finite-difference Jacobian) so the formula is applied at a true minimum.
Where the lowest point is the end of a curve on a speed edge of the box, the corner moves along
that edge: dFz/dtheta is the same formula at (V_edge, Fz); on the lowest load edge there is no
derivative (the figure is the edge).

The largest stable torsional amplitude at the load, A = max_t |psi(t)| of the stable cycle where
it is largest along the branch (an interior maximum in V, or at the end of the speed range):
with G(u; theta) = 0 the collocation equations of that orbit at fixed V (u = node values and
period), du/dtheta = -G_u^-1 G_theta (one sparse factorisation; G_theta by central differences of
the residual in the coefficients), and dA/dtheta = sign(psi(t*)) dpsi(t*)/dtheta at the instant t*
of the maximum, located on the collocation polynomial (envelope in V and in t). Where the largest
stable amplitude sits where the stable part of the branch ends (a fold or torus point) the
fixed-speed derivative does not apply and none is given.

Parameters that cannot move a quantity are reported with the reason: not fitted in the
configuration; not in the equations (a geometry record); or, for the particle damper's material
and packing (a_p, rho_p, ...), entering only the damper torque n r^2 c*(r |dpsi|) dpsi, whose
slope is zero at rest, so they leave the linearisation at x = 0, and with it every Hopf speed,
unchanged.
"""

from __future__ import annotations

import copy
import math
import time
from dataclasses import dataclass, field
from types import SimpleNamespace
from typing import Any, Sequence

import numpy as np
import scipy.linalg
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ...version import __version__
from ...continuation import ContinuationOptions, PointKind, correct
from ...continuation.collocation import Mesh, PeriodicProblem
from ...errors import ConvergenceError, InvalidParameterError
from ...model.configurations import Configuration, affects
from ...model.equations import Model, build_model, jacobian, model_coefficients
from ...model.parameters import DIAGRAM_V_RANGE, FZ_RANGE, PARAMETER_SPECS, Parameters, check_number, unknown_name_error
from ...model.units import kn
from ..diagrams.bifurcation import STATE_SCALE, T_SCALE, V_SCALE, BifurcationOptions, bifurcation, gear_field
from .design_space import DESIGN_PARAMETERS
from .summaries import sensitivity_summary
from ..core.stability import Linearisation, hopf_points

#: Relative step of the central differences in the parameters.
REL_STEP = 1e-5
V_BAND = DIAGRAM_V_RANGE  # m/s: the map's speed range

NOT_FITTED = "not fitted in this configuration"
NOT_IN_EQUATIONS = "not in the equations of motion (a geometry record)"
ZERO_SLOPE = ("enters only the particle damper's torque n r^2 c*(r |dpsi|) dpsi, whose slope is zero at rest: "
              "no effect on the linearisation of straight rolling")
NO_LINEAR_EFFECT = "does not enter the linearisation of straight rolling"


def design_with(params: Parameters, name: str, value: float) -> Any:
    """An object with params' groups and one value changed, without range checks (a central
    difference at a range end steps 1e-5 outside it, a continuation in the parameter locates the
    range's ends by stepping just past them; the model is smooth there)."""
    spec = PARAMETER_SPECS[name]
    group = copy.copy(getattr(params, spec.group))
    object.__setattr__(group, name, float(value))
    groups = {g: getattr(params, g) for g in ("gear", "nes", "pd")}
    groups[spec.group] = group
    return SimpleNamespace(**groups)


def model_with(config: Configuration, params: Parameters, name: str, value: float) -> Model:
    """The model of ``config`` at ``params`` with one parameter's value changed (:func:`design_with`)."""
    return Model(config, params, model_coefficients(config, design_with(params, name, value)))


def parameter_step(params: Parameters, name: str) -> float:
    """The central-difference step of parameter ``name``: REL_STEP of its value (of its range if 0)."""
    spec = PARAMETER_SPECS[name]
    value = float(getattr(params, name))
    return REL_STEP * (abs(value) if value != 0.0 else (spec.high - spec.low))


def coefficient_pairs(config: Configuration, params: Parameters, names: Sequence[str]) -> dict[str, tuple]:
    """{name: (coefficients at theta + h, at theta - h, h)} for every parameter in ``names``."""
    out = {}
    for name in names:
        h = parameter_step(params, name)
        value = float(getattr(params, name))
        out[name] = (model_coefficients(config, design_with(params, name, value + h)),
                     model_coefficients(config, design_with(params, name, value - h)), h)
    return out


def _model(model: Model, coefficients: np.ndarray) -> Model:
    return Model(model.config, model.params, coefficients, model.exact_nes)


@dataclass(frozen=True)
class EigenPair:
    """A simple eigenvalue of a Jacobian with its right (q) and left (w) eigenvectors."""

    lam: complex
    q: np.ndarray
    w: np.ndarray  # left eigenvector scaled so that w^H q = 1

    def derivative(self, dJ: np.ndarray) -> complex:
        """d lambda for the change dJ of the Jacobian: w^H dJ q."""
        return complex(np.conj(self.w) @ dJ @ self.q)


def critical_pair(J: np.ndarray, omega_hint: float | None = None) -> EigenPair:
    """The eigenvalue with Im > 0 nearest the imaginary axis (nearest to i omega_hint if given)."""
    ev, vl, vr = scipy.linalg.eig(J, left=True, right=True)
    if omega_hint is None:
        score = np.abs(ev.real) + np.where(ev.imag > 0, 0.0, np.inf)
    else:
        score = np.abs(ev - 1j * omega_hint)
    i = int(np.argmin(score))
    q, w = vr[:, i], vl[:, i]
    w = w / np.conj(np.conj(w) @ q)
    return EigenPair(complex(ev[i]), q, w)


def _dJ_dFz(model: Model, V: float, Fz: float) -> np.ndarray:
    h = 1e-6 * Fz  # J at x = 0 is affine in Fz: exact to rounding
    x = np.zeros(model.n_states)
    return (jacobian(model, x, V, Fz + h) - jacobian(model, x, V, Fz - h)) / (2.0 * h)


def _dJ_dV(lin: Linearisation, V: float) -> np.ndarray:
    return lin.J1 - lin.J2 / (V * V)


def jacobian_derivatives(model: Model, V: float, Fz: float, pairs: dict[str, tuple]) -> dict[str, np.ndarray]:
    """{name: dJ/dtheta at x = 0, (V, Fz)} from the coefficient pairs."""
    x = np.zeros(model.n_states)
    return {name: (jacobian(_model(model, cp), x, V, Fz) - jacobian(_model(model, cm), x, V, Fz)) / (2.0 * h)
            for name, (cp, cm, h) in pairs.items()}


def _reason(name: str, config: Configuration, exact_zero: bool, quantity: str) -> str | None:
    """Why parameter ``name`` has no effect on ``quantity`` ("hopf" or "amplitude"), or None."""
    if not affects(name, config):
        return NOT_FITTED
    if not exact_zero:
        return None
    if name == "H":
        return NOT_IN_EQUATIONS
    if PARAMETER_SPECS[name].group == "pd" and quantity == "hopf":
        return ZERO_SLOPE
    return NO_LINEAR_EFFECT if quantity == "hopf" else "does not enter the equations of this configuration"


@dataclass
class SensitivityResult:
    """Derivatives of the boundaries at one load, per parameter, with scaled views."""

    config: Configuration
    Fz: float
    params: Parameters
    names: list[str]
    hopf: list[dict[str, Any]]  # {"V", "frequency_hz", "dV_dp", "domega_dp", "destabilising"}
    min_shimmy: dict[str, Any] | None  # {"Fz", "V", "dFz_dp", "source"}
    max_psi: dict[str, Any] | None  # {"value", "V", "dA_dp"} or {"value", "V", "dA_dp": None, "reason"}
    no_effect: dict[str, dict[str, str]]  # {quantity kind: {name: reason}}
    elapsed_s: dict[str, float] = field(default_factory=dict)

    def quantities(self) -> list[dict[str, Any]]:
        """Every differentiated quantity: key, label, unit, value and {name: derivative}."""
        out = []
        for k, h in enumerate(self.hopf):
            out.append({"key": f"hopf_V{k + 1}", "label": f"Hopf speed {k + 1} at {self.Fz / 1e3:g} kN",
                        "unit": "m/s", "value": h["V"], "derivatives": h["dV_dp"], "kind": "hopf"})
        if len(self.hopf) == 2:
            d = {n: self.hopf[1]["dV_dp"][n] - self.hopf[0]["dV_dp"][n] for n in self.names}
            out.append({"key": "hopf_interval", "label": f"Hopf interval width at {self.Fz / 1e3:g} kN",
                        "unit": "m/s", "value": self.hopf[1]["V"] - self.hopf[0]["V"], "derivatives": d,
                        "kind": "hopf"})
        if self.min_shimmy is not None and self.min_shimmy["dFz_dp"] is not None:
            out.append({"key": "min_shimmy_Fz", "label": "minimum shimmy load (lowest point of the Hopf curves)",
                        "unit": "N", "value": self.min_shimmy["Fz"], "derivatives": self.min_shimmy["dFz_dp"],
                        "kind": "hopf"})
        if self.max_psi is not None and self.max_psi.get("dA_dp") is not None:
            out.append({"key": "max_psi", "label": f"largest stable torsional amplitude at {self.Fz / 1e3:g} kN",
                        "unit": "rad", "value": self.max_psi["value"], "derivatives": self.max_psi["dA_dp"],
                        "kind": "amplitude"})
        return out

    def scaled(self, derivatives: dict[str, float]) -> dict[str, dict[str, float]]:
        """{name: {"per_percent", "per_half_range"}}: the change for +1 % of the parameter's value
        (None where the value is 0) and for half its design range (linear)."""
        out = {}
        for name, d in derivatives.items():
            spec = PARAMETER_SPECS[name]
            value = float(getattr(self.params, name))
            out[name] = {"per_percent": d * 0.01 * value if value != 0.0 else None,  # no relative change of 0
                         "per_half_range": d * 0.5 * (spec.high - spec.low)}
        return out

    def tornado(self, key: str, by: str = "per_percent") -> list[dict[str, Any]]:
        """Rows {name, unit, value, low, high, derivative, per_percent, per_half_range, reason} of one
        quantity, largest effect first; parameters without effect last, with their reason."""
        q = next((q for q in self.quantities() if q["key"] == key), None)
        if q is None:
            raise InvalidParameterError("quantity", key, "one of " + ", ".join(x["key"] for x in self.quantities()))
        scaled = self.scaled(q["derivatives"])
        reasons = self.no_effect.get(q["kind"], {})
        rows = []
        for name in self.names:
            spec = PARAMETER_SPECS[name]
            value = float(getattr(self.params, name))
            rows.append({"name": name, "unit": spec.unit, "group": spec.group, "value": value,
                         "low": spec.low, "high": spec.high, "derivative": q["derivatives"][name],
                         **scaled[name], "reason": reasons.get(name), "device": name in DESIGN_PARAMETERS})
        rows.sort(key=lambda r: (r["reason"] is not None, -abs(r[by] or 0.0)))
        return rows

    def to_dict(self) -> dict[str, Any]:
        quantities = []
        for q in self.quantities():
            quantities.append({k: q[k] for k in ("key", "label", "unit", "value")}
                              | {"rows": self.tornado(q["key"])})
        return {"config": self.config.value, "Fz": self.Fz, "params": self.params.to_dict(), "names": self.names,
                "hopf_points": self.hopf, "min_shimmy_Fz": self.min_shimmy, "max_psi": self.max_psi,
                "no_effect": self.no_effect, "quantities": quantities, "elapsed_s": self.elapsed_s,
                "methods": {
                    "hopf_points": "implicit differentiation of Re lambda = 0 at each Hopf point (left and right "
                                   "eigenvectors; dJ/dtheta by central differences of the model coefficients, "
                                   f"relative step {REL_STEP:g})",
                    "min_shimmy_Fz": "envelope theorem at the lowest point of the Hopf curves (continued, then "
                                     "polished by Newton on Re lambda = d Re lambda/dV = 0)",
                    "max_psi": "implicit differentiation of the collocation equations of the largest stable cycle "
                               "at fixed speed (envelope in V and t)"},
                "version": __version__}

    def summary_text(self, top: int = 8) -> str:
        """The tables ``python -m shimmy sensitivity`` prints: per quantity its ``top`` largest effects
        (:func:`~shimmy.analyses.decisions.summaries.sensitivity_summary`)."""
        return sensitivity_summary(self.to_dict(), top)


def _check_names(names: Sequence[str] | None) -> list[str]:
    if names is None:
        return list(PARAMETER_SPECS)
    out = []
    for name in names:
        if name not in PARAMETER_SPECS:
            raise unknown_name_error(name, PARAMETER_SPECS)
        if name not in out:
            out.append(name)
    if not out:
        raise InvalidParameterError("params", list(names), "one or more parameter names")
    return out


def hopf_sensitivities(model: Model, Fz: float, hopf_V: Sequence[float], pairs: dict[str, tuple]) -> list[dict]:
    """For each Hopf speed at Fz: dV/dtheta and domega/dtheta for every parameter in ``pairs``."""
    lin = Linearisation(model, Fz)
    out = []
    for V in hopf_V:
        eig = critical_pair(lin.at(V))
        dlam_dV = eig.derivative(_dJ_dV(lin, V))
        if abs(dlam_dV.real) < 1e-14:
            raise ConvergenceError(f"the Hopf point at V = {V:.6g} m/s, Fz = {Fz:.6g} N is degenerate "
                                   "(d Re lambda / dV = 0): its speed is not differentiable")
        dJ = jacobian_derivatives(model, V, Fz, pairs)
        dV, dw = {}, {}
        for name, d in dJ.items():
            dlam = eig.derivative(d)
            dV[name] = -dlam.real / dlam_dV.real
            dw[name] = dlam.imag + dlam_dV.imag * dV[name]
        out.append({"V": float(V), "frequency_hz": eig.lam.imag / (2 * math.pi), "dV_dp": dV,
                    "domega_dp": dw, "exact_zero": {n: bool(np.all(d == 0.0)) for n, d in dJ.items()},
                    "crossing_rate": dlam_dV.real})
    return out


def newton_in_plane(g, z0, scale, tol: float, what: str, max_steps: int = 30,
                    stop_diverging: bool = False) -> np.ndarray:
    """A zero z = (V, Fz) of the two equations ``g(V, Fz)`` near ``z0``, by Newton's method with a
    central-difference Jacobian (step 1e-6 of ``scale``): converged when a step is below ``tol`` of the
    scales, or when steps stop shrinking below 1e-8 of them (the rounding level of the
    finite-difference Jacobian); ConvergenceError naming ``what`` otherwise (or on a singular
    Jacobian, or a value that is not finite). ``stop_diverging``: give up as soon as a step longer
    than the scales doubles (a caller that halves its continuation step instead)."""
    z = np.array(z0, float)
    scale = np.asarray(scale, float)
    last = math.inf
    why = f"did not converge in {max_steps} Newton steps"
    for _ in range(max_steps):
        r = np.asarray(g(*z), float)
        if not np.all(np.isfinite(r)):
            why = f"gave a value that is not finite at V = {z[0]:.6g} m/s, Fz = {kn(z[1])}"
            break
        D = np.empty((2, 2))
        for k in range(2):
            e = np.zeros(2)
            e[k] = 1e-6 * scale[k]
            D[:, k] = (np.asarray(g(*(z + e)), float) - np.asarray(g(*(z - e)), float)) / (2 * e[k])
        try:
            dz = -np.linalg.solve(D, r)
        except np.linalg.LinAlgError:
            raise ConvergenceError(f"{what}: singular Newton matrix at V = {z[0]:.6g} m/s, Fz = {z[1]:.6g} N") from None
        if not np.all(np.isfinite(dz)):
            why = "took a step that is not finite"
            break
        z = z + dz
        size = float(np.max(np.abs(dz) / scale))
        if stop_diverging and size > 1.0 and size > 2.0 * last:  # diverging: no point in the remaining steps
            why = f"diverged (steps of {last:.2g} then {size:.2g} of the scales)"
            break
        if size < tol or (size < 1e-8 and size >= 0.5 * last):
            g(*z)  # the caller's state (e.g. the followed frequency) at the solution
            return z
        last = size
    raise ConvergenceError(f"{what} near V = {z0[0]:.6g} m/s, Fz = {z0[1]:.6g} N {why}")


def polish_lowest_point(model: Model, V: float, Fz: float, tol: float = 1e-10) -> tuple[float, float, float]:
    """(V, Fz, omega) of the turning point Re lambda = d Re lambda/dV = 0 near (V, Fz), by Newton with
    a finite-difference Jacobian (scales 10 m/s and 1e5 N; :func:`newton_in_plane`)."""
    omega = None

    def g(v, f):
        nonlocal omega
        lin = Linearisation(model, f)
        eig = critical_pair(lin.at(v), omega)
        omega = eig.lam.imag
        return np.array([eig.lam.real, V_SCALE * eig.derivative(_dJ_dV(lin, v)).real])

    z = newton_in_plane(g, (V, Fz), (V_SCALE, 1e5), tol, "the lowest point of the Hopf curve")
    return float(z[0]), float(z[1]), float(omega)


def min_shimmy_sensitivity(model: Model, pairs: dict[str, tuple], fz_box: tuple[float, float],
                           hopf=None) -> dict[str, Any] | None:
    """dFz/dtheta of the lowest point of the Hopf curves (None without Hopf curves)."""
    from ..diagrams.hopf_curves import hopf_curves

    hopf = hopf or hopf_curves(model.config, params=model.params, v_range=V_BAND, fz_range=fz_box)
    low = hopf.fz_minimum
    if low is None:
        return None
    turning = any(abs(e.p[1] - low["Fz"]) <= 1e-9 * low["Fz"] for c in hopf.curves
                  for e in c.points_of(PointKind.P2_TURN))
    if turning:
        V, Fz, omega = polish_lowest_point(model, low["V"], low["Fz"])
        source = "lowest point of the Hopf curves"
    elif abs(low["Fz"] - hopf.fz_range[0]) <= 1e-9 * low["Fz"]:
        return {"Fz": low["Fz"], "V": low["V"], "dFz_dp": None, "source": "load edge",
                "reason": f"the Hopf curves reach the lowest load of the box ({kn(hopf.fz_range[0])}): the minimum "
                          "shimmy load is that edge, not a point that moves with the parameters"}
    elif min(abs(low["V"] - edge) for edge in hopf.v_range) <= 1e-9 * max(hopf.v_range):
        # an end of a curve on a speed edge: the corner moves along the edge
        V = min(hopf.v_range, key=lambda edge: abs(edge - low["V"]))
        Fz, omega = _hopf_load_at(model, V, low["Fz"], 2 * math.pi * low["frequency_hz"])
        source = f"end of a Hopf curve on the speed edge V = {V:g} m/s"
    else:
        reasons = "; ".join(r for c in hopf.curves for r in c.stop_reasons)
        return {"Fz": low["Fz"], "V": low["V"], "dFz_dp": None, "source": "end of a Hopf curve inside the box",
                "reason": f"the lowest point is where a Hopf curve stopped inside the box ({reasons}): not a turning "
                          "point, no derivative"}
    lin = Linearisation(model, Fz)
    eig = critical_pair(lin.at(V), omega)
    dlam_dFz = eig.derivative(_dJ_dFz(model, V, Fz))
    dJ = jacobian_derivatives(model, V, Fz, pairs)
    return {"Fz": Fz, "V": V, "frequency_hz": omega / (2 * math.pi),
            "dFz_dp": {n: -eig.derivative(d).real / dlam_dFz.real for n, d in dJ.items()}, "source": source}


def _hopf_load_at(model: Model, V: float, Fz: float, omega: float, tol: float = 1e-10) -> tuple[float, float]:
    """(Fz, omega) with Re lambda(V, Fz) = 0 near Fz, by Newton with the exact d lambda/dFz."""
    for _ in range(30):
        eig = critical_pair(Linearisation(model, Fz).at(V), omega)
        omega = eig.lam.imag
        step = -eig.lam.real / eig.derivative(_dJ_dFz(model, V, Fz)).real
        Fz += step
        if abs(step) <= tol * Fz:
            return Fz, critical_pair(Linearisation(model, Fz).at(V), omega).lam.imag
    raise ConvergenceError(f"the Hopf load at V = {V:.6g} m/s near Fz = {Fz:.6g} N did not converge in 30 Newton "
                           "steps")


def _orbit_at(result, V: float, amplitude: float):
    """(raw branch, index) of the stable computed cycle of ``result`` nearest to (V, amplitude)."""
    best = None
    for b in result.branches:
        raw = b.raw
        if b.kind != "periodic" or raw is None or raw.p.size == 0:
            continue
        amp = np.maximum(np.abs(raw.x_max[:, 0]), np.abs(raw.x_min[:, 0]))
        d = np.abs(raw.p - V) / V_SCALE + np.abs(amp - amplitude) / STATE_SCALE[0] + np.where(raw.stable, 0, np.inf)
        i = int(np.argmin(d))
        if np.isfinite(d[i]) and (best is None or d[i] < best[0]):
            best = (float(d[i]), raw, i)
    if best is None:
        return None
    _, raw, i = best
    return raw, i


def amplitude_sensitivity(model: Model, Fz: float, pairs: dict[str, tuple], v_range=V_BAND,
                          result=None) -> dict[str, Any]:
    """dA/dtheta of the largest stable torsional amplitude at Fz (one diagram, one factorisation)."""
    result = result or bifurcation(model.config, Fz, v_range=(v_range[0], v_range[1]), params=model.params,
                                   options=BifurcationOptions(mesh_check=False))
    A, V = float(result.max_psi), result.max_psi_V
    if V is None or A <= 0.0:
        return {"value": 0.0, "V": None, "dA_dp": None, "reason": "no stable limit cycle at this load"}
    found = _orbit_at(result, V, A)
    if found is None:
        return {"value": A, "V": V, "dA_dp": None, "reason": "the largest stable cycle was not found on a branch"}
    raw, i = found
    # The branch points bracketing the maximum's speed: both stable for an interior maximum.
    j = i - 1 if i > 0 and (i == raw.p.size - 1 or (raw.p[i - 1] - V) * (raw.p[i] - V) <= 0) else i
    interior = 0 <= j < raw.p.size - 1 and bool(raw.stable[j]) and bool(raw.stable[j + 1]) \
        and 0 < i < raw.p.size - 1
    at_edge = abs(V - v_range[0]) <= 1e-9 * V_SCALE or abs(V - v_range[1]) <= 1e-9 * V_SCALE
    if not (interior or at_edge):
        return {"value": A, "V": V, "dA_dp": None,
                "reason": f"the largest stable amplitude is where the stable part of the branch ends (near V = "
                          f"{V:.4g} m/s, a fold or torus point): the fixed-speed derivative does not apply"}
    system = gear_field(model, Fz)
    mesh_points, u = raw.solutions[i]
    scale = STATE_SCALE[:model.n_states]
    problem = PeriodicProblem(system, Mesh(mesh_points, raw.ncol), scale, T_SCALE, V_SCALE)
    problem.accept(u)
    u = u.copy()
    u[-1] = V
    e_V = np.zeros(u.size)
    e_V[-1] = 1.0
    options = ContinuationOptions(tol=1e-10, residual_tol=1e-9, max_newton=12)
    for _ in range(3):  # the phase condition's reference moves with the orbit: correct, accept, repeat
        out = correct(problem, u, e_V / math.sqrt(problem.weights[-1]), options)
        if out is None:
            return {"value": A, "V": V, "dA_dp": None,
                    "reason": f"the cycle at V = {V:.6g} m/s did not converge at fixed speed"}
        u = out[0]
        problem.accept(u)
    tau_peak, sign, A_here = problem.peak(u, 0)
    matrix = sp.vstack([problem.jacobian(u), sp.csr_matrix(e_V)]).tocsc()
    lu = spla.splu(matrix)
    derivatives = {}
    exact_zero = {}
    for name, (cp, cm, h) in pairs.items():
        rp = PeriodicProblem(gear_field(_model(model, cp), Fz), problem.mesh, scale, T_SCALE, V_SCALE)
        rm = PeriodicProblem(gear_field(_model(model, cm), Fz), problem.mesh, scale, T_SCALE, V_SCALE)
        for q in (rp, rm):
            q.reference_values, q.reference_derivative = problem.reference_values, problem.reference_derivative
        G = (rp.residual(u) - rm.residual(u)) / (2.0 * h)
        exact_zero[name] = bool(np.all(G == 0.0))
        du = lu.solve(-np.append(G, 0.0))
        dX = du[:problem.n_x].reshape(problem.mesh.n_nodes, model.n_states)
        derivatives[name] = sign * float(problem.evaluate(dX, np.array([tau_peak]))[0, 0])  # envelope in t
    return {"value": A_here, "V": V, "dA_dp": derivatives, "exact_zero": exact_zero,
            "where": "interior maximum" if interior else "end of the speed range"}


def sensitivity(config: Configuration | str, Fz: float, *, params: Parameters | None = None,
                names: Sequence[str] | None = None, amplitude: bool = True, min_shimmy: bool = True,
                fz_box: tuple[float, float] = (1.0e4, 9.0e5), v_range: tuple[float, float] = V_BAND,
                hopf_curves_result=None, bifurcation_result=None) -> SensitivityResult:
    """Derivatives of the Hopf speeds at ``Fz`` (N), of the minimum shimmy load and of the largest stable
    torsional amplitude at ``Fz``, with respect to every parameter in ``names`` (default: all)."""
    config = Configuration.parse(config)
    params = params if params is not None else Parameters()
    Fz = check_number("Fz", Fz, *FZ_RANGE, "N")
    names = _check_names(names)
    model = build_model(config, params)
    timings = {}
    clock = time.perf_counter()
    pairs = coefficient_pairs(config, params, names)
    hp = hopf_points(config, Fz, params=params, v_range=(v_range[0], v_range[1]))
    hopf = hopf_sensitivities(model, Fz, [h.V for h in hp.hopf_points], pairs)
    for h, p in zip(hopf, hp.hopf_points, strict=True):
        h["destabilising"] = p.destabilising
        h["criticality"] = p.criticality.value
    timings["hopf_points"] = time.perf_counter() - clock
    hopf_zero = {n: all(h["exact_zero"][n] for h in hopf) for n in names}
    no_effect: dict[str, dict[str, str]] = {"hopf": {}, "amplitude": {}}
    low = None
    if min_shimmy:
        clock = time.perf_counter()
        low = min_shimmy_sensitivity(model, pairs, fz_box, hopf_curves_result)
        timings["min_shimmy_Fz"] = time.perf_counter() - clock
    if hopf or low is not None:
        V0 = hopf[0]["V"] if hopf else low["V"]
        J0 = jacobian_derivatives(model, V0, Fz, pairs)
        for n in names:
            reason = _reason(n, config, hopf_zero[n] if hopf else bool(np.all(J0[n] == 0.0)), "hopf")
            if reason:
                no_effect["hopf"][n] = reason
    for h in hopf:
        h.pop("exact_zero")
    amp = None
    if amplitude:
        clock = time.perf_counter()
        amp = amplitude_sensitivity(model, Fz, pairs, v_range, bifurcation_result)
        timings["max_psi"] = time.perf_counter() - clock
        zero = amp.pop("exact_zero", None)
        for n in names:
            if zero is not None or not affects(n, config):
                reason = _reason(n, config, bool(zero and zero[n]), "amplitude")
                if reason:
                    no_effect["amplitude"][n] = reason
    return SensitivityResult(config, Fz, params, names, hopf, low, amp, no_effect, timings)
