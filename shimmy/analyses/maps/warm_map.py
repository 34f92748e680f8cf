"""A stability map for a design next to one whose map is known, computed from that map.

A map is its region boundaries (the Hopf, fold and torus curves) and its regions' types (read off
classified slices, :mod:`shimmy.analyses.maps.map_shading`). One slider step changes the design a
little: the curves move, but where their arrangement stays the same the regions keep their types.
:func:`warm_map` makes the map of the new design from the old one's :meth:`warm start
<shimmy.analyses.maps.stability_map.StabilityMap.warm_start>`:

1. **The Hopf curves** are computed afresh (:func:`~shimmy.analyses.diagrams.hopf_curves.hopf_curves`:
   the same computation as a cold map's, so the same curves, GH and double-Hopf points).
2. **Every fold and torus curve** is continued again from its seed, a point of the old curve with
   its cycle, corrected by Newton at the new design on the seed's load and then traced both ways
   (:class:`~shimmy.analyses.diagrams.cycle_curves.WarmUnit`, the longest half first), each step
   predicted from the old curve's next point (:mod:`shimmy.continuation.cycle_curves.guide`) and
   taken as a cold trace's steps are: its points, crossings of the slices' loads, turning points
   and codimension-2 points are the new design's to the location tolerance. The search for curve
   starts (branches beside GH and double-Hopf points, the slices' diagrams) is what is saved.
3. **The arrangement is checked** (:func:`same_arrangement`): the same number of Hopf curves (and
   their closure), GH and double-Hopf points, the same fold and torus curves (kind, closure,
   codimension-2 points in order along each). Where that fails (a curve appeared, vanished or
   closed, or a seed did not converge) :func:`warm_map` raises :class:`NotWarm` saying why, and
   :func:`~shimmy.analyses.maps.stability_map.stability_map` with ``warm_from`` computes the map cold.
4. **The slices are carried where the curves cross their load in the same order as before**
   (:func:`arrangement_change`: two crossings may swap only where they lie within half a grid cell,
   their order being the polylines' rounding): each slice's intervals move with the curves (an end
   on a curve to that curve's new crossing, an end where a cycle's mode changes to that change
   located again on its cycle at the new design, :func:`~shimmy.analyses.diagrams.mode_changes.relocate`,
   beside the curves' traces), its Hopf points are located again by the eigenvalue scan, its
   fold and torus points are the new curves' located crossings of its load (each point moved with
   its curve's drawn crossing, then matched to the located crossing within half a cell of there, or
   else to the one crossing between there and where it was; a point the slice lists twice, found on
   two of its branches, matched once). Its diagram is not
   recomputed, so it reports no largest amplitude (``max_psi`` None, ``"carried": true``). A slice
   whose load the curves now cross otherwise, or with a Hopf point more or less, or with a point
   on no curve of the map (a period doubling), or a mode change not found again, is computed again;
   and, as a cold map does, a slice
   is added through each region between the new curves that no slice crosses. The curves of the mode
   changes between two carried slices (:mod:`~shimmy.analyses.maps.mode_links`) are carried too: their
   inner points relocated at their loads beside the curves' traces, a change lost at the nearby design
   resumed where its follow gave up; those next to a slice computed again or added are followed afresh. A
   fold or torus point of a slice computed again that lies on no curve is continued as a cold map continues
   it: a curve the map lacks makes the map cold; none (no such point converges there) is the cold map's
   warning.

The result's ``methods.warmed_from`` names the design warmed from, the parameters changed and the
slices carried, computed again and added. What the checks cannot see: a curve born away from a GH
or double-Hopf point between the two designs (an isola appearing) is found only by a cold map, as
it is by a cold map only where a slice's diagram meets it. Nor do they see a mode change appear or
vanish on a carried slice (a stable cycle's torsional share reaching 0.8 or 0.2 at a new place, on no
curve): a slice is carried only within ``CARRY_DISTANCE`` of the design its diagram was computed at.
The mode changes it has are exact at the new design: a cold slice locates them on its diagram's
branches (:func:`~shimmy.analyses.diagrams.mode_changes.locate_mode_changes`) and a carried one again
from their cycles, the two to 1e-5 m/s. (Kept where the slice's diagram put them, they were 1.4-5 m/s
off after one slider step of the damper's filling ratio, and cells differed away from any edge of the
cold map's regions: 12 of 18 000 on nes_pd at a_p + 0.05.)
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from ...continuation import PointKind
from ...errors import InvalidParameterError
from ...model.configurations import Configuration
from ...model.parameters import FZ_RANGE, V_RANGE, Parameters, check_range, design_distance
from ..core.executors import describe_work_unit, name_of, open_executor, run_dynamic, run_work_unit
from ..core.stability import hopf_points
from ..diagrams.bifurcation import V_SCALE, BifurcationOptions
from ..diagrams.cycle_curves import (FZ_SCALE, KINDS, CurveSearch, CurveSeed, GearCycleCurve, WarmUnit,
                                     continue_start, joined_halves, reversed_curve, same_curve)
from ..diagrams.hopf_curves import HopfCurvesResult
from ..diagrams.mode_changes import ModeChange, relocate
from . import map_shading
from .map_slices import FINE, SliceResult, speed_grids, type_lengths
from .mode_links import LinkPointsUnit, carried_link, follows, links_unit, polylines
from .stability_map import (COVERAGE_AREA, COVERAGE_ROUNDS, HopfCurvesUnit, SliceUnit, Sketch, StabilityMap,
                            arrangement, curve_boundaries, lowest_shimmy, sketch_of)
from ...model.units import kn

#: Kinds of a slice's special points that lie on the map's curves (carried to the curves' crossings);
#: a slice with any other (a period doubling, a branch point of cycles) is not carried.
ON_CURVES = (PointKind.FOLD_OF_CYCLES, PointKind.TORUS)
#: Two fold or torus points of one kind on a slice within this fraction of half a grid cell are one
#: point the slice's diagram found on two of its branches (measured: 0.024 m/s apart, a cell ~2 m/s).
DUPLICATE = 0.1
#: A slice is carried only within this largest relative parameter change from the design its
#: diagram was computed at (a mode change appearing or vanishing between the curves is seen only by a
#: diagram); farther, it is computed again. One slider step of 10 % is carried once; a walk of several
#: steps recomputes its slices every 10 %.
CARRY_DISTANCE = 0.1


class NotWarm(Exception):
    """The map cannot be warmed from the one given; ``reason`` says why (a cold map is needed)."""

    def __init__(self, reason: str):
        super().__init__(reason)
        self.reason = reason


def _changed(a: Parameters, b: Parameters) -> dict[str, list[float]]:
    """{name: [old, new]} of the parameters that differ."""
    da, db = a.to_dict(), b.to_dict()
    return {k: [da[k], db[k]] for k in da if da[k] != db[k]}


def same_arrangement(old: dict[str, Any], new: dict[str, Any]) -> str | None:
    """None if two :func:`~shimmy.analyses.maps.stability_map.arrangement` records agree, else what differs."""
    for key, what in (("hopf_curves", "Hopf curves (count or closure)"), ("gh_points", "GH points"),
                      ("double_hopf_points", "double-Hopf points")):
        if old[key] != new[key]:
            return f"the {what} changed: {old[key]} -> {new[key]}"
    if len(old["cycle_curves"]) != len(new["cycle_curves"]):
        return f"{len(old['cycle_curves'])} fold and torus curves became {len(new['cycle_curves'])}"
    for i, (a, b) in enumerate(zip(old["cycle_curves"], new["cycle_curves"], strict=True)):
        if a["closed"] and b["closed"]:  # a loop has no first point: its codimension-2 points as a set
            a, b = dict(a, codim2=sorted(a["codim2"])), dict(b, codim2=sorted(b["codim2"]))
        elif a["codim2"] == b["codim2"][::-1]:  # traced from another point: the same points the other way
            b = dict(b, codim2=a["codim2"])
        if a != b:
            return f"cycle curve {i + 1} changed: {a} -> {b}"
    return None


def _inside(curves, Fz: float, v_range, tol: float) -> dict:
    """{(curve, crossing number): V} of the curves' crossings of the load ``Fz``, those within ``tol``
    (m/s) of the speed range's ends left out (inside or outside by rounding)."""
    return {label: V for V, label in map_shading.crossings(curves, Fz) if v_range[0] + tol < V < v_range[1] - tol}


