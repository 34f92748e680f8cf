"""Search the device parameters for the best figure of merit, under constraints on the others.

Figures (:data:`~shimmy.analyses.decisions.design_space.FIGURES`), each a function of the design:

* ``min_shimmy_Fz`` (N, maximised): the lowest point of the Hopf curves of straight rolling (below
  it x = 0 is stable at every speed; for the four nominal configurations this is also the map's
  minimum shimmy load, the fold curves lying above it);
* ``interval`` (m/s, minimised): the width of the shimmy speed range at a load (the hull of the
  classified slice's shimmy intervals, :func:`shimmy.analyses.maps.design_metrics.speed_metrics`);
* ``max_psi`` (rad, minimised): the largest stable torsional amplitude at a load;
* ``torsion_area`` ((m/s) kN, minimised): the pure-torsion area of the map's band Fz <= 250 kN
  (a map of the band: expensive, no derivative).

The parameters are searched inside their ranges, scaled to z in [0, 1]^d. Two methods:

* ``gradient`` (when the objective and every constraint have derivatives,
  :mod:`shimmy.analyses.decisions.sensitivity`): a scrambled Sobol sample of ``starts`` designs (the nominal
  one among them) evaluated through the executor, then SLSQP (scipy.optimize) from the best
  ``local_runs`` of them, each run one unit of the executor (so runs proceed in parallel on a Dask
  cluster), with analytic gradients of objective and constraints;
* ``global`` (a figure without derivatives: the torsion area, a shimmy interval that does not end
  at Hopf points): differential evolution (scipy.optimize) with each generation's designs
  evaluated through the executor, constraints by a penalty on the scaled violation.

Every evaluation is recorded (the convergence history). Designs the model refuses (the NES roller
leaving its track for some r2, r3) count as infeasible evaluations.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Sequence

import numpy as np
from scipy.optimize import differential_evolution, minimize
from scipy.stats import qmc

from ...version import __version__
from ...errors import ConvergenceError, InvalidParameterError
from ...model.configurations import Configuration, affects
from ...model.equations import build_model
from ...model.parameters import DEFAULT_FZ, FZ_RANGE, PARAMETER_SPECS, Parameters, check_number, unknown_name_error
from ..core.executors import open_executor, run_units
from . import spec_text
from .design_space import DIFFERENTIABLE, FIGURES, Figure, device_parameters  # noqa: F401 (Figure: re-exported)
from .summaries import constraint_text, optimise_summary
from .sensitivity import (V_BAND, amplitude_sensitivity, coefficient_pairs, hopf_sensitivities,
                          min_shimmy_sensitivity)

FZ_BOX = FZ_RANGE  # N




class _NotDifferentiable(Exception):
    pass


@dataclass(frozen=True)
class Constraint:
    """``figure`` (at ``Fz`` for figures at a load) ``op`` ``value``, op "<=" or ">="."""

    figure: str
    op: str
    value: float
    Fz: float | None = None

    @classmethod
    def parse(cls, text: str, default_Fz: float) -> "Constraint":
        """'max_psi<=0.02', 'max_psi@150000<=0.02' or 'min_shimmy_Fz>=80000' (values in the figure's unit;
        spaces ignored). A part refused is quoted as typed ('0.02 extra', not '0.02extra')."""
        parts = spec_text.constraint_parts(str(text))
        if parts is None:
            raise InvalidParameterError("constraint", text, "FIGURE<=VALUE or FIGURE>=VALUE (FIGURE[@Fz in N])",
                                        "has no <= or >=")
        typed, op, right, at = parts
        name = spec_text.name_text(typed, FIGURES)
        if name not in FIGURES:
            raise unknown_name_error(name, FIGURES, "constraint figure")
        value = check_number("constraint", spec_text.number_text(right), -1e12, 1e12, FIGURES[name].unit)
        Fz = (check_number("constraint Fz", spec_text.number_text(at), *FZ_BOX, "N") if at is not None
              else (default_Fz if FIGURES[name].at_load else None))
        return cls(name, op, value, Fz)

    def key(self) -> tuple[str, float | None]:
        return self.figure, self.Fz

    def margin(self, value: float) -> float:
        """>= 0 when satisfied, in units of the figure's scale."""
        m = (self.value - value) if self.op == "<=" else (value - self.value)
        return m / FIGURES[self.figure].scale

    def to_dict(self) -> dict[str, Any]:
        return {"figure": self.figure, "op": self.op, "value": self.value, "Fz": self.Fz,
                "unit": FIGURES[self.figure].unit}

    def __str__(self) -> str:
        return constraint_text(self.to_dict())


