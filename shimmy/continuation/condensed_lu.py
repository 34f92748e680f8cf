"""LU factors of collocation matrices by condensation of the mesh intervals (AUTO's elimination).

Every matrix the engine solves for periodic orbits has the same shape: a *chain* of links (the
mesh intervals; in the torus test the two periods joined by a continuity condition), each link
a block of rows touching only its own unknowns (the nodes inside the interval), the two boundary
nodes it shares with its neighbours, and a few *global* unknowns (period, parameters, border
columns); plus a few global rows touching anything (periodicity, phase, borders, test
functions). A general sparse LU (SuperLU) spends most of its time on bookkeeping for these
small blocks. This module factors them directly, as AUTO does (Doedel et al.):

1. per link: Gaussian elimination with partial pivoting of the interior unknowns within the
   link's rows (the n rows left over relate only the two boundary nodes and the globals), and
   the same elimination of the interior columns from the global rows;
2. along the chain: the boundary nodes 1 .. L-1 are eliminated one after the other, each from
   the 2n rows that touch it (the rows left over from the previous step and the next link's),
   with partial pivoting among those 2n rows;
3. the last 2n + g rows, in the first and last boundary nodes and the globals, by dense LU.

Pivoting is restricted to the rows of a link (stage 1) and of two neighbouring links (stage 2):
the stability of AUTO's condensation, not of full partial pivoting. A singular pivot raises
``numpy.linalg.LinAlgError``. Solves with the matrix and with its transpose reuse the
factors; the transposed solve runs the eliminations backwards.

``ChainLayout`` says which row and column of the matrix plays which role (built by the
problem, once per mesh); ``CondensedLU`` factors a scipy.sparse matrix of that layout.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit


@dataclass(eq=False)
class ChainLayout:
    """Roles of the rows and columns of a square matrix of size ``size`` with the chain shape.

    ``link_rows`` (L, r_max): rows of each link, in any order (-1 padding);
    ``interior_cols`` (L, ni_max): the link's interior unknowns (-1 padding);
    ``node_cols`` (L + 1, n): the boundary nodes (link l joins nodes l and l + 1);
    ``global_cols`` (g,); ``global_rows`` (q,) with q = n + g (the matrix is square).
    A link with i interior unknowns has i + n rows.
    """

    size: int
    link_rows: np.ndarray
    interior_cols: np.ndarray
    node_cols: np.ndarray
    global_cols: np.ndarray
    global_rows: np.ndarray

    def __post_init__(self):
        for name in ("link_rows", "interior_cols", "node_cols", "global_cols", "global_rows"):
            setattr(self, name, np.asarray(getattr(self, name), dtype=np.int64))
        self.n = self.node_cols.shape[1]
        self.links = self.link_rows.shape[0]
        self.n_interior = (self.interior_cols >= 0).sum(axis=1).astype(np.int64)
        self.r_max = self.link_rows.shape[1]
        self.ni_max = self.interior_cols.shape[1]
        self.g, self.q = self.global_cols.size, self.global_rows.size
        for name, table in (("link_rows", self.link_rows), ("interior_cols", self.interior_cols)):
            used = table >= 0
            if np.any(used[:, 1:] & ~used[:, :-1]):
                raise ValueError(f"chain layout: {name} has -1 padding before an entry (pad at the end only)")
        rows = np.concatenate([self.link_rows[self.link_rows >= 0], self.global_rows])
        cols = np.concatenate([self.interior_cols[self.interior_cols >= 0], self.node_cols.ravel(), self.global_cols])
        for name, roles in (("row", rows), ("column", cols)):
            if roles.size != self.size or np.unique(roles).size != self.size or roles.min() < 0 \
                    or roles.max() >= self.size:
                raise ValueError(f"chain layout: every {name} needs exactly one role")
        rows_used = (self.link_rows >= 0).sum(axis=1)
        if np.any(rows_used != self.n_interior + self.n) or self.q != self.n + self.g:
            raise ValueError("chain layout: a link needs n rows more than interior unknowns, "
                             "and the global rows must number n + g")
        # role of every column: (link or node or global index, position in the link's block)
        self.width = 2 * self.n + self.ni_max + self.g
        self._col_kind = np.full(self.size, -1, np.int64)  # 0 node, 1 interior, 2 global
        self._col_index = np.zeros(self.size, np.int64)
        self._col_pos = np.zeros(self.size, np.int64)
        for kind, cols in ((0, self.node_cols), (1, self.interior_cols)):
            owner, pos = np.nonzero(cols >= 0)
            c = cols[owner, pos]
            self._col_kind[c], self._col_index[c], self._col_pos[c] = kind, owner, pos
        self._col_kind[self.global_cols] = 2
        self._col_pos[self.global_cols] = np.arange(self.g)
        if np.any(self._col_kind < 0):
            raise ValueError("chain layout: some columns have no role")
        self._row_link = np.full(self.size, -1, np.int64)
        self._row_local = np.zeros(self.size, np.int64)
        link, local = np.nonzero(self.link_rows >= 0)
        r = self.link_rows[link, local]
        self._row_link[r], self._row_local[r] = link, local
        self._row_local[self.global_rows] = np.arange(self.q)
        if np.sum(self._row_link >= 0) + self.q != self.size:
            raise ValueError("chain layout: some rows have no role")
        self._pattern: tuple | None = None

    @property
    def buffer_size(self) -> int:
        return self.links * self.r_max * self.width + self.q * self.size

    def destinations(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """Slot in the factor's input buffer of every entry (rows[i], cols[i]): link blocks
        [left node | interior | right node | globals], then the global rows in full."""
        link = self._row_link[rows]
        in_link = link >= 0
        kind, index, pos = self._col_kind[cols], self._col_index[cols], self._col_pos[cols]
        n, ni = self.n, self.ni_max
        col_in_block = np.full(rows.size, -1, np.int64)
        col_in_block[(kind == 0) & (index == link)] = pos[(kind == 0) & (index == link)]
        right = (kind == 0) & (index == link + 1)
        col_in_block[right] = n + ni + pos[right]
        inner = (kind == 1) & (index == link)
        col_in_block[inner] = n + pos[inner]
        glob = kind == 2
        col_in_block[glob] = 2 * n + ni + pos[glob]
        if np.any(in_link & (col_in_block < 0)):
            raise ValueError("matrix does not have the chain layout: a link row touches another link's unknowns")
        dest = np.where(in_link, (link * self.r_max + self._row_local[rows]) * self.width + col_in_block,
                        self.links * self.r_max * self.width + self._row_local[rows] * self.size + cols)
        return dest

    def buffer(self, matrix) -> np.ndarray:
        """The factor's input (link blocks and global rows) from a scipy.sparse CSR or CSC matrix."""
        fmt = matrix.format
        if fmt not in ("csr", "csc"):
            matrix = matrix.tocsr()
            fmt = "csr"
        indptr, indices = matrix.indptr, matrix.indices
        cached = self._pattern
        if cached is None or cached[0] != fmt or not (np.array_equal(cached[1], indptr)
                                                      and np.array_equal(cached[2], indices)):
            major = np.repeat(np.arange(indptr.size - 1), np.diff(indptr))
            rows, cols = (major, indices) if fmt == "csr" else (indices, major)
            self._pattern = cached = (fmt, indptr.copy(), indices.copy(), self.destinations(rows, cols))
        return np.bincount(cached[3], weights=matrix.data, minlength=self.buffer_size)


