"""The settings of a disturbance margin and of basin fractions (:mod:`shimmy.analyses.maps.margins`), with
their limits, in a module of their own: the request schemas and the command line read them without
loading the integrator."""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

from ...errors import InvalidParameterError
from ...model.parameters import check_number, unknown_name_error

#: The disturbed components of the state, their index and unit; the rest of the state starts at rest.
COMPONENTS = {"psi": (0, "rad"), "dpsi": (1, "rad/s"), "delta": (2, "rad"), "ddelta": (3, "rad/s")}
#: The directions a margin is asked along: one component, a given mix of them ("mix", with ``mix``), or all four in
#: the energy norm ("energy").
DIRECTIONS = (*COMPONENTS, "mix", "energy")
#: Where the disturbance is added: to straight rolling, or to the attractor the standard start reaches (at
#: ``phases`` points of its cycle).
ORIGINS = ("straight_rolling", "standard_attractor")
#: (low, high, unit, integer) of every numeric setting.
LIMITS = {"max_size": (0.002, 1.0, "rad", False), "min_size": (1e-5, 0.1, "rad", False),
          "scan_points": (4, 40, "", True), "rtol": (1e-4, 0.1, "", False), "t_max": (10.0, 600.0, "s", False),
          "radius": (1e-3, 1.0, "rad", False), "samples": (10, 5000, "", True), "seed": (0, 2 ** 31 - 1, "", True),
          "n_v": (2, 60, "", True), "n_fz": (2, 40, "", True), "phases": (1, 32, "", True)}
MIX_EXAMPLE = "psi=0.01,dpsi=0.2"
#: The phases of an orbit kicked by default: an even number, so that kicks u over a whole period also cover -u
#: (half a period later, on the gear's symmetric cycles).
PHASES = 8


#: A mix's value as typed: a plain decimal number, optionally signed and with an exponent.
_NUMBER = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?", re.ASCII)
#: The magnitudes a mix's nonzero values may have (in their units): only the direction counts, and one far
#: outside these would put the others below the direction's rounding.
MIX_MAGNITUDE = (1e-9, 1e6)


def parse_mix(value: Any) -> str:
    """The canonical text of a mix of components (``"psi=0.01,dpsi=0.2"``: each the component's value in its
    unit, rad or rad/s; only the direction counts, the size is searched): the named components in state order,
    zeros left out. Refused with the field ``mix`` named: not text, an empty part, an unknown component, a value
    that is not a plain number or whose magnitude is outside ``MIX_MAGNITUDE``, a component twice, all zero."""
    low, high = MIX_MAGNITUDE
    allowed = (f"components and values such as '{MIX_EXAMPLE}' (of {', '.join(COMPONENTS)}; rad, rad/s; each 0 or "
               f"of magnitude {low:g} to {high:g})")
    if not isinstance(value, str) or not value.strip():
        raise InvalidParameterError("mix", value, allowed, "is not a list of component=value")
    values: dict[str, float] = {}
    for part in value.split(","):
        if not part.strip():
            raise InvalidParameterError("mix", value, allowed, "has an empty part (two commas, or one at an end)")
        name, sep, number = (piece.strip() for piece in part.partition("="))
        if not sep:
            raise InvalidParameterError("mix", value, allowed, f"has '{part.strip()}' without '='")
        if name not in COMPONENTS:
            raise InvalidParameterError("mix", value, allowed, f"names an unknown component '{name}'")
        if name in values:
            raise InvalidParameterError("mix", value, allowed, f"names {name} twice")
        if not _NUMBER.fullmatch(number):
            raise InvalidParameterError("mix", value, allowed, f"gives {name} the value '{number}', not a number")
        values[name] = float(number) + 0.0  # -0 is 0
        if values[name] and not low <= abs(values[name]) <= high:
            raise InvalidParameterError("mix", value, allowed, f"gives {name} the value {number}, of a magnitude "
                                        f"outside {low:g} to {high:g}")
    if not any(values.values()):
        raise InvalidParameterError("mix", value, allowed, "is zero in every component: no direction")
    return ",".join(f"{name}={values[name]!r}" for name in COMPONENTS if values.get(name))


