"""One-parameter bifurcation diagrams of the landing gear in the forward speed V.

``bifurcation(config, Fz, params=..., v_range=(v_min, v_max))`` computes

1. the straight-rolling equilibrium x = 0 continued in V by the generic engine
   (:func:`shimmy.continuation.equilibrium_branch`), with its stability and Hopf points;
   the Hopf points are cross-checked against the independent eigenvalue scan of
   :func:`shimmy.analyses.core.stability.hopf_points` (which also gives their criticality);
2. every periodic branch born at those Hopf points (orthogonal collocation,
   :mod:`shimmy.continuation.periodic_orbits`), followed until it ends at another Hopf point, leaves
   [v_min, v_max], or meets a stop rule; a branch that reaches another Hopf point
   accounts for that one too;
3. branches not born at a Hopf point inside the range (e.g. the lateral limit cycle at
   high load, where x = 0 is unstable over the whole range): time simulations at the
   ends and middle of every unstable interval of x = 0; a settled periodic motion not
   lying on a branch already found seeds a new branch, continued both ways.

Mode of each periodic point: the torsional share of elastic energy, k_psi psi_amp^2
against k_delta delta_amp^2 (psi_amp, delta_amp = half the peak-to-peak of psi and
delta over the orbit): torsional >= 0.8, lateral <= 0.2, both in between
(:func:`shimmy.analyses.core.response.mode_of`, the thresholds of the simulation's response type).

The particle damper's |dpsi|^(1/2) dpsi is used exactly: it is C^1 (its slope is zero
at dpsi = 0), which is all Newton's method and the Floquet multipliers (first
derivatives) need. No smoothing is applied. The collocation error is then limited by
the reduced smoothness at the two instants per period where dpsi = 0; the diagram
reports the change of the maximum torsional amplitude under mesh doubling
(``mesh_check``), the figure that shows the result does not depend on the mesh.

``max_psi`` is the largest torsional amplitude of a *stable* limit cycle (what the
gear would show), refined by a bounded 1-D search along the branch, each orbit's maximum located on
its collocation polynomial (:meth:`PeriodicProblem.peak`); ``max_psi_any``
includes unstable cycles.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace, field
from typing import Any, Callable

import numpy as np

from ...version import __version__
from ...continuation.errors import ConvergenceError as EngineConvergenceError
from ...continuation.collocation import Mesh, PeriodicProblem
from ...continuation.scalar import minimum_in
from ...model.configurations import Configuration
from ...continuation import (ContinuationOptions, CurvePoint, EquilibriumBranch, PointKind, Stop, VectorField,
                             equilibrium_branch, locate, step, tangent, weighted_norm)
from ...model.equations import Model, build_model, field_and_derivatives, jacobian, parameter_jacobian, rhs
from ...errors import ConvergenceError
from ...model.nes import VALID_ANGLE, cubic_range
from ...model.parameters import DIAGRAM_V_RANGE, Parameters
from ...continuation.periodic_orbits import (PeriodicBranch, hopf_guess, orbit_from_samples,
                              periodic_branch)
from ..core import nes_range
from ...model.units import kn
from ..core.response import mode_of, torsional_share
from ..core.stability import HopfResult, check_speeds_and_load, hopf_points
from .summaries import bifurcation_summary, write_bifurcation_csv
from .options import BifurcationOptions

# Size of a unit step in each unknown (the arclength metric): psi, dpsi, delta, ddelta, lam, psis, dpsis.
STATE_SCALE = np.array([0.05, 5.0, 0.005, 0.5, 0.01, 0.05, 5.0])
V_SCALE = 10.0  # m/s
T_SCALE = 0.01  # s
MAX_PSI = 1.0  # rad: beyond this a branch is stopped (far outside any physical shimmy)
SEED_T_END = 30.0  # s of simulation per seed
SEED_RETRIES = 2  # further runs of 2 * SEED_T_END from the last state while the motion has not settled
#: A seed needs the attractor, not the trajectory: its orbit is then converged by collocation (to 1e-9).
#: At rtol 1e-6 instead of the histories' 1e-7 a 30 s run costs ~30 % less; amplitudes agree to 1e-6.
SEED_RTOL = 1e-6
#: Large-amplitude seeds: cycles no Hopf point in range feeds and the standard start does not reach
#: (the torsional isola between two folds above ~720 kN). (state, size): psi in rad, l_g delta in m.
LARGE_STARTS = (("psi", 0.2), ("lateral", 0.1))
LARGE_SEED_SPEEDS = (30.0, 80.0)  # m/s
#: The drawn polyline of a periodic branch: points are added between computed orbits, on the
#: branch's cubic in arclength (:meth:`PeriodicBranch.between`), until straight segments in V stray
#: from it by at most this fraction of the torsional and lateral amplitudes. Near a Hopf point the
#: amplitude grows like (V - V_H)^(1/2): a straight segment in V between computed orbits fell 0.6 %
#: below it (original at 150 kN, V = 7 and 90 m/s), 12 % next to the end of a branch.
DRAW_TOL = 1e-3
DRAW_SPLITS = 6  # a step is drawn as at most 2^6 segments


def gear_field(model: Model, Fz: float) -> VectorField:
    """The gear's vector field with V as the continuation parameter at fixed Fz."""
    return VectorField(model.n_states,
                       lambda x, V: rhs(model, x, V, Fz),
                       lambda x, V: jacobian(model, x, V, Fz),
                       lambda x, V: parameter_jacobian(model, x, V, Fz)[0],
                       name=f"{model.config.value} at Fz = {kn(Fz)}",
                       evaluate=lambda x, V: field_and_derivatives(model, x, V, Fz)[:3])


