"""Request schemas: one declaration per analysis gives validation, defaults and the OpenAPI text.

Validation turns a JSON body into a *canonical request*: every field present (defaults
filled), numbers as floats, the design as the complete parameter dict (material preset
and overrides applied). Equal questions give equal canonical requests, hence equal cache
keys. Every refusal is an :class:`~shimmy.errors.InvalidParameterError` naming the field
(``params.r2`` for a design parameter), the value and what is allowed.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping

from ..model.configurations import Configuration, affects
from ..errors import InvalidParameterError
from . import settings
from .request_fields import Field, field_key as _key, huge as _huge
from ..analyses.decisions import design_space, spec_text
from ..analyses.ground.ground_profiles import MAX_PROFILE_POINTS, PRESETS
from ..analyses.ground import kicks
from ..analyses.maps import margin_options
from ..model.parameters import (DEFAULT_FZ, DEFAULT_MAP_SLICES, DEFAULT_PSI0, DIAGRAM_V_RANGE, FZ_RANGE, MATERIALS,
                                PARAMETER_SPECS, V_RANGE, Parameters, check_number, unknown_name_error)

CONFIGS = tuple(c.value for c in Configuration)
#: A margin's mix as typed (the workbench's placeholder).
MIX_EXAMPLE = margin_options.MIX_EXAMPLE


@dataclass(frozen=True)
class RequestSchema:
    name: str
    summary: str
    fields: tuple[Field, ...]

    def field(self, name: str) -> Field:
        """The declaration of field ``name`` (its limits are the ones the API, the CLI and the pages use)."""
        for f in self.fields:
            if f.name == name:
                return f
        raise KeyError(name)

    def validate(self, body: Any, extra: tuple[str, ...] = ()) -> dict[str, Any]:
        """The canonical request for ``body`` (a JSON object); ``extra`` names keys to ignore."""
        if not isinstance(body, Mapping):
            raise InvalidParameterError("body", type(body).__name__, "a JSON object", "is not a JSON object")
        known = {f.name for f in self.fields}
        for name in body:
            if name not in known and name not in extra:
                hint = unknown_name_error(name, sorted(known), "field")
                raise InvalidParameterError(_key(name), body[name], hint.allowed, message=str(hint))
        out: dict[str, Any] = {}
        for f in self.fields:
            if f.name in body and body[f.name] is not None:
                out[f.name] = f.check(body[f.name])
            elif f.required:
                raise InvalidParameterError(f.name, None, f.allowed,
                                            message=f"{f.name} is required; allowed: {f.allowed}")
            else:
                out[f.name] = f.default
        if "params" in out:
            out["params"] = design(out.pop("params") or {}, out.pop("material", None))
        if self.name == "study":
            _check_study(out)
        if self.name == "ground_run":
            _check_ground_run(out)
        if self.name in _CHECKS:
            _CHECKS[self.name](out)
        for low, high in (("v_min", "v_max"), ("fz_min", "fz_max")):
            if low in out and high in out and not out[high] > out[low]:
                raise InvalidParameterError(high, out[high], f"a number above {low} = {out[low]:g}",
                                            f"must exceed {low}")
        return out

    def openapi(self) -> dict[str, Any]:
        out = {"type": "object", "additionalProperties": False, "required": [f.name for f in self.fields if f.required],
               "properties": {f.name: f.openapi() for f in self.fields},
               "description": "Rules across fields (answered 422 naming the field): v_max above v_min, fz_max above "
                              "fz_min, params a design whose NES roller stays on its track (r2 + r3 > "
                              "(sqrt(3)/4)(r1 + r2), with the defaults for the parameters not given)."}
        if self.name == "ground_run":
            out["description"] += (f" Ground run: profile rows [t, V, Fz] with t increasing, V and Fz within their "
                                   f"ranges, a run of at most {settings.MAX_T_END:g} s (refusals name profile[i].t, "
                                   ".V or .Fz); without a profile, the preset with preset_options (its settings: "
                                   "python -m shimmy ground-run --help, shimmy.analyses.ground.ground_profiles). "
                                   "A kick: kick (psi or dpsi) with kick_size (rad within [-0.5, 0.5] for psi, rad/s "
                                   "within [-50, 50] for dpsi) and exactly one of kick_at_time (s, within the run) "
                                   "and kick_at_speed (m/s, a speed the run reaches); kick_size, kick_at_time and "
                                   "kick_at_speed only with kick; a scenario preset (runway_joint, touchdown_yaw) "
                                   "only without a profile table.")
        if self.name in _RULES:
            out["description"] += " " + _RULES[self.name]
        if self.name == "study":
            out["dependentRequired"] = {"parameter2": ["values2"], "values2": ["parameter2"]}
            out["description"] += (" Study: each of values (values2) within the range of parameter (parameter2); "
                                   "parameter2 another parameter than parameter, given with values2; values x "
                                   f"values2 x configs at most {settings.MAX_STUDY_UNITS} designs x configurations.")
        return out


def _check_study(out: dict[str, Any]) -> None:
    """Values within their parameter's range; the second parameter complete; the grid within limits."""
    if (out["parameter2"] is None) != (out["values2"] is None):
        missing = "values2" if out["values2"] is None else "parameter2"
        raise InvalidParameterError(missing, None, "given together with "
                                    + ("parameter2" if missing == "values2" else "values2"),
                                    message=f"{missing} is required when the other of parameter2/values2 is given")
    if out["parameter2"] is not None and out["parameter2"] == out["parameter"]:
        raise InvalidParameterError("parameter2", out["parameter2"], "a parameter other than " + out["parameter"])
    for name_key, values_key in (("parameter", "values"), ("parameter2", "values2")):
        name = out[name_key]
        if name is None:
            continue
        spec = PARAMETER_SPECS[name]
        for k, v in enumerate(out[values_key]):
            if not spec.low <= v <= spec.high:
                raise InvalidParameterError(f"{values_key}[{k}]", v, spec.allowed, f"is out of the range of {name}")
    units = len(out["values"]) * len(out["values2"] or [1]) * len(out["configs"])
    if units > settings.MAX_STUDY_UNITS:
        raise InvalidParameterError("values", units, f"at most {settings.MAX_STUDY_UNITS} designs x configurations",
                                    "asks for too many diagrams")