def _interval_of(result, Fz, params, config, names, gradient, pairs, model):
    from ..maps.map_slices import map_slice

    s = map_slice(config, Fz, v_range=(V_BAND[0], V_BAND[1]), n_v=200, params=params, result=result)
    if not s.intervals:
        return {"value": 0.0, "gradient": {n: 0.0 for n in names} if gradient else None}
    lo, hi = s.intervals[0]["V_start"], s.intervals[-1]["V_end"]
    speeds = [h["V"] for h in s.hopf_points]
    step = (V_BAND[1] - V_BAND[0]) / (10 * 199)
    at_lo = [x for x in speeds if abs(x - lo) <= step]
    at_hi = [x for x in speeds if abs(x - hi) <= step]
    if at_lo and at_hi and at_lo[0] != at_hi[-1]:  # both ends are Hopf points: the width moves with them
        ends = [at_lo[0], at_hi[-1]]
        if not gradient:
            return {"value": ends[1] - ends[0], "gradient": None}
        d = hopf_sensitivities(model, Fz, ends, pairs)
        grad = {n: d[1]["dV_dp"][n] - d[0]["dV_dp"][n] for n in names}
        return {"value": ends[1] - ends[0], "gradient": grad}
    return {"value": hi - lo, "gradient": None}


def figures_of(config: Configuration | str, params: Parameters, wanted: Sequence[tuple[str, float | None]],
               names: Sequence[str] = (), gradient: bool = False) -> dict[tuple[str, float | None], dict]:
    """{(figure, Fz): {"value", "gradient": {name: d/dtheta} or None}} of one design."""
    from ..diagrams.bifurcation import BifurcationOptions, bifurcation

    config = Configuration.parse(config)
    model = build_model(config, params)
    names = list(names)
    pairs = coefficient_pairs(config, params, names) if gradient and names else {}
    out: dict[tuple[str, float | None], dict] = {}
    diagrams: dict[float, Any] = {}
    for key in dict.fromkeys(wanted):
        figure, Fz = key
        if figure == "min_shimmy_Fz":
            low = min_shimmy_sensitivity(model, pairs, FZ_BOX)
            if low is None:
                out[key] = {"value": FZ_BOX[1], "gradient": None, "note": "no Hopf curve in the box"}
            else:
                out[key] = {"value": low["Fz"], "gradient": low["dFz_dp"] if gradient else None, "V": low["V"]}
        elif figure in ("interval", "max_psi"):
            if Fz not in diagrams:
                diagrams[Fz] = bifurcation(config, Fz, v_range=(V_BAND[0], V_BAND[1]), params=params,
                                           options=BifurcationOptions(mesh_check=False))
            if figure == "interval":
                out[key] = _interval_of(diagrams[Fz], Fz, params, config, names, gradient, pairs, model)
            else:
                amp = amplitude_sensitivity(model, Fz, pairs, V_BAND, diagrams[Fz]) if gradient else None
                value = float(diagrams[Fz].max_psi)
                grad = None if amp is None else amp["dA_dp"]
                out[key] = {"value": value, "gradient": grad, "V": diagrams[Fz].max_psi_V}
        elif figure == "torsion_area":
            from ..maps.design_metrics import torsion_area
            from ..maps.map_slices import BAND_FZ_MAX
            from ..maps.stability_map import stability_map

            with open_executor(max_workers=1) as inline:
                smap = stability_map(config, v_range=V_BAND, fz_range=(FZ_BOX[0], BAND_FZ_MAX), resolution=6,
                                     params=params, executor=inline)
            out[key] = {"value": torsion_area(smap)["torsion_area"], "gradient": None}
    return out


def _evaluate_unit(task: tuple) -> dict[str, Any]:
    """One design: (config, base params dict, names, values, wanted, gradient) -> figures or the refusal."""
    config, base, names, values, wanted, gradient = task
    try:
        params = Parameters.from_dict(base).with_overrides(dict(zip(names, values, strict=True)))
    except InvalidParameterError as exc:
        return {"ok": False, "reason": str(exc)}
    try:
        return {"ok": True, "figures": figures_of(config, params, wanted, names, gradient)}
    except ConvergenceError as exc:
        return {"ok": False, "reason": str(exc)}


