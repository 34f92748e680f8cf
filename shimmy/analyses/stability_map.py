"""(V, Fz) stability maps and the shimmy type of an operating point.

How a map is built (what :func:`stability_map` returns says the same in ``methods``):

* **Hopf curves and GH points**: two-parameter continuation of the Hopf points of x = 0
  (:func:`shimmy.analyses.hopf_curves.hopf_curves`; the extended system, l1 along the curve).
* **Fold-of-cycles (LPC) and torus (NS) curves**: two-parameter continuation of each curve
  (:func:`shimmy.analyses.cycle_curves.cycle_curves`: minimally augmented systems, started from
  the GH and double-Hopf points, one-parameter diagrams and large-amplitude starts), exact in V
  and Fz; each curve's crossings of the slice loads are located, so the slices' LPC and NS
  points lie on the drawn curves. Double-Hopf points are reported beside the GH points.
* **Shimmy type** on every slice: the stable attractors at each V read off the slice's
  bifurcation diagram (:func:`attractors_at`): x = 0 where its eigenvalues say so, and every
  periodic branch point with all nontrivial Floquet multipliers inside the unit circle, with
  its mode (torsional / lateral / both, :func:`shimmy.analyses.response.mode_of`). The type
  (:func:`shimmy_type`) is Bistable if a torsional and a lateral cycle are both stable, else
  Both if a stable cycle has both motions large, else Torsion or Lateral after the stable
  cycle, else Stable. Where neither x = 0 nor any cycle is stable (past a torus point the
  attractor is quasi-periodic), the type comes from a time simulation from the standard
  start (psi = 0.001 rad) at that V; the attractor is then reported with
  ``"kind": "simulation"``.

:func:`classify` runs exactly the slice computation at one Fz and reads the answer at V,
so at a map's grid points it gives the map's answer.

Slices are independent units of work and go through :mod:`shimmy.analyses.executors` (a local
process pool, or a Dask cluster).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from .. import __version__
from .bifurcation import BifurcationOptions, BifurcationResult, bifurcation
from ..model.configurations import Configuration
from ..errors import InvalidParameterError
from . import map_shading
from .cycle_curves import cycle_curves
from .executors import InlineExecutor, name_of, run_units
from .hopf_curves import HopfCurvesResult, hopf_curves
from ..model.parameters import FZ_RANGE, V_RANGE, Parameters, check_number, check_operating_point, check_range
from .response import ResponseType

SHIMMY_TYPES = ("Stable", "Torsion", "Lateral", "Bistable", "Both")
SHADING_ROWS = 180  # rows of the read-off shading (at least 4 per slice)
DEFAULT_V_RANGE = (1.0, 200.0)
DEFAULT_FZ_RANGE = (1.0e4, 9.0e5)
#: Simulated V per slice at most where no stable equilibrium or cycle exists; the other grid
#: points of such a stretch take the answer of the nearest simulated one.
MAX_SIMULATIONS_PER_SLICE = 12
FALLBACK_T_END = 60.0  # s
#: Fine grid (per output grid step) on which speed intervals and region lengths are measured.
FINE = 10
#: Low-load band of the pure-torsion area metric.
BAND_FZ_MAX = 250.0e3  # N
BAND_V = (1.0, 200.0)  # m/s
#: Where x = 0 is stable, a "cycle" smaller than this (rad, m) is x = 0 itself: continuation with the
#: particle damper can run a branch on through its Hopf point along the trivial orbit (amplitudes
#: ~1e-100 observed). Where x = 0 is unstable, small cycles are real (with the PD they grow like
#: (V - V_H)^2 from the Hopf point) and count.
TRIVIAL_PSI = 1e-6
TRIVIAL_LATERAL = 1e-7
#: Curve joining: slice-to-slice match if |ln(V1 / V2)| is below this (a 50 % change).


# --------------------------------------------------------------------------- attractors


def attractors_at(result: BifurcationResult, V: float) -> list[dict[str, Any]]:
    """The stable equilibria and limit cycles of a bifurcation diagram at speed V."""
    found: list[dict[str, Any]] = []
    equilibrium_stable = not any(a <= V <= b for a, b in result.hopf.unstable_intervals)
    if equilibrium_stable:
        found.append({"kind": "equilibrium", "mode": None, "max_psi": 0.0, "max_lateral": 0.0,
                      "period": None, "branch": 0})
    tol = 1e-7 * max(1.0, abs(V))  # end points located on a range bound to rounding
    for k, b in enumerate(result.branches):
        if b.kind != "periodic" or b.V.size < 2:
            continue
        segments = [(i, i + 1) for i in range(b.V.size - 1)]
        if b.stop_reason.startswith("closed branch"):  # a loop: its last orbit joins its first
            segments.append((b.V.size - 1, 0))
        for i, j in segments:
            v0, v1 = b.V[i], b.V[j]
            if not min(v0, v1) - tol <= V <= max(v0, v1) + tol or v0 == v1:
                continue
            f = min(max((V - v0) / (v1 - v0), 0.0), 1.0)
            near = i if f <= 0.5 else j
            stable = bool(b.stable[i]) if b.stable[i] == b.stable[j] else bool(b.stable[near])
            mode = b.mode[near] or b.mode[i] or b.mode[j]
            if not stable or mode is None:
                continue
            amp = float(b.max_psi[i] + f * (b.max_psi[j] - b.max_psi[i]))
            lateral = float(b.max_lateral[i] + f * (b.max_lateral[j] - b.max_lateral[i]))
            if equilibrium_stable and amp <= TRIVIAL_PSI and lateral <= TRIVIAL_LATERAL:
                continue  # a zero-amplitude end point, or a branch run on along a stable x = 0
            if amp <= 0.0 and lateral <= 0.0:
                continue  # the zero-amplitude end point at a Hopf point
            found.append({"kind": "limit cycle", "mode": mode, "max_psi": amp,
                          "max_lateral": lateral,
                          "period": float(b.period[i] + f * (b.period[j] - b.period[i])), "branch": k})
    return found


def shimmy_type(attractors: list[dict[str, Any]]) -> str:
    """Stable / Torsion / Lateral / Bistable / Both from a list of stable attractors."""
    modes = {a["mode"] for a in attractors if a["kind"] != "equilibrium"}
    if "torsional" in modes and "lateral" in modes:
        return "Bistable"
    if "both" in modes:
        return "Both"
    if "torsional" in modes:
        return "Torsion"
    if "lateral" in modes:
        return "Lateral"
    return "Stable"


_RESPONSE_MODE = {ResponseType.TORSION: "torsional", ResponseType.LATERAL: "lateral", ResponseType.BOTH: "both"}


def simulated_attractor(config: Configuration, V: float, Fz: float, params: Parameters) -> dict[str, Any]:
    """The attractor reached from the standard start, for speeds with no stable equilibrium or cycle."""
    from .simulation import simulate

    run = simulate(config, V, Fz, params, t_end=FALLBACK_T_END)
    mode = _RESPONSE_MODE.get(run.response_type)
    note = "" if run.success else f"simulation stopped: {run.message}"
    if run.response_type is ResponseType.STABLE:
        note = note or "the simulation decays (slowly) although x = 0 is unstable"
    return {"kind": "simulation", "mode": mode, "max_psi": float(run.amplitude["psi"]),
            "max_lateral": float(run.amplitude["lateral"]), "period": None,
            "frequency_hz": None if not math.isfinite(run.frequency_hz) else float(run.frequency_hz),
            "steady": bool(run.steady), "note": note}


# --------------------------------------------------------------------------- one slice


@dataclass
class SliceResult:
    """One Fz slice of a map: types on the V grid, special points, speed measures."""

    Fz: float
    V: np.ndarray  # output grid (m/s)
    types: list[str]
    hopf_points: list[dict[str, Any]]
    special_points: list[dict[str, Any]]  # LPC / NS / PD / BPC on periodic branches: kind, V, mode
    intervals: list[dict[str, Any]]  # maximal V intervals of one type other than Stable (fine grid)
    lengths: dict[str, float]  # measure (m/s) of V with each type (fine grid)
    max_psi: float
    max_psi_V: float | None
    simulated: list[float]  # V where the type came from a simulation
    warnings: list[str]
    elapsed_s: float

    def to_dict(self) -> dict[str, Any]:
        return {"Fz": self.Fz, "hopf_points": self.hopf_points, "special_points": self.special_points,
                "intervals": self.intervals, "lengths": self.lengths, "max_psi": self.max_psi,
                "max_psi_V": self.max_psi_V, "simulated_V": self.simulated, "warnings": self.warnings,
                "elapsed_s": self.elapsed_s}


def _grids(v_min: float, v_max: float, n_v: int) -> tuple[np.ndarray, np.ndarray]:
    fine = np.linspace(v_min, v_max, (n_v - 1) * FINE + 1).round(10)  # no 6.800000000000001 in outputs
    return fine[::FINE].copy(), fine


def _slice_types(result: BifurcationResult, fine: np.ndarray, coarse_step: int, config: Configuration,
                 params: Parameters) -> tuple[list[str], list[list[dict]], list[float]]:
    """Types on the fine grid; stretches with no stable equilibrium or cycle are simulated at
    their output-grid points (at most MAX_SIMULATIONS_PER_SLICE, spread evenly)."""
    attractors = [attractors_at(result, float(v)) for v in fine]
    empty = [i for i, a in enumerate(attractors) if not a]
    simulated: list[float] = []
    if empty:
        on_grid = [i for i in empty if i % coarse_step == 0] or [empty[len(empty) // 2]]
        if len(on_grid) > MAX_SIMULATIONS_PER_SLICE:
            pick = np.linspace(0, len(on_grid) - 1, MAX_SIMULATIONS_PER_SLICE).round().astype(int)
            on_grid = [on_grid[k] for k in sorted(set(pick.tolist()))]
        runs = {i: simulated_attractor(config, float(fine[i]), result.Fz, params) for i in on_grid}
        simulated = [float(fine[i]) for i in on_grid]
        keys = np.array(on_grid)
        for i in empty:
            j = int(keys[np.argmin(np.abs(keys - i))])
            attractors[i] = [dict(runs[j], simulated_at=float(fine[j]))] if j != i else [runs[j]]
    return [shimmy_type(a) for a in attractors], attractors, simulated


def _intervals(fine: np.ndarray, types: list[str], critical: list[float] = ()) -> list[dict[str, Any]]:
    """Maximal V intervals of one type other than Stable. An end between two grid points moves to
    the located Hopf / fold / torus point between them, if there is one (exact), else it is the
    grid point inside the interval (within one fine step)."""
    crit = np.sort(np.asarray(list(critical), float))

    def snap(inside: int, outside: int) -> float:
        lo, hi = sorted((fine[inside], fine[outside]))
        hits = crit[(crit >= lo) & (crit <= hi)]
        return float(hits[0]) if hits.size else float(fine[inside])

    out = []
    start = 0
    n = len(types)
    for i in range(1, n + 1):
        if i == n or types[i] != types[start]:
            if types[start] != "Stable":
                out.append({"type": types[start],
                            "V_start": snap(start, start - 1) if start > 0 else float(fine[0]),
                            "V_end": snap(i - 1, i) if i < n else float(fine[-1])})
            start = i
    return out


def _lengths(fine: np.ndarray, types: list[str]) -> dict[str, float]:
    """Measure of V with each type: each fine point stands for the cell around it."""
    edges = np.concatenate([[fine[0]], 0.5 * (fine[1:] + fine[:-1]), [fine[-1]]])
    widths = np.diff(edges)
    return {t: float(sum(w for w, ty in zip(widths, types, strict=True) if ty == t)) for t in SHIMMY_TYPES}


def _special_points(result: BifurcationResult) -> list[dict[str, Any]]:
    points = []
    for b in result.branches:
        if b.kind != "periodic":
            continue
        for s in b.special_points:
            if s["kind"] in ("LPC", "NS", "PD", "BPC"):
                k = int(np.argmin(np.abs(b.V - s["V"])))
                points.append({"kind": s["kind"], "V": float(s["V"]), "mode": b.mode[k]})
    return points


def map_slice(config: Configuration | str, Fz: float, v_min: float, v_max: float, n_v: int,
              params: Parameters, options: BifurcationOptions | None = None) -> SliceResult:
    """The map's computation on one load: diagram in V, types on the grid, special points."""
    clock = time.perf_counter()
    config = Configuration.parse(config)
    options = options or BifurcationOptions(mesh_check=False)
    result = bifurcation(config, Fz, v_min, v_max, params, options)
    coarse, fine = _grids(v_min, v_max, n_v)
    types_fine, _, simulated = _slice_types(result, fine, FINE, config, params)
    hopf = [{"V": h.V, "frequency_hz": h.frequency_hz, "criticality": h.criticality.value}
            for h in result.hopf.hopf_points]
    special = _special_points(result)
    critical = [h["V"] for h in hopf] + [p["V"] for p in special]
    return SliceResult(Fz, coarse, types_fine[::FINE], hopf, special, _intervals(fine, types_fine, critical),
                       _lengths(fine, types_fine), result.max_psi, result.max_psi_V, simulated,
                       list(result.warnings), time.perf_counter() - clock)


