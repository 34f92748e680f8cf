"""Folds of cycles (LPC): A is the Jacobian of the cycle equations in (x, T), singular where the
cycle folds in p1 at fixed p2 (a multiplier at +1 beside the trivial one).

Codimension-2 points on a fold curve: the cusp (CPC: the curve's direction in the parameter plane
reverses), a fold meeting a torus (LPNS: a complex pair crosses the unit circle) or a period
doubling (LPPD: a real multiplier crosses -1).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Callable

import numpy as np

from ..core import CurvePoint
from ..kinds import PointKind
from .defining_system import DefiningSystem

if TYPE_CHECKING:
    from .bordered import CycleCurveProblem


class FoldOfCycles(DefiningSystem):
    kind = PointKind.FOLD_OF_CYCLES
    # with fewer sweeps one of the original gear's fold curves took shorter steps (28 points with 2
    # or 3 sweeps, 42 with 1, 26 with 6)
    refine_sweeps = 6
    reads_phase = True  # A is the Jacobian of the cycle equations, the phase row among them
    crossings = {PointKind.FOLD_TORUS: "complex", PointKind.FOLD_FLIP: "negative"}
    codim2 = (PointKind.CUSP_OF_CYCLES, PointKind.FOLD_TORUS, PointKind.FOLD_FLIP)
    tangent_tests = frozenset({PointKind.CUSP_OF_CYCLES})

    def size(self, n_x: int) -> int:
        return n_x + 1  # the node values and the period

    def global_columns(self, problem: CycleCurveProblem) -> list[int]:
        return [problem.n_x]

    def boundary_entries(self, problem: CycleCurveProblem) -> tuple[list[np.ndarray], list[np.ndarray]]:
        """The period's column, the periodicity rows and the phase row."""
        n, n_x, n_coll = problem.n, problem.n_x, problem.n_coll
        a = np.arange(n)
        idx = problem.mesh.node_index[:, :, None] * n + a[None, None, :]
        return ([np.arange(n_coll), n_coll + a, n_coll + a, np.full(idx.size, n_coll + n)],
                [np.full(n_coll, n_x), a, n_x - n + a, idx.ravel()])

    def boundary_values(self, problem: CycleCurveProblem, u: np.ndarray, F: np.ndarray) -> list[np.ndarray]:
        mesh, cycle = problem.mesh, problem.cycle
        ones = np.ones(problem.n)
        coeff = np.einsum("j,k,kl,jkn->jln", mesh.h, cycle.basis.gauss[1], cycle.basis.L, cycle.reference_derivative)
        return [(-mesh.h[:, None, None] * F).ravel(), ones, -ones, coeff.ravel()]

    def gradient_terms(self, problem: CycleCurveProblem, u: np.ndarray, V: np.ndarray, W: np.ndarray):
        d = np.zeros(problem.size)
        d[:problem.n_x + 1] = V
        return [(d, W[:problem.n_coll])], None

    def transferred_border(self, problem: CycleCurveProblem, nodes: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
        return np.vstack([nodes(problem.C[:problem.n_x]), problem.C[problem.n_x:]])

    def critical(self, mu: np.ndarray, kappa: float) -> list[int]:
        rest = np.arange(1, mu.size)
        return [0, int(rest[np.argmin(np.abs(mu[1:] - 1.0))])]

    def own_monitors(self, problem: CycleCurveProblem, point: CurvePoint, reference: np.ndarray) -> dict:
        cusp = float(_direction(problem, point) @ reference) if reference is not None else 1.0
        return {PointKind.CUSP_OF_CYCLES: cusp}

    def own_test(self, problem: CycleCurveProblem, name: PointKind,
                 reference: np.ndarray) -> Callable[[CurvePoint], float]:
        if name != PointKind.CUSP_OF_CYCLES:
            raise KeyError(name)
        return lambda q: float(_direction(problem, q) @ reference)


def _direction(problem: CycleCurveProblem, point: CurvePoint) -> np.ndarray:
    """The point's tangent in (p1, p2), scaled (the cusp is where it reverses)."""
    i = problem.n_x + 1
    return point.tangent[i:i + 2] * np.sqrt(problem.weights[i:i + 2])
