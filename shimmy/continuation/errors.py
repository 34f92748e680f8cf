"""The engine's own exception root, so that it depends on nothing outside numpy and scipy.

Each class also inherits the built-in it refines. A program built on the engine may
derive its own errors from these (the gear package does), so one ``except`` on the base
catches both.
"""

from __future__ import annotations


class ContinuationError(Exception):
    """Root of every error the continuation engine raises on purpose."""


class InvalidInputError(ContinuationError, ValueError):
    """An option or start value is missing, non-finite or out of its range.

    ``field`` names the input, ``value`` is what was given and ``allowed`` what is accepted.
    """

    def __init__(self, field: str, value: object, allowed: str, reason: str | None = None,
                 message: str | None = None):
        self.field = field
        self.value = value
        self.allowed = allowed
        head = reason or "is out of range"
        super().__init__(message or f"{field}={value!r} {head}; allowed: {allowed}")

    def __reduce__(self):
        # rebuilt from its fields and message: a refusal raised in a process pool's worker reaches the
        # caller as itself (Exception's default pickling passes only the message to __init__, whose
        # unpickling failed and broke the pool: BrokenProcessPool instead of the field's error)
        return self.__class__, (self.field, self.value, self.allowed, None, str(self))

    def to_dict(self) -> dict:
        return {"error": str(self), "field": self.field, "allowed": self.allowed}


class ConvergenceError(ContinuationError, RuntimeError):
    """A Newton corrector or a start did not converge; the message says which and why."""
