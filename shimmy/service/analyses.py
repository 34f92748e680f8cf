"""The analyses the service offers, as functions canonical request -> JSON-ready result.

One registry used by the HTTP API, the job workers and the Dash pages (which never call the
numerics directly). :func:`run` validates, consults the shared cache and computes on a miss.
``progress(fraction, message)`` is called by the long analyses; it may raise to cancel.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable


from ..errors import InvalidParameterError
from ..model.parameters import Parameters
from . import admission, cache, neighbours, schemas
from .settings import MAX_SERIES_POINTS

Progress = Callable[[float, str], None]
Runner = Callable[[dict[str, Any], Progress | None], dict[str, Any]]


@dataclass(frozen=True)
class Analysis:
    """One analysis the service offers: its request schema, its runner and how it may be asked."""

    schema: schemas.RequestSchema
    runner: Runner
    sync: bool  # answered in the request: POST /api/v1/<name>
    job: bool  # runs as a background job: POST /api/v1/jobs {"analysis": <name>}


#: Every analysis by name, in the order their runners are declared below (the API lists them so).
ANALYSES: dict[str, Analysis] = {}


def serves(name: str, *, sync: bool, job: bool) -> Callable[[Runner], Runner]:
    """Declare the decorated runner as the service's analysis ``name`` (its schema: ``schemas.SCHEMAS[name]``)."""
    def declare(runner: Runner) -> Runner:
        ANALYSES[name] = Analysis(schemas.SCHEMAS[name], runner, sync, job)
        return runner
    return declare


def _params(request: dict[str, Any]) -> Parameters:
    return Parameters.from_dict(request["params"])


@serves("simulate", sync=True, job=True)
def simulate(request: dict[str, Any], progress: Progress | None = None) -> dict[str, Any]:
    from ..analyses.core.simulation import SimulationOptions, kicked_state, simulate as run_simulation

    stride = max(1, int(round(request["series_dt"] / SimulationOptions.dt_out)))
    if request["include_series"]:  # refuse before computing, not after
        samples = int(round(request["t_end"] / SimulationOptions.dt_out)) // stride + 1
        if samples > MAX_SERIES_POINTS:
            raise InvalidParameterError("series_dt", request["series_dt"],
                                        f"at least {request['t_end'] / MAX_SERIES_POINTS:g} s for t_end = "
                                        f"{request['t_end']:g} s (at most {MAX_SERIES_POINTS} samples per series)",
                                        "gives too many samples")
    params = _params(request)
    if request["x0"] is None:
        x0 = kicked_state(request["config"], params, request["psi0"], request["lateral0"])
        start = {"psi0": request["psi0"], "lateral0": request["lateral0"]}
    else:
        x0 = request["x0"]  # checked with the request (schemas.check_whole_state)
        start = {"psi0": x0[0], "lateral0": params.gear.l_g * x0[2], "x0": x0}
    result = run_simulation(request["config"], request["V"], request["Fz"], params=params, t_end=request["t_end"],
                            exact_nes=request["exact_nes"], x0=x0)
    out = result.to_dict()
    out["start"] = start
    if request["include_series"]:
        out["series"] = {k: v[::stride] for k, v in result.series().items()}
        out["series_dt"] = stride * result.options.dt_out
        out["spectrum"] = result.spectrum()
    return out


@serves("hopf", sync=True, job=False)
def hopf(request: dict[str, Any], progress: Progress | None = None) -> dict[str, Any]:
    from ..analyses.core.stability import hopf_points

    return hopf_points(request["config"], request["Fz"], params=_params(request), v_range=(request["v_min"],
                                                                                           request["v_max"])).to_dict()


@serves("stability", sync=True, job=False)
def stability(request: dict[str, Any], progress: Progress | None = None) -> dict[str, Any]:
    """Largest real part of the eigenvalues of x = 0 against V, and the Hopf points, per configuration."""
    from ..analyses.core.stability import growth_rate, growth_speeds
    from ..model.configurations import Configuration

    params = _params(request)
    v_range = (request["v_min"], request["v_max"])
    configs = {}
    for config in Configuration:  # each from the shared cache by the parameters of its own model: a slider
        # step of one device recomputes only the configurations that have that device
        part = {"config": config.value, "Fz": request["Fz"], "v_min": request["v_min"], "v_max": request["v_max"],
                "n_points": request["n_points"], "params": request["params"]}
        configs[config.value], _ = cache.get_or_compute(
            "growth", part, lambda c=config: growth_rate(c, request["Fz"], params=params, v_range=v_range,
                                                         n_points=request["n_points"]))
    return {"Fz": request["Fz"], "V": growth_speeds(v_range, request["n_points"]).tolist(),
            "params": request["params"], "configs": configs}


