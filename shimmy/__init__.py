"""shimmy: nose-landing-gear shimmy with a torsional NES and an annular particle damper.

The model (docs/model.md) and its analyses: parameters, devices, equations with analytic
Jacobians, time histories, ground runs (take-off, landing roll, taxi), linear stability with
Hopf points, calibration, and a continuation engine (equilibria, periodic orbits with
Floquet multipliers, LPC/NS/PD points, Hopf curves) with the gear's bifurcation diagrams
(``shimmy.analyses.bifurcation``, ``shimmy.analyses.hopf_curves``, imported on demand).
"""

__version__ = "0.1.0"

from .model.configurations import ALL_CONFIGURATIONS, Configuration  # noqa: E402
from .errors import ConvergenceError, GeometryError, InvalidParameterError, ShimmyError  # noqa: E402
from .model.parameters import MATERIALS, PARAMETER_SPECS, Parameters  # noqa: E402
from .analyses.simulation import SimulationOptions, SimulationResult, simulate  # noqa: E402
from .analyses.stability import HopfPoint, HopfResult, eigenvalues, hopf_points  # noqa: E402
from .analyses.ground_profiles import GroundProfile, preset, profile_from_table  # noqa: E402
from .analyses.ground_run import GroundRunOptions, GroundRunResult, ground_run, ground_runs  # noqa: E402

__all__ = [
    "ALL_CONFIGURATIONS", "Configuration", "ConvergenceError", "GeometryError",
    "InvalidParameterError", "MATERIALS", "PARAMETER_SPECS", "Parameters", "ShimmyError",
    "SimulationOptions", "SimulationResult", "simulate", "HopfPoint", "HopfResult", "eigenvalues",
    "hopf_points", "GroundProfile", "preset", "profile_from_table", "GroundRunOptions", "GroundRunResult",
    "ground_run", "ground_runs", "__version__",
]
