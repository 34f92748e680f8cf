"""Two-parameter curves of cycle bifurcations: folds (LPC), period doublings (PD) and
Neimark-Sacker / torus (NS) points of periodic orbits.

Formulation: minimally augmented systems with bordered test functions on the collocation
discretisation of :mod:`.collocation` (Doedel, Govaerts, Kuznetsov, *Computation of periodic
solution bifurcations in ODEs using bordered systems*, SIAM J. Numer. Anal. 41, 2003; the
formulation MATCONT's ``limitpointcycle``, ``perioddoubling`` and ``neimarksacker`` curves
use). Chosen over the fully extended systems because the unknowns are the cycle's plus one
parameter (plus kappa for NS) instead of doubling (PD, LPC) or tripling (NS) them; the cost per
Newton step is one sparse LU more than a cycle's, and the test functions are regular at the
bifurcation, so Newton converges quadratically up to the finite-difference second
derivatives.

Unknowns u = (x at the mesh nodes, T, p1, p2[, kappa]); equations: the cycle's collocation,
periodicity and phase conditions (:class:`~.collocation.PeriodicProblem`) and

* LPC: g = 0 from [[A, b], [c^T, 0]] [v; g] = [0; 1], A the Jacobian of the cycle equations
  in (x, T) (singular where the cycle folds in p1 at fixed p2);
* PD: the same with A the linearised collocation in x with the anti-periodic condition
  v(0) + v(1) = 0 (singular where a multiplier is -1);
* NS: A the linearised collocation on two periods with v(0) - 2 kappa v(1) + v(2) = 0
  (singular, with a two-dimensional kernel, where exp(+-i theta), kappa = cos theta, are
  multipliers); bordered by two vectors, two entries of the 2x2 G = 0, chosen at the start
  as the best-conditioned pair.

Derivatives: g_u = -w^T A_u v, with w from the transposed bordered system; A_u v is the
second derivative of the cycle equations along v, a central difference of the analytic
Jacobian (step 1e-6 of v's size in the weighted norm: relative error ~1e-10, which only
enters the Newton matrix; the residuals are exact). Borders are moved to the last kernel
vectors at every accepted point, and the mesh is re-adapted every ``adapt_every`` steps.

Along a curve, codimension-2 points are detected by sign changes between points and located
by the secant method: on LPC curves the cusp (CPC: the parameter tangent reverses), a fold
meeting a torus (LPNS: a complex pair crosses the unit circle) or a period doubling (LPPD);
on PD curves LPPD, PDNS and the 1:2 resonance (R2: a second multiplier at -1); on NS curves
the strong resonances R1 (kappa = 1), R2 (kappa = -1), R3 (kappa = -1/2), R4 (kappa = 0), and
LPNS / PDNS (a real multiplier crosses +1 / -1). Stops, each said in ``stop_reason``: the
parameter box (end point located on it), a closed curve, the amplitude shrinking to zero (the
curve ends at a codimension-2 point of the equilibrium: GH for a fold curve, a double-Hopf
or zero-Hopf point for a torus curve), kappa leaving [-1, 1] (past R1/R2 the NS condition
describes neutral saddle cycles, not tori), the period limit, step underflow, the step budget.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Any, Callable

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from .collocation import Mesh, PeriodicProblem
from .condensed_lu import ChainLayout, CondensedLU, collocation_layout
from .core import (ContinuationOptions, CurvePoint, Tracer, condensed_factors, locate_between, point_at, refine, step,
                   tangent, weighted_norm)
from .errors import ContinuationError, ConvergenceError, InvalidInputError
from .fields import SliceInP1, TwoParameterField
from .kinds import CYCLE_BIFURCATIONS, PointKind, Stop, StopReason
from .lyapunov import hopf_eigenvectors
from .periodic_orbits import PeriodicOptions, hopf_guess, multiplier_crossing_test, periodic_branch
from .results import ContinuationResult, SpecialPoint


LPC, PD, NS = PointKind.FOLD_OF_CYCLES, PointKind.PERIOD_DOUBLING, PointKind.TORUS

#: Codimension-2 points reported on each curve type.
CODIM2_KINDS = {LPC: (PointKind.CUSP_OF_CYCLES, PointKind.FOLD_TORUS, PointKind.FOLD_FLIP),
                PD: (PointKind.FOLD_FLIP, PointKind.FLIP_TORUS, PointKind.RESONANCE_1_2),
                NS: (PointKind.RESONANCE_1_1, PointKind.RESONANCE_1_2, PointKind.RESONANCE_1_3,
                     PointKind.RESONANCE_1_4, PointKind.FOLD_TORUS, PointKind.FLIP_TORUS)}
#: kappa = cos(theta) at the strong resonances 1:k
RESONANCES = {PointKind.RESONANCE_1_1: 1.0, PointKind.RESONANCE_1_4: 0.0, PointKind.RESONANCE_1_3: -0.5,
              PointKind.RESONANCE_1_2: -1.0}
COMPLEX_TOL = 1e-7
#: |test function| accepted at a located point: tangent slopes and kappa to 1e-8 (the tangent
#: carries the finite-difference error of the Newton matrix, ~1e-10); ln |mu| to 1e-5: where a
#: multiplier crosses +1 on a torus curve it meets the trivial one, and a double eigenvalue is
#: only accurate to the square root of the monodromy matrix's error (~1e-6 for the gear)
LOCATE_TOL = 1e-8
MULTIPLIER_TOL = 1e-5


@dataclass(frozen=True)
class CycleCurveOptions:
    adapt_every: int = 10
    period_max: float = math.inf
    amplitude_min: float = 0.02  # end: amplitude below this fraction of the curve's largest
    #: the drawn polyline in (p1, p2): each step's chord strays from the curve (the midpoint of
    #: the cubic through both points with their tangents) by at most this fraction of each
    #: parameter (at least a tenth of its scale)
    chord_tol: float = 5e-3
    kappa_weight: float = 1.0
    continuation: ContinuationOptions = field(default_factory=lambda: ContinuationOptions(ds=0.05, ds_max=0.5,
                                                                                         max_steps=300))

    def __post_init__(self):
        if not (isinstance(self.adapt_every, int) and self.adapt_every >= 0):
            raise InvalidInputError("adapt_every", self.adapt_every, "an integer >= 0 (0: never)")
        if not (isinstance(self.chord_tol, (int, float)) and 0.0 < self.chord_tol <= 1.0):
            raise InvalidInputError("chord_tol", self.chord_tol, "a number in (0, 1]")
        if not 0.0 < self.amplitude_min < 1.0:
            raise InvalidInputError("amplitude_min", self.amplitude_min, "a number in (0, 1)")


@dataclass
class CycleCurve(ContinuationResult):
    """Points of a curve of cycle bifurcations (one row per point) and its special points (p1 in
    ``p``, p2 in their data)."""

    kind: PointKind
    p: np.ndarray  # (points, 2)
    period: np.ndarray
    x_max: np.ndarray  # (points, n)
    x_min: np.ndarray
    kappa: np.ndarray  # NS: cos of the torus angle; nan otherwise
    multipliers: np.ndarray  # (points, n), trivial first, then by decreasing modulus
    solutions: list[tuple[np.ndarray, np.ndarray]]  # (mesh points, cycle u = (x, T, p1)) per point

    def to_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, "p": self.p.tolist(), "period": self.period.tolist(),
                "x_max": self.x_max.tolist(), "x_min": self.x_min.tolist(),
                "kappa": [None if not np.isfinite(k) else float(k) for k in self.kappa], **super().to_dict()}


# --------------------------------------------------------------------------- the defining systems


#: Refinement sweeps of the test matrix's solves on the last factors before it is factored
#: afresh (fewer: more factorisations), per curve type, and on fresh factors. Measured on the gear's
#: curves with the condensed LU (a factorisation ~2.5 solves): NS (two periods, two right-hand
#: sides) is fastest with 2 (nes curves 5.9 -> 5.4 s); LPC with 6 (with fewer, one of original's fold
#: curves took shorter steps: 28 points with 2 or 3 sweeps, 42 with 1, 26 with 6).
REFINE_SWEEPS = {LPC: 6, PD: 6, NS: 2}
FRESH_SWEEPS = 3


class CycleCurveProblem:
    """The minimally augmented system of one curve type on one mesh, as a curve problem."""

    def __init__(self, system: TwoParameterField, kind: PointKind | str, mesh: Mesh,
                 scale: np.ndarray, T_scale: float, p_scale: np.ndarray, kappa_weight: float = 1.0):
        self.kind = _cycle_bifurcation(kind)
        self.system = system
        self.slice = SliceInP1(system, 0.0)
        self.p_scale = np.asarray(p_scale, float)
        self.cycle = PeriodicProblem(self.slice.field, mesh, scale, T_scale, self.p_scale[0])
        self.mesh, self.n = mesh, system.n
        self.n_x = self.cycle.n_x
        self.n_coll = mesh.ntst * mesh.ncol * self.n
        extra = [1.0 / self.p_scale[1] ** 2] + ([kappa_weight] if self.kind is NS else [])
        self.weights = np.concatenate([self.cycle.weights, extra])
        self.size = self.weights.size
        self.k = 2 if self.kind is NS else 1  # kernel dimension
        self.m = {LPC: self.n_x + 1, PD: self.n_x,
                  NS: 2 * self.n_x}[self.kind]  # size of A
        rng = np.random.default_rng(12345)
        self.B = np.linalg.qr(rng.standard_normal((self.m, self.k)))[0]
        self.C = np.linalg.qr(rng.standard_normal((self.m, self.k)))[0]
        self.entries: list[tuple[int, int]] = [(0, 0)] if self.k == 1 else [(0, 0), (1, 1)]
        self._memo: tuple[bytes, dict] | None = None
        self._lu = None  # factors of the last bordered matrix factored

    # -- unknowns --------------------------------------------------------------------------
    def cycle_u(self, u: np.ndarray) -> np.ndarray:
        """(x, T, p1) with the slice moved to p2 = u[n_x + 2]."""
        p2 = float(u[self.n_x + 2])
        if p2 != self.slice.p2:
            self.slice.p2 = p2
            self.cycle._blocks_memo = None  # the cycle's field changed under the same (x, T, p1):
            self.cycle._factors_memo = None  # nothing computed from it at another p2 is reused
        return u[:self.n_x + 2]

    def kappa(self, u: np.ndarray) -> float:
        return float(u[self.n_x + 3]) if self.kind is NS else math.nan

    @cached_property
    def chain_layout(self) -> ChainLayout:
        """Roles of the rows and columns of the Newton matrix [jacobian; row] for its condensed LU:
        the mesh intervals are the links; T, p1, p2 (and kappa) and the periodicity, phase, test
        function and bordering rows are the globals."""
        n_x, n_coll, n = self.n_x, self.n_coll, self.n
        return collocation_layout(self.mesh.ntst, self.mesh.ncol, n, self.size, [(0, 0)], [],
                                  np.arange(n_x, self.size), n_coll + np.arange(self.size - n_coll))

    @cached_property
    def test_layout(self) -> ChainLayout:
        """Roles of the rows and columns of the bordered test matrix [[A, B], [C^T, 0]] (LPC: the
        period column and the periodicity and phase rows are globals beside the borders; PD: the
        anti-periodic rows; NS: the two periods are two copies of the mesh joined by the continuity
        rows, the boundary condition rows are globals)."""
        n_x, n_coll, n, m, k = self.n_x, self.n_coll, self.n, self.m, self.k
        mesh = self.mesh
        borders_c, borders_r = m + np.arange(k), m + np.arange(k)
        if self.kind is NS:
            return collocation_layout(mesh.ntst, mesh.ncol, n, m + k, [(0, 0), (n_coll, n_x)],
                                      [2 * n_coll + np.arange(n)], borders_c,
                                      np.concatenate([2 * n_coll + n + np.arange(n), borders_r]))
        extra = [n_x] if self.kind is LPC else []  # the period's column
        return collocation_layout(mesh.ntst, mesh.ncol, n, m + k, [(0, 0)], [], np.concatenate([extra, borders_c]),
                                  np.concatenate([n_coll + np.arange(m - n_coll), borders_r]))

    def _factor(self, M: sp.csc_matrix):
        """LU factors of the bordered test matrix: condensed (:mod:`.condensed_lu`); SuperLU if
        that meets a zero pivot."""
        try:
            return CondensedLU(M, self.test_layout)
        except np.linalg.LinAlgError:
            return splu(M, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.1)

    def factor_bordered(self, u: np.ndarray, row: np.ndarray):
        """LU factors of the Newton matrix [jacobian(u); row] (``solve(b)``, ``row``), condensed
        straight from the cycle's collocation blocks, the test functions' gradients and the
        bordering row, without assembling the sparse matrix; SuperLU on a zero pivot."""
        data = self.analyse(u)
        grads = [self._gradient(u, i, j, data) for i, j in self.entries]
        cu = self.cycle_u(u)
        lay = self.chain_layout
        A = self.cycle.link_blocks(cu, lay.width)
        N, m, n = self.mesh.ntst, self.mesh.ncol, self.n
        X, T, p1 = self.cycle.unpack(cu)
        Fp2 = self.slice.dfdp2(self.cycle.collocation_points(cu), p1).T.reshape(N, m, n)
        A[:, :, (m + 1) * n + 2] = (-(self.mesh.h * T)[:, None, None] * Fp2).reshape(N, m * n)
        Q = np.zeros((lay.q, self.size))
        Q[:n + 1, :self.n_x + 2] = self.cycle.periodicity_and_phase_rows()
        Q[n + 1:n + 1 + len(grads)] = grads
        Q[-1] = row
        return condensed_factors(lay, (A, Q), row, lambda: self.jacobian(u))

    # -- the cycle equations in (x, T, p1, p2[, kappa]) ------------------------------------------
    def cycle_jacobian(self, u: np.ndarray) -> sp.csr_matrix:
        cu = self.cycle_u(u)
        J = self.cycle.jacobian(cu)
        X, T, p1 = self.cycle.unpack(cu)
        Xc, _ = self.cycle._at_collocation(X)
        flat = Xc.reshape(-1, self.n).T
        Fp2 = self.slice.dfdp2(flat, p1).T.reshape(Xc.shape)
        col = np.zeros(J.shape[0])
        col[:self.n_coll] = (-(self.mesh.h * T)[:, None, None] * Fp2).ravel()
        cols = [J, sp.csr_matrix(col[:, None])]
        if self.kind is NS:
            cols.append(sp.csr_matrix((J.shape[0], 1)))
        return sp.hstack(cols, format="csr")

    def _row_jacobian(self, u: np.ndarray, w: np.ndarray) -> np.ndarray:
        """w^T (collocation rows of the cycle Jacobian) at u, straight from the blocks (no assembly)."""
        cu = self.cycle_u(u)
        mesh, n = self.mesh, self.n
        _, T, p1 = self.cycle.unpack(cu)
        F, J, Fps = self.system.all_at(self.cycle.collocation_points(cu), np.array([p1, self.slice.p2]))
        shape = (mesh.ntst, mesh.ncol, n)
        F, Fp, Fp2 = F.T.reshape(shape), Fps[0].T.reshape(shape), Fps[1].T.reshape(shape)
        W = w.reshape(shape)
        # w^T (D x - h T L f_x x) per interval, contracted without forming the blocks
        WJ = np.einsum("jka,jkab->jkb", W, J.reshape(mesh.ntst, mesh.ncol, n, n))
        basis = self.cycle.basis
        nodes = (np.einsum("kl,jkb->jlb", basis.D, W)
                 - (mesh.h * T)[:, None, None] * np.einsum("kl,jkb->jlb", basis.L, WJ))
        row = np.zeros(self.size)
        np.add.at(row[:self.n_x].reshape(mesh.n_nodes, n), mesh.node_index, nodes)
        weighted = W * mesh.h[:, None, None]
        row[self.n_x] = -np.sum(weighted * F)
        row[self.n_x + 1] = -T * np.sum(weighted * Fp)
        row[self.n_x + 2] = -T * np.sum(weighted * Fp2)
        return row

    def _second(self, u: np.ndarray, direction: np.ndarray, w: np.ndarray) -> np.ndarray:
        """d/de of w^T (collocation rows of the cycle Jacobian) at u + e * direction: the row
        w^T F_uu[direction, .] (central difference; the other rows of A do not depend on u)."""
        size = weighted_norm(direction, self.weights)
        if size == 0.0:
            return np.zeros(self.size)
        eps = 1e-6 / size
        plus = self._row_jacobian(u + eps * direction, w)
        minus = self._row_jacobian(u - eps * direction, w)
        self.cycle_u(u)
        return (plus - minus) / (2.0 * eps)

    # -- the bordered test matrix [[A, B], [C^T, 0]] ------------------------------------------------
    def _structure(self) -> None:
        """Row and column of every entry of the bordered matrix, in the order :meth:`_values`
        produces them, and the slots of the CSC arrays they are summed into (built once per mesh)."""
        n, n_x, n_coll, m, k = self.n, self.n_x, self.n_coll, self.m, self.k
        cyc = self.cycle
        a = np.arange(n)
        rows, cols = [], []
        copies = 2 if self.kind is NS else 1
        for c in range(copies):
            rows.append(cyc._rows + c * n_coll)
            cols.append(cyc._cols + c * n_x)
        if self.kind is LPC:
            idx = self.mesh.node_index[:, :, None] * n + a[None, None, :]
            rows += [np.arange(n_coll), n_coll + a, n_coll + a, np.full(idx.size, n_coll + n)]
            cols += [np.full(n_coll, n_x), a, n_x - n + a, idx.ravel()]
        elif self.kind is PD:
            rows += [n_coll + a, n_coll + a]
            cols += [a, n_x - n + a]
        else:
            cont, bc = 2 * n_coll + a, 2 * n_coll + n + a
            rows += [cont, cont, bc, bc, bc]
            cols += [n_x - n + a, n_x + a, a, n_x - n + a, 2 * n_x - n + a]
        border_r, border_c = np.meshgrid(np.arange(m), np.arange(k), indexing="ij")
        rows += [border_r.ravel(), m + border_c.ravel()]  # B, then C^T
        cols += [m + border_c.ravel(), border_r.ravel()]
        rows, cols = np.concatenate(rows), np.concatenate(cols)
        size = m + k
        key = cols.astype(np.int64) * size + rows
        unique, slot = np.unique(key, return_inverse=True)
        self._slot, self._nnz = slot, unique.size
        self._indices = (unique % size).astype(np.int32)
        counts = np.bincount(unique // size, minlength=size)
        self._indptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int32)

    def _values(self, u: np.ndarray) -> np.ndarray:
        cu = self.cycle_u(u)
        n, mesh = self.n, self.mesh
        blocks, F, _, T = self.cycle.collocation_blocks(cu)
        parts = [blocks.ravel()] * (2 if self.kind is NS else 1)
        ones = np.ones(n)
        if self.kind is LPC:
            coeff = np.einsum("j,k,kl,jkn->jln", mesh.h, self.cycle.basis.gauss[1], self.cycle.basis.L,
                              self.cycle.reference_derivative)
            parts += [(-mesh.h[:, None, None] * F).ravel(), ones, -ones, coeff.ravel()]
        elif self.kind is PD:
            parts += [ones, ones]
        else:
            parts += [-ones, ones, ones, np.full(n, -2.0 * self.kappa(u)), ones]
        parts += [self.B.ravel(), self.C.ravel()]
        return np.concatenate(parts)

    def _bordered(self, u: np.ndarray) -> sp.csc_matrix:
        if not hasattr(self, "_slot"):
            self._structure()
        data = np.bincount(self._slot, weights=self._values(u), minlength=self._nnz)
        size = self.m + self.k
        return sp.csc_matrix((data, self._indices, self._indptr), shape=(size, size))

    def _solve(self, M: sp.csc_matrix, rhs: np.ndarray, trans: bool, sweeps: int | None = None) -> np.ndarray | None:
        """M^-1 rhs (or M^-T rhs) by iterative refinement on the last LU factors (those of a nearby
        point: a Newton iterate, the previous point); None if the residual does not reach 1e-13
        of the solution (a looser 1e-12 leaves the test functions noisy enough to slow Newton), or
        stops shrinking fast (by 4 per sweep: the factors are too far off, better refactor)."""
        if self._lu is None:
            return None
        op = M.T if trans else M
        mode = "T" if trans else "N"
        scale = max(float(np.abs(rhs).max()), 1e-300)
        sweeps = REFINE_SWEEPS[self.kind] if sweeps is None else sweeps
        return refine(lambda b: self._lu.solve(b, trans=mode), lambda z: op @ z, rhs,
                      lambda z: 1e-13 * scale * max(1.0, float(np.abs(z).max())), sweeps)

    def analyse(self, u: np.ndarray, left: bool = True) -> dict:
        """Kernel vectors V, the 2x2 (or 1x1) G and (``left``) the left vectors W of the bordered
        test matrix at u (memoised for the last u). The bordered matrix is factored afresh only
        when refinement on the last factors does not converge: most Newton iterates and trial
        points reuse them. The test values need only the right solve; gradients need both."""
        key = u.tobytes()
        if self._memo is not None and self._memo[0] == key and (not left or "W" in self._memo[1]):
            return self._memo[1]
        M = self._bordered(u)
        k, m = self.k, self.m
        rhs = np.zeros((m + k, k))
        rhs[m:, :] = np.eye(k)
        out = self._memo[1] if self._memo is not None and self._memo[0] == key else {}
        right = out.get("_right")
        if right is None:
            right = self._solve(M, rhs, False)
        solved = right is not None and (not left or (lhs := self._solve(M, rhs, True)) is not None)
        if not solved:  # refactor; the solves are refined on the new factors too
            self._lu = self._factor(M)
            right = self._solve(M, rhs, False, FRESH_SWEEPS)
            lhs = self._solve(M, rhs, True, FRESH_SWEEPS) if left and right is not None else None
            if right is None or (left and lhs is None):  # fresh condensed factors not accurate: SuperLU
                self._lu = splu(M, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.1)
                right = self._solve(M, rhs, False, FRESH_SWEEPS)
                right = self._lu.solve(rhs) if right is None else right
                if left:
                    lhs = self._solve(M, rhs, True, FRESH_SWEEPS)
                    lhs = self._lu.solve(rhs, trans="T") if lhs is None else lhs
        out = {"_right": right, "V": right[:m], "G": right[m:]}
        if left:
            out.update({"W": lhs[:m], "GT": lhs[m:]})
        self._memo = (key, out)
        return out

    def test_values(self, u: np.ndarray) -> np.ndarray:
        G = self.analyse(u, left=False)["G"]
        return np.array([G[i, j] for i, j in self.entries])

    def _gradient(self, u: np.ndarray, i: int, j: int, data: dict) -> np.ndarray:
        """d g_ij / du = -W_i^T A_u V_j."""
        V, W = data["V"][:, j], data["W"][:, i]
        n_x, n_coll = self.n_x, self.n_coll
        grad = np.zeros(self.size)
        if self.kind is LPC:
            d = np.zeros(self.size)
            d[:n_x + 1] = V
            grad -= self._second(u, d, W[:n_coll])
        elif self.kind is PD:
            d = np.zeros(self.size)
            d[:n_x] = V
            grad -= self._second(u, d, W[:n_coll])
        else:
            for copy in range(2):
                d = np.zeros(self.size)
                d[:n_x] = V[copy * n_x:(copy + 1) * n_x]
                grad -= self._second(u, d, W[copy * n_coll:(copy + 1) * n_coll])
            w_bc = W[2 * n_coll + self.n:]  # rows of V0(0) - 2 kappa V0(1) + V1(1)
            grad[n_x + 3] = 2.0 * w_bc @ V[n_x - self.n:n_x]  # -w^T (dA/dkappa) v, dA/dkappa = -2 at V0(1)
        return grad

    # -- curve problem ------------------------------------------------------------------------------
    def residual(self, u: np.ndarray) -> np.ndarray:
        cycle = self.cycle.residual(self.cycle_u(u))
        return np.concatenate([cycle, self.test_values(u)])

    def jacobian(self, u: np.ndarray):
        data = self.analyse(u)
        rows = np.array([self._gradient(u, i, j, data) for i, j in self.entries])
        full = np.tile(np.arange(self.size, dtype=np.int32), rows.shape[0])  # dense rows, zeros kept: a fixed pattern
        dense = sp.csr_matrix((rows.ravel(), full, np.arange(rows.shape[0] + 1, dtype=np.int32) * self.size),
                              shape=rows.shape)
        return sp.vstack([self.cycle_jacobian(u), dense], format="csr")

    def accept(self, u: np.ndarray) -> None:
        self.cycle.accept(self.cycle_u(u))
        self._memo = None  # accepting moves the phase condition: the bordered matrix at u changes
        self.update_borders(u)

    def update_borders(self, u: np.ndarray, sweeps: int = 1) -> None:
        for _ in range(sweeps):
            data = self.analyse(u)
            self.C = np.linalg.qr(data["V"])[0]
            self.B = np.linalg.qr(data["W"])[0]
            self._memo = None  # the factors stay: refinement absorbs the change of borders

    def choose_entries(self, u: np.ndarray) -> None:
        """NS: the two entries of G whose gradients, restricted to the cycle manifold, are the
        best conditioned pair (G has four entries, two of them independent near the curve)."""
        if self.k == 1:
            return
        data = self.analyse(u)
        J = self.cycle_jacobian(u)
        n_x = self.n_x
        square = J[:, :n_x + 1].tocsc()
        lu = splu(square, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.1)
        null = np.zeros((self.size, 3))
        for c, col in enumerate((n_x + 1, n_x + 2, n_x + 3)):  # p1, p2, kappa directions on the manifold
            null[col, c] = 1.0
            rhs = -J[:, col].toarray().ravel()
            null[:n_x + 1, c] = lu.solve(rhs)
        grads = {(i, j): self._gradient(u, i, j, data) @ null for i in range(2) for j in range(2)}
        best, best_value = self.entries, -1.0
        keys = list(grads)
        for a in range(4):
            for b in range(a + 1, 4):
                R = np.vstack([grads[keys[a]], grads[keys[b]]])
                R = R / np.maximum(np.linalg.norm(R, axis=1, keepdims=True), 1e-300)
                value = np.linalg.svd(R, compute_uv=False)[-1]
                if value > best_value:
                    best, best_value = [keys[a], keys[b]], value
        self.entries = best
        self._memo = None

    # -- results --------------------------------------------------------------------------------------
    def multipliers(self, u: np.ndarray) -> np.ndarray:
        return self.cycle.multipliers(self.cycle_u(u))

    def extremes(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        _, x = self.cycle.sample(self.cycle_u(u))
        return x.max(axis=0), x.min(axis=0)

    def rebuilt(self, mesh: Mesh) -> "CycleCurveProblem":
        other = CycleCurveProblem(self.system, self.kind, mesh, self.cycle.scale, self.cycle.T_scale, self.p_scale,
                                  float(self.weights[-1]) if self.kind is NS else 1.0)
        other.entries = list(self.entries)
        return other

    def transfer(self, other: "CycleCurveProblem", u: np.ndarray) -> np.ndarray:
        """A point (or tangent) of this problem on ``other``'s mesh."""
        head = self.cycle.transfer(other.cycle, u[:self.n_x + 2])
        return np.concatenate([head, u[self.n_x + 2:]])

    def transfer_borders(self, other: "CycleCurveProblem") -> None:
        """Kernel vectors carried over by interpolation; left vectors found again by two sweeps."""
        def nodes(V):
            return np.column_stack([self.cycle.evaluate(V[:, c].reshape(self.mesh.n_nodes, self.n),
                                                        other.mesh.node_times).ravel() for c in range(V.shape[1])])
        if self.kind is LPC:
            C = np.vstack([nodes(self.C[:self.n_x]), self.C[self.n_x:]])
        elif self.kind is PD:
            C = nodes(self.C)
        else:
            C = np.vstack([nodes(self.C[:self.n_x]), nodes(self.C[self.n_x:])])
        other.C = np.linalg.qr(C)[0]


