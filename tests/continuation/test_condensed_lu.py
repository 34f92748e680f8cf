"""The condensed LU of collocation matrices against dense solves, on the matrices the engine builds."""

import math

import numpy as np
import pytest
import scipy.sparse as sp
from textbook_systems import bautin, flip_two_parameter, period_doubling, torus_two_parameter

from shimmy.continuation import CycleCurveProblem, Mesh, PeriodicProblem
from shimmy.continuation.condensed_lu import ChainLayout, CondensedLU, collocation_layout, monodromy
from shimmy.continuation.core import _Bordered, condensed_factors


def assert_solves(matrix, lu, rng, columns=3):
    """M x = b and M^T x = b to a residual of 1e-13 of the solution's size times cond(M), for one
    and for several right-hand sides."""
    dense = matrix.toarray()
    bound = 1e-15 * np.linalg.cond(dense) + 1e-13
    B = rng.standard_normal((dense.shape[0], columns))
    for trans, op in (("N", dense), ("T", dense.T)):
        X = lu.solve(B, trans=trans)
        assert X.shape == B.shape
        assert np.abs(op @ X - B).max() <= bound * np.abs(X).max()
        x = lu.solve(B[:, 0], trans=trans)
        assert x.shape == (dense.shape[0],)
        np.testing.assert_allclose(x, X[:, 0], rtol=0, atol=1e-12 * np.abs(x).max())


def orbit_problem(mesh: Mesh):
    system = period_doubling()
    problem = PeriodicProblem(system, mesh, np.ones(system.n), 1.0, 1.0)
    theta = 2 * np.pi * mesh.node_times
    X = np.column_stack([np.cos(theta), np.sin(theta), 0.3 * np.sin(2 * theta), 0.2 * np.cos(theta)])
    problem.accept(problem.pack(X, 6.0, 0.4))
    return problem, problem.pack(X + 0.05 * np.sin(3 * theta)[:, None], 6.1, 0.45)


@pytest.mark.parametrize("points,ncol", [(np.linspace(0, 1, 11), 4), (np.array([0.0, 0.2, 0.45, 0.7, 1.0]), 3),
                                         (np.array([0.0, 0.5, 1.0]), 2)])
def test_bordered_collocation_jacobian_is_solved_like_a_dense_matrix(points, ncol):
    """The Newton matrix [F_u; row] of a periodic orbit (uniform and non-uniform meshes, down to
    two intervals), solved and transpose-solved by the condensed LU."""
    problem, u = orbit_problem(Mesh(points, ncol))
    rng = np.random.default_rng(3)
    row = rng.standard_normal(u.size)
    matrix = sp.vstack([problem.jacobian(u), sp.csr_matrix(row[None, :])], format="csr")
    assert_solves(matrix, CondensedLU(matrix, problem.chain_layout), rng)
    # and through the corrector's bordered factors, which use it, and the factors condensed
    # straight from the collocation blocks without assembling the matrix
    b = rng.standard_normal(u.size)
    direct = problem.factor_bordered(u, row)
    assert isinstance(direct, CondensedLU)  # not the SuperLU fallback
    for lu in (_Bordered(problem.jacobian(u), row), direct):
        x = lu.solve(b)
        np.testing.assert_allclose(matrix @ x, b, atol=1e-12 * np.abs(x).max())
        assert lu.row is row


@pytest.mark.parametrize("kind,system,kappa", [("LPC", bautin, None), ("PD", flip_two_parameter, None),
                                               ("NS", torus_two_parameter, 0.3)])
