"""(V, Fz) stability maps and the shimmy type of an operating point.

How a map is built (what :func:`stability_map` returns says the same in ``methods``):

* **Region boundaries are continued curves**, exact in V and Fz: the Hopf curves and their GH and
  double-Hopf points (:func:`shimmy.analyses.diagrams.hopf_curves.hopf_curves`; the extended system, l1
  along the curve), and every fold-of-cycles (LPC) and torus (NS) curve
  (:class:`shimmy.analyses.diagrams.cycle_curves.CurveSearch`: minimally augmented systems, started from
  the GH and double-Hopf points and from the LPC / NS points of the slices' diagrams, whose seeds
  include large-amplitude starts). Each curve's crossings of the first slices' loads are
  located, so those slices' LPC and NS points lie on the drawn curves.
* **The regions' types** come from classified slices: the stable attractors at each V read off a
  slice's bifurcation diagram (:func:`~shimmy.analyses.maps.map_slices.attractors_at`): x = 0
  where its eigenvalues say so, and every periodic branch point with all nontrivial Floquet
  multipliers inside the unit circle, with its mode (torsional / lateral / both,
  :func:`shimmy.analyses.core.response.mode_of`). The type
  (:func:`~shimmy.analyses.core.response.shimmy_type`) is Bistable if a torsional and a lateral
  cycle are both stable, else Both if a stable cycle has both motions large, else Torsion or
  Lateral after the stable cycle, else Stable. Where neither x = 0 nor any cycle is stable (past a
  torus point the attractor is quasi-periodic), the type comes from a time simulation from the
  standard start (psi = 0.001 rad) at that V; the attractor is then reported with ``"kind":
  "simulation"``. ``resolution`` slices evenly spaced in Fz, and one more through each region
  between the curves that none of them crosses (:func:`map_shading.uncovered`).
* **Shading and region polygons** are read off the slices along the curves
  (:mod:`shimmy.analyses.maps.map_shading`): each row interval between two boundary crossings takes
  the types of the same interval on the nearest slices (a mode change inside it on its curve followed
  in Fz between the slices, :mod:`shimmy.analyses.maps.mode_links`; interpolated where none was
  followed), on 180 rows (at least four per slice); the polygons chain the rows' segments.

:func:`~shimmy.analyses.maps.map_slices.classify` (in :mod:`.map_slices`, with the slices) runs
exactly the slice computation at one Fz and reads the answer at V: at a slice load it gives the
map's answer; between slices it agrees with the shading wherever the type is set by the curves (a
mode change inside a region is followed between the slices to the chords' tolerance, ~0.02 m/s).

All units of a map (the Hopf curves, branches beside codimension-2 points, curve continuations,
slices) go through :mod:`shimmy.analyses.core.executors` (a local process pool, or a Dask cluster),
most urgent first (:func:`~shimmy.analyses.core.executors.run_dynamic`). :func:`stability_maps` runs
several maps' units through one executor at once (no worker waits for one map's last unit while
another map has units left); each map is the one :func:`stability_map` computes alone.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Sequence

import numpy as np

from ...version import __version__
from ...continuation import PointKind
from ..diagrams.bifurcation import BifurcationOptions
from ...model.configurations import Configuration
from ...errors import InvalidParameterError
from . import map_shading
from ..diagrams.cycle_curves import (KEY_OF_KIND, CurveSearch, CurveSeed, GearCycleCurve, SearchUnit, search_done)
from ..core.executors import name_of, open_executor, run_dynamic
from ..diagrams.hopf_curves import HopfCurvesResult, hopf_curves
from ...model.parameters import DEFAULT_MAP_SLICES, FZ_RANGE, V_RANGE, Parameters, check_number, check_range
from .map_slices import DEFAULT_V_RANGE, SliceResult, map_slice
from .mode_links import ModeLink, ModeLinksUnit, follows, links_unit, polylines
from .summaries import map_summary, write_map_csv
from ...model.units import kn

log = logging.getLogger(__name__)
SHADING_ROWS = 180  # rows of the read-off shading (at least 4 per slice)
COVERAGE_ROUNDS = 2  # rounds of further slices through regions no slice crosses
#: ... that are at least one grid cell wide and cover this fraction of the map (thinner slivers
#: between curves that nearly meet are read off the nearest slice at the same speed, and counted)
COVERAGE_AREA = 2e-4
DEFAULT_FZ_RANGE = FZ_RANGE
#: ``sketch(curves so far)``: called while a map is made, each time a curve is known (the Hopf curves,
#: then each fold and torus curve), with :func:`sketch_of` (to draw the boundaries before the shading)
Sketch = Callable[[dict[str, Any]], None]


def sketch_of(config: Configuration, v_range: tuple[float, float], fz_range: tuple[float, float],
              hopf: HopfCurvesResult, curves: Sequence[GearCycleCurve]) -> dict[str, Any]:
    """The curves of a map known so far, JSON-ready under the keys of :meth:`StabilityMap.to_dict`
    (curve points with V and Fz only): the Hopf curves with their GH and double-Hopf points, and
    the fold and torus curves continued so far."""
    def line(p: np.ndarray) -> list[dict[str, float]]:
        return [{"V": float(v), "Fz": float(f)} for v, f in p]

    out: dict[str, Any] = {"config": config.value, "v_range": list(v_range), "fz_range": list(fz_range),
                           "hopf_curves": [line(c.p) for c in hopf.curves], "gh_points": hopf.gh_points,
                           "double_hopf_points": hopf.double_hopf_points}
    for kind, key in KEY_OF_KIND.items():
        out[key] = [line(c.curve.p) for c in curves if c.kind == kind]
    return out


@dataclass
class StabilityMap:
    config: Configuration
    params: Parameters
    v_range: tuple[float, float]
    fz_range: tuple[float, float]
    V: np.ndarray
    Fz: np.ndarray
    types: list[list[str]]  # [i_Fz][j_V] on the classified slices (Fz: their loads, ascending)
    slices: list[SliceResult]
    hopf: HopfCurvesResult
    cycles: dict[str, Any]  # fold and torus curves with their details (:meth:`CycleCurvesResult.to_dict`)
    shading_Fz: np.ndarray  # rows of the shading (N), on the grid V
    shading: list[list[str]]  # [i_row][j_V]: types read off the slices along the curves
    shading_lengths: list[dict[str, float]]  # per row: measure (m/s) of each type, exact for the read-off
    shading_fallbacks: int  # row intervals read off the nearest slice at the same speed instead
    regions: list[dict[str, Any]]  # polygons {"type", "V", "Fz"} (:func:`map_shading.polygons`)
    min_shimmy: dict[str, Any] | None
    executor: str
    elapsed_s: float
    warnings: list[str] = field(default_factory=list)
    #: how it was made: ``resolution`` first slices, ``n_v`` speeds, the slices' diagram options
    resolution: int = DEFAULT_MAP_SLICES
    n_v: int = 100
    options: BifurcationOptions | None = None
    #: a point with its cycle on each fold and torus curve (:meth:`warm_start`; not in :meth:`to_dict`)
    seeds: list[CurveSeed] = field(default_factory=list, repr=False)
    #: the map this one was warmed from (:mod:`shimmy.analyses.maps.warm_map`), else None
    warmed_from: dict[str, Any] | None = None
    #: why a map asked to be warmed was computed cold, else None
    warm_refused: str | None = None
    #: the curves of the slices' mode changes between consecutive slices (:mod:`~.mode_links`; in
    #: :meth:`warm_start`, not in :meth:`to_dict`: the shading is read along them)
    mode_links: list[ModeLink] = field(default_factory=list, repr=False)

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
        """The shading's type at the grid point nearest to (V, Fz)."""
        i = int(np.argmin(np.abs(self.shading_Fz - Fz)))
        j = int(np.argmin(np.abs(self.V - V)))
        return self.shading[i][j]

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
                "regions": self.regions,
                "methods": {
                    "hopf_curves": "two-parameter continuation of Hopf points (extended system)",
                    "gh_points": "sign changes of the first Lyapunov coefficient along the Hopf curves "
                                 "(not defined with the particle damper: not smooth at x = 0)",
                    "double_hopf_points": "sign changes of the other eigenvalues' real parts along the Hopf curves",
                    "fold_curves": "two-parameter continuation of folds of cycles (minimally augmented system on the "
                                   "collocation mesh), started from GH points and the slices' LPC points; exact in V "
                                   "and Fz",
                    "torus_curves": "two-parameter continuation of Neimark-Sacker points of cycles (minimally "
                                    "augmented system), started from double-Hopf points and the slices' NS points; "
                                    "exact in V and Fz",
                    "types": "stable attractors of each slice's one-parameter diagram (equilibrium eigenvalues, "
                             "Floquet multipliers, cycle modes); a time simulation where none is stable; slices "
                             "evenly spaced plus one through each region between the curves that they miss",
                    "shading": "each row's intervals between the Hopf, fold and torus curves take the types of the "
                               "same interval on the nearest slices, as fractions of it; a mode change inside it "
                               "on its curve, followed in Fz from the slice's located change to the next slice's "
                               "load (interpolated in Fz between the slices below and above where none was "
                               "followed)",
                    "regions": "polygons of the shading's row segments between consecutive rows, one per region "
                               "until it splits or merges; their edges are the curves' crossings of the rows"}
                | ({} if self.warmed_from is None else {"warmed_from": self.warmed_from})
                | ({} if self.warm_refused is None else {"warm_refused": self.warm_refused}),
                "executor": self.executor, "warnings": list(self.warnings), "elapsed_s": self.elapsed_s,
                "version": __version__}

    def boundaries(self) -> list[tuple[str, np.ndarray]]:
        """The region boundaries as named polylines in (V, Fz): ``hopf<i>`` for the Hopf curves, then
        the kind and index of each fold and torus curve (``LPC2``), as the shading names them, with their
        located crossings of the slices' loads as vertices (:func:`curve_boundaries`)."""
        out = [(f"hopf{i}", c.p) for i, c in enumerate(self.hopf.curves)]
        for i, c in enumerate(self.cycles["curves"]):
            points = self.cycles[KEY_OF_KIND[c["kind"]]][_index_of_kind(self.cycles["curves"], i)]
            polyline = np.array([[q["V"], q["Fz"]] for q in points], float).reshape(-1, 2)
            located = [(x["V"], x["Fz"]) for x in c["crossings"]]
            out.append((f"{c['kind']}{i}", map_shading.with_points(polyline, located)))
        return out

    def warm_start(self) -> dict[str, Any]:
        """What a map of a nearby design is warmed from (:func:`shimmy.analyses.maps.warm_map.warm_map`),
        JSON-ready: the plane, grid and options, the boundaries, the slices' intervals, the arrangement
        (curve counts, GH and double-Hopf points, each cycle curve's closure and codimension-2
        points), a seed on each fold and torus curve and, per slice, the mode changes its intervals end
        at with their cycles."""
        options = self.options or BifurcationOptions(mesh_check=False)
        return {"config": self.config.value, "params": self.params.to_dict(), "v_range": list(self.v_range),
                "fz_range": list(self.fz_range), "resolution": self.resolution, "n_v": self.n_v,
                "options": dataclasses.asdict(options), "rows": self.shading_Fz.tolist(),
                "boundaries": [[name, p.tolist()] for name, p in self.boundaries()],
                "slices": [s.to_dict() | {"computed_at": s.computed_at or self.params.to_dict(),
                                          "mode_changes": [c.to_dict() for c in s.mode_changes]} for s in self.slices],
                "arrangement": arrangement(self.hopf, self.cycles),
                "seeds": [seed.to_dict() for seed in self.seeds],
                "links": [link.to_dict() for link in self.mode_links], "version": __version__}

    def write_csv(self, path) -> None:
        """The shading (the map's answer on its fine grid): one row per (Fz, V)
        (:func:`~shimmy.analyses.maps.summaries.write_map_csv`)."""
        write_map_csv(self.to_dict(), path)

    def summary_text(self, metrics: dict[str, Any] | None = None) -> str:
        """The short table ``python -m shimmy map`` prints, with ``metrics``
        (:func:`~shimmy.analyses.maps.design_metrics.metrics` of this map) its pure-torsion area
        (:func:`~shimmy.analyses.maps.summaries.map_summary`)."""
        result = self.to_dict()
        if metrics is not None:
            result["metrics"] = metrics
        return map_summary(result)