# --------------------------------------------------------------------------- tracing a curve


def _critical(kind: PointKind, mu: np.ndarray, kappa: float) -> list[int]:
    """Indices of the trivial multiplier (0) and of those the curve's condition holds at."""
    rest = np.arange(1, mu.size)
    if kind is LPC:
        return [0, int(rest[np.argmin(np.abs(mu[1:] - 1.0))])]
    if kind is PD:
        return [0, int(rest[np.argmin(np.abs(mu[1:] + 1.0))])]
    target = kappa + 1j * math.sqrt(max(0.0, 1.0 - kappa ** 2))
    d = np.minimum(np.abs(mu[1:] - target), np.abs(mu[1:] - np.conj(target)))
    order = rest[np.argsort(d, kind="stable")]
    return [0, int(order[0]), int(order[1])]


def _monitors(problem: CycleCurveProblem, point: CurvePoint, mu: np.ndarray, reference_direction) -> dict:
    """Test functions of the codimension-2 points of this curve type at a point."""
    kind = problem.kind
    kappa = problem.kappa(point.u)
    out: dict[str, float] = {}
    if kind is LPC:
        t_p = point.tangent[problem.n_x + 1:problem.n_x + 3] * np.sqrt(problem.weights[problem.n_x + 1:problem.n_x + 3])
        out[PointKind.CUSP_OF_CYCLES] = float(t_p @ reference_direction) if reference_direction is not None else 1.0
    elif kind is NS:
        for name, value in RESONANCES.items():
            out[name] = kappa - value
    for name, which in _CROSSINGS[kind].items():
        out[name] = _crossing_value(problem, which, mu, kappa)
    return out