@serves("devices", sync=True, job=False)
def devices(request: dict[str, Any], progress: Progress | None = None) -> dict[str, Any]:
    from ..analyses.core.device_curves import nes_curve, pd_curves

    params = _params(request)
    nes = nes_curve(params=params)
    return {"params": request["params"], "nes": nes.to_dict(),
            "nes_cubic_error": {str(a): e for a, e in nes.cubic_error_at.items()},
            "pd": [c.to_dict() for c in pd_curves(params=params, v_max=request["v_max"])]}


@serves("bifurcation", sync=False, job=True)
def bifurcation(request: dict[str, Any], progress: Progress | None = None) -> dict[str, Any]:
    from ..analyses.diagrams.bifurcation import BifurcationOptions, bifurcation as run_bifurcation

    options = BifurcationOptions(ntst=request["ntst"], seeds=request["seeds"], exact_nes=request["exact_nes"])
    return run_bifurcation(request["config"], request["Fz"], v_range=(request["v_min"], request["v_max"]),
                           params=_params(request), options=options, progress=progress).to_dict()


@serves("hopf_curves", sync=False, job=True)
def hopf_curves(request: dict[str, Any], progress: Progress | None = None) -> dict[str, Any]:
    from ..analyses.diagrams.hopf_curves import hopf_curves as run_hopf_curves

    return run_hopf_curves(request["config"], params=_params(request), v_range=(request["v_min"], request["v_max"]),
                           fz_range=(request["fz_min"], request["fz_max"]), progress=progress).to_dict()


@serves("map", sync=False, job=True)
def stability_map(request: dict[str, Any], progress: Progress | None = None) -> dict[str, Any]:
    """The map with its design metrics; slices go through the executor of this environment. Warmed
    from the map of the nearest cached design within reach (:mod:`shimmy.service.neighbours`), if there is one;
    its own warm start is kept for the next. A job's progress with a ``sketch`` (a job worker's) is told
    the curves as they are known, for the map page to draw them before the shading."""
    from ..analyses.core.executors import name_of, open_executor, run_work_unit
    from ..analyses.maps.design_metrics import SpeedMetricsUnit, metrics
    from ..analyses.maps.stability_map import stability_map as run_map
    from ..model.configurations import Configuration

    params = _params(request)
    v_range = (request["v_min"], request["v_max"])
    with open_executor() as pool:  # the metrics' slice beside the map's units, not after them
        at_fz = pool.submit(run_work_unit, SpeedMetricsUnit(Configuration.parse(request["config"]),
                                                            request["metrics_Fz"], params, v_range))
        smap = run_map(request["config"], params=params, v_range=v_range,
                       fz_range=(request["fz_min"], request["fz_max"]), resolution=request["resolution"],
                       n_v=request["n_v"], progress=progress, warm_from=neighbours.nearest("map", request),
                       sketch=getattr(progress, "sketch", None), executor=pool)
        smap.executor = name_of(None)  # this environment's executor, as a map opening its own says
        at_fz = at_fz.result()
    neighbours.remember("map", request, smap.warm_start())
    out = smap.to_dict()
    out["metrics"] = metrics(smap, Fz=request["metrics_Fz"], at_fz=at_fz)
    return out


@serves("study", sync=False, job=True)
def study(request: dict[str, Any], progress: Progress | None = None) -> dict[str, Any]:
    from ..analyses.decisions.studies import study as run_study, study_grid

    common = dict(configs=request["configs"], Fz=request["Fz"], params=_params(request),
                  v_range=(request["v_min"], request["v_max"]), progress=progress)
    if request["parameter2"] is None:
        return run_study(request["parameter"], request["values"], **common).to_dict()
    return study_grid((request["parameter"], request["parameter2"]), (request["values"], request["values2"]),
                      **common).to_dict()