def collocation_layout(ntst: int, ncol: int, n: int, size: int, copies: list[tuple[int, int]],
                       join_rows: list[np.ndarray], global_cols: np.ndarray, global_rows: np.ndarray) -> ChainLayout:
    """The layout of a collocation matrix: ``copies`` of the orbit's mesh, each given by the first
    row of its collocation equations ((interval, point, component) order) and the first column of
    its nodes ((node, component) order), joined one to the next by the n rows ``join_rows[i]``
    (e.g. continuity of a second period); the remaining rows and columns are the globals."""
    m, N = ncol, ntst
    comp = np.arange(n)
    link_rows, interior, nodes = [], [], []
    for c, (row0, col0) in enumerate(copies):
        link_rows.append(row0 + np.arange(N * m * n).reshape(N, m * n))
        interior.append(col0 + ((np.arange(N)[:, None] * m + np.arange(1, m)[None, :])[:, :, None] * n
                                + comp).reshape(N, -1))
        nodes.append(col0 + (np.arange(N + 1) * m)[:, None] * n + comp)
        if c + 1 < len(copies):  # a join: a link of n rows without interior unknowns
            link_rows.append(np.full((1, m * n), -1))
            link_rows[-1][0, :n] = join_rows[c]
            interior.append(np.full((1, (m - 1) * n), -1))
    return ChainLayout(size, np.vstack(link_rows), np.vstack(interior), np.vstack(nodes), np.asarray(global_cols),
                       np.asarray(global_rows))


