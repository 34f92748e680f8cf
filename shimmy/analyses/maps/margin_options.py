"""The settings of a disturbance margin and of basin fractions (:mod:`shimmy.analyses.maps.margins`), with
their limits, in a module of their own: the request schemas and the command line read them without
loading the integrator."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ...errors import InvalidParameterError
from ...model.parameters import check_number, unknown_name_error

#: The disturbed components of the state, their index and unit; the rest of the state starts at rest.
COMPONENTS = {"psi": (0, "rad"), "dpsi": (1, "rad/s"), "delta": (2, "rad"), "ddelta": (3, "rad/s")}
#: The directions a margin is asked along: one component, or all four in the energy norm ("energy").
DIRECTIONS = (*COMPONENTS, "energy")
#: (low, high, unit, integer) of every numeric setting.
LIMITS = {"max_size": (0.002, 1.0, "rad", False), "min_size": (1e-5, 0.1, "rad", False),
          "scan_points": (4, 40, "", True), "rtol": (1e-4, 0.1, "", False), "t_max": (10.0, 600.0, "s", False),
          "radius": (1e-3, 1.0, "rad", False), "samples": (10, 5000, "", True), "seed": (0, 2 ** 31 - 1, "", True),
          "n_v": (2, 60, "", True), "n_fz": (2, 40, "", True)}


def _check(name: str, value: Any) -> float:
    low, high, unit, integer = LIMITS[name]
    number = check_number(name, value, low, high, unit, integer)
    return int(number) if integer else number


@dataclass(frozen=True)
class MarginOptions:
    """How a margin is searched: ``direction`` (psi, dpsi, delta, ddelta or energy); the scan's sizes from
    ``min_size`` to ``max_size`` (rad, as the yaw angle of the same energy) in ``scan_points`` geometric
    steps; bisection to ``rtol`` of the threshold; runs of at most ``t_max`` (s)."""

    direction: str = "psi"
    max_size: float = 0.4
    min_size: float = 0.001
    scan_points: int = 12
    rtol: float = 0.005
    t_max: float = 80.0

    def __post_init__(self):
        if self.direction not in DIRECTIONS:
            raise unknown_name_error(str(self.direction), DIRECTIONS, "direction")
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
