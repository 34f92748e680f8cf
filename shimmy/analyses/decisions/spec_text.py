"""Constraint and tolerance strings as typed ('max_psi@150000 <= 0.02', 'k_s = 0.05 : uniform'): read
with every space ignored ('150 000', '< =', as ever), and each part also kept as typed, its ends stripped,
for a refusal to quote ('0.02 extra', not '0.02extra'). The package's parsers
(:class:`~shimmy.analyses.decisions.optimise.Constraint`, :class:`~shimmy.analyses.decisions.robustness.Tolerance`)
and the service's request schemas share these."""

from __future__ import annotations

import re

#: a constraint's operator, spaces allowed inside it: group 1 is "<" or ">"
OPERATOR = re.compile(r"([<>])\s*=")


def compact(part: str) -> str:
    """``part`` without any space (how it is read)."""
    return "".join(part.split())


def constraint_parts(text: str) -> tuple[str, str, str, str | None] | None:
    """(figure, op, value, Fz) of 'FIGURE[@FZ] OP VALUE' as typed (ends stripped; Fz None without '@'),
    or None without an operator."""
    found = OPERATOR.search(text)
    if found is None:
        return None
    figure, at, fz = text[:found.start()].partition("@")
    return figure.strip(), found.group(1) + "=", text[found.end():].strip(), fz.strip() if at else None


def tolerance_parts(text: str) -> tuple[str, str, str | None] | None:
    """(name, relative, distribution) of 'NAME=REL[:DIST]' as typed (ends stripped; None without ':'), or
    None without '='."""
    name, sep, rest = text.partition("=")
    if not sep:
        return None
    relative, colon, dist = rest.partition(":")
    return name.strip(), relative.strip(), dist.strip() if colon else None


def name_text(typed: str, names) -> str:
    """A name part as read (spaces dropped: 'max _psi' -> 'max_psi') if it is one of ``names``, else as typed
    (to be refused quoting it)."""
    read = compact(typed)
    return read if read in names else typed


def number_text(typed: str) -> str:
    """A number part as read (spaces dropped: '150 000' -> '150000') if it is one, else as typed (to be
    refused quoting it)."""
    read = compact(typed)
    try:
        float(read)
    except ValueError:
        return typed
    return read
