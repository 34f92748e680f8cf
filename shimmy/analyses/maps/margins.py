"""Disturbance margins at one operating point: how large a kick starts shimmy, and which shimmy it starts.

The study defines shimmy by what follows a disturbance, and where two attractors coexist, which one
the gear reaches depends on the size and the kind of the disturbance. At a point (V, Fz):

* :func:`margins`: the attractors (:func:`~shimmy.analyses.maps.point_attractors.point_attractors`:
  the stable equilibrium and cycles of the one-parameter diagram at V, the saddle cycles between
  them, runs from the standard and two large starts; the standard start's marked), and for each the
  smallest disturbance that ends on it, added to straight rolling (``origin="straight_rolling"``, the
  rest of the state at rest) or to the attractor the standard start reaches
  (``origin="standard_attractor"``: at ``phases`` equally spaced phases of its orbit, phase 0 at a yaw
  maximum, each threshold the smallest over the phases; with an even number of phases, as the
  default 8, kicks of both signs are covered, a kick -u at one phase being the kick u half a period
  later on the gear's symmetric cycles (its vector field is odd); with an odd number only +u):
  along one component (``direction`` psi, dpsi, delta or ddelta) or a given mix of them
  (``direction="mix"``, ``mix="psi=0.01,dpsi=0.2"``: the direction of that vector in the energy
  norm; the threshold also as a multiple of the mix, ``factor``): a bracketing scan on a geometric
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
from ...errors import ConvergenceError, InvalidParameterError
from ...model.configurations import Configuration
from ...model.parameters import DIAGRAM_V_RANGE, Parameters, check_operating_point
from ...model.units import kn
from ..core.basins import (FAILED, UNSETTLED, Ray, Threshold, geometric_sizes, refine, sample_ball, scan,
                           smallest_over_directions, sweep_directions, wilson)
from ..core.executors import describe_work_unit, executor_width, name_of, open_executor, run_units, run_work_unit
from .margin_options import COMPONENTS, BasinOptions, MarginOptions, mix_vector
from .point_attractors import (DISCOVERY_STARTS, MATCH_TOL, ORBIT_SETTLED, WINDOW, OrbitUnit, PointAttractors, RunUnit,
                               point_attractors)
from .summaries import basins_summary, margins_summary

ENERGY_COMPONENTS = tuple(COMPONENTS)
MIN_ANGLE_DEG = 1.0
#: Rows of the orbit between two sampled phases: the phase of a smallest threshold is located to 1 / (phases *
#: PHASE_STEPS) of the period (three halvings between the sampled phases).
PHASE_STEPS = 8
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
    origin: dict[str, Any] = field(default_factory=lambda: {"kind": "straight_rolling", "attractor": None})

    @property
    def attractors(self) -> list[dict[str, Any]]:
        return [{**a, "min_disturbance": m} for a, m in zip(self.found.attractors, self.minima, strict=True)]

    def to_dict(self) -> dict[str, Any]:
        return {**_header(self.config, self.V, self.Fz, self.params, self.found, self.options, self.runs,
                          self.elapsed_s, self.executor, self.warnings),
                "direction": self.options.direction, "origin": self.origin, "attractors": self.attractors,
                "unsettled_runs": self.unsettled}

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
        self.expected, self.count, self.unsettled, self.shown = max(1, expected), 0, 0, 0.0
        self.found: PointAttractors | None = None

        def forward(fraction: float, message: str) -> None:  # a bar that never goes back
            self.shown = max(self.shown, fraction)
            report(self.shown, message)
        self.report = forward

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


def _state(base: np.ndarray, names: tuple[str, ...], scales: np.ndarray, z: np.ndarray) -> np.ndarray:
    """``base`` (the state kicked) plus the disturbance ``z`` (sizes along ``names``, scaled to state units)."""
    x = base.copy()
    for name, s, value in zip(names, scales, z, strict=True):
        x[COMPONENTS[name][0]] += s * value
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


@dataclass(frozen=True)
class Direction:
    """What a margin is searched along: ``kind`` "component" (one of psi, dpsi, delta, ddelta), "mix" (a given mix of
    them) or "energy" (all four); the components ``names`` and their ``scales`` (state change per unit of size);
    for a component or a mix the unit vector ``u`` in size coordinates, and ``length``: the size of the mix as
    given (a threshold of size a is a / length times the mix)."""

    kind: str
    names: tuple[str, ...]
    scales: np.ndarray
    u: np.ndarray | None
    length: float = 1.0

    @classmethod
    def of(cls, options: MarginOptions, norm) -> "Direction":
        if options.direction == "energy":
            return cls("energy", ENERGY_COMPONENTS, norm.scales(ENERGY_COMPONENTS), None)
        if options.direction == "mix":
            given = mix_vector(options.mix)
            names = tuple(given)
            scales = norm.scales(names)
            z = np.array([given[name] for name in names]) / scales
            top = float(np.abs(z).max())  # the norm of z / top: no overflow or underflow on the way
            length = top * float(np.linalg.norm(z / top))
            return cls("mix", names, scales, (z / top) / float(np.linalg.norm(z / top)), length)
        names = (options.direction,)
        return cls("component", names, norm.scales(names), np.array([1.0]))

    @property
    def in_energy(self) -> bool:
        """Sizes reported as energies (J): several components at once."""
        return self.kind != "component"


@dataclass(frozen=True)
class Origin:
    """The states a disturbance may be added to (``states``: one row per phase, ``PHASE_STEPS`` rows between two
    sampled phases; straight rolling: one row of zeros), the rows sampled first (``sampled``), the phases as
    fractions of the period after a yaw maximum (None for straight rolling), and what it is (``info``, the
    result's ``origin``)."""

    states: np.ndarray
    sampled: tuple[int, ...]
    phases: np.ndarray | None
    info: dict[str, Any]

    @property
    def refined(self) -> bool:
        """Whether the phase of each smallest threshold is located between the sampled phases."""
        return len(self.sampled) > 1


def _straight(n: int, why: str) -> Origin:
    return Origin(np.zeros((1, n)), (0,), None, {"kind": "straight_rolling", "attractor": None, "note": why})


def _origin(runs: _Runs, options: MarginOptions, n: int) -> Origin:
    """Straight rolling, or the attractor the standard start reaches (``options.origin``), sampled at
    ``options.phases`` phases of its orbit (:func:`~shimmy.analyses.maps.point_attractors.orbit_states`)."""
    found = runs.found
    if options.origin == "straight_rolling":
        return _straight(n, "straight rolling, the rest of the state at rest")
    label = found.standard
    if label is None:
        raise ConvergenceError(f"the standard start (psi = {DISCOVERY_STARTS[0][2]:g} rad) settles on no attractor "
                               f"within {options.t_max:g} s at V = {runs.V:g} m/s, Fz = {kn(runs.Fz)}: there is no "
                               "attractor to disturb (origin standard_attractor)")
    attractor = found.attractors[label]
    if attractor["kind"] == "equilibrium":
        return _straight(n, "the standard start ends on straight rolling: the disturbance is added to it")
    if attractor["kind"] == "simulation":  # found by a run, not a cycle of the diagram: no period to kick at
        raise InvalidParameterError("origin", options.origin, "straight_rolling at this point", "has no period here: "
                                    f"the standard start settles on a motion the diagram does not have at V = "
                                    f"{runs.V:g} m/s, Fz = {kn(runs.Fz)} (quasi-periodic, perhaps)")
    x0 = np.zeros(n)
    x0[0] = DISCOVERY_STARTS[0][2]
    steps = PHASE_STEPS if options.phases > 1 else 1
    rows = options.phases * steps
    unit = OrbitUnit(runs.config, runs.V, runs.Fz, runs.params, tuple(map(float, x0)), found.classifier, label,
                     options.t_max, rows)
    orbit = runs.units([unit])[0]
    if orbit["states"] is None:
        raise ConvergenceError(f"the orbit of the standard start's {attractor['mode']} attractor at V = {runs.V:g} "
                               f"m/s, Fz = {kn(runs.Fz)} was not reached: {orbit['status']}")
    info = {"kind": "standard_attractor", "attractor": label, "mode": attractor["mode"],
            "period_s": orbit["period"], "phases": options.phases, "settled_at_s": orbit["t_s"],
            "note": f"the {attractor['mode']} {attractor['kind']} the standard start reaches, kicked at "
                    + (f"{options.phases} phases of its yaw period ({orbit['period']:.4g} s; phase 0 at a yaw "
                       f"maximum, to 1 ms), each threshold the smallest over them, its phase located to 1/{rows} of "
                       "the period between the sampled ones" if options.phases > 1 else
                       f"a yaw maximum (to 1 ms) of its period ({orbit['period']:.4g} s)")}
    if not orbit["settled"]:
        info["warning"] = (f"its amplitude still changed by more than {100 * ORBIT_SETTLED:g} % per {WINDOW:g} s at "
                           f"{options.t_max:g} s")
    return Origin(orbit["states"][:, :n], tuple(range(0, rows, steps)), np.arange(rows) / rows, info)


def _outcome(found: PointAttractors, end: tuple, size: float, unit: str, l_g: float, x0: np.ndarray) -> dict[str, Any]:
    """A check run's end: the size it started from (in ``unit``) and its whole start state ``x0`` (a simulation's
    ``x0``), the attractor it ends on (None: none), its mode."""
    label, psi, delta, t, _ = end
    mode = found.attractors[label]["mode"] if label >= 0 else ("failed" if label == FAILED else "unsettled")
    return {"size": size, "unit": unit, "x0": [float(x) for x in x0], "ends_on": label if label >= 0 else None,
            "mode": mode,
            "amplitude": {"psi": None if math.isnan(psi) else psi,
                          "lateral": None if math.isnan(delta) else l_g * delta},
            "t_s": t}


def _method(options: MarginOptions, d: Direction, swept: int, origin: Origin) -> str:
    unit = "rad (the yaw angle of the same energy)" if d.in_energy else COMPONENTS[d.names[0]][1]
    runs = (f"each run classified by its amplitudes within {100 * MATCH_TOL:g} % of the attractor's (energy-weighted) "
            f"and nearer to it than to any saddle cycle over two {WINDOW:g} s windows (at most {options.t_max:g} s)")
    start = f"from {origin.info['note']}; "
    if d.kind == "component":
        return (f"{start}bracketing scan of {options.scan_points} sizes in geometric steps from {options.min_size:g} "
                f"to {options.max_size:g} {unit} (in {d.names[0]}: the sizes of the same energy), then bisection to "
                f"{options.rtol:g} of the threshold; {runs}")
    if d.kind == "mix":
        return (f"{start}along the mix {options.mix} (its direction in the energy norm): bracketing scan of "
                f"{options.scan_points} sizes in geometric steps from {options.min_size:g} to {options.max_size:g} "
                f"{unit}, then bisection to {options.rtol:g} of the threshold; {runs}")
    return (f"{start}sweep of {swept} directions in ({', '.join(d.names)}) (the axes and the diagonals of every pair, "
            f"in the energy norm), along each a bracketing scan of {options.scan_points} sizes from "
            f"{options.min_size:g} to {options.max_size:g} {unit} and bisection to {options.rtol:g}; then a pattern "
            f"search on the unit sphere from the best direction, down to {MIN_ANGLE_DEG:g} degree; {runs}")


def _unreached(options: MarginOptions, d: Direction, norm, swept: int, origin: Origin) -> dict[str, Any]:
    limit = norm.energy(options.max_size) if d.in_energy else options.max_size * d.scales[0]
    unit = "J" if d.in_energy else COMPONENTS[d.names[0]][1]
    return {"value": None, "unit": unit, "direction": options.direction, "method": _method(options, d, swept, origin),
            "tolerance": None, "reached": False,
            "note": f"no disturbance up to {limit:.4g} {unit} {'along any direction swept ' if d.kind == 'energy' else ''}"
                    "ends on it" + (f" at any of the {len(origin.sampled)} phases" if origin.refined else ""),
            "check": None}


@dataclass(frozen=True)
class Found:
    """The smallest threshold of one attractor: its bracket ``t`` along the unit vector ``u`` (size coordinates),
    from origin row ``row``, and the threshold's value at every row searched ({row: size or None})."""

    t: Threshold
    u: np.ndarray
    row: int
    by_row: dict[int, float | None]


def _minimum(found: PointAttractors, options: MarginOptions, d: Direction, norm, hit: Found, check: dict[str, Any],
             label: int, swept: int, l_g: float, origin: Origin) -> dict[str, Any]:
    """``min_disturbance`` of one attractor from its smallest threshold ``hit``."""
    t = hit.t
    if d.in_energy:
        unit = "J"
        convert = norm.energy
        value = 0.0 if t.lower == 0.0 else norm.energy(t.value)
        tolerance = norm.energy(t.upper) if t.lower == 0.0 else 0.5 * (norm.energy(t.upper) - norm.energy(t.lower))
    else:
        unit = COMPONENTS[d.names[0]][1]

        def convert(size: float) -> float:
            return float(size * d.scales[0])
        value, tolerance = convert(t.value), convert(t.tolerance)
    sides = {side: None if check[side] is None else _outcome(found, check[side][1], convert(check[side][0]), unit, l_g,
                                                             check[side][2])
             for side in ("below", "above")}
    below_ok = sides["below"] is None or sides["below"]["ends_on"] != label
    confirmed = bool(below_ok and sides["above"] is not None and sides["above"]["ends_on"] == label)
    out = {"value": value, "unit": unit, "direction": options.direction,
           "method": _method(options, d, swept, origin), "tolerance": tolerance, "rtol": options.rtol, "reached": True,
           "lower": convert(t.lower), "upper": convert(t.upper), "energy_J": norm.energy(t.value),
           "equivalent_psi": t.value,
           "disturbance": {name: float(s * c * t.value) for name, s, c in zip(d.names, d.scales, hit.u, strict=True)},
           "check": {**sides, "confirmed": confirmed}}
    if d.kind == "mix":
        out["mix"] = options.mix
        out["factor"] = t.value / d.length
    if origin.phases is not None:
        out["phase"] = float(origin.phases[hit.row])
        out["origin_state"] = [float(x) for x in origin.states[hit.row]]
        out["by_phase"] = [{"phase": float(origin.phases[row]),
                            "value": None if v is None else norm.energy(v) if d.in_energy else convert(v)}
                           for row, v in sorted(hit.by_row.items())]
    if t.lower == 0.0:
        out["note"] = (f"reached from the smallest size scanned ({convert(t.upper):.4g} {unit}): the threshold is "
                       "below it")
    return out


def _search(probe, d: Direction, options: MarginOptions) -> tuple[dict[int, tuple[Threshold, np.ndarray]], int]:
    """The smallest threshold of every attractor reached from one state, along the direction or over all."""
    sizes = geometric_sizes(options.min_size, options.max_size, options.scan_points)
    if d.kind == "energy":
        rays, best = smallest_over_directions(probe, len(d.names), sizes, options.rtol, width=ROUND_WIDTH,
                                              min_angle=math.radians(MIN_ANGLE_DEG))
        return {label: (s.threshold, s.direction) for label, s in best.items()}, len(rays)
    ray = Ray(d.u)
    scan([ray], sizes, probe)
    refine([ray], probe, options.rtol, ROUND_WIDTH)
    return {label: (ray.threshold(label), ray.direction) for label in ray.reached()}, 1


def _best_row(per_row: dict[int, dict[int, tuple[Threshold, np.ndarray]]], label: int) -> int:
    """The row (phase) of the smallest threshold of ``label`` among the rows searched."""
    rows = [(k, found[label][0]) for k, found in per_row.items() if label in found]
    return min(rows, key=lambda row: (row[1].value, row[1].upper, row[0]))[0]


def _smallest(per_row: dict[int, dict[int, tuple[Threshold, np.ndarray]]]) -> dict[int, Found]:
    """Each attractor's smallest threshold over the origin's rows searched (phases)."""
    out: dict[int, Found] = {}
    for label in dict.fromkeys(label for found in per_row.values() for label in found):
        k = _best_row(per_row, label)
        t, u = per_row[k][label]
        by_row = {row: found[label][0].value if label in found else None for row, found in per_row.items()}
        out[label] = Found(t, u, k, by_row)
    return out


def _search_phases(origin: Origin, search: Callable[[int], dict[int, tuple[Threshold, np.ndarray]]],
                   report: Callable[[str], None]) -> dict[int, dict[int, tuple[Threshold, np.ndarray]]]:
    """The thresholds from every sampled row of ``origin``; then, for each attractor reached, its smallest
    threshold's phase located between the sampled ones: the rows half way to the best row's neighbours, then
    half of that, down to one row (``PHASE_STEPS`` between two sampled phases: three halvings). A local search:
    the threshold need not be smooth in the phase, and a narrow dip between two sampled phases can be missed."""
    per_row: dict[int, dict[int, tuple[Threshold, np.ndarray]]] = {}
    rows = len(origin.states)

    def at(row: int) -> None:
        if row not in per_row:
            report(f"phase {row / rows:.4g} of the period" if origin.refined else "")
            per_row[row] = search(row)
    for row in origin.sampled:
        at(row)
    if not origin.refined:
        return per_row
    for label in list(dict.fromkeys(label for found in per_row.values() for label in found)):
        if per_row[_best_row(per_row, label)][label][0].lower == 0.0:
            continue  # reached from the smallest size already at a sampled phase: nothing to locate
        step = PHASE_STEPS // 2
        while step >= 1:
            best = _best_row(per_row, label)
            for row in ((best - step) % rows, (best + step) % rows):
                at(row)
            step //= 2
    return per_row


def margins(config: Configuration | str, V: float, Fz: float, *, params: Parameters | None = None,
            options: MarginOptions | None = None, diagram=None, executor=None,
            progress: Callable[[float, str], None] | None = None, **option_overrides) -> MarginsResult:
    """The attractors at (V, Fz) (m/s, N) and the smallest disturbance that ends on each, from straight rolling
    or from the attractor the standard start reaches (``options.origin``), along ``options.direction`` (module
    docstring). ``diagram``: the one-parameter diagram in V at Fz, if already computed (default: computed, and
    kept for the process). Options as a :class:`MarginOptions` or as keyword overrides (``direction="energy"``)."""
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
    per_ray = options.scan_points + 10
    rows = options.phases + (6 if options.phases > 1 else 0) if options.origin == "standard_attractor" else 1
    per_row = len(sweep_directions(4)) * per_ray + 80 if options.direction == "energy" else per_ray
    runs = _prepare(config, V, Fz, params, diagram, executor, options.t_max, report, 3 + rows * per_row + 6)
    report = runs.report
    found = runs.found
    norm = found.norm
    d = Direction.of(options, norm)
    origin = _origin(runs, options, config.n_states)
    report(0.1, "bracketing scan")
    swept = 1

    def search(row: int) -> dict[int, tuple[Threshold, np.ndarray]]:
        nonlocal swept
        base = origin.states[row]

        def probe(points: np.ndarray) -> list[int]:
            return [end[0] for end in runs.run([_state(base, d.names, d.scales, z) for z in points])]
        thresholds, swept = _search(probe, d, options)
        return thresholds

    per_row = _search_phases(origin, search, lambda message: message and report(
        min(0.9, 0.1 + 0.85 * runs.count / runs.expected), message))
    found_at = _smallest(per_row)
    report(0.95, "checking every threshold by two runs")
    checks: list[tuple[int, str, float]] = []
    starts = []
    for label, hit in found_at.items():
        for side, size in (("below", hit.t.lower), ("above", hit.t.upper)):
            if size > 0.0:
                checks.append((label, side, size))
                starts.append(_state(origin.states[hit.row], d.names, d.scales, size * hit.u))
    ends = runs.run(starts, full=True)
    checked: dict[int, dict[str, Any]] = {}
    for (label, side, size), end, start in zip(checks, ends, starts, strict=True):
        checked.setdefault(label, {"below": None, "above": None})[side] = (size, end, start)
    warnings: list[str] = [f"the orbit kicked: {origin.info['warning']}"] if "warning" in origin.info else []
    minima = []
    for label, attractor in enumerate(found.attractors):
        if label not in found_at:
            minima.append(_unreached(options, d, norm, swept, origin))
            continue
        minima.append(_minimum(found, options, d, norm, found_at[label], checked.get(label, {"below": None,
                               "above": None}), label, swept, params.gear.l_g, origin))
        if not minima[-1]["check"]["confirmed"]:
            warnings.append(f"the threshold of the {attractor['mode']} attractor is not confirmed by its check runs")
    report(1.0, "done")
    orbit_runs = 1 if origin.info["kind"] == "standard_attractor" else 0
    return MarginsResult(config, V, Fz, params, options, found, minima, runs.count + found.runs + orbit_runs,
                         runs.unsettled, time.perf_counter() - clock, type(executor).__name__, warnings, origin.info)


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
    labels = [end[0] for end in runs.run([_state(np.zeros(config.n_states), names, scales, z) for z in points])]
    counts = [labels.count(k) for k in range(len(found.attractors))]
    report(1.0, "done")
    return BasinsResult(config, V, Fz, params, options, found, counts, labels.count(UNSETTLED), labels.count(FAILED),
                        runs.count + found.runs, time.perf_counter() - clock, type(executor).__name__)