def arrangement_change(old: dict, new: dict, tol: float) -> str | None:
    """None if two loads' crossings ({(curve, crossing number): V} inside the speed range) are the
    same curves' in the same order, two of them allowed to swap where they lie within ``tol`` of
    each other before or after (their order is the polylines' rounding); else what changed."""
    if set(old) != set(new):
        gone, born = sorted(set(old) - set(new)), sorted(set(new) - set(old))
        return f"crossings {_labels(gone)} gone, {_labels(born)} new"
    for a in old:
        for b in old:
            if old[a] < old[b] and new[a] > new[b] and old[b] - old[a] > tol and new[a] - new[b] > tol:
                return f"{_labels([a])} (V = {old[a]:.4g} m/s) and {_labels([b])} (V = {old[b]:.4g} m/s) swapped"
    return None


def _labels(labels) -> str:
    return ", ".join(f"{name}#{k}" for name, k in labels) or "none"


class _Carrier:
    """Moves speeds at one load with the curves. A curve's crossing goes to that curve's crossing at
    the new design; any other speed (an interval's end at a mode change not located on its cycle, from
    an older cache: on the slice's fine grid; a simulated speed) stays where it was, held inside the same
    interval between the curves."""

    def __init__(self, old_curves, new_curves, Fz: float, v_range):
        new = {label: V for V, label in map_shading.crossings(new_curves, Fz)}
        pairs = sorted([(v_range[0], v_range[0]), (v_range[1], v_range[1])]
                       + [(V, new[label]) for V, label in map_shading.crossings(old_curves, Fz)
                          if label in new and v_range[0] < V < v_range[1]])
        self.old = np.array([p[0] for p in pairs])
        self.new = np.array([p[1] for p in pairs])

    def __call__(self, V: float) -> float:
        return float(min(max(self._moved(V), self.old[0]), self.old[-1]))  # inside the speed range

    def _moved(self, V: float) -> float:
        k = int(np.searchsorted(self.old, V, side="right"))  # self.old[k - 1] <= V < self.old[k]
        if k == 0 or k == len(self.old):
            return float(V)
        if V == self.old[k - 1]:
            return float(self.new[k - 1])
        lo, hi = sorted((self.new[k - 1], self.new[k]))
        return float(min(max(V, lo), hi))