def _check_ground_run(out: dict[str, Any]) -> None:
    """The profile as checked rows (a table) or as the preset's complete settings; the run and its series
    within the service's limits."""
    from ..analyses.ground.ground_profiles import preset, preset_fields, profile_from_table

    given = {name: out[name] for name in kicks.FIELDS}
    if out["profile"] is not None and out["preset"] in kicks.KICK_PRESETS:
        raise InvalidParameterError("preset", out["preset"], "a profile preset (" + ", ".join(PRESETS) + ") or none "
                                    "with a profile table", "is a scenario (a preset with a kick): with a profile "
                                    "table, give the kick's fields")
    if out["preset"] in kicks.KICK_PRESETS:  # a scenario: its preset, and its kick where the request gives none
        out["preset"], given = kicks.scenario(out["preset"], given)
    kick = kicks.Kick.of(given)
    if out["profile"] is not None:
        if out["preset_options"]:
            raise InvalidParameterError("preset_options", out["preset_options"], "only with a preset (no profile)",
                                        "is given with a profile table")
        profile = profile_from_table(out["profile"])
        out["preset"], out["preset_options"] = None, {}
        out["profile"] = profile.rows()
    else:
        ranges = {f["name"]: f"a number in [{f['low']:g}, {f['high']:g}] {f['unit']}".rstrip()
                  for f in preset_fields(out["preset"])}
        for name, value in out["preset_options"].items():  # JSON numbers only, as for every other number
            if isinstance(value, (str, bool)) or value is None:  # (an unknown name: refused by preset() below)
                raise InvalidParameterError(f"preset_options.{_key(name)}", value, ranges.get(name, "a number"),
                                            "is not a number")
        profile = preset(out["preset"], {k: _huge(v) for k, v in out["preset_options"].items()})
        out["preset_options"] = dict(profile.settings)
    if profile.duration > settings.MAX_T_END:
        raise InvalidParameterError("profile" if out["preset"] is None else "preset_options", profile.duration,
                                    f"a run of at most {settings.MAX_T_END:g} s", "makes the run too long (s)")
    if kick is not None:
        kicks.kick_instant(kick, profile)  # within the run
        out.update(kick=kick.kind, kick_size=kick.size, kick_at_time=kick.at_time, kick_at_speed=kick.at_speed)
    if profile.duration / out["series_dt"] > settings.MAX_SERIES_POINTS:
        raise InvalidParameterError("series_dt", out["series_dt"],
                                    f"at least {profile.duration / settings.MAX_SERIES_POINTS:g} s for a "
                                    f"{profile.duration:g} s run", "gives too many samples")


# -- sensitivities, optimiser, robustness -------------------------------------------------------
# The figures, device parameters and tolerance limits are the analyses' own definitions
# (shimmy.analyses.decisions.design_space: constants only, the solvers are imported when an analysis runs).

#: The optimiser's figures of merit: unit, whether taken at a load, the range a constraint value may take.
FIGURE_LIMITS: dict[str, tuple[str, bool, float, float]] = {
    name: (f.unit, f.at_load, f.low, f.high) for name, f in design_space.FIGURES.items()}
#: The figures of merit themselves (label, unit, sense, ...), re-exported for the workbench, which names them by
#: these labels and imports no analysis.
FIGURES = design_space.FIGURES
#: Figures with derivatives (the gradient method needs the objective and every constraint among them).
DIFFERENTIABLE = design_space.DIFFERENTIABLE
#: The optimiser's default search parameters (those of them the configuration has).
DEFAULT_SEARCH = design_space.DESIGN_PARAMETERS
DISTRIBUTIONS = design_space.DISTRIBUTIONS
TOLERANCE_RANGE = (0.0, max(design_space.TOLERANCE_LIMITS.values()))  # relative: a fraction of the value
MAX_CONSTRAINTS = 8
OPS = ("<=", ">=")

CONSTRAINT_TEXT = ("FIGURE<=VALUE or FIGURE>=VALUE (FIGURE@Fz for a figure at another load, Fz in N), or an object "
                   "{figure, op, value, Fz}")
TOLERANCE_TEXT = "NAME=REL or NAME=REL:normal|uniform (REL a fraction, 0.05 = 5 %), or an object " \
                 "{name, relative, distribution}"


def _item_keys(field: str, item: Mapping[str, Any], known: tuple[str, ...]) -> None:
    for key in item:
        if key not in known:
            hint = unknown_name_error(str(key), known, f"{field} key")
            raise InvalidParameterError(f"{field}.{_key(key)}", item[key], hint.allowed, message=str(hint))


