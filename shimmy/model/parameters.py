"""Typed, immutable parameter sets of the shimmy model (docs/model.md), in SI units.

Every parameter is declared once, as a dataclass field whose metadata carries its
unit, allowed range, description and provenance. Everything else (the CLI listing,
the API schema, UI slider ranges, validation) reads these declarations, so a range
is never written twice.

Ranges: where the published study gives a range it is used as is; for the gear and tyre
constants, which the study gives as single values, the range is a plausible
engineering envelope around the nominal value (documented per field).
"""

from __future__ import annotations

import copy
import dataclasses
import difflib
import hashlib
import json
import math
from dataclasses import dataclass, field
from typing import Any, Mapping

from ..errors import InvalidParameterError

PUBLISHED = "published study"
ENVELOPE = "published value; range is an engineering envelope around it"
CALIBRATED = "calibrated by shimmy.analyses.core.calibration against the published study (docs/validation.md)"
FIXED = "docs/model.md"


def _param(default: float, low: float, high: float, unit: str, description: str,
           provenance: str = PUBLISHED, integer: bool = False, step: float | None = None):
    return field(default=default, metadata={
        "low": low, "high": high, "unit": unit, "description": description,
        "provenance": provenance, "integer": integer, "step": step})


@dataclass(frozen=True)
class ParameterSpec:
    """What a parameter is: name, group, unit, default, allowed range, meaning."""

    name: str
    group: str
    unit: str
    default: float
    low: float
    high: float
    description: str
    provenance: str
    integer: bool = False
    #: the engineering step a design parameter moves by (its slider's step; values it gives are
    #: rounded to it), None for the others
    step: float | None = None

    @property
    def decimals(self) -> int:
        """Decimal places of a value on the step grid (values rounded to them print without float
        noise: 0.0778, not 0.07780000000000001); 0 without a step."""
        if self.step is None:
            return 0
        return max(0, -math.floor(math.log10(self.step) + 1e-9)) + (0 if float(f"{self.step:.0e}") == self.step else 1)

    def on_step(self, value: float) -> float:
        """``value`` rounded to the step grid from ``low`` (unchanged without a step)."""
        if self.step is None:
            return float(value)
        return round(self.low + round((value - self.low) / self.step) * self.step, self.decimals)

    @property
    def allowed(self) -> str:
        kind = "an integer" if self.integer else "a number"
        return f"{kind} in [{self.low:g}, {self.high:g}] {self.unit}".rstrip()

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)


def _validate_fields(obj) -> None:
    for f in dataclasses.fields(obj):
        value = getattr(obj, f.name)
        checked = check_number(f.name, value, f.metadata["low"], f.metadata["high"],
                               f.metadata["unit"], f.metadata["integer"])
        object.__setattr__(obj, f.name, checked)


class _AsTyped(str):
    """A number as the user typed it, shown in messages without quotes."""

    def __repr__(self) -> str:
        return str(self)


def check_number(name: str, value: Any, low: float, high: float, unit: str = "",
                 integer: bool = False) -> float:
    """Return ``value`` as a float after checking it is a finite number in [low, high].

    Raises :class:`InvalidParameterError` naming ``name``, the value and the range.
    """
    kind = "an integer" if integer else "a number"
    allowed = f"{kind} in [{low:g}, {high:g}] {unit}".rstrip()
    if isinstance(value, bool) or value is None:
        raise InvalidParameterError(name, value, allowed, "is not a number")
    typed = value
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise InvalidParameterError(name, typed, allowed, "is not a number") from None
    if isinstance(value, str):  # a number typed as text is quoted as typed (resolution=100, not 100.0)
        typed = _AsTyped(value.strip())
    if not math.isfinite(number):
        raise InvalidParameterError(name, typed, allowed, "is not finite")
    if integer and number != round(number):
        raise InvalidParameterError(name, typed, allowed, "is not an integer")
    if not low <= number <= high:
        raise InvalidParameterError(name, typed, allowed)
    return number


def check_pair(name: str, value: Any) -> tuple[Any, Any]:
    """``value`` as a (low, high) pair, or an error naming ``name``; the numbers are checked by the caller."""
    try:
        low, high = value
    except (TypeError, ValueError):
        raise InvalidParameterError(name, value, "a pair (low, high)") from None
    return low, high