class CondensedLU:
    """Factors of a square sparse matrix with a :class:`ChainLayout`; ``solve(b, trans)``
    like SuperLU's ("N": M x = b, "T": M^T x = b), b of shape (size,) or (size, k)."""

    def __init__(self, matrix, layout: ChainLayout, parts: tuple[np.ndarray, np.ndarray] | None = None):
        """``parts``: instead of ``matrix`` (None then), the link blocks (L, r_max, width: columns
        [left node | interior | right node | globals], rows in the layout's order) and the global
        rows in full (q, size), for a caller that has them without assembling the matrix (both are
        overwritten by the factors)."""
        self.layout = lay = layout
        if parts is None:
            if matrix.shape != (layout.size, layout.size):
                raise ValueError(f"matrix of shape {matrix.shape} for a chain layout of size {layout.size}")
            buf = lay.buffer(matrix)
            split = lay.links * lay.r_max * lay.width
            self._A = buf[:split].reshape(lay.links, lay.r_max, lay.width)
            self._Q = buf[split:].reshape(lay.q, lay.size)
        else:
            self._A, self._Q = parts
            if self._A.shape != (lay.links, lay.r_max, lay.width) or self._Q.shape != (lay.q, lay.size):
                raise ValueError("link blocks or global rows of the wrong shape for the chain layout")
        out = _factor(self._A, self._Q, lay.n_interior, lay.n, lay.ni_max, lay.g, lay.interior_cols,
                      lay.node_cols, lay.global_cols)
        status = out[-1]
        if status != 0:
            raise np.linalg.LinAlgError("condensed LU: singular pivot (the matrix is singular or nearly so)")
        self._factors = out[:-1]

    def solve(self, b: np.ndarray, trans: str = "N") -> np.ndarray:
        lay = self.layout
        if trans not in ("N", "T"):
            raise ValueError(f"trans must be 'N' or 'T', got {trans!r}")
        b = np.asarray(b, float)
        if b.shape[0] != lay.size or b.ndim > 2:
            raise ValueError(f"right-hand side of shape {b.shape} for a matrix of size {lay.size}")
        flat = b.ndim == 1
        B = np.ascontiguousarray(b.reshape(lay.size, -1))
        X = _solve(trans == "T", self._A, *self._factors, B, lay.n_interior, lay.n, lay.ni_max, lay.g, lay.link_rows,
                   lay.global_rows, lay.interior_cols, lay.node_cols, lay.global_cols)
        return X.ravel() if flat else X

    def monodromy(self) -> np.ndarray:
        """P_(L-1) ... P_0, P_k mapping node k to node k + 1 through link k's rows with the global
        columns left out: for the Newton matrix of one periodic orbit (links = its mesh intervals,
        in order), the monodromy matrix of the orbit (the same numbers as :func:`monodromy` on its
        blocks, whose interior elimination the factors hold). Meaningless for other chains (the two
        periods of a torus test matrix)."""
        lay = self.layout
        return _transfer_product(_reduced_rows(self._A, lay.n_interior, lay.n, lay.ni_max), lay.n)


