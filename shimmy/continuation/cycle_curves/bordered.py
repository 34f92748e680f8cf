"""The bordered machinery every curve of cycle bifurcations shares: its minimally augmented system.

Unknowns u = (x at the mesh nodes, T, p1, p2[, kappa]); equations: the cycle's collocation,
periodicity and phase conditions (:class:`~shimmy.continuation.PeriodicProblem`) and the test functions
G = 0 of the bordered matrix [[A, B], [C^T, 0]] [V; G] = [0; I], A the curve type's linearisation
of the cycle (its ``DefiningSystem``, :mod:`.defining_system`), singular on the curve.

Derivatives: g_u = -w^T A_u v, with w from the transposed bordered system; A_u v is the
second derivative of the cycle equations along v, a central difference of the analytic
Jacobian (step 1e-6 of v's size in the weighted norm: relative error ~1e-10 to ~1e-7, which
only enters the Newton matrix; the residuals are exact). The borders are moved to the last kernel
vectors at every accepted point. The bordered matrix is factored by the condensed LU of
:mod:`shimmy.continuation.condensed_lu` (SuperLU where that meets a zero pivot), and its solves are refined on the
last factors, so that most Newton iterates and trial points do not factor it; the refinement's products
are taken from the collocation blocks without assembling the matrix (:mod:`.bordered_operator`).
"""

from __future__ import annotations

import math
from functools import cached_property

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from ..collocation import Mesh, PeriodicProblem
from ..condensed_lu import ChainLayout, CondensedLU, collocation_layout
from ..core import condensed_factors, refine, weighted_norm
from ..errors import InvalidInputError
from ..fields import SliceInP1, TwoParameterField
from ..kinds import CYCLE_BIFURCATIONS, PointKind
from ..results import SpecialPoint
from .defining_system import DefiningSystem
from .fold_of_cycles import FoldOfCycles
from .period_doubling import PeriodDoubling
from .bordered_operator import BorderedOperator
from .torus import Torus

#: The defining system of each curve type.
DEFINING_SYSTEMS: dict[PointKind, DefiningSystem] = {s.kind: s for s in (FoldOfCycles(), PeriodDoubling(), Torus())}

#: Step (weighted norm) of the central differences of the cycle Jacobian along a direction
#: (:meth:`CycleCurveProblem.second_many`): truncation ~1e-12, rounding ~1e-10 relative.
SECOND_STEP = 1e-6

#: Refinement sweeps of the test matrix's solves on fresh factors. On the last factors, before the
#: matrix is factored afresh, each curve type has its own (``DefiningSystem.refine_sweeps``, fewer:
#: more factorisations), measured on the gear's curves with the condensed LU (a factorisation ~2.5
#: solves).
FRESH_SWEEPS = 3


def defining_system(kind: PointKind | str) -> DefiningSystem:
    """The defining system of the curves of ``kind``, one of ``CYCLE_BIFURCATIONS``."""
    kind = PointKind(kind)
    if kind not in DEFINING_SYSTEMS:
        raise InvalidInputError("kind", kind.value, ", ".join(CYCLE_BIFURCATIONS), "is not a bifurcation of cycles")
    return DEFINING_SYSTEMS[kind]