#: Codimension-2 points where a further multiplier crosses the unit circle: which kind of
#: multiplier (real positive, real negative, complex) crosses, per curve type.
_CROSSINGS = {LPC: {PointKind.FOLD_TORUS: "complex", PointKind.FOLD_FLIP: "negative"},
              PD: {PointKind.FOLD_FLIP: "positive", PointKind.FLIP_TORUS: "complex",
                   PointKind.RESONANCE_1_2: "negative"},
              NS: {PointKind.FOLD_TORUS: "positive", PointKind.FLIP_TORUS: "negative"}}


def _crossing_value(problem: "CycleCurveProblem", which: str, mu: np.ndarray, kappa: float,
                    guard: bool = True) -> float:
    """(-1)^(noncritical multipliers of one kind outside the unit circle) times the smallest
    |ln |mu|| among them (a complex pair counted once): continuous, zero exactly where one of
    them is on the circle, and of the other sign after it crossed; multipliers far from the
    circle (tiny ones flip between real kinds on rounding) do not change it. NaN where the
    crossing multiplier is within the multipliers' accuracy (10 |mu_trivial - 1|, at least 1e-6)
    of the circle: near a zero-amplitude end the cycle's radial multiplier tends to 1 and its
    side is not resolved."""
    keep = np.ones(mu.size, bool)
    keep[_critical(problem.kind, mu, kappa)] = False
    return multiplier_crossing_test(mu[keep], which, max(10.0 * abs(mu[0] - 1.0), 1e-6) if guard else 0.0)


