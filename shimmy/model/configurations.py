"""The four configurations of the gear: which devices are fitted."""

from __future__ import annotations

from enum import Enum

from .parameters import unknown_name_error


class Configuration(str, Enum):
    """A gear configuration; the value is the canonical name used by CLI, API and UI."""

    ORIGINAL = "original"
    NES = "nes"
    PD = "pd"
    NES_PD = "nes_pd"

    @property
    def has_nes(self) -> bool:
        return self in (Configuration.NES, Configuration.NES_PD)

    @property
    def has_pd(self) -> bool:
        return self in (Configuration.PD, Configuration.NES_PD)

    @property
    def n_states(self) -> int:
        """5 gear/tyre states, plus the absorber's rotation and rate with an NES."""
        return 7 if self.has_nes else 5

    @property
    def is_smooth(self) -> bool:
        """False where the vector field is not C^3 at dpsi = 0 (the PD's |dpsi|^(1/2) dpsi)."""
        return not self.has_pd

    @classmethod
    def parse(cls, value: "Configuration | str") -> "Configuration":
        if isinstance(value, cls):
            return value
        try:
            return cls(str(value))
        except ValueError:
            raise unknown_name_error(value, [c.value for c in cls], "config") from None


ALL_CONFIGURATIONS = tuple(Configuration)
#: Their names, in the same order: the default of every question asked of all configurations.
CONFIGURATION_NAMES = tuple(c.value for c in Configuration)


def affects(parameter: str, config: "Configuration | str") -> bool:
    """Whether ``parameter`` enters the model of ``config``: a device's parameters (group ``nes`` or
    ``pd``) do not enter a gear without that device, so a study of them there is a flat line."""
    from .parameters import PARAMETER_SPECS

    spec = PARAMETER_SPECS.get(parameter)
    if spec is None:
        raise unknown_name_error(parameter, PARAMETER_SPECS)
    config = Configuration.parse(config)
    return {"gear": True, "nes": config.has_nes, "pd": config.has_pd}[spec.group]

#: State names in order; an NES adds the last two.
STATE_NAMES = ("psi", "dpsi", "delta", "ddelta", "lam", "psis", "dpsis")
STATE_UNITS = ("rad", "rad/s", "rad", "rad/s", "m", "rad", "rad/s")

#: The study's operating points (docs/model.md): name -> (V in m/s, Fz in N). A-C low load (< 250 kN),
#: D-F medium (250-450 kN), G-I high (> 450 kN).
OPERATING_POINTS = {"A": (30.0, 150e3), "B": (110.0, 200e3), "C": (170.0, 150e3), "D": (50.0, 350e3),
                    "E": (135.0, 350e3), "F": (180.0, 350e3), "G": (50.0, 550e3), "H": (110.0, 550e3),
                    "I": (170.0, 550e3)}