@dataclass
class SearchProblem:
    """What :func:`search` optimises: the design parameters (scaled to [0, 1]), the objective and
    constraints, and the function that evaluates a design (``evaluator``, run on the executor)."""

    config: str
    base: dict[str, float]
    names: list[str]
    objective: str
    Fz: float
    constraints: list[Constraint]
    #: design task -> {"ok", "figures"} (a module-level function: it travels to the executor's workers)
    evaluator: Callable[[tuple], dict[str, Any]] = _evaluate_unit

    @property
    def lows(self) -> np.ndarray:
        return np.array([PARAMETER_SPECS[n].low for n in self.names])

    @property
    def spans(self) -> np.ndarray:
        return np.array([PARAMETER_SPECS[n].high - PARAMETER_SPECS[n].low for n in self.names])

    @property
    def objective_key(self) -> tuple[str, float | None]:
        return self.objective, (self.Fz if FIGURES[self.objective].at_load else None)

    @property
    def wanted(self) -> list[tuple[str, float | None]]:
        return list(dict.fromkeys([self.objective_key] + [c.key() for c in self.constraints]))

    def values(self, z: np.ndarray) -> list[float]:
        highs = np.array([PARAMETER_SPECS[n].high for n in self.names])
        v = np.clip(self.lows + np.clip(z, 0.0, 1.0) * self.spans, self.lows, highs)  # rounding at the ends
        return [round(float(x)) if PARAMETER_SPECS[n].integer else float(x) for n, x in zip(self.names, v, strict=True)]

    def z_of(self, params: Parameters) -> np.ndarray:
        return (np.array([float(getattr(params, n)) for n in self.names]) - self.lows) / self.spans

    def task(self, z: np.ndarray, gradient: bool) -> tuple:
        return self.config, self.base, self.names, self.values(z), self.wanted, gradient

    def merit(self, evaluation: dict[str, Any]) -> tuple[float, float]:
        """(scaled objective to minimise, largest scaled constraint violation >= 0)."""
        if not evaluation["ok"]:
            return math.inf, math.inf
        f = evaluation["figures"]
        figure = FIGURES[self.objective]
        obj = -figure.sense * f[self.objective_key]["value"] / figure.scale
        violation = max([0.0] + [-c.margin(f[c.key()]["value"]) for c in self.constraints])
        return obj, violation


def _record(history: list, problem: SearchProblem, z, evaluation, stage: str) -> None:
    obj, violation = problem.merit(evaluation)
    design = dict(zip(problem.names, problem.values(z), strict=True))
    entry = {"evaluation": len(history) + 1, "stage": stage, "design": design,
             "feasible": bool(evaluation["ok"] and violation <= 1e-9)}
    if evaluation["ok"]:
        figure = evaluation["figures"][problem.objective_key]
        entry["objective"] = figure["value"]
        entry["violation"] = violation
        if figure.get("gradient") is not None:
            entry["objective_gradient"] = dict(figure["gradient"])
    else:
        entry["objective"], entry["violation"], entry["reason"] = None, None, evaluation["reason"]
    history.append(entry)


def _local_unit(task: tuple) -> dict[str, Any]:
    """One SLSQP run from z0 with analytic gradients; returns its evaluations in order."""
    problem, z0, max_iterations, start = task
    memo: dict[tuple, dict] = {tuple(problem.values(z0)): start}  # the start is in the history already
    log: list[tuple[list[float], dict]] = []

    def evaluate(z):
        z = np.clip(np.asarray(z, float), 0.0, 1.0)
        k = tuple(problem.values(z))  # the design evaluated (rounded where a parameter is an integer)
        if k not in memo:
            memo[k] = problem.evaluator(problem.task(z, True))
            log.append((z.tolist(), memo[k]))
        return memo[k]

    def grad_z(gradient: dict[str, float] | None, factor: float) -> np.ndarray:
        if gradient is None:
            raise _NotDifferentiable("a figure has no derivative at this design")
        return np.array([gradient[n] for n in problem.names]) * problem.spans * factor

    figure = FIGURES[problem.objective]

    def fun(z):
        e = evaluate(z)
        if not e["ok"]:
            return 1e6, np.zeros(len(z))
        g = e["figures"][problem.objective_key]
        return (-figure.sense * g["value"] / figure.scale,
                grad_z(g["gradient"], -figure.sense / figure.scale))

    def constraint(c: Constraint):
        sign = 1.0 if c.op == ">=" else -1.0

        def value(z):
            e = evaluate(z)
            return c.margin(e["figures"][c.key()]["value"]) if e["ok"] else -1e6

        def jac(z):
            e = evaluate(z)
            if not e["ok"]:
                return np.zeros(len(z))
            return grad_z(e["figures"][c.key()]["gradient"], sign / FIGURES[c.figure].scale)

        return {"type": "ineq", "fun": value, "jac": jac}

    try:
        res = minimize(fun, z0, jac=True, method="SLSQP", bounds=[(0.0, 1.0)] * len(z0),
                       constraints=[constraint(c) for c in problem.constraints],
                       options={"maxiter": max_iterations, "ftol": 1e-9})
        message, success, z_end = str(res.message), bool(res.success), np.clip(res.x, 0, 1).tolist()
    except _NotDifferentiable as exc:
        message, success, z_end = f"stopped: {exc}", False, log[-1][0]
    return {"log": log, "message": message, "success": success, "z": z_end}