def check_range(prefix: str, bounds: Any, allowed: tuple[float, float], unit: str = "") -> tuple[float, float]:
    """(low, high) of a range given as ``bounds``, checked as ``{prefix}_min`` and ``{prefix}_max``
    within ``allowed``, with high above low."""
    low = check_number(f"{prefix}_min", bounds[0], *allowed, unit)
    high = check_number(f"{prefix}_max", bounds[1], *allowed, unit)
    if not high > low:
        raise InvalidParameterError(f"{prefix}_max", high, f"a number in ({low:g}, {allowed[1]:g}] {unit}".rstrip(),
                                    f"must exceed {prefix}_min")
    return low, high


@dataclass(frozen=True)
class GearParameters:
    """Strut and tyre of the single-wheel nose landing gear."""

    Iz: float = _param(100.0, 10.0, 1000.0, "kg m^2", "strut inertia about the steering axis", ENVELOPE)
    Ix: float = _param(600.0, 60.0, 6000.0, "kg m^2", "strut inertia about x (lateral bending)", ENVELOPE)
    R: float = _param(0.362, 0.1, 1.0, "m", "wheel radius", ENVELOPE)
    phi: float = _param(0.1571, 0.0, 0.5, "rad", "rake angle (9 deg)", ENVELOPE)
    e: float = _param(0.12, 0.0, 0.5, "m", "caster length", ENVELOPE)
    k_psi: float = _param(3.8e5, 1e4, 1e7, "N m/rad", "torsional stiffness", ENVELOPE)
    c_psi: float = _param(300.0, 0.0, 1e4, "N m s/rad", "torsional damping", ENVELOPE)
    k_delta: float = _param(6.1e6, 1e5, 1e8, "N m/rad", "lateral bending stiffness", ENVELOPE)
    c_delta: float = _param(300.0, 0.0, 1e4, "N m s/rad", "lateral bending damping", ENVELOPE)
    k_a: float = _param(1.0, 0.0, 5.0, "m/rad", "self-aligning moment coefficient", ENVELOPE)
    alpha_m: float = _param(0.1745, 0.02, 0.5, "rad", "self-aligning moment limit (10 deg)", ENVELOPE)
    c_lam: float = _param(570.0, 0.0, 5000.0, "N m^2/rad", "tyre lateral damping", ENVELOPE)
    l_g: float = _param(2.5, 0.5, 5.0, "m", "gear height (attachment to ground)", ENVELOPE)
    h: float = _param(0.1, 0.0, 0.3, "m", "contact patch length", ENVELOPE)
    L: float = _param(0.3, 0.05, 1.0, "m", "tyre relaxation length", ENVELOPE)
    k_lam: float = _param(0.002022, 1e-4, 0.02, "1/rad", "tyre lateral force coefficient", CALIBRATED)

    def __post_init__(self):
        _validate_fields(self)


@dataclass(frozen=True)
class NESParameters:
    """Torsional nonlinear energy sink: roller-spring geometry, inertia and damping."""

    r1: float = _param(0.1, 0.05, 0.2, "m", "inner-cylinder radius", ENVELOPE)
    r2: float = _param(0.08, 0.07, 0.09, "m", "concave-track radius", step=1e-4)
    r3: float = _param(0.01, 0.005, 0.02, "m", "roller radius", step=1e-4)
    k_s: float = _param(1.2e6, 1.0e6, 1.4e6, "N/m", "spring stiffness", step=1e4)
    e_p: float = _param(0.001, 0.0005, 0.005, "m", "spring pre-stretch", step=5e-5)
    I_nes: float = _param(4.6746, 0.1, 50.0, "kg m^2", "absorber inertia", CALIBRATED)
    c_nes: float = _param(80.396, 0.0, 1000.0, "N m s/rad", "absorber damping", CALIBRATED)

    def __post_init__(self):
        _validate_fields(self)
        check_roller_track(self.r1, self.r2, self.r3)


def check_roller_track(r1: float, r2: float, r3: float) -> None:
    """The NES roller must stay on its track over the whole valid angle |a| < pi/6, i.e.
    (r2 + r3) > A sin(pi/6) with A = (sqrt(3)/2)(r1 + r2); raises InvalidParameterError on r3."""
    A = 0.5 * math.sqrt(3.0) * (r1 + r2)
    if r2 + r3 <= 0.5 * A:
        raise InvalidParameterError(
            "r3", r3, f"r2 + r3 > (sqrt(3)/4)(r1 + r2) = {0.5 * A:.5g} m",
            "makes the roller leave its track inside |a| < pi/6")


