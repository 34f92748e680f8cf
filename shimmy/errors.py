"""One exception root for the package.

Each subclass also inherits the built-in exception it refines, so callers that do
not know about :mod:`shimmy` can still catch ``ValueError`` or ``RuntimeError``.
The service layer maps these classes to HTTP status codes in one place.
"""

from __future__ import annotations


class ShimmyError(Exception):
    """Root of every error raised on purpose by :mod:`shimmy`."""


class InvalidParameterError(ShimmyError, ValueError):
    """An input is missing, non-numeric, non-finite, unknown or out of its range.

    ``field`` names the offending input, ``value`` is what was given and
    ``allowed`` describes what is accepted (a range, or a list of names).
    """

    def __init__(self, field: str, value: object, allowed: str, reason: str | None = None,
                 message: str | None = None):
        self.field = field
        self.value = value
        self.allowed = allowed
        head = reason or "is out of range"
        super().__init__(message or f"{field}={value!r} {head}; allowed: {allowed}")

    def to_dict(self) -> dict:
        return {"error": str(self), "field": self.field, "allowed": self.allowed}


class GeometryError(ShimmyError, ValueError):
    """A device geometry is asked for outside the range where it is defined."""


class ConvergenceError(ShimmyError, RuntimeError):
    """A numerical solver did not converge; the message says which and why."""