# --------------------------------------------------------------------------- classify


def classify(config: Configuration | str, V: float, Fz: float, params: Parameters | None = None,
             v_range: tuple[float, float] = DEFAULT_V_RANGE, options: BifurcationOptions | None = None,
             result: BifurcationResult | None = None) -> dict[str, Any]:
    """Shimmy type and stable attractors at (V, Fz): the map's computation on the slice at Fz.

    ``result`` may pass an already computed diagram at this Fz over ``v_range``."""
    config = Configuration.parse(config)
    params = params if params is not None else Parameters()
    V, Fz = check_operating_point(V, Fz)
    v_min, v_max = check_range("v", v_range, V_RANGE, "m/s")
    if not v_min <= V <= v_max:
        raise InvalidParameterError("V", V, f"a number in [{v_min:g}, {v_max:g}] m/s (the diagram's range)")
    if result is None:
        result = bifurcation(config, Fz, v_min, v_max, params, options or BifurcationOptions(mesh_check=False))
    found = attractors_at(result, V)
    if not found:
        found = [simulated_attractor(config, V, Fz, params)]
    return {"config": config.value, "V": V, "Fz": Fz, "shimmy_type": shimmy_type(found), "attractors": found,
            "hopf_points": [h.V for h in result.hopf.hopf_points], "warnings": list(result.warnings),
            "version": __version__}