#: A pivot below this fraction of its column's size in the whole matrix is taken for zero (the
#: pivoting is restricted to a link's rows, or two links', so a tiny one may be rounding where the
#: whole matrix is regular): the factorisation stops and the caller falls back to SuperLU.
PIVOT_TOL = 1e-13

# ------------------------------------------------------------------ compiled kernels
@njit(cache=True, error_model="numpy")
def _lu_columns(M, rows, col0, ncols, perm, colscale):
    """In place: partial-pivot elimination of columns col0 .. col0 + ncols - 1 of M[:rows]
    (all other columns transformed alike; multipliers stored below the pivots). 1 if singular:
    a pivot not above PIVOT_TOL times ``colscale[c]``, the size of that column in the whole
    matrix (its entries in rows this elimination cannot pivot on included)."""
    width = M.shape[1]
    for c in range(ncols):
        col = col0 + c
        p = c
        big = abs(M[c, col])
        for i in range(c + 1, rows):
            if abs(M[i, col]) > big:
                big, p = abs(M[i, col]), i
        perm[c] = p
        if not big > PIVOT_TOL * colscale[c] or not np.isfinite(big):
            return 1
        if p != c:  # the multipliers of earlier columns stay where they were made
            for j in range(width):
                if j < col0 or j >= col:
                    M[c, j], M[p, j] = M[p, j], M[c, j]
        piv = M[c, col]
        for i in range(c + 1, rows):
            f = M[i, col] / piv
            M[i, col] = f
            if f != 0.0:
                for j in range(col0):
                    M[i, j] -= f * M[c, j]
                for j in range(col + 1, width):
                    M[i, j] -= f * M[c, j]
    return 0


@njit(cache=True, error_model="numpy")
def _column_sizes(M, rows, col0, ncols, G, gcols):
    """max |entry| of columns col0 .. col0 + ncols - 1 over M[:rows] and, column c, over G[:, gcols[c]]
    (the global rows' entries of that unknown; G may have no rows)."""
    out = np.zeros(ncols)
    for c in range(ncols):
        big = 0.0
        for i in range(rows):
            big = max(big, abs(M[i, col0 + c]))
        for a in range(G.shape[0]):
            big = max(big, abs(G[a, gcols[c]]))
        out[c] = big
    return out


@njit(cache=True, error_model="numpy")
def _row_times_inverse_upper(Q, M, col0, ncols, C):
    """C (q, ncols) = Q (q, ncols) U^-1, U the upper triangle of M[:ncols, col0:col0 + ncols]."""
    for a in range(Q.shape[0]):
        for c in range(ncols):
            s = Q[a, c]
            for k in range(c):
                s -= C[a, k] * M[k, col0 + c]
            C[a, c] = s / M[c, col0 + c]


