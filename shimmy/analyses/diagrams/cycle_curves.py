"""The gear's curves of cycle bifurcations in (V, Fz): every fold-of-cycles (LPC), torus (NS) and
period-doubling (PD) curve of a configuration in a box, each continued to its ends.

Found without being told where to look, from four kinds of start, each a located special point
of a one-parameter branch in V at some load:

1. generalised Hopf (GH) points of the Hopf curves (a fold curve is born there): the branch from
   the Hopf point just beside the GH point, on either side, stopped at its first LPC;
2. double-Hopf points (a torus curve is born there): the branches from both Hopf points just
   beside it, stopped at their first NS point;
3. one-parameter diagrams on a few loads (every LPC, NS and PD point of every branch), whose
   seeds include large-amplitude starts (psi = 0.2 rad, l_g delta = 0.1 m) that reach cycles no
   Hopf point feeds (the isola between two folds above ~720 kN).

A start that lies on a curve already continued is skipped, so each curve is continued once
(:func:`shimmy.continuation.cycle_curve`: minimally augmented systems on the collocation mesh
of the one-parameter branch, so its points agree with the one-parameter points to the
location tolerance). Along each curve: its crossings of requested loads, its turning points
in Fz and its codimension-2 points, located.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field
from concurrent.futures import Executor
from typing import Any, Callable

import numpy as np

from ...version import __version__
from ...continuation import (CYCLE_BIFURCATIONS, ContinuationOptions, CycleCurve, CycleCurveOptions, PointKind,
                             SpecialPoint, cycle_curve, join_halves, start_beside)
from ...continuation.cycle_curves.guide import Guide, decode, encode, guide_points
from ...continuation.errors import ContinuationError
from ...continuation.periodic_orbits import FOLD_PAIR_ANGLE
from ...errors import InvalidParameterError
from ...model.configurations import Configuration
from ...model.equations import build_model
from ...model.units import kn, kn_range
from ...model.parameters import DIAGRAM_V_RANGE, FZ_RANGE, V_RANGE, Parameters, check_number, check_range
from .bifurcation import STATE_SCALE, V_SCALE, BifurcationOptions, bifurcation, orbit_limits
from .hopf_curves import gear_two_parameter_field, hopf_curves
from ..core.polylines import near_polyline
from ..core.executors import describe_work_unit, open_executor, run_dynamic, run_work_unit
from ..core.stability import hopf_points

KINDS = CYCLE_BIFURCATIONS
KEY_OF_KIND = {PointKind.FOLD_OF_CYCLES: "fold_curves", PointKind.TORUS: "torus_curves",
               PointKind.PERIOD_DOUBLING: "pd_curves"}
#: Marks on a cycle curve that are not codimension-2 points: its ends, its turns and crossings in Fz
MARKS = (PointKind.END, PointKind.ZERO_AMPLITUDE, PointKind.P2_TURN, PointKind.P2_MARK)
ENDS = (PointKind.END, PointKind.ZERO_AMPLITUDE)
#: each kind of curve in words (progress and status lines)
PLAIN = {PointKind.FOLD_OF_CYCLES: "fold-of-cycles", PointKind.TORUS: "torus",
         PointKind.PERIOD_DOUBLING: "period-doubling"}
FZ_SCALE = 1.0e5  # N: a unit step in the curves' arclength is ~10 m/s or ~100 kN
CURVE_OPTIONS = CycleCurveOptions(continuation=ContinuationOptions(ds=0.05, ds_max=2.0, max_steps=400,
                                                                   max_angle=0.3))
#: A warm trace's first step: its seed is an interior point of a curve already traced, whose points were
#: steps of 0.1-1.4 apart, not a located point of a one-parameter branch; starting at the cold start's
#: 0.05 spent its first few steps growing to that (the nes map's four curves again: 4.98 s of work at
#: 0.05, 4.46 s at 0.15, 4.43 s at 0.3, the same ends; 0.15: the step control takes over from there).
WARM_FIRST_STEP = 0.15
#: A torus start whose multiplier pair lies within this angle (rad per period) of +1 or -1 is a strong
#: resonance, not a torus: nes_pd's diagram at 278.5 kN reported a torus point at its fold of cycles at
#: 130.25 m/s with the pair at 6.6e-6 rad (two multipliers at +1), where no torus curve passes (the
#: diagrams no longer report such points: the engine's threshold, the same angle).
RESONANCE_ANGLE = FOLD_PAIR_ANGLE
BESIDE = 0.015  # relative offset in Fz from a GH / double-Hopf point to the Hopf point a start branch leaves
START_STEPS = 80  # step budget of a start branch
SCAN_FRACTIONS = (0.3, 0.6, 0.9)  # loads of the one-parameter diagrams, as fractions of the box in Fz


@dataclass(eq=False)  # compared by identity: list.remove takes the very start
class Start:
    kind: PointKind
    point: SpecialPoint  # located on a branch in V, with its solution
    Fz: float
    ncol: int
    origin: str
    #: next to the codimension-2 point it was found beside, where a curve is born: continued
    #: before the other starts (a diagram's points mostly lie on curves already started)
    eager: bool = False
    from_diagram: bool = False  # a point of a one-parameter diagram (a slice or a scan)


@dataclass
class GearCycleCurve:
    kind: PointKind
    curve: CycleCurve
    origin: str

    def points(self, l_g: float) -> list[dict[str, float]]:
        c = self.curve
        psi = np.maximum(np.abs(c.x_max[:, 0]), np.abs(c.x_min[:, 0]))
        lateral = l_g * np.maximum(np.abs(c.x_max[:, 2]), np.abs(c.x_min[:, 2]))
        return [{"V": float(p[0]), "Fz": float(p[1]), "period": float(T), "max_psi": float(a),
                 "max_lateral": float(b)} for p, T, a, b in zip(c.p, c.period, psi, lateral, strict=True)]


def _located_point(s: SpecialPoint, l_g: float) -> dict[str, Any]:
    out: dict[str, Any] = {"kind": s.kind, "V": s.p, "Fz": s.data["p2"]}
    if s.located is not None:
        out["located"] = s.located
    if "x_max" in s.data:
        xmax, xmin = np.array(s.data["x_max"]), np.array(s.data["x_min"])
        out.update({"period": s.data["period"], "max_psi": float(max(abs(xmax[0]), abs(xmin[0]))),
                    "max_lateral": float(l_g * max(abs(xmax[2]), abs(xmin[2])))})
    return out


@dataclass
class CycleCurvesResult:
    config: Configuration
    params: Parameters
    v_range: tuple[float, float]
    fz_range: tuple[float, float]
    kinds: tuple[PointKind, ...]
    curves: list[GearCycleCurve]
    gh_points: list[dict[str, float]]
    double_hopf_points: list[dict[str, float]]
    loads: tuple[float, ...]
    elapsed_s: float
    starts_tried: int
    warnings: list[str] = field(default_factory=list)

    def of_kind(self, kind: PointKind) -> list[GearCycleCurve]:
        return [c for c in self.curves if c.kind == kind]

    def codim2_points(self) -> list[dict[str, Any]]:
        """GH and double-Hopf points of the Hopf curves, and those located on the cycle curves
        (one entry per point: the same point found on two curves is listed once)."""
        out = [{"kind": PointKind.GENERALISED_HOPF, "V": g["V"], "Fz": g["Fz"]} for g in self.gh_points]
        out += [{"kind": PointKind.DOUBLE_HOPF, "V": g["V"], "Fz": g["Fz"]} for g in self.double_hopf_points]
        for c in self.curves:
            for s in c.curve.special_points:
                if s.kind in MARKS or s.located is False:
                    continue  # ends and load marks are not codimension-2 points; unlocated ones stay in "curves"
                entry = {"kind": s.kind, "V": s.p, "Fz": s.data["p2"]}
                # the same point on two curves (LPNS on a fold and a torus curve) agrees to the
                # location accuracy of the multipliers (~1e-5): one entry
                if not any(e["kind"] == entry["kind"] and _close(e, entry, 1e-3) for e in out):
                    out.append(entry)
        return out

    def to_dict(self) -> dict[str, Any]:
        l_g = self.params.gear.l_g
        out: dict[str, Any] = {"config": self.config.value, "params": self.params.to_dict(),
                               "v_range": list(self.v_range), "fz_range": list(self.fz_range),
                               "kinds": list(self.kinds)}
        for kind in KINDS:
            out[KEY_OF_KIND[kind]] = [c.points(l_g) for c in self.of_kind(kind)] if kind in self.kinds else []
        details = []
        for c in self.curves:
            special = c.curve.special_points
            turns = [_located_point(s, l_g) | {"turn": s.data["turn"]} for s in special if s.kind == PointKind.P2_TURN]
            fz = c.curve.p[:, 1]
            lowest = min([{"V": float(c.curve.p[int(np.argmin(fz)), 0]), "Fz": float(fz.min())}]
                         + [t for t in turns if t["turn"] == "min"], key=lambda e: e["Fz"])
            highest = max([{"V": float(c.curve.p[int(np.argmax(fz)), 0]), "Fz": float(fz.max())}]
                          + [t for t in turns if t["turn"] == "max"], key=lambda e: e["Fz"])
            details.append({
                "kind": c.kind, "origin": c.origin, "points": len(c.curve.p), "closed": c.curve.closed,
                "stop_reasons": c.curve.stop_reasons, "steps": c.curve.steps,
                "fz_min": {"V": lowest["V"], "Fz": lowest["Fz"]}, "fz_max": {"V": highest["V"], "Fz": highest["Fz"]},
                "turning_points": turns,
                "crossings": sorted((_located_point(s, l_g) for s in special if s.kind == PointKind.P2_MARK),
                                    key=lambda e: (e["Fz"], e["V"])),
                "ends": [_located_point(s, l_g) for s in special if s.kind in ENDS],
                "codim2_points": [_located_point(s, l_g) for s in special
                                  if s.kind not in MARKS],
            })
        out.update({"curves": details, "codim2_points": self.codim2_points(), "gh_points": self.gh_points,
                    "double_hopf_points": self.double_hopf_points, "loads": list(self.loads),
                    "starts_tried": self.starts_tried, "warnings": list(self.warnings),
                    "elapsed_s": self.elapsed_s, "version": __version__,
                    "method": "two-parameter continuation of each curve (minimally augmented systems with bordered "
                              "test functions on the collocation mesh), started from GH and double-Hopf points, "
                              "one-parameter diagrams and large-amplitude starts; points exact to the location "
                              "tolerance (1e-9 in the defining equations)"})
        return out

    def summary_text(self) -> str:
        """The short table ``python -m shimmy curves`` prints: the curves of each kind, each curve's range of
        loads, crossings and ends, the codimension-2 points."""
        data = self.to_dict()
        lines = [f"{self.config.value}: cycle-bifurcation curves in V {self.v_range[0]:g}..{self.v_range[1]:g} m/s, "
                 f"Fz {kn_range(*self.fz_range)} ({self.elapsed_s:.2f} s, "
                 f"{self.starts_tried} curve starts)"]
        names = {PointKind.FOLD_OF_CYCLES: "fold", PointKind.TORUS: "torus",
                 PointKind.PERIOD_DOUBLING: "period-doubling"}
        for kind in self.kinds:
            lines.append(f"  {names[kind]} curves: {len(data[KEY_OF_KIND[kind]])}")
        for i, c in enumerate(data["curves"], start=1):
            lines.append(f"  {i}. {names[c['kind']]} curve from {c['origin']}: {c['points']} points, Fz "
                         f"{kn(c['fz_min']['Fz'])} (V {c['fz_min']['V']:.5g}) .. {kn(c['fz_max']['Fz'])} "
                         f"(V {c['fz_max']['V']:.5g})")
            for x in c["crossings"]:
                lines.append(f"       at Fz = {kn(x['Fz'])}: V = {x['V']:.6f} m/s, period {x['period']:.5g} s, "
                             f"max |psi| {x['max_psi']:.4g} rad")
            for e in c["stop_reasons"]:
                lines.append(f"       end: {e}")
        for p in data["codim2_points"]:
            lines.append(f"  {p['kind']:<5} V = {p['V']:.6g} m/s, Fz = {kn(p['Fz'])}")
        lines += [f"  warning: {w}" for w in self.warnings]
        return "\n".join(lines)


def _close(a: dict, b: dict, tol: float) -> bool:
    return abs(a["V"] - b["V"]) <= tol * V_SCALE and abs(a["Fz"] - b["Fz"]) <= tol * FZ_SCALE


class CurveSearch:
    """The state of a search for every curve of some kinds in a box: the starts found so far,
    the curves continued from them, the continuations under way. Units (:data:`SearchUnit`) come
    from :meth:`start_units` (branches beside codimension-2 points of the Hopf curves) and from
    :meth:`continuations`; whoever runs them hands back their results (:meth:`add_beside`,
    :meth:`add_source` for a diagram's points, :meth:`add_curve`).

    A start is continued only if it lies on no curve known; one curve of each kind is under way
    at a time (two starts may lie on one curve, and which do is known only once it is continued:
    two double-Hopf points joined by a torus curve); starts born at a codimension-2 point go
    first, in the order of those points; a diagram's starts wait until every diagram expected
    (:meth:`expect_sources`), the Hopf curves and every branch beside a point are in, then go by
    load and speed within each batch of diagrams.
    So the curves, and the start each is continued from, do not depend on the order in which
    units finish: a map or a set of curves is the same on any executor.
    :func:`cycle_curves` and the stability maps both drive it."""

    def __init__(self, config: Configuration, params: Parameters, box, kinds: tuple[PointKind, ...],
                 loads: tuple[float, ...]):
        self.config, self.params, self.box, self.kinds, self.loads = config, params, box, kinds, loads
        self.gh: list[dict[str, float]] = []
        self.hh: list[dict[str, Any]] = []
        self.starts: list[Start] = []
        self.running: list[Start] = []
        self.curves: list[GearCycleCurve] = []
        self.warnings: list[str] = []
        self.tried = 0
        self.hopf_pending = True  # the Hopf curves (and so the units beside their points) not yet in
        self.beside_order: list[BesideUnit] = []  # the units beside codimension-2 points, in order
        self.beside_in: dict[int, tuple[list[Start], list[str]]] = {}
        self.beside_taken = 0
        self.sources_pending = 0  # diagrams expected and not yet in
        self.source_buffer: list[Start] = []

    def start_units(self, hopf) -> list[BesideUnit]:
        """The branches beside the GH points (fold curves) and double-Hopf points (torus curves)."""
        self.gh = [{"V": g.p[0], "Fz": g.p[1]} for c in hopf.curves for g in c.points_of(PointKind.GENERALISED_HOPF)]
        for c in hopf.curves:
            for g in c.points_of(PointKind.DOUBLE_HOPF):
                entry = {"V": g.p[0], "Fz": g.p[1], "omega": g.data["omega"], "omega2": g.data["omega2"]}
                if not any(_close(entry, e, 1e-4) for e in self.hh):
                    self.hh.append(entry)
        units = [BesideUnit(self.config, self.params, g, PointKind.FOLD_OF_CYCLES, self.box,
                            f"beside the GH point at V = {g['V']:.5g} m/s, Fz = {kn(g['Fz'])}")
                 for g in self.gh if PointKind.FOLD_OF_CYCLES in self.kinds]
        units += [BesideUnit(self.config, self.params, g, PointKind.TORUS, self.box,
                             f"beside the double-Hopf point at V = {g['V']:.5g} m/s, Fz = {kn(g['Fz'])}")
                  for g in self.hh if PointKind.TORUS in self.kinds]
        self.hopf_pending = False
        self.beside_order += units
        return units

    def _usable(self, starts: list[Start]) -> list[Start]:
        return [s for s in starts if s.kind in self.kinds and s.point.solution is not None]

    def add_beside(self, unit: BesideUnit, starts: list[Start], warnings: list[str]) -> None:
        """A unit beside a codimension-2 point is in; its starts count in the order of the points."""
        self.beside_in[next(k for k, u in enumerate(self.beside_order) if u is unit)] = (starts, warnings)
        while self.beside_taken in self.beside_in:
            starts, warnings = self.beside_in.pop(self.beside_taken)
            self.starts += self._usable(starts)
            self.warnings += list(warnings)
            self.beside_taken += 1

    def expect_sources(self, count: int) -> None:
        """``count`` more diagrams will hand in their starts (:meth:`add_source`)."""
        self.sources_pending += count

    def add_source(self, starts: list[Start], warnings: list[str] = ()) -> None:
        """A diagram's starts; they count once every diagram expected is in."""
        self.source_buffer += self._usable(starts)
        self.warnings += list(warnings)
        self.sources_pending -= 1
        if self.sources_pending <= 0:
            self.sources_pending = 0
            self.starts += sorted(self.source_buffer, key=lambda s: (s.Fz, s.point.p, s.kind))
            self.source_buffer = []

    def _gathering(self) -> bool:
        return self.hopf_pending or self.beside_taken < len(self.beside_order) or self.sources_pending > 0

    def _may_go(self, start: Start) -> bool:
        """Born at a point: at once; another start beside a point: once every branch beside a point
        is in; a diagram's: once every diagram is in, too."""
        if start.eager:
            return True
        if self.hopf_pending or self.beside_taken < len(self.beside_order):
            return False
        return not (start.from_diagram and self.sources_pending > 0)

    def add_curve(self, start: Start, curve: GearCycleCurve | None, warning: str | None) -> None:
        self.running.remove(start)
        self.tried += 1
        if warning:
            self.warnings.append(warning)
        elif curve is not None and not any(same_curve(curve, c, self.params.gear.l_g) for c in self.curves):
            self.curves = with_curve(self.curves, curve, self.params.gear.l_g)

    def idle(self) -> bool:
        """Nothing under way, waiting or expected: the curves stand as they are."""
        return not (self.running or self.starts or self._gathering())

    def continuations(self) -> list[ContinueUnit]:
        """Units continuing the waiting starts that may (see the class)."""
        l_g = self.params.gear.l_g
        self.starts = [s for s in self.starts
                       if not any(_on_curve(c, s, l_g) for c in self.curves if c.kind == s.kind)]
        units = []
        for s in sorted(self.starts, key=lambda s: (not s.eager, s.from_diagram)):
            if any(r.kind == s.kind for r in self.running) or not self._may_go(s):
                continue
            self.starts.remove(s)
            self.running.append(s)
            units.append(ContinueUnit(self.config, self.params, s, self.box, self.loads))
        return units

    def result(self, elapsed_s: float) -> CycleCurvesResult:
        (v_lo, v_hi), (f_lo, f_hi) = self.box
        hh = [{"V": e["V"], "Fz": e["Fz"], "omega": e["omega"], "omega2": e["omega2"]} for e in self.hh]
        curves = sorted(self.curves, key=lambda c: KINDS.index(c.kind))  # each kind's in the order continued
        return CycleCurvesResult(self.config, self.params, (v_lo, v_hi), (f_lo, f_hi), self.kinds, curves,
                                 self.gh, hh, self.loads, elapsed_s, self.tried, sorted(self.warnings))


@dataclass(frozen=True, eq=False)
class BesideUnit:
    """The branches beside one codimension-2 point of the Hopf curves: (starts, warnings)."""

    config: Configuration
    params: Parameters
    point: dict[str, Any]
    kind: str
    box: tuple[tuple[float, float], tuple[float, float]]
    origin: str

    def run(self) -> tuple[list[Start], list[str]]:
        model = build_model(self.config, self.params)
        return _starts_beside(self.config, model, self.params, self.point, self.kind, self.box[0], self.box[1],
                              self.origin), []

    def describe(self) -> str:
        where = "GH" if self.kind == PointKind.FOLD_OF_CYCLES else "double-Hopf"
        return (f"cycles beside the {where} point at V = {self.point['V']:.4g} m/s, "
                f"Fz = {self.point['Fz'] / 1e3:.4g} kN (where a {PLAIN[self.kind]} curve starts)")

    def hand_in(self, search: CurveSearch, result: tuple[list[Start], list[str]]) -> None:
        search.add_beside(self, *result)


@dataclass(frozen=True, eq=False)
class ScanUnit:
    """The diagram and the large-amplitude starts at one load: (starts, warnings)."""

    config: Configuration
    params: Parameters
    Fz: float
    box: tuple[tuple[float, float], tuple[float, float]]

    def run(self) -> tuple[list[Start], list[str]]:
        try:
            diagram = bifurcation(self.config, self.Fz, v_range=self.box[0], params=self.params,
                                  options=BifurcationOptions(mesh_check=False))
        except ContinuationError as exc:
            return [], [f"diagram at Fz = {kn(self.Fz)} failed: {exc}"]
        return starts_of_diagram(diagram, self.Fz), []

    def describe(self) -> str:
        return f"diagram and large-amplitude starts at Fz = {self.Fz / 1e3:.4g} kN"

    def hand_in(self, search: CurveSearch, result: tuple[list[Start], list[str]]) -> None:
        search.add_source(*result)


@dataclass(frozen=True, eq=False)
class ContinueUnit:
    """One curve continued from one start: (curve or None, warning or None)."""

    config: Configuration
    params: Parameters
    start: Start
    box: tuple[tuple[float, float], tuple[float, float]]
    loads: tuple[float, ...]

    def run(self) -> tuple[GearCycleCurve | None, str | None]:
        return continue_start(self.config, self.params, self.start, self.box, self.loads)

    def describe(self) -> str:
        return (f"{PLAIN[self.start.kind]} curve from V = {self.start.point.p:.4g} m/s, "
                f"Fz = {self.start.Fz / 1e3:.4g} kN")

    def hand_in(self, search: CurveSearch, result: tuple[GearCycleCurve | None, str | None]) -> None:
        search.add_curve(self.start, *result)


def reversed_curve(curve: GearCycleCurve) -> GearCycleCurve:
    """The same curve with its points in the opposite order (its special points' indices with them)."""
    c = curve.curve
    last = len(c.p) - 1
    flipped = CycleCurve(c.kind, c.p[::-1].copy(), c.period[::-1].copy(), c.x_max[::-1].copy(), c.x_min[::-1].copy(),
                         c.kappa[::-1].copy(), c.multipliers[::-1].copy(), c.solutions[::-1], c.guided,
                         special_points=sorted((dataclasses.replace(s, index=last - s.index) for s in c.special_points),
                                               key=lambda s: s.index),
                         stops=list(c.stops)[::-1], steps=c.steps, closed=c.closed)
    return GearCycleCurve(curve.kind, flipped, curve.origin)


@dataclass(frozen=True)
class CurveSeed:
    """A point of a continued curve with its cycle (collocation mesh and u = (x, T, V)), from which
    the same curve is continued again at a nearby design (:class:`WarmUnit`): a point where the
    curve crosses its load most steeply, so that a Newton correction at that load finds it."""

    kind: PointKind
    origin: str
    mesh: np.ndarray
    u: np.ndarray
    Fz: float
    ncol: int
    kappa: float | None
    #: the amplitudes (state scales) at the curve's zero-amplitude ends, its first and its last point
    #: (None at an end that is not one): a trace from the seed towards such an end stops only below
    #: it. Where a trace ends near a GH or double-Hopf point depends on the largest amplitude it met,
    #: so on where it began: traced from its large cycles, a torus curve of nes_pd stopped at 116.7 m/s;
    #: from a slice's small cycle at 120.6 m/s it ran on to 123.2 m/s, next to the double-Hopf point
    #: at 123.5 m/s, and the warm map missed the slices' torus points in between
    end_amplitudes: tuple[float | None, float | None] = (None, None)
    #: whether the trace towards higher Fz from the seed runs towards the curve's last point
    plus_to_last: bool = True
    #: the curve's points from the seed on, each way ({+1: the way Fz first rises, -1: the other}; a
    #: closed curve's all round), each (mesh points, u = (x, T, V, Fz[, kappa])): what the traces
    #: from the seed follow (:mod:`~shimmy.continuation.cycle_curves.guide`); none from an older cache
    guides: dict[int, list[tuple[np.ndarray, np.ndarray]]] | None = field(default=None, repr=False, compare=False)

    @classmethod
    def of(cls, curve: GearCycleCurve, n: int) -> CurveSeed:
        """The seed of a curve of an ``n``-state model: of its interior points (two steps from either
        end where it has them) whose cycle is at least a third of the curve's largest (near a GH or
        double-Hopf point the cycles shrink to x = 0 and a correction there is ill-conditioned), the
        one whose chord to its neighbours is most nearly along Fz."""
        c = curve.curve
        p = c.p / np.array([V_SCALE, FZ_SCALE])
        count = len(p)
        amplitude = np.max(0.5 * (c.x_max - c.x_min) / STATE_SCALE[:n], axis=1)
        inner = list(range(2, count - 2)) or list(range(count))
        inner = [i for i in inner if amplitude[i] >= amplitude.max() / 3.0] or inner

        def steepness(i: int) -> float:
            d = p[min(i + 1, count - 1)] - p[max(i - 1, 0)]
            return abs(d[1]) / max(float(np.hypot(*d)), 1e-300)

        i = max(inner, key=steepness)
        mesh, u = c.solutions[i]
        ntst = len(mesh) - 1
        ncol = int(round(((len(u) - 2) / n - 1) / ntst))
        kappa = float(c.kappa[i]) if np.isfinite(c.kappa[i]) else None
        ends: list[float | None] = [None, None]
        for q in c.special_points:
            if q.kind == PointKind.ZERO_AMPLITUDE:
                ends[0 if q.index <= (count - 1) / 2 else 1] = float(q.data["amplitude"])
        rising = c.p[min(i + 1, count - 1), 1] - c.p[max(i - 1, 0), 1] >= 0
        return cls(curve.kind, curve.origin, np.asarray(mesh, float), np.asarray(u, float), float(c.p[i, 1]), ncol,
                   kappa, (ends[0], ends[1]), bool(rising), guide_points(c, i, bool(rising)))

    def to_dict(self) -> dict[str, Any]:
        return {"kind": self.kind.value, "origin": self.origin, "mesh": self.mesh.tolist(), "u": self.u.tolist(),
                "Fz": self.Fz, "ncol": self.ncol, "kappa": self.kappa, "end_amplitudes": list(self.end_amplitudes),
                "plus_to_last": self.plus_to_last,
                **({} if self.guides is None else
                   {"guides": {str(d): [[encode(m), encode(u)] for m, u in points]
                               for d, points in self.guides.items()}})}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> CurveSeed:
        return cls(PointKind(data["kind"]), str(data["origin"]), np.asarray(data["mesh"], float),
                   np.asarray(data["u"], float), float(data["Fz"]), int(data["ncol"]),
                   None if data["kappa"] is None else float(data["kappa"]),
                   tuple(None if a is None else float(a) for a in data.get("end_amplitudes", (None, None))),
                   bool(data.get("plus_to_last", True)),
                   None if "guides" not in data else
                   {int(d): [(decode(m), decode(u)) for m, u in points] for d, points in data["guides"].items()})


@dataclass(frozen=True, eq=False)
class WarmUnit:
    """A curve of a nearby design continued again at this one from its seed: (curve or None,
    warning or None). The seed is corrected by Newton at its load, then the curve traced both
    ways, each step predicted from the old curve's next point where the seed has them
    (:mod:`~shimmy.continuation.cycle_curves.guide`) and taken as from any start (its points,
    crossings and codimension-2 points those of the curve at this design, to the location
    tolerance). With ``direction`` +1 or -1 only that half
    is traced (a :class:`~shimmy.continuation.cycle_curves.CycleCurve` half, or None and a
    warning): the two halves run as two units and :func:`joined_halves` makes the curve."""

    config: Configuration
    params: Parameters
    seed: CurveSeed
    box: tuple[tuple[float, float], tuple[float, float]]
    loads: tuple[float, ...]
    direction: int = 0  # 0: both ways

    def run(self) -> tuple[GearCycleCurve | None, str | None]:
        s = self.seed
        data = {"x_max": [], "x_min": []}
        if s.kappa is not None:
            data["torus_angle"] = math.acos(s.kappa)
        point = SpecialPoint(s.kind, float(s.u[-1]), 0, data, solution=(s.mesh, s.u))
        start = Start(s.kind, point, s.Fz, s.ncol, s.origin)
        first, last = s.end_amplitudes
        towards = {1: last if s.plus_to_last else first, -1: first if s.plus_to_last else last}
        end = towards.get(self.direction, min((a for a in (first, last) if a is not None), default=None))
        options = dataclasses.replace(CURVE_OPTIONS, continuation=dataclasses.replace(CURVE_OPTIONS.continuation,
                                                                                      ds=WARM_FIRST_STEP))
        if end is not None:
            options = dataclasses.replace(options, amplitude_end_below=end)
        directions = (self.direction,) if self.direction else (1, -1)
        n = self.config.n_states
        guides = None if s.guides is None else {d: Guide(s.guides[d], s.ncol, n) for d in directions}
        return continue_start(self.config, self.params, start, self.box, self.loads, directions, options, guides)

    def describe(self) -> str:
        half = {1: ", towards higher Fz", -1: ", towards lower Fz"}.get(self.direction, "")
        return (f"{PLAIN[self.seed.kind]} curve of the nearby design again, from V = {self.seed.u[-1]:.4g} m/s, "
                f"Fz = {self.seed.Fz / 1e3:.4g} kN{half}")


def joined_halves(plus: tuple[GearCycleCurve | None, str | None], minus: tuple[GearCycleCurve | None, str | None]
                  ) -> tuple[GearCycleCurve | None, str | None]:
    """The curve from the results of the two half units of one seed (:class:`WarmUnit` with
    ``direction`` +1 and -1), as the unit tracing both ways gives it."""
    for half, warning in (plus, minus):
        if half is None:
            return None, warning
    curve = join_halves(plus[0].curve, minus[0].curve)
    if len(curve.p) < 2:
        return None, f"{plus[0].origin}: gives no curve: {'; '.join(curve.stop_reasons)}"
    return GearCycleCurve(plus[0].kind, curve, plus[0].origin), None


#: A unit of a curve search: run in any process (``executors.run_work_unit``), its result handed
#: back to the search by its ``hand_in``.
SearchUnit = BesideUnit | ScanUnit | ContinueUnit


def search_done(search: CurveSearch, unit: SearchUnit, result: Any) -> list[ContinueUnit]:
    """Hand a finished search unit's result to ``search``; the continuations it makes possible."""
    unit.hand_in(search, result)
    return search.continuations()


def cycle_curves(config: Configuration | str, *, params: Parameters | None = None,
                 v_range: tuple[float, float] = DIAGRAM_V_RANGE, fz_range: tuple[float, float] = FZ_RANGE,
                 kinds: tuple[PointKind | str, ...] = KINDS, loads: tuple[float, ...] = (),
                 executor: Executor | None = None,
                 progress: Callable[[float, str], None] | None = None) -> CycleCurvesResult:
    """Every fold, torus and period-doubling curve of cycles in the box (m/s, N); ``loads``: the
    loads (N) at which each curve's crossings are located and reported.

    The starts (branches beside each codimension-2 point, a diagram and large-amplitude starts
    per scan load) are independent units, and so are the continuations of starts that lie on no
    curve yet (:class:`CurveSearch`): all go through ``executor`` (default
    :func:`~.executors.open_executor`: one process per core, or a Dask cluster), a curve's
    continuation as soon as a start for it is known and before the remaining starts.
    """
    clock = time.perf_counter()
    config = Configuration.parse(config)
    params = params if params is not None else Parameters()
    v_lo, v_hi = check_range("v", v_range, V_RANGE, "m/s")
    f_lo, f_hi = check_range("fz", fz_range, FZ_RANGE, "N")
    kinds = tuple(kinds)
    for k in kinds:
        if k not in KINDS:
            raise InvalidParameterError("kinds", k, ", ".join(KINDS), "is not a kind of cycle curve")
    kinds = tuple(PointKind(k) for k in kinds)
    if not kinds:
        raise InvalidParameterError("kinds", "", ", ".join(KINDS), "is empty")
    loads = tuple(float(check_number(f"loads[{i}]", f, f_lo, f_hi, "N")) for i, f in enumerate(loads))
    if executor is None:
        with open_executor() as own:
            return cycle_curves(config, params=params, v_range=v_range, fz_range=fz_range, kinds=kinds, loads=loads,
                                progress=progress, executor=own)
    report = progress or (lambda fraction, message: None)
    box = ((v_lo, v_hi), (f_lo, f_hi))

    report(0.0, "Hopf curves and their GH and double-Hopf points")
    hopf = hopf_curves(config, params=params, v_range=(v_lo, v_hi), fz_range=(f_lo, f_hi))
    search = CurveSearch(config, params, box, kinds, loads)
    search.expect_sources(len(SCAN_FRACTIONS))
    units = [(1, u) for u in search.start_units(hopf)]
    units += [(2, ScanUnit(config, params, f_lo + fr * (f_hi - f_lo), box)) for fr in SCAN_FRACTIONS]
    run_dynamic(run_work_unit, units, executor,
                lambda unit, result: [(0, u) for u in search_done(search, unit, result)],
                lambda f, m: report(0.05 + 0.95 * f, m), describe_work_unit)
    report(1.0, "done")
    return search.result(time.perf_counter() - clock)


def starts_of_diagram(diagram, Fz: float) -> list[Start]:
    """The located LPC, NS and PD points (with their orbits) of a diagram's periodic branches."""
    return [Start(s.kind, s, Fz, b.raw.ncol, f"{b.origin}, diagram at Fz = {kn(Fz)}", from_diagram=True)
            for b in diagram.branches if b.kind == "periodic" and b.raw is not None
            for s in b.raw.special_points if s.kind in KINDS]


def continue_start(config: Configuration, params: Parameters, start: Start, box, loads: tuple[float, ...],
                   directions: tuple[int, ...] = (1, -1), options: CycleCurveOptions | None = None,
                   guides: dict[int, Guide] | None = None) -> tuple[GearCycleCurve | None, str | None]:
    """One curve continued from one start (a unit of :func:`cycle_curves`); with one of
    ``directions``, the half traced that way (whatever its length: the other half may hold the rest);
    ``guides``: the same curve's points at a nearby design each half follows (a warm start's)."""
    system = gear_two_parameter_field(config, params)
    angle = start.point.data["torus_angle"] if start.kind == PointKind.TORUS else None
    if angle is not None and not RESONANCE_ANGLE < angle < math.pi - RESONANCE_ANGLE:
        return None, None  # a pair at +1 or -1 (a strong resonance, e.g. born at a fold), not a torus
    kappa = None if angle is None else math.cos(angle)
    about = f"{start.kind} point at V = {start.point.p:.6g} m/s, Fz = {kn(start.Fz)} ({start.origin})"
    try:
        curve = cycle_curve(system, start.kind, start.point.solution, start.Fz, box=box,
                            options=options or CURVE_OPTIONS,
                            scale=STATE_SCALE[:system.n], p_scale=(V_SCALE, FZ_SCALE), kappa=kappa, ncol=start.ncol,
                            p2_marks=loads, directions=directions, guides=guides)
    except ContinuationError as exc:
        return None, f"{about} not continued: {exc}"
    extent = np.ptp(curve.p / np.array([V_SCALE, FZ_SCALE]), axis=0).max() if len(curve.p) else 0.0
    if (len(curve.p) < 2 or extent <= 1e-6) and len(directions) == 2:  # stopped at its start both ways
        return None, f"{about} gives no curve: {'; '.join(curve.stop_reasons)}"
    return GearCycleCurve(start.kind, curve, start.origin), None


#: Where a new curve is probed against a known one (fractions of its points): all must lie on it.
SAME_CURVE_PROBES = (0.25, 0.5, 0.75)


def with_curve(curves: list[GearCycleCurve], new: GearCycleCurve, l_g: float) -> list[GearCycleCurve]:
    """``curves`` with a new curve that is none of them (:func:`same_curve`): a curve it contains (a
    shorter trace of the same curve: its points probed all on the new one) gives way to it, in its
    place; else the new curve is added last. (A torus curve of nes_pd traced from a slice's torus
    point ran on to 123.2 m/s, 275 kN, next to the double-Hopf point at 123.5 m/s, past the end of the
    one traced from beside that point at 116.7 m/s: both were kept, the map had the same boundary
    twice, and every warm map of it fell back to a cold one, finding the two one curve.) Where each
    trace ran further at a different end (where a trace ends near a GH or double-Hopf point depends on
    the largest amplitude it met), the tail the replaced one had beyond the new one's end, among
    cycles below 2 % of its largest, next to that point, is given up with it."""
    inside = [k for k, c in enumerate(curves) if same_curve(c, new, l_g)]
    if not inside:
        return [*curves, new]
    return [new if k == inside[0] else c for k, c in enumerate(curves) if k == inside[0] or k not in inside]


def same_curve(new: GearCycleCurve, old: GearCycleCurve, l_g: float) -> bool:
    """Whether a curve continued while another was under way is that curve again: its points a quarter,
    half and three quarters along its list of points all lie on the other. (The middle alone took a
    torus curve of nes_pd, traced from a slice's torus point at 120.6 m/s, 273.5 kN that no known
    curve passed, for the low-speed torus curve it runs into, and dropped the part of the map's
    boundary it carried.)"""
    if new.kind != old.kind:
        return False
    c = new.curve
    for fraction in SAME_CURVE_PROBES:
        i = min(int(fraction * len(c.p)), len(c.p) - 1)
        probe = SpecialPoint(new.kind, float(c.p[i, 0]), 0,
                             {"x_max": c.x_max[i].tolist(), "x_min": c.x_min[i].tolist()})
        if not _on_curve(old, Start(new.kind, probe, float(c.p[i, 1]), 0, ""), l_g):
            return False
    return True


def _starts_beside(config, model, params, point, kind, v_range, fz_range, origin) -> list[Start]:
    """LPC (beside GH) or NS (beside a double-Hopf point) points of the branches that leave the
    Hopf points just above and below the codimension-2 point's load."""
    out = []
    n = model.n_states
    system = gear_two_parameter_field(config, params)
    options = BifurcationOptions(max_steps=START_STEPS).periodic()
    for side in (-1.0, 1.0):
        Fz = point["Fz"] * (1.0 + side * BESIDE)
        if not fz_range[0] <= Fz <= fz_range[1]:
            continue
        hopf = hopf_points(config, Fz, params=params, v_range=(v_range[0], v_range[1])).hopf_points
        near = sorted(hopf, key=lambda h: abs(math.log(h.V / point["V"])))[:2 if kind == PointKind.TORUS else 1]
        for h in near:
            if abs(math.log(h.V / point["V"])) > 0.2:
                continue
            found, ncol = start_beside(system, kind, np.zeros(n), np.array([h.V, Fz]), p_range=v_range,
                                       options=options, scale=STATE_SCALE[:n], p_scale=V_SCALE,
                                       limits=orbit_limits(model))
            if found is not None:
                # eager when born at the point (a branch beside it may fold or lose stability
                # first on another curve, far away: that start waits like a diagram's)
                out.append(Start(kind, found, Fz, ncol, origin, eager=abs(found.p - point["V"]) <= 0.1 * point["V"]))
    return out


def _on_curve(curve: GearCycleCurve, start: Start, l_g: float) -> bool:
    """Whether a start point lies on a continued curve: within a fifth of the local step of its
    polyline in (V, Fz) (scaled) with amplitudes within 5 % (of its own, or of the curve's there
    where that is more) plus half their change along that step."""
    c = curve.curve
    scale = np.array([V_SCALE, FZ_SCALE])
    hit = near_polyline(c.p / scale, np.array([start.point.p, start.Fz]) / scale)
    if hit is None:
        return False
    i, s = hit
    amp = 0.5 * (c.x_max - c.x_min)
    here = amp[i] + s * (amp[i + 1] - amp[i])
    xmax, xmin = np.array(start.point.data["x_max"]), np.array(start.point.data["x_min"])
    theirs = 0.5 * (xmax - xmin)
    scale = STATE_SCALE[:len(theirs)]
    # near a zero-amplitude end the amplitude varies like the root of the distance and the
    # polyline's linear interpolation is poor: the change of amplitude along the segment counts too
    local = float(np.max(np.abs(amp[i:i + 2]) / scale))
    change = float(np.max(np.abs(amp[i + 1] - amp[i]) / scale))
    return bool(np.max(np.abs(here - theirs) / scale)
                <= 0.05 * max(np.max(np.abs(theirs) / scale), local, 1e-12) + 0.5 * change)