@dataclass
class Branch:
    """A branch of the diagram in output form."""

    kind: str  # "equilibrium" | "periodic"
    V: np.ndarray
    period: np.ndarray  # s (nan on the equilibrium)
    max_psi: np.ndarray  # rad
    max_lateral: np.ndarray  # m: l_g max |delta|
    stable: np.ndarray
    mode: list[str | None]
    special_points: list[dict[str, Any]]
    origin: str
    stop_reason: str
    steps: int
    raw: PeriodicBranch | None = None
    closed: bool = False  # a loop of orbits: its last point joins its first

    def to_dict(self) -> dict[str, Any]:
        points = [{"V": float(v), "period": None if math.isnan(T) else float(T), "max_psi": float(a),
                   "max_lateral": float(lat), "stable": bool(s), "mode": m}
                  for v, T, a, lat, s, m in zip(self.V, self.period, self.max_psi, self.max_lateral, self.stable,
                                                self.mode, strict=True)]
        return {"kind": self.kind, "origin": self.origin, "stop_reason": self.stop_reason, "steps": self.steps,
                "points": points, "special_points": self.special_points}


@dataclass(frozen=True, eq=False)
class MaximumOrbit:
    """The stable cycle of the largest torsional amplitude, as the collocation left it: its mesh
    (``mesh`` points, ``ncol``) and unknowns ``u`` (X, T, V). ``interior``: the maximum was located
    inside a stable stretch of its branch (d max|psi| / ds = 0 there); otherwise it is the largest
    computed stable point, not located (at the end of a stable stretch, where the branch loses
    stability or ends, or where the refinement did not improve on it)."""

    mesh: np.ndarray
    ncol: int
    u: np.ndarray
    interior: bool


@dataclass
class BifurcationResult:
    config: Configuration
    Fz: float
    v_min: float
    v_max: float
    params: Parameters
    hopf: HopfResult
    branches: list[Branch]
    max_psi: float  # over stable cycles (0 if none)
    max_psi_V: float | None
    max_psi_any: float
    mesh_check: dict[str, Any] | None
    options: BifurcationOptions
    elapsed_s: float
    warnings: list[str] = field(default_factory=list)
    #: the cycle of ``max_psi`` (None if no stable cycle), for following it in a design parameter
    #: (:mod:`shimmy.analyses.decisions.max_psi_curve`); not part of the JSON
    max_psi_orbit: MaximumOrbit | None = field(default=None, compare=False)

    def to_dict(self) -> dict[str, Any]:
        return {"config": self.config.value, "Fz": self.Fz, "v_min": self.v_min, "v_max": self.v_max,
                "params": self.params.to_dict(),
                "hopf_points": [h.to_dict() for h in self.hopf.hopf_points],
                "branches": [b.to_dict() for b in self.branches],
                "max_psi": self.max_psi, "max_psi_V": self.max_psi_V, "max_psi_any": self.max_psi_any,
                "mesh_check": self.mesh_check,
                "numerics": {"ntst": self.options.ntst, "ncol": self.options.ncol,
                             "steps": sum(b.steps for b in self.branches),
                             "seeds": self.options.seeds, "exact_nes": self.options.exact_nes},
                "warnings": list(self.warnings), "elapsed_s": self.elapsed_s, "version": __version__}

    def write_csv(self, path) -> None:
        """Every branch point, one row each (:func:`~shimmy.analyses.diagrams.summaries.write_bifurcation_csv`)."""
        write_bifurcation_csv(self.to_dict(), path)

    def summary_text(self) -> str:
        """The short table ``python -m shimmy bifurcation`` prints
        (:func:`~shimmy.analyses.diagrams.summaries.bifurcation_summary`)."""
        return bifurcation_summary(self.to_dict())