@njit(cache=True, error_model="numpy")
def _factor(A, Q, nint, n, nimax, g, int_cols, node_cols, glob_cols):
    L = A.shape[0]
    q = Q.shape[0]
    right0, glob0 = n + nimax, 2 * n + nimax
    perm1 = np.zeros((L, max(nimax, 1)), np.int64)
    C1 = np.zeros((L, q, max(nimax, 1)))
    w2 = 3 * n + g
    M2 = np.zeros((L, 2 * n, w2))  # stage 2, columns [node k | node 0 | node k+1 | globals]
    perm2 = np.zeros((L, n), np.int64)
    C2 = np.zeros((L, q, n))
    size = 2 * n + g
    F = np.zeros((size, size))
    permF = np.zeros(size, np.int64)
    # global rows by role: nodes (q, L+1, n), globals (q, g)
    Qn = np.zeros((q, L + 1, n))
    Qg = np.zeros((q, g))
    for a in range(q):
        for k in range(L + 1):
            for c in range(n):
                Qn[a, k, c] = Q[a, node_cols[k, c]]
        for c in range(g):
            Qg[a, c] = Q[a, glob_cols[c]]
    Red = np.zeros((L, n, 2 * n + g))  # leftover link rows: [left | right | globals]
    Qi = np.zeros((q, max(nimax, 1)))
    for link in range(L):
        ni = nint[link]
        M = A[link]
        if ni > 0:
            sizes = _column_sizes(M, ni + n, n, ni, Q, int_cols[link])
            if _lu_columns(M, ni + n, n, ni, perm1[link], sizes):
                return perm1, C1, M2, perm2, C2, F, permF, 1
            for a in range(q):
                for c in range(ni):
                    Qi[a, c] = Q[a, int_cols[link, c]]
            C = C1[link]
            _row_times_inverse_upper(Qi, M, n, ni, C)
            for a in range(q):
                for k in range(ni):
                    f = C[a, k]
                    if f != 0.0:
                        for c in range(n):
                            Qn[a, link, c] -= f * M[k, c]
                            Qn[a, link + 1, c] -= f * M[k, right0 + c]
                        for c in range(g):
                            Qg[a, c] -= f * M[k, glob0 + c]
        for i in range(n):
            for c in range(n):
                Red[link, i, c] = M[ni + i, c]
                Red[link, i, n + c] = M[ni + i, right0 + c]
            for c in range(g):
                Red[link, i, 2 * n + c] = M[ni + i, glob0 + c]
    # stage 2: nodes 1 .. L-1
    run = np.zeros((n, 2 * n + g))  # [node 0 | current node | globals]
    for i in range(n):
        for c in range(2 * n + g):
            run[i, c] = Red[0, i, c]
    for k in range(1, L):
        S = M2[k]
        for i in range(n):
            for c in range(n):
                S[i, c] = run[i, n + c]
                S[i, n + c] = run[i, c]
                S[n + i, c] = Red[k, i, c]
                S[n + i, 2 * n + c] = Red[k, i, n + c]
            for c in range(g):
                S[i, 3 * n + c] = run[i, 2 * n + c]
                S[n + i, 3 * n + c] = Red[k, i, 2 * n + c]
        if _lu_columns(S, 2 * n, 0, n, perm2[k], _column_sizes(S, 2 * n, 0, n, Qn[:, k, :], np.arange(n))):
            return perm1, C1, M2, perm2, C2, F, permF, 1
        C = C2[k]
        _row_times_inverse_upper(Qn[:, k, :], S, 0, n, C)
        for a in range(q):
            for j in range(n):
                f = C[a, j]
                if f != 0.0:
                    for c in range(n):
                        Qn[a, 0, c] -= f * S[j, n + c]
                        Qn[a, k + 1, c] -= f * S[j, 2 * n + c]
                    for c in range(g):
                        Qg[a, c] -= f * S[j, 3 * n + c]
        for i in range(n):
            for c in range(n):
                run[i, c] = S[n + i, n + c]
                run[i, n + c] = S[n + i, 2 * n + c]
            for c in range(g):
                run[i, 2 * n + c] = S[n + i, 3 * n + c]
    # final block: rows [run; global rows], columns [node 0 | node L | globals]
    for i in range(n):
        for c in range(size):
            F[i, c] = run[i, c]
    for a in range(q):
        for c in range(n):
            F[n + a, c] = Qn[a, 0, c]
            F[n + a, n + c] = Qn[a, L, c]
        for c in range(g):
            F[n + a, 2 * n + c] = Qg[a, c]
    status = _lu_columns(F, size, 0, size, permF, _column_sizes(F, size, 0, size, F[:0], np.arange(size)))
    return perm1, C1, M2, perm2, C2, F, permF, status


@njit(cache=True, error_model="numpy")
def _forward_rows(M, rows, ncols, col0, perm, v):
    """v (rows,) <- the row operations of the elimination of M's columns col0.. applied to v."""
    for c in range(ncols):
        p = perm[c]
        if p != c:
            v[c], v[p] = v[p], v[c]
        for i in range(c + 1, rows):
            f = M[i, col0 + c]
            if f != 0.0:
                v[i] -= f * v[c]


