"""Linear stability of straight rolling (x = 0) and its Hopf points in V.

x = 0 is an equilibrium for every (V, Fz). Its Jacobian depends on V only through
V and 1/V (the tyre kinematics V sin(theta) - (V/L) lam and the damping c_lam/V), so
at fixed Fz

    J(V) = J0 + V J1 + J2 / V

exactly. :class:`Linearisation` extracts J0, J1, J2 from three Jacobian evaluations,
checks the decomposition against a fourth and then evaluates J(V) for any number of
speeds at the cost of two matrix additions.

Hopf search (``hopf_points``): eigenvalues on a geometric grid of V; the number of
eigenvalues with positive real part is counted at each grid point. Where the count
changes, the k-th largest real part (a continuous function of V) changes sign and is
refined by Brent's method to ``v_tol`` (1e-9 m/s by default). Two crossings that
cancel inside one grid interval are caught by checking every local maximum (minimum)
of each ordered real part that lies below (above) zero by less than ``near_axis``
(1/s): a bounded 1-D optimisation decides whether it reaches across the axis. A
crossing whose eigenvalue has |Im| below 1e-6 of the spectral radius is a real
crossing (a branch point of x = 0), reported separately.

Criticality: the first Lyapunov coefficient l1 (Kuznetsov, Elements of Applied
Bifurcation Theory, 3rd ed., eq. 3.20) with q, p normalised by <q, q> = <p, q> = 1;
l1 < 0 supercritical, l1 > 0 subcritical. The multilinear forms B and C are taken
from the analytic Jacobian by complex steps (exact to rounding for B) and a central
difference of those (relative error ~ (eps/scale)^2, below 1e-6 here). With the
particle damper the vector field contains |dpsi|^(1/2) dpsi, which is C^1 but has no
second or third derivative at dpsi = 0: B and C do not exist, l1 is undefined and
the Hopf point is labelled ``nonsmooth`` instead of guessing.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from enum import Enum
from typing import Any

import numpy as np

from ...version import __version__
from ...continuation import lyapunov
from ...continuation.scalar import minimum_in, root_in
from ...model.configurations import Configuration
from ...model.equations import Model, build_model, jacobian
from ...errors import InvalidParameterError
from ...model.parameters import V_RANGE, Parameters, check_number, check_operating_point, check_pair
from .summaries import hopf_summary


class Criticality(str, Enum):
    SUPERCRITICAL = "supercritical"
    SUBCRITICAL = "subcritical"
    NONSMOOTH = "nonsmooth"
    DEGENERATE = "degenerate"


def check_speeds_and_load(v_range: Any, Fz: Any) -> tuple[float, float, float]:
    """(v_min, v_max, Fz) of a question on a speed range at one load, checked against the model's
    ranges (errors name v_min, v_max or Fz)."""
    v_min, v_max = check_pair("v_range", v_range)
    v_min, Fz = check_operating_point(v_min, Fz)
    v_max = check_number("v_max", v_max, V_RANGE[0], V_RANGE[1], "m/s")
    if not v_max > v_min:
        raise InvalidParameterError("v_max", v_max, f"a number in ({v_min:g}, {V_RANGE[1]:g}] m/s",
                                    "must exceed v_min")
    return v_min, v_max, Fz


class Linearisation:
    """J(V) = J0 + V J1 + J2 / V at x = 0 for one model and load Fz (the Jacobian evaluated as plain
    Python: four evaluations, no compiled kernel to load; bit for bit the compiled one at x = 0)."""

    def __init__(self, model: Model, Fz: float):
        self.model = model
        self.Fz = float(Fz)
        x = np.zeros((model.n_states, 4))
        probe = np.array([1.0, 2.0, 4.0, 7.0])
        J = jacobian(model, x, probe, self.Fz, plain=True)
        # Solve for J0, J1, J2 from V = 1, 2, 4; check with V = 7.
        basis = np.stack([np.ones(3), probe[:3], 1.0 / probe[:3]], axis=1)
        coeffs = np.linalg.solve(basis, J[:3].reshape(3, -1))
        self.J0, self.J1, self.J2 = (c.reshape(J.shape[1:]) for c in coeffs)
        check = self.at(probe[3])
        scale = np.abs(J[3]).max()
        if not np.allclose(check, J[3], rtol=1e-10, atol=1e-12 * scale):
            raise AssertionError("the Jacobian at x = 0 is not of the form J0 + V J1 + J2/V")

    def at(self, V):
        V = np.asarray(V, dtype=float)
        return self.J0 + V[..., None, None] * self.J1 + self.J2 / V[..., None, None]

    def eigenvalues(self, V):
        return np.linalg.eigvals(self.at(V))


@dataclass(frozen=True)
class HopfPoint:
    """A Hopf point of x = 0 in V at fixed Fz."""

    V: float
    Fz: float
    omega: float  # rad/s
    criticality: Criticality
    lyapunov: float | None  # first Lyapunov coefficient, None where undefined
    destabilising: bool  # True if x = 0 loses stability as V increases through this point
    bracket: tuple[float, float]

    @property
    def frequency_hz(self) -> float:
        return self.omega / (2.0 * math.pi)

    def to_dict(self) -> dict[str, Any]:
        return {"V": self.V, "frequency_hz": self.frequency_hz, "criticality": self.criticality.value,
                "lyapunov": self.lyapunov, "destabilising": self.destabilising,
                "bracket": list(self.bracket)}


@dataclass(frozen=True)
class HopfResult:
    """All crossings of the imaginary axis by eigenvalues of x = 0 over [v_min, v_max]."""

    config: Configuration
    Fz: float
    v_min: float
    v_max: float
    params: Parameters
    hopf_points: list[HopfPoint]
    branch_points: list[float]
    unstable_intervals: list[tuple[float, float]]
    n_grid: int
    elapsed_s: float
    success: bool = True
    message: str = "all crossings located"
    warnings: list[str] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        return {"config": self.config.value, "Fz": self.Fz, "v_min": self.v_min, "v_max": self.v_max,
                "params": self.params.to_dict(),
                "hopf_points": [h.to_dict() for h in self.hopf_points],
                "branch_points": [{"V": v} for v in self.branch_points],
                "unstable_intervals": [list(iv) for iv in self.unstable_intervals],
                "success": self.success, "message": self.message, "warnings": list(self.warnings),
                "n_grid": self.n_grid, "version": __version__}

    def summary_text(self) -> str:
        """The short table ``python -m shimmy hopf`` prints
        (:func:`~shimmy.analyses.core.summaries.hopf_summary`)."""
        return hopf_summary(self.to_dict())


def eigenvalues(config: Configuration | str, V, Fz: float, *, params: Parameters | None = None) -> np.ndarray:
    """Eigenvalues (1/s) of the Jacobian at x = 0; shape (n,) or (len(V), n), sorted by real part."""
    model = build_model(config, params)
    V_arr = np.atleast_1d(np.asarray(V, dtype=float))
    for v in V_arr:
        check_operating_point(v, Fz)
    ev = Linearisation(model, Fz).eigenvalues(V_arr)
    ev = np.take_along_axis(ev, np.argsort(-ev.real, axis=-1, kind="stable"), axis=-1)
    return ev[0] if np.ndim(V) == 0 else ev


def hopf_points(config: Configuration | str, Fz: float, *, params: Parameters | None = None,
                v_range: tuple[float, float] = V_RANGE, n_grid: int = 400,
                v_tol: float = 1e-9, near_axis: float = 1.0) -> HopfResult:
    """Locate every Hopf point of x = 0 in V in ``v_range`` = (v_min, v_max) (m/s) at load Fz (N)."""
    clock = time.perf_counter()
    config = Configuration.parse(config)
    params = params if params is not None else Parameters()
    v_min, v_max, Fz = check_speeds_and_load(v_range, Fz)
    n_grid = int(check_number("n_grid", n_grid, 10, 100_000, integer=True))
    v_tol = check_number("v_tol", v_tol, 1e-12, 1e-3, "m/s")
    near_axis = check_number("near_axis", near_axis, 0.0, 100.0, "1/s")
    model = build_model(config, params)
    lin = Linearisation(model, Fz)

    grid = np.geomspace(v_min, v_max, n_grid)
    re = _ordered_real_parts(lin, grid)
    count = (re > 0).sum(axis=1)
    roots: list[tuple[float, int, tuple[float, float]]] = []

    def ordered(k: int):
        return lambda v: _ordered_real_parts(lin, np.array([v]))[0, k]

    for i in np.nonzero(count[:-1] != count[1:])[0]:
        lo, hi = int(min(count[i], count[i + 1])), int(max(count[i], count[i + 1]))
        k = lo
        while k < hi:
            v = root_in(ordered(k), grid[i], grid[i + 1], xtol=v_tol, rtol=1e-15)
            roots.append((v, k, (grid[i], grid[i + 1])))
            k += 2 if _crossing_is_complex(lin, v) else 1  # a complex pair moves two order statistics
    # Hidden double crossings between grid points: near-axis extrema of the ordered real parts.
    mid, left, right = re[1:-1], re[:-2], re[2:]
    is_max = (mid >= left) & (mid >= right) & (mid < 0) & (mid > -near_axis)
    is_min = (mid <= left) & (mid <= right) & (mid > 0) & (mid < near_axis)
    partner = np.zeros_like(mid, dtype=bool)
    partner[:, 1:] = mid[:, 1:] == mid[:, :-1]  # second member of a complex pair: same curve
    for i, k in np.argwhere((is_max | is_min) & ~partner):
        i += 1
        sign = -1.0 if is_max[i - 1, k] else 1.0
        g = ordered(int(k))
        v_opt, g_opt = minimum_in(lambda v: sign * g(v), grid[i - 1], grid[i + 1], xatol=v_tol)
        if g_opt < 0:  # the extremum reaches across the imaginary axis
            for a, b in ((grid[i - 1], v_opt), (v_opt, grid[i + 1])):
                roots.append((root_in(g, a, b, xtol=v_tol, rtol=1e-15), int(k), (grid[i - 1], grid[i + 1])))

    hopf, branch, warnings = [], [], []
    for v, k, bracket in sorted(roots):
        if any(abs(v - h.V) < 1e3 * v_tol for h in hopf) or any(abs(v - b) < 1e3 * v_tol for b in branch):
            continue  # the pair partner of a crossing already found
        if not _crossing_is_complex(lin, v):
            branch.append(float(v))
            continue
        ev = lin.eigenvalues(np.array([v]))[0]
        omega = abs(ev[np.argmin(np.abs(ev.real))].imag)
        dv = 1e-4 * max(v, 1.0)
        destabilising = ordered(k)(min(v + dv, bracket[1])) > ordered(k)(max(v - dv, bracket[0]))
        l1, criticality = _criticality(model, v, Fz, warnings)
        hopf.append(HopfPoint(float(v), Fz, float(omega), criticality, l1, bool(destabilising), bracket))

    intervals = _unstable_intervals([h.V for h in hopf] + branch, v_min, v_max, lin)
    return HopfResult(config, Fz, v_min, v_max, params, hopf, branch, intervals, n_grid,
                      time.perf_counter() - clock, warnings=warnings)


def _crossing_is_complex(lin: Linearisation, V: float) -> bool:
    ev = lin.eigenvalues(np.array([V]))[0]
    crit = ev[np.argmin(np.abs(ev.real))]
    return bool(abs(crit.imag) > 1e-6 * np.abs(ev).max())


def _ordered_real_parts(lin: Linearisation, V: np.ndarray) -> np.ndarray:
    return -np.sort(-lin.eigenvalues(V).real, axis=1)


def _unstable_intervals(crossings, v_min, v_max, lin) -> list[tuple[float, float]]:
    """Maximal V intervals between crossings where x = 0 has an eigenvalue with Re > 0."""
    edges = sorted([v_min, *crossings, v_max])
    out: list[tuple[float, float]] = []
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        if b - a <= 0:
            continue
        mid = math.sqrt(a * b)
        if _ordered_real_parts(lin, np.array([mid]))[0, 0] > 0:
            if out and abs(out[-1][1] - a) < 1e-12:
                out[-1] = (out[-1][0], b)
            else:
                out.append((a, b))
    return out


def _criticality(model: Model, V: float, Fz: float, warnings: list[str]):
    if not model.config.is_smooth:
        return None, Criticality.NONSMOOTH
    l1 = first_lyapunov_coefficient(model, V, Fz)
    # The central difference in C has error O(eps^2): comparing eps with 2 eps bounds it.
    uncertainty = abs(first_lyapunov_coefficient(model, V, Fz, eps=2e-4) - l1)
    if not np.isfinite(l1) or abs(l1) <= 10.0 * uncertainty:
        warnings.append(f"first Lyapunov coefficient {l1:.3g} at V={V:.6g} m/s is zero within its "
                        f"numerical error {uncertainty:.1g}: degenerate (generalised Hopf) point")
        return float(l1), Criticality.DEGENERATE
    return float(l1), Criticality.SUPERCRITICAL if l1 < 0 else Criticality.SUBCRITICAL


def first_lyapunov_coefficient(model: Model, V: float, Fz: float, eps: float = 1e-4,
                               omega_hint: float | None = None) -> float:
    """l1 of x = 0 at a Hopf point (V, Fz) of a smooth configuration; < 0 is supercritical (the
    Jacobian evaluated as plain Python, a dozen evaluations: see :func:`~shimmy.model.equations.jacobian`).
    ``omega_hint``: the pair nearest i omega_hint (:func:`shimmy.continuation.first_lyapunov_coefficient`)."""
    return lyapunov.first_lyapunov_coefficient(lambda x: jacobian(model, x, V, Fz, plain=True), model.n_states,
                                               eps=eps, omega_hint=omega_hint)


def growth_rates(Fz: float, *, params: Parameters | None = None, v_range: tuple[float, float] = V_RANGE,
                 n_points: int = 200) -> dict[str, Any]:
    """Straight rolling's leading eigenvalue against V on a geometric grid of ``n_points`` speeds in
    ``v_range`` (m/s), with the Hopf points and unstable intervals, for every configuration:
    ``{"V": [...], "configs": {name: {"max_real" (1/s), "frequency_hz", "hopf_points", "unstable_intervals"}}}``
    (each configuration's part is :func:`growth_rate`'s)."""
    params = params or Parameters()
    v_min, v_max, Fz = check_speeds_and_load(v_range, Fz)
    n_points = int(check_number("n_points", n_points, 10, 2000, integer=True))
    return {"V": growth_speeds((v_min, v_max), n_points).tolist(),
            "configs": {c.value: growth_rate(c, Fz, params=params, v_range=(v_min, v_max), n_points=n_points)
                        for c in Configuration}}


def growth_speeds(v_range: tuple[float, float], n_points: int) -> np.ndarray:
    """The speeds (m/s) :func:`growth_rate` evaluates: ``n_points`` on a geometric grid over ``v_range``."""
    return np.geomspace(float(v_range[0]), float(v_range[1]), int(n_points))


def growth_rate(config: Configuration | str, Fz: float, *, params: Parameters | None = None,
                v_range: tuple[float, float] = V_RANGE, n_points: int = 200) -> dict[str, Any]:
    """One configuration's part of :func:`growth_rates`: ``{"max_real" (1/s), "frequency_hz"}`` of the
    leading eigenvalue at :func:`growth_speeds`, and its ``hopf_points`` and ``unstable_intervals``. It
    depends on the design only through the configuration's model (a cache may key it so)."""
    config = Configuration.parse(config)
    params = params or Parameters()
    v_min, v_max, Fz = check_speeds_and_load(v_range, Fz)
    n_points = int(check_number("n_points", n_points, 10, 2000, integer=True))
    V = growth_speeds((v_min, v_max), n_points)
    lin = Linearisation(build_model(config, params), Fz)
    ev = lin.eigenvalues(V)
    k = np.argmax(ev.real, axis=1)
    lead = ev[np.arange(V.size), k]
    # A coarse grid suffices: the near-axis extremum scan catches pairs between grid points
    # (tests/analyses/core/test_stability.py: 12 points find what 20 000 do); 1e-7 m/s is far below display.
    h = hopf_points(config, Fz, params=params, v_range=(v_min, v_max), n_grid=80, v_tol=1e-7)
    return {"max_real": lead.real.tolist(), "frequency_hz": (np.abs(lead.imag) / (2 * np.pi)).tolist(),
            "hopf_points": [p.to_dict() for p in h.hopf_points],
            "unstable_intervals": [list(iv) for iv in h.unstable_intervals]}
