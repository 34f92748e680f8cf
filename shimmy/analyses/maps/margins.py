"""Disturbance margins at one operating point: how large a kick starts shimmy, and which shimmy it starts.

The study defines shimmy by what follows a disturbance, and where two attractors coexist, which one
the gear reaches depends on the size and the kind of the disturbance. At a point (V, Fz):

* :func:`margins`: the attractors (:func:`~shimmy.analyses.maps.point_attractors.point_attractors`:
  the stable equilibrium and cycles of the one-parameter diagram at V, the saddle cycles between
  them, runs from the standard and two large starts; the standard start's marked), and for each the
  smallest disturbance from straight rolling that ends on it, the rest of the state at rest:
  along one component (``direction`` psi, dpsi, delta or ddelta): a bracketing scan on a geometric
  grid of sizes, then bisection to ``rtol`` (:mod:`shimmy.analyses.core.basins`); over all
  directions of the four (``direction="energy"``): the smallest energy, from a sweep of 16
  directions with the bisection along each and a pattern search on the unit sphere from the best.
  Sizes are measured in the energy norm of the linearised gear
  (:class:`~shimmy.analyses.maps.point_attractors.EnergyNorm`), as the yaw angle of the same
  energy: a yaw kick psi0 has size psi0. Every threshold is checked by two full runs (to
  ``t_max``, judged on their last 20 s) at the ends of its bracket, just below and just above it;
  both outcomes are in the result, and ``confirmed`` says whether they agree with it.
* :func:`basins`: the share of disturbances up to a size (uniform in the energy ball, seeded) that
  ends on each attractor, with 95 % Wilson intervals.

All runs go through ``executor`` (default: :func:`~shimmy.analyses.core.executors.open_executor`), a
few per unit, side by side.
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from ...version import __version__
from ...errors import InvalidParameterError
from ...model.configurations import Configuration
from ...model.parameters import DIAGRAM_V_RANGE, Parameters, check_operating_point
from ...model.units import kn
from ..core.basins import (FAILED, UNSETTLED, Ray, Threshold, geometric_sizes, refine, sample_ball, scan,
                           smallest_over_directions, sweep_directions, wilson)
from ..core.executors import describe_work_unit, executor_width, name_of, open_executor, run_units, run_work_unit
from .margin_options import COMPONENTS, BasinOptions, MarginOptions
from .point_attractors import MATCH_TOL, WINDOW, PointAttractors, RunUnit, point_attractors
from .summaries import basins_summary, margins_summary

ENERGY_COMPONENTS = tuple(COMPONENTS)
MIN_ANGLE_DEG = 1.0
#: Sizes probed per round of the bisection (:func:`~shimmy.analyses.core.basins.refine`'s ``width``): two
#: interior sizes of a bracket while it is the only one open (trisection: two runs side by side), one per bracket
#: when several are. Fixed, not the executor's worker count, so that a margin is the same on every executor.
ROUND_WIDTH = 2


def _header(config: Configuration, V: float, Fz: float, params: Parameters, found: PointAttractors,
            options: Any, runs: int, elapsed: float, executor: str, warnings: list[str]) -> dict[str, Any]:
    return {"config": config.value, "V": V, "Fz": Fz, "options": options.to_dict(),
            "straight_rolling_stable": found.straight_rolling_stable, "standard_start": found.standard,
            "saddles": found.saddles, "norm": found.norm.to_dict(), "runs": runs, "elapsed_s": elapsed,
            "executor": executor, "warnings": list(found.warnings) + list(warnings), "params": params.to_dict(),
            "version": __version__}


@dataclass(frozen=True)
class MarginsResult:
    """The attractors at a point, each with the smallest disturbance that ends on it (``min_disturbance``:
    value, unit, direction, method, tolerance, the bracket, the energy, the check runs)."""

    config: Configuration
    V: float
    Fz: float
    params: Parameters
    options: MarginOptions
    found: PointAttractors
    minima: list[dict[str, Any]]
    runs: int
    unsettled: int
    elapsed_s: float
    executor: str
    warnings: list[str] = field(default_factory=list)

    @property
    def attractors(self) -> list[dict[str, Any]]:
        return [{**a, "min_disturbance": m} for a, m in zip(self.found.attractors, self.minima, strict=True)]

    def to_dict(self) -> dict[str, Any]:
        return {**_header(self.config, self.V, self.Fz, self.params, self.found, self.options, self.runs,
                          self.elapsed_s, self.executor, self.warnings),
                "direction": self.options.direction, "attractors": self.attractors, "unsettled_runs": self.unsettled}

    def summary_text(self) -> str:
        """The lines ``python -m shimmy margins`` prints (:func:`~shimmy.analyses.maps.summaries.margins_summary`)."""
        return margins_summary(self.to_dict())


@dataclass(frozen=True)
class BasinsResult:
    """The attractors at a point, each with the share of the sampled disturbances that ends on it (``basin``:
    count, fraction, 95 % Wilson interval), and the runs that settled on none (``unsettled``, ``failed``)."""

    config: Configuration
    V: float
    Fz: float
    params: Parameters
    options: BasinOptions
    found: PointAttractors
    counts: list[int]
    unsettled: int
    failed: int
    runs: int
    elapsed_s: float
    executor: str

    def to_dict(self) -> dict[str, Any]:
        n = self.options.samples
        attractors = [{**a, "basin": {"count": c, "fraction": c / n, "ci95": list(wilson(c, n))}}
                      for a, c in zip(self.found.attractors, self.counts, strict=True)]
        norm = self.found.norm
        return {**_header(self.config, self.V, self.Fz, self.params, self.found, self.options, self.runs,
                          self.elapsed_s, self.executor, []),
                "attractors": attractors, "unsettled": self.unsettled, "failed": self.failed,
                "energy_J": norm.energy(self.options.radius),
                "method": f"{n} disturbances uniform in the ball E <= {norm.energy(self.options.radius):.6g} J of "
                          f"(psi, dpsi, delta, ddelta) (the energy of a yaw angle of {self.options.radius:g} rad), "
                          f"seed {self.options.seed}; shares with 95 % Wilson score intervals"}

    def summary_text(self) -> str:
        """The lines ``python -m shimmy basins`` prints (:func:`~shimmy.analyses.maps.summaries.basins_summary`)."""
        return basins_summary(self.to_dict())


@functools.lru_cache(maxsize=8)
def diagram_at(config: Configuration, Fz: float, params: Parameters, v_max: float):
    """The one-parameter diagram in V (1 to ``v_max`` m/s) at Fz, kept for the process (the attractors of
    every point at that load read it)."""
    from ..diagrams.bifurcation import BifurcationOptions, bifurcation

    return bifurcation(config, Fz, params=params, v_range=(DIAGRAM_V_RANGE[0], v_max),
                       options=BifurcationOptions(mesh_check=False))


class _Runs:
    """Runs at one point through the executor, a few per unit, counted, with progress."""

    def __init__(self, config: Configuration, V: float, Fz: float, params: Parameters, executor, t_max: float,
                 report: Callable[[float, str], None], expected: int):
        self.config, self.V, self.Fz, self.params, self.executor, self.t_max = config, V, Fz, params, executor, t_max
        self.width = max(1, min(64, executor_width(executor)))
        self.report, self.expected, self.count, self.unsettled = report, max(1, expected), 0, 0
        self.found: PointAttractors | None = None

    def units(self, units: list[RunUnit]) -> list[list[tuple]]:
        return run_units(run_work_unit, units, self.executor, describe_unit=describe_work_unit)

    def run(self, starts: list[np.ndarray], full: bool = False) -> list[tuple]:
        """(label, psi_amp, delta_amp, t, settled) of the run from each start."""
        if not starts:
            return []
        per = max(1, min(8, math.ceil(len(starts) / (4 * self.width))))
        chunks = [starts[k:k + per] for k in range(0, len(starts), per)]
        units = [RunUnit(self.config, self.V, self.Fz, self.params, tuple(tuple(map(float, x)) for x in chunk),
                         self.found.classifier, self.t_max, full) for chunk in chunks]
        out = [end for ends in self.units(units) for end in ends]
        self.count += len(starts)
        self.unsettled += sum(end[0] < 0 for end in out)
        self.report(min(0.95, 0.1 + 0.85 * self.count / self.expected), f"{self.count} runs")
        return out


def _state(n: int, names: tuple[str, ...], scales: np.ndarray, z: np.ndarray) -> np.ndarray:
    x = np.zeros(n)
    for name, s, value in zip(names, scales, z, strict=True):
        x[COMPONENTS[name][0]] = s * value
    return x


def _prepare(config, V, Fz, params, diagram, executor, t_max, report, expected) -> _Runs:
    runs = _Runs(config, V, Fz, params, executor, t_max, report, expected)
    if diagram is None:
        report(0.0, f"bifurcation diagram at {Fz / 1e3:g} kN")
        diagram = diagram_at(config, Fz, params, max(DIAGRAM_V_RANGE[1], V))
    elif abs(diagram.Fz - Fz) > 1e-9 * Fz or not diagram.v_min <= V <= diagram.v_max:
        raise InvalidParameterError("diagram", f"Fz = {kn(diagram.Fz)}, V {diagram.v_min:g}..{diagram.v_max:g} m/s",
                                    f"a diagram at Fz = {kn(Fz)} whose speeds include V = {V:g} m/s")
    report(0.05, "attractors")
    runs.found = point_attractors(config, V, Fz, params=params, diagram=diagram, run_units=runs.units, t_max=t_max)
    return runs


def _outcome(found: PointAttractors, end: tuple, size: float, unit: str, l_g: float) -> dict[str, Any]:
    """A check run's end: the size it started from (in ``unit``), the attractor it ends on (None: none), its mode."""
    label, psi, delta, t, _ = end
    mode = found.attractors[label]["mode"] if label >= 0 else ("failed" if label == FAILED else "unsettled")
    return {"size": size, "unit": unit, "ends_on": label if label >= 0 else None, "mode": mode,
            "amplitude": {"psi": None if math.isnan(psi) else psi,
                          "lateral": None if math.isnan(delta) else l_g * delta},
            "t_s": t}


