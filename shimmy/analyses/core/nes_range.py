"""Where the NES's cubic torque stops being the device: a result whose NES relative rotation
psi - psi_s leaves the cubic's stated range (its torque within 1 % of the exact one,
:func:`shimmy.model.nes.cubic_range`, for the design at hand) says so, and how far off the cubic is
there, so that the user reruns it with the exact torque (``exact_nes``). One wording for every
result that can carry it (time histories, ground runs, bifurcation diagrams) and so for the API,
the command line and the workbench."""

from __future__ import annotations

import numpy as np

from ...model.configurations import Configuration
from ...model import nes as nes_model
from ...model.nes import CUBIC_TOLERANCE, VALID_ANGLE, cubic_range
from ...model.parameters import Parameters

#: The warning's first words: pages and tests find it by them.
WARNING_START = "NES rotation beyond the cubic's range"


def rotation_peak(states: np.ndarray) -> float:
    """The largest |psi - psi_s| (rad) of states (n_states, samples); 0 without an NES."""
    if states.shape[0] < 6 or states.shape[1] == 0:
        return 0.0
    return float(np.max(np.abs(states[0] - states[5])))


def cubic_error(params: Parameters, a: float) -> float:
    """Relative error of the cubic torque against the exact one at rotation ``a`` (rad, |a| < pi/6)."""
    n = params.nes
    return float(nes_model.cubic_error(min(abs(a), 0.999 * VALID_ANGLE), n.r1, n.r2, n.r3, n.k_s, n.e_p))


def warning(config: Configuration | str, params: Parameters, peak: float, exact_nes: bool,
            bound: bool = False, where: str = "") -> str | None:
    """The warning for a result of ``config`` whose NES relative rotation reaches ``peak`` (rad), or None
    (no NES, the exact torque used, or within the cubic's range). ``bound``: ``peak`` is an upper
    bound, not a value reached ("may reach"); ``where`` says where it does ("on the stable cycles")."""
    if exact_nes or not Configuration.parse(config).has_nes or peak <= 0.0:
        return None
    n = params.nes
    limit = cubic_range(n.r1, n.r2, n.r3, n.k_s, n.e_p)
    if peak <= limit:
        return None
    reach = "may reach up to" if bound else "reaches"
    return (f"{WARNING_START}: the NES relative rotation {reach} {peak:.3g} rad{' ' + where if where else ''}, where the cubic torque is "
            f"{100 * cubic_error(params, peak):.2g} % off the exact one; the cubic is within "
            f"{100 * CUBIC_TOLERANCE:g} % only up to {limit:.3g} rad for this design. Rerun with the exact NES "
            "torque (exact_nes) to trust this result.")