@dataclass(frozen=True, eq=False)
class HopfCurvesUnit:
    """A map's Hopf curves."""

    config: Configuration
    params: Parameters
    v_range: tuple[float, float]
    fz_range: tuple[float, float]

    def run(self) -> HopfCurvesResult:
        return hopf_curves(self.config, params=self.params, v_range=self.v_range, fz_range=self.fz_range)

    def describe(self) -> str:
        return "Hopf curves of straight rolling"


@dataclass(frozen=True, eq=False)
class SliceUnit:
    """A map's classified slice at one load."""

    config: Configuration
    Fz: float
    v_range: tuple[float, float]
    n_v: int
    params: Parameters
    options: BifurcationOptions

    def run(self) -> SliceResult:
        return map_slice(self.config, self.Fz, v_range=self.v_range, n_v=self.n_v, params=self.params,
                         options=self.options)

    def describe(self) -> str:
        return f"slice at Fz = {self.Fz / 1e3:.4g} kN"


#: A unit of a map: its Hopf curves, a slice, a unit of its curve search, or the links of two slices' mode changes.
MapUnit = HopfCurvesUnit | SliceUnit | SearchUnit | ModeLinksUnit


class _MapBuild:
    """One map's units and what their results add (see :func:`stability_maps`)."""

    def __init__(self, config: Configuration | str, v_range: tuple[float, float], fz_range: tuple[float, float],
                 resolution: int, params: Parameters | None, n_v: int, options: BifurcationOptions | None):
        self.config = Configuration.parse(config)
        self.params = params if params is not None else Parameters()
        self.v_range = check_range("v", v_range, V_RANGE, "m/s")
        self.fz_range = check_range("fz", fz_range, FZ_RANGE, "N")
        self.resolution = int(check_number("resolution", resolution, 2, 400, integer=True))
        self.n_v = int(check_number("n_v", n_v, 2, 2000, integer=True))
        self.options = options or BifurcationOptions(mesh_check=False)
        (v_min, v_max), (f_min, f_max) = self.v_range, self.fz_range
        self.loads = np.linspace(f_min, f_max, self.resolution)
        self.search = CurveSearch(self.config, self.params, ((v_min, v_max), (f_min, f_max)),
                                  (PointKind.FOLD_OF_CYCLES, PointKind.TORUS),
                                  tuple(float(f) for f in self.loads))
        self.rows = np.linspace(f_min, f_max, max(SHADING_ROWS, 4 * self.resolution))
        self.hopf: HopfCurvesResult | None = None
        self.slices: list[SliceResult] = []
        self.slice_loads = [float(f) for f in self.loads]
        self.rounds = 0
        self.links: list[ModeLink] | None = None  # None until the slices are all done: then followed
        self.search.expect_sources(len(self.loads))
        self.pending = 0  # units submitted or queued and not finished
        self.finished_at = 0.0  # s after the start when its last unit finished
        self.sketch: Sketch | None = None
        self._sketched: list[int] | None = None  # the curves (ids) known at the last sketch

    def _slice_unit(self, Fz: float) -> SliceUnit:
        return SliceUnit(self.config, float(Fz), self.v_range, self.n_v, self.params, self.options)

    def _counted(self, units: list[tuple[int, MapUnit]]) -> list[tuple[int, MapUnit]]:
        self.pending += len(units)
        return units

    def first_units(self) -> list[tuple[int, MapUnit]]:
        units = [(0, HopfCurvesUnit(self.config, self.params, self.v_range, self.fz_range))]
        return self._counted(units + [(2, self._slice_unit(Fz)) for Fz in self.loads])

    def _coverage(self) -> list[tuple[int, SliceUnit]]:
        """Slices through the regions that no slice load (computed or under way) crosses: what
        a region's boundaries are does not depend on the slices, only on the curves."""
        if self.rounds == COVERAGE_ROUNDS:
            return []
        (v_min, v_max), (f_min, f_max) = self.v_range, self.fz_range
        extra = map_shading.uncovered(self.slice_loads, _boundaries(self.hopf, self.search), self.rows,
                                      (v_min, v_max), min_width=(v_max - v_min) / (self.n_v - 1),
                                      min_area=COVERAGE_AREA * (v_max - v_min) * (f_max - f_min))
        self.rounds += bool(extra)
        self.slice_loads += extra
        self.search.expect_sources(len(extra))
        return [(2, self._slice_unit(Fz)) for Fz in extra]

    def done(self, unit: MapUnit, result: Any, elapsed: float) -> list[tuple[int, MapUnit]]:
        """The units that a finished unit's result adds: curves from its starts, coverage slices
        once the curves as they stand are all continued, the links of the slices' mode changes once
        every slice is done."""
        self.pending -= 1
        if isinstance(unit, ModeLinksUnit):
            self.links += result
            if self.pending == 0:
                self.finished_at = elapsed
            return []
        if isinstance(unit, HopfCurvesUnit):
            self.hopf = result
            more = [(0, u) for u in self.search.start_units(result)] + [(0, u) for u in self.search.continuations()]
        elif isinstance(unit, SliceUnit):
            self.slices.append(result)
            self.search.add_source(result.starts)
            more = [(0, u) for u in self.search.continuations()]
        else:
            more = [(0, u) for u in search_done(self.search, unit, result)]
        if self.search.idle() and self.hopf is not None:  # the curves as they stand
            more += self._coverage()
        if not more and self.pending == 0 and self.links is None:  # every slice done: their mode changes' links
            self.links = []
            more = [(2, links_unit(a, b, only, self.config, self.params, self.options.exact_nes))
                    for a, b, only in follows(self.slices)]
        if not more and self.pending == 0:
            self.finished_at = elapsed
        if self.sketch is not None and self.hopf is not None \
                and [id(c) for c in self.search.curves] != self._sketched:  # a curve added or replaced
            self._sketched = [id(c) for c in self.search.curves]
            self.sketch(sketch_of(self.config, self.v_range, self.fz_range, self.hopf, self.search.curves))
        return self._counted(more)

    def result(self, executor: str) -> StabilityMap:
        """The map from the finished units; ``elapsed_s``: until its last unit finished, plus this."""
        clock = time.perf_counter()
        (v_min, v_max), rows = self.v_range, self.rows
        hopf: HopfCurvesResult = self.hopf
        slices = sorted(self.slices, key=lambda s: s.Fz)
        cycles = self.search.result(self.finished_at).to_dict()
        warnings = list(hopf.warnings) + list(cycles.pop("warnings"))
        for s in slices:
            warnings += [f"Fz = {kn(s.Fz)}: {w}" for w in s.warnings]
        links = sorted(self.links or [], key=lambda link: (link.loads, link.start))
        segments, fallbacks = map_shading.row_segments(slices, _boundaries(hopf, self.search), rows, (v_min, v_max),
                                                       polylines(links))
        V = slices[0].V
        return StabilityMap(self.config, self.params, self.v_range, self.fz_range, V,
                            np.array([s.Fz for s in slices]), [s.types for s in slices], slices, hopf, cycles, rows,
                            map_shading.grid(segments, V), [map_shading.measures(r) for r in segments], fallbacks,
                            map_shading.polygons(segments, rows), lowest_shimmy(hopf, cycles, slices), executor,
                            self.finished_at + time.perf_counter() - clock, warnings, resolution=self.resolution,
                            n_v=self.n_v, options=self.options,
                            seeds=[CurveSeed.of(c, self.config.n_states) for c in self.search.result(0.0).curves],
                            mode_links=links)