def _crossings_of(curves: list[GearCycleCurve], Fz: float) -> dict[str, list[float]]:
    """The located crossings (P2_MARK points) of the load ``Fz`` on the curves, by kind."""
    out: dict[str, list[float]] = {}
    for c in curves:
        for s in c.curve.points_of(PointKind.P2_MARK):
            if abs(s.data["p2"] - Fz) <= 1e-9 * max(abs(Fz), 1.0):
                out.setdefault(str(c.kind), []).append(float(s.p))
    return out


def _on_curve(old_boundaries, new_boundaries, Fz: float, carry: _Carrier, tol: float) -> Callable[[float, str], float]:
    """Where a slice's point of a fold or torus curve goes: by the move of that curve's drawn crossing of
    the load (the crossing of the kind nearest the point, within its polyline's chord error: 1 % of V,
    at least two half cells; its label found again at the new design); :class:`_Carrier` where no
    crossing is that near. (Carried like an interval's end, a point on a curve that moved more than
    half a cell stayed behind and the slice was computed again.)"""
    old = map_shading.crossings(old_boundaries, Fz)
    new = {label: V for V, label in map_shading.crossings(new_boundaries, Fz)}

    def moved(V: float, kind: str) -> float:
        reach = max(2.0 * tol, 0.01 * abs(V))
        near = [(abs(x - V), x, label) for x, label in old
                if label[0].startswith(kind) and label in new and abs(x - V) <= reach]
        if not near:
            return carry(V)
        _, x, label = min(near)
        return V + new[label] - x

    return moved


def _near(old: dict[str, Any], params: Parameters, config: Configuration) -> bool:
    """Whether a slice of the old map was computed within CARRY_DISTANCE of ``params`` (else it is computed
    again, not carried)."""
    computed_at = old.get("computed_at")
    return computed_at is not None and \
        design_distance(params, Parameters.from_dict(computed_at), config) <= CARRY_DISTANCE


