"""Disturbance margins on the map: over the cells of the (V, Fz) plane where two or more attractors coexist and one
of them is torsional shimmy, how large a yaw kick from straight rolling ends on it.

* **The cells**: the plane cut into ``n_v`` x ``n_fz`` equal cells
  (:class:`~shimmy.analyses.maps.margin_options.MapGrid`), each asked at its centre (the speeds
  v_min + (j + 1/2) dV, the loads likewise).
* **Which cells**: at each load, the one-parameter bifurcation diagram in V (the diagram
  :func:`~shimmy.analyses.maps.margins.margins` computes at that load: V from 1 to max(200, v_max) m/s) read at
  the cells' speeds (:func:`~shimmy.analyses.maps.map_slices.attractors_on`, the map's own reading of its slices):
  a cell is *multistable* where two or more attractors (the stable equilibrium, stable limit cycles) coexist:
  the map's Bistable cells (a torsional and a lateral cycle) and the cells where straight rolling is stable
  beside a cycle. Its margin is computed where one of them is a torsional cycle.
* **The worst shimmy** (:data:`WORST`): the torsional limit cycle (the largest torsional amplitude if there are
  several), the fatigue-critical one.
* **The margin of a cell**: :func:`~shimmy.analyses.maps.margins.margins` at its centre along ``psi`` (a yaw kick,
  the rest of the state at rest), with the load's diagram: the attractors (the diagram's and the discovery runs'),
  a bracketing scan of kicks and bisection to ``rtol``, each threshold checked by two full runs. The cell's margin
  is the torsional cycle's threshold (rad): 0 where the smallest kick scanned (``min_size``, the standard start's
  0.001 rad by default) already ends there, None where no kick up to ``max_size`` does.
* **Units of work** (through :mod:`shimmy.analyses.core.executors`, most urgent first): one :class:`LoadUnit` per
  load (its diagram, without the orbits' profiles, and the cells to compute), then one :class:`PointUnit` per cell,
  submitted as soon as its load's diagram is known and carrying it: each diagram is computed once and read by
  every speed of its load, and the cells spread over the workers (a local pool or a Dask cluster). A cell's margin
  is the one :func:`~shimmy.analyses.maps.margins.margins` gives at that point (its runs go side by side in a fixed
  pattern, whatever the executor).
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from ...errors import InvalidParameterError
from ...model.configurations import Configuration
from ...model.parameters import DIAGRAM_V_RANGE, FZ_RANGE, V_RANGE, Parameters, check_range
from ...model.units import kn
from ...version import __version__
from ..core.executors import InlineExecutor, name_of, open_executor, run_dynamic, run_work_unit
from ..core.response import Mode, shimmy_type
from .margin_options import MapGrid, MarginOptions
from .summaries import margin_map_summary

#: What the map's margin is to: the worst shimmy of a cell.
WORST = ("the torsional limit cycle (at least 80 % of its elastic energy in torsion; the largest torsional "
         "amplitude if there are several): the fatigue-critical shimmy")
DEFAULT_V_RANGE = DIAGRAM_V_RANGE
DEFAULT_FZ_RANGE = FZ_RANGE


def cell_centres(low: float, high: float, n: int) -> np.ndarray:
    """The centres of ``n`` equal cells from ``low`` to ``high`` (rounded to 10 digits: no 5.975000000000001)."""
    step = (high - low) / n
    return np.array([float(f"{low + (k + 0.5) * step:.10g}") for k in range(n)])


def slim(diagram):
    """The diagram without its orbits' profiles (what a cell's attractors are read from; a unit ships it)."""
    return dataclasses.replace(diagram, branches=[dataclasses.replace(b, raw=None) for b in diagram.branches])


@dataclass(frozen=True)
class LoadResult:
    """One load: its diagram (slim), the attractors' count at each cell's speed, the cells to compute (indices into
    the speeds), the shimmy type and whether straight rolling is stable at each of them."""

    Fz: float
    diagram: Any
    coexisting: tuple[int, ...]
    candidates: tuple[int, ...]
    types: tuple[str, ...]
    straight: tuple[bool, ...]
    elapsed_s: float


@dataclass(frozen=True, eq=False)
class LoadUnit:
    """The diagram at one load and the cells of that load whose margin is asked."""

    config: Configuration
    Fz: float
    params: Parameters
    v_max: float
    speeds: tuple[float, ...]

    def run(self) -> LoadResult:
        from .map_slices import attractors_on
        from .margins import diagram_at

        clock = time.perf_counter()
        diagram = slim(diagram_at(self.config, self.Fz, self.params, self.v_max))
        found = attractors_on(diagram, np.array(self.speeds))
        candidates = tuple(j for j, a in enumerate(found) if len(a) >= 2 and any(
            x["kind"] != "equilibrium" and x["mode"] == Mode.TORSIONAL for x in a))
        return LoadResult(self.Fz, diagram, tuple(len(a) for a in found), candidates,
                          tuple(str(shimmy_type(a)) for a in found),
                          tuple(any(x["kind"] == "equilibrium" for x in a) for a in found),
                          time.perf_counter() - clock)

    def describe(self) -> str:
        return f"diagram at Fz = {self.Fz / 1e3:.4g} kN"


def worst_of(attractors: list[dict[str, Any]]) -> int | None:
    """The index of the worst shimmy (:data:`WORST`) among a point's attractors, None if none is torsional."""
    torsional = [k for k, a in enumerate(attractors) if a["mode"] == Mode.TORSIONAL]
    return max(torsional, key=lambda k: attractors[k]["amplitude"]["psi"]) if torsional else None