def test_bordered_test_matrices_of_cycle_curves_are_solved_like_dense_matrices(kind, system, kappa):
    """The bordered test matrices [[A, B], [C^T, 0]]: LPC (period column), PD (anti-periodic
    rows), NS (two periods joined by continuity rows), and the curves' Newton matrices."""
    system = system()
    mesh = Mesh.uniform(6, 3)
    problem = CycleCurveProblem(system, kind, mesh, np.ones(system.n), 2 * np.pi, np.ones(2))
    theta = 2 * np.pi * mesh.node_times
    X = np.zeros((mesh.n_nodes, system.n))
    X[:, 0], X[:, 1] = np.cos(theta), np.sin(theta)
    u = np.concatenate([X.ravel(), [2 * np.pi, 0.04, 0.2]] + ([[kappa]] if kind == "NS" else []))
    problem.cycle.accept(problem.cycle_u(u))
    rng = np.random.default_rng(5)
    u = u + 1e-2 * rng.standard_normal(u.size)
    test_matrix = problem._bordered(u)
    assert_solves(test_matrix, CondensedLU(test_matrix, problem.test_layout), rng)
    row = rng.standard_normal(u.size)
    newton = sp.vstack([problem.jacobian(u), sp.csr_matrix(row[None, :])], format="csr")
    assert_solves(newton, CondensedLU(newton, problem.chain_layout), rng)
    b = rng.standard_normal(u.size)  # factored straight from the blocks and gradients, without assembly
    direct = problem.factor_bordered(u, row)
    assert isinstance(direct, CondensedLU)  # not the SuperLU fallback
    x = direct.solve(b)
    np.testing.assert_allclose(newton @ x, b, atol=1e-11 * np.abs(x).max())


@pytest.mark.parametrize("kind,system,kappa", [("LPC", bautin, None), ("PD", flip_two_parameter, None),
                                               ("NS", torus_two_parameter, 0.3)])
def test_the_test_matrix_applied_without_assembly_is_the_assembled_matrix(kind, system, kappa):
    """M z and M^T z from the collocation blocks and boundary entries (the refinement's products)
    equal the assembled sparse matrix's, for one and several right-hand sides, on a graded mesh; the
    condensed factors made from the same entries solve with the assembled matrix."""
    system = system()
    mesh = Mesh(np.sort(np.concatenate([[0.0, 1.0], np.random.default_rng(2).uniform(0, 1, 6)])), 3)
    problem = CycleCurveProblem(system, kind, mesh, np.ones(system.n), 2 * np.pi, np.ones(2))
    rng = np.random.default_rng(7)
    theta = 2 * np.pi * mesh.node_times
    X = np.zeros((mesh.n_nodes, system.n))
    X[:, 0], X[:, 1] = np.cos(theta), np.sin(theta)
    u = np.concatenate([X.ravel(), [2 * np.pi, 0.04, 0.2]] + ([[kappa]] if kind == "NS" else []))
    problem.cycle.accept(problem.cycle_u(u))
    u = u + 1e-2 * rng.standard_normal(u.size)
    operator = problem._operator(u)
    M = problem._bordered(u)
    for shape in [(M.shape[0],), (M.shape[0], 2)]:
        z = rng.standard_normal(shape)
        np.testing.assert_allclose(operator.matvec(z), M @ z, rtol=0, atol=1e-12 * np.abs(M @ z).max())
        np.testing.assert_allclose(operator.rmatvec(z), M.T @ z, rtol=0, atol=1e-12 * np.abs(M.T @ z).max())
    lu = problem._factor(operator, u)  # the condensed LU's input summed from the entries, not from M
    assert isinstance(lu, CondensedLU)
    for trans in ("N", "T"):
        b = rng.standard_normal(M.shape[0])
        x = lu.solve(b, trans=trans)
        np.testing.assert_allclose((M.T if trans == "T" else M) @ x, b, rtol=0, atol=1e-10 * np.abs(b).max())


def random_chain(rng, links=5, n=2, interior=(3, 0, 2, 4, 1), g=2):
    """A random matrix of a chain layout with links of different interior sizes (one without)."""
    size = 0
    r_max, ni_max = max(interior) + n, max(interior)
    node_cols = np.arange((links + 1) * n).reshape(links + 1, n)
    next_col = node_cols.size
    link_rows = np.full((links, r_max), -1)
    interior_cols = np.full((links, ni_max), -1)
    for link, ni in enumerate(interior):
        link_rows[link, :ni + n] = size + np.arange(ni + n)
        interior_cols[link, :ni] = next_col + np.arange(ni)
        next_col += ni
        size += ni + n
    global_cols = next_col + np.arange(g)
    total = next_col + g
    global_rows = size + np.arange(n + g)
    layout = ChainLayout(total, link_rows, interior_cols, node_cols, global_cols, global_rows)
    M = np.zeros((total, total))
    for link, ni in enumerate(interior):
        touched = np.concatenate([node_cols[link], interior_cols[link, :ni], node_cols[link + 1], global_cols])
        M[np.ix_(link_rows[link, :ni + n], touched)] = rng.standard_normal((ni + n, touched.size))
    M[global_rows] = rng.standard_normal((n + g, total))
    return M, layout


