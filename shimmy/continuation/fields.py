"""The systems the engine continues: x' = f(x, p) in one parameter, and in two.

:class:`VectorField` is what equilibrium and periodic branches continue; :class:`TwoParameterField`
what Hopf curves and curves of cycle bifurcations continue, and :meth:`TwoParameterField.at` its
one-parameter slice for the branches they start from. Both take the derivatives analytically and
are vectorised over columns of x.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np


@dataclass(frozen=True)
class VectorField:
    """x' = f(x, p) with analytic derivatives, vectorised over columns.

    ``f(x, p)``: x (n,) or (n, m) -> same shape; ``dfdx(x, p)``: (n, n) or (m, n, n);
    ``dfdp(x, p)``: like f. ``p`` is a scalar (the continuation parameter).
    """

    n: int
    f: Callable[[np.ndarray, float], np.ndarray]
    dfdx: Callable[[np.ndarray, float], np.ndarray]
    dfdp: Callable[[np.ndarray, float], np.ndarray]
    name: str = "system"
    #: Optional ``evaluate(x, p) -> (f, dfdx, dfdp)`` in one pass (a compiled field's fast path);
    #: must agree with the three functions.
    evaluate: Callable[[np.ndarray, float], tuple[np.ndarray, np.ndarray, np.ndarray]] | None = None

    def all_at(self, x: np.ndarray, p: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(f, dfdx, dfdp) at columns x: one call of ``evaluate`` where the field has it."""
        if self.evaluate is not None:
            return self.evaluate(x, p)
        return self.f(x, p), self.dfdx(x, p), self.dfdp(x, p)


@dataclass(frozen=True)
class TwoParameterField:
    """x' = f(x, p1, p2) with analytic first derivatives, vectorised over columns.

    ``f(x, p)``: x (n,) or (n, m), p = (p1, p2) -> like x; ``dfdx(x, p)``: (n, n) or (m, n, n);
    ``dfdp(x, p)``: (2, n) or (2, n, m), the derivatives in p1 and p2 stacked. For Hopf curves
    ``dfdx`` must accept complex x (the first Lyapunov coefficient differentiates it along complex
    directions); ``smooth`` False (e.g. a |v|^(1/2) v term) skips the Lyapunov coefficient and the
    generalised Hopf points.
    """

    n: int
    f: Callable[[np.ndarray, np.ndarray], np.ndarray]
    dfdx: Callable[[np.ndarray, np.ndarray], np.ndarray]
    dfdp: Callable[[np.ndarray, np.ndarray], np.ndarray]
    name: str = "system"
    #: Optional ``evaluate(x, p) -> (f, dfdx, dfdp)`` in one pass (a compiled field's fast path).
    evaluate: Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]] | None = None
    smooth: bool = True
    #: Whether ``dfdx`` takes complex columns (n, m) too, returning (m, n, n): the first Lyapunov coefficient's
    #: eight complex evaluations are then one call (:func:`~shimmy.continuation.first_lyapunov_coefficient`).
    complex_columns: bool = False

    def all_at(self, x: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(f, dfdx, dfdp with both parameters stacked) at columns x."""
        if self.evaluate is not None:
            return self.evaluate(x, p)
        return self.f(x, p), self.dfdx(x, p), self.dfdp(x, p)

    def at(self, p2: float) -> VectorField:
        """The one-parameter field in p1 at fixed p2 (for one-parameter branches)."""
        return SliceInP1(self, float(p2)).field


class SliceInP1:
    """The field in p1 at a p2 that can be moved (the curve problems move it every evaluation)."""

    def __init__(self, system: TwoParameterField, p2: float):
        self.system, self.p2 = system, p2
        self.field = VectorField(system.n, lambda x, p: system.f(x, np.array([p, self.p2])),
                                 lambda x, p: system.dfdx(x, np.array([p, self.p2])),
                                 lambda x, p: system.dfdp(x, np.array([p, self.p2]))[0], system.name,
                                 self._evaluate if system.evaluate is not None else None)

    def _evaluate(self, x: np.ndarray, p1: float):
        f, J, fp = self.system.evaluate(x, np.array([p1, self.p2]))
        return f, J, fp[0]

    def dfdp2(self, x: np.ndarray, p1: float) -> np.ndarray:
        return self.system.dfdp(x, np.array([p1, self.p2]))[1]
