"""Periodic orbits by orthogonal collocation, and their Floquet multipliers.

The orbit x(t), t in [0, T], is written in the scaled time tau = t / T in [0, 1], where
it solves dx/dtau = T f(x, p). The interval [0, 1] is cut into ``ntst`` mesh intervals
(lengths h_j, uniform or adapted); on each, x is a polynomial of degree ``ncol``
represented by its values at ncol + 1 equally spaced nodes, the end nodes shared with
the neighbours (continuity). The equations (as in AUTO, Doedel et al.):

* collocation at the ``ncol`` Gauss-Legendre points of every interval:
  sum_l D_kl x_jl - h_j T f(sum_l L_kl x_jl, p) = 0;
* periodicity x(0) = x(1);
* the integral phase condition int_0^1 <x(tau) - x_ref(tau), x_ref'(tau)> dtau = 0
  against the previous orbit on the branch (Gauss quadrature on the mesh).

Unknowns u = [x at the ntst*ncol + 1 nodes (row-major, n per node), T, p]: the system
has one equation fewer than unknowns, as continuation needs. The Jacobian is assembled
sparse from the vector field's analytic Jacobian at all collocation points at once.
At Gauss points the method is superconvergent at the mesh points (error O(h^(2 ncol))),
O(h^(ncol+1)) elsewhere, for smooth vector fields.

Floquet multipliers come from the same collocation blocks (the linearised collocation
equations of interval j map x at its first node to x at its last node: the transfer
matrix P_j); the monodromy matrix is P_(ntst-1) ... P_0. The multiplier closest to 1
is the trivial one (the orbit's phase); its distance from 1 is reported as an accuracy
check.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property, lru_cache

import numpy as np
import scipy.sparse as sp
from numba import njit

from .condensed_lu import ChainLayout, CondensedLU, collocation_layout, monodromy
from .core import condensed_factors
from .fields import VectorField
from .scalar import minimum_in


@dataclass(frozen=True)
class Mesh:
    """Mesh points 0 = tau_0 < ... < tau_ntst = 1 and the collocation degree."""

    points: np.ndarray
    ncol: int

    @classmethod
    def uniform(cls, ntst: int, ncol: int = 4) -> "Mesh":
        if ntst < 2 or not 1 <= ncol <= 7:
            raise ValueError(f"mesh needs ntst >= 2 and 1 <= ncol <= 7, got {ntst}, {ncol}")
        return cls(np.linspace(0.0, 1.0, ntst + 1), ncol)

    @property
    def ntst(self) -> int:
        return self.points.size - 1

    @cached_property
    def h(self) -> np.ndarray:
        return np.diff(self.points)

    @property
    def n_nodes(self) -> int:
        return self.ntst * self.ncol + 1

    @cached_property
    def node_times(self) -> np.ndarray:
        s = np.arange(self.ncol) / self.ncol
        t = (self.points[:-1, None] + self.h[:, None] * s[None, :]).ravel()
        return np.append(t, 1.0)

    @cached_property
    def node_index(self) -> np.ndarray:
        """(ntst, ncol + 1) index of the nodes of every interval."""
        return np.arange(self.ntst)[:, None] * self.ncol + np.arange(self.ncol + 1)[None, :]

    def evaluate(self, X: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """x at arbitrary tau in [0, 1] (k, n) from node values X on this mesh (its polynomials)."""
        tau = np.clip(np.asarray(tau, float), 0.0, 1.0)
        j = np.clip(np.searchsorted(self.points, tau, side="right") - 1, 0, self.ntst - 1)
        s = (tau - self.points[j]) / self.h[j]
        E = basis(self.ncol).values(s)  # (k, m+1)
        U = X[self.node_index[j]]  # (k, m+1, n)
        return np.einsum("kl,kln->kn", E, U)

    @cached_property
    def node_weights(self) -> np.ndarray:
        """Trapezoidal weights of the nodes for integrals over tau in [0, 1]."""
        w = np.zeros(self.n_nodes)
        seg = np.repeat(self.h / self.ncol, self.ncol)
        w[:-1] += 0.5 * seg
        w[1:] += 0.5 * seg
        return w


@dataclass(frozen=True)
class _Basis:
    """Lagrange basis on ncol + 1 equally spaced nodes in [0, 1]."""

    ncol: int

    @cached_property
    def coefficients(self) -> np.ndarray:
        s = np.arange(self.ncol + 1) / self.ncol
        return np.linalg.inv(np.vander(s, increasing=True))  # column l: monomial coefficients of ell_l

    def values(self, s: np.ndarray) -> np.ndarray:
        return np.vander(np.asarray(s, float), self.ncol + 1, increasing=True) @ self.coefficients

    def derivatives(self, s: np.ndarray) -> np.ndarray:
        s = np.asarray(s, float)
        powers = np.arange(self.ncol + 1)
        V = np.where(powers > 0, powers * s[:, None] ** np.maximum(powers - 1, 0), 0.0)
        return V @ self.coefficients

    @cached_property
    def gauss(self) -> tuple[np.ndarray, np.ndarray]:
        z, w = np.polynomial.legendre.leggauss(self.ncol)
        return 0.5 * (z + 1.0), 0.5 * w

    @cached_property
    def L(self) -> np.ndarray:
        return self.values(self.gauss[0])

    @cached_property
    def D(self) -> np.ndarray:
        return self.derivatives(self.gauss[0])


_BASES: dict[int, _Basis] = {}


def basis(ncol: int) -> _Basis:
    if ncol not in _BASES:
        _BASES[ncol] = _Basis(ncol)
    return _BASES[ncol]


@njit(cache=True)
def _blocks(J, hT, D, L):
    """out[j, k, a, l, b] = D[k, l] delta_ab - hT[j] L[k, l] J[j, k, a, b]: d(collocation)/d(nodes)."""
    N, m, n, _ = J.shape
    out = np.zeros((N, m, n, m + 1, n))
    for j in range(N):
        for k in range(m):
            for a in range(n):
                for l_ in range(m + 1):
                    c = hT[j] * L[k, l_]
                    for b in range(n):
                        out[j, k, a, l_, b] = -c * J[j, k, a, b]
                    out[j, k, a, l_, a] += D[k, l_]
    return out


@dataclass(frozen=True)
class _Pattern:
    """What the Jacobian's structure depends on: ntst, ncol and n only (not the mesh points)."""

    rows: np.ndarray  # collocation blocks' rows (j, k, a) and columns (node(j, l), b)
    cols: np.ndarray
    slot: np.ndarray  # CSR slot of every entry in the order jacobian() produces them
    nnz: int
    indices: np.ndarray
    indptr: np.ndarray
    chain_layout: ChainLayout


