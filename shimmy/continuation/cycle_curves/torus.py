"""Neimark-Sacker / torus points (NS): A is the linearised collocation on two periods with
v(0) - 2 kappa v(1) + v(2) = 0, singular, with a two-dimensional kernel, where exp(+-i theta),
kappa = cos theta, are multipliers. kappa is an unknown of the curve; the bordered matrix has two
border vectors, and two entries of the 2x2 G are its test functions (chosen at the start as the
best-conditioned pair).

Codimension-2 points on a torus curve: the strong resonances R1 (kappa = 1), R2 (kappa = -1), R3
(kappa = -1/2), R4 (kappa = 0), and a fold (LPNS) or a period doubling (PDNS) meeting it (a real
multiplier crosses +1 / -1).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Callable

import numpy as np

from ..condensed_lu import ChainLayout, collocation_layout
from ..core import CurvePoint
from ..kinds import PointKind
from .defining_system import DefiningSystem

if TYPE_CHECKING:
    from .bordered import CycleCurveProblem

#: kappa = cos(theta) at the strong resonances 1:k
RESONANCES = {PointKind.RESONANCE_1_1: 1.0, PointKind.RESONANCE_1_4: 0.0, PointKind.RESONANCE_1_3: -0.5,
              PointKind.RESONANCE_1_2: -1.0}


class Torus(DefiningSystem):
    kind = PointKind.TORUS
    kernel = 2
    has_kappa = True
    periods = 2
    # two periods and two right-hand sides: fastest with 2 (the NES gear's curves 5.9 -> 5.4 s)
    refine_sweeps = 2
    crossings = {PointKind.FOLD_TORUS: "positive", PointKind.FLIP_TORUS: "negative"}
    codim2 = (PointKind.RESONANCE_1_1, PointKind.RESONANCE_1_2, PointKind.RESONANCE_1_3, PointKind.RESONANCE_1_4,
              PointKind.FOLD_TORUS, PointKind.FLIP_TORUS)

    def size(self, n_x: int) -> int:
        return 2 * n_x  # the node values of two periods

    def test_layout(self, problem: CycleCurveProblem) -> ChainLayout:
        """The two periods are two copies of the mesh joined by the continuity rows; the boundary
        condition rows are globals beside the borders."""
        n_x, n_coll, n, m, k = problem.n_x, problem.n_coll, problem.n, problem.m, problem.k
        mesh = problem.mesh
        borders_c, borders_r = m + np.arange(k), m + np.arange(k)
        return collocation_layout(mesh.ntst, mesh.ncol, n, m + k, [(0, 0), (n_coll, n_x)],
                                  [2 * n_coll + np.arange(n)], borders_c,
                                  np.concatenate([2 * n_coll + n + np.arange(n), borders_r]))

    def boundary_entries(self, problem: CycleCurveProblem) -> tuple[list[np.ndarray], list[np.ndarray]]:
        """The continuity rows v0(1) = v1(0) and the rows of v0(0) - 2 kappa v0(1) + v1(1)."""
        n, n_x, n_coll = problem.n, problem.n_x, problem.n_coll
        a = np.arange(n)
        cont, bc = 2 * n_coll + a, 2 * n_coll + n + a
        return [cont, cont, bc, bc, bc], [n_x - n + a, n_x + a, a, n_x - n + a, 2 * n_x - n + a]

    def boundary_values(self, problem: CycleCurveProblem, u: np.ndarray, F: np.ndarray) -> list[np.ndarray]:
        ones = np.ones(problem.n)
        return [-ones, ones, ones, np.full(problem.n, -2.0 * problem.kappa(u)), ones]

    def gradient_terms(self, problem: CycleCurveProblem, u: np.ndarray, V: np.ndarray, W: np.ndarray):
        n, n_x, n_coll = problem.n, problem.n_x, problem.n_coll
        pairs = []
        for copy in range(2):
            d = np.zeros(problem.size)
            d[:n_x] = V[copy * n_x:(copy + 1) * n_x]
            pairs.append((d, W[copy * n_coll:(copy + 1) * n_coll]))
        extra = np.zeros(problem.size)
        w_bc = W[2 * n_coll + n:]  # rows of V0(0) - 2 kappa V0(1) + V1(1)
        extra[n_x + 3] = 2.0 * w_bc @ V[n_x - n:n_x]  # -w^T (dA/dkappa) v, dA/dkappa = -2 at V0(1)
        return pairs, extra

    def transferred_border(self, problem: CycleCurveProblem, nodes: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
        return np.vstack([nodes(problem.C[:problem.n_x]), nodes(problem.C[problem.n_x:])])

    def critical(self, mu: np.ndarray, kappa: float) -> list[int]:
        rest = np.arange(1, mu.size)
        target = kappa + 1j * math.sqrt(max(0.0, 1.0 - kappa ** 2))
        d = np.minimum(np.abs(mu[1:] - target), np.abs(mu[1:] - np.conj(target)))
        order = rest[np.argsort(d, kind="stable")]
        return [0, int(order[0]), int(order[1])]

    def own_monitors(self, problem: CycleCurveProblem, point: CurvePoint, reference: np.ndarray) -> dict:
        kappa = problem.kappa(point.u)
        return {name: kappa - value for name, value in RESONANCES.items()}

    def own_level(self, problem: CycleCurveProblem, name: PointKind) -> tuple[int, float] | None:
        return problem.kappa_index, RESONANCES[name]