def _number_of(field: str, value: Any, low: float, high: float, unit: str = "") -> float:
    if isinstance(value, str) or isinstance(value, bool) or value is None:
        allowed = f"a number in [{low:g}, {high:g}] {unit}".rstrip()
        raise InvalidParameterError(field, value, allowed, "is not a number")
    return check_number(field, _huge(value), low, high, unit)


def _read_number(typed: str) -> Any:
    """A number part of a constraint or tolerance string as a float, or as typed (refused by name below)."""
    text = spec_text.number_text(typed)
    try:
        return float(text)
    except ValueError:
        return text


def constraint(field: str, item: Any, default_Fz: float) -> dict[str, Any]:
    """One optimiser constraint as {figure, op, value, Fz} (Fz None for a figure not taken at a load)."""
    if isinstance(item, str):  # spaces ignored; a part refused is quoted as typed (spec_text)
        parts = spec_text.constraint_parts(item)
        if parts is None:
            raise InvalidParameterError(field, item, CONSTRAINT_TEXT, "has no <= or >=")
        typed, op, right, fz = parts
        item = {"figure": spec_text.name_text(typed, FIGURE_LIMITS), "op": op, "value": _read_number(right),
                **({"Fz": _read_number(fz)} if fz is not None else {})}
    elif isinstance(item, Mapping):
        _item_keys(field, item, ("figure", "op", "value", "Fz"))
        for key in ("figure", "op", "value"):
            if key not in item:
                raise InvalidParameterError(f"{field}.{key}", None, CONSTRAINT_TEXT,
                                            message=f"{field}.{key} is required; allowed: {CONSTRAINT_TEXT}")
    else:
        raise InvalidParameterError(field, item, CONSTRAINT_TEXT, "is not a string or an object")
    figure = item["figure"]
    if not isinstance(figure, str) or figure not in FIGURE_LIMITS:
        err = unknown_name_error(str(figure), FIGURE_LIMITS, f"{field}.figure")
        raise InvalidParameterError(f"{field}.figure", figure, err.allowed, message=str(err))
    unit, at_load, low, high = FIGURE_LIMITS[figure]
    if item["op"] not in OPS:
        raise InvalidParameterError(f"{field}.op", item["op"], "<= or >=", "is not <= or >=")
    value = _number_of(f"{field}.value", item["value"], low, high, unit)
    Fz = item.get("Fz")
    if Fz is not None and not at_load:
        raise InvalidParameterError(f"{field}.Fz", Fz, "none: " + figure + " is not taken at a load",
                                    f"is given for {figure}, which is not taken at a load")
    if at_load:
        Fz = default_Fz if Fz is None else _number_of(f"{field}.Fz", Fz, FZ_RANGE[0], FZ_RANGE[1], "N")
    return {"figure": figure, "op": item["op"], "value": value, "Fz": Fz}


def tolerance(field: str, item: Any) -> dict[str, Any]:
    """One toleranced parameter as {name, relative, distribution}."""
    if isinstance(item, str):  # spaces ignored; a part refused is quoted as typed (spec_text)
        parts = spec_text.tolerance_parts(item)
        if parts is None:
            raise InvalidParameterError(field, item, TOLERANCE_TEXT, "has no =")
        typed, relative, dist = parts
        item = {"name": spec_text.name_text(typed, PARAMETER_SPECS), "relative": _read_number(relative),
                "distribution": "normal" if dist is None else spec_text.name_text(dist, DISTRIBUTIONS)}
    elif isinstance(item, Mapping):
        _item_keys(field, item, ("name", "relative", "distribution"))
        for key in ("name", "relative"):
            if key not in item:
                raise InvalidParameterError(f"{field}.{key}", None, TOLERANCE_TEXT,
                                            message=f"{field}.{key} is required; allowed: {TOLERANCE_TEXT}")
    else:
        raise InvalidParameterError(field, item, TOLERANCE_TEXT, "is not a string or an object")
    name = item["name"]
    if not isinstance(name, str) or name not in PARAMETER_SPECS:
        err = unknown_name_error(str(name), PARAMETER_SPECS, f"{field}.name")
        raise InvalidParameterError(f"{field}.name", name, err.allowed, message=str(err))
    if PARAMETER_SPECS[name].integer:
        raise InvalidParameterError(f"{field}.name", name, "a parameter that is not a whole number",
                                    "is a whole number: a relative tolerance does not apply")
    dist = item.get("distribution", "normal")  # absent: normal; a wrong type or an empty name is refused
    if not isinstance(dist, str) or dist not in DISTRIBUTIONS:
        raise InvalidParameterError(f"{field}.distribution", dist, "normal or uniform", "is not a distribution")
    relative = _number_of(f"{field}.relative", item["relative"], 0.0, design_space.TOLERANCE_LIMITS[dist],
                          f"(a fraction of the value; {dist})")
    return {"name": name, "relative": relative, "distribution": dist}


def _check_sensitivity(out: dict[str, Any]) -> None:
    """The parameter names in the parameter table's order (equal sets, equal cache keys); all when absent."""
    chosen = set(out["names"] or PARAMETER_SPECS)
    out["names"] = [n for n in PARAMETER_SPECS if n in chosen]


