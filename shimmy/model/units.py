"""The units quantities are shown in, for people (tables of the command line, the workbench's axes,
tables, hover texts, status lines and downloads): one per quantity. Results and requests keep SI
units (N, m, rad); people read loads in kN and the lateral displacement l_g delta in mm; speeds in
m/s and angles in rad as they are (degrees beside them in hover texts).

``KN`` and ``MM`` are the SI units per shown unit: ``Fz / KN`` is a load in kN, ``value_mm * MM``
a displacement in m again.
"""

from __future__ import annotations

import math

#: N per kN (a load is shown in kN).
KN = 1e3
#: m per mm (the lateral displacement l_g delta is shown in mm).
MM = 1e-3


def to_kn(Fz: float | None) -> float | None:
    """A load (N) in kN (None stays None: a missing value)."""
    return None if Fz is None else Fz / KN


def to_mm(lateral: float | None) -> float | None:
    """A lateral displacement l_g delta (m) in mm (None stays None)."""
    return None if lateral is None else lateral / MM


def kn(Fz: float, digits: int = 6) -> str:
    """A load (N) as text in kN, to ``digits`` significant digits: ``kn(550000.0)`` is ``"550 kN"``."""
    return f"{Fz / KN:.{digits}g} kN"


def kn_range(low: float, high: float, digits: int = 6) -> str:
    """A range of loads (N) as text in kN: ``"10..900 kN"``."""
    return f"{low / KN:.{digits}g}..{high / KN:.{digits}g} kN"


def mm(lateral: float, digits: int = 6) -> str:
    """A lateral displacement l_g delta (m) as text in mm."""
    return f"{lateral / MM:.{digits}g} mm"


def degrees(angle: float, digits: int = 3) -> str:
    """An angle (rad) in degrees, for a hover text beside the value in rad: ``degrees(0.1)`` is ``"5.73°"``."""
    return f"{math.degrees(angle):.{digits}g}°"
