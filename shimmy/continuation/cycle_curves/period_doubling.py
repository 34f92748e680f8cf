"""Period doublings (PD): A is the linearised collocation in x with the anti-periodic condition
v(0) + v(1) = 0, singular where a multiplier is -1.

Codimension-2 points on a period-doubling curve: a fold meeting it (LPPD: a real multiplier
crosses +1), a torus (PDNS: a complex pair crosses the unit circle) and the 1:2 resonance (R2: a
second multiplier crosses -1).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Callable

import numpy as np

from ..kinds import PointKind
from .defining_system import DefiningSystem

if TYPE_CHECKING:
    from .bordered import CycleCurveProblem


class PeriodDoubling(DefiningSystem):
    kind = PointKind.PERIOD_DOUBLING
    crossings = {PointKind.FOLD_FLIP: "positive", PointKind.FLIP_TORUS: "complex",
                 PointKind.RESONANCE_1_2: "negative"}
    codim2 = (PointKind.FOLD_FLIP, PointKind.FLIP_TORUS, PointKind.RESONANCE_1_2)

    def size(self, n_x: int) -> int:
        return n_x

    def boundary_entries(self, problem: CycleCurveProblem) -> tuple[list[np.ndarray], list[np.ndarray]]:
        """The anti-periodic rows v(0) + v(1)."""
        n, n_x, n_coll = problem.n, problem.n_x, problem.n_coll
        a = np.arange(n)
        return [n_coll + a, n_coll + a], [a, n_x - n + a]

    def boundary_values(self, problem: CycleCurveProblem, u: np.ndarray, F: np.ndarray) -> list[np.ndarray]:
        ones = np.ones(problem.n)
        return [ones, ones]

    def gradient_terms(self, problem: CycleCurveProblem, u: np.ndarray, V: np.ndarray, W: np.ndarray):
        d = np.zeros(problem.size)
        d[:problem.n_x] = V
        return [(d, W[:problem.n_coll])], None

    def transferred_border(self, problem: CycleCurveProblem, nodes: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
        return nodes(problem.C)

    def critical(self, mu: np.ndarray, kappa: float) -> list[int]:
        rest = np.arange(1, mu.size)
        return [0, int(rest[np.argmin(np.abs(mu[1:] + 1.0))])]
