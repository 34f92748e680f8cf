"""A request field: its kind, default, range, unit and choices, how a value of it is checked (each refusal an
:class:`~shimmy.errors.InvalidParameterError` naming the field) and its JSON Schema. The request schemas
(:mod:`shimmy.service.schemas`) are made of these."""

from __future__ import annotations

import difflib
from dataclasses import dataclass
from typing import Any, Mapping

from ..errors import InvalidParameterError
from ..model.parameters import PARAMETER_SPECS, check_number, unknown_name_error


def field_key(name: Any) -> str:
    """A body key as a field name: quoted where it is empty or has surrounding blanks."""
    name = str(name)
    return name if name and name == name.strip() else repr(name)


def huge(value: Any) -> Any:
    """An integer beyond float range as inf (refused as not finite, by name) instead of an OverflowError."""
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) > 1e308:
        return float("inf") if value > 0 else float("-inf")
    return value


@dataclass(frozen=True)
class Field:
    name: str
    kind: str  # number | integer | string | boolean | object | numbers | strings (arrays) | table (rows of numbers)
    #   | list (items checked by the schema's own rule; ``item`` says what one is, ``items`` is its JSON Schema)
    description: str
    required: bool = False
    default: Any = None
    low: float | None = None
    high: float | None = None
    unit: str = ""
    choices: tuple[str, ...] | None = None
    item: str = ""
    items: Any = None
    #: a number must be a whole multiple of this (in the field's unit), not rounded to one
    multiple: float | None = None

    @property
    def allowed(self) -> str:
        if self.choices:
            return "one of " + ", ".join(self.choices)
        if self.kind in ("number", "integer"):
            kind = "an integer" if self.kind == "integer" else "a number"
            step = f", a multiple of {self.multiple:g} {self.unit}".rstrip() if self.multiple else ""
            return f"{kind} in [{self.low:g}, {self.high:g}] {self.unit}".rstrip() + step
        if self.kind == "boolean":
            return "true or false"
        if self.kind == "object":
            return self.item or "an object {parameter name: number}; names and ranges from GET /api/v1/parameters"
        if self.kind == "numbers":
            return f"a list of 1 to {self.high:g} numbers"
        if self.kind == "strings":
            return f"a non-empty list of {', '.join(self.choices or ())}"
        if self.kind == "table":
            return f"a list of 2 to {self.high:g} rows [t (s), V (m/s), Fz (N)]"
        if self.kind == "list":
            return f"a list of {self.low:g} to {self.high:g} {self.item}"
        return "a string"

    def check(self, value: Any) -> Any:
        if self.kind in ("number", "integer"):
            if isinstance(value, str):  # JSON numbers only: "30" is a type error in a body
                raise InvalidParameterError(self.name, value, self.allowed, "is not a number")
            number = check_number(self.name, huge(value), self.low, self.high, self.unit, self.kind == "integer")
            if self.multiple:
                steps = number / self.multiple
                if abs(steps - round(steps)) > 1e-9 * max(1.0, abs(steps)):
                    raise InvalidParameterError(self.name, value, self.allowed,
                                                f"is not a multiple of {self.multiple:g} {self.unit}".rstrip())
            return int(number) if self.kind == "integer" else number
        if self.kind == "boolean":
            if not isinstance(value, bool):
                raise InvalidParameterError(self.name, value, self.allowed, "is not a boolean")
            return value
        if self.kind == "string":
            if not isinstance(value, str):
                raise InvalidParameterError(self.name, value, self.allowed, "is not a string")
            if self.choices and value not in self.choices:
                raise unknown_name_error(value, self.choices, self.name)
            return value
        if self.kind == "numbers":
            if not isinstance(value, list):
                raise InvalidParameterError(self.name, value, self.allowed, "is not a list")
            if not 1 <= len(value) <= self.high:
                raise InvalidParameterError(self.name, f"{len(value)} items", self.allowed,
                                            message=f"{self.name} has {len(value)} items; allowed: {self.allowed}")
            out = []
            for k, v in enumerate(value):
                if not isinstance(v, (int, float)) or isinstance(v, bool):
                    raise InvalidParameterError(f"{self.name}[{k}]", v, "a number", "is not a number")
                out.append(check_number(f"{self.name}[{k}]", huge(v), -1e300, 1e300))  # ranges: per parameter
            return out
        if self.kind == "strings":
            if not isinstance(value, list):
                raise InvalidParameterError(self.name, value, self.allowed, "is not a list")
            if not value:
                raise InvalidParameterError(self.name, value, self.allowed, "is empty")
            choices = list(self.choices or ())
            for k, v in enumerate(value):
                if not isinstance(v, str):
                    raise InvalidParameterError(f"{self.name}[{k}]", v, "one of " + ", ".join(choices),
                                                "is not a string")
                if v not in choices:
                    close = difflib.get_close_matches(v, choices, n=3)
                    hint = f" (did you mean {', '.join(close)}?)" if close else ""
                    allowed = "one of " + ", ".join(choices)
                    raise InvalidParameterError(f"{self.name}[{k}]", v, allowed,
                                                message=f"{self.name}[{k}]={v!r} is not a known name{hint}; "
                                                        f"allowed: {allowed}")
            return list(dict.fromkeys(value))
        if self.kind == "list":  # the items are checked by the schema's rule, by position
            if not isinstance(value, list):
                raise InvalidParameterError(self.name, value, self.allowed, "is not a list")
            if not self.low <= len(value) <= self.high:
                raise InvalidParameterError(self.name, f"{len(value)} items", self.allowed,
                                            message=f"{self.name} has {len(value)} items; allowed: {self.allowed}")
            return list(value)
        if self.kind == "table":  # the rows themselves are checked by the analysis's profile check, by row
            if not isinstance(value, list):
                raise InvalidParameterError(self.name, value, self.allowed, "is not a list of rows")
            if not 2 <= len(value) <= self.high:
                raise InvalidParameterError(self.name, f"{len(value)} rows", self.allowed,
                                            message=f"{self.name} has {len(value)} rows; allowed: {self.allowed}")
            return [list(row) if isinstance(row, list) else row for row in value]
        if not isinstance(value, Mapping):
            raise InvalidParameterError(self.name, value, self.allowed, "is not an object")
        return dict(value)

    def openapi(self) -> dict[str, Any]:
        """The field's JSON Schema; an optional field may also be null (the server takes it as absent)."""
        out = self._openapi()
        if not self.required:
            out["type"] = [out["type"], "null"]
            if "enum" in out:
                out["enum"] = [*out["enum"], None]
        return out

    def _openapi(self) -> dict[str, Any]:
        out: dict[str, Any] = {"type": self.kind, "description": self.description + (f" ({self.unit})" if self.unit
                                                                                      else "")}
        if self.low is not None:
            out["minimum"], out["maximum"] = self.low, self.high
        if self.choices:
            out["enum"] = list(self.choices)
        if self.default is not None:
            out["default"] = self.default
        if self.kind == "object":  # exactly the parameter names the server takes, each with its range
            out["additionalProperties"] = False
            out["properties"] = {
                name: {"type": "integer" if spec.integer else "number", "minimum": spec.low, "maximum": spec.high,
                       "description": spec.description + (f" ({spec.unit})" if spec.unit else "")}
                for name, spec in PARAMETER_SPECS.items()}
        if self.kind == "table":
            out.update(type="array", minItems=2, maxItems=int(self.high),
                       items={"type": "array", "items": {"type": "number"}, "minItems": 3, "maxItems": 3})
            out.pop("minimum", None)
            out.pop("maximum", None)
        if self.kind == "list":
            out.update(type="array", minItems=int(self.low), maxItems=int(self.high), items=self.items or {})
            out.pop("minimum", None)
            out.pop("maximum", None)
        if self.kind in ("numbers", "strings"):
            out["type"] = "array"
            out.pop("minimum", None)
            out.pop("maximum", None)
            out.pop("enum", None)  # the choices are the items' (an enum here would list arrays)
            out["items"] = {"type": "number"} if self.kind == "numbers" else {"type": "string",
                                                                              "enum": list(self.choices or ())}
            out["minItems"] = 1
            if self.kind == "numbers":
                out["maxItems"] = int(self.high)
        return out
