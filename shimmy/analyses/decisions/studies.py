"""Parametric studies: how the Hopf speeds and the torsional amplitude move with design parameters.

:func:`study` sweeps one parameter, :func:`study_grid` two on a grid. Each (design, config)
pair is one unit of work (a bifurcation diagram in V at the study's load, through
:mod:`shimmy.analyses.core.executors`), giving the row a design report carries: the first and last Hopf
speed of x = 0 in the speed range (shimmy onset and end of the linear instability), every
Hopf point, and the largest torsional amplitude of a stable limit cycle with its speed.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any, Callable, Sequence

from ...version import __version__
from ..diagrams.bifurcation import BifurcationOptions, bifurcation
from ...model.configurations import CONFIGURATION_NAMES, Configuration, affects
from ...errors import ConvergenceError, InvalidParameterError
from ..core.executors import name_of, open_executor, run_units
from ..diagrams.hopf_curves import hopf_curves
from .codim2_curve import codim2_curves
from .max_psi_curve import arrives, follow_maximum, grid as max_psi_grid, max_psi_curve, orbit_of, substeps
from .min_shimmy_curve import min_shimmy_curve
from .study_curves import hopf_speed_curves
from .summaries import STUDY_COLUMNS, study_summary, write_study_csv
from ...model.parameters import (DEFAULT_FZ, DIAGRAM_V_RANGE, FZ_RANGE, PARAMETER_SPECS, V_RANGE, Parameters,
                                 check_operating_point, check_range)

MAX_VALUES = 200  # per parameter
MAX_UNITS = 2000  # designs x configurations
DEFAULT_CONFIGS = CONFIGURATION_NAMES


@dataclass
class StudyResult:
    parameters: list[str]
    values: list[list[float]]  # one list per parameter
    configs: list[str]
    Fz: float
    v_range: tuple[float, float]
    rows: list[dict[str, Any]]
    executor: str
    elapsed_s: float
    warnings: list[str] = field(default_factory=list)
    #: Exact curves of the Hopf speeds against the parameter (:mod:`.study_curves`); a one-parameter study's.
    curves: list[dict[str, Any]] = field(default_factory=list)
    #: each row's maximum's cycle where a follow can start from it (:func:`.max_psi_curve.orbit_of`), by
    #: (config, the row's parameter values); not part of the JSON
    orbits: dict[tuple, Any] = field(default_factory=dict, repr=False, compare=False)

    COLUMNS = STUDY_COLUMNS

    def to_dict(self) -> dict[str, Any]:
        return {"parameters": self.parameters, "values": self.values, "configs": self.configs, "Fz": self.Fz,
                "v_range": list(self.v_range), "rows": self.rows,
                "units": {"hopf_start": "m/s", "hopf_end": "m/s", "max_psi": "rad", "max_psi_V": "m/s",
                          "Fz": "N"},
                "executor": self.executor, "warnings": self.warnings, "elapsed_s": self.elapsed_s,
                "curves": self.curves, "version": __version__}

    def write_csv(self, stream) -> None:
        """The rows as CSV to ``stream`` (:func:`~shimmy.analyses.decisions.summaries.write_study_csv`)."""
        write_study_csv(self.to_dict(), stream)

    def summary_text(self) -> str:
        """The table ``python -m shimmy study`` prints: one row per design and configuration
        (:func:`~shimmy.analyses.decisions.summaries.study_summary`)."""
        return study_summary(self.to_dict())


def _check_values(name: str, values: Sequence[float], params: Parameters) -> list[float]:
    if name not in PARAMETER_SPECS:
        raise InvalidParameterError("parameter", name, "one of " + ", ".join(PARAMETER_SPECS))
    if isinstance(values, (str, bytes)) or not hasattr(values, "__len__") or not 1 <= len(values) <= MAX_VALUES:
        raise InvalidParameterError("values", values, f"a list of 1 to {MAX_VALUES} numbers")
    checked = []
    for v in values:
        params.with_overrides({name: v})  # names the parameter, its value and its range if out of range
        checked.append(float(v))
    return checked


def _check_configs(configs: Sequence[str]) -> list[str]:
    if isinstance(configs, str) or not configs:
        raise InvalidParameterError("configs", configs, "a non-empty list of " + ", ".join(DEFAULT_CONFIGS))
    return [Configuration.parse(c).value for c in configs]


def _unit(task: tuple) -> dict[str, Any]:
    config, overrides, Fz, v_min, v_max, params, options = task
    design = params.with_overrides(overrides)
    result = bifurcation(config, Fz, v_range=(v_min, v_max), params=design, options=options)
    speeds = sorted(h.V for h in result.hopf.hopf_points)
    return {**overrides, "config": config, "hopf_start": speeds[0] if speeds else None,
            "hopf_end": speeds[-1] if speeds else None, "max_psi": result.max_psi, "max_psi_V": result.max_psi_V,
            "hopf_points": speeds, "unstable_intervals": [list(iv) for iv in result.hopf.unstable_intervals],
            "warnings": list(result.warnings), "orbit": orbit_of(result)}


def _orbits(rows: list[dict[str, Any]], parameters: Sequence[str]) -> dict[tuple, Any]:
    """Take the cycles out of the rows (rows are JSON), by (config, the row's parameter values)."""
    return {(r["config"], tuple(r[p] for p in parameters)): r.pop("orbit") for r in rows}


def _run(parameters: list[str], designs: list[dict[str, float]], configs, Fz, v_range, params, executor,
         progress, options) -> StudyResult:
    clock = time.perf_counter()
    params = params if params is not None else Parameters()
    configs = _check_configs(configs)
    _, Fz = check_operating_point(V_RANGE[0], Fz)
    v_min, v_max = check_range("v", v_range, V_RANGE, "m/s")
    if len(designs) * len(configs) > MAX_UNITS:
        raise InvalidParameterError("values", len(designs) * len(configs),
                                    f"at most {MAX_UNITS} designs x configurations")
    options = options or BifurcationOptions(mesh_check=False)
    tasks = [(c, d, Fz, v_min, v_max, params, options) for d in designs for c in configs]
    rows = run_units(_unit, tasks, executor, progress,
                     lambda t: f"{t[0]} at " + ", ".join(f"{k} = {v:g}" for k, v in t[1].items()))
    orbits = _orbits(rows, parameters)
    warnings = [f"{r['config']} at " + ", ".join(f"{p} = {r[p]:g}" for p in parameters) + f": {w}"
                for r in rows for w in r["warnings"]]
    values = [sorted({d[p] for d in designs}, key=[d[p] for d in designs].index) for p in parameters]
    return StudyResult(parameters, values, configs, Fz, (v_min, v_max), rows,
                       name_of(executor), time.perf_counter() - clock,
                       warnings, orbits=orbits)


def study(parameter: str, values: Sequence[float], *, configs: Sequence[str] = DEFAULT_CONFIGS,
          Fz: float = DEFAULT_FZ, params: Parameters | None = None, v_range: tuple[float, float] = DIAGRAM_V_RANGE,
          options: BifurcationOptions | None = None, executor=None,
          progress: Callable[[float, str], None] | None = None) -> StudyResult:
    """One-parameter study: a row per (value, configuration), and per configuration the exact curves
    hopf_V_start and hopf_V_end (m/s) over the parameter's whole range
    (:func:`~shimmy.analyses.decisions.study_curves.hopf_speed_curves`), through the sampled values,
    and min_shimmy_Fz (N), the lowest point of the Hopf curves in (V, Fz) over the plane V in the
    study's range, Fz 10-900 kN (:func:`~shimmy.analyses.decisions.min_shimmy_curve.min_shimmy_curve`), and
    max_psi (rad), the largest stable torsional amplitude at Fz, from diagrams on a grid over the whole
    range with the sampled values, the maximum followed between them
    (:func:`~shimmy.analyses.decisions.max_psi_curve.max_psi_curve`), and the GH and
    double-Hopf points of the Hopf curves in that plane, their loads and speeds
    (:func:`~shimmy.analyses.decisions.codim2_curve.codim2_curves`)."""
    if executor is None:  # one pool for the sampled rows and the curve's grid
        with open_executor() as own:
            result = study(parameter, values, configs=configs, Fz=Fz, params=params, v_range=v_range,
                           options=options, executor=own, progress=progress)
        result.executor = name_of(None)  # what this environment's executor is (a Dask cluster, a pool)
        return result
    base = params if params is not None else Parameters()
    checked = _check_values(parameter, values, base)
    report = progress or (lambda fraction, message: None)

    def part(low: float, high: float):  # the progress of one stage, within the study's (never back)
        return lambda fraction, message: report(low + (high - low) * fraction, message)

    result = _run([parameter], [{parameter: v} for v in checked], configs, Fz, v_range, base, executor,
                  part(0.0, 0.5), options)
    clock = time.perf_counter()
    for k, config in enumerate(result.configs):
        report(0.5 + 0.3 * k / len(result.configs), f"curves of {config} in {parameter}")
        speeds = hopf_speed_curves(config, parameter, Fz=result.Fz, params=base, v_range=result.v_range)
        result.curves += [c.to_dict() for c in speeds.study_curves(values=checked)]
        result.warnings += [f"{config}, curves in {parameter}: {w}" for w in speeds.warnings]
        try:  # the base design's Hopf curves in (V, Fz): where the lowest point and the GH/HH points start
            hopf = hopf_curves(config, params=base, v_range=result.v_range, fz_range=FZ_RANGE)
        except ConvergenceError as exc:
            result.warnings.append(f"{config}, min_shimmy_Fz and GH/HH points in {parameter}: not followed: the base "
                                   f"design's Hopf curves: {exc}")
            continue
        try:
            lowest, notes = min_shimmy_curve(config, parameter, params=base, v_range=result.v_range, values=checked,
                                             hopf=hopf)
        except ConvergenceError as exc:
            result.warnings.append(f"{config}, min_shimmy_Fz in {parameter}: not followed: {exc}")
        else:
            result.curves.append(lowest.to_dict())
            result.warnings += [f"{config}, min_shimmy_Fz in {parameter}: {w}" for w in notes]
        try:
            points, notes = codim2_curves(config, parameter, params=base, v_range=result.v_range, values=checked,
                                          hopf=hopf)
        except ConvergenceError as exc:
            result.warnings.append(f"{config}, GH and double-Hopf points in {parameter}: not followed: {exc}")
        else:
            result.curves += [c.to_dict() for c in points]
            result.warnings += [f"{config}, GH and double-Hopf points in {parameter}: {w}" for w in notes]
    extra = [theta for theta in max_psi_grid(parameter, base, checked) if theta not in checked]
    options = options or BifurcationOptions(mesh_check=False)
    tasks = [(c, {parameter: theta}, result.Fz, *result.v_range, base, options)
             for theta in extra for c in result.configs]
    report(0.8, f"largest amplitude over the range of {parameter}")
    more = run_units(_unit, tasks, executor, part(0.8, 0.93), lambda t: f"{t[0]} at {parameter} = {t[1][parameter]:g}")
    orbits = {**result.orbits, **_orbits(more, [parameter])}
    rows = {c: sorted((r for r in result.rows + more if r["config"] == c), key=lambda r: r[parameter])
            for c in result.configs}
    follows = _follow_maxima(parameter, rows, orbits, result.Fz, result.v_range, base, options, executor,
                             part(0.93, 0.98), part(0.98, 1.0))
    for config in result.configs:
        result.curves.append(max_psi_curve(config, parameter, rows[config], result.v_range,
                                           follows[config]).to_dict())
    result.orbits.clear()  # what the follows started from; the result is its JSON
    report(1.0, f"largest amplitude over the range of {parameter} done")
    result.warnings += [f"{r['config']} at {parameter} = {r[parameter]:g} (max_psi curve): {w}"
                        for r in more for w in r["warnings"]]
    result.elapsed_s += time.perf_counter() - clock
    return result


def _follow_maxima(parameter: str, rows: dict[str, list[dict[str, Any]]], orbits: dict[tuple, Any], Fz: float,
                   v_range: tuple[float, float], base: Parameters, options: BifurcationOptions, executor, ahead,
                   back) -> dict[str, dict]:
    """Each grid diagram's maximum followed to the next grid value; where it does not arrive at that
    value's maximum, that one followed back (:func:`.max_psi_curve.follow_maximum`). By config, then
    by (from, towards) grid value. A configuration whose model the parameter does not enter has the
    same diagram at every grid value: nothing to follow. ``ahead``, ``back``: the two passes' progress."""
    follows: dict[str, dict] = {c: {} for c in rows}

    def run(pairs, report):
        pairs = [(c, a, b) for c, a, b in pairs if orbits.get((c, (a,))) is not None and affects(parameter, c)]
        tasks = [(c, Fz, parameter, base, orbits[c, (a,)], substeps(a, b, parameter), options, v_range)
                 for c, a, b in pairs]
        done = run_units(follow_maximum, tasks, executor, report,
                         lambda t: f"{t[0]}: largest amplitude followed to {parameter} = {t[5][-1]:g}")
        for (c, a, b), follow in zip(pairs, done, strict=True):
            follows[c][a, b] = follow

    steps = [(c, r[parameter], s[parameter], s["max_psi"]) for c in rows for r, s in zip(rows[c], rows[c][1:])]
    run([(c, a, b) for c, a, b, _ in steps], ahead)
    run([(c, b, a) for c, a, b, value in steps if not arrives(follows[c].get((a, b)), b, value)], back)
    return follows


def study_grid(parameters: tuple[str, str], values: tuple[Sequence[float], Sequence[float]],
               *, configs: Sequence[str] = DEFAULT_CONFIGS, Fz: float = DEFAULT_FZ,
               params: Parameters | None = None, v_range: tuple[float, float] = DIAGRAM_V_RANGE,
               options: BifurcationOptions | None = None, executor=None,
               progress: Callable[[float, str], None] | None = None) -> StudyResult:
    """Two-parameter study on the grid values[0] x values[1]: a row per (pair, configuration)."""
    base = params if params is not None else Parameters()
    if len(parameters) != 2 or len(values) != 2 or parameters[0] == parameters[1]:
        raise InvalidParameterError("parameters", list(parameters), "two different parameter names")
    first = _check_values(parameters[0], values[0], base)
    second = _check_values(parameters[1], values[1], base)
    designs = [{parameters[0]: a, parameters[1]: b} for a in first for b in second]
    result = _run(list(parameters), designs, configs, Fz, v_range, base, executor, progress, options)
    result.orbits.clear()  # nothing is followed in a two-parameter study
    return result