def _tagged_unit(tagged: tuple[int, MapUnit]) -> Any:
    """A unit of map ``tagged[0]`` of :func:`stability_maps` (top level, for process pools and Dask)."""
    return tagged[1].run()


def stability_maps(configs: Sequence[Configuration | str], *, params: Parameters | None = None,
                   v_range: tuple[float, float] = DEFAULT_V_RANGE, fz_range: tuple[float, float] = DEFAULT_FZ_RANGE,
                   resolution: int = DEFAULT_MAP_SLICES, n_v: int = 100, options: BifurcationOptions | None = None,
                   executor=None, progress: Callable[[float, str], None] | None = None,
                   sketches: Sequence[Sketch | None] = ()) -> list[StabilityMap]:
    """The maps of several configurations (same plane, resolution and parameters), in the order
    given: :func:`stability_map` of each, their units all through one ``executor`` at once.

    The maps' units share the workers, most urgent first (every map's curve units ahead of any
    slice), so that no worker idles while another map's units wait: one map's last curve or slice
    no longer holds the workers back. Each map's ``elapsed_s`` is the time until its own last unit
    finished. ``sketches``: a :data:`Sketch` per map (or None), told each curve of it as it is known."""
    clock = time.perf_counter()
    configs = list(configs)
    builds = [_MapBuild(c, v_range, fz_range, resolution, params, n_v, options) for c in configs]
    if not builds:
        raise InvalidParameterError("configs", list(configs), "one or more configurations")
    if executor is None:
        with open_executor() as own:
            maps = stability_maps(configs, v_range=v_range, fz_range=fz_range, resolution=resolution, params=params,
                                  n_v=n_v, executor=own, progress=progress, options=options, sketches=sketches)
        for smap in maps:
            smap.executor = name_of(None)
        return maps
    report = progress or (lambda fraction, message: None)
    several = len(builds) > 1
    for build, sketch in zip(builds, sketches, strict=False):  # maps beyond the sketches given: none
        build.sketch = sketch

    def done(tagged: tuple[int, MapUnit], result: Any) -> list[tuple[int, tuple[int, MapUnit]]]:
        k, unit = tagged
        more = builds[k].done(unit, result, time.perf_counter() - clock)
        return [(priority, (k, u)) for priority, u in more]

    def describe(tagged: tuple[int, MapUnit]) -> str:
        k, unit = tagged
        return f"{builds[k].config.value}: {unit.describe()}" if several else unit.describe()

    units = [(priority, (k, unit)) for k, b in enumerate(builds) for priority, unit in b.first_units()]
    run_dynamic(_tagged_unit, units, executor, done, report, describe,
                lambda tagged: "slices" if isinstance(tagged[1], SliceUnit)
                else "mode changes followed" if isinstance(tagged[1], ModeLinksUnit) else "curve units")
    maps = [b.result(type(executor).__name__) for b in builds]
    report(1.0, "done")
    return maps