def _method(options: MarginOptions, names: tuple[str, ...], swept: int) -> str:
    unit = "rad (the yaw angle of the same energy)" if len(names) > 1 else COMPONENTS[names[0]][1]
    runs = (f"each run classified by its amplitudes within {100 * MATCH_TOL:g} % of the attractor's (energy-weighted) "
            f"and nearer to it than to any saddle cycle over two {WINDOW:g} s windows (at most {options.t_max:g} s)")
    if len(names) == 1:
        return (f"bracketing scan of {options.scan_points} sizes in geometric steps from {options.min_size:g} to "
                f"{options.max_size:g} {unit} (in {names[0]}: the sizes of the same energy), then bisection to "
                f"{options.rtol:g} of the threshold; {runs}")
    return (f"sweep of {swept} directions in ({', '.join(names)}) (the axes and the diagonals of every pair, in the "
            f"energy norm), along each a bracketing scan of {options.scan_points} sizes from {options.min_size:g} to "
            f"{options.max_size:g} {unit} and bisection to {options.rtol:g}; then a pattern search on the unit sphere "
            f"from the best direction, down to {MIN_ANGLE_DEG:g} degree; {runs}")


def _unreached(options: MarginOptions, names: tuple[str, ...], norm, swept: int) -> dict[str, Any]:
    energy = len(names) > 1
    limit = norm.energy(options.max_size) if energy else options.max_size * norm.scales(names)[0]
    unit = "J" if energy else COMPONENTS[names[0]][1]
    return {"value": None, "unit": unit, "direction": "energy" if energy else names[0],
            "method": _method(options, names, swept), "tolerance": None, "reached": False,
            "note": f"no disturbance up to {limit:.4g} {unit} {'along any direction swept ' if energy else ''}"
                    "ends on it", "check": None}


