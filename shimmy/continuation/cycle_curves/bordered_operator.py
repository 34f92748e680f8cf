"""The bordered test matrix [[A, B], [C^T, 0]] as an operator, applied without assembling it.

Every residual of a curve of cycle bifurcations solves the bordered test matrix at the iterate, by
iterative refinement on the factors of a nearby one (:mod:`.bordered`): a refinement sweep needs
only the products M z and M^T z. A is ``periods`` copies of the cycle's collocation blocks (dense
(ncol n) x ((ncol + 1) n) blocks, one per mesh interval, neighbours sharing a node's n columns)
plus a few boundary entries (periodicity or continuity rows, the fold's period column and phase
row), so both products are a batched product of the blocks and a short scatter of the boundary
entries. The sparse matrix is assembled only for SuperLU (``BorderedOperator.sparse``).
Both products equal the assembled matrix's to rounding (the sums are taken in another order).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Callable

import numpy as np
import scipy.sparse as sp

if TYPE_CHECKING:
    from .bordered import CycleCurveProblem


class BorderedOperator:
    """M = [[A, B], [C^T, 0]] of ``problem`` at one point: ``matvec(z)``, ``rmatvec(z)`` (M^T z),
    z of shape (m + k,) or (m + k, r); ``sparse()`` the assembled CSC matrix (built on first use)."""

    def __init__(self, problem: CycleCurveProblem, blocks: np.ndarray, rows: np.ndarray, cols: np.ndarray,
                 values: np.ndarray, assemble: Callable[[], sp.csc_matrix]):
        mesh = problem.mesh
        self.N, self.m_n, self.n = mesh.ntst, mesh.ncol * problem.n, problem.n
        self.periods = problem.defining.periods
        self.n_coll, self.n_x, self.m, self.k = problem.n_coll, problem.n_x, problem.m, problem.k
        self.node_index = mesh.node_index  # (N, ncol + 1): the nodes of each interval
        self.blocks = blocks.reshape(self.N, self.m_n, self.m_n + self.n)  # (N, ncol n, (ncol + 1) n)
        self.rows, self.cols, self.values = rows, cols, values  # the boundary entries of A
        self.B, self.C = problem.B, problem.C
        self._assemble = assemble
        self._sparse: sp.csc_matrix | None = None

    def sparse(self) -> sp.csc_matrix:
        if self._sparse is None:
            self._sparse = self._assemble()
        return self._sparse

    def _windows(self, x: np.ndarray) -> np.ndarray:
        """The node values of each interval, (N, (ncol + 1) n, r), from one period's x (n_x, r)."""
        return x.reshape(-1, self.n, x.shape[1])[self.node_index].reshape(self.N, self.m_n + self.n, -1)

    def matvec(self, z: np.ndarray) -> np.ndarray:
        flat = z.ndim == 1
        Z = z.reshape(z.shape[0], -1)
        m, k, n_x, n_coll = self.m, self.k, self.n_x, self.n_coll
        out = np.empty_like(Z)
        top = out[:m]
        top[:] = self.B @ Z[m:]
        for c in range(self.periods):
            x = Z[c * n_x:(c + 1) * n_x]
            top[c * n_coll:(c + 1) * n_coll] += (self.blocks @ self._windows(x)).reshape(n_coll, -1)
        for r in range(Z.shape[1]):
            top[:, r] += np.bincount(self.rows, weights=self.values * Z[self.cols, r], minlength=m)
        out[m:] = self.C.T @ Z[:m]
        return out.ravel() if flat else out

    def rmatvec(self, z: np.ndarray) -> np.ndarray:
        flat = z.ndim == 1
        Z = z.reshape(z.shape[0], -1)
        m, n_x, n_coll, N, m_n, n = self.m, self.n_x, self.n_coll, self.N, self.m_n, self.n
        out = np.empty_like(Z)
        top = out[:m]
        top[:] = self.C @ Z[m:]
        for c in range(self.periods):
            y = Z[c * n_coll:(c + 1) * n_coll].reshape(N, m_n, -1)
            parts = np.matmul(self.blocks.transpose(0, 2, 1), y)  # (N, (ncol + 1) n, r)
            x = top[c * n_x:(c + 1) * n_x]
            # the transpose of _windows' gather, as two slices (np.add.at on node_index is slower): each
            # interval's nodes but its last, then its last node (ncol (j + 1)), shared with the next interval
            x[:N * m_n] += parts[:, :m_n].reshape(N * m_n, -1)
            x[m_n:].reshape(-1, n, Z.shape[1])[::m_n // n][:N] += parts[:, m_n:]
        for r in range(Z.shape[1]):
            top[:, r] += np.bincount(self.cols, weights=self.values * Z[self.rows, r], minlength=m)
        out[m:] = self.B.T @ Z[:m]
        return out.ravel() if flat else out