def _crossing_test(problem: "CycleCurveProblem", which: str) -> Callable[[CurvePoint], float]:
    def g(q: CurvePoint) -> float:
        return _crossing_value(problem, which, problem.multipliers(q.u), problem.kappa(q.u), guard=False)
    return g


def cycle_curve(system: TwoParameterField, kind: PointKind | str, start: tuple[np.ndarray, np.ndarray],
                p2: float, *, box: tuple[tuple[float, float], tuple[float, float]],
                options: CycleCurveOptions | None = None, scale: np.ndarray | None = None,
                p_scale: tuple[float, float] = (1.0, 1.0), kappa: float | None = None, ncol: int = 4,
                directions: tuple[int, ...] = (1, -1), p2_marks: tuple[float, ...] = (),
                progress: Callable[[float], None] | None = None) -> CycleCurve:
    """Continue a fold (LPC), period doubling (PD) or torus (NS) point of a cycle in (p1, p2).

    ``start`` = (mesh points, cycle u = (x at the nodes, T, p1)): a located special point of a
    one-parameter branch in p1 at ``p2`` (``PeriodicBranch.solutions`` at its index); for NS,
    ``kappa`` = cos of the torus angle there. ``box`` bounds (p1, p2); ``scale`` (n,) and ``p_scale``
    set the size of a unit step in the states and in (p1, p2). Traced in both directions
    (``directions``: +1 first increases p2); the two halves are joined into one curve. Where the
    curve turns in p2 a ``P2_TURN`` point is located, and where it crosses a value of ``p2_marks``
    a ``P2_MARK`` point (both with the cycle's period and extremes).
    """
    kind = _cycle_bifurcation(kind)
    options = options or CycleCurveOptions()
    if kind is NS and (kappa is None or not -1.0 < kappa < 1.0):
        raise InvalidInputError("kappa", kappa, "cos of the torus angle, in (-1, 1)")
    for name, (low, high) in zip(("p1 range", "p2 range"), box, strict=True):
        if not (math.isfinite(low) and math.isfinite(high) and low < high):
            raise InvalidInputError(name, (low, high), "finite bounds, low < high")
    mesh_points, cu = start
    mesh = Mesh(np.asarray(mesh_points, float), ncol)
    scale = np.ones(system.n) if scale is None else scale
    problem = CycleCurveProblem(system, kind, mesh, scale, float(cu[-2]), np.asarray(p_scale, float),
                                options.kappa_weight)
    u0 = np.concatenate([cu, [p2]] + ([[kappa]] if kind is NS else []))
    problem.cycle.accept(problem.cycle_u(u0))
    problem.update_borders(u0, sweeps=3)
    problem.choose_entries(u0)
    problem.update_borders(u0, sweeps=1)
    copts = options.continuation
    e2 = np.zeros(problem.size)
    e2[problem.n_x + 2] = 1.0
    first = step(problem, CurvePoint(u0, e2 / weighted_norm(e2, problem.weights)), 0.0, copts)
    if first is None:
        raise ConvergenceError(f"no {kind} point converged near the start (p = ({cu[-1]:g}, {p2:g}))")
    halves, stops, steps_total = [], [], 0
    for direction in directions:
        half_problem = problem if not halves else _fresh(problem, first.u)
        t = first.tangent if first.tangent[problem.n_x + 2] * direction >= 0 else -first.tangent
        rows, special, stop, steps = _trace(half_problem, CurvePoint(first.u.copy(), t), box, options,
                                                      tuple(p2_marks), progress)
        halves.append((rows, special))
        stops.append(stop)
        steps_total += steps
        if stop.reason is StopReason.CLOSED:
            break
    return _join(kind, halves, stops, steps_total)


