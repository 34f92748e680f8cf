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

from ..model.configurations import Configuration
from ..errors import InvalidParameterError
from . import settings
from ..analyses.ground_profiles import MAX_PROFILE_POINTS, PRESETS
from ..model.parameters import (DEFAULT_MAP_SLICES, FZ_RANGE, MATERIALS, PARAMETER_SPECS, V_RANGE, Parameters,
                                check_number, unknown_name_error)

CONFIGS = tuple(c.value for c in Configuration)


def _key(name: Any) -> str:
    """A body key as a field name: quoted where it is empty or has surrounding blanks."""
    name = str(name)
    return name if name and name == name.strip() else repr(name)


def _huge(value: Any) -> Any:
    """An integer beyond float range as inf (refused as not finite, by name) instead of an OverflowError."""
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) > 1e308:
        return float("inf") if value > 0 else float("-inf")
    return value


@dataclass(frozen=True)
class Field:
    name: str
    kind: str  # number | integer | string | boolean | object | numbers | strings (arrays) | table (rows of numbers)
    description: str
    required: bool = False
    default: Any = None
    low: float | None = None
    high: float | None = None
    unit: str = ""
    choices: tuple[str, ...] | None = None

    @property
    def allowed(self) -> str:
        if self.choices:
            return "one of " + ", ".join(self.choices)
        if self.kind in ("number", "integer"):
            kind = "an integer" if self.kind == "integer" else "a number"
            return f"{kind} in [{self.low:g}, {self.high:g}] {self.unit}".rstrip()
        if self.kind == "boolean":
            return "true or false"
        if self.kind == "object":
            return "an object {parameter name: number}; names and ranges from GET /api/v1/parameters"
        if self.kind == "numbers":
            return f"a list of 1 to {self.high:g} numbers"
        if self.kind == "strings":
            return f"a non-empty list of {', '.join(self.choices or ())}"
        if self.kind == "table":
            return f"a list of 2 to {self.high:g} rows [t (s), V (m/s), Fz (N)]"
        return "a string"

    def check(self, value: Any) -> Any:
        if self.kind in ("number", "integer"):
            if isinstance(value, str):  # JSON numbers only: "30" is a type error in a body
                raise InvalidParameterError(self.name, value, self.allowed, "is not a number")
            number = check_number(self.name, _huge(value), self.low, self.high, self.unit, self.kind == "integer")
            return int(number) if self.kind == "integer" else number
        if self.kind == "boolean":
            if not isinstance(value, bool):
                raise InvalidParameterError(self.name, value, self.allowed, "is not a boolean")
            return value
        if self.kind == "string":
            if not isinstance(value, str):
                raise InvalidParameterError(self.name, value, self.allowed, "is not a string")
            if self.choices and value not in self.choices:
                raise unknown_name_error(value, self.choices, self.name)
            return value
        if self.kind == "numbers":
            if not isinstance(value, list) or not 1 <= len(value) <= self.high:
                raise InvalidParameterError(self.name, value, self.allowed)
            out = []
            for k, v in enumerate(value):
                if isinstance(v, (str, bool)) or v is None:
                    raise InvalidParameterError(f"{self.name}[{k}]", v, "a number", "is not a number")
                out.append(check_number(f"{self.name}[{k}]", _huge(v), -1e300, 1e300))  # ranges: per parameter
            return out
        if self.kind == "strings":
            if not isinstance(value, list) or not value:
                raise InvalidParameterError(self.name, value, self.allowed)
            for k, v in enumerate(value):
                if not isinstance(v, str) or v not in (self.choices or ()):
                    raise InvalidParameterError(f"{self.name}[{k}]", v, "one of " + ", ".join(self.choices or ()))
            return list(dict.fromkeys(value))
        if self.kind == "table":  # the rows themselves are checked by the analysis's profile check, by row
            if not isinstance(value, list) or not 2 <= len(value) <= self.high:
                size = f"{len(value)} rows" if isinstance(value, list) else type(value).__name__
                raise InvalidParameterError(self.name, size, self.allowed)
            return [list(row) if isinstance(row, list) else row for row in value]
        if not isinstance(value, Mapping):
            raise InvalidParameterError(self.name, value, self.allowed, "is not an object")
        return dict(value)

    def openapi(self) -> dict[str, Any]:
        """The field's JSON Schema; an optional field may also be null (the server takes it as absent)."""
        out = self._openapi()
        if not self.required:
            out["type"] = [out["type"], "null"]
            if "enum" in out:
                out["enum"] = [*out["enum"], None]
        return out

    def _openapi(self) -> dict[str, Any]:
        out: dict[str, Any] = {"type": self.kind, "description": self.description + (f" ({self.unit})" if self.unit
                                                                                      else "")}
        if self.low is not None:
            out["minimum"], out["maximum"] = self.low, self.high
        if self.choices:
            out["enum"] = list(self.choices)
        if self.default is not None:
            out["default"] = self.default
        if self.kind == "object":  # exactly the parameter names the server takes, each with its range
            out["additionalProperties"] = False
            out["properties"] = {
                name: {"type": "integer" if spec.integer else "number", "minimum": spec.low, "maximum": spec.high,
                       "description": spec.description + (f" ({spec.unit})" if spec.unit else "")}
                for name, spec in PARAMETER_SPECS.items()}
        if self.kind == "table":
            out.update(type="array", minItems=2, maxItems=int(self.high),
                       items={"type": "array", "items": {"type": "number"}, "minItems": 3, "maxItems": 3})
            out.pop("minimum", None)
            out.pop("maximum", None)
        if self.kind in ("numbers", "strings"):
            out["type"] = "array"
            out.pop("minimum", None)
            out.pop("maximum", None)
            out["items"] = {"type": "number"} if self.kind == "numbers" else {"type": "string",
                                                                              "enum": list(self.choices or ())}
            out["minItems"] = 1
            if self.kind == "numbers":
                out["maxItems"] = int(self.high)
        return out


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
        for low, high in (("v_min", "v_max"), ("fz_min", "fz_max")):
            if low in out and high in out and not out[high] > out[low]:
                raise InvalidParameterError(high, out[high], f"a number above {low} = {out[low]:g}",
                                            f"must exceed {low}")
        return out

    def openapi(self) -> dict[str, Any]:
        out = {"type": "object", "additionalProperties": False, "required": [f.name for f in self.fields if f.required],
               "properties": {f.name: f.openapi() for f in self.fields},
               "description": "Rules across fields (answered 422 naming the field): v_max above v_min, fz_max above "
                              "fz_min, a design whose NES roller stays on its track (r2 + r3 > (sqrt(3)/4)(r1 + r2))."}
        if self.name == "ground_run":
            out["description"] += (f" Ground run: profile rows [t, V, Fz] with t increasing, V and Fz within their "
                                   f"ranges, a run of at most {settings.MAX_T_END:g} s (refusals name profile[i].t, "
                                   ".V or .Fz); without a profile, the preset with preset_options (its settings: "
                                   "python -m shimmy ground-run --help, shimmy.analyses.ground_profiles).")
        if self.name == "study":
            out["dependentRequired"] = {"parameter2": ["values2"], "values2": ["parameter2"]}
            out["description"] += (f" Study: each value within its parameter's range; at most "
                                   f"{settings.MAX_STUDY_UNITS} designs x configurations.")
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
    from ..analyses.ground_profiles import preset, profile_from_table

    if out["profile"] is not None:
        if out["preset_options"]:
            raise InvalidParameterError("preset_options", out["preset_options"], "only with a preset (no profile)",
                                        "is given with a profile table")
        profile = profile_from_table(out["profile"])
        out["preset"], out["preset_options"] = None, {}
        out["profile"] = profile.rows()
    else:
        for name, value in out["preset_options"].items():  # JSON numbers only, as for every other number
            if isinstance(value, (str, bool)) or value is None:
                raise InvalidParameterError(f"preset_options.{_key(name)}", value, "a number", "is not a number")
        profile = preset(out["preset"], {k: _huge(v) for k, v in out["preset_options"].items()})
        out["preset_options"] = dict(profile.settings)
    if profile.duration > settings.MAX_T_END:
        raise InvalidParameterError("profile" if out["preset"] is None else "preset_options", profile.duration,
                                    f"a run of at most {settings.MAX_T_END:g} s", "makes the run too long (s)")
    if profile.duration / out["series_dt"] > settings.MAX_SERIES_POINTS:
        raise InvalidParameterError("series_dt", out["series_dt"],
                                    f"at least {profile.duration / settings.MAX_SERIES_POINTS:g} s for a "
                                    f"{profile.duration:g} s run", "gives too many samples")


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


