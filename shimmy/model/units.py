"""The units quantities are shown in, for people (tables of the command line, the workbench's
status lines): one per quantity. Results and requests keep SI units (N, m); text shows loads in kN
and the lateral displacement l_g delta in mm; speeds in m/s and angles in rad as they are."""

from __future__ import annotations


def kn(Fz: float, digits: int = 6) -> str:
    """A load (N) as text in kN, to ``digits`` significant digits: ``kn(550000.0)`` is ``"550 kN"``."""
    return f"{Fz / 1e3:.{digits}g} kN"


def kn_range(low: float, high: float, digits: int = 6) -> str:
    """A range of loads (N) as text in kN: ``"10..900 kN"``."""
    return f"{low / 1e3:.{digits}g}..{high / 1e3:.{digits}g} kN"


def mm(lateral: float, digits: int = 6) -> str:
    """A lateral displacement l_g delta (m) as text in mm."""
    return f"{lateral * 1e3:.{digits}g} mm"