@njit(cache=True, error_model="numpy")
def _backward_rows(M, rows, ncols, col0, perm, v):
    """Transpose of :func:`_forward_rows`: v <- E^T v for the same row operations E."""
    for c in range(ncols - 1, -1, -1):
        for i in range(c + 1, rows):
            f = M[i, col0 + c]
            if f != 0.0:
                v[c] -= f * v[i]
        p = perm[c]
        if p != c:
            v[c], v[p] = v[p], v[c]


@njit(cache=True, error_model="numpy")
def _upper_solve(M, ncols, col0, v):
    """v <- U^-1 v, U the upper triangle of M[:ncols, col0:col0 + ncols]."""
    for c in range(ncols - 1, -1, -1):
        s = v[c]
        for k in range(c + 1, ncols):
            s -= M[c, col0 + k] * v[k]
        v[c] = s / M[c, col0 + c]


@njit(cache=True, error_model="numpy")
def _upper_transposed_solve(M, ncols, col0, v):
    """v <- U^-T v."""
    for c in range(ncols):
        s = v[c]
        for k in range(c):
            s -= M[k, col0 + c] * v[k]
        v[c] = s / M[c, col0 + c]


@njit(cache=True, error_model="numpy")
def _solve_one(A, perm1, C1, M2, perm2, C2, F, permF, B, nint, n, nimax, g, link_rows, glob_rows,
               int_cols, node_cols, glob_cols):
    L = A.shape[0]
    q = glob_rows.size
    right0, glob0 = n + nimax, 2 * n + nimax
    rmax = A.shape[1]
    V = np.zeros((L, rmax))
    bq = np.zeros((q))
    for a in range(q):
        bq[a] = B[glob_rows[a]]
    for link in range(L):
        ni = nint[link]
        v = V[link]
        for i in range(ni + n):
            v[i] = B[link_rows[link, i]]
        if ni > 0:
            _forward_rows(A[link], ni + n, ni, n, perm1[link], v)
            for a in range(q):
                for k in range(ni):
                    f = C1[link, a, k]
                    if f != 0.0:
                        bq[a] -= f * v[k]
    # stage 2
    S2 = np.zeros((L, 2 * n))
    run = np.zeros((n))
    for i in range(n):
        run[i] = V[0, nint[0] + i]
    for k in range(1, L):
        s = S2[k]
        for i in range(n):
            s[i] = run[i]
            s[n + i] = V[k, nint[k] + i]
        _forward_rows(M2[k], 2 * n, n, 0, perm2[k], s)
        for a in range(q):
            for i in range(n):
                f = C2[k, a, i]
                if f != 0.0:
                    bq[a] -= f * s[i]
        for i in range(n):
            run[i] = s[n + i]
    size = 2 * n + g
    z = np.zeros((size))
    for i in range(n):
        z[i] = run[i]
    for a in range(q):
        z[n + a] = bq[a]
    _forward_rows(F, size, size, 0, permF, z)
    _upper_solve(F, size, 0, z)
    X = np.zeros((L + 1, n))
    for c in range(n):
        X[0, c] = z[c]
        X[L, c] = z[n + c]
    xg = z[2 * n:]
    for k in range(L - 1, 0, -1):
        S = M2[k]
        r = np.zeros((n))
        for i in range(n):
            s = S2[k, i]
            for c in range(n):
                s -= S[i, n + c] * X[0, c] + S[i, 2 * n + c] * X[k + 1, c]
            for c in range(g):
                s -= S[i, 3 * n + c] * xg[c]
            r[i] = s
        _upper_solve(S, n, 0, r)
        for i in range(n):
            X[k, i] = r[i]
    out = np.zeros(B.size)
    for k in range(L + 1):
        for c in range(n):
            out[node_cols[k, c]] = X[k, c]
    for c in range(g):
        out[glob_cols[c]] = xg[c]
    for link in range(L):
        ni = nint[link]
        if ni == 0:
            continue
        M = A[link]
        r = np.zeros((ni))
        for i in range(ni):
            s = V[link, i]
            for c in range(n):
                s -= M[i, c] * X[link, c] + M[i, right0 + c] * X[link + 1, c]
            for c in range(g):
                s -= M[i, glob0 + c] * xg[c]
            r[i] = s
        _upper_solve(M, ni, n, r)
        for i in range(ni):
            out[int_cols[link, i]] = r[i]
    return out


