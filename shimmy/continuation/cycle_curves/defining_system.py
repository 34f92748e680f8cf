"""What differs between the curve types: the interface of a defining system.

A curve of cycle bifurcations is continued as a minimally augmented system
(``CycleCurveProblem``, :mod:`.bordered`): the cycle's equations and the test functions G = 0 of the
bordered matrix [[A, B], [C^T, 0]], A a linearisation of the cycle that is singular on the curve.
The bordered machinery is shared; a ``DefiningSystem`` holds what is not: A's boundary rows
and its size, the dimension of its kernel, the gradient of G, the multipliers the condition holds
at and the codimension-2 points the curve reports. One subclass per curve type, as MATCONT has one
curve type per defining system: :mod:`.fold_of_cycles`, :mod:`.period_doubling`, :mod:`.torus`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Callable

import numpy as np

from ..condensed_lu import ChainLayout, collocation_layout
from ..core import CurvePoint
from ..kinds import PointKind

if TYPE_CHECKING:
    from .bordered import CycleCurveProblem


class DefiningSystem:
    """The defining system of one curve type (a stateless description, shared by all its curves)."""

    kind: PointKind
    #: dimension of A's kernel on the curve: the number of border vectors and of test functions
    kernel = 1
    #: whether kappa = cos(theta) is an unknown of the curve (after p2)
    has_kappa = False
    #: periods A spans: copies of the cycle's collocation blocks in it
    periods = 1
    #: whether A holds the cycle's phase row (which moves with the reference when a point is accepted)
    reads_phase = False
    #: refinement sweeps of the test matrix's solves on the last factors before it is factored
    #: afresh (see ``FRESH_SWEEPS`` in :mod:`.bordered`)
    refine_sweeps = 6
    #: codimension-2 points where a further multiplier crosses the unit circle, and which kind of
    #: multiplier crosses there ("positive", "negative" real, "complex")
    crossings: dict[PointKind, str] = {}
    #: every codimension-2 point the curve reports
    codim2: tuple[PointKind, ...] = ()
    #: the codimension-2 tests that read the curve's tangent (their trial points need one)
    tangent_tests: frozenset[PointKind] = frozenset()

    def size(self, n_x: int) -> int:
        """Rows (and columns) of A, for a cycle of n_x node values."""
        raise NotImplementedError

    def global_columns(self, problem: CycleCurveProblem) -> list[int]:
        """A's columns that are not node values (the fold's period)."""
        return []

    def test_layout(self, problem: CycleCurveProblem) -> ChainLayout:
        """Roles of the rows and columns of [[A, B], [C^T, 0]] for its condensed LU (one period: A's
        boundary rows and global columns are globals beside the borders)."""
        n_coll, n, m, k = problem.n_coll, problem.n, problem.m, problem.k
        mesh = problem.mesh
        borders_c, borders_r = m + np.arange(k), m + np.arange(k)
        return collocation_layout(mesh.ntst, mesh.ncol, n, m + k, [(0, 0)], [],
                                  np.concatenate([self.global_columns(problem), borders_c]),
                                  np.concatenate([n_coll + np.arange(m - n_coll), borders_r]))

    def boundary_entries(self, problem: CycleCurveProblem) -> tuple[list[np.ndarray], list[np.ndarray]]:
        """Rows and columns of A's entries beside its collocation blocks, in the order of
        :meth:`boundary_values`."""
        raise NotImplementedError

    def boundary_values(self, problem: CycleCurveProblem, u: np.ndarray, F: np.ndarray) -> list[np.ndarray]:
        """The values of those entries at u (F: the field at the collocation points)."""
        raise NotImplementedError

    def gradient_terms(self, problem: CycleCurveProblem, u: np.ndarray, V: np.ndarray,
                       W: np.ndarray) -> tuple[list[tuple[np.ndarray, np.ndarray]], np.ndarray | None]:
        """d g / du = -W^T A_u V for the right and left vectors V, W of one entry g of G, as the
        (direction, w) pairs whose second derivatives (``problem.second_many``) it subtracts and a row
        it adds (A's entries beside the collocation blocks that depend on u), or None."""
        raise NotImplementedError

    def transferred_border(self, problem: CycleCurveProblem, nodes: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
        """The border C on a new mesh, ``nodes`` interpolating node values of one period onto it."""
        raise NotImplementedError

    def critical(self, mu: np.ndarray, kappa: float) -> list[int]:
        """Indices of the trivial multiplier (0) and of those the curve's condition holds at."""
        raise NotImplementedError

    def own_monitors(self, problem: CycleCurveProblem, point: CurvePoint, reference: np.ndarray) -> dict:
        """The test functions of the codimension-2 points that are not crossings of the unit circle,
        at ``point`` (``reference``: the curve's direction in the parameter plane at the last point)."""
        return {}

    def own_test(self, problem: CycleCurveProblem, name: PointKind,
                 reference: np.ndarray) -> Callable[[CurvePoint], float]:
        """The test function of one of those points along the curve, to locate it (by default the
        unknown minus the value of :meth:`own_level`)."""
        level = self.own_level(problem, name)
        if level is None:
            raise KeyError(name)
        index, value = level
        return lambda q: float(q.u[index]) - value

    def own_level(self, problem: CycleCurveProblem, name: PointKind) -> tuple[int, float] | None:
        """(index, value) if that test function is an unknown of the curve minus a value (the point
        is then one Newton solve with the unknown held there, not a search), else None."""
        return None