def stability_map(config: Configuration | str, *, params: Parameters | None = None,
                  v_range: tuple[float, float] = DEFAULT_V_RANGE, fz_range: tuple[float, float] = DEFAULT_FZ_RANGE,
                  resolution: int = DEFAULT_MAP_SLICES, n_v: int = 100, options: BifurcationOptions | None = None,
                  executor=None, progress: Callable[[float, str], None] | None = None,
                  warm_from: dict[str, Any] | None = None, sketch: Sketch | None = None) -> StabilityMap:
    """The (V, Fz) stability map of one configuration: its region boundaries continued as curves,
    the regions' types from ``resolution`` classified Fz slices (and further ones where a region
    lies between them), read off on a fine grid with ``n_v`` speeds.

    One computation of units through ``executor`` (any :class:`concurrent.futures.Executor`;
    default: see :mod:`shimmy.analyses.core.executors`), most urgent first: the Hopf curves, then the
    branches beside their GH and double-Hopf points, and the slices' diagrams; each fold or torus
    curve is continued as soon as a start for it is known (a GH or double-Hopf point, or a
    slice's LPC / NS point), ahead of the remaining slices.

    ``warm_from``: the :meth:`StabilityMap.warm_start` of a map of the same configuration, plane,
    grid and options at a nearby design: the map is warmed from it where the arrangement of the
    curves is unchanged (:func:`shimmy.analyses.maps.warm_map.warm_map`; ``methods`` says
    ``warmed_from``), else computed cold (``methods`` says ``warm_refused`` and why).

    ``sketch`` (a :data:`Sketch`) is told the curves known so far each time one more is: the Hopf
    curves first, then each fold and torus curve, before the slices and the shading are done."""
    refused = None
    if warm_from is not None:
        from .warm_map import NotWarm, compatible, warm_map

        params = params if params is not None else Parameters()
        refused = compatible(warm_from, config, v_range=v_range, fz_range=fz_range, resolution=resolution, n_v=n_v,
                             options=options or BifurcationOptions(mesh_check=False))
        if refused is None:
            try:
                return warm_map(warm_from, params=params, executor=executor, progress=progress, sketch=sketch)
            except NotWarm as exc:
                refused = exc.reason
            except Exception as exc:  # noqa: BLE001 - a warm start that fails in any way: the cold map answers
                log.warning("warming the %s map failed (%s: %s): computing it cold", config, type(exc).__name__, exc)
                refused = f"warming failed ({type(exc).__name__}: {exc})"
        if progress is not None:
            progress(0.0, f"computing cold: {refused}")
    smap = stability_maps([config], v_range=v_range, fz_range=fz_range, resolution=resolution, params=params, n_v=n_v,
                          executor=executor, progress=progress, options=options, sketches=[sketch])[0]
    if refused is not None:
        smap.warm_refused = refused
    return smap