def start_beside(system: TwoParameterField, kind: PointKind | str, x_star: np.ndarray, p: np.ndarray, *,
                 p_range: tuple[float, float], options: PeriodicOptions | None = None,
                 scale: np.ndarray | None = None, p_scale: float = 1.0,
                 limits=None) -> tuple[SpecialPoint | None, int]:
    """A start for :func:`cycle_curve` near a codimension-2 point of an equilibrium: the first
    ``kind`` point of the cycle branch born at the Hopf point (x_star, p) (continued in p1 over
    ``p_range`` at p2 = p[1], with :func:`~.periodic_orbits.periodic_branch`'s ``scale``,
    ``p_scale`` and ``limits``). Beside a generalised Hopf point that is the small-amplitude fold
    of the fold curve born there; beside a double-Hopf point, the torus point of a torus curve born there. Returns
    (the located point with its solution, or None; the collocation degree of its mesh)."""
    kind = _cycle_bifurcation(kind)
    options = replace(options or PeriodicOptions(), stop_at=(kind,))
    field_ = system.at(float(p[1]))
    x_star = np.asarray(x_star, float)
    omega, q, _ = hopf_eigenvectors(field_.dfdx(x_star, float(p[0])))
    guess, shape = hopf_guess(x_star, float(p[0]), omega, q, Mesh.uniform(options.ntst, options.ncol), 0.0)
    try:
        branch = periodic_branch(field_, guess, p_range=p_range, options=options, scale=scale, p_scale=p_scale,
                                 direction=shape, limits=limits)
    except ContinuationError:
        return None, options.ncol
    found = [s for s in branch.special_points if s.kind == kind]
    return (found[0] if found else None), branch.ncol