def _check_optimise(out: dict[str, Any]) -> None:
    """Search parameters of the configuration, constraints as objects, the method fit for the figures."""
    config = out["config"]
    if out["parameters"] is None:
        out["parameters"] = design_space.device_parameters(config)
        if not out["parameters"]:
            raise InvalidParameterError("parameters", None, f"parameters of configuration {config}",
                                        message=f"parameters is required for configuration {config}: the default "
                                                f"({', '.join(DEFAULT_SEARCH)}) are device parameters, and it has "
                                                "no device")
    for k, name in enumerate(out["parameters"]):
        if not affects(name, config):
            raise InvalidParameterError(f"parameters[{k}]", name, f"a parameter of configuration {config}",
                                        f"is not a parameter of configuration {config} (it has no "
                                        f"{'NES' if PARAMETER_SPECS[name].group == 'nes' else 'particle damper'})")
    out["constraints"] = [constraint(f"constraints[{k}]", c, out["Fz"]) for k, c in enumerate(out["constraints"])]
    if out["local_runs"] > out["starts"]:
        raise InvalidParameterError("local_runs", out["local_runs"], f"at most starts = {out['starts']}",
                                    "exceeds the number of start designs")
    figures = [out["objective"]] + [c["figure"] for c in out["constraints"]]
    rough = [f for f in figures if f not in DIFFERENTIABLE]
    if out["method"] == "gradient" and rough:
        raise InvalidParameterError("method", "gradient", "auto or global (" + ", ".join(dict.fromkeys(rough))
                                    + " has no derivative)", f"needs derivatives, which {rough[0]} does not have")


def _check_robustness(out: dict[str, Any]) -> None:
    tols = [tolerance(f"tolerances[{k}]", t) for k, t in enumerate(out["tolerances"])]
    seen: dict[str, int] = {}
    for k, t in enumerate(tols):
        if t["name"] in seen:
            raise InvalidParameterError(f"tolerances[{k}].name", t["name"], "each parameter at most once",
                                        f"repeats tolerances[{seen[t['name']]}]")
        seen[t["name"]] = k
    out["tolerances"] = tols
    if out["disturbance"] is not None and out["samples"] > settings.MAX_DISTURBED_SAMPLES:
        raise InvalidParameterError("samples", out["samples"], f"at most {settings.MAX_DISTURBED_SAMPLES} with a "
                                    "disturbance", "asks for too many samples with a disturbance (margins at nine "
                                    "points each)")


#: The ranges of a simulation's whole start state ``x0``, by index: (name, bound, unit) with |x0[k]| <= bound (for
#: delta: |l_g delta| <= bound m). Wide enough for every start a margin's check run makes (a kick up to the largest
#: max_size, 1 rad of yaw or the same energy, added to a cycle), far beyond the physical gear.
X0_BOUNDS = (("psi", 2.0, "rad"), ("dpsi", 100.0, "rad/s"), ("l_g delta", 1.5, "m"), ("ddelta", 100.0, "rad/s"),
             ("lam", 1.0, "m"), ("psis", 2.0, "rad"), ("dpsis", 100.0, "rad/s"))


def _check_simulate(out: dict[str, Any]) -> None:
    """``x0``: one number per state of the configuration, each within ``X0_BOUNDS``, and not together with a psi0 or
    lateral0 of its own."""
    if out.get("x0") is None:
        return
    x0, config = out["x0"], out["config"]
    n = Configuration.parse(config).n_states
    if len(x0) != n:
        raise InvalidParameterError("x0", x0, f"{n} numbers for {config} (psi, dpsi, delta, ddelta, lambda"
                                    + (", the NES rotation and rate)" if n == 7 else ")"), "has the wrong length")
    l_g = Parameters.from_dict(out["params"]).gear.l_g
    for k, (name, bound, unit) in enumerate(X0_BOUNDS[:n]):
        if name == "l_g delta":
            if abs(l_g * x0[k]) > bound:
                raise InvalidParameterError(f"x0[{k}]", x0[k], f"delta in [{-bound / l_g:.4g}, {bound / l_g:.4g}] rad "
                                            f"(l_g delta within [{-bound:g}, {bound:g}] {unit})", "is out of range")
        elif abs(x0[k]) > bound:
            raise InvalidParameterError(f"x0[{k}]", x0[k], f"a number in [{-bound:g}, {bound:g}] {unit} ({name})",
                                        "is out of range")
    for name, default in (("psi0", DEFAULT_PSI0), ("lateral0", 0.0)):
        if out[name] != default:
            raise InvalidParameterError(name, out[name], f"its default ({default:g}) when x0 is given",
                                        "is given together with x0")


def _check_margins(out: dict[str, Any]) -> None:
    """The settings together, as the analysis checks them (min_size below max_size; a mix with direction mix
    only), the mix in its canonical text (equal mixes, one cache key)."""
    options = margin_options.MarginOptions(**{name: out[name]
                                              for name in margin_options.MarginOptions.__dataclass_fields__})
    out["mix"] = options.mix


_CHECKS = {"sensitivity": _check_sensitivity, "optimise": _check_optimise, "robustness": _check_robustness,
           "margins": _check_margins, "simulate": _check_simulate}