def test_random_chains_with_links_of_any_interior_size():
    rng = np.random.default_rng(11)
    for _ in range(5):
        M, layout = random_chain(rng)
        matrix = sp.csr_matrix(M)
        assert_solves(matrix, CondensedLU(matrix, layout), rng)
        assert_solves(matrix.tocsc(), CondensedLU(matrix.tocsc(), layout), rng)


def test_one_link_chain():
    rng = np.random.default_rng(12)
    M, layout = random_chain(rng, links=1, interior=(3,))
    assert_solves(sp.csr_matrix(M), CondensedLU(sp.csr_matrix(M), layout), rng)


@pytest.mark.parametrize("tiny", [0.0, 1e-18, 1e-15])
def test_a_zero_pivot_raises_and_the_corrector_falls_back_to_superlu(tiny):
    """Pivoting is restricted to a link's rows: an interior unknown that its link's rows touch
    only at rounding size (a global row carries it) stops the condensation although the matrix
    is regular (eliminating on such a pivot gave errors of order 1 to 30); the corrector's
    factors then come from SuperLU and still solve it."""
    rng = np.random.default_rng(13)
    M, layout = random_chain(rng)
    lonely = layout.interior_cols[0, 0]
    M[layout.link_rows[0][layout.link_rows[0] >= 0], lonely] = tiny
    assert np.linalg.cond(M) < 1e8
    with pytest.raises(np.linalg.LinAlgError, match="singular pivot"):
        CondensedLU(sp.csr_matrix(M), layout)
    row = M[-1]  # the last row is a global row: the bordering row
    buf = layout.buffer(sp.csr_matrix(M))
    split = layout.links * layout.r_max * layout.width
    parts = (buf[:split].reshape(layout.links, layout.r_max, layout.width), buf[split:].reshape(layout.q, layout.size))
    b = rng.standard_normal(M.shape[0])
    x = condensed_factors(layout, parts, row, lambda: sp.csr_matrix(M[:-1])).solve(b)
    np.testing.assert_allclose(M @ x, b, atol=1e-10 * np.abs(x).max())


def test_a_matrix_outside_the_layout_is_refused():
    rng = np.random.default_rng(14)
    M, layout = random_chain(rng)
    M[layout.link_rows[0, 0], layout.interior_cols[3, 0]] = 1.0  # link 0 touching link 3's unknowns
    with pytest.raises(ValueError, match="chain layout"):
        CondensedLU(sp.csr_matrix(M), layout)
    with pytest.raises(ValueError, match="chain layout: every row needs exactly one role"):
        ChainLayout(layout.size, layout.link_rows[:, :-1], layout.interior_cols, layout.node_cols,
                    layout.global_cols, layout.global_rows)


def test_collocation_layout_covers_every_row_and_column_once():
    mesh = Mesh.uniform(4, 3)
    n = 2
    n_x = mesh.n_nodes * n
    n_coll = mesh.ntst * mesh.ncol * n
    layout = collocation_layout(mesh.ntst, mesh.ncol, n, 2 * n_x + 2, [(0, 0), (n_coll, n_x)],
                                [2 * n_coll + np.arange(n)], 2 * n_x + np.arange(2),
                                np.concatenate([2 * n_coll + n + np.arange(n), 2 * n_x + np.arange(2)]))
    rows = np.concatenate([layout.link_rows[layout.link_rows >= 0], layout.global_rows])
    cols = np.concatenate([layout.interior_cols[layout.interior_cols >= 0], layout.node_cols.ravel(),
                           layout.global_cols])
    assert sorted(rows) == list(range(layout.size)) and sorted(cols) == list(range(layout.size))
    assert layout.links == 2 * mesh.ntst + 1 and math.isclose(layout.n_interior[mesh.ntst], 0)


