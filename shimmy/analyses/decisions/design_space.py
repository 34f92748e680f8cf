"""What the design analyses search, constrain and sample: the figures of merit, the device
parameters, the tolerance distributions and their limits.

Definitions only (no numerics): the optimiser and the robustness analysis use them, and the
service's request schemas read them without loading the solvers.
"""

from __future__ import annotations

from dataclasses import dataclass

from ...model.configurations import Configuration, affects
from ...model.parameters import FZ_RANGE


@dataclass(frozen=True)
class Figure:
    label: str
    unit: str
    sense: int  # +1 maximised, -1 minimised as an objective
    at_load: bool
    scale: float  # a typical size, to make objectives and constraints O(1)
    low: float  # the range a constraint's value may take, in ``unit``
    high: float


#: The figures of merit by name: label, unit, sense as an objective, whether taken at a load, scale,
#: the range of a constraint's value.
FIGURES = {
    "min_shimmy_Fz": Figure("minimum shimmy load", "N", +1, False, 1e5, FZ_RANGE[0], FZ_RANGE[1]),
    "interval": Figure("shimmy speed interval width", "m/s", -1, True, 100.0, 0.0, 199.0),  # within 1-200 m/s
    "max_psi": Figure("largest stable torsional amplitude", "rad", -1, True, 0.1, 0.0, 1.0),
    "torsion_area": Figure("pure-torsion area (Fz <= 250 kN)", "(m/s) kN", -1, False, 1e4, 0.0, 199.0 * 240.0),
}
#: Figures with derivatives (where the interval ends at Hopf points and the amplitude's maximum is
#: inside the stable part; a local search that meets a point without one stops there).
DIFFERENTIABLE = ("min_shimmy_Fz", "max_psi", "interval")
#: The device parameters with sliders in the workbench (their design ranges are the study's).
DESIGN_PARAMETERS = ("r2", "e_p", "k_s", "r3", "a_p", "rho_p")
#: Tolerance distributions and the largest relative tolerance of each: a normal one's standard
#: deviation up to 20 % (zero 5 standard deviations away), a uniform one's half-width up to 50 %.
TOLERANCE_LIMITS = {"normal": 0.2, "uniform": 0.5}
DISTRIBUTIONS = tuple(TOLERANCE_LIMITS)


def device_parameters(config: Configuration | str) -> list[str]:
    """The device parameters fitted in ``config`` (none for ``original``)."""
    return [n for n in DESIGN_PARAMETERS if affects(n, config)]