def point_record(result: dict[str, Any], shimmy: str) -> dict[str, Any]:
    """A cell's entry from :meth:`~shimmy.analyses.maps.margins.MarginsResult.to_dict` at its centre: its
    attractors (each with its own smallest kick), the worst, and the margin to it."""
    attractors = result["attractors"]
    worst = worst_of(attractors)
    out = {"V": result["V"], "Fz": result["Fz"], "type": shimmy,
           "straight_rolling_stable": result["straight_rolling_stable"],
           "attractors": [{"kind": a["kind"], "mode": a["mode"], "psi": a["amplitude"]["psi"],
                           "lateral": a["amplitude"]["lateral"], "standard_start": a["standard_start"],
                           "min_kick": a["min_disturbance"]["value"],
                           "confirmed": (a["min_disturbance"]["check"] or {}).get("confirmed")} for a in attractors],
           "worst": worst, "runs": result["runs"], "unsettled_runs": result["unsettled_runs"],
           "warnings": result["warnings"]}
    if worst is None:
        return {**out, "margin": None, "tolerance": None, "lower": None, "upper": None, "reached": False,
                "confirmed": None, "note": "no torsional attractor at this point"}
    m = attractors[worst]["min_disturbance"]
    if not m["reached"]:
        return {**out, "margin": None, "tolerance": None, "lower": None, "upper": None, "reached": False,
                "confirmed": None, "note": m["note"]}
    note = ("the smallest kick scanned already ends on it (the standard start's size): the threshold is below it"
            if m["value"] == 0.0 else "")
    return {**out, "margin": m["value"], "tolerance": m["tolerance"], "lower": m["lower"], "upper": m["upper"],
            "reached": True, "confirmed": m["check"]["confirmed"], "note": note}


@dataclass(frozen=True, eq=False)
class PointUnit:
    """The margin of one cell, at its centre, with its load's diagram."""

    config: Configuration
    V: float
    Fz: float
    params: Parameters
    options: MarginOptions
    diagram: Any
    shimmy: str

    def run(self) -> tuple[dict[str, Any], str]:
        """(the cell's entry, the method of its margin)."""
        from .margins import margins

        result = margins(self.config, self.V, self.Fz, params=self.params, options=self.options, diagram=self.diagram,
                         executor=InlineExecutor()).to_dict()
        worst = worst_of(result["attractors"])
        method = result["attractors"][worst]["min_disturbance"]["method"] if worst is not None else ""
        return point_record(result, self.shimmy), method

    def describe(self) -> str:
        return f"margin at V = {self.V:.4g} m/s, Fz = {self.Fz / 1e3:.4g} kN"