def _cycle_bifurcation(kind: PointKind | str) -> PointKind:
    """The curve type ``kind`` names: one of :data:`~.kinds.CYCLE_BIFURCATIONS`."""
    kind = PointKind(kind)
    if kind not in CYCLE_BIFURCATIONS:
        raise InvalidInputError("kind", kind.value, ", ".join(CYCLE_BIFURCATIONS), "is not a bifurcation of cycles")
    return kind


def _fresh(problem: CycleCurveProblem, u: np.ndarray) -> CycleCurveProblem:
    other = problem.rebuilt(problem.mesh)
    other.B, other.C = problem.B.copy(), problem.C.copy()
    other.cycle.accept(other.cycle_u(u))
    other.update_borders(u, sweeps=2)
    return other


def _record(problem: CycleCurveProblem, rows: dict, point: CurvePoint) -> np.ndarray:
    mu = problem.multipliers(point.u)
    xmax, xmin = problem.extremes(point.u)
    n_x = problem.n_x
    rows["p"].append(point.u[n_x + 1:n_x + 3].copy())
    rows["T"].append(float(point.u[n_x]))
    rows["xmax"].append(xmax)
    rows["xmin"].append(xmin)
    rows["kappa"].append(problem.kappa(point.u))
    rows["mu"].append(mu)
    rows["solutions"].append((problem.mesh.points.copy(), point.u[:n_x + 2].copy()))
    return mu