@dataclass
class StabilityMap:
    config: Configuration
    params: Parameters
    v_range: tuple[float, float]
    fz_range: tuple[float, float]
    V: np.ndarray
    Fz: np.ndarray
    types: list[list[str]]  # [i_Fz][j_V]
    slices: list[SliceResult]
    hopf: HopfCurvesResult
    cycles: dict[str, Any]  # fold and torus curves with their details (:func:`_cycle_curves_unit`)
    shading_Fz: np.ndarray  # rows of the shading (N), on the grid V
    shading: list[list[str]]  # [i_row][j_V]: types read off the slices along the curves
    shading_lengths: list[dict[str, float]]  # per row: measure (m/s) of each type, exact for the read-off
    shading_fallbacks: int  # row intervals read off the nearest slice at the same speed instead
    min_shimmy: dict[str, Any] | None
    executor: str
    elapsed_s: float
    warnings: list[str] = field(default_factory=list)

    @property
    def min_shimmy_Fz(self) -> float | None:
        return None if self.min_shimmy is None else self.min_shimmy["Fz"]

    @property
    def fold_curves(self) -> list[list[dict[str, float]]]:
        return self.cycles["fold_curves"]

    @property
    def torus_curves(self) -> list[list[dict[str, float]]]:
        return self.cycles["torus_curves"]

    @property
    def hopf_curves(self) -> list[list[dict[str, float]]]:
        return [[{"V": float(p[0]), "Fz": float(p[1])} for p in c.p] for c in self.hopf.curves]

    def type_at(self, V: float, Fz: float) -> str:
        """The type of the grid point nearest to (V, Fz)."""
        i = int(np.argmin(np.abs(self.Fz - Fz)))
        j = int(np.argmin(np.abs(self.V - V)))
        return self.types[i][j]

    def to_dict(self) -> dict[str, Any]:
        return {"config": self.config.value, "params": self.params.to_dict(),
                "v_range": list(self.v_range), "fz_range": list(self.fz_range),
                "hopf_curves": self.hopf_curves, "gh_points": self.hopf.gh_points,
                "double_hopf_points": self.hopf.double_hopf_points,
                "fold_curves": self.fold_curves, "torus_curves": self.torus_curves,
                "cycle_curves": self.cycles["curves"], "codim2_points": self.cycles["codim2_points"],
                "V": self.V.tolist(), "Fz": self.Fz.tolist(), "types": self.types,
                "min_shimmy_Fz": self.min_shimmy_Fz, "min_shimmy": self.min_shimmy,
                "slices": [s.to_dict() for s in self.slices],
                "shading": {"V": self.V.tolist(), "Fz": self.shading_Fz.tolist(), "types": self.shading,
                            "fallback_intervals": self.shading_fallbacks},
                "methods": {
                    "hopf_curves": "two-parameter continuation of Hopf points (extended system)",
                    "gh_points": "sign changes of the first Lyapunov coefficient along the Hopf curves "
                                 "(not defined with the particle damper: not smooth at x = 0)",
                    "double_hopf_points": "sign changes of the other eigenvalues' real parts along the Hopf curves",
                    "fold_curves": "two-parameter continuation of folds of cycles (minimally augmented system on the "
                                   "collocation mesh), exact in V and Fz",
                    "torus_curves": "two-parameter continuation of Neimark-Sacker points of cycles (minimally "
                                    "augmented system), exact in V and Fz",
                    "types": "stable attractors of each slice's diagram; simulation where none is stable",
                    "shading": "each row's intervals between the Hopf, fold and torus curves take the type of the "
                               "same interval on the nearest slice, mapped linearly (read off the curves)"},
                "executor": self.executor, "warnings": list(self.warnings), "elapsed_s": self.elapsed_s,
                "version": __version__}

    def write_csv(self, path) -> None:
        import csv

        with open(path, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["Fz_N", "V_m_s", "shimmy_type"])
            for Fz, row in zip(self.Fz, self.types, strict=True):
                for V, t in zip(self.V, row, strict=True):
                    w.writerow([f"{Fz:.10g}", f"{V:.10g}", t])