@dataclass
class OptimisationResult:
    config: Configuration
    objective: str
    Fz: float
    names: list[str]
    constraints: list[Constraint]
    method: str
    design: dict[str, float]
    objective_value: float
    nominal_objective: float | None
    figures: dict[str, dict[str, Any]]  # "optimum" / "nominal" / "original": {figure label: value}
    history: list[dict[str, Any]]
    feasible: bool
    message: str
    params: Parameters
    elapsed_s: float
    executor: str
    warnings: list[str] = field(default_factory=list)
    #: the searched parameters the optimum has on a bound of their range (:func:`bounds_reached`)
    at_bounds: list[dict[str, Any]] = field(default_factory=list)

    @property
    def evaluations(self) -> int:
        return len(self.history)

    @property
    def link_query(self) -> dict[str, str]:
        """URL keys that open the optimum in the workbench (?config=...&r2=...): the searched values and
        every other value of the design that differs from the defaults (the workbench starts from them)."""
        default = Parameters().to_dict()
        base = {n: v for n, v in self.params.to_dict().items()
                if n not in self.design and abs(v - default[n]) > 1e-12 * max(1.0, abs(default[n]))}
        return {"config": self.config.value, **{n: f"{v:.10g}" for n, v in {**base, **self.design}.items()}}

    def to_dict(self) -> dict[str, Any]:
        f = FIGURES[self.objective]
        return {"config": self.config.value, "objective": self.objective_value,
                "objective_figure": {"name": self.objective, "label": f.label, "unit": f.unit,
                                     "sense": "maximise" if f.sense > 0 else "minimise",
                                     "Fz": self.Fz if f.at_load else None},
                "nominal_objective": self.nominal_objective, "design": self.design, "parameters": self.names,
                "constraints": [c.to_dict() for c in self.constraints], "method": self.method,
                "figures": self.figures, "evaluations": self.evaluations, "history": self.history,
                "feasible": self.feasible, "message": self.message, "link_query": self.link_query,
                "params": self.params.to_dict(), "elapsed_s": self.elapsed_s, "executor": self.executor,
                "warnings": self.warnings, "at_bounds": self.at_bounds, "version": __version__}

    def summary_text(self) -> str:
        """The lines ``python -m shimmy optimise`` prints
        (:func:`~shimmy.analyses.decisions.summaries.optimise_summary`)."""
        return optimise_summary(self.to_dict())


def _figure_table(figures: dict, keys) -> dict[str, Any]:
    return {f"{k[0]}" + (f"@{k[1]:g}" if k[1] is not None else ""): figures[k]["value"] for k in keys}