def bifurcation(config: Configuration | str, Fz: float, *, params: Parameters | None = None,
                v_range: tuple[float, float] = DIAGRAM_V_RANGE, options: BifurcationOptions | None = None,
                progress: Callable[[float, str], None] | None = None) -> BifurcationResult:
    """The bifurcation diagram in V at load Fz (N) over ``v_range`` = (v_min, v_max) (m/s)."""
    clock = time.perf_counter()
    config = Configuration.parse(config)
    params = params if params is not None else Parameters()
    options = options or BifurcationOptions()
    v_min, v_max, Fz = check_speeds_and_load(v_range, Fz)
    report = progress or (lambda fraction, message: None)
    model = build_model(config, params, exact_nes=options.exact_nes)
    system = gear_field(model, Fz)
    n = model.n_states
    scale = STATE_SCALE[:n]
    warnings: list[str] = []

    report(0.0, "equilibrium branch")
    hopf = hopf_points(config, Fz, params=params, v_range=(v_min, v_max))
    eq = equilibrium_branch(system, np.zeros(n), v_min, p_range=(v_min, v_max),
                            options=ContinuationOptions(ds=0.1, ds_max=2.0, max_steps=10_000), scale=scale,
                            p_scale=V_SCALE)
    engine_h = [s.p for s in eq.special_points if s.kind == PointKind.HOPF]
    scan_h = [h.V for h in hopf.hopf_points]
    starts = sorted(scan_h)
    for v in scan_h:
        if not any(abs(v - e) <= 1e-6 * max(v, 1.0) for e in engine_h):
            warnings.append(f"Hopf point V = {v:.9g} m/s found by the eigenvalue scan but stepped over by the "
                            "equilibrium continuation (two crossings within one step); used as a start")
    for e in engine_h:
        if not any(abs(v - e) <= 1e-6 * max(v, 1.0) for v in scan_h):
            warnings.append(f"equilibrium continuation reports a Hopf point at V = {e:.9g} m/s "
                            "that the eigenvalue scan does not confirm")
    branches = [_equilibrium_output(eq, hopf)]

    popts = options.periodic()
    limits = orbit_limits(model)
    done: list[float] = []
    large = [(V, what, size) for V in LARGE_SEED_SPEEDS if v_min < V < v_max for what, size in LARGE_STARTS]
    units = max(1, len(starts)) + (len(_seed_speeds(hopf)) + len(large) if options.seeds else 0)
    unit = 0
    for v_h in starts:
        unit += 1
        if v_h in done:
            continue  # reached by an earlier branch
        report(unit / (units + 1), f"periodic branch from the Hopf point at V = {v_h:.4g} m/s")
        A = jacobian(model, np.zeros(n), v_h, Fz)
        ev, vecs = np.linalg.eig(A)
        i = int(np.argmin(np.abs(ev.real) + np.where(ev.imag > 0, 0.0, np.inf)))
        q = vecs[:, i] / vecs[np.argmax(np.abs(vecs[:, i] / scale)), i]
        guess, shape = hopf_guess(np.zeros(n), v_h, ev[i].imag, q, Mesh.uniform(popts.ntst, popts.ncol), 0.0)
        try:
            raw = periodic_branch(system, guess, p_range=(v_min, v_max), options=popts, scale=scale, p_scale=V_SCALE,
                                  direction=shape, limits=limits)
        except EngineConvergenceError as exc:  # the engine's, or ours derived from it
            warnings.append(f"no periodic branch from the Hopf point at V = {v_h:.6g} m/s: {exc}")
            continue
        done.append(v_h)
        for s in raw.special_points:
            if s.kind == PointKind.HOPF:  # ended on another Hopf point: the located one it approaches
                near = _hopf_reached(starts, raw)
                if near is not None:
                    done.append(near)
                else:
                    warnings.append(f"branch from V = {v_h:.6g} m/s returns to x = 0 near V = {s.p:.6g} m/s, "
                                    "where no Hopf point was located")
        branch = _periodic_output(raw, params, f"Hopf point at V = {v_h:.6g} m/s", starts)
        omega = {h.V: h.omega for h in hopf.hopf_points}
        branches.append(_with_hopf_ends(branch, v_h, omega))

    if options.seeds:
        for v_seed in _seed_speeds(hopf):
            unit += 1
            report(unit / (units + 1), f"simulation seed at V = {v_seed:.4g} m/s")
            seeded = _seeded_branch(config, model, system, Fz, params, v_seed, v_min, v_max, popts,
                                    limits, branches, warnings)
            if seeded is not None:
                branches.append(seeded)
        for v_seed, what, size in large:
            unit += 1
            report(unit / (units + 1), f"large {what} seed at V = {v_seed:.4g} m/s")
            x0 = np.zeros(n)
            x0[0 if what == "psi" else 2] = size if what == "psi" else size / params.gear.l_g
            seeded = _seeded_branch(config, model, system, Fz, params, v_seed, v_min, v_max, popts,
                                    limits, branches, warnings, x0=x0, label=f"large {what} start")
            if seeded is not None:
                branches.append(seeded)

    report(0.97, "maximum torsional amplitude")
    max_psi, max_v, max_any, mesh_check, orbit = _maximum(system, branches, options, scale, warnings,
                                                         params.gear.l_g)
    if config.has_nes and not options.exact_nes:
        n = params.nes
        peak, is_bound = _nes_rotation(system, branches, scale, cubic_range(n.r1, n.r2, n.r3, n.k_s, n.e_p))
        beyond = nes_range.warning(config, params, peak, options.exact_nes, bound=is_bound,
                                   where="on the stable cycles of this diagram")
        if beyond:
            warnings.append(beyond)
    report(1.0, "done")
    return BifurcationResult(config, Fz, v_min, v_max, params, hopf, branches, max_psi, max_v, max_any,
                             mesh_check, options, time.perf_counter() - clock, warnings, orbit)


def _seed_speeds(hopf: HopfResult) -> list[float]:
    """Where to look for periodic motions not born at a Hopf point in range: the middle of every
    unstable interval of x = 0, and its ends where they are range bounds, not Hopf points."""
    hopf_speeds = [h.V for h in hopf.hopf_points] + list(hopf.branch_points)
    speeds = []
    for a, b in hopf.unstable_intervals:
        speeds.append(math.sqrt(a * b))
        for end, inward in ((a, b), (b, a)):
            if not any(abs(end - v) <= 1e-9 * max(end, 1.0) for v in hopf_speeds):
                speeds.append(end + 1e-4 * (inward - end))
    return sorted(speeds)


def orbit_limits(model: Model):
    """The stop rule of the gear's periodic branches (and curves of cycles): a check of an orbit's
    extremes, period and speed that returns why the branch must stop there, or None."""
    has_nes = model.config.has_nes

    def check(x_max, x_min, T, V):
        if max(abs(x_max[0]), abs(x_min[0])) > MAX_PSI:
            return f"torsional amplitude above {MAX_PSI:g} rad at V = {V:.6g} m/s: branch stopped"
        if has_nes and model.exact_nes:
            # |psi - psis| is not available from the extremes alone; bound it conservatively
            rel = max(abs(x_max[0] - x_min[5]), abs(x_min[0] - x_max[5]))
            if rel >= VALID_ANGLE:
                return f"NES relative rotation may exceed pi/6 at V = {V:.6g} m/s (roller leaves its track)"
        return None
    return check