def test_monodromy_from_the_condensed_blocks_equals_the_product_of_dense_transfer_matrices():
    problem, u = orbit_problem(Mesh(np.array([0.0, 0.2, 0.45, 0.7, 1.0]), 3))
    blocks = problem.collocation_blocks(u)[0]
    n, m, N = problem.n, problem.mesh.ncol, problem.mesh.ntst
    B = np.ascontiguousarray(blocks.reshape(N, m * n, (m + 1) * n))
    expected = np.eye(n)
    for block in B:  # all nodes after the first from the first: x = -E^-1 F x_first
        expected = np.linalg.solve(block[:, n:], -block[:, :n])[-n:] @ expected
    np.testing.assert_allclose(monodromy(B, n), expected, atol=1e-13 * np.abs(expected).max())
    B = B.copy()  # the problem's blocks are shared (read-only)
    B[1] = 0.0  # a singular interval: no monodromy matrix
    assert np.isnan(monodromy(B, n)).all()


@pytest.mark.parametrize("points,ncol", [(np.linspace(0, 1, 11), 4), (np.array([0.0, 0.2, 0.45, 0.7, 1.0]), 3)])
def test_the_factors_give_the_same_monodromy_matrix_as_the_blocks(points, ncol):
    """The Newton matrix's condensed factors hold each interval's interior elimination: the monodromy
    matrix from them is the blocks' (bit for bit), and so are the multipliers at the point last
    factored; elsewhere the multipliers come from the blocks."""
    problem, u = orbit_problem(Mesh(points, ncol))
    n, m, N = problem.n, problem.mesh.ncol, problem.mesh.ntst
    blocks = np.ascontiguousarray(problem.collocation_blocks(u)[0].reshape(N, m * n, (m + 1) * n))
    row = np.random.default_rng(4).standard_normal(u.size)
    lu = problem.factor_bordered(u, row)
    assert isinstance(lu, CondensedLU)
    np.testing.assert_array_equal(lu.monodromy(), monodromy(blocks, n))
    problem._blocks_memo = None  # the multipliers at u must come from the factors, not the blocks
    from_factors = problem.multipliers(u)
    assert problem._blocks_memo is None
    other = u + 0.01
    problem.factor_bordered(other, row)  # the last factors are elsewhere now
    np.testing.assert_array_equal(problem.multipliers(u), from_factors)
    assert not np.array_equal(problem.multipliers(other), from_factors)


def test_the_phase_row_follows_the_reference_orbit():
    """The periodicity and phase rows are remembered, and recomputed when the reference changes
    (accept, or a reference set from outside)."""
    problem, u = orbit_problem(Mesh(np.linspace(0, 1, 6), 3))
    first = problem.periodicity_and_phase_rows()
    assert problem.periodicity_and_phase_rows() is first and not first.flags.writeable
    problem.accept(u)
    moved = problem.periodicity_and_phase_rows()
    assert not np.array_equal(moved, first)
    np.testing.assert_allclose(moved, problem.jacobian(u)[-(problem.n + 1):].toarray())
    problem.reference_derivative = 2.0 * problem.reference_derivative
    np.testing.assert_allclose(problem.periodicity_and_phase_rows()[-1], 2.0 * moved[-1])


def test_layouts_with_roles_missing_doubled_or_padded_inside_are_refused():
    rng = np.random.default_rng(15)
    _, layout = random_chain(rng)
    parts = dict(size=layout.size, link_rows=layout.link_rows, interior_cols=layout.interior_cols,
                 node_cols=layout.node_cols, global_cols=layout.global_cols, global_rows=layout.global_rows)
    doubled = dict(parts, global_rows=np.append(layout.global_rows[:-1], layout.link_rows[0, 0]))
    with pytest.raises(ValueError, match="exactly one role"):
        ChainLayout(**doubled)
    inside = layout.interior_cols.copy()
    inside[0, :2] = inside[0, [1, 0]]
    inside[0, 0] = -1  # padding before an entry
    with pytest.raises(ValueError, match="padding"):
        ChainLayout(**dict(parts, interior_cols=inside))


def test_solve_refuses_an_unknown_transposition_and_a_wrong_right_hand_side():
    rng = np.random.default_rng(16)
    M, layout = random_chain(rng)
    lu = CondensedLU(sp.csr_matrix(M), layout)
    with pytest.raises(ValueError, match="trans"):
        lu.solve(np.ones(layout.size), trans="H")
    with pytest.raises(ValueError, match="right-hand side"):
        lu.solve(np.ones(2 * layout.size))