@dataclass(frozen=True)
class PDParameters:
    """Annular particle damper: ring geometry, particle material and packing."""

    r: float = _param(0.15, 0.05, 0.5, "m", "ring centre-line radius", ENVELOPE)
    n: float = _param(24.0, 1.0, 100.0, "", "number of segments", ENVELOPE, integer=True)
    H: float = _param(0.1, 0.01, 0.5, "m", "ring height (geometry record; h_chamber enters the model)", ENVELOPE)
    d_chamber: float = _param(0.06, 0.01, 0.2, "m", "segment chamber size d", ENVELOPE)
    h_chamber: float = _param(0.1, 0.01, 0.5, "m", "segment chamber height h_c", ENVELOPE)
    a_p: float = _param(0.9, 0.5, 0.95, "", "mass filling ratio", step=0.01)
    rho_p: float = _param(7800.0, 7800.0, 17000.0, "kg/m^3", "particle density", step=100.0)
    rho_m_frac: float = _param(0.9, 0.8, 0.95, "", "mixture density as a fraction of rho_p")
    g_p: float = _param(5.0, 1.0, 5.0, "", "radial distribution function", CALIBRATED)
    e_r: float = _param(0.8, 0.5, 0.9, "", "coefficient of restitution")
    d_p: float = _param(0.001, 0.0003, 0.002, "m", "mean particle diameter")
    f: float = _param(30.0, 10.0, 30.0, "", "correction factor", CALIBRATED)
    phi_f: float = _param(0.6109, 0.4363, 0.6981, "rad", "internal friction angle (25 to 40 deg)")
    I2D: float = _param(1.0, 0.1, 10.0, "", "second invariant I_2D of the deviatoric strain rate", ENVELOPE)
    I_pd: float = _param(4.9037, 0.0, 50.0, "kg m^2", "rotational inertia added by the damper", CALIBRATED)

    def __post_init__(self):
        _validate_fields(self)


GROUPS: dict[str, type] = {"gear": GearParameters, "nes": NESParameters, "pd": PDParameters}

#: PD material presets (docs/model.md): the fields each preset sets.
MATERIALS: dict[str, dict[str, float]] = {
    "steel": {"rho_p": 7800.0, "e_r": 0.8},
    "tungsten": {"rho_p": 16500.0, "e_r": 0.6},
}


def _specs() -> dict[str, ParameterSpec]:
    specs = {}
    for group, cls in GROUPS.items():
        for f in dataclasses.fields(cls):
            m = f.metadata
            specs[f.name] = ParameterSpec(f.name, group, m["unit"], f.default, m["low"], m["high"],
                                          m["description"], m["provenance"], m["integer"], m["step"])
    return specs


#: Every parameter by canonical name, in declaration order.
PARAMETER_SPECS: dict[str, ParameterSpec] = _specs()


def unknown_name_error(name: str, choices, field_name: str | None = None) -> InvalidParameterError:
    """Error for a name that is not among ``choices`` (a parameter, configuration, material)."""
    close = difflib.get_close_matches(str(name), list(choices), n=3)
    hint = f" (did you mean {', '.join(close)}?)" if close else ""
    allowed = f"one of {', '.join(choices)}"
    what = field_name or "parameter"
    return InvalidParameterError(field_name or str(name), name, allowed,
                                 message=f"unknown {what} {name!r}{hint}; allowed: {allowed}")


