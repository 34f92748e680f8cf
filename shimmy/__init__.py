"""shimmy: nose-landing-gear shimmy with a torsional NES and an annular particle damper.

The model (docs/model.md) and its analyses: parameters, devices, equations with analytic
Jacobians, time histories, ground runs (take-off, landing roll, taxi), linear stability with
Hopf points, calibration, and a continuation engine (equilibria, periodic orbits with
Floquet multipliers, LPC/NS/PD points, Hopf curves) with the gear's bifurcation diagrams
(``shimmy.analyses.diagrams.bifurcation``, ``shimmy.analyses.diagrams.hopf_curves``, imported on demand).
"""

from .version import __version__
from .model.configurations import ALL_CONFIGURATIONS, Configuration
from .errors import ConvergenceError, GeometryError, InvalidParameterError, ShimmyError
from .model.parameters import MATERIALS, PARAMETER_SPECS, Parameters
from .analyses.core.simulation import SimulationOptions, SimulationResult, simulate
from .analyses.core.stability import HopfPoint, HopfResult, eigenvalues, hopf_points
from .analyses.ground.ground_profiles import GroundProfile, preset, profile_from_table
from .analyses.ground.ground_run import GroundRunOptions, GroundRunResult, ground_run, ground_runs

__all__ = [
    "ALL_CONFIGURATIONS", "Configuration", "ConvergenceError", "GeometryError",
    "InvalidParameterError", "MATERIALS", "PARAMETER_SPECS", "Parameters", "ShimmyError",
    "SimulationOptions", "SimulationResult", "simulate", "HopfPoint", "HopfResult", "eigenvalues",
    "hopf_points", "GroundProfile", "preset", "profile_from_table", "GroundRunOptions", "GroundRunResult",
    "ground_run", "ground_runs", "__version__",
]