def _cycle_curves_unit(config, params, v_range, fz_range, loads) -> dict[str, Any]:
    """The fold and torus curves of a map, with their crossings of the slice loads (one unit: run in
    one process, its own units inline)."""
    result = cycle_curves(config, params, v_range, fz_range, kinds=("LPC", "NS"), loads=tuple(loads),
                          executor=InlineExecutor())
    data = result.to_dict()
    return {key: data[key] for key in ("fold_curves", "torus_curves", "curves", "codim2_points", "warnings")}


def _unit(task: tuple) -> Any:
    """One independent unit of a map (top level, so that process pools and Dask can ship it)."""
    if task[0] == "hopf_curves":
        _, config, params, v_range, fz_range = task
        return hopf_curves(config, params, v_range=v_range, fz_range=fz_range)
    if task[0] == "cycle_curves":
        return _cycle_curves_unit(*task[1:])
    _, config, Fz, v_min, v_max, n_v, params, options = task
    return map_slice(config, Fz, v_min, v_max, n_v, params, options)


def _describe(task: tuple) -> str:
    if task[0] in ("hopf_curves", "cycle_curves"):
        return {"hopf_curves": "Hopf curves", "cycle_curves": "fold and torus curves"}[task[0]]
    return f"slice Fz = {task[2] / 1e3:.4g} kN"