@dataclass(frozen=True)
class Parameters:
    """The complete parameter set: gear/tyre, NES and PD groups.

    Build variants with :meth:`with_overrides` (validated, by canonical name) or
    :meth:`with_material`; serialise with :meth:`to_dict` and :meth:`digest`.
    """

    gear: GearParameters = field(default_factory=GearParameters)
    nes: NESParameters = field(default_factory=NESParameters)
    pd: PDParameters = field(default_factory=PDParameters)

    def __getattr__(self, name: str):
        # Flat access by canonical name: params.r2, params.k_lam, ...
        spec = PARAMETER_SPECS.get(name)
        if spec is None:
            raise AttributeError(name)
        return getattr(object.__getattribute__(self, spec.group), name)

    def with_overrides(self, overrides: Mapping[str, Any] | None = None, **kwargs) -> "Parameters":
        """Return a copy with the named parameters replaced (each one validated)."""
        merged = dict(overrides or {}, **kwargs)
        grouped: dict[str, dict[str, Any]] = {g: {} for g in GROUPS}
        for name, value in merged.items():
            spec = PARAMETER_SPECS.get(name)
            if spec is None:
                raise unknown_name_error(name, PARAMETER_SPECS)
            grouped[spec.group][name] = value
        changes = {g: dataclasses.replace(getattr(self, g), **vals)
                   for g, vals in grouped.items() if vals}
        return dataclasses.replace(self, **changes)

    def with_sampled(self, overrides: Mapping[str, float]) -> "Parameters":
        """A copy with the named values replaced, allowed outside their design ranges (a tolerance
        study's samples reach past them); the physical conditions still hold: finite, positive where
        the range is positive (non-negative where it starts at 0), the NES roller on its track."""
        grouped: dict[str, dict[str, float]] = {g: {} for g in GROUPS}
        for name, value in overrides.items():
            spec = PARAMETER_SPECS.get(name)
            if spec is None:
                raise unknown_name_error(name, PARAMETER_SPECS)
            number = float(value)
            sign = "positive" if spec.low > 0 else "non-negative"
            if not math.isfinite(number) or number < 0 or (spec.low > 0 and number == 0):
                raise InvalidParameterError(name, value, f"a finite {sign} number {spec.unit}".rstrip(),
                                            "is not physical")
            grouped[spec.group][name] = number
        changes = {}
        for g, values in grouped.items():
            if values:
                group = copy.copy(getattr(self, g))
                for name, number in values.items():
                    object.__setattr__(group, name, number)
                changes[g] = group
        out = dataclasses.replace(self, **changes)
        check_roller_track(out.nes.r1, out.nes.r2, out.nes.r3)
        return out

    def with_material(self, material: str) -> "Parameters":
        """Apply a PD material preset ('steel' or 'tungsten')."""
        if material not in MATERIALS:
            raise unknown_name_error(material, MATERIALS, "material")
        return self.with_overrides(MATERIALS[material])

    def to_dict(self) -> dict[str, float]:
        """Flat canonical dict {name: value} in declaration order (JSON-safe)."""
        out: dict[str, float] = {}
        for group in GROUPS:
            out.update(dataclasses.asdict(getattr(self, group)))
        return out

    @classmethod
    def from_dict(cls, values: Mapping[str, Any]) -> "Parameters":
        return cls().with_overrides(values)

    def digest(self) -> str:
        """Stable SHA-256 of the canonical JSON form (for cache keys)."""
        return canonical_digest(self.to_dict())


def design_distance(a: Parameters, b: Parameters, config: Any = None) -> float:
    """The largest relative difference between two designs' parameters (0: the same design); with
    ``config``, of the parameters that enter that configuration's model only
    (:func:`~shimmy.model.configurations.affects`: a device's parameters do not enter a gear without it)."""
    da, db = a.to_dict(), b.to_dict()
    names = da if config is None else affecting(da, config)
    return max((abs(da[k] - db[k]) / max(abs(da[k]), abs(db[k]), 1e-300) for k in names if da[k] != db[k]),
               default=0.0)


def affecting(params: dict[str, Any], config: Any) -> dict[str, Any]:
    """The entries of a parameter dict that enter the model of ``config`` (names outside the
    parameter table are kept: what is not known to be irrelevant counts)."""
    from .configurations import affects

    return {k: v for k, v in params.items() if k not in PARAMETER_SPECS or affects(k, config)}


def canonical_json(obj: Any) -> str:
    """JSON with sorted keys and floats written by repr: equal inputs, equal text."""
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), allow_nan=False)


def canonical_digest(obj: Any) -> str:
    return hashlib.sha256(canonical_json(obj).encode()).hexdigest()


def check_operating_point(V: Any, Fz: Any) -> tuple[float, float]:
    """Validate forward speed V (m/s) and vertical load Fz (N) against the model's ranges (docs/model.md)."""
    return (check_number("V", V, V_RANGE[0], V_RANGE[1], "m/s"),
            check_number("Fz", Fz, FZ_RANGE[0], FZ_RANGE[1], "N"))


#: Operating ranges of the continuation parameters (docs/model.md).
V_RANGE = (1.0, 500.0)
FZ_RANGE = (1.0e4, 9.0e5)
#: The speeds (m/s) of a bifurcation diagram, a map or a study: up to the top speed of the study's figures.
DIAGRAM_V_RANGE = (V_RANGE[0], 200.0)
#: The load (N) of the one-load questions (the study's Figs. 3-10): every such default reads it.
DEFAULT_FZ = 150e3
#: The standard start of a time history (rad of torsion, the rest of the state at rest), as the study's.
DEFAULT_PSI0 = 0.001
#: Classified Fz slices of a stability map by default (its boundaries are continued curves; the
#: slices tell the regions' types, and more are added through regions they miss).
DEFAULT_MAP_SLICES = 10