def _minimum(found: PointAttractors, options: MarginOptions, names: tuple[str, ...], scales: np.ndarray, norm,
             t: Threshold, u: np.ndarray, check: dict[str, Any], label: int, swept: int, l_g: float) -> dict[str, Any]:
    """``min_disturbance`` of one attractor from its threshold ``t`` (sizes) along ``u``."""
    energy = len(names) > 1
    if energy:
        unit = "J"
        convert = norm.energy
        value = 0.0 if t.lower == 0.0 else norm.energy(t.value)
        tolerance = norm.energy(t.upper) if t.lower == 0.0 else 0.5 * (norm.energy(t.upper) - norm.energy(t.lower))
    else:
        unit = COMPONENTS[names[0]][1]

        def convert(size: float) -> float:
            return float(size * scales[0])
        value, tolerance = convert(t.value), convert(t.tolerance)
    sides = {side: None if check[side] is None else _outcome(found, check[side][1], convert(check[side][0]), unit, l_g)
             for side in ("below", "above")}
    below_ok = sides["below"] is None or sides["below"]["ends_on"] != label
    confirmed = bool(below_ok and sides["above"] is not None and sides["above"]["ends_on"] == label)
    out = {"value": value, "unit": unit, "direction": options.direction, "method": _method(options, names, swept),
           "tolerance": tolerance, "rtol": options.rtol, "reached": True, "lower": convert(t.lower),
           "upper": convert(t.upper), "energy_J": norm.energy(t.value), "equivalent_psi": t.value,
           "disturbance": {name: float(s * c * t.value) for name, s, c in zip(names, scales, u, strict=True)},
           "check": {**sides, "confirmed": confirmed}}
    if t.lower == 0.0:
        out["note"] = (f"reached from the smallest size scanned ({convert(t.upper):.4g} {unit}): the threshold is "
                       "below it")
    return out