class CycleCurveProblem:
    """The minimally augmented system of one curve type on one mesh, as a curve problem."""

    def __init__(self, system: TwoParameterField, kind: PointKind | str, mesh: Mesh,
                 scale: np.ndarray, T_scale: float, p_scale: np.ndarray, kappa_weight: float = 1.0):
        self.defining = defining_system(kind)
        self.kind = self.defining.kind
        self.system = system
        self.slice = SliceInP1(system, 0.0)
        self.p_scale = np.asarray(p_scale, float)
        self.cycle = PeriodicProblem(self.slice.field, mesh, scale, T_scale, self.p_scale[0])
        self.mesh, self.n = mesh, system.n
        self.n_x = self.cycle.n_x
        self.n_coll = mesh.ntst * mesh.ncol * self.n
        extra = [1.0 / self.p_scale[1] ** 2] + ([kappa_weight] if self.defining.has_kappa else [])
        self.weights = np.concatenate([self.cycle.weights, extra])
        self.size = self.weights.size
        self.k = self.defining.kernel
        self.m = self.defining.size(self.n_x)  # size of A
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

    @property
    def kappa_index(self) -> int:
        """Where kappa is in u (after p2; only when the defining system has it)."""
        return self.n_x + 3

    def kappa(self, u: np.ndarray) -> float:
        return float(u[self.kappa_index]) if self.defining.has_kappa else math.nan

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
        """Roles of the rows and columns of the bordered test matrix [[A, B], [C^T, 0]]."""
        return self.defining.test_layout(self)

    def _factor(self, M: BorderedOperator, u: np.ndarray):
        """LU factors of the bordered test matrix M at u: condensed (:mod:`.condensed_lu`), its input
        summed straight from the matrix's entries (no sparse matrix); SuperLU if that meets a zero
        pivot."""
        lay = self.test_layout
        if not hasattr(self, "_slot"):
            self._structure()
        if not hasattr(self, "_destinations"):
            self._destinations = lay.destinations(*self._entries)
        buffer = np.bincount(self._destinations, weights=self._values(u), minlength=lay.buffer_size)
        split = lay.links * lay.r_max * lay.width
        parts = (buffer[:split].reshape(lay.links, lay.r_max, lay.width), buffer[split:].reshape(lay.q, lay.size))
        try:
            return CondensedLU(None, lay, parts)
        except np.linalg.LinAlgError:
            return splu(M.sparse(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.1)

    def factor_bordered(self, u: np.ndarray, row: np.ndarray):
        """LU factors of the Newton matrix [jacobian(u); row] (``solve(b)``, ``row``), condensed
        straight from the cycle's collocation blocks, the test functions' gradients and the
        bordering row, without assembling the sparse matrix; SuperLU on a zero pivot."""
        data = self.analyse(u)
        grads = self._gradients(u, self.entries, data)
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
        if self.defining.has_kappa:
            cols.append(sp.csr_matrix((J.shape[0], 1)))
        return sp.hstack(cols, format="csr")

    def second(self, u: np.ndarray, direction: np.ndarray, w: np.ndarray) -> np.ndarray:
        """d/de of w^T (collocation rows of the cycle Jacobian) at u + e * direction: the row
        w^T F_uu[direction, .] (central difference; the other rows of A do not depend on u)."""
        return self.second_many(u, [(direction, w)])[0]

    def second_many(self, u: np.ndarray, pairs: list[tuple[np.ndarray, np.ndarray]]) -> list[np.ndarray]:
        """:meth:`second` for several (direction, w), the field evaluated at the collocation points of
        every displaced u in one call where the displacements leave the parameters as they are (the
        curve types' directions move only the cycle).

        The row w^T (D x - h T L f_x x) at u +- eps d (eps = ``SECOND_STEP`` over d's size),
        contracted per interval without forming the blocks. D's part is the same at both ends and is
        left out of the difference: subtracting it from itself cost a fold curve's rows up to 6e-6 of
        their size in rounding (at steps 1e-6 and 1e-5 the rows now agree to 3e-7, before to 6e-6)."""
        mesh, n, N, m = self.mesh, self.n, self.mesh.ntst, self.mesh.ncol
        rows: list[np.ndarray] = [np.zeros(self.size) for _ in pairs]
        displaced, steps = [], []
        for k, (d, _) in enumerate(pairs):
            size = weighted_norm(d, self.weights)
            if size > 0.0:
                eps = SECOND_STEP / size
                steps.append((k, eps))
                displaced += [u + eps * d, u - eps * d]
        if not displaced:
            return rows
        i = self.n_x + 1
        params = [v[i:i + 2].copy() for v in displaced]
        points = [self.cycle.collocation_points(v[:i + 1]) for v in displaced]
        if all(np.array_equal(q, params[0]) for q in params):
            F, J, Fps = self.system.all_at(np.hstack(points), params[0])
            K = N * m
            fields = [(F[:, j * K:(j + 1) * K], J[j * K:(j + 1) * K], Fps[:, :, j * K:(j + 1) * K])
                      for j in range(len(displaced))]
        else:
            fields = [self.system.all_at(x, q) for x, q in zip(points, params)]
        shape = (N, m, n)
        for slot, (k, eps) in enumerate(steps):
            W = pairs[k][1].reshape(shape)
            weighted = W * mesh.h[:, None, None]
            TWJ, sums = 0.0, np.zeros(3)
            for sign, j in ((1.0, 2 * slot), (-1.0, 2 * slot + 1)):
                F, J, Fps = fields[j]
                T = float(displaced[j][self.n_x])
                TWJ = TWJ + sign * T * np.einsum("jka,jkab->jkb", W, J.reshape(N, m, n, n))
                sums += sign * np.array([np.sum(weighted * F.T.reshape(shape)),
                                         T * np.sum(weighted * Fps[0].T.reshape(shape)),
                                         T * np.sum(weighted * Fps[1].T.reshape(shape))])
            nodes = -mesh.h[:, None, None] * np.einsum("kl,jkb->jlb", self.cycle.basis.L, TWJ)
            row = rows[k]
            np.add.at(row[:self.n_x].reshape(mesh.n_nodes, n), mesh.node_index, nodes)
            row[self.n_x:self.n_x + 3] = -sums
            row /= 2.0 * eps
        return rows

    # -- the bordered test matrix [[A, B], [C^T, 0]] ------------------------------------------------
    def _structure(self) -> None:
        """Row and column of every entry of the bordered matrix, in the order :meth:`_values`
        produces them, and the slots of the CSC arrays they are summed into (built once per mesh)."""
        n_x, n_coll, m, k = self.n_x, self.n_coll, self.m, self.k
        cyc = self.cycle
        rows, cols = [], []
        for c in range(self.defining.periods):
            rows.append(cyc._rows + c * n_coll)
            cols.append(cyc._cols + c * n_x)
        boundary_rows, boundary_cols = self.defining.boundary_entries(self)
        self._boundary = (np.concatenate(boundary_rows), np.concatenate(boundary_cols))  # the operator's
        rows += boundary_rows
        cols += boundary_cols
        border_r, border_c = np.meshgrid(np.arange(m), np.arange(k), indexing="ij")
        rows += [border_r.ravel(), m + border_c.ravel()]  # B, then C^T
        cols += [m + border_c.ravel(), border_r.ravel()]
        rows, cols = np.concatenate(rows), np.concatenate(cols)
        self._entries = (rows, cols)
        size = m + k
        key = cols.astype(np.int64) * size + rows
        unique, slot = np.unique(key, return_inverse=True)
        self._slot, self._nnz = slot, unique.size
        self._indices = (unique % size).astype(np.int32)
        counts = np.bincount(unique // size, minlength=size)
        self._indptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int32)

    def _values(self, u: np.ndarray) -> np.ndarray:
        cu = self.cycle_u(u)
        blocks, F, _, T = self.cycle.collocation_blocks(cu)
        parts = [blocks.ravel()] * self.defining.periods
        parts += self.defining.boundary_values(self, u, F)
        parts += [self.B.ravel(), self.C.ravel()]
        return np.concatenate(parts)

    def _bordered(self, u: np.ndarray) -> sp.csc_matrix:
        if not hasattr(self, "_slot"):
            self._structure()
        data = np.bincount(self._slot, weights=self._values(u), minlength=self._nnz)
        size = self.m + self.k
        return sp.csc_matrix((data, self._indices, self._indptr), shape=(size, size))

    def _operator(self, u: np.ndarray) -> BorderedOperator:
        """The bordered test matrix at u as an operator (its products without assembly; the sparse
        matrix assembled only if it is factored)."""
        if not hasattr(self, "_slot"):
            self._structure()
        cu = self.cycle_u(u)
        blocks, F, _, _ = self.cycle.collocation_blocks(cu)
        values = np.concatenate(self.defining.boundary_values(self, u, F))
        return BorderedOperator(self, blocks, *self._boundary, values, lambda: self._bordered(u))

    def _solve(self, M: BorderedOperator, rhs: np.ndarray, trans: bool, sweeps: int | None = None) -> np.ndarray | None:
        """M^-1 rhs (or M^-T rhs) by iterative refinement on the last LU factors (those of a nearby
        point: a Newton iterate, the previous point); None if the residual does not reach 1e-13
        of the solution (a looser 1e-12 leaves the test functions noisy enough to slow Newton), or
        stops shrinking fast (by 4 per sweep: the factors are too far off, better refactor)."""
        if self._lu is None:
            return None
        apply = M.rmatvec if trans else M.matvec
        mode = "T" if trans else "N"
        scale = max(float(np.abs(rhs).max()), 1e-300)
        sweeps = self.defining.refine_sweeps if sweeps is None else sweeps
        return refine(lambda b: self._lu.solve(b, trans=mode), apply, rhs,
                      lambda z: 1e-13 * scale * max(1.0, float(np.abs(z).max())), sweeps)

    def analyse(self, u: np.ndarray, left: bool = True) -> dict:
        """Kernel vectors V, the 2x2 (or 1x1) G and (``left``) the left vectors W of the bordered
        test matrix at u (memoised for the last u). The bordered matrix is factored afresh only
        when refinement on the last factors does not converge: most Newton iterates and trial
        points reuse them. The test values need only the right solve; gradients need both."""
        key = u.tobytes()
        if self._memo is not None and self._memo[0] == key and (not left or "W" in self._memo[1]):
            return self._memo[1]
        M = self._operator(u)
        k, m = self.k, self.m
        rhs = np.zeros((m + k, k))
        rhs[m:, :] = np.eye(k)
        out = self._memo[1] if self._memo is not None and self._memo[0] == key else {}
        right = out.get("_right")
        if right is None:
            right = self._solve(M, rhs, False)
        solved = right is not None and (not left or (lhs := self._solve(M, rhs, True)) is not None)
        if not solved:  # refactor; the solves are refined on the new factors too
            self._lu = self._factor(M, u)
            right = self._solve(M, rhs, False, FRESH_SWEEPS)
            lhs = self._solve(M, rhs, True, FRESH_SWEEPS) if left and right is not None else None
            if right is None or (left and lhs is None):  # fresh condensed factors not accurate: SuperLU
                self._lu = splu(M.sparse(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.1)
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

    def _gradients(self, u: np.ndarray, entries: list[tuple[int, int]], data: dict) -> list[np.ndarray]:
        """d g_ij / du = -W_i^T A_u V_j for each entry (i, j), their second derivatives taken together."""
        terms = [self.defining.gradient_terms(self, u, data["V"][:, j], data["W"][:, i]) for i, j in entries]
        seconds = iter(self.second_many(u, [pair for pairs, _ in terms for pair in pairs]))
        out = []
        for pairs, extra in terms:
            grad = -sum(next(seconds) for _ in pairs)
            out.append(grad + extra if extra is not None else grad)
        return out

    # -- curve problem ------------------------------------------------------------------------------
    def residual(self, u: np.ndarray) -> np.ndarray:
        cycle = self.cycle.residual(self.cycle_u(u))
        return np.concatenate([cycle, self.test_values(u)])

    def jacobian(self, u: np.ndarray):
        data = self.analyse(u)
        rows = np.array(self._gradients(u, self.entries, data))
        full = np.tile(np.arange(self.size, dtype=np.int32), rows.shape[0])  # dense rows, zeros kept: a fixed pattern
        dense = sp.csr_matrix((rows.ravel(), full, np.arange(rows.shape[0] + 1, dtype=np.int32) * self.size),
                              shape=rows.shape)
        return sp.vstack([self.cycle_jacobian(u), dense], format="csr")

    def accept(self, u: np.ndarray) -> None:
        self.cycle.accept(self.cycle_u(u))
        if self.defining.reads_phase:
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
        keys = [(i, j) for i in range(2) for j in range(2)]
        grads = {key: g @ null for key, g in zip(keys, self._gradients(u, keys, data))}
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

    def special_point(self, kind: PointKind, u: np.ndarray, index: int, extra: dict | None = None,
                      located: bool | None = None) -> SpecialPoint:
        """A special point of the curve at u, point ``index`` of the curve: p1, and p2, the cycle's
        period, extremes and multipliers (and kappa) in its data, ``extra`` after them."""
        n_x = self.n_x
        mu = self.multipliers(u)
        xmax, xmin = self.extremes(u)
        data = {"p2": float(u[n_x + 2]), "period": float(u[n_x]), "x_max": xmax.tolist(), "x_min": xmin.tolist(),
                "multipliers_abs": np.abs(mu[1:]).tolist(), **(extra or {})}
        if self.defining.has_kappa:
            data["kappa"] = self.kappa(u)
        return SpecialPoint(kind, float(u[n_x + 1]), index, data, located)

    def rebuilt(self, mesh: Mesh) -> "CycleCurveProblem":
        other = CycleCurveProblem(self.system, self.kind, mesh, self.cycle.scale, self.cycle.T_scale, self.p_scale,
                                  float(self.weights[-1]) if self.defining.has_kappa else 1.0)
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
        other.C = np.linalg.qr(self.defining.transferred_border(self, nodes))[0]
