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
from .continuation.lazy import lazy_exports

#: The analyses' front doors, imported on first use: ``import shimmy`` loads no compiled kernel.
_EXPORTS = {
    "SimulationOptions": ".analyses.core.simulation", "SimulationResult": ".analyses.core.simulation",
    "simulate": ".analyses.core.simulation",
    "HopfPoint": ".analyses.core.stability", "HopfResult": ".analyses.core.stability",
    "eigenvalues": ".analyses.core.stability", "hopf_points": ".analyses.core.stability",
    "GroundProfile": ".analyses.ground.ground_profiles", "preset": ".analyses.ground.ground_profiles",
    "profile_from_table": ".analyses.ground.ground_profiles",
    "GroundRunOptions": ".analyses.ground.ground_run", "GroundRunResult": ".analyses.ground.ground_run",
    "ground_run": ".analyses.ground.ground_run", "ground_runs": ".analyses.ground.ground_run",
}
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)

__all__ = [
    "ALL_CONFIGURATIONS", "Configuration", "ConvergenceError", "GeometryError",
    "InvalidParameterError", "MATERIALS", "PARAMETER_SPECS", "Parameters", "ShimmyError",
    "SimulationOptions", "SimulationResult", "simulate", "HopfPoint", "HopfResult", "eigenvalues",
    "hopf_points", "GroundProfile", "preset", "profile_from_table", "GroundRunOptions", "GroundRunResult",
    "ground_run", "ground_runs", "__version__",
]