def _amplitude(problem: CycleCurveProblem, xmax, xmin) -> float:
    return float(np.max(0.5 * (np.asarray(xmax) - np.asarray(xmin)) / problem.cycle.scale))


def _trace(problem: CycleCurveProblem, start: CurvePoint, box, options: CycleCurveOptions, marks, progress):
    copts = options.continuation
    n_x = problem.n_x
    rows: dict[str, list] = {k: [] for k in ("p", "T", "xmax", "xmin", "kappa", "mu", "solutions")}
    problem.accept(start.u)
    mu = _record(problem, rows, start)
    tracer = Tracer(problem, start, copts, chord=lambda pr, a, b, h: _chord_ratio(pr, a, b, h, options.chord_tol))
    special: list[SpecialPoint] = []

    def p_direction(point):
        t_p = point.tangent[n_x + 1:n_x + 3] * np.sqrt(problem.weights[n_x + 1:n_x + 3])
        return t_p / max(np.linalg.norm(t_p), 1e-300)

    reference = p_direction(start)
    monitors = _monitors(problem, start, mu, reference)
    amp_peak = _amplitude(problem, rows["xmax"][0], rows["xmin"][0])
    amp_last = amp_peak
    stop = Stop(StopReason.STEP_BUDGET, f"step budget of {copts.max_steps} steps used")
    steps = 0
    for steps in range(1, copts.max_steps + 1):  # noqa: B007
        prev = tracer.point
        adv = tracer.advance()
        if adv is None:
            stop = tracer.failed
            break
        new, h = adv
        p_new = new.u[n_x + 1:n_x + 3]
        outside = [(c, bound) for c in range(2) for bound in box[c]
                   if (bound == box[c][0] and p_new[c] < bound) or (bound == box[c][1] and p_new[c] > bound)]
        if outside:
            c, bound = outside[0]
            index = n_x + 1 + c
            hit = locate_between(problem, prev, new, lambda q: q.u[index] - bound, prev.u[index] - bound,
                                 new.u[index] - bound, copts, 1e-9 * problem.p_scale[c], with_tangent=False)
            if hit is not None:
                special.extend(_p2_points(problem, prev, hit[0], marks, rows, copts))
                problem.accept(hit[0].u)
                _record(problem, rows, hit[0])
                special.append(SpecialPoint(PointKind.END, float(hit[0].u[n_x + 1]), len(rows["p"]) - 1,
                                            {"p2": float(hit[0].u[n_x + 2])}))
            stop = Stop(StopReason.BOUND, f"left the parameter box at p{c + 1} = {bound:g}")
            break
        if new.u[n_x] > options.period_max:
            stop = Stop(StopReason.PERIOD_LIMIT, f"period {new.u[n_x]:.4g} above the limit {options.period_max:.4g}")
            break
        if new.u[n_x] <= 0:
            stop = Stop(StopReason.NONPOSITIVE_PERIOD, "period became non-positive: the continuation left the curve")
            break
        kappa = problem.kappa(new.u)
        if problem.kind is NS and not -1.0 <= kappa <= 1.0:
            stop = Stop(StopReason.PAST_RESONANCE, f"kappa = {kappa:.4g} left [-1, 1] near p = ({p_new[0]:.6g}, "
                        f"{p_new[1]:.6g}): past a strong resonance the condition describes neutral saddle cycles, "
                        "not tori")
            break
        mu = _record(problem, rows, new)
        special.extend(_p2_points(problem, prev, new, marks, rows, copts))
        new_monitors = _monitors(problem, new, mu, reference)
        special.extend(_codim2(problem, prev, new, h, monitors, new_monitors, reference, rows, copts))
        monitors = new_monitors
        reference = p_direction(new)
        if problem.kind is LPC:  # the cusp test at `new` against its own direction
            monitors[PointKind.CUSP_OF_CYCLES] = _monitors(problem, new, mu, reference)[PointKind.CUSP_OF_CYCLES]
        if progress is not None:
            progress(min(1.0, steps / copts.max_steps))
        if _closed(rows):
            stop = Stop(StopReason.CLOSED, "closed curve: returned to its first point")
            break
        amp = _amplitude(problem, rows["xmax"][-1], rows["xmin"][-1])
        amp_peak = max(amp_peak, amp)
        if amp < options.amplitude_min * amp_peak and amp < amp_last:
            stop = Stop(StopReason.ZERO_AMPLITUDE, f"amplitude shrank to zero near p = ({p_new[0]:.6g}, "
                        f"{p_new[1]:.6g}): the curve ends at a codimension-2 point of the equilibrium")
            special.append(SpecialPoint(PointKind.ZERO_AMPLITUDE, float(p_new[0]), len(rows["p"]) - 1,
                                        {"p2": float(p_new[1]), "amplitude": amp}))
            break
        if amp < amp_last:
            tracer.limit_step(max(0.7 * amp * h / max(amp_last - amp, 1e-300), copts.ds_min))
        amp_last = amp
        if options.adapt_every and steps % options.adapt_every == 0:
            problem = _remesh(problem, tracer, copts)
    return rows, special, stop, steps


def _chord_ratio(problem: CycleCurveProblem, a: CurvePoint, b: CurvePoint, h: float, tol: float) -> float:
    """How far the step from a to b strays from its chord in the parameter plane, over the
    allowed ``tol`` of each parameter (relative to its size, at least a tenth of its scale): the
    cubic through both points with their tangents (d/ds, s the weighted arclength h) lies
    h/8 (t_a - t_b) from the chord at the middle."""
    i = problem.n_x + 1
    p = np.abs(np.stack([a.u[i:i + 2], b.u[i:i + 2]])).max(axis=0)
    allowed = tol * np.maximum(p, 0.1 * problem.p_scale)
    return float(np.max(np.abs(0.125 * h * (a.tangent[i:i + 2] - b.tangent[i:i + 2])) / allowed))