@lru_cache(maxsize=32)
def _pattern(N: int, m: int, n: int) -> _Pattern:
    """The fixed CSR structure of the Jacobian of a mesh of N intervals of degree m for n states (built
    once per shape: remeshing keeps it) and the chain layout of its bordered matrix."""
    j, k, a, node, b = np.meshgrid(np.arange(N), np.arange(m), np.arange(n), np.arange(m + 1), np.arange(n),
                                   indexing="ij")
    block_rows = ((j * m + k) * n + a).ravel()
    block_cols = ((j * m + node) * n + b).ravel()
    n_coll, n_x = N * m * n, (N * m + 1) * n
    idx = (np.arange(N)[:, None] * m + np.arange(m + 1)[None, :])[:, :, None] * n + np.arange(n)[None, None, :]
    rows = np.concatenate([block_rows, np.arange(n_coll), np.arange(n_coll), n_coll + np.arange(n),
                           n_coll + np.arange(n), np.full(idx.size, n_coll + n)])
    cols = np.concatenate([block_cols, np.full(n_coll, n_x), np.full(n_coll, n_x + 1),
                           np.arange(n), n_x - n + np.arange(n), idx.ravel()])
    key = rows.astype(np.int64) * (n_x + 2) + cols
    unique, slot = np.unique(key, return_inverse=True)
    counts = np.bincount(unique // (n_x + 2), minlength=n_coll + n + 1)
    indptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int32)
    layout = collocation_layout(N, m, n, n_x + 2, [(0, 0)], [], np.array([n_x, n_x + 1]),
                                n_coll + np.arange(n + 2))
    indices = (unique % (n_x + 2)).astype(np.int32)
    for array in (block_rows, block_cols, slot, indptr, indices):
        array.flags.writeable = False
    return _Pattern(block_rows, block_cols, slot, unique.size, indices, indptr, layout)


