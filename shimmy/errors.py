"""One exception root for the package.

Each subclass also inherits the built-in exception it refines, so callers that do
not know about :mod:`shimmy` can still catch ``ValueError`` or ``RuntimeError``.
The service layer maps these classes to HTTP status codes in one place.

The generic continuation engine (:mod:`shimmy.continuation`) has its own root,
:class:`~shimmy.continuation.ContinuationError`; the classes here that have an engine
counterpart derive from it too, so catching the engine's class catches both.
"""

from __future__ import annotations

from .continuation import errors as engine


class ShimmyError(Exception):
    """Root of every error raised on purpose by :mod:`shimmy`."""


class InvalidParameterError(ShimmyError, engine.InvalidInputError):
    """An input is missing, non-numeric, non-finite, unknown or out of its range.

    ``field`` names the offending input, ``value`` is what was given and
    ``allowed`` describes what is accepted (a range, or a list of names).
    """


class GeometryError(ShimmyError, ValueError):
    """A device geometry is asked for outside the range where it is defined."""


class ConvergenceError(ShimmyError, engine.ConvergenceError):
    """A numerical solver did not converge; the message says which and why."""


#: What a caller catches to report every error raised on purpose, the engine's included.
EXPECTED_ERRORS: tuple[type[Exception], ...] = (ShimmyError, engine.ContinuationError)