def margins(config: Configuration | str, V: float, Fz: float, *, params: Parameters | None = None,
            options: MarginOptions | None = None, diagram=None, executor=None,
            progress: Callable[[float, str], None] | None = None, **option_overrides) -> MarginsResult:
    """The attractors at (V, Fz) (m/s, N) and the smallest disturbance from straight rolling that ends on each,
    along ``options.direction`` (module docstring). ``diagram``: the one-parameter diagram in V at Fz, if
    already computed (default: computed, and kept for the process). Options as a :class:`MarginOptions` or as
    keyword overrides (``direction="energy"``)."""
    clock = time.perf_counter()
    config = Configuration.parse(config)
    V, Fz = check_operating_point(V, Fz)
    params = params if params is not None else Parameters()
    options = options or MarginOptions()
    if option_overrides:
        options = MarginOptions(**{**options.to_dict(), **option_overrides})
    if executor is None:
        with open_executor() as own:
            result = margins(config, V, Fz, params=params, options=options, diagram=diagram, executor=own,
                             progress=progress)
        return MarginsResult(**{**result.__dict__, "executor": name_of(None)})
    report = progress or (lambda fraction, message: None)
    energy = options.direction == "energy"
    names = ENERGY_COMPONENTS if energy else (options.direction,)
    per_ray = options.scan_points + 10
    expected = 3 + (len(sweep_directions(len(names))) * per_ray + 80 if energy else per_ray) + 6
    runs = _prepare(config, V, Fz, params, diagram, executor, options.t_max, report, expected)
    found = runs.found
    norm = found.norm
    scales = norm.scales(names)
    n = config.n_states

    def probe(points: np.ndarray) -> list[int]:
        return [end[0] for end in runs.run([_state(n, names, scales, z) for z in points])]

    sizes = geometric_sizes(options.min_size, options.max_size, options.scan_points)
    report(0.1, "bracketing scan")
    if energy:
        rays, best = smallest_over_directions(probe, len(names), sizes, options.rtol, width=ROUND_WIDTH,
                                              min_angle=math.radians(MIN_ANGLE_DEG))
        found_at = {label: (s.threshold, s.direction) for label, s in best.items()}
        swept = len(rays)
    else:
        ray = Ray(np.array([1.0]))
        scan([ray], sizes, probe)
        refine([ray], probe, options.rtol, ROUND_WIDTH)
        found_at = {label: (ray.threshold(label), ray.direction) for label in ray.reached()}
        swept = 1
    report(0.95, "checking every threshold by two runs")
    checks: list[tuple[int, str, float]] = []
    starts = []
    for label, (t, u) in found_at.items():
        for side, size in (("below", t.lower), ("above", t.upper)):
            if size > 0.0:
                checks.append((label, side, size))
                starts.append(_state(n, names, scales, size * u))
    ends = runs.run(starts, full=True)
    checked: dict[int, dict[str, Any]] = {}
    for (label, side, size), end in zip(checks, ends, strict=True):
        checked.setdefault(label, {"below": None, "above": None})[side] = (size, end)
    warnings: list[str] = []
    minima = []
    for label, attractor in enumerate(found.attractors):
        if label not in found_at:
            minima.append(_unreached(options, names, norm, swept))
            continue
        t, u = found_at[label]
        minima.append(_minimum(found, options, names, scales, norm, t, u, checked.get(label, {"below": None,
                               "above": None}), label, swept, params.gear.l_g))
        if not minima[-1]["check"]["confirmed"]:
            warnings.append(f"the threshold of the {attractor['mode']} attractor is not confirmed by its check runs")
    report(1.0, "done")
    return MarginsResult(config, V, Fz, params, options, found, minima, runs.count + found.runs, runs.unsettled,
                         time.perf_counter() - clock, type(executor).__name__, warnings)


