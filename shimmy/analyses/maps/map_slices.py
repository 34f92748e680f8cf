"""The map's slices: the stable attractors of a bifurcation diagram at each speed, a slice's
shimmy types on the speed grid, and :func:`classify`, the shimmy type of one operating point.

A slice is a one-parameter bifurcation diagram in V at one load; its stable attractors at each V
(:func:`attractors_at`) are x = 0 where its eigenvalues say so and every periodic branch point with
all nontrivial Floquet multipliers inside the unit circle, with its mode (torsional / lateral /
both). Where neither x = 0 nor any cycle is stable, the attractor comes from a time simulation from
the standard start (:func:`simulated_attractor`). :mod:`shimmy.analyses.maps.stability_map` builds
the map from these slices and the continued curves.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...continuation import CYCLE_BIFURCATIONS, PointKind
from ...errors import InvalidParameterError
from ...model.configurations import Configuration
from ...model.parameters import DIAGRAM_V_RANGE, V_RANGE, Parameters, check_operating_point, check_range
from ...version import __version__
from ..core.response import LATERAL_SHARE, TORSION_SHARE, Mode, ResponseType, ShimmyType, shimmy_type
from ..diagrams.bifurcation import BifurcationOptions, BifurcationResult, bifurcation
from ..diagrams.cycle_curves import starts_of_diagram
from ..diagrams.mode_changes import ModeChange, locate_mode_changes
from .map_shading import type_at
from ...model.units import kn, mm

SHIMMY_TYPES = tuple(ShimmyType)
DEFAULT_V_RANGE = DIAGRAM_V_RANGE
#: Simulated V per slice at most where no stable equilibrium or cycle exists; the other grid
#: points of such a stretch take the answer of the nearest simulated one.
MAX_SIMULATIONS_PER_SLICE = 12
FALLBACK_T_END = 60.0  # s
#: Fine grid (per output grid step) on which speed intervals and region lengths are measured.
FINE = 10
#: Low-load band of the pure-torsion area metric.
BAND_FZ_MAX = 250.0e3  # N
BAND_V = DIAGRAM_V_RANGE  # m/s
#: Where x = 0 is stable, a "cycle" smaller than this (rad, m) is x = 0 itself: continuation with the
#: particle damper can run a branch on through its Hopf point along the trivial orbit (amplitudes
#: ~1e-100 observed). Where x = 0 is unstable, small cycles are real (with the PD they grow like
#: (V - V_H)^2 from the Hopf point) and count.
TRIVIAL_PSI = 1e-6
TRIVIAL_LATERAL = 1e-7


# --------------------------------------------------------------------------- attractors


def attractors_at(result: BifurcationResult, V: float) -> list[dict[str, Any]]:
    """The stable equilibria and limit cycles of a bifurcation diagram at speed V."""
    return attractors_on(result, np.array([float(V)]))[0]


def attractors_on(result: BifurcationResult, speeds: np.ndarray) -> list[list[dict[str, Any]]]:
    """:func:`attractors_at` at each of ``speeds`` (one pass over each branch for all of them): x = 0
    where no unstable interval holds V, then, branch by branch, every branch segment whose speeds
    bracket V, interpolated linearly, if stable (the nearer end's flag where the ends differ) with
    a mode."""
    speeds = np.asarray(speeds, float)
    found: list[list[dict[str, Any]]] = [[] for _ in speeds]
    equilibrium_stable = np.ones(speeds.size, bool)
    for a, b in result.hopf.unstable_intervals:
        equilibrium_stable &= ~((a <= speeds) & (speeds <= b))
    for g in np.nonzero(equilibrium_stable)[0]:
        found[g].append({"kind": "equilibrium", "mode": None, "max_psi": 0.0, "max_lateral": 0.0,
                         "period": None, "branch": 0})
    tol = 1e-7 * np.maximum(1.0, np.abs(speeds))  # end points located on a range bound to rounding
    for k, b in enumerate(result.branches):
        if b.kind != "periodic" or b.V.size < 2:
            continue
        first = np.arange(b.V.size - 1)
        if b.closed:  # a loop: its last orbit joins its first
            first = np.append(first, b.V.size - 1)
        second = (first + 1) % b.V.size
        v0s, v1s = b.V[first], b.V[second]
        lo, hi = np.minimum(v0s, v1s), np.maximum(v0s, v1s)
        inside = (lo[None, :] - tol[:, None] <= speeds[:, None]) & (speeds[:, None] <= hi[None, :] + tol[:, None]) \
            & (v0s != v1s)[None, :]
        gs, segs = np.nonzero(inside)  # by speed, then along the branch
        if gs.size == 0:
            continue
        i, j = first[segs], second[segs]
        v0, v1 = b.V[i], b.V[j]
        f = np.minimum(np.maximum((speeds[gs] - v0) / (v1 - v0), 0.0), 1.0)
        near = np.where(f <= 0.5, i, j)
        flags = np.asarray(b.stable, bool)
        stable = np.where(flags[i] == flags[j], flags[i], flags[near])
        amp = b.max_psi[i] + f * (b.max_psi[j] - b.max_psi[i])
        lateral = b.max_lateral[i] + f * (b.max_lateral[j] - b.max_lateral[i])
        period = b.period[i] + f * (b.period[j] - b.period[i])
        for h in np.nonzero(stable)[0]:
            mode = b.mode[near[h]] or b.mode[i[h]] or b.mode[j[h]]
            if mode is None:
                continue
            g = gs[h]
            if equilibrium_stable[g] and amp[h] <= TRIVIAL_PSI and lateral[h] <= TRIVIAL_LATERAL:
                continue  # a zero-amplitude end point, or a branch run on along a stable x = 0
            if amp[h] <= 0.0 and lateral[h] <= 0.0:
                continue  # the zero-amplitude end point at a Hopf point
            found[g].append({"kind": "limit cycle", "mode": mode, "max_psi": float(amp[h]),
                             "max_lateral": float(lateral[h]), "period": float(period[h]), "branch": k})
    return found


_RESPONSE_MODE = {ResponseType.TORSION: Mode.TORSIONAL, ResponseType.LATERAL: Mode.LATERAL,
                  ResponseType.BOTH: Mode.BOTH}


def simulated_attractor(config: Configuration, V: float, Fz: float, params: Parameters) -> dict[str, Any]:
    """The attractor reached from the standard start, for speeds with no stable equilibrium or cycle."""
    from ..core.simulation import simulate

    run = simulate(config, V, Fz, params=params, t_end=FALLBACK_T_END)
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
    max_psi: float | None
    max_psi_V: float | None
    simulated: list[float]  # V where the type came from a simulation
    warnings: list[str]
    elapsed_s: float
    #: the diagram's located LPC / NS / PD points with their orbits: starts of the map's curves
    #: (not in :meth:`to_dict`)
    starts: list = field(default_factory=list, repr=False)
    #: carried from the map of a nearby design (:mod:`shimmy.analyses.maps.warm_map`): intervals moved
    #: with the curves, Hopf points scanned again, no diagram (``max_psi`` None)
    carried: bool = False
    #: the design (parameters) its diagram was computed at (a warm start's record: a carried slice
    #: keeps its own; not in :meth:`to_dict`)
    computed_at: dict[str, float] | None = field(default=None, repr=False)
    #: the located mode changes its intervals end at, with their cycles (a warm start's record: a
    #: carried slice's relocated at its new design; not in :meth:`to_dict`)
    mode_changes: list[ModeChange] = field(default_factory=list, repr=False)

    def to_dict(self) -> dict[str, Any]:
        return {"Fz": self.Fz, "hopf_points": self.hopf_points, "special_points": self.special_points,
                "intervals": self.intervals, "lengths": self.lengths, "max_psi": self.max_psi,
                "max_psi_V": self.max_psi_V, "simulated_V": self.simulated, "warnings": self.warnings,
                "elapsed_s": self.elapsed_s, **({"carried": True} if self.carried else {})}


def speed_grids(v_min: float, v_max: float, n_v: int) -> tuple[np.ndarray, np.ndarray]:
    fine = np.linspace(v_min, v_max, (n_v - 1) * FINE + 1).round(10)  # no 6.800000000000001 in outputs
    return fine[::FINE].copy(), fine


def _slice_types(result: BifurcationResult, fine: np.ndarray, coarse_step: int, config: Configuration,
                 params: Parameters) -> tuple[list[str], list[list[dict]], list[float]]:
    """Types on the fine grid; stretches with no stable equilibrium or cycle are simulated at
    their output-grid points (at most MAX_SIMULATIONS_PER_SLICE, spread evenly)."""
    attractors = attractors_on(result, fine)
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
    the located Hopf / fold / torus point between them, if there is one (exact), else to the
    middle between them (a cycle's mode changing: :func:`map_slice` then moves it to the located
    change, :func:`at_mode_changes`), so that two intervals that meet share their end."""
    crit = np.sort(np.asarray(list(critical), float))

    def snap(inside: int, outside: int) -> float:
        lo, hi = sorted((fine[inside], fine[outside]))
        hits = crit[(crit >= lo) & (crit <= hi)]
        return float(hits[0]) if hits.size else float(0.5 * (lo + hi))

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


def type_lengths(fine: np.ndarray, types: list[str]) -> dict[str, float]:
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
            if s["kind"] in (*CYCLE_BIFURCATIONS, PointKind.BRANCH_POINT_OF_CYCLES):
                k = int(np.argmin(np.abs(b.V - s["V"])))
                points.append({"kind": s["kind"], "V": float(s["V"]), "mode": b.mode[k]})
    return points


def map_slice(config: Configuration | str, Fz: float, *, params: Parameters, v_range: tuple[float, float], n_v: int,
              options: BifurcationOptions | None = None, result=None) -> SliceResult:
    """The map's computation on one load: diagram in V (``result`` if already computed, with the same
    load, range and parameters), types on the grid, special points."""
    clock = time.perf_counter()
    config = Configuration.parse(config)
    options = options or BifurcationOptions(mesh_check=False)
    result = result or bifurcation(config, Fz, v_range=v_range, params=params, options=options)
    coarse, fine = speed_grids(*v_range, n_v)
    types_fine, _, simulated = _slice_types(result, fine, FINE, config, params)
    hopf = [{"V": h.V, "frequency_hz": h.frequency_hz, "criticality": h.criticality.value}
            for h in result.hopf.hopf_points]
    special = _special_points(result)
    critical = [h["V"] for h in hopf] + [p["V"] for p in special]
    intervals = _intervals(fine, types_fine, critical)
    changes: list[ModeChange] = []
    if _mode_ends(intervals, critical, fine):
        intervals, changes = at_mode_changes(intervals, locate_mode_changes(result), critical, fine)
        if changes:
            types_fine = [type_at(intervals, float(v)) for v in fine]
    return SliceResult(Fz, coarse, types_fine[::FINE], hopf, special, intervals,
                       type_lengths(fine, types_fine), result.max_psi, result.max_psi_V, simulated,
                       list(result.warnings), time.perf_counter() - clock, starts_of_diagram(result, Fz),
                       mode_changes=changes)


def _mode_ends(intervals: list[dict[str, Any]], critical, fine: np.ndarray) -> list[float]:
    """The intervals' inner ends at no located point: where a cycle's mode changes (a fine-grid midpoint)."""
    exact = set(critical) | {float(fine[0]), float(fine[-1])}
    return sorted({v for iv in intervals for v in (iv["V_start"], iv["V_end"]) if v not in exact})


def at_mode_changes(intervals: list[dict[str, Any]], changes: list[ModeChange], critical,
                    fine: np.ndarray) -> tuple[list[dict[str, Any]], list[ModeChange]]:
    """The intervals with each end where a cycle's mode changes (put halfway between the fine-grid points
    around the diagram's change) moved to the located change it stands for: the nearest one located
    between the diagram's two points around it (a fine step either side) whose threshold fits the types
    either side (Torsion | Both: 0.8, Both | Lateral: 0.2, any other pair: either), each used once, moved
    only as far as the ends beside it, where they stand by then, allow. (The intervals, the changes used.)"""
    step = float(fine[1] - fine[0]) if fine.size > 1 else 0.0
    ends = _mode_ends(intervals, critical, fine)
    where = {v: v for iv in intervals for v in (iv["V_start"], iv["V_end"])}  # each end: where it stands now
    used: list[ModeChange] = []
    for end in ends:
        allowed = _thresholds(intervals, end)
        near = [c for c in changes if c not in used and c.threshold in allowed
                and min(c.bracket) - step <= end <= max(c.bracket) + step]
        if not near:
            continue
        change = min(near, key=lambda c: abs(c.V - end))
        lo, hi = sorted((end, change.V))
        if any(lo <= v <= hi for was, v in where.items() if was != end):
            continue  # it would reach another end: left where it was
        where[end] = change.V
        used.append(change)
    if not used:
        return intervals, []
    return [{**iv, "V_start": where[iv["V_start"]], "V_end": where[iv["V_end"]]} for iv in intervals], used


def _thresholds(intervals: list[dict[str, Any]], end: float) -> set[float]:
    """The torsional shares whose crossing can change the type at ``end`` (the types either side)."""
    below = next((str(iv["type"]) for iv in intervals if iv["V_end"] == end), "Stable")
    above = next((str(iv["type"]) for iv in intervals if iv["V_start"] == end), "Stable")
    pair = {below, above}
    if pair == {ShimmyType.TORSION.value, ShimmyType.BOTH.value}:
        return {TORSION_SHARE}
    if pair == {ShimmyType.BOTH.value, ShimmyType.LATERAL.value}:
        return {LATERAL_SHARE}
    return {TORSION_SHARE, LATERAL_SHARE}


# --------------------------------------------------------------------------- classify


def classify(config: Configuration | str, V: float, Fz: float, *, params: Parameters | None = None,
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
        result = bifurcation(config, Fz, v_range=(v_min, v_max), params=params,
                             options=options or BifurcationOptions(mesh_check=False))
    found = attractors_at(result, V)
    if not found:
        found = [simulated_attractor(config, V, Fz, params)]
    return {"config": config.value, "V": V, "Fz": Fz, "shimmy_type": shimmy_type(found), "attractors": found,
            "hopf_points": [h.V for h in result.hopf.hopf_points], "warnings": list(result.warnings),
            "version": __version__}


def classification_summary(result: dict[str, Any]) -> str:
    """The lines ``python -m shimmy classify`` prints for a :func:`classify` answer: the shimmy type, then
    each stable attractor."""
    lines = [f"{result['config']} at V = {result['V']:g} m/s, Fz = {kn(result['Fz'])}: {result['shimmy_type']}"]
    for a in result["attractors"]:
        if a["kind"] == "equilibrium":
            lines.append("  stable: straight rolling x = 0")
        else:
            lines.append(f"  stable: {a['kind']} ({a['mode']}), max |psi| {a['max_psi']:.5g} rad, "
                         f"max |l_g delta| {mm(a['max_lateral'], 5)}")
    return "\n".join(lines)