def search(problem: SearchProblem, method: str, z_start: np.ndarray, starts: int, local_runs: int, max_iterations: int,
           generations: int, popsize: int, seed: int, executor, report) -> tuple[list[dict[str, Any]], str]:
    """The evaluations (in order) and the method's message: ``gradient`` (Sobol starts with ``z_start``
    first, then SLSQP runs from the best) or ``global`` (differential evolution from a Sobol population
    holding ``z_start``)."""
    history: list[dict[str, Any]] = []
    names = problem.names
    if method == "gradient":
        m = max(0, math.ceil(math.log2(max(starts - 1, 1))))
        sample = qmc.Sobol(len(names), scramble=True, seed=seed).random_base2(m)[:starts - 1]
        zs = [z_start] + list(sample)
        report(0.02, f"evaluating {len(zs)} start designs")
        results = run_units(problem.evaluator, [problem.task(z, True) for z in zs], executor,
                            lambda f, m: report(0.02 + 0.3 * f, f"start designs: {m}"), lambda t: "design")
        for z, e in zip(zs, results, strict=True):
            _record(history, problem, z, e, "start")
        usable = [k for k in range(len(zs)) if results[k]["ok"]]
        if not usable:
            return history, "no start design could be evaluated: " + results[0]["reason"]
        ranked = sorted(usable, key=lambda k: (problem.merit(results[k])[1], problem.merit(results[k])[0]))
        runs = run_units(_local_unit, [(problem, zs[k], max_iterations, results[k]) for k in ranked[:local_runs]],
                         executor, lambda f, m: report(0.32 + 0.6 * f, f"local searches (SLSQP): {m}"),
                         lambda t: "search")
        messages = []
        for run in runs:
            for z, e in run["log"]:
                _record(history, problem, z, e, "local")
            messages.append(run["message"])
        message = "SLSQP: " + "; ".join(dict.fromkeys(messages))
    else:
        calls = [0]

        def mapper(_func, population):
            population = [np.asarray(z, float) for z in population]
            calls[0] += 1
            out = run_units(problem.evaluator, [problem.task(z, False) for z in population], executor, None,
                            lambda t: "design")
            merits = []
            for z, e in zip(population, out, strict=True):
                _record(history, problem, z, e, "global")
                obj, violation = problem.merit(e)
                merits.append(1e6 if not math.isfinite(obj) else obj + 100.0 * violation)
            report(min(0.95, calls[0] / (generations + 1)),
                   f"differential evolution: generation {calls[0] - 1}, {len(history)} designs evaluated")
            return merits

        res = differential_evolution(lambda z: 0.0, [(0.0, 1.0)] * len(names), workers=mapper, updating="deferred",
                                     maxiter=generations, popsize=popsize, seed=seed, polish=False, tol=1e-3,
                                     init="sobol", x0=z_start)
        message = f"differential evolution: {res.message}"
    return history, message