@serves("ground_run", sync=False, job=True)
def ground_run(request: dict[str, Any], progress: Progress | None = None) -> dict[str, Any]:
    """One configuration through the profile; with ``hopf_curves`` its Hopf curves (from the shared cache)."""
    from ..analyses.ground.ground_run import GroundRunOptions, ground_run as run_ground_run

    report = progress or (lambda fraction, message: None)
    profile = request["profile"] if request["profile"] is not None else request["preset"]
    options = GroundRunOptions(psi_threshold=request["psi_threshold"], lateral_threshold=request["lateral_threshold"],
                               exact_nes=request["exact_nes"], cycle_curves=request["fold_torus"])
    report(0.0, f"ground run of {request['config']}")
    kick = {name: request[name] for name in ("kick", "kick_size", "kick_at_time", "kick_at_speed")}
    result = run_ground_run(request["config"], profile, params=_params(request), options=options,
                            preset_options=request["preset_options"] if request["profile"] is None else None,
                            kick=kick)
    stride = max(1, int(round(request["series_dt"] / options.dt_out)))
    out = result.to_dict(stride)
    if request["hopf_curves"]:
        report(0.6, "Hopf curves")
        curves_request = schemas.validate("hopf_curves", {"config": request["config"], "params": request["params"]})
        curves, _ = run_canonical("hopf_curves", curves_request)
        out["hopf_curves"] = [{"V": [p["V"] for p in c["points"]], "Fz": [p["Fz"] for p in c["points"]]}
                              for c in curves["curves"]]
    report(1.0, "done")
    return out


@serves("sensitivity", sync=True, job=True)
def sensitivity(request: dict[str, Any], progress: Progress | None = None) -> dict[str, Any]:
    """Derivatives of the boundaries at one load to the chosen parameters, with the tornado rows."""
    from ..analyses.decisions.sensitivity import sensitivity as run_sensitivity

    report = progress or (lambda fraction, message: None)
    report(0.0, f"sensitivities of {request['config']} at {request['Fz'] / 1e3:g} kN")
    out = run_sensitivity(request["config"], request["Fz"], params=_params(request), names=request["names"],
                          amplitude=request["amplitude"], min_shimmy=request["min_shimmy"]).to_dict()
    report(1.0, "done")
    return out


@serves("optimise", sync=False, job=True)
def optimise(request: dict[str, Any], progress: Progress | None = None) -> dict[str, Any]:
    """The optimiser; its design evaluations and local searches go through the executor of this environment."""
    from ..analyses.decisions.optimise import Constraint, optimise as run_optimise

    constraints = [Constraint(c["figure"], c["op"], c["value"], c["Fz"]) for c in request["constraints"]]
    return run_optimise(request["config"], request["objective"], parameters=request["parameters"], Fz=request["Fz"],
                        constraints=constraints, params=_params(request), method=request["method"],
                        starts=request["starts"], local_runs=request["local_runs"],
                        max_iterations=request["max_iterations"], generations=request["generations"],
                        popsize=request["popsize"], seed=request["seed"], progress=progress).to_dict()


@serves("robustness", sync=False, job=True)
def robustness(request: dict[str, Any], progress: Progress | None = None) -> dict[str, Any]:
    """Quasi-Monte Carlo and linear propagation of the tolerances; chunks of samples through the executor."""
    from ..analyses.decisions.robustness import Tolerance, robustness as run_robustness

    tolerances = [Tolerance(t["name"], t["relative"], t["distribution"]) for t in request["tolerances"]]
    return run_robustness(request["config"], tolerances, samples=request["samples"], Fz=request["Fz"],
                          params=_params(request), seed=request["seed"], disturbance=request["disturbance"],
                          disturbance_direction=request["disturbance_direction"], progress=progress).to_dict()


@serves("margins", sync=False, job=True)
def margins(request: dict[str, Any], progress: Progress | None = None) -> dict[str, Any]:
    """The attractors at a point and the smallest disturbance to each; runs through the executor of this environment."""
    from ..analyses.maps.margins import margins as run_margins

    settings = ("direction", "mix", "origin", "phases", "max_size", "min_size", "scan_points", "rtol", "t_max")
    return run_margins(request["config"], request["V"], request["Fz"], params=_params(request), progress=progress,
                       **{name: request[name] for name in settings}).to_dict()