_RULES = {
    "margins": "Margins: min_size below max_size; mix given with direction mix and only then, as "
               f"'{margin_options.MIX_EXAMPLE}' (components of " + ", ".join(margin_options.COMPONENTS) + ").",
    "simulate": f"Simulate: with include_series, at most {settings.MAX_SERIES_POINTS} samples per series "
                "(t_end / series_dt + 1; series_dt is refused, naming the smallest it may be for this t_end).",
    "optimise": "Optimise: the search parameters are parameters of the configuration (default: those of r2, e_p, "
                "k_s, r3 it has); local_runs at most starts; method gradient only for figures with derivatives ("
                + ", ".join(DIFFERENTIABLE) + "); constraints as 'FIGURE<=VALUE', 'FIGURE@Fz>=VALUE' or "
                "{figure, op, value, Fz}, each value in the figure's unit and range: "
                + "; ".join(f"{f} [{lo:g}, {hi:g}] {u}" + (" at a load (default: Fz)" if at else "")
                            for f, (u, at, lo, hi) in FIGURE_LIMITS.items()) + ".",
    "robustness": "Robustness: tolerances as 'NAME=REL', 'NAME=REL:uniform' or {name, relative, distribution}, "
                  f"REL a fraction (normal: the standard deviation, at most "
                  f"{design_space.TOLERANCE_LIMITS['normal']:g}; uniform: the half-width, at most "
                  f"{design_space.TOLERANCE_LIMITS['uniform']:g}), each parameter at most once, not a whole-number "
                  f"one; with a disturbance at most {settings.MAX_DISTURBED_SAMPLES} samples.",
}

_CONSTRAINT_ITEM = {"oneOf": [
    {"type": "string", "pattern": r"^\s*[a-zA-Z_]+(@[0-9.eE+-]+)?\s*(<=|>=)\s*[-0-9.eE+]+\s*$",
     "examples": ["max_psi<=0.02", "min_shimmy_Fz>=80000", "interval@200000<=40"]},
    {"type": "object", "additionalProperties": False, "required": ["figure", "op", "value"], "properties": {
        "figure": {"type": "string", "enum": list(FIGURE_LIMITS)}, "op": {"type": "string", "enum": list(OPS)},
        "value": {"type": "number", "description": "in the figure's unit"},
        "Fz": {"type": ["number", "null"], "minimum": FZ_RANGE[0], "maximum": FZ_RANGE[1],
               "description": "load of a figure at a load (N); default: the request's Fz"}}}]}
_TOLERANCE_ITEM = {"oneOf": [
    {"type": "string", "pattern": r"^\s*[a-zA-Z_0-9]+\s*=\s*[0-9.eE+-]+(:(normal|uniform))?\s*$",
     "examples": ["k_lam=0.05", "k_s=0.05:uniform"]},
    {"type": "object", "additionalProperties": False, "required": ["name", "relative"], "properties": {
        "name": {"type": "string", "enum": [n for n, spec in PARAMETER_SPECS.items() if not spec.integer]},
        "relative": {"type": "number", "minimum": TOLERANCE_RANGE[0], "maximum": TOLERANCE_RANGE[1],
                     "description": "relative tolerance, a fraction of the value"},
        "distribution": {"type": "string", "enum": list(DISTRIBUTIONS), "default": "normal"}}}]}


def design(overrides: Mapping[str, Any], material: str | None) -> dict[str, float]:
    """The complete parameter dict of a design: material preset, then overrides (validated)."""
    params = Parameters()
    if material is not None:
        params = params.with_material(material)
    for name, value in overrides.items():
        if name not in PARAMETER_SPECS:
            err = unknown_name_error(name, PARAMETER_SPECS)
            raise InvalidParameterError(f"params.{_key(name)}", name, err.allowed, message=str(err))
        if isinstance(value, str) or isinstance(value, bool) or value is None:
            spec = PARAMETER_SPECS[name]
            raise InvalidParameterError(f"params.{name}", value, spec.allowed, "is not a number")
    try:
        params = params.with_overrides({name: _huge(value) for name, value in overrides.items()})
    except InvalidParameterError as exc:
        name = exc.field if exc.field in PARAMETER_SPECS else next(iter(overrides), exc.field)
        raise InvalidParameterError(f"params.{name}", exc.value, exc.allowed, message=str(exc)) from None
    return params.to_dict()


def _config(required: bool = True) -> Field:
    return Field("config", "string", "configuration", required=required, choices=CONFIGS)


PARAMS = Field("params", "object", "design overrides {name: value}; the rest at their defaults", default={})
MATERIAL = Field("material", "string", "particle-damper material preset applied before params",
                 choices=tuple(MATERIALS))
V = Field("V", "number", "forward speed", required=True, low=V_RANGE[0], high=V_RANGE[1], unit="m/s")
FZ = Field("Fz", "number", "vertical load", required=True, low=FZ_RANGE[0], high=FZ_RANGE[1], unit="N")


def _range(name: str, default: float, bounds: tuple[float, float], unit: str, what: str) -> Field:
    return Field(name, "number", what, default=default, low=bounds[0], high=bounds[1], unit=unit)


def _setting(name: str, what: str, options: Any) -> Field:
    """A setting of a margin or of basin fractions: its default and limits those of the analysis's options."""
    low, high, unit, integer = margin_options.LIMITS[name]
    return Field(name, "integer" if integer else "number", what, default=getattr(options, name), low=low, high=high,
                 unit=unit)


_MARGIN, _BASIN, _GRID = margin_options.MarginOptions(), margin_options.BasinOptions(), margin_options.MapGrid()
_T_MAX = "longest run; a run that settles on no attractor by then counts as unsettled"