class PeriodicProblem:
    """The collocation equations of one mesh as a continuation curve problem in (x, T, p)."""

    def __init__(self, system: VectorField, mesh: Mesh, scale: np.ndarray, T_scale: float, p_scale: float):
        self.system, self.mesh = system, mesh
        self.n = system.n
        self.basis = basis(mesh.ncol)
        self.scale = np.asarray(scale, float)
        self.T_scale, self.p_scale = float(T_scale), float(p_scale)
        n, m, N = self.n, mesh.ncol, mesh.ntst
        self.n_x = mesh.n_nodes * n
        w_nodes = mesh.node_weights[:, None] / self.scale[None, :] ** 2
        self.weights = np.concatenate([w_nodes.ravel(), [1.0 / self.T_scale ** 2, 1.0 / self.p_scale ** 2]])
        self._rows_memo: np.ndarray | None = None  # periodicity and phase rows of the current reference
        self.reference_derivative = np.zeros((N, m, n))
        self.reference_values = np.zeros((N, m, n))
        self.n_equations = N * m * n + n + 1
        self._blocks_memo: tuple[bytes, tuple] | None = None
        self._factors_memo: tuple[bytes, CondensedLU] | None = None  # the last condensed factors, at u
        pattern = _pattern(N, m, n)
        self._rows, self._cols = pattern.rows, pattern.cols
        self._slot, self._nnz, self._indices, self._indptr = pattern.slot, pattern.nnz, pattern.indices, pattern.indptr
        #: Roles of the rows and columns of the bordered Jacobian [jacobian; row] for its condensed LU
        #: (:mod:`.condensed_lu`): the mesh intervals are the links; T and p, the periodicity, phase and
        #: bordering rows are the globals.
        self.chain_layout: ChainLayout = pattern.chain_layout

    # -- unknowns ------------------------------------------------------------------------
    def unpack(self, u: np.ndarray) -> tuple[np.ndarray, float, float]:
        return u[:self.n_x].reshape(self.mesh.n_nodes, self.n), float(u[self.n_x]), float(u[self.n_x + 1])

    @staticmethod
    def pack(X: np.ndarray, T: float, p: float) -> np.ndarray:
        return np.concatenate([X.ravel(), [T, p]])

    def _at_collocation(self, X: np.ndarray):
        U = X[self.mesh.node_index]  # (ntst, m+1, n)
        return self.basis.L @ U, self.basis.D @ U  # derivative in local s; d/dtau = / h

    @property
    def reference_derivative(self) -> np.ndarray:
        """d/dtau of the reference orbit at the collocation points (the phase condition's weights)."""
        return self._reference_derivative

    @reference_derivative.setter
    def reference_derivative(self, value: np.ndarray) -> None:
        self._reference_derivative = value
        self._rows_memo = None  # the phase row changes with it

    # -- curve problem -------------------------------------------------------------------
    def accept(self, u: np.ndarray) -> None:
        X, _, _ = self.unpack(u)
        Xc, DXc = self._at_collocation(X)
        self.reference_values = Xc
        self.reference_derivative = DXc / self.mesh.h[:, None, None]

    def residual(self, u: np.ndarray) -> np.ndarray:
        X, T, p = self.unpack(u)
        mesh, n = self.mesh, self.n
        Xc, DXc = self._at_collocation(X)
        flat = Xc.reshape(-1, n).T
        F = self.system.f(flat, p).T.reshape(Xc.shape)
        coll = DXc - (mesh.h * T)[:, None, None] * F
        wq = self.basis.gauss[1]
        phase = np.einsum("j,k,jkn,jkn->", mesh.h, wq, Xc - self.reference_values, self.reference_derivative)
        return np.concatenate([coll.ravel(), X[0] - X[-1], [phase]])

    def collocation_points(self, u: np.ndarray) -> np.ndarray:
        """x at the collocation points of u as columns (n, ntst * m), interval-major."""
        Xc, _ = self._at_collocation(self.unpack(u)[0])
        return Xc.reshape(-1, self.n).T

    def blocks_of(self, J: np.ndarray, T: float) -> np.ndarray:
        """d(collocation)/d(nodes) (ntst, m, n, m+1, n) from the field's Jacobian at the
        collocation points (ntst * m, n, n) and the period."""
        mesh, n = self.mesh, self.n
        return _blocks(np.ascontiguousarray(J).reshape(mesh.ntst, mesh.ncol, n, n), mesh.h * T, self.basis.D,
                       self.basis.L)

    def collocation_blocks(self, u: np.ndarray):
        """Values of d(collocation)/d(nodes) as (ntst, m, n, m+1, n), and f, f_p at the points
        (remembered for the last u: an accepted point's tangent and multipliers both need them;
        callers must not modify them)."""
        key = u.tobytes()
        memo = self._blocks_memo
        if memo is not None and memo[0] == key:
            return memo[1]
        _, T, p = self.unpack(u)
        flat = self.collocation_points(u)
        F, J, Fp = self.system.all_at(flat, p)
        shape = (self.mesh.ntst, self.mesh.ncol, self.n)
        out = (self.blocks_of(J, T), np.ascontiguousarray(F.T).reshape(shape),
               np.ascontiguousarray(Fp.T).reshape(shape), T)
        for array in out[:3]:
            array.flags.writeable = False  # shared with later calls at the same u
        self._blocks_memo = (key, out)
        return out

    def jacobian(self, u: np.ndarray):
        mesh, n = self.mesh, self.n
        blocks, F, Fp, T = self.collocation_blocks(u)
        # d(phase)/d x(node(j,l), b) of sum_jk h_j w_k <L_kl x_jl, xref'_jk>
        coeff = np.einsum("j,k,kl,jkn->jln", mesh.h, self.basis.gauss[1], self.basis.L, self.reference_derivative)
        values = np.concatenate([blocks.ravel(), (-mesh.h[:, None, None] * F).ravel(),
                                 (-mesh.h[:, None, None] * T * Fp).ravel(), np.ones(n), -np.ones(n),
                                 coeff.ravel()])
        data = np.bincount(self._slot, weights=values, minlength=self._nnz)
        # the pattern is shared by every problem of this shape: the matrix gets its own copy
        return sp.csr_matrix((data, self._indices.copy(), self._indptr.copy()),
                             shape=(self.n_equations, self.n_x + 2))

    def factor_bordered(self, u: np.ndarray, row: np.ndarray):
        """LU factors of the bordered Jacobian [jacobian(u); row] (``solve(b)``; ``row`` kept as an
        attribute), condensed straight from the collocation blocks without assembling the sparse
        matrix: the corrector's factorisation. A zero pivot of the condensation falls back to
        SuperLU on the assembled matrix."""
        lay = self.chain_layout
        A = self.link_blocks(u, lay.width)
        Q = np.zeros((self.n + 2, self.n_x + 2))
        Q[:self.n + 1] = self.periodicity_and_phase_rows()
        Q[self.n + 1] = row
        lu = condensed_factors(lay, (A, Q), row, lambda: self.jacobian(u))
        if isinstance(lu, CondensedLU):  # its interval eliminations give the multipliers at u
            self._factors_memo = (u.tobytes(), lu)
        return lu

    def link_blocks(self, u: np.ndarray, width: int) -> np.ndarray:
        """The collocation rows of the Jacobian per mesh interval, as the condensed LU's link blocks
        (ntst, ncol n, ``width``): the interval's nodes in order, then d/dT and d/dp (further
        columns, for unknowns beyond (x, T, p), zero)."""
        mesh, n, m, N = self.mesh, self.n, self.mesh.ncol, self.mesh.ntst
        blocks, F, Fp, T = self.collocation_blocks(u)
        nodes = (m + 1) * n
        A = np.zeros((N, m * n, width))
        A[:, :, :nodes] = blocks.reshape(N, m * n, nodes)
        A[:, :, nodes] = (-mesh.h[:, None, None] * F).reshape(N, m * n)
        A[:, :, nodes + 1] = (-(mesh.h * T)[:, None, None] * Fp).reshape(N, m * n)
        return A

    def periodicity_and_phase_rows(self) -> np.ndarray:
        """The Jacobian's last n + 1 rows (x(0) - x(1), the phase condition) in full, (n + 1, n_x + 2)
        (remembered until the next :meth:`accept`; callers must not modify them)."""
        if self._rows_memo is None:
            self._rows_memo = self._periodicity_and_phase_rows()
            self._rows_memo.flags.writeable = False
        return self._rows_memo

    def _periodicity_and_phase_rows(self) -> np.ndarray:
        mesh, n, m, N = self.mesh, self.n, self.mesh.ncol, self.mesh.ntst
        Q = np.zeros((n + 1, self.n_x + 2))
        Q[np.arange(n), np.arange(n)] = 1.0
        Q[np.arange(n), self.n_x - n + np.arange(n)] = -1.0
        coeff = np.einsum("j,k,kl,jkn->jln", mesh.h, self.basis.gauss[1], self.basis.L, self.reference_derivative)
        phase = Q[n, :self.n_x].reshape(mesh.n_nodes, n)
        phase[:-1].reshape(N, m, n)[:] += coeff[:, :m]
        phase[m::m] += coeff[:, m]
        return Q

    # -- results -------------------------------------------------------------------------
    def multipliers(self, u: np.ndarray) -> np.ndarray:
        """Floquet multipliers (n,), the trivial one first, the others by decreasing modulus.

        The monodromy matrix comes from the condensed factors at u if the last factorisation was
        there (an accepted point's tangent), else from the collocation blocks: the same numbers."""
        memo = self._factors_memo
        if memo is not None and memo[0] == u.tobytes():
            M = memo[1].monodromy()
        else:
            blocks, _, _, _ = self.collocation_blocks(u)
            n, m, N = self.n, self.mesh.ncol, self.mesh.ntst
            M = monodromy(np.ascontiguousarray(blocks.reshape(N, m * n, (m + 1) * n)), n)
        if not np.all(np.isfinite(M)):
            raise np.linalg.LinAlgError("singular collocation block: no monodromy matrix")
        mu, vectors = np.linalg.eig(M)
        i = self._trivial(u, mu, vectors)
        rest = np.delete(mu, i)
        return np.concatenate([[mu[i]], rest[np.argsort(-np.abs(rest), kind="stable")]])

    def _trivial(self, u: np.ndarray, mu: np.ndarray, vectors: np.ndarray) -> int:
        """Index of the trivial multiplier: among those within 1e-3 of 1, the one whose eigenvector is
        the orbit's tangent f(x(0)) (another multiplier passing through 1, at a fold or where a
        fold curve meets a torus curve, must not be taken for it); else the one nearest to 1."""
        near = np.abs(mu - 1.0) < 1e-3
        if near.sum() < 2:
            return int(np.argmin(np.abs(mu - 1.0)))
        X, _, p = self.unpack(u)
        f0 = self.system.f(X[0], p) / self.scale
        V = vectors / self.scale[:, None]
        align = np.abs(np.conj(V).T @ f0) / np.maximum(np.linalg.norm(V, axis=0) * np.linalg.norm(f0), 1e-300)
        return int(np.argmax(np.where(near, align, -1.0)))

    def sample(self, u: np.ndarray, per_interval: int = 12) -> tuple[np.ndarray, np.ndarray]:
        """tau (k,) and x (k, n) on a fine grid (``per_interval`` points per mesh interval)."""
        X, _, _ = self.unpack(u)
        s = np.arange(per_interval) / per_interval
        E = self.basis.values(s)
        U = X[self.mesh.node_index]
        values = np.einsum("ql,jln->jqn", E, U).reshape(-1, self.n)
        tau = (self.mesh.points[:-1, None] + self.mesh.h[:, None] * s[None, :]).ravel()
        return np.append(tau, 1.0), np.vstack([values, X[-1]])

    def peak(self, u: np.ndarray, k: int = 0) -> tuple[float, float, float]:
        """(tau*, sign, A) of the largest |x_k| over the orbit u: the best of 12 samples per mesh
        interval, refined by a bounded search on the collocation polynomial (to 1e-13 in tau)."""
        X = self.unpack(u)[0]
        tau, x = self.sample(u)
        i = int(np.argmax(np.abs(x[:, k])))
        sign = 1.0 if x[i, k] >= 0 else -1.0
        brackets = [(tau[max(i - 1, 0)], tau[min(i + 1, tau.size - 1)])]
        if i in (0, tau.size - 1):  # tau = 0 and 1 are the same instant
            brackets = [(0.0, tau[1]), (tau[-2], 1.0)]
        best = (float(abs(x[i, k])), float(tau[i]))
        for lo, hi in brackets:
            t_opt, f_opt = minimum_in(lambda t: -sign * float(self.evaluate(X, np.array([t]))[0, k]), lo, hi,
                                      xatol=1e-13)
            if -f_opt > best[0]:
                best = (float(-f_opt), float(t_opt))
        return best[1], sign, best[0]

    def extremes(self, u: np.ndarray, k: int) -> tuple[float, float]:
        """(max, min) of x_k over the orbit u on its collocation polynomials: those of the mesh intervals
        around the largest and the smallest of 12 samples per interval, at their ends and where their
        derivatives vanish (roots of a polynomial of degree ncol - 1), so that they do not depend on where
        the mesh puts its samples (the samples alone are low by ~(pi / samples)^2 / 2, relative)."""
        X = self.unpack(u)[0]
        _, x = self.sample(u)
        per, N = x.shape[0] - 1, self.mesh.ntst
        coefficients = self.basis.coefficients  # column l: monomial coefficients of ell_l
        out = []
        for sign in (1.0, -1.0):
            i = int(np.argmax(sign * x[:, k]))
            j = min(i * N // per, N - 1)
            best = sign * float(x[i, k])
            for jj in {(j - 1) % N, j, (j + 1) % N}:
                c = coefficients @ X[self.mesh.node_index[jj], k]  # x_k(s) = sum_p c_p s^p on [0, 1]
                d = np.polynomial.polynomial.polyder(c)
                roots = np.polynomial.polynomial.polyroots(d) if np.any(d[1:]) else np.array([])
                s_ = np.concatenate([[0.0, 1.0], roots.real[(np.abs(roots.imag) <= 1e-12)
                                                             & (roots.real >= 0.0) & (roots.real <= 1.0)]])
                best = max(best, float(np.max(sign * np.polynomial.polynomial.polyval(s_, c))))
            out.append(sign * best)
        return out[0], out[1]

    def evaluate(self, X: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """x at arbitrary tau in [0, 1] (k, n) from node values X of this mesh."""
        return self.mesh.evaluate(X, tau)

    def adapted_mesh(self, u: np.ndarray, ntst: int | None = None) -> Mesh:
        """A mesh that equidistributes |x^(ncol)|^(1/(ncol+1)) (scaled), the error monitor of
        collocation, with a 5 % uniform share so no interval becomes too long."""
        X, _, _ = self.unpack(u)
        m = self.mesh.ncol
        U = X[self.mesh.node_index] / self.scale  # (ntst, m+1, n)
        lead = np.einsum("l,jln->jn", self.basis.coefficients[m], U)  # leading coefficient in s
        deriv = math.factorial(m) * np.abs(lead) / self.mesh.h[:, None] ** m
        density = np.linalg.norm(deriv, axis=1) ** (1.0 / (m + 1))
        total = float(np.sum(density * self.mesh.h))
        density = density + 0.05 * total + 1e-300
        cumulative = np.concatenate([[0.0], np.cumsum(density * self.mesh.h)])
        target = np.linspace(0.0, cumulative[-1], (ntst or self.mesh.ntst) + 1)
        points = np.interp(target, cumulative, self.mesh.points)
        points[0], points[-1] = 0.0, 1.0
        return Mesh(points, m)

    def transfer(self, other: "PeriodicProblem", u: np.ndarray) -> np.ndarray:
        """A point (or tangent) on this mesh -> the same on ``other``'s mesh: linear in u."""
        X, T, p = self.unpack(u)
        return other.pack(self.evaluate(X, other.mesh.node_times), T, p)