def _carried_slice(old: dict[str, Any], config: Configuration, params: Parameters, v_range, n_v: int, scan: list,
                   carry: _Carrier, on_curve: Callable[[float, str], float], crossings: dict[str, list[float]],
                   tol: float, changes: list[tuple[ModeChange, ModeChange | None]] = ()) -> SliceResult:
    """A slice of the old map at the new design (see the module's step 4), ``scan`` the Hopf points at
    its load at the new design, ``changes`` the mode changes its intervals end at, (as they were, as
    located again at the new design: None where not found); NotWarm where it cannot be carried (it is then
    computed again)."""
    clock = time.perf_counter()
    Fz = float(old["Fz"])
    computed_at = old.get("computed_at")
    if not _near(old, params, config):
        raise NotWarm(f"the slice at Fz = {Fz / 1e3:.4g} kN was computed at a design more than "
                      f"{CARRY_DISTANCE:g} (relative) from this one")
    if len(scan) != len(old["hopf_points"]):
        raise NotWarm(f"the slice at Fz = {Fz / 1e3:.4g} kN has {len(scan)} Hopf points, before "
                      f"{len(old['hopf_points'])}")
    hopf = [{"V": h.V, "frequency_hz": h.frequency_hz, "criticality": h.criticality.value} for h in scan]
    special: list[dict[str, Any]] = []
    taken: dict[float, float] = {}  # a located crossing: the old point it was given to
    for q in old["special_points"]:
        if q["kind"] not in ON_CURVES:
            raise NotWarm(f"the slice at Fz = {Fz / 1e3:.4g} kN has a {q['kind']} point, on no curve of the map")
        V = on_curve(q["V"], str(q["kind"]))
        # the new curves' located crossing of this load where the point was carried (within half a cell),
        # each used once
        crossed = crossings.get(str(q["kind"]), [])
        free = [x for x in crossed if x not in taken]
        located = [x for x in free if abs(x - V) <= tol]
        lo, hi = sorted((V, q["V"]))
        if not located:  # near a turn of a curve in Fz its drawn crossing of the load moves by more than a
            # cell when the curve is traced again through other points (45.64 m/s on pd's fold curve at
            # 233.7 kN moved 1.24 m/s, its located crossing 2e-5 m/s): the one crossing between there and
            # where it was, half a cell either side
            located = [x for x in free if lo - tol <= x <= hi + tol]
            if len(located) > 1:
                raise NotWarm(f"the slice at Fz = {Fz / 1e3:.4g} kN has a {q['kind']} point at V = {q['V']:.5g} m/s "
                              f"that {len(located)} crossings of the map's curves may stand for")
        if not located:  # a point the slice lists twice, found on two of its branches and located on each to
            # the diagram's tolerance (17.887 and 17.863 m/s on pd's at 213.9 kN), is one point
            located = [x for x in crossed if x in taken and lo - tol <= x <= hi + tol
                       and abs(taken[x] - q["V"]) <= DUPLICATE * tol]
        if not located:
            raise NotWarm(f"the slice at Fz = {Fz / 1e3:.4g} kN has a {q['kind']} point at V = {q['V']:.5g} m/s that "
                          "no curve of the map crosses there now")
        V = min(located, key=lambda x: abs(x - V))
        taken[V] = q["V"]
        special.append({"kind": q["kind"], "V": V, "mode": q["mode"]})
    for was, now in changes:
        if now is None:
            raise NotWarm(f"the slice at Fz = {Fz / 1e3:.4g} kN has a mode change at V = {was.V:.5g} m/s (torsional "
                          f"share {was.threshold:g}) that was not found again at this design")
    # an interval's end at one of the slice's located points, or at a located mode change, goes to that point
    # at the new design
    exact = list(zip([h["V"] for h in old["hopf_points"]] + [q["V"] for q in old["special_points"]]
                     + [was.V for was, _ in changes],
                     [h["V"] for h in hopf] + [q["V"] for q in special] + [now.V for _, now in changes], strict=True))

    def moved(V: float) -> float:
        for was, now in exact:
            if abs(V - was) <= 1e-9 * max(abs(V), 1.0):
                return float(now)
        return carry(V)

    intervals = []
    for iv in old["intervals"]:
        a = float(v_range[0]) if iv["V_start"] <= v_range[0] else moved(iv["V_start"])
        b = float(v_range[1]) if iv["V_end"] >= v_range[1] else moved(iv["V_end"])
        if a > b:  # its ends went to crossings the other way round: the points were matched wrongly
            raise NotWarm(f"the slice at Fz = {Fz / 1e3:.4g} kN has an interval from {iv['V_start']:.5g} to "
                          f"{iv['V_end']:.5g} m/s whose ends would go to {a:.5g} and {b:.5g} m/s")
        intervals.append({"type": iv["type"], "V_start": a, "V_end": b})
    coarse, fine = speed_grids(*v_range, n_v)
    fine_types = [map_shading.type_at(intervals, float(v)) for v in fine]
    return SliceResult(Fz, coarse, fine_types[::FINE], hopf, special, intervals, type_lengths(fine, fine_types), None,
                       None, [carry(v) for v in old["simulated_V"]],
                       [f"{w} (at the design the slice was computed at)" for w in old["warnings"]],
                       time.perf_counter() - clock, carried=True, computed_at=computed_at,
                       mode_changes=[now for _, now in changes])