def _hopf_reached(hopf_speeds: list[float], raw: PeriodicBranch) -> float | None:
    """The Hopf point a branch ending at zero amplitude runs into: among the Hopf points within
    5 % (or ten last steps) of its last point, the nearest one ahead in its direction of travel,
    else the nearest one (near a degenerate Hopf point the amplitude is tiny over a wide speed
    range, so the branch can stop just past the point it is joining)."""
    if raw.p.size < 2 or not hopf_speeds:
        return None
    last, before = raw.p[-1], raw.p[-2]
    tolerance = 10.0 * abs(last - before)
    close = [v for v in hopf_speeds if abs(v - last) <= 0.05 * v + tolerance]
    if not close:
        return None
    ahead = [v for v in close if (v - last) * (last - before) >= -1e-9 * max(abs(last), 1.0)]
    return min(ahead or close, key=lambda v: abs(v - last))


def _equilibrium_output(eq: EquilibriumBranch, hopf: HopfResult) -> Branch:
    """x = 0 with its stability from the engine, the exact Hopf points inserted (neutral there)."""
    V = list(eq.p)
    stable = [bool(s) for s in eq.stable]
    for h in hopf.hopf_points:
        k = int(np.searchsorted(V, h.V))
        V.insert(k, h.V)
        stable.insert(k, False)
    V_arr = np.array(V)
    zeros = np.zeros_like(V_arr)
    special = [{"kind": PointKind.HOPF, "V": h.V, "frequency_hz": h.frequency_hz, "criticality": h.criticality.value,
                "lyapunov": h.lyapunov} for h in hopf.hopf_points]
    special += [{"kind": PointKind.BRANCH_POINT, "V": v} for v in hopf.branch_points]
    return Branch("equilibrium", V_arr, np.full_like(V_arr, np.nan), zeros, zeros.copy(), np.array(stable),
                  [None] * V_arr.size, special, "x = 0", eq.stop_reason, eq.steps)


def _amplitudes(x_max: np.ndarray, x_min: np.ndarray) -> np.ndarray:
    """(points, 2): max |psi| and max |delta| over each orbit."""
    return np.column_stack([np.maximum(np.abs(x_max[:, k]), np.abs(x_min[:, k])) for k in (0, 2)])


def _added(raw: PeriodicBranch) -> tuple[np.ndarray, np.ndarray]:
    """Where to add drawn points between the computed orbits: (step index i, sigma in (0, 1), in
    arclength from point i to i + 1), sorted. Each step is halved, and its halves again (at most
    ``DRAW_SPLITS`` times), while a straight segment in V strays from the branch's cubic in
    arclength by more than ``DRAW_TOL`` of the torsional or lateral amplitude there, checked at the
    segment's quarter points and middle (where V turns inside a segment, a fold, the segment is
    linear in arclength instead)."""
    quarters = np.array([0.25, 0.5, 0.75])
    steps, lo, hi = np.arange(raw.p.size - 1), np.zeros(raw.p.size - 1), np.ones(raw.p.size - 1)
    added_steps, added_sigma = [], []
    for _ in range(DRAW_SPLITS):
        checks = lo[:, None] + quarters[None, :] * (hi - lo)[:, None]
        p_n, _, xa_n, xi_n = raw.between(np.repeat(steps, 2), np.column_stack([lo, hi]).ravel())
        p_c, _, xa_c, xi_c = raw.between(np.repeat(steps, 3), checks.ravel())
        a_n = _amplitudes(xa_n, xi_n).reshape(-1, 2, 2)
        a_c = _amplitudes(xa_c, xi_c).reshape(-1, 3, 2)
        v_n, v_c = p_n.reshape(-1, 2), p_c.reshape(-1, 3)
        with np.errstate(divide="ignore", invalid="ignore"):
            f = (v_c - v_n[:, :1]) / (v_n[:, 1:] - v_n[:, :1])
        f = np.where((f >= 0.0) & (f <= 1.0), f, quarters[None, :])
        line = a_n[:, :1, :] + f[:, :, None] * (a_n[:, 1:, :] - a_n[:, :1, :])
        error = np.max(np.abs(line - a_c) / np.maximum(np.abs(a_c), 1e-12), axis=(1, 2))
        split = error > DRAW_TOL
        if not split.any():
            break
        steps, lo, hi = steps[split], lo[split], hi[split]
        middle = 0.5 * (lo + hi)
        added_steps.append(steps)
        added_sigma.append(middle)
        steps, lo, hi = np.tile(steps, 2), np.concatenate([lo, middle]), np.concatenate([middle, hi])
    if not added_steps:
        return np.zeros(0, int), np.zeros(0)
    steps, sigma = np.concatenate(added_steps), np.concatenate(added_sigma)
    order = np.lexsort((sigma, steps))
    return steps[order], sigma[order]