def stability_map(config: Configuration | str, v_range: tuple[float, float] = DEFAULT_V_RANGE,
                  fz_range: tuple[float, float] = DEFAULT_FZ_RANGE, resolution: int = 40,
                  params: Parameters | None = None, n_v: int = 100, executor=None,
                  progress: Callable[[float, str], None] | None = None,
                  options: BifurcationOptions | None = None) -> StabilityMap:
    """The (V, Fz) stability map of one configuration: ``resolution`` Fz slices, ``n_v`` speeds.

    ``executor`` is any :class:`concurrent.futures.Executor` (default: see :mod:`shimmy.analyses.executors`)."""
    clock = time.perf_counter()
    config = Configuration.parse(config)
    params = params if params is not None else Parameters()
    v_min, v_max = check_range("v", v_range, V_RANGE, "m/s")
    f_min, f_max = check_range("fz", fz_range, FZ_RANGE, "N")
    resolution = int(check_number("resolution", resolution, 2, 400, integer=True))
    n_v = int(check_number("n_v", n_v, 2, 2000, integer=True))
    options = options or BifurcationOptions(mesh_check=False)
    loads = np.linspace(f_min, f_max, resolution)
    # The curves go first: each one unit, longer than a slice.
    tasks = [("cycle_curves", config, params, (v_min, v_max), (f_min, f_max), [float(f) for f in loads]),
             ("hopf_curves", config, params, (v_min, v_max), (f_min, f_max))]
    tasks += [("slice", config, float(Fz), v_min, v_max, n_v, params, options) for Fz in loads]
    results = run_units(_unit, tasks, executor, progress, _describe,
                        lambda task: "slices" if task[0] == "slice" else "curve sets")
    cycles: dict[str, Any] = results[0]
    hopf: HopfCurvesResult = results[1]
    slices: list[SliceResult] = results[2:]
    warnings = list(hopf.warnings) + list(cycles.pop("warnings"))
    for s in slices:
        warnings += [f"Fz = {s.Fz:.6g} N: {w}" for w in s.warnings]
    boundaries = [(f"hopf{i}", c.p) for i, c in enumerate(hopf.curves)]
    for key in ("fold_curves", "torus_curves"):
        boundaries += [(f"{key}{i}", np.array([[p["V"], p["Fz"]] for p in c])) for i, c in enumerate(cycles[key])]
    rows = np.linspace(f_min, f_max, max(SHADING_ROWS, 4 * resolution))
    shading, lengths, fallbacks = map_shading.shade(slices, boundaries, slices[0].V, rows, (v_min, v_max))
    return StabilityMap(config, params, (v_min, v_max), (f_min, f_max), slices[0].V, loads,
                        [s.types for s in slices], slices, hopf, cycles, rows, shading, lengths, fallbacks,
                        _min_shimmy(hopf, cycles, slices), name_of(executor),
                        time.perf_counter() - clock, warnings)


def _min_shimmy(hopf: HopfCurvesResult, cycles: dict[str, Any], slices: list[SliceResult]) -> dict[str, Any] | None:
    """Lowest load with any shimmy: the located lowest point of the Hopf and fold curves, or the
    lowest slice with a type other than Stable, whichever is lower."""
    candidates = []
    low = hopf.fz_minimum
    if low is not None and any(c.p.size for c in hopf.curves):
        candidates.append({"Fz": low["Fz"], "V": low["V"], "source": "Hopf curve"})
    for c in cycles["curves"]:
        if c["kind"] == "LPC":
            candidates.append({"Fz": c["fz_min"]["Fz"], "V": c["fz_min"]["V"], "source": "fold-of-cycles curve"})
    for s in slices:
        if s.intervals:
            candidates.append({"Fz": s.Fz, "V": s.intervals[0]["V_start"], "source": "classified slice"})
            break
    return min(candidates, key=lambda c: c["Fz"]) if candidates else None