def _off_curve(q: dict[str, Any], s: SliceResult, config: Configuration, params: Parameters, box, marks,
               curves: list[GearCycleCurve]) -> list[str]:
    """A fold or torus point of a slice computed again that lies on no curve of the map: continued as
    a cold map continues it (:func:`~shimmy.analyses.diagrams.cycle_curves.continue_start` from the
    slice's located point). A curve that is none of the map's means the arrangement changed
    (:class:`NotWarm`); no curve (no such point converges near it) is what the cold map finds too,
    and its warning is the cold map's."""
    where = f"the slice computed at Fz = {s.Fz / 1e3:.4g} kN has a {q['kind']} point at V = {q['V']:.5g} m/s"
    start = min((t for t in s.starts if t.kind == q["kind"]), key=lambda t: abs(t.point.p - q["V"]), default=None)
    if start is None or abs(start.point.p - q["V"]) > 1e-6 * max(abs(q["V"]), 1.0):
        raise NotWarm(f"{where} on no curve of the map, without its located point")
    curve, warning = continue_start(config, params, start, box, marks)
    if curve is None:
        return [warning] if warning else []
    if any(same_curve(curve, c, params.gear.l_g) for c in curves):
        return []  # a curve of the map after all (the point lay beside its polyline)
    raise NotWarm(f"{where} on no curve of the map: it continues to a curve, or a part of one, the map lacks")


def compatible(start: dict[str, Any], config: Configuration | str, *, v_range, fz_range, resolution: int, n_v: int,
               options: BifurcationOptions) -> str | None:
    """None if a map of ``config`` on this plane, grid and options can be warmed from ``start``,
    else why not."""
    want = {"config": Configuration.parse(config).value, "v_range": [float(v) for v in v_range],
            "fz_range": [float(f) for f in fz_range], "resolution": int(resolution), "n_v": int(n_v),
            "options": dataclasses.asdict(options)}
    for key, value in want.items():
        if start.get(key) != value:
            return f"the nearby map's {key} is {start.get(key)!r}, this map's {value!r}"
    return None


@dataclass(frozen=True, eq=False)
class SliceHopfUnit:
    """The Hopf points of x = 0 at the slices' loads (the eigenvalue scan, as a cold slice locates
    them): {Fz: Hopf points}. Run beside the curves instead of after them."""

    config: Configuration
    params: Parameters
    loads: tuple[float, ...]
    v_range: tuple[float, float]

    def run(self) -> dict[float, list]:
        return {Fz: hopf_points(self.config, Fz, params=self.params, v_range=self.v_range).hopf_points
                for Fz in self.loads}

    def describe(self) -> str:
        return f"Hopf points at the {len(self.loads)} slices' loads"


@dataclass(frozen=True, eq=False)
class ModeChangesUnit:
    """The mode changes a slice's intervals end at, located again at the new design
    (:func:`~shimmy.analyses.diagrams.mode_changes.relocate`; None where one is not found). Run beside the
    curves: they need only the design."""

    config: Configuration
    params: Parameters
    changes: tuple[ModeChange, ...]
    exact_nes: bool

    def run(self) -> list[ModeChange | None]:
        return [relocate(c, self.config, self.params, exact_nes=self.exact_nes) for c in self.changes]

    def describe(self) -> str:
        return f"{len(self.changes)} mode change(s) at Fz = {kn(self.changes[0].Fz)} located again"


#: A curve half's cost per point it follows, by kind, relative to a fold curve's (the torus system has
#: two periods: ~20 against ~14 ms a point on nes)
COST_PER_POINT = {PointKind.TORUS: 1.5}


def _priority(seed: CurveSeed, direction: int) -> float:
    """The order a curve half's unit runs in (lowest first, after the Hopf curves' 0): its expected
    cost, longest first; in the seeds' order where a seed has no guide (an older cache)."""
    if seed.guides is None:
        return 1.0
    return 1.0 / (1.0 + len(seed.guides[direction]) * COST_PER_POINT.get(seed.kind, 1.0))