def basins(config: Configuration | str, V: float, Fz: float, *, params: Parameters | None = None,
           options: BasinOptions | None = None, diagram=None, executor=None,
           progress: Callable[[float, str], None] | None = None, **option_overrides) -> BasinsResult:
    """The attractors at (V, Fz) and the share of disturbances of (psi, dpsi, delta, ddelta) uniform in the
    energy ball of ``options.radius`` (the yaw angle of the same energy, rad) ending on each, with 95 % Wilson
    intervals (module docstring)."""
    clock = time.perf_counter()
    config = Configuration.parse(config)
    V, Fz = check_operating_point(V, Fz)
    params = params if params is not None else Parameters()
    options = options or BasinOptions()
    if option_overrides:
        options = BasinOptions(**{**options.to_dict(), **option_overrides})
    if executor is None:
        with open_executor() as own:
            result = basins(config, V, Fz, params=params, options=options, diagram=diagram, executor=own,
                            progress=progress)
        return BasinsResult(**{**result.__dict__, "executor": name_of(None)})
    report = progress or (lambda fraction, message: None)
    runs = _prepare(config, V, Fz, params, diagram, executor, options.t_max, report, options.samples)
    found = runs.found
    names = ENERGY_COMPONENTS
    scales = found.norm.scales(names)
    points = sample_ball(len(names), options.radius, options.samples, options.seed)
    labels = [end[0] for end in runs.run([_state(config.n_states, names, scales, z) for z in points])]
    counts = [labels.count(k) for k in range(len(found.attractors))]
    report(1.0, "done")
    return BasinsResult(config, V, Fz, params, options, found, counts, labels.count(UNSETTLED), labels.count(FAILED),
                        runs.count + found.runs, time.perf_counter() - clock, type(executor).__name__)