def mix_vector(mix: str) -> "dict[str, float]":
    """The components of a canonical mix (:func:`parse_mix`), in their units."""
    return {name: float(number) for name, number in (part.split("=") for part in mix.split(","))}


def _check(name: str, value: Any) -> float:
    low, high, unit, integer = LIMITS[name]
    number = check_number(name, value, low, high, unit, integer)
    return int(number) if integer else number


@dataclass(frozen=True)
class MarginOptions:
    """How a margin is searched: ``direction`` (psi, dpsi, delta, ddelta, mix with ``mix`` (:func:`parse_mix`),
    or energy); the scan's sizes from ``min_size`` to ``max_size`` (rad, as the yaw angle of the same energy) in
    ``scan_points`` geometric steps; bisection to ``rtol`` of the threshold; runs of at most ``t_max`` (s);
    the disturbance added to straight rolling or to the attractor the standard start reaches (``origin``), there at
    ``phases`` points of its cycle."""

    direction: str = "psi"
    max_size: float = 0.4
    min_size: float = 0.001
    scan_points: int = 12
    rtol: float = 0.005
    t_max: float = 80.0
    mix: str | None = None
    origin: str = "straight_rolling"
    phases: int = PHASES

    def __post_init__(self):
        if self.direction not in DIRECTIONS:
            raise unknown_name_error(str(self.direction), DIRECTIONS, "direction")
        if self.direction == "mix":
            if self.mix is None:
                raise InvalidParameterError("mix", None, f"components and values such as '{MIX_EXAMPLE}'",
                                            "is needed with direction mix")
            object.__setattr__(self, "mix", parse_mix(self.mix))
        elif self.mix is not None:
            raise InvalidParameterError("mix", self.mix, "none unless direction is mix",
                                        f"is given with direction {self.direction}, which does not read it")
        if self.origin not in ORIGINS:
            raise unknown_name_error(str(self.origin), ORIGINS, "origin")
        object.__setattr__(self, "phases", _check("phases", self.phases))
        if self.origin == "straight_rolling" and self.phases != PHASES:
            raise InvalidParameterError("phases", self.phases, f"{PHASES} (the default) unless origin is "
                                        "standard_attractor", "is given with origin straight_rolling, which does not "
                                        "read it")
        object.__setattr__(self, "max_size", _check("max_size", self.max_size))
        object.__setattr__(self, "min_size", _check("min_size", self.min_size))
        if not self.min_size < self.max_size:
            raise InvalidParameterError("min_size", self.min_size, f"a number below max_size = {self.max_size:g} rad",
                                        "must be below max_size")
        object.__setattr__(self, "scan_points", _check("scan_points", self.scan_points))
        object.__setattr__(self, "rtol", _check("rtol", self.rtol))
        object.__setattr__(self, "t_max", _check("t_max", self.t_max))

    def to_dict(self) -> dict[str, Any]:
        return dict(self.__dict__)


@dataclass(frozen=True)
class BasinOptions:
    """Disturbances uniform in the energy ball of ``radius`` (rad, the yaw angle of the same energy), ``samples``
    of them from ``seed``; runs of at most ``t_max`` (s)."""

    radius: float = 0.2
    samples: int = 200
    seed: int = 0
    t_max: float = 80.0

    def __post_init__(self):
        object.__setattr__(self, "radius", _check("radius", self.radius))
        object.__setattr__(self, "samples", _check("samples", self.samples))
        object.__setattr__(self, "seed", _check("seed", self.seed))
        object.__setattr__(self, "t_max", _check("t_max", self.t_max))

    def to_dict(self) -> dict[str, Any]:
        return dict(self.__dict__)




@dataclass(frozen=True)
class MapGrid:
    """The cells of a margin map (:mod:`shimmy.analyses.maps.margin_map`): ``n_v`` speeds by ``n_fz`` loads, the
    plane cut into equal cells, each asked at its centre."""

    n_v: int = 20
    n_fz: int = 10

    def __post_init__(self):
        object.__setattr__(self, "n_v", _check("n_v", self.n_v))
        object.__setattr__(self, "n_fz", _check("n_fz", self.n_fz))

    def to_dict(self) -> dict[str, Any]:
        return dict(self.__dict__)