def _remesh(problem: CycleCurveProblem, tracer: Tracer, copts: ContinuationOptions) -> CycleCurveProblem:
    point = tracer.point
    new_mesh = problem.cycle.adapted_mesh(problem.cycle_u(point.u))
    other = problem.rebuilt(new_mesh)
    u_t = problem.transfer(other, point.u)
    t_t = problem.transfer(other, point.tangent)
    problem.transfer_borders(other)
    other.cycle.accept(other.cycle_u(u_t))
    other.update_borders(u_t, sweeps=2)
    t_t /= weighted_norm(t_t, other.weights)
    fixed = step(other, CurvePoint(u_t, t_t), 0.0, copts)
    if fixed is None:  # keep the old mesh
        problem.cycle_u(point.u)
        return problem
    other.accept(fixed.u)
    tracer.problem = other
    tracer.point = CurvePoint(fixed.u, tangent(other, fixed.u, t_t))
    return other


def _located(problem: CycleCurveProblem, kind: PointKind, at: CurvePoint, rows, extra=None,
             located: bool | None = None) -> SpecialPoint:
    n_x = problem.n_x
    mu = problem.multipliers(at.u)
    xmax, xmin = problem.extremes(at.u)
    data = {"p2": float(at.u[n_x + 2]), "period": float(at.u[n_x]), "x_max": xmax.tolist(), "x_min": xmin.tolist(),
            "multipliers_abs": np.abs(mu[1:]).tolist(), **(extra or {})}
    if problem.kind is NS:
        data["kappa"] = problem.kappa(at.u)
    return SpecialPoint(kind, float(at.u[n_x + 1]), len(rows["p"]) - 1, data, located)


def _p2_points(problem: CycleCurveProblem, prev: CurvePoint, new: CurvePoint, marks, rows, copts) -> list[SpecialPoint]:
    """Turning points of the curve in p2 and its crossings of the marked p2 values in this step."""
    i2 = problem.n_x + 2
    found = []

    def slope(q):  # p2's share of the curve's direction in the parameter plane (scaled)
        t_p = q.tangent[i2 - 1:i2 + 1] * np.sqrt(problem.weights[i2 - 1:i2 + 1])
        return float(t_p[1] / max(np.linalg.norm(t_p), 1e-300))

    if prev.tangent[i2] * new.tangent[i2] < 0:
        hit = locate_between(problem, prev, new, slope, slope(prev), slope(new), copts, LOCATE_TOL)
        at = hit[0] if hit is not None else new
        found.append(_located(problem, PointKind.P2_TURN, at, rows,
                              {"turn": "max" if prev.tangent[i2] > 0 else "min"}, hit is not None))
    for mark in marks:
        a, b = prev.u[i2] - mark, new.u[i2] - mark
        if abs(b) <= 1e-9 * problem.p_scale[1]:  # the step ends on the mark (a box edge)
            found.append(_located(problem, PointKind.P2_MARK, new, rows))
        elif a * b < 0:
            at = point_at(problem, prev, new, i2, mark, copts)  # p2 held at the mark: one Newton solve
            if at is None:
                hit = locate_between(problem, prev, new, lambda q, m=mark: q.u[i2] - m, a, b, copts,
                                     1e-9 * problem.p_scale[1], with_tangent=False)
                at = None if hit is None else hit[0]
            if at is not None:
                found.append(_located(problem, PointKind.P2_MARK, at, rows))
    problem.cycle_u(new.u)
    return found


def _codim2(problem: CycleCurveProblem, prev: CurvePoint, new: CurvePoint, h: float, before: dict, after: dict,
            reference, rows, copts) -> list[SpecialPoint]:
    found = []
    n_x = problem.n_x
    for name, a in before.items():
        b = after[name]
        if not (np.isfinite(a) and np.isfinite(b)) or a * b > 0 or a == b:
            continue
        if name in _CROSSINGS[problem.kind]:
            g = _crossing_test(problem, _CROSSINGS[problem.kind][name])
        elif name is PointKind.CUSP_OF_CYCLES:
            def g(q):
                t_p = q.tangent[n_x + 1:n_x + 3] * np.sqrt(problem.weights[n_x + 1:n_x + 3])
                return float(t_p @ reference)
        else:
            def g(q, target=RESONANCES[name]):
                return problem.kappa(q.u) - target
        hit = locate_between(problem, prev, new, g, a, b, copts,
                             MULTIPLIER_TOL if name in _CROSSINGS[problem.kind] else LOCATE_TOL,
                             with_tangent=name is PointKind.CUSP_OF_CYCLES)
        at = hit[0] if hit is not None else new
        found.append(_located(problem, name, at, rows, located=hit is not None))
    problem.cycle_u(new.u)
    return found


def _closed(rows: dict) -> bool:
    k = len(rows["p"])
    if k < 8:
        return False

    def measure(i):
        return np.concatenate([rows["p"][i], [rows["T"][i]], rows["xmax"][i]])

    first, prev, last = measure(0), measure(k - 2), measure(k - 1)
    span = np.ptp(np.array([measure(i) for i in range(k)]), axis=0)
    span[span == 0] = 1.0
    first, prev, last = first / span, prev / span, last / span
    seg = last - prev
    length = float(np.linalg.norm(seg))
    if length == 0.0:
        return False
    far = max(float(np.linalg.norm(measure(i) / span - first)) for i in range(k))
    if far < 5.0 * length:
        return False
    s = float(np.clip(np.dot(first - prev, seg) / length ** 2, 0.0, 1.0))
    return float(np.linalg.norm(prev + s * seg - first)) < length / 3.0


def _join(kind: PointKind, halves, stops, steps) -> CycleCurve:
    """One curve: the second half reversed, then the first (they share the start point)."""
    parts = []
    special: list[SpecialPoint] = []
    offset = 0
    ordered = [halves[1], halves[0]] if len(halves) == 2 else halves
    for h_index, (rows, pts) in enumerate(ordered):
        count = len(rows["p"])
        if len(halves) == 2 and h_index == 0:
            order = list(range(count - 1, 0, -1))  # reversed, without the shared start point
            position = {i: k for k, i in enumerate(order)}
            for s in pts:
                special.append(replace(s, index=position.get(s.index, 0)))
        else:
            order = list(range(count))
            for s in pts:
                special.append(replace(s, index=offset + s.index))
        parts.append((rows, order))
        offset += len(order)

    def gather(key):
        return [rows[key][i] for rows, order in parts for i in order]

    mu = gather("mu")
    special.sort(key=lambda s: s.index)
    return CycleCurve(kind, np.array(gather("p")), np.array(gather("T")), np.array(gather("xmax")),
                      np.array(gather("xmin")), np.array(gather("kappa"), float), np.array(mu), gather("solutions"),
                      special_points=special, stops=stops, steps=steps,
                      closed=any(s.reason is StopReason.CLOSED for s in stops))
