"""The figures of merit as the pages name them, read from the package's one definition of them
(``shimmy.service.schemas.FIGURES``: label, unit, sense, ...) instead of written again here."""

from __future__ import annotations

import re

from shimmy.service.schemas import FIGURES


def label(name: str) -> str:
    """A figure's label as the pages write it: "pure-torsion area (Fz <= 250 kN)" -> "pure-torsion area,
    Fz ≤ 250 kN" (a qualifier after a comma, since the pages put the unit in brackets; <= as ≤)."""
    return re.sub(r" \((.*)\)$", r", \1", FIGURES[name].label.replace("<=", "≤"))


def unit(name: str) -> str:
    """A figure's unit (SI, or the package's own: "(m/s) kN" for the torsion area)."""
    return FIGURES[name].unit
