"""A page's numeric fields: limits from the request schema (the one definition the API and the CLI
use), shown and refused in the unit the page shows the field in (Fz in kN), quoting what was typed.

The boxes carry no ``min``/``max``/``step`` of their own: a browser turns a value outside them into
"no value", which a page could only mistake for "empty" and replace by a default. The page reads
the raw number and refuses it here, by name, in the box's unit.

A box refuses at the field, as the design panel does: it sends its value on Enter or on leaving it
(``debounce``), and the line under it (:func:`field_error`, kept up by :func:`check`) says at once
what is wrong, quoting what was typed and the allowed range; the page's button refuses the same, by
the same rules (:meth:`Quantity.read`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import dash
from dash import Input, Output, dcc, html

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
        return _allowed(self.low, self.high, self.unit, self.integer)

    def shown(self, value: Any) -> str:
        return _shown(self.label, value, self.unit)

    def read(self, value: Any) -> float | int:
        """The value typed into the box, in SI units; refused with a message in the box's unit."""
        number = typed_number(self.name, self.label, value, self.low, self.high, self.unit, self.integer)
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
        """The number box (no browser-side limits: the page refuses a bad value by name), sending its
        value on Enter or on leaving it."""
        kwargs.setdefault("debounce", True)
        return dcc.Input(id=box_id, type="number", value=value, step="any", **kwargs)

    def field(self, label: str, box_id: str, value: float | None, problem: str | None = None, **kwargs) -> html.Div:
        """The labelled box with the line under it that refuses what is typed (:func:`check` keeps it up);
        ``problem``: what it says when the page opens (a value of the address it cannot use)."""
        return html.Div([html.Label(label, htmlFor=box_id), self.box(box_id, value, **kwargs),
                         field_error(error_id(box_id), problem)], className="field")


def _allowed(low: float, high: float, unit: str, integer: bool = False) -> str:
    kind = "an integer" if integer else "a number"
    return f"{kind} in [{significant(low, 6)}, {significant(high, 6)}] {unit}".rstrip()


def _shown(label: str, value: Any, unit: str) -> str:
    return f"{label} = {value:g} {unit}".rstrip() if isinstance(value, (int, float)) else f"{label} = {value}"


def typed_number(name: str, label: str, value: Any, low: float, high: float, unit: str,
                 integer: bool = False) -> float:
    """What was typed into a box or a table cell, as a number in its unit (``unit``, range [low, high]);
    refused by ``name`` with a message quoting what was typed, in that unit, and the range."""
    allowed = _allowed(low, high, unit, integer)

    def refuse(why: str) -> InvalidParameterError:
        return InvalidParameterError(name, value, allowed, message=why)

    if value is None or (isinstance(value, str) and not value.strip()):
        raise refuse(f"{label} is empty or not a number; enter {allowed}")
    if isinstance(value, bool):
        raise refuse(f"{label} = {value} is not a number; enter {allowed}")
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise refuse(f"{label} = {value!s} is not a number; enter {allowed}") from None
    if not math.isfinite(number):
        raise refuse(f"{label} = {value!s} is not finite; enter {allowed}")
    if integer and number != round(number):
        raise refuse(f"{_shown(label, number, unit)} is not a whole number; enter {allowed}")
    if not low <= number <= high:
        raise refuse(f"{_shown(label, number, unit)} is outside [{significant(low, 6)}, {significant(high, 6)}] "
                     f"{unit}".rstrip())
    return number


@dataclass(frozen=True)
class Column:
    """A numeric column of an editable table as the page shows it: its id, label, unit and range (in that unit)."""

    id: str
    label: str
    unit: str
    low: float
    high: float


def cell_refusals(rows: Any, columns: list[Column]) -> list[tuple[int, str, str]]:
    """(row index, column id, why) of every cell of ``rows`` that ``columns`` refuse: what was typed, in the
    column's unit, and the range; the row is named as the table numbers it (from 1)."""
    out = []
    for i, row in enumerate(rows or []):
        for c in columns:
            try:
                typed_number(f"row {i + 1}.{c.id}", f"row {i + 1}: {c.label}", (row or {}).get(c.id), c.low, c.high,
                             c.unit)
            except InvalidParameterError as exc:
                out.append((i, c.id, str(exc)))
    return out


def cell_styles(refused: list[tuple[int, str, str]]) -> list[dict]:
    """The DataTable's style_data_conditional marking each refused cell."""
    return [{"if": {"row_index": i, "column_id": c}, "backgroundColor": "#fde8e4", "color": "#9b1c00",
             "fontWeight": "600"} for i, c, _ in refused]


def error_id(box_id: str) -> str:
    """The id of the line under a box that says what is wrong with it."""
    return f"{box_id}-error"


def field_error(element_id: str, text: str | None = None) -> html.Div:
    """The line under a field that says what is wrong with it."""
    return html.Div(text, id=element_id, className="error field-error", role="alert")


def refusal(read, value) -> str:
    """Why ``read`` refuses ``value`` ('' if it accepts it)."""
    try:
        read(value)
    except InvalidParameterError as exc:
        return str(exc)
    return ""


def check(box_id: str, quantity: Quantity, error: str | None = None) -> None:
    """The box's line says at once (on Enter or leaving the box) what is wrong with what was typed, in the
    box's unit; empty once it is right (the page's button refuses the same, by the same rules)."""
    dash.callback(Output(error or error_id(box_id), "children"), Input(box_id, "value"), prevent_initial_call=True)(
        lambda value: refusal(quantity.read, value))


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