def _index_of_kind(curves: list[dict[str, Any]], i: int) -> int:
    """The position of curve ``i`` among the curves of its kind (the order of ``fold_curves`` etc.)."""
    return sum(1 for c in curves[:i] if c["kind"] == curves[i]["kind"])


def arrangement(hopf: HopfCurvesResult, cycles: dict[str, Any]) -> dict[str, Any]:
    """What must stay the same between two designs for a map to be warmed from the other: the
    number of Hopf curves with the closure of each, the GH and double-Hopf points, and each fold and
    torus curve's kind, closure and codimension-2 points (by kind, in order along it)."""
    return {"hopf_curves": [bool(c.closed) for c in hopf.curves], "gh_points": len(hopf.gh_points),
            "double_hopf_points": len(hopf.double_hopf_points),
            "cycle_curves": [{"kind": str(c["kind"]), "closed": bool(c["closed"]),
                              "codim2": [str(q["kind"]) for q in c["codim2_points"]]} for c in cycles["curves"]]}


def _boundaries(hopf: HopfCurvesResult, search: CurveSearch) -> list[tuple[str, np.ndarray]]:
    """The region boundaries of a map being built (:func:`curve_boundaries` of its curves so far)."""
    return curve_boundaries(hopf, search.result(0.0).curves)