@njit(cache=True, error_model="numpy")
def _solve_transposed_one(A, perm1, C1, M2, perm2, C2, F, permF, B, nint, n, nimax, g, link_rows,
                          glob_rows, int_cols, node_cols, glob_cols):
    L = A.shape[0]
    q = glob_rows.size
    right0, glob0 = n + nimax, 2 * n + nimax
    # 1. U~^T w = b, in the order of U~'s columns: interiors, nodes 1 .. L-1, final
    W1 = np.zeros((L, max(nimax, 1)))
    for link in range(L):
        ni = nint[link]
        for i in range(ni):
            W1[link, i] = B[int_cols[link, i]]
        if ni > 0:
            _upper_transposed_solve(A[link], ni, n, W1[link])
    W2 = np.zeros((L, n))
    for k in range(1, L):
        w = W2[k]
        for c in range(n):
            s = B[node_cols[k, c]]
            Ml, Mr = A[k - 1], A[k]
            for i in range(nint[k - 1]):
                s -= Ml[i, right0 + c] * W1[k - 1, i]
            for i in range(nint[k]):
                s -= Mr[i, c] * W1[k, i]
            if k >= 2:
                S = M2[k - 1]
                for i in range(n):
                    s -= S[i, 2 * n + c] * W2[k - 1, i]
            w[c] = s
        _upper_transposed_solve(M2[k], n, 0, w)
    size = 2 * n + g
    z = np.zeros((size))
    for c in range(n):
        s0 = B[node_cols[0, c]]
        sL = B[node_cols[L, c]]
        for i in range(nint[0]):
            s0 -= A[0, i, c] * W1[0, i]
        for i in range(nint[L - 1]):
            sL -= A[L - 1, i, right0 + c] * W1[L - 1, i]
        for k in range(1, L):
            for i in range(n):
                s0 -= M2[k, i, n + c] * W2[k, i]
        if L >= 2:
            for i in range(n):
                sL -= M2[L - 1, i, 2 * n + c] * W2[L - 1, i]
        z[c] = s0
        z[n + c] = sL
    for c in range(g):
        s = B[glob_cols[c]]
        for link in range(L):
            for i in range(nint[link]):
                s -= A[link, i, glob0 + c] * W1[link, i]
        for k in range(1, L):
            for i in range(n):
                s -= M2[k, i, 3 * n + c] * W2[k, i]
        z[2 * n + c] = s
    _upper_transposed_solve(F, size, 0, z)
    _backward_rows(F, size, size, 0, permF, z)
    # 2. the eliminations transposed, last first
    aq = z[n:]
    arun = np.zeros((n))
    for i in range(n):
        arun[i] = z[i]
    out = np.zeros(B.size)
    for a in range(q):
        out[glob_rows[a]] = aq[a]
    Ared = np.zeros((L, n))
    s = np.zeros((2 * n))
    for k in range(L - 1, 0, -1):
        for i in range(n):
            t = W2[k, i]
            for a in range(q):
                t -= C2[k, a, i] * aq[a]
            s[i] = t
            s[n + i] = arun[i]
        _backward_rows(M2[k], 2 * n, n, 0, perm2[k], s)
        for i in range(n):
            arun[i] = s[i]
            Ared[k, i] = s[n + i]
    for i in range(n):
        Ared[0, i] = arun[i]
    v = np.zeros((A.shape[1]))
    for link in range(L):
        ni = nint[link]
        for i in range(ni):
            t = W1[link, i]
            for a in range(q):
                t -= C1[link, a, i] * aq[a]
            v[i] = t
        for i in range(n):
            v[ni + i] = Ared[link, i]
        if ni > 0:
            _backward_rows(A[link], ni + n, ni, n, perm1[link], v)
        for i in range(ni + n):
            out[link_rows[link, i]] = v[i]
    return out


