"""The settings of a bifurcation diagram, in a module of their own so that a command's help can show
their defaults without loading the continuation's compiled kernels (the engine is imported when the
options are checked or used)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from ...continuation.errors import InvalidInputError as EngineInvalidInputError
from ...errors import InvalidParameterError
from ...model.parameters import check_number

if TYPE_CHECKING:
    from ...continuation.periodic_orbits import PeriodicOptions

PERIOD_MAX = 2.0  # s: a period blow-up (homoclinic approach) stops a branch


@dataclass(frozen=True)
class BifurcationOptions:
    """A diagram's numerical settings: collocation mesh (``ntst`` intervals of ``ncol`` points), steps,
    whether to seed branches by simulation, the doubled-mesh check of the largest amplitude, the exact
    NES torque, and the curvature control of the periodic branches."""

    ntst: int = 40
    ncol: int = 4
    ds: float = 0.05
    ds_max: float = 0.5
    max_steps: int = 300
    seeds: bool = True
    mesh_check: bool = True
    exact_nes: bool = False
    max_angle: float = 0.2  # rad: the tangent turns at most this much per step (curvature control)

    def __post_init__(self):
        from ...continuation.periodic_orbits import PeriodicOptions

        try:  # the engine validates the mesh; the gear's callers see the gear's error class
            PeriodicOptions(ntst=self.ntst, ncol=self.ncol)
        except EngineInvalidInputError as exc:
            raise InvalidParameterError(exc.field, exc.value, exc.allowed, message=str(exc)) from None
        check_number("ds", self.ds, 1e-6, 1.0)
        check_number("ds_max", self.ds_max, self.ds, 10.0)
        check_number("max_steps", self.max_steps, 1, 100_000, integer=True)
        check_number("max_angle", self.max_angle, 0.01, 3.2, "rad")

    def periodic(self) -> PeriodicOptions:
        from ...continuation import ContinuationOptions
        from ...continuation.periodic_orbits import PeriodicOptions

        return PeriodicOptions(ntst=self.ntst, ncol=self.ncol, period_max=PERIOD_MAX,
                               continuation=ContinuationOptions(ds=self.ds, ds_max=self.ds_max,
                                                                max_steps=int(self.max_steps),
                                                                max_angle=self.max_angle))