def optimise(config: Configuration | str, objective: str = "min_shimmy_Fz", *,
             parameters: Sequence[str] | None = None, Fz: float = DEFAULT_FZ,
             constraints: Sequence[Constraint | str] = (), params: Parameters | None = None,
             method: str = "auto", starts: int = 8, local_runs: int = 2, max_iterations: int = 30,
             generations: int = 6, popsize: int = 5, seed: int = 0, executor=None,
             progress: Callable[[float, str], None] | None = None) -> OptimisationResult:
    """The design of ``parameters`` (inside their ranges; default: the device parameters fitted in
    ``config``) with the best ``objective`` (see :data:`~shimmy.analyses.decisions.design_space.FIGURES`) subject
    to ``constraints``; the other parameters as in ``params``."""
    clock = time.perf_counter()
    config = Configuration.parse(config)
    params = params if params is not None else Parameters()
    if objective not in FIGURES:
        raise unknown_name_error(objective, FIGURES, "objective")
    Fz = check_number("Fz", Fz, *FZ_BOX, "N")
    fitted = device_parameters(config)
    if parameters is None:
        if not fitted:
            raise InvalidParameterError("params", None, "gear parameters to search (configuration original has no "
                                        "device parameters), e.g. k_psi,c_psi")
        parameters = fitted
    names = []
    for n in parameters:
        if n not in PARAMETER_SPECS:
            raise unknown_name_error(n, PARAMETER_SPECS)
        if not affects(n, config):
            allowed = [m for m in PARAMETER_SPECS if affects(m, config)]
            raise InvalidParameterError("params", n, f"a parameter of configuration {config.value} "
                                        f"(device parameters: {', '.join(fitted) or 'none'}; or any of "
                                        f"{', '.join(m for m in allowed if m not in fitted)})",
                                        f"is not fitted in configuration {config.value}")
        if n not in names:
            names.append(n)
    if not names:
        raise InvalidParameterError("params", list(parameters), "one or more parameter names")
    cons = [c if isinstance(c, Constraint) else Constraint.parse(c, Fz) for c in constraints]
    if method not in ("auto", "gradient", "global"):
        raise InvalidParameterError("method", method, "one of auto, gradient, global")
    starts = int(check_number("starts", starts, 1, 256, integer=True))
    local_runs = int(check_number("local_runs", local_runs, 1, starts, integer=True))
    problem = SearchProblem(config.value, params.to_dict(), names, objective, Fz, cons)
    smooth = all(k[0] in DIFFERENTIABLE for k in problem.wanted)
    integers = [n for n in names if PARAMETER_SPECS[n].integer]
    chosen = ("gradient" if smooth and not integers else "global") if method == "auto" else method
    if chosen == "gradient" and not smooth:
        raise InvalidParameterError("method", method, "auto or global for " + ", ".join(
            k[0] for k in problem.wanted if k[0] not in DIFFERENTIABLE), "needs derivatives that figure has not")
    if chosen == "gradient" and integers:
        raise InvalidParameterError("method", method, f"auto or global with the integer parameter {integers[0]}",
                                    "needs continuous parameters")
    report = progress or (lambda fraction, message: None)
    if executor is None:
        with open_executor() as own:
            return optimise(config, objective, parameters=names, Fz=Fz, constraints=cons, params=params,
                            method=chosen, starts=starts, local_runs=local_runs, max_iterations=max_iterations,
                            generations=generations, popsize=popsize, seed=seed, executor=own, progress=progress)
    warnings: list[str] = []
    z_nominal = np.clip(problem.z_of(params), 0.0, 1.0)
    history, message = search(problem, chosen, z_nominal, starts, local_runs, max_iterations, generations, popsize,
                              seed, executor, report)
    feasible = [h for h in history if h["feasible"]]
    sense = FIGURES[objective].sense
    if feasible:
        best = max(feasible, key=lambda h: sense * h["objective"])
    else:
        best = min((h for h in history if h["violation"] is not None), key=lambda h: h["violation"], default=None)
        warnings.append("no evaluated design satisfies every constraint; the least violating one is reported")
    if best is None:
        raise ConvergenceError("no design could be evaluated: " + history[0].get("reason", "unknown reason"))
    design = best["design"]
    at_bounds = bounds_reached(design)
    if at_bounds:
        warnings.append("the range limits the optimum: " + "; ".join(
            f"{b['name']} at its {'lower' if b['bound'] == 'low' else 'upper'} bound {b['limit']:g} "
            f"{PARAMETER_SPECS[b['name']].unit}".rstrip() for b in at_bounds)
            + ". A wider range (or another parameter) could improve it further.")
    report(0.96, "figures of the optimum, the nominal design and original")
    keys = list(dict.fromkeys(problem.wanted + _all_figures(Fz)))  # every figure of merit, the asked ones first
    optimum_params = params.with_overrides(design)
    tables = run_units(_evaluate_unit, [(config.value, optimum_params.to_dict(), names, list(design.values()),
                                         keys, False),
                                        (config.value, params.to_dict(), [], [], keys, False),
                                        ("original", params.to_dict(), [], [], keys, False)], executor)
    figures = {}
    for label, t in zip(("optimum", "nominal", "original"), tables, strict=True):
        figures[label] = _figure_table(t["figures"], keys) if t["ok"] else {"error": t["reason"]}
    nominal = tables[1]["figures"][problem.objective_key]["value"] if tables[1]["ok"] else None
    if tables[1]["ok"] is False:
        warnings.append(f"the nominal design could not be evaluated: {tables[1]['reason']}")
    start_gradient = history[0].get("objective_gradient") if history else None
    if start_gradient is not None and all(v == 0.0 for v in start_gradient.values()):
        warnings.append(f"{', '.join(names)} do not move the {FIGURES[objective].label} at the nominal design "
                        "(zero derivatives): the search cannot improve it")
    report(1.0, "done")
    return OptimisationResult(config, objective, Fz, names, cons, chosen, design, best["objective"], nominal, figures,
                              history, bool(feasible), message, params, time.perf_counter() - clock,
                              type(executor).__name__, warnings, at_bounds)


#: How close to a range bound (a fraction of the range) an optimum's parameter counts as on it: the
#: local search (SLSQP) stops on a bound to round-off, differential evolution within its tolerance 1e-3.
BOUND_TOLERANCE = 1e-3


def bounds_reached(design: dict[str, float]) -> list[dict[str, Any]]:
    """The parameters of ``design`` on a bound of their range: [{name, bound ("low" | "high"), limit,
    value}], in the design's order."""
    out = []
    for name, value in design.items():
        spec = PARAMETER_SPECS[name]
        width = spec.high - spec.low
        for bound, limit in (("low", spec.low), ("high", spec.high)):
            if abs(value - limit) <= BOUND_TOLERANCE * width:
                out.append({"name": name, "bound": bound, "limit": limit, "value": value})
    return out


def _all_figures(Fz: float) -> list[tuple[str, float | None]]:
    """Every figure of merit, those taken at a load at ``Fz``: the table of optimum, nominal and original."""
    return [(name, Fz if f.at_load else None) for name, f in FIGURES.items()]