SCHEMAS: dict[str, RequestSchema] = {
    "simulate": RequestSchema("simulate", "time history at one operating point", (
        _config(), V, FZ,
        Field("t_end", "number", "simulated time", default=60.0, low=0.1, high=settings.MAX_T_END, unit="s"),
        Field("include_series", "boolean", "return the time series (t, states, lateral)", default=False),
        Field("series_dt", "number", "sampling interval of the returned series (a multiple of 1 ms)",
              default=0.002, low=0.001, high=0.1, unit="s"),
        Field("exact_nes", "boolean", "exact NES torque instead of the cubic fit", default=False),
        Field("psi0", "number", "initial torsion psi (REFERENCE.md's start: 0.001 rad; the rest of the state zero "
              "unless lateral0 is given)", default=0.001, low=-0.5, high=0.5, unit="rad"),
        Field("lateral0", "number", "initial lateral bending displacement l_g delta", default=0.0, low=-0.5,
              high=0.5, unit="m"),
        PARAMS, MATERIAL)),
    "hopf": RequestSchema("hopf", "Hopf points of straight rolling in V at one load", (
        _config(), FZ, _range("v_min", V_RANGE[0], V_RANGE, "m/s", "lowest speed"),
        _range("v_max", V_RANGE[1], V_RANGE, "m/s", "highest speed"), PARAMS, MATERIAL)),
    "stability": RequestSchema("stability", "largest eigenvalue real part of x = 0 against V, all configurations", (
        FZ, _range("v_min", V_RANGE[0], V_RANGE, "m/s", "lowest speed"),
        _range("v_max", 200.0, V_RANGE, "m/s", "highest speed"),
        Field("n_points", "integer", "speeds on a geometric grid", default=200, low=10, high=2000),
        PARAMS, MATERIAL)),
    "devices": RequestSchema("devices", "NES torque/stiffness and PD damping curves", (
        Field("v_max", "number", "largest PD tangential speed", default=2.0, low=0.01, high=20.0, unit="m/s"),
        PARAMS, MATERIAL)),
    "bifurcation": RequestSchema("bifurcation", "bifurcation diagram in V (equilibrium and periodic branches)", (
        _config(), FZ, _range("v_min", V_RANGE[0], V_RANGE, "m/s", "lowest speed"),
        _range("v_max", 200.0, V_RANGE, "m/s", "highest speed"),
        Field("ntst", "integer", "collocation mesh intervals", default=40, low=10, high=settings.MAX_NTST),
        Field("seeds", "boolean", "look for branches not born at a Hopf point by simulation", default=True),
        PARAMS, MATERIAL)),
    "hopf_curves": RequestSchema("hopf_curves", "Hopf curves of x = 0 in (V, Fz) with generalised Hopf points", (
        _config(), _range("v_min", V_RANGE[0], V_RANGE, "m/s", "lowest speed"),
        _range("v_max", V_RANGE[1], V_RANGE, "m/s", "highest speed"),
        _range("fz_min", FZ_RANGE[0], FZ_RANGE, "N", "lowest load"),
        _range("fz_max", FZ_RANGE[1], FZ_RANGE, "N", "highest load"), PARAMS, MATERIAL)),
    "map": RequestSchema("map", "(V, Fz) stability map: Hopf, fold and torus curves, shimmy type on a grid, "
                         "design metrics", (
        _config(), _range("v_min", 1.0, V_RANGE, "m/s", "lowest speed"),
        _range("v_max", 200.0, V_RANGE, "m/s", "highest speed"),
        _range("fz_min", FZ_RANGE[0], FZ_RANGE, "N", "lowest load"),
        _range("fz_max", FZ_RANGE[1], FZ_RANGE, "N", "highest load"),
        Field("resolution", "integer", "classified Fz slices (more through regions they miss)",
              default=DEFAULT_MAP_SLICES, low=2, high=settings.MAX_MAP_SLICES),
        Field("n_v", "integer", "speeds per slice on the output grid", default=100, low=10,
              high=settings.MAX_MAP_SPEEDS),
        Field("metrics_Fz", "number", "load of the speed-interval and amplitude metrics", default=150e3,
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
        Field("Fz", "number", "vertical load", default=150e3, low=FZ_RANGE[0], high=FZ_RANGE[1], unit="N"),
        _range("v_min", 1.0, V_RANGE, "m/s", "lowest speed"),
        _range("v_max", 200.0, V_RANGE, "m/s", "highest speed"),
        PARAMS, MATERIAL)),
    "ground_run": RequestSchema("ground_run", "ground run: take-off, landing roll, taxi or a (t, V, Fz) table; "
                                "envelopes, time in shimmy, peaks, boundary crossings, onset delay", (
        _config(),
        Field("profile", "table", "rows [t (s), V (m/s), Fz (N)], linearly interpolated (instead of a preset)",
              high=MAX_PROFILE_POINTS),
        Field("preset", "string", "preset profile, used when no profile table is given", default="takeoff",
              choices=tuple(PRESETS)),
        Field("preset_options", "object", "the preset's settings {name: value}; the rest at their defaults",
              default={}),
        Field("psi_threshold", "number", "torsional amplitude counted as shimmy", default=0.01, low=1e-6, high=1.0,
              unit="rad"),
        Field("lateral_threshold", "number", "lateral amplitude l_g delta counted as shimmy", default=0.001,
              low=1e-7, high=1.0, unit="m"),
        Field("series_dt", "number", "sampling interval of the returned series (a multiple of 1 ms)", default=0.01,
              low=0.001, high=1.0, unit="s"),
        Field("fold_torus", "boolean", "also the crossings of the fold and torus curves of cycles (seconds per "
              "configuration)", default=False),
        Field("hopf_curves", "boolean", "include the configuration's Hopf curves (V 1-500 m/s, Fz 10-900 kN)",
              default=False),
        Field("exact_nes", "boolean", "exact NES torque instead of the cubic fit", default=False),
        PARAMS, MATERIAL)),
}

#: Analyses that run as background jobs (POST /api/v1/jobs).
JOB_ANALYSES = ("simulate", "bifurcation", "hopf_curves", "map", "study", "ground_run")


def validate(analysis: str, body: Any, extra: tuple[str, ...] = ()) -> dict[str, Any]:
    if analysis not in SCHEMAS:
        raise unknown_name_error(analysis, list(SCHEMAS), "analysis")
    return SCHEMAS[analysis].validate(body, extra)

