"""How the pages write numbers: one definition of each way, named by what it does.

Every formatter that may meet a missing value (None) writes it as an en dash; the signed ones never
write "-0" (a value that rounds to zero is written without a sign).
"""

from __future__ import annotations

MISSING = "–"


def significant(x: float | None, digits: int = 4) -> str:
    """``digits`` significant digits (Python's ``g``: 0.0123, 1.13e+04)."""
    return MISSING if x is None else f"{x:.{digits}g}"


def significant_or_whole(x: float | None, digits: int = 4) -> str:
    """``digits`` significant digits; whole numbers from 10 000 up to 1e9 written out (11300, not 1.13e+04)."""
    if x is None:
        return MISSING
    return f"{x:.0f}" if 1e4 <= abs(x) < 1e9 else f"{x:.{digits}g}"


def compact(x: float, digits: int = 6) -> str:
    """``digits`` significant digits with a short exponent (1.4e+06 -> 1.4e6): slider ends, tables, hover text."""
    return f"{x:.{digits}g}".replace("e+0", "e").replace("e-0", "e-").replace("e+", "e")


def signed(x: float | None, digits: int = 3) -> str:
    """A signed number to ``digits`` significant digits; zero without a sign (no "-0")."""
    if x is None:
        return MISSING
    text = f"{x:+.{digits}g}"
    return "0" if float(text) == 0 else text


def signed_or_whole(x: float | None, digits: int = 3) -> str:
    """A signed change to ``digits`` significant digits, from 1000 up to 1e9 written out whole (+1250, not
    +1.25e+03); zero without a sign."""
    if x is None:
        return MISSING
    text = f"{x:+.0f}" if 1e3 <= abs(x) < 1e9 else f"{x:+.{digits}g}"
    return "0" if float(text) == 0 else text


def signed_percent(x: float | None, digits: int = 1) -> str:
    """A signed percentage with ``digits`` decimals; one that rounds to zero is "0.0 %", never "-0.0 %"."""
    if x is None:
        return MISSING
    text = f"{x:+.{digits}f}"
    if float(text) == 0:
        text = f"{0:.{digits}f}"
    return f"{text} %"