def _drawn(raw: PeriodicBranch) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The points of the drawn polyline (V, period, x_max, x_min, stable): the computed orbits, and
    between them points on the branch's cubic in arclength where a straight segment would stray
    (:func:`_added`). An added point is stable as the computed orbit on its side of the special
    point located in that step (else as the nearer one)."""
    if raw.rates is None or raw.p.size < 2:
        return raw.p, raw.period, raw.x_max, raw.x_min, raw.stable
    steps, sigma = _added(raw)
    if steps.size == 0:
        return raw.p, raw.period, raw.x_max, raw.x_min, raw.stable
    p, T, x_max, x_min = raw.between(steps, sigma)
    stable = np.where(sigma <= 0.5, raw.stable[steps], raw.stable[steps + 1])
    for i in np.unique(steps[raw.stable[steps] != raw.stable[steps + 1]]):
        lo, hi = sorted((raw.p[i], raw.p[i + 1]))
        at = [s.p for s in raw.special_points if s.index in (i, i + 1) and lo <= s.p <= hi]
        if at:
            here = steps == i
            stable[here] = np.where((p[here] - at[0]) * (raw.p[i] - at[0]) >= 0, raw.stable[i], raw.stable[i + 1])
    # computed orbit i sorts before the points added in step i (position i + sigma, sigma in (0, 1))
    order = np.argsort(np.concatenate([np.arange(raw.p.size, dtype=float), steps + sigma]), kind="stable")
    return tuple(np.concatenate([a, b])[order] for a, b in ((raw.p, p), (raw.period, T), (raw.x_max, x_max),
                                                            (raw.x_min, x_min), (raw.stable, stable)))


def _periodic_output(raw: PeriodicBranch, params: Parameters, origin: str, hopf_speeds: list[float]) -> Branch:
    l_g = params.gear.l_g
    V, period, x_max, x_min, stable = _drawn(raw)
    psi_amp, delta_amp = _amplitudes(x_max, x_min).T
    half_psi = 0.5 * (x_max[:, 0] - x_min[:, 0])
    half_delta = 0.5 * (x_max[:, 2] - x_min[:, 2])
    share = torsional_share(half_psi, half_delta, params.gear.k_psi, params.gear.k_delta)
    modes = [mode_of(s).value if np.isfinite(s) else None for s in share]
    special = []
    for s in raw.special_points:
        d = {"kind": s.kind, "V": s.p}
        if s.kind == PointKind.HOPF and hopf_speeds:
            near = _hopf_reached(hopf_speeds, raw)
            if near is not None:
                d.update({"V": near, "V_last_point": s.p})
        if "period" in s.data:
            xmax, xmin = np.array(s.data["x_max"]), np.array(s.data["x_min"])
            d.update({"period": s.data["period"], "max_psi": float(max(abs(xmax[0]), abs(xmin[0]))),
                      "max_lateral": float(l_g * max(abs(xmax[2]), abs(xmin[2]))),
                      "multipliers_abs": s.data["multipliers_abs"]})
        if "torus_angle" in s.data:
            d["torus_angle"] = s.data["torus_angle"]
        special.append(d)
    return Branch("periodic", V, period, psi_amp, l_g * delta_amp, stable, modes, special, origin,
                  raw.stop_reason, raw.steps, raw, raw.closed)


def _with_hopf_ends(branch: Branch, v_start: float, omega: dict[float, float]) -> Branch:
    """The branch with its zero-amplitude end points at the Hopf points it joins (for plots and
    tables: the cycles shrink to x = 0 there; with the particle damper the amplitude grows like
    (V - V_H)^2, so the first computed orbit can lie well away from V_H)."""
    def point(V):
        return V, 2.0 * math.pi / omega[V]

    head = [point(v_start)]
    tail = [point(s["V"]) for s in branch.special_points if s["kind"] == PointKind.HOPF and s["V"] in omega]
    V = np.concatenate([[v for v, _ in head], branch.V, [v for v, _ in tail]])
    T = np.concatenate([[t for _, t in head], branch.period, [t for _, t in tail]])
    zeros_h, zeros_t = np.zeros(len(head)), np.zeros(len(tail))
    stable = np.concatenate([branch.stable[:1], branch.stable, branch.stable[-1:][:len(tail)]])
    mode = branch.mode[:1] + branch.mode + branch.mode[-1:][:len(tail)]
    return Branch(branch.kind, V, T, np.concatenate([zeros_h, branch.max_psi, zeros_t]),
                  np.concatenate([zeros_h, branch.max_lateral, zeros_t]), stable, mode, branch.special_points,
                  branch.origin, branch.stop_reason, branch.steps, branch.raw, branch.closed)


def _on_branch(branches: list[Branch], V: float, period: float, psi_amp: float, lat_amp: float) -> bool:
    """Whether a periodic motion (V, period, amplitudes) lies on a computed periodic branch (2 %)."""
    for b in branches:
        if b.kind != "periodic":
            continue
        for i in range(b.V.size - 1):
            lo, hi = sorted((b.V[i], b.V[i + 1]))
            if not lo <= V <= hi:
                continue
            f = 0.0 if hi == lo else (V - b.V[i]) / (b.V[i + 1] - b.V[i])
            T = b.period[i] + f * (b.period[i + 1] - b.period[i])
            a = b.max_psi[i] + f * (b.max_psi[i + 1] - b.max_psi[i])
            lat = b.max_lateral[i] + f * (b.max_lateral[i + 1] - b.max_lateral[i])
            if abs(T - period) <= 0.02 * period and abs(a - psi_amp) <= 0.02 * max(psi_amp, 1e-6) + 1e-5 \
                    and abs(lat - lat_amp) <= 0.02 * max(lat_amp, 1e-6) + 1e-5:
                return True
    return False


def periodic_orbit_from_simulation(config: Configuration, Fz: float, V: float, *, params: Parameters,
                                   mesh: Mesh, t_end: float = SEED_T_END, exact_nes: bool = False, x0=None):
    """(guess, None) from a simulated settled periodic motion, or (None, reason). ``x0``: the
    start state (default the standard start, psi = 0.001 rad)."""
    from ..core.simulation import simulate  # analyses may use analyses; kept local to keep start-up light

    run = simulate(config, V, Fz, params=params, t_end=t_end, exact_nes=exact_nes, x0=x0, rtol=SEED_RTOL,
                   frequency=False)
    for _ in range(SEED_RETRIES):  # slow growth or decay: go on from where the run ended
        if not run.success or run.steady:
            break
        run = simulate(config, V, Fz, params=params, t_end=2 * t_end, x0=run.states[:, -1], exact_nes=exact_nes,
                       rtol=SEED_RTOL, frequency=False)
    if not run.success:
        return None, f"simulation failed: {run.message}"
    if run.response_type.value == "Stable":
        return None, "the simulation decays to x = 0"
    if not run.steady:
        return None, f"the simulated motion did not settle within {t_end * (1 + 2 * SEED_RETRIES):g} s"
    k_psi, k_delta = params.gear.k_psi, params.gear.k_delta
    states = run.states
    window = states[:, states.shape[1] // 2:]
    t = run.t[states.shape[1] // 2:]
    signal = (np.sqrt(k_psi) * window[0] if run.amplitude["psi"] ** 2 * k_psi
              >= (run.amplitude["lateral"] / params.gear.l_g) ** 2 * k_delta else np.sqrt(k_delta) * window[2])
    signal = signal - signal.mean()
    up = np.nonzero((signal[:-1] < 0) & (signal[1:] >= 0))[0]
    if up.size < 4:
        return None, "too few oscillations in the simulated window"
    crossings = t[up] - signal[up] * (t[up + 1] - t[up]) / (signal[up + 1] - signal[up])
    periods = np.diff(crossings)
    T = float(np.median(periods[-10:]))
    spread = float(np.std(periods[-10:]) / T)
    if spread > 0.02:
        return None, f"the simulated motion is not periodic (period spread {100 * spread:.1f} %)"
    t0 = crossings[-2] - T if crossings[-1] + 1e-12 > run.t[-1] else crossings[-2]
    tau = np.linspace(0.0, 1.0, 400)
    x = np.column_stack([np.interp(t0 + tau * T, run.t, states[i]) for i in range(states.shape[0])])
    return orbit_from_samples(t0 + tau * T, x, T, V, mesh), None


def _seeded_branch(config, model, system, Fz, params, v_seed, v_min, v_max, popts, limits, branches,
                   warnings, x0=None, label: str = "simulation") -> Branch | None:
    mesh = Mesh.uniform(popts.ntst, popts.ncol)
    guess, reason = periodic_orbit_from_simulation(config, Fz, v_seed, params=params, mesh=mesh,
                                                   exact_nes=model.exact_nes, x0=x0)
    if guess is None:
        if "not periodic" in reason or "failed" in reason:
            warnings.append(f"{label} at V = {v_seed:.6g} m/s: {reason}")
        return None
    psi_amp = float(np.abs(guess.X[:, 0]).max())
    lat_amp = float(params.gear.l_g * np.abs(guess.X[:, 2]).max())
    if _on_branch(branches, v_seed, guess.T, psi_amp, lat_amp):
        return None
    scale = STATE_SCALE[:model.n_states]
    halves = []
    for direction in (-1, +1):
        try:
            halves.append(periodic_branch(system, guess, p_range=(v_min, v_max), options=popts, scale=scale,
                                          p_scale=V_SCALE, p_direction=direction, limits=limits))
        except EngineConvergenceError as exc:  # the engine's, or ours derived from it
            warnings.append(f"{label} at V = {v_seed:.6g} m/s: {exc}")
            return None
        if halves[0].closed:  # a loop: one way round covers it
            return _periodic_output(halves[0], params, f"{label} at V = {v_seed:.6g} m/s", [])
    joined = _join(halves[0], halves[1])
    return _periodic_output(joined, params, f"{label} at V = {v_seed:.6g} m/s", [])


def _join(down: PeriodicBranch, up: PeriodicBranch) -> PeriodicBranch:
    """One branch from two halves continued both ways from the same first point (open: a loop is kept
    from its first half alone)."""
    k = down.p.size

    def cat(a, b):
        return np.concatenate([a[::-1], b[1:]])

    special = [replace(s, index=k - 1 - s.index) for s in down.special_points][::-1]
    special += [replace(s, index=k - 1 + s.index) for s in up.special_points]
    rates = lengths = None
    if down.rates is not None and up.rates is not None:  # the down half runs backwards: its rates turn
        rates = np.concatenate([-down.rates[::-1], up.rates[1:]])
        lengths = np.concatenate([[0.0], down.lengths[:0:-1], up.lengths[1:]])
    return PeriodicBranch(cat(down.p, up.p), cat(down.period, up.period), cat(down.x_max, up.x_max),
                          cat(down.x_min, up.x_min), cat(down.stable, up.stable),
                          cat(down.multipliers, up.multipliers), up.ntst, up.ncol,
                          down.solutions[::-1] + up.solutions[1:], max(down.trivial_error, up.trivial_error),
                          rates, lengths,
                          special_points=special, steps=down.steps + up.steps,
                          stops=[Stop(s.reason, f"{way}: {s.message}")
                                 for way, half in (("decreasing V", down), ("increasing V", up)) for s in half.stops])


def restore_point(system: VectorField, raw: PeriodicBranch, i: int, scale: np.ndarray,
             to: int | None = None) -> tuple[PeriodicProblem, CurvePoint, float]:
    """The problem on point i's mesh, the point with its tangent oriented towards point ``to``
    (default i + 1), and the arclength to that point."""
    mesh_points, u = raw.solutions[i]
    problem = PeriodicProblem(system, Mesh(mesh_points, raw.ncol), scale, T_SCALE, V_SCALE)
    problem.accept(u)
    j = min(i + 1 if to is None else to, len(raw.solutions) - 1)
    if j == i:
        return problem, CurvePoint(u, tangent(problem, u, np.eye(u.size)[-1])), 0.0
    other = PeriodicProblem(system, Mesh(raw.solutions[j][0], raw.ncol), scale, T_SCALE, V_SCALE)
    direction = other.transfer(problem, raw.solutions[j][1]) - u
    return problem, CurvePoint(u, tangent(problem, u, direction)), weighted_norm(direction, problem.weights)


def cycle_at(result: BifurcationResult, branch: int, V: float, max_psi: float | None = None) -> dict[str, Any]:
    """The periodic orbit of ``result.branches[branch]`` at speed V, located exactly on the branch
    (secant on the step from the neighbouring branch point): period, amplitudes, stability and the
    orbit itself (t, psi, l_g delta; ``x0`` the full state at t = 0). Raises ValueError if the
    branch does not reach V. A branch that passes V more than once (a fold, a loop) gives the
    orbit whose torsional amplitude is nearest to ``max_psi`` (default: the first one)."""
    b = result.branches[branch]
    if b.kind != "periodic" or b.raw is None:
        raise ValueError(f"branch {branch} is not a periodic branch")
    raw = b.raw
    model = build_model(result.config, result.params, exact_nes=result.options.exact_nes)
    system = gear_field(model, result.Fz)
    scale = STATE_SCALE[:model.n_states]
    crossings = [i for i in range(raw.p.size - 1) if (raw.p[i] - V) * (raw.p[i + 1] - V) <= 0]
    if max_psi is not None:
        amp = np.maximum(np.abs(raw.x_max[:, 0]), np.abs(raw.x_min[:, 0]))

        def distance(i):
            f = 0.0 if raw.p[i + 1] == raw.p[i] else (V - raw.p[i]) / (raw.p[i + 1] - raw.p[i])
            return abs(amp[i] + f * (amp[i + 1] - amp[i]) - max_psi)

        crossings.sort(key=distance)
    for i in crossings:
        problem, start, h = restore_point(system, raw, i, scale)
        if raw.p[i] == V:
            point = start
        else:
            hit = locate(problem, start, h, lambda q: q.u[-1] - V, raw.p[i] - V, raw.p[i + 1] - V,
                         ContinuationOptions(locate_tol=1e-10))
            if hit is None:
                raise ConvergenceError(f"could not locate the orbit at V = {V:g} m/s on branch {branch}")
            point = hit[0]
        tau, x = problem.sample(point.u)
        mu = problem.multipliers(point.u)
        T = float(point.u[-2])
        l_g = result.params.gear.l_g
        return {"V": float(point.u[-1]), "period": T, "max_psi": float(np.abs(x[:, 0]).max()),
                "max_lateral": float(l_g * np.abs(x[:, 2]).max()), "stable": bool(np.all(np.abs(mu[1:]) < 1.0)),
                "multipliers": mu, "t": tau * T, "psi": x[:, 0], "lateral": l_g * x[:, 2], "x0": x[0].copy()}
    raise ValueError(f"branch {branch} does not reach V = {V:g} m/s")


def _draw_located(branches: list[Branch], raw: PeriodicBranch, problem: PeriodicProblem, point: CurvePoint,
                  psi_amp: float, l_g: float) -> None:
    """Put the located maximum among the drawn points of its branch (between the drawn points that
    bracket it), so that the plotted curve peaks where the reported maximum is."""
    for k, b in enumerate(branches):
        if b.raw is not raw:
            continue
        V = float(point.u[-1])
        near = int(np.argmin(np.abs(b.V - V) / V_SCALE + np.abs(b.max_psi - psi_amp) / STATE_SCALE[0]))
        j = next((m for m in (near - 1, near) if 0 <= m < len(b.V) - 1
                  and min(b.V[m], b.V[m + 1]) <= V <= max(b.V[m], b.V[m + 1])), None)
        if j is None:
            return
        _, x = problem.sample(point.u)
        branches[k] = replace(b, V=np.insert(b.V, j + 1, V), period=np.insert(b.period, j + 1, float(point.u[-2])),
                              max_psi=np.insert(b.max_psi, j + 1, psi_amp),
                              max_lateral=np.insert(b.max_lateral, j + 1, l_g * float(np.abs(x[:, 2]).max())),
                              stable=np.insert(b.stable, j + 1, True),
                              mode=b.mode[:j + 1] + [b.mode[j]] + b.mode[j + 1:])
        return


#: Stable cycles whose NES rotation is sampled at most, for the cubic-range warning (largest bound first).
NES_ROTATION_SAMPLES = 12


def _nes_rotation(system, branches: list[Branch], scale, limit: float) -> tuple[float, bool]:
    """(largest |psi - psi_s| over the stable cycles, whether it is only a bound) as far as it matters for
    the cubic's range ``limit``: the bound max(psi_max - psis_min, psis_max - psi_min) of every stored
    cycle first (exact enough when it stays within ``limit``); the cycles whose bound exceeds it are
    sampled on their collocation polynomials, largest bound first, and the largest value found is given
    when one exceeds ``limit``; else the largest bound not sampled, flagged as a bound."""
    candidates = []
    for b in branches:
        raw = b.raw
        if b.kind != "periodic" or raw is None or raw.p.size == 0 or raw.x_max.shape[1] < 6:
            continue
        bound = np.maximum(raw.x_max[:, 0] - raw.x_min[:, 5], raw.x_max[:, 5] - raw.x_min[:, 0])
        candidates += [(float(bound[i]), raw, int(i)) for i in np.flatnonzero(raw.stable & (bound > limit))]
    candidates.sort(key=lambda c: -c[0])
    found = 0.0
    for _, raw, i in candidates[:NES_ROTATION_SAMPLES]:
        mesh_points, u = raw.solutions[i]
        _, x = PeriodicProblem(system, Mesh(mesh_points, raw.ncol), scale, T_SCALE, V_SCALE).sample(u)
        found = max(found, float(np.abs(x[:, 0] - x[:, 5]).max()))
    if found > limit or len(candidates) <= NES_ROTATION_SAMPLES:
        return found, False
    return candidates[NES_ROTATION_SAMPLES][0], True


def at_fixed_speed(problem: PeriodicProblem, u: np.ndarray, copts: ContinuationOptions) -> CurvePoint | None:
    """The cycle ``u`` corrected by Newton with its speed V held (a step of length 0 along V), with
    its tangent; None if Newton does not converge."""
    along_v = np.zeros_like(u)
    along_v[-1] = 1.0
    return step(problem, CurvePoint(u, along_v / weighted_norm(along_v, problem.weights)), 0.0, copts)


def largest_peak_along(problem: PeriodicProblem, start: CurvePoint, lo: float, hi: float,
                       copts: ContinuationOptions, xatol: float) -> tuple[float, float, CurvePoint | None]:
    """(h, A, point): the largest torsional amplitude A along the branch from ``start``, over the
    arclength h in (lo, hi), by a bounded search to ``xatol`` (each orbit's peak on its collocation
    polynomial, :meth:`PeriodicProblem.peak`); a trial step that does not converge counts as A = 0
    (point None)."""
    tried: dict[float, tuple[float, CurvePoint | None]] = {}

    def minus_amplitude(h):
        point = step(problem, start, h, copts, with_tangent=False) if h != 0 else start
        tried[h] = (0.0, None) if point is None else (problem.peak(point.u, 0)[2], point)
        return -tried[h][0]

    h, _ = minimum_in(minus_amplitude, lo, hi, xatol=xatol)
    return h, *tried.get(h, (0.0, None))


def _maximum(system, branches: list[Branch], options: BifurcationOptions, scale, warnings, l_g: float):
    """Largest torsional amplitude of stable cycles, refined along the branch, a mesh check, and the
    cycle of the maximum (:class:`MaximumOrbit`)."""
    best = (0.0, None, None, None)  # amplitude, V, branch, index into its raw points
    max_any = 0.0
    for b in branches:
        raw = b.raw
        if b.kind != "periodic" or raw is None or raw.p.size == 0:
            continue
        psi_amp = np.maximum(np.abs(raw.x_max[:, 0]), np.abs(raw.x_min[:, 0]))
        max_any = max(max_any, float(psi_amp.max()))
        stable_amp = np.where(raw.stable, psi_amp, -np.inf)
        i = int(np.argmax(stable_amp))
        if np.isfinite(stable_amp[i]) and stable_amp[i] > best[0]:
            best = (float(stable_amp[i]), float(raw.p[i]), raw, i)
    amp, V, raw, i = best
    if raw is None:
        return 0.0, None, max_any, None, None
    copts = ContinuationOptions(ds=options.ds, ds_max=options.ds_max)
    lo = max(i - 1, 0)
    if 0 < i < raw.p.size - 1 and raw.stable[lo] and raw.stable[i + 1]:
        problem, start, span = restore_point(system, raw, lo, scale, to=i + 1)
        _, a_opt, point = largest_peak_along(problem, start, 0.0, span, copts, xatol=1e-5 * span)
        if point is not None and a_opt >= amp:
            amp, V = a_opt, float(point.u[-1])
            i_point = point
            _draw_located(branches, raw, problem, point, a_opt, l_g)
        else:
            i_point = None
    else:
        i_point = None
    if i_point is not None:  # the refined point lives on point lo's mesh
        orbit = MaximumOrbit(raw.solutions[lo][0], raw.ncol, i_point.u.copy(), True)
    else:
        orbit = MaximumOrbit(raw.solutions[i][0], raw.ncol, raw.solutions[i][1].copy(), False)
    mesh_check = None
    if options.mesh_check:
        problem, start, _ = restore_point(system, raw, i, scale)
        point = i_point or start
        fine = PeriodicProblem(system, problem.adapted_mesh(point.u, 2 * problem.mesh.ntst), scale, T_SCALE,
                               V_SCALE)
        u_f = problem.transfer(fine, point.u)
        fine.accept(u_f)
        fixed = at_fixed_speed(fine, u_f, copts)
        if fixed is None:
            warnings.append("mesh check: no convergence on the doubled mesh")
        else:
            a_f = fine.peak(fixed.u, 0)[2]
            a_c = problem.peak(point.u, 0)[2]
            mesh_check = {"V": float(point.u[-1]), "ntst": problem.mesh.ntst, "ntst_fine": fine.mesh.ntst,
                          "max_psi": a_c, "max_psi_fine": a_f, "change": abs(a_f - a_c)}
    return amp, V, max(max_any, amp), mesh_check, orbit