def warm_map(start: dict[str, Any], *, params: Parameters, executor=None,
             progress: Callable[[float, str], None] | None = None, sketch: Sketch | None = None) -> StabilityMap:
    """The map of design ``params`` warmed from ``start`` (:meth:`StabilityMap.warm_start` of a map of
    the same configuration, plane, grid and options at a nearby design); raises :class:`NotWarm`
    where the arrangement of the curves changed (see the module). ``sketch`` is told the curves
    known so far as each is (the Hopf curves, then each fold and torus curve found again)."""
    clock = time.perf_counter()
    config = Configuration.parse(start["config"])
    old_params = Parameters.from_dict(start["params"])
    v_range = check_range("v", tuple(start["v_range"]), V_RANGE, "m/s")
    fz_range = check_range("fz", tuple(start["fz_range"]), FZ_RANGE, "N")
    if not start.get("seeds") and start["arrangement"]["cycle_curves"]:
        raise InvalidParameterError("warm_from", "a warm start without seeds", "a StabilityMap.warm_start()")
    if executor is None:
        with open_executor() as own:
            smap = warm_map(start, params=params, executor=own, progress=progress, sketch=sketch)
        smap.executor = name_of(None)
        return smap
    report = progress or (lambda fraction, message: None)
    n_v, resolution = int(start["n_v"]), int(start["resolution"])
    options = BifurcationOptions(**start["options"])
    loads = tuple(float(f) for f in np.linspace(fz_range[0], fz_range[1], resolution))
    box = (v_range, fz_range)
    seeds = [CurveSeed.from_dict(s) for s in start["seeds"]]
    units = [(0, HopfCurvesUnit(config, params, v_range, fz_range))]
    # every slice's load is marked, so that the slices' fold and torus points are located crossings;
    # the marks beyond the first slices' loads are dropped from the curves afterwards (as a cold map's)
    marks = loads + tuple(sorted({float(s["Fz"]) for s in start["slices"]} - set(loads)))
    # each curve's two halves from its seed as two units (unit 2j + 1 towards higher Fz, 2j + 2 lower),
    # so that the longest curve's halves run side by side; after the Hopf curves (drawn first), the
    # longest first (the points each half follows, a torus point costing ~1.5 a fold point: measured
    # on nes, the two workers' curves then end 0.1 s sooner than in the seeds' order)
    units += [(_priority(seed, direction), WarmUnit(config, params, seed, box, marks, direction))
              for seed in seeds for direction in (1, -1)]
    # the slices' Hopf points at the new design, last (keyed -1 in the results)
    scans = SliceHopfUnit(config, params, tuple(float(s["Fz"]) for s in start["slices"]), v_range)
    units.append((2.0, scans))
    # the mode changes the slices' intervals end at, slice by slice (keyed -2, -3, ...)
    relocations = {float(s["Fz"]): ModeChangesUnit(config, params, tuple(map(ModeChange.from_dict, s["mode_changes"])),
                                                   options.exact_nes)
                   for s in start["slices"] if s.get("mode_changes") and _near(s, params, config)}
    units += [(2.0, unit) for unit in relocations.values()]
    # the inner points of the links between two such slices, link by link (keyed -1000, -1001, ...)
    near_loads = {float(s["Fz"]) for s in start["slices"] if _near(s, params, config)}
    old_links: dict[tuple[float, float], list[dict[str, Any]]] = {}
    for link in start.get("links", []):
        if all(float(f) in near_loads for f in link["loads"]):
            old_links.setdefault(tuple(float(f) for f in link["loads"]), []).append(link)
    moving = {loads: LinkPointsUnit(config, params, tuple(links), options.exact_nes)
              for loads, links in old_links.items() if any(link["points"] for link in links)}
    units += [(2.0, unit) for unit in moving.values()]
    results: dict[int, Any] = {}
    index = {id(u): k for k, (_, u) in enumerate(units)}
    index[id(scans)] = -1
    index.update({id(unit): -2 - k for k, unit in enumerate(relocations.values())})
    index.update({id(unit): -1000 - k for k, unit in enumerate(moving.values())})

    def curve_of(j: int) -> tuple[GearCycleCurve | None, str | None]:
        return joined_halves(results[2 * j + 1], results[2 * j + 2])

    def done(unit, result):
        results[index[id(unit)]] = result
        if sketch is not None and 0 in results and index[id(unit)] >= 0:
            found = []
            for j in range(len(seeds)):
                halves = [results.get(2 * j + 1), results.get(2 * j + 2)]
                if all(h is not None for h in halves):
                    found.append(curve_of(j)[0])
                else:  # one half known: drawn as it is
                    found += [h[0] for h in halves if h is not None]
            sketch(sketch_of(config, v_range, fz_range, results[0], [c for c in found if c is not None]))
        return []

    report(0.0, "Hopf curves, and each fold and torus curve again from the map of the nearby design")
    run_dynamic(run_work_unit, units, executor, done, lambda f, m: report(0.8 * f, m), describe_work_unit)
    hopf: HopfCurvesResult = results[0]
    curves: list[GearCycleCurve] = []
    traced_from: list[CurveSeed] = []
    l_g = params.gear.l_g
    for j, seed in enumerate(seeds):
        curve, warning = curve_of(j)
        if curve is None:
            raise NotWarm(f"the {seed.kind} curve was not found again at the new design: {warning or 'no curve'}")
        if any(same_curve(curve, c, l_g) for c in curves):
            raise NotWarm(f"two {seed.kind} curves of the nearby design are one curve at this design")
        curves.append(curve)
        traced_from.append(seed)
    old_boundaries = [(name, np.array(p, float).reshape(-1, 2)) for name, p in start["boundaries"]]
    old_curves = old_boundaries[len(start["arrangement"]["hopf_curves"]):]
    scale = np.array([V_SCALE, FZ_SCALE])
    for k, (curve, (_, before)) in enumerate(zip(curves, old_curves, strict=True)):
        # the same way round as before (traced from another point, an open curve may come out reversed)
        if len(before) and np.linalg.norm((curve.curve.p[-1] - before[0]) / scale) \
                < np.linalg.norm((curve.curve.p[0] - before[0]) / scale):
            curves[k] = reversed_curve(curve)
    # the cold traces' end amplitudes (in the curve's order, kept above); a seed from an older cache
    # has none: this trace's own then
    ends = {id(c): CurveSeed.of(c, config.n_states).end_amplitudes if seed.end_amplitudes == (None, None)
            else seed.end_amplitudes for c, seed in zip(curves, traced_from, strict=True)}
    curves.sort(key=lambda c: KINDS.index(c.kind))  # stable: each kind's in the old order, as a cold map's
    search = CurveSearch(config, params, box, (PointKind.FOLD_OF_CYCLES, PointKind.TORUS), loads)
    search.start_units(hopf)  # its GH and double-Hopf points (the units beside them are not run)
    search.curves, search.tried, search.warnings = curves, len(seeds), []
    cycles = search.result(0.0).to_dict()
    why = same_arrangement(start["arrangement"], arrangement(hopf, cycles))
    if why:
        raise NotWarm(why)
    report(0.8, "regions carried along the curves")
    boundaries = curve_boundaries(hopf, curves)
    rows = np.array(start["rows"], float)
    tol = 0.5 * (v_range[1] - v_range[0]) / (n_v - 1)  # half a grid cell
    slices: list[SliceResult] = []
    again: dict[float, str] = {}  # slices computed again at the new design: load -> why
    for old in start["slices"]:
        Fz = float(old["Fz"])
        change = arrangement_change(_inside(old_boundaries, Fz, v_range, tol), _inside(boundaries, Fz, v_range, tol),
                                    tol)
        try:
            if change:
                raise NotWarm(f"the curves' arrangement changed on it: {change}")
            carry = _Carrier(old_boundaries, boundaries, Fz, v_range)
            unit = relocations.get(Fz)
            moved_changes = [] if unit is None else list(zip(unit.changes, results[index[id(unit)]], strict=True))
            slices.append(_carried_slice(old, config, params, v_range, n_v, results[-1][Fz], carry,
                                         _on_curve(old_boundaries, boundaries, Fz, carry, tol),
                                         _crossings_of(curves, Fz), tol, moved_changes))
        except NotWarm as exc:
            again[Fz] = exc.reason
    # regions between the new curves that no slice crosses: slices through them, as a cold map adds them
    loads_now = [float(s["Fz"]) for s in start["slices"]]
    added: list[float] = []
    for _ in range(COVERAGE_ROUNDS):
        extra = map_shading.uncovered(loads_now, boundaries, rows, v_range, min_width=2.0 * tol,
                                      min_area=COVERAGE_AREA * (v_range[1] - v_range[0]) * (fz_range[1] - fz_range[0]))
        if not extra:
            break
        loads_now += extra
        added += extra
    fresh = sorted(again) + added
    warnings_off: list[str] = []  # off-curve points continued as a cold map does, that gave no curve
    if fresh:
        report(0.8, f"{len(again)} slice(s) computed again, {len(added)} added through regions no slice crosses")
        units = [(2, SliceUnit(config, Fz, v_range, n_v, params, options)) for Fz in fresh]
        computed: list[SliceResult] = []
        run_dynamic(run_work_unit, units, executor, lambda unit, result: computed.append(result) or [],
                    lambda f, m: report(0.8 + 0.15 * f, m), describe_work_unit)
        for s in computed:  # a fold or torus point on no curve of the map: a curve the warm map may lack
            # just above and below the load too: a curve ending on a box edge at this load crosses it there
            near = [x for f in (s.Fz, s.Fz * (1 + 1e-7), s.Fz * (1 - 1e-7))
                    for x in map_shading.crossings(boundaries, f)]
            on_curves = {str(k): [V for V, (name, _) in near if name.startswith(k)] for k in ON_CURVES}
            for q in s.special_points:
                if q["kind"] in ON_CURVES and not any(abs(V - q["V"]) <= 2 * tol for V in on_curves[str(q["kind"])]):
                    warnings_off += _off_curve(q, s, config, params, box, marks, curves)
            s.computed_at = params.to_dict()
        slices += computed
    slices.sort(key=lambda s: s.Fz)
    links, follow = [], []
    for a, b, only in follows(slices):  # links between carried slices carried, the others followed afresh
        carried = set()
        if a.carried and b.carried:
            unit = moving.get((a.Fz, b.Fz))
            for k, old in enumerate(old_links.get((a.Fz, b.Fz), [])):
                if old["start"] not in only:
                    continue
                moved = results[index[id(unit)]][k] if unit is not None else []
                link = carried_link(old, moved, a, b)
                if link is not None:
                    links.append(link)
                    carried.add(link.start)
        rest = [i for i in only if i not in carried]
        if rest:
            follow.append((2, links_unit(a, b, rest, config, params, options.exact_nes)))
    if follow:
        report(0.95, f"mode changes followed between {len(follow)} pair(s) of slices")
        run_dynamic(run_work_unit, follow, executor, lambda unit, result: links.extend(result) or [],
                    lambda f, m: None, describe_work_unit)
    links.sort(key=lambda link: (link.loads, link.start))
    report(0.95, "the shading read off the slices along the curves")
    for c in curves:
        c.curve.special_points = [q for q in c.curve.special_points if q.kind != PointKind.P2_MARK
                                  or not any(abs(q.data["p2"] - f) <= 1e-9 * f for f in marks[len(loads):])]
    cycles = search.result(0.0).to_dict()
    warnings = list(hopf.warnings) + list(cycles.pop("warnings")) + warnings_off
    for s in slices:
        warnings += [f"Fz = {kn(s.Fz)}: {w}" for w in s.warnings]
    segments, fallbacks = map_shading.row_segments(slices, boundaries, rows, v_range, polylines(links))
    V = slices[0].V
    elapsed = time.perf_counter() - clock
    cycles["elapsed_s"] = elapsed
    smap = StabilityMap(config, params, v_range, fz_range, V, np.array([s.Fz for s in slices]),
                        [s.types for s in slices], slices, hopf, cycles, rows, map_shading.grid(segments, V),
                        [map_shading.measures(r) for r in segments], fallbacks, map_shading.polygons(segments, rows),
                        lowest_shimmy(hopf, cycles, slices), type(executor).__name__, elapsed, warnings,
                        resolution=resolution, n_v=n_v, options=options,
                        # the end amplitudes of the cold map's traces, not of these (each warm map would
                        # reach half as far again towards the codimension-2 points)
                        seeds=[dataclasses.replace(CurveSeed.of(c, config.n_states), end_amplitudes=ends[id(c)])
                               for c in curves], mode_links=links,
                        warmed_from={"params": start["params"], "changed": _changed(old_params, params),
                                     "slices": {"carried": len(start["slices"]) - len(again),
                                                "computed_again": [{"Fz": Fz, "why": why} for Fz, why in
                                                                   sorted(again.items())],
                                                "added": added},
                                     "curve_points": {"traced": sum(len(c.curve.p) for c in curves),
                                                      "guided": sum(c.curve.guided for c in curves)},
                                     "method": "Hopf curves computed afresh; each fold and torus curve continued "
                                               "again from a point of the nearby design's curve (Newton at its "
                                               "load, then traced both ways, each step predicted from the nearby "
                                               "curve's next point where that converges), the curves' kinds, "
                                               "closure and codimension-2 points checked unchanged; a slice whose "
                                               "load the curves cross in the same order carried with them (an end on a "
                                               "curve to its new crossing, a mode change to the same change "
                                               "located again on its cycle), "
                                               "its Hopf points scanned again; the others computed again, and "
                                               "slices added through regions between the new curves that none "
                                               "crosses"})
    smap.elapsed_s = time.perf_counter() - clock
    report(1.0, "done")
    return smap