def curve_boundaries(hopf: HopfCurvesResult, curves: Sequence[GearCycleCurve]) -> list[tuple[str, np.ndarray]]:
    """The region boundaries: every Hopf, fold and torus curve as a polyline in (V, Fz), named
    ``hopf<i>``, then the kind and index of each cycle curve (``LPC2``), as the shading names them; a
    cycle curve's located crossings of the slices' loads put in as vertices
    (:func:`~shimmy.analyses.maps.map_shading.with_points`)."""
    out = [(f"hopf{i}", c.p) for i, c in enumerate(hopf.curves)]
    out += [(f"{c.kind}{i}", map_shading.with_points(c.curve.p, [(float(q.p), float(q.data["p2"]))
                                                                 for q in c.curve.points_of(PointKind.P2_MARK)]))
            for i, c in enumerate(curves)]
    return out


def lowest_shimmy(hopf: HopfCurvesResult, cycles: dict[str, Any], slices: list[SliceResult]) -> dict[str, Any] | None:
    """Lowest load with any shimmy: the located lowest point of the Hopf and fold curves, or the
    lowest slice with a type other than Stable, whichever is lower."""
    candidates = []
    low = hopf.fz_minimum
    if low is not None and any(c.p.size for c in hopf.curves):
        candidates.append({"Fz": low["Fz"], "V": low["V"], "source": "Hopf curve"})
    for c in cycles["curves"]:
        if c["kind"] == PointKind.FOLD_OF_CYCLES:
            candidates.append({"Fz": c["fz_min"]["Fz"], "V": c["fz_min"]["V"], "source": "fold-of-cycles curve"})
    for s in slices:
        if s.intervals:
            candidates.append({"Fz": s.Fz, "V": s.intervals[0]["V_start"], "source": "classified slice"})
            break
    return min(candidates, key=lambda c: c["Fz"]) if candidates else None