@njit(cache=True, error_model="numpy")
def _solve(transposed, A, perm1, C1, M2, perm2, C2, F, permF, B, nint, n, nimax, g, link_rows, glob_rows,
           int_cols, node_cols, glob_cols):
    """M^-1 B (or M^-T B) column by column."""
    out = np.empty_like(B)
    for j in range(B.shape[1]):
        b = B[:, j].copy()
        if transposed:
            out[:, j] = _solve_transposed_one(A, perm1, C1, M2, perm2, C2, F, permF, b, nint, n, nimax, g, link_rows,
                                              glob_rows, int_cols, node_cols, glob_cols)
        else:
            out[:, j] = _solve_one(A, perm1, C1, M2, perm2, C2, F, permF, b, nint, n, nimax, g, link_rows, glob_rows,
                                   int_cols, node_cols, glob_cols)
    return out


@njit(cache=True, error_model="numpy")
def _transfer_product(R, n):
    """P_(N-1) ... P_0 with P_j = -D_j^-1 C_j from the rows R[j] = [C_j | D_j] (N, n, 2n) left after
    eliminating interval j's interior nodes (C_j x_first + D_j x_last = 0); NaN if a D_j is singular."""
    N = R.shape[0]
    M = np.eye(n)
    p2 = np.zeros(n, np.int64)
    for j in range(N):
        S = np.zeros((n, 2 * n))  # elimination on [D | -C]
        for i in range(n):
            for c in range(n):
                S[i, c] = R[j, i, n + c]
                S[i, n + c] = -R[j, i, c]
        if _lu_columns(S, n, 0, n, p2, _column_sizes(S, n, 0, n, S[:0], np.arange(n))):
            return np.full((n, n), np.nan)
        P = S[:, n:].copy()
        for c in range(n - 1, -1, -1):
            for k in range(c + 1, n):
                for a in range(n):
                    P[c, a] -= S[c, k] * P[k, a]
            for a in range(n):
                P[c, a] /= S[c, c]
        M = P @ M
    return M


@njit(cache=True, error_model="numpy")
def monodromy(blocks, n):
    """The monodromy matrix P_(N-1) ... P_0 from the linearised collocation blocks (N, m n, (m + 1) n)
    of the intervals (columns: the interval's nodes in order): P_j maps x at an interval's first node
    to x at its last, found by eliminating the interior nodes (the first stage of the condensed LU)
    and solving the n rows left over. NaN where an interval's block is singular."""
    N, rows, width = blocks.shape
    ni = rows - n
    perm = np.zeros(max(ni, 1), np.int64)
    B = blocks.copy()
    for j in range(N):
        if _lu_columns(B[j], rows, n, ni, perm, _column_sizes(B[j], rows, n, ni, B[j][:0], np.arange(ni))):
            return np.full((n, n), np.nan)
    return _transfer_product(_reduced_rows(B, np.full(N, ni), n, ni), n)


@njit(cache=True, error_model="numpy")
def _reduced_rows(A, nint, n, nimax):
    """[left node | right node] of the rows each link keeps after its interior elimination (stage 1
    of :func:`_factor`, left in A), (L, n, 2n)."""
    L = A.shape[0]
    right0 = n + nimax
    R = np.zeros((L, n, 2 * n))
    for link in range(L):
        ni = nint[link]
        for i in range(n):
            for c in range(n):
                R[link, i, c] = A[link, ni + i, c]
                R[link, i, n + c] = A[link, ni + i, right0 + c]
    return R