SCHEMAS: dict[str, RequestSchema] = {
    "simulate": RequestSchema("simulate", "time history at one operating point", (
        _config(), V, FZ,
        Field("t_end", "number", "simulated time", default=60.0, low=0.1, high=settings.MAX_T_END, unit="s"),
        Field("include_series", "boolean", "return the time series (t, states, lateral)", default=False),
        Field("series_dt", "number", "sampling interval of the returned series (a multiple of 1 ms)",
              default=0.002, low=0.001, high=0.1, unit="s", multiple=0.001),
        Field("exact_nes", "boolean", "exact NES torque instead of the cubic fit", default=False),
        Field("psi0", "number", "initial torsion psi (the standard start: 0.001 rad; the rest of the state zero "
              "unless lateral0 is given)", default=DEFAULT_PSI0, low=-0.5, high=0.5, unit="rad"),
        Field("lateral0", "number", "initial lateral bending displacement l_g delta", default=0.0, low=-0.5,
              high=0.5, unit="m"),
        Field("x0", "numbers", "the whole initial state instead of psi0 and lateral0, one number per state of the "
              "configuration: psi (rad), dpsi (rad/s), delta (rad), ddelta (rad/s), lambda, and with the NES its "
              "rotation and rate (a margin's start, origin_state plus the kick); angles within 2 rad, rates within "
              "100 rad/s, l_g delta within 1.5 m, lambda within 1 m", high=7),
        PARAMS, MATERIAL)),
    "hopf": RequestSchema("hopf", "Hopf points of straight rolling in V at one load", (
        _config(), FZ, _range("v_min", V_RANGE[0], V_RANGE, "m/s", "lowest speed"),
        _range("v_max", V_RANGE[1], V_RANGE, "m/s", "highest speed"), PARAMS, MATERIAL)),
    "stability": RequestSchema("stability", "largest eigenvalue real part of x = 0 against V, all configurations", (
        FZ, _range("v_min", V_RANGE[0], V_RANGE, "m/s", "lowest speed"),
        _range("v_max", DIAGRAM_V_RANGE[1], V_RANGE, "m/s", "highest speed"),
        Field("n_points", "integer", "speeds on a geometric grid", default=200, low=10, high=2000),
        PARAMS, MATERIAL)),
    "devices": RequestSchema("devices", "NES torque/stiffness and PD damping curves", (
        Field("v_max", "number", "largest PD tangential speed", default=2.0, low=0.01, high=20.0, unit="m/s"),
        PARAMS, MATERIAL)),
    "bifurcation": RequestSchema("bifurcation", "bifurcation diagram in V (equilibrium and periodic branches)", (
        _config(), FZ, _range("v_min", V_RANGE[0], V_RANGE, "m/s", "lowest speed"),
        _range("v_max", DIAGRAM_V_RANGE[1], V_RANGE, "m/s", "highest speed"),
        Field("ntst", "integer", "collocation mesh intervals", default=40, low=10, high=settings.MAX_NTST),
        Field("seeds", "boolean", "look for branches not born at a Hopf point by simulation", default=True),
        Field("exact_nes", "boolean", "exact NES torque instead of the cubic fit", default=False),
        PARAMS, MATERIAL)),
    "hopf_curves": RequestSchema("hopf_curves", "Hopf curves of x = 0 in (V, Fz) with generalised Hopf points", (
        _config(), _range("v_min", V_RANGE[0], V_RANGE, "m/s", "lowest speed"),
        _range("v_max", V_RANGE[1], V_RANGE, "m/s", "highest speed"),
        _range("fz_min", FZ_RANGE[0], FZ_RANGE, "N", "lowest load"),
        _range("fz_max", FZ_RANGE[1], FZ_RANGE, "N", "highest load"), PARAMS, MATERIAL)),
    "map": RequestSchema("map", "(V, Fz) stability map: Hopf, fold and torus curves, shimmy type on a grid, "
                         "design metrics", (
        _config(), _range("v_min", 1.0, V_RANGE, "m/s", "lowest speed"),
        _range("v_max", DIAGRAM_V_RANGE[1], V_RANGE, "m/s", "highest speed"),
        _range("fz_min", FZ_RANGE[0], FZ_RANGE, "N", "lowest load"),
        _range("fz_max", FZ_RANGE[1], FZ_RANGE, "N", "highest load"),
        Field("resolution", "integer", "classified Fz slices (more through regions they miss)",
              default=DEFAULT_MAP_SLICES, low=2, high=settings.MAX_MAP_SLICES),
        Field("n_v", "integer", "speeds per slice on the output grid", default=100, low=10,
              high=settings.MAX_MAP_SPEEDS),
        Field("metrics_Fz", "number", "load of the speed-interval and amplitude metrics", default=DEFAULT_FZ,
              low=FZ_RANGE[0], high=FZ_RANGE[1], unit="N"),
        PARAMS, MATERIAL)),
    "study": RequestSchema("study", "parametric study: Hopf speeds and max torsional amplitude per design and "
                           "configuration (one parameter, or a grid of two)", (
        Field("parameter", "string", "design parameter to vary", required=True, choices=tuple(PARAMETER_SPECS)),
        Field("values", "numbers", "its values (each within the parameter's range)", required=True,
              high=settings.MAX_STUDY_VALUES),
        Field("parameter2", "string", "second parameter (two-parameter grid)", choices=tuple(PARAMETER_SPECS)),
        Field("values2", "numbers", "values of the second parameter", high=settings.MAX_STUDY_VALUES),
        Field("configs", "strings", "configurations", default=list(CONFIGS), choices=CONFIGS),
        Field("Fz", "number", "vertical load", default=DEFAULT_FZ, low=FZ_RANGE[0], high=FZ_RANGE[1], unit="N"),
        _range("v_min", 1.0, V_RANGE, "m/s", "lowest speed"),
        _range("v_max", DIAGRAM_V_RANGE[1], V_RANGE, "m/s", "highest speed"),
        PARAMS, MATERIAL)),
    "ground_run": RequestSchema("ground_run", "ground run: take-off, landing roll, taxi or a (t, V, Fz) table; "
                                "envelopes, time in shimmy, peaks, boundary crossings, onset delay", (
        _config(),
        Field("profile", "table", "rows [t (s), V (m/s), Fz (N)], linearly interpolated (instead of a preset)",
              high=MAX_PROFILE_POINTS),
        Field("preset", "string", "preset profile, used when no profile table is given; runway_joint and "
              "touchdown_yaw: the take-off and the landing roll with a kick (a runway joint at 60 m/s, a touchdown "
              "with yaw), the kick's fields given taking the place of theirs", default="takeoff",
              choices=(*PRESETS, *kicks.KICK_PRESETS)),
        Field("preset_options", "object", "the preset's settings {name: value}; the rest at their defaults",
              default={}, item="an object {setting name: number}: settings of the preset, each with a default and "
                               "a range (the table of ground-run settings in the numerics documentation)"),
        Field("psi_threshold", "number", "torsional amplitude counted as shimmy", default=0.01, low=1e-6, high=1.0,
              unit="rad"),
        Field("lateral_threshold", "number", "lateral amplitude l_g delta counted as shimmy", default=0.001,
              low=1e-7, high=1.0, unit="m"),
        Field("series_dt", "number", "sampling interval of the returned series (a multiple of 1 ms)", default=0.01,
              low=0.001, high=1.0, unit="s", multiple=0.001),
        Field("fold_torus", "boolean", "also the crossings of the fold and torus curves of cycles (seconds per "
              "configuration)", default=False),
        Field("hopf_curves", "boolean", "include the configuration's Hopf curves (V 1-500 m/s, Fz 10-900 kN)",
              default=False),
        Field("kick", "string", "a kick during the run: a jump of the yaw angle psi or of the yaw rate dpsi (none: "
              "no kick)", choices=tuple(kicks.KINDS)),
        Field("kick_size", "number", "the kick's size: rad for psi (at most 0.5 either way), rad/s for dpsi (at most "
              "50 either way)", low=-max(k[2] for k in kicks.KINDS.values()),
              high=max(k[2] for k in kicks.KINDS.values()), unit="rad or rad/s"),
        Field("kick_at_time", "number", "when the kick comes, on the profile's clock (within the run); or "
              "kick_at_speed", low=-kicks.TIME_LIMIT, high=kicks.TIME_LIMIT, unit="s"),
        Field("kick_at_speed", "number", "the speed at which the kick comes (the first time the run reaches it); or "
              "kick_at_time", low=V_RANGE[0], high=V_RANGE[1], unit="m/s"),
        Field("exact_nes", "boolean", "exact NES torque instead of the cubic fit", default=False),
        PARAMS, MATERIAL)),
    "sensitivity": RequestSchema("sensitivity", "sensitivities: derivatives of the Hopf speeds and the largest "
                                 "stable torsional amplitude at a load and of the minimum shimmy load, to every "
                                 "parameter (implicit differentiation), as tornado rows", (
        _config(), Field("Fz", "number", "vertical load", default=DEFAULT_FZ, low=FZ_RANGE[0], high=FZ_RANGE[1],
                         unit="N"),
        Field("names", "strings", "parameters to differentiate against (default: all)", choices=tuple(PARAMETER_SPECS)),
        Field("amplitude", "boolean", "also the largest stable torsional amplitude (a bifurcation diagram, ~1 s)",
              default=True),
        Field("min_shimmy", "boolean", "also the minimum shimmy load (the Hopf curves, ~0.4 s)", default=True),
        PARAMS, MATERIAL)),
    "optimise": RequestSchema("optimise", "optimiser: the design of the chosen parameters (within their ranges) with "
                              "the best figure of merit under constraints on the others", (
        _config(),
        Field("objective", "string", "figure of merit (maximised: min_shimmy_Fz; minimised: the others)",
              default="min_shimmy_Fz", choices=tuple(FIGURE_LIMITS)),
        Field("parameters", "strings", "parameters to search, each within its range (default: those of r2, e_p, "
              "k_s, r3 the configuration has)", choices=tuple(PARAMETER_SPECS)),
        Field("Fz", "number", "load of the figures taken at a load (interval, max_psi)", default=DEFAULT_FZ,
              low=FZ_RANGE[0], high=FZ_RANGE[1], unit="N"),
        Field("constraints", "list", "constraints on figures of merit", default=[], low=0, high=MAX_CONSTRAINTS,
              item="constraints: " + CONSTRAINT_TEXT, items=_CONSTRAINT_ITEM),
        Field("method", "string", "gradient (Sobol starts, then SLSQP with analytic gradients), global "
              "(differential evolution) or auto (gradient when every figure has derivatives)", default="auto",
              choices=("auto", "gradient", "global")),
        Field("starts", "integer", "start designs of the gradient method (the nominal one among them)", default=8,
              low=1, high=64),
        Field("local_runs", "integer", "SLSQP runs from the best start designs", default=2, low=1, high=8),
        Field("max_iterations", "integer", "iterations per SLSQP run", default=30, low=1, high=100),
        Field("generations", "integer", "generations of differential evolution", default=6, low=1, high=30),
        Field("popsize", "integer", "differential evolution's population per searched parameter", default=5, low=2,
              high=15),
        Field("seed", "integer", "seed of the Sobol starts and of differential evolution", default=0, low=0,
              high=2 ** 31 - 1),
        PARAMS, MATERIAL)),
    "robustness": RequestSchema("robustness", "robustness to tolerances: distributions of the Hopf speeds at a load, "
                                "of the minimum shimmy load and of shimmy at the nine operating points, sampled "
                                "(quasi-Monte Carlo) and by linear propagation", (
        _config(),
        Field("tolerances", "list", "toleranced parameters", required=True, low=1, high=len(PARAMETER_SPECS),
              item="tolerances: " + TOLERANCE_TEXT, items=_TOLERANCE_ITEM),
        Field("samples", "integer", "samples (a scrambled Sobol sequence)", default=128, low=2,
              high=settings.MAX_ROBUSTNESS_SAMPLES),
        Field("Fz", "number", "load of the Hopf speeds", default=DEFAULT_FZ, low=FZ_RANGE[0], high=FZ_RANGE[1],
              unit="N"),
        Field("seed", "integer", "seed of the samples (the same seed gives the same samples)", default=0, low=0,
              high=2 ** 31 - 1),
        Field("disturbance", "number", "also P(shimmy) after a disturbance up to this size from straight rolling, "
              "counting every attractor it reaches (the margins at each sample's nine points: about 5 s per sample "
              "and core), as the yaw angle of the same energy", low=margin_options.LIMITS["max_size"][0],
              high=margin_options.LIMITS["max_size"][1], unit="rad"),
        Field("disturbance_direction", "string", "the disturbed component (psi, dpsi, delta, ddelta; the rest at "
              "rest), or all four in the energy norm (energy)", default="psi", choices=margin_options.DIRECTIONS),
        PARAMS, MATERIAL)),
    "margins": RequestSchema("margins", "disturbance margins at one operating point: its attractors and the smallest "
                             "disturbance from straight rolling that ends on each, each checked by two runs", (
        _config(), V, FZ,
        Field("direction", "string", "the disturbed component (psi, dpsi, delta, ddelta; the rest at rest), a given "
              "mix of them (mix, with mix), or all four in the energy norm (energy)", default=_MARGIN.direction,
              choices=margin_options.DIRECTIONS),
        Field("mix", "string", "with direction mix: the mix's components in their units (rad, rad/s), such as "
              f"'{margin_options.MIX_EXAMPLE}'; only its direction counts, the size is searched", default=None),
        Field("origin", "string", "what the disturbance is added to: straight rolling, or the attractor the "
              "standard start (psi = 0.001 rad) reaches, at phases points of its orbit", default=_MARGIN.origin,
              choices=margin_options.ORIGINS),
        _setting("phases", "phases of the orbit kicked with origin standard_attractor (each threshold the "
                 "smallest over them)", _MARGIN),
        _setting("max_size", "largest disturbance scanned, as the yaw angle of the same energy", _MARGIN),
        _setting("min_size", "smallest disturbance scanned, as the yaw angle of the same energy", _MARGIN),
        _setting("scan_points", "sizes of the bracketing scan (geometric steps)", _MARGIN),
        _setting("rtol", "relative tolerance of the bisection", _MARGIN), _setting("t_max", _T_MAX, _MARGIN),
        PARAMS, MATERIAL)),
    "basins": RequestSchema("basins", "basin fractions at one operating point: the share of disturbances up to a "
                            "size ending on each attractor, with 95 % intervals", (
        _config(), V, FZ,
        _setting("radius", "disturbances uniform in the energy ball of this yaw angle", _BASIN),
        _setting("samples", "disturbances sampled", _BASIN),
        _setting("seed", "seed of the samples (the same seed gives the same samples)", _BASIN),
        _setting("t_max", _T_MAX, _BASIN), PARAMS, MATERIAL)),
    "margin_map": RequestSchema("margin_map", "disturbance margins on the map: in each cell of the plane where a "
                                "torsional cycle coexists with another attractor, the smallest yaw kick from straight "
                                "rolling that ends on it", (
        _config(), _range("v_min", 1.0, V_RANGE, "m/s", "lowest speed"),
        _range("v_max", DIAGRAM_V_RANGE[1], V_RANGE, "m/s", "highest speed"),
        _range("fz_min", FZ_RANGE[0], FZ_RANGE, "N", "lowest load"),
        _range("fz_max", FZ_RANGE[1], FZ_RANGE, "N", "highest load"),
        _setting("n_v", "cells in V (each asked at its centre)", _GRID),
        _setting("n_fz", "cells in Fz (each asked at its centre)", _GRID),
        _setting("max_size", "largest yaw kick scanned", _MARGIN), PARAMS, MATERIAL)),
}

def validate(analysis: str, body: Any, extra: tuple[str, ...] = ()) -> dict[str, Any]:
    if analysis not in SCHEMAS:
        raise unknown_name_error(analysis, list(SCHEMAS), "analysis")
    return SCHEMAS[analysis].validate(body, extra)