@dataclass
class MarginMapResult:
    """The margins of the cells of a plane (``points``, each with its attractors and its margin to the worst shimmy),
    the cells' attractor counts and types (``coexisting``, ``types``: [i_Fz][j_V]), the loads' diagrams' times."""

    config: Configuration
    params: Parameters
    v_range: tuple[float, float]
    fz_range: tuple[float, float]
    grid: MapGrid
    options: MarginOptions
    V: np.ndarray
    Fz: np.ndarray
    coexisting: list[list[int]]
    types: list[list[str]]
    straight: list[list[bool]]
    points: list[dict[str, Any]]
    method: str
    diagrams_s: list[float]
    elapsed_s: float
    executor: str
    warnings: list[str] = field(default_factory=list)

    def counts(self) -> dict[str, Any]:
        multistable = sum(n >= 2 for row in self.coexisting for n in row)
        margins = [p["margin"] for p in self.points]
        by_type: dict[str, int] = {}
        for p in self.points:
            key = p["type"] + (" beside stable straight rolling" if p["straight_rolling_stable"] else "")
            by_type[key] = by_type.get(key, 0) + 1
        bistable = sum(t == "Bistable" for row in self.types for t in row)
        return {"cells": len(self.V) * len(self.Fz), "multistable": multistable, "bistable": bistable,
                "computed": len(self.points), "by_type": by_type,
                "reached": sum(m is not None for m in margins), "zero": sum(m == 0.0 for m in margins),
                "not_reached": sum(m is None for m in margins),
                "unconfirmed": sum(p["confirmed"] is False for p in self.points),
                "runs": sum(p["runs"] for p in self.points)}

    def to_dict(self) -> dict[str, Any]:
        reached = [p for p in self.points if p["margin"] is not None and p["margin"] > 0.0]
        smallest = min(reached, key=lambda p: p["margin"]) if reached else None
        return {"config": self.config.value, "params": self.params.to_dict(), "v_range": list(self.v_range),
                "fz_range": list(self.fz_range), "grid": self.grid.to_dict(), "options": self.options.to_dict(),
                "direction": self.options.direction, "unit": "rad", "worst": WORST,
                "V": self.V.tolist(), "Fz": self.Fz.tolist(), "coexisting": self.coexisting, "types": self.types,
                "straight_rolling_stable": self.straight, "points": self.points,
                "smallest": None if smallest is None else {k: smallest[k] for k in ("V", "Fz", "margin", "tolerance")},
                "counts": self.counts(),
                "method": {"cells": f"{self.grid.n_v} x {self.grid.n_fz} equal cells of the plane, each asked at its "
                                    "centre",
                           "which": "cells where two or more attractors coexist (the stable equilibrium and stable "
                                    "cycles of the one-parameter diagram in V at the cell's load, at its speed) and "
                                    "one of them is a torsional cycle",
                           "margin": self.method or "the smallest yaw kick from straight rolling that ends on the "
                                                    "worst shimmy (margins, direction psi)",
                           "tolerance": f"each margin within {self.options.rtol:g} of itself (its bracket: lower, "
                                        f"upper; 'tolerance' the half-width, rad), checked by two runs of "
                                        f"{self.options.t_max:g} s just below and just above it ('confirmed')",
                           "zero": f"a margin 0: the smallest kick scanned ({self.options.min_size:g} rad) already "
                                   "ends on the torsional cycle",
                           "null": f"no yaw kick up to {self.options.max_size:g} rad ends on the torsional cycle"},
                "diagrams_s": self.diagrams_s, "elapsed_s": self.elapsed_s, "executor": self.executor,
                "warnings": list(self.warnings), "version": __version__}

    def summary_text(self) -> str:
        """The lines ``python -m shimmy margin-map`` prints
        (:func:`~shimmy.analyses.maps.summaries.margin_map_summary`)."""
        return margin_map_summary(self.to_dict())


