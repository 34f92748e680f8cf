"""A page's numeric fields: limits from the request schema (the one definition the API and the CLI
use), shown and refused in the unit the page shows the field in (Fz in kN), quoting what was typed.

The boxes carry no ``min``/``max``/``step`` of their own: a browser turns a value outside them into
"no value", which a page could only mistake for "empty" and replace by a default. The page reads
the raw number and refuses it here, by name, in the box's unit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from dash import dcc

from shimmy.errors import InvalidParameterError
from shimmy.service import schemas

from .formats import significant


@dataclass(frozen=True)
class Quantity:
    """A request field as a page shows it: ``scale`` SI units per shown unit (1e3 for kN)."""

    analysis: str
    name: str  # the request field
    label: str  # how the page names it in a message
    unit: str  # the unit the page shows
    scale: float = 1.0

    @property
    def spec(self) -> schemas.Field:
        return schemas.SCHEMAS[self.analysis].field(self.name)

    @property
    def low(self) -> float:
        return self.spec.low / self.scale

    @property
    def high(self) -> float:
        return self.spec.high / self.scale

    @property
    def integer(self) -> bool:
        return self.spec.kind == "integer"

    @property
    def allowed(self) -> str:
        kind = "an integer" if self.integer else "a number"
        return f"{kind} in [{significant(self.low, 6)}, {significant(self.high, 6)}] {self.unit}".rstrip()

    def _refuse(self, value: Any, why: str) -> InvalidParameterError:
        return InvalidParameterError(self.name, value, self.allowed, message=why)

    def shown(self, value: Any) -> str:
        return f"{self.label} = {value:g} {self.unit}".rstrip() if isinstance(value, (int, float)) else \
            f"{self.label} = {value}"

    def read(self, value: Any) -> float | int:
        """The value typed into the box, in SI units; refused with a message in the box's unit."""
        if value is None or (isinstance(value, str) and not value.strip()):
            raise self._refuse(value, f"{self.label} is empty or not a number; enter {self.allowed}")
        if isinstance(value, bool):
            raise self._refuse(value, f"{self.label} = {value} is not a number; enter {self.allowed}")
        try:
            number = float(value)
        except (TypeError, ValueError):
            raise self._refuse(value, f"{self.label} = {value!s} is not a number; enter {self.allowed}") from None
        if not math.isfinite(number):
            raise self._refuse(value, f"{self.label} = {value!s} is not finite; enter {self.allowed}")
        if self.integer and number != round(number):
            raise self._refuse(value, f"{self.shown(number)} is not a whole number; enter {self.allowed}")
        if not self.low <= number <= self.high:
            raise self._refuse(value, f"{self.shown(number)} is outside [{significant(self.low, 6)}, "
                                      f"{significant(self.high, 6)}] "
                                      f"{self.unit}".rstrip())
        si = number * self.scale
        return int(round(si)) if self.integer else si

    def from_url(self, key: str, raw: Any, default: float) -> tuple[float | None, str | None]:
        """The box's first value from the address (``key=raw``) and, if it is not usable, why.

        A value that is not a number leaves the box empty (nothing is computed from it); one out of
        range is put in the box as it is, so the page refuses it in the box's unit when asked."""
        if raw is None:
            return default, None
        try:
            number = float(raw)
        except (TypeError, ValueError):
            return None, f"The address gives {key}={raw}, which is not a number: enter {self.label} ({self.allowed})."
        if not math.isfinite(number):
            return None, f"The address gives {key}={raw}, which is not finite: enter {self.label} ({self.allowed})."
        try:
            self.read(number)
        except InvalidParameterError as exc:
            return number, f"The address gives {key}={raw}: {exc}."
        return number, None

    def box(self, box_id: str, value: float | None, **kwargs) -> dcc.Input:
        """The number box (no browser-side limits: the page refuses a bad value by name)."""
        return dcc.Input(id=box_id, type="number", value=value, step="any", **kwargs)


@dataclass(frozen=True)
class SignedQuantity(Quantity):
    """A request field read within [-``largest``, ``largest``], narrower than the field's own limits: a size whose
    range depends on a choice beside its box (a ground run's kick: rad for a yaw angle, rad/s for a yaw rate)."""

    largest: float = 0.0

    @property
    def low(self) -> float:
        return -self.largest

    @property
    def high(self) -> float:
        return self.largest


def choice(key: str, raw: Any, choices, default: str, what: str) -> tuple[str, str | None]:
    """A choice from the address and, if it is not one of ``choices``, why the default is shown."""
    if raw is None or raw in choices:
        return (default if raw is None else raw), None
    return default, (f"The address gives {key}={raw}, which is not {what} ({', '.join(choices)}); "
                     f"showing {default}.")


def choices_list(key: str, raw: Any, choices, default: list[str], what: str) -> tuple[list[str], str | None]:
    """A comma-separated list of choices from the address; unknown entries are named, not dropped silently."""
    if raw is None:
        return list(default), None
    items = [c.strip() for c in str(raw).split(",") if c.strip()]
    unknown = [c for c in items if c not in choices]
    known = [c for c in items if c in choices]
    if not unknown:
        return known, None
    return known or list(default), (f"The address gives {key}={raw}: {', '.join(unknown)} "
                                    f"{'is' if len(unknown) == 1 else 'are'} not {what} ({', '.join(choices)}).")