@serves("basins", sync=False, job=True)
def basins(request: dict[str, Any], progress: Progress | None = None) -> dict[str, Any]:
    """Basin fractions at a point: sampled disturbances through the executor of this environment."""
    from ..analyses.maps.margins import basins as run_basins

    return run_basins(request["config"], request["V"], request["Fz"], params=_params(request), progress=progress,
                      **{name: request[name] for name in ("radius", "samples", "seed", "t_max")}).to_dict()


@serves("margin_map", sync=False, job=True)
def margin_map(request: dict[str, Any], progress: Progress | None = None) -> dict[str, Any]:
    """Margins on the cells of a plane: the loads' diagrams, then the cells, through the executor of this
    environment."""
    from ..analyses.maps.margin_map import margin_map as run_margin_map

    return run_margin_map(request["config"], params=_params(request), v_range=(request["v_min"], request["v_max"]),
                          fz_range=(request["fz_min"], request["fz_max"]), n_v=request["n_v"], n_fz=request["n_fz"],
                          max_size=request["max_size"], progress=progress).to_dict()


def kick_kinds() -> dict[str, dict[str, Any]]:
    """What a ground run's kick may be: per kind (psi, dpsi) its unit, the largest size either way and what it is."""
    from ..analyses.ground.kicks import KINDS

    return {kind: {"unit": unit, "largest": largest, "what": what} for kind, (_, unit, largest, what) in KINDS.items()}


def kick_presets() -> dict[str, dict[str, Any]]:
    """The ground-run scenarios (a profile preset with a kick): label, preset, kick fields, description."""
    from ..analyses.ground.kicks import KICK_PRESETS

    return {name: {**s, "kick": dict(s["kick"])} for name, s in KICK_PRESETS.items()}


def preset_profile(name: str, options: dict[str, Any] | None = None) -> dict[str, Any]:
    """A ground-run preset's table rows [t, V, Fz], its complete settings, each setting's range and
    its assumptions, for a profile editor (a table of a few hundred points: nothing to cache)."""
    from ..analyses.ground.ground_profiles import preset, preset_fields

    profile = preset(name, options)
    return {"name": name, "rows": profile.rows(), "settings": profile.settings, "fields": preset_fields(name),
            "assumptions": profile.assumptions}


#: The runner of each analysis.
RUNNERS: dict[str, Runner] = {name: a.runner for name, a in ANALYSES.items()}
#: Analyses answered in the request (POST /api/v1/NAME).
SYNC_ANALYSES = tuple(name for name, a in ANALYSES.items() if a.sync)
#: Analyses that run as background jobs (POST /api/v1/jobs).
JOB_ANALYSES = tuple(name for name, a in ANALYSES.items() if a.job)


def run(analysis: str, body: Any, progress: Progress | None = None) -> tuple[dict[str, Any], bool]:
    """Validate ``body``, then (result, cached?) from the shared cache or by computing it in the request (the
    API's quick answers and the pages): a computation takes one of this worker's slots and one of its
    user's rate (:func:`shimmy.service.admission.fast_slot`; :class:`~shimmy.service.admission.Busy` when
    none comes); a cached answer takes neither."""
    request = schemas.validate(analysis, body)
    k = cache.key(analysis, request)
    found = cache.as_asked(cache.get_key(k), request)
    if found is not None:
        return found, True
    with admission.fast_slot(analysis, admission.requester()):
        found = cache.as_asked(cache.get_key(k), request)  # computed by another request while this one waited
        if found is not None:
            return found, True
        value = RUNNERS[analysis](request, progress)
        cache.put(k, value)
    return value, False


def cached(analysis: str, body: Any) -> dict[str, Any] | None:
    """The cached result for ``body``, or None (validation errors raise as in :func:`run`)."""
    return cache.get(analysis, schemas.validate(analysis, body))


def run_canonical(analysis: str, request: dict[str, Any], progress: Progress | None = None):
    return cache.get_or_compute(analysis, request, lambda: RUNNERS[analysis](request, progress))