class _Build:
    """The units of one margin map and what their results add."""

    def __init__(self, config, params, options, V, Fz, v_max):
        self.config, self.params, self.options, self.V, self.Fz, self.v_max = config, params, options, V, Fz, v_max
        self.loads: dict[float, LoadResult] = {}
        self.points: dict[tuple[int, int], dict[str, Any]] = {}
        self.method = ""

    def first_units(self) -> list[tuple[int, LoadUnit]]:
        speeds = tuple(float(v) for v in self.V)
        return [(0, LoadUnit(self.config, float(f), self.params, self.v_max, speeds)) for f in self.Fz]

    def done(self, unit, result) -> list[tuple[int, PointUnit]]:
        if isinstance(unit, LoadUnit):
            self.loads[unit.Fz] = result
            return [(1, PointUnit(self.config, float(self.V[j]), unit.Fz, self.params, self.options, result.diagram,
                                  result.types[j])) for j in result.candidates]
        record, method = result
        self.method = self.method or method
        self.points[(int(np.argmin(np.abs(self.Fz - unit.Fz))), int(np.argmin(np.abs(self.V - unit.V))))] = record
        return []


def margin_map(config: Configuration | str, *, params: Parameters | None = None,
               v_range: tuple[float, float] = DEFAULT_V_RANGE, fz_range: tuple[float, float] = DEFAULT_FZ_RANGE,
               n_v: int = MapGrid.n_v, n_fz: int = MapGrid.n_fz, options: MarginOptions | None = None, executor=None,
               progress: Callable[[float, str], None] | None = None, **option_overrides) -> MarginMapResult:
    """The smallest yaw kick from straight rolling that ends on torsional shimmy, at the centre of each of the
    ``n_v`` x ``n_fz`` cells of the plane where two or more attractors coexist and one is a torsional cycle
    (module docstring). Options of each cell's margin as a :class:`MarginOptions` (direction psi) or as keyword
    overrides (``max_size=0.3``)."""
    clock = time.perf_counter()
    config = Configuration.parse(config)
    params = params if params is not None else Parameters()
    v_range = check_range("v", v_range, V_RANGE, "m/s")
    fz_range = check_range("fz", fz_range, FZ_RANGE, "N")
    grid = MapGrid(n_v, n_fz)
    options = options or MarginOptions()
    if option_overrides:
        options = MarginOptions(**{**options.to_dict(), **option_overrides})
    if options.direction != "psi":
        raise InvalidParameterError("direction", options.direction, "psi (a margin map is of yaw kicks)",
                                    "is not psi")
    if executor is None:
        with open_executor() as own:
            result = margin_map(config, params=params, v_range=v_range, fz_range=fz_range, n_v=grid.n_v,
                                n_fz=grid.n_fz, options=options, executor=own, progress=progress)
        result.executor = name_of(None)
        return result
    report = progress or (lambda fraction, message: None)
    V, Fz = cell_centres(*v_range, grid.n_v), cell_centres(*fz_range, grid.n_fz)
    build = _Build(config, params, options, V, Fz, max(DIAGRAM_V_RANGE[1], v_range[1]))
    report(0.0, f"diagrams at {grid.n_fz} loads")
    run_dynamic(run_work_unit, build.first_units(), executor, build.done, report, lambda unit: unit.describe(),
                lambda unit: "loads" if isinstance(unit, LoadUnit) else "points")
    loads = [build.loads[float(f)] for f in Fz]
    warnings = [f"Fz = {kn(r.Fz)}: {w}" for r in loads for w in r.diagram.warnings]
    warnings += [f"V = {p['V']:.4g} m/s, Fz = {kn(p['Fz'])}: the margin is not confirmed by its check runs"
                 for p in build.points.values() if p["confirmed"] is False]
    report(1.0, "done")
    return MarginMapResult(config, params, v_range, fz_range, grid, options, V, Fz,
                           [list(r.coexisting) for r in loads], [list(r.types) for r in loads],
                           [list(r.straight) for r in loads], [build.points[k] for k in sorted(build.points)],
                           build.method, [r.elapsed_s for r in loads], time.perf_counter() - clock,
                           type(executor).__name__, warnings)
