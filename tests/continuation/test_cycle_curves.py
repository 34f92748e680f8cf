"""Two-parameter curves of cycle bifurcations and one-parameter detection, on textbook systems
whose curves are known in closed form."""

import math

import numpy as np
import pytest
from textbook_systems import (TWO_PARAMETER_SYSTEMS, bautin, cusp_of_cycles, flip_two_parameter, fold_near_torus,
                              torus_two_parameter)

from shimmy.continuation import (CycleCurveOptions, CycleCurveProblem, InvalidInputError, Mesh, OrbitGuess,
                                 PeriodicOptions, ContinuationOptions, cycle_curve, hopf_guess, periodic_branch)

BOX = ((-2.0, 2.0), (-1.0, 1.0))


def circle(mesh: Mesh, radius: float, n: int) -> np.ndarray:
    tau = mesh.node_times
    return np.column_stack([radius * np.cos(2 * np.pi * tau), radius * np.sin(2 * np.pi * tau)]
                           + [0.0 * tau] * (n - 2))


def start(mesh: Mesh, radius: float, n: int, p1: float) -> tuple[np.ndarray, np.ndarray]:
    return mesh.points, np.concatenate([circle(mesh, radius, n).ravel(), [2 * np.pi, p1]])


def kinds(curve, kind):
    return [s for s in curve.special_points if s.kind == kind]


@pytest.mark.parametrize("name", sorted(TWO_PARAMETER_SYSTEMS))
def test_two_parameter_fields_have_exact_jacobians(name):
    system = TWO_PARAMETER_SYSTEMS[name]()
    rng = np.random.default_rng(1)
    x, p = 0.7 * rng.standard_normal(system.n), np.array([0.3, -0.4])
    eps = 1e-6
    J = system.dfdx(x, p)
    for j in range(system.n):
        e = np.zeros(system.n)
        e[j] = eps
        np.testing.assert_allclose(J[:, j], (system.f(x + e, p) - system.f(x - e, p)) / (2 * eps), atol=1e-7)
    dp = system.dfdp(x, p)
    for k in range(2):
        e = np.zeros(2)
        e[k] = eps
        np.testing.assert_allclose(dp[k], (system.f(x, p + e) - system.f(x, p - e)) / (2 * eps), atol=1e-7)
    X = rng.standard_normal((system.n, 5))  # vectorised over columns
    np.testing.assert_allclose(system.dfdx(X, p)[2], system.dfdx(X[:, 2], p), atol=1e-14)
    np.testing.assert_allclose(system.dfdp(X, p)[:, :, 2], system.dfdp(X[:, 2], p), atol=1e-14)


@pytest.mark.parametrize("kind,system,radius,p,kappa", [
    ("LPC", bautin, math.sqrt(0.5), (-0.25, 1.0), None),
    ("PD", flip_two_parameter, 1.0, (0.04, 0.2), None),
    ("NS", torus_two_parameter, 1.0, (0.04, 0.2), 0.3),
])
def test_minimally_augmented_jacobian_matches_finite_differences(kind, system, radius, p, kappa):
    """The bordered test functions' gradients (second derivatives along the kernel vectors)
    against central differences of the residual, with the borders held fixed."""
    system = system()
    mesh = Mesh.uniform(8, 3)
    problem = CycleCurveProblem(system, kind, mesh, np.ones(system.n), 2 * np.pi, np.ones(2))
    u = np.concatenate([circle(mesh, radius, system.n).ravel(), [2 * np.pi, p[0], p[1]]]
                       + ([[kappa]] if kind == "NS" else []))
    problem.cycle.accept(problem.cycle_u(u))
    problem.update_borders(u, sweeps=2)
    rng = np.random.default_rng(7)
    u = u + 1e-3 * rng.standard_normal(u.size)  # off the curve: the test functions are not zero
    J = problem.jacobian(u).toarray()
    B, C = problem.B.copy(), problem.C.copy()
    for _ in range(3):
        d = rng.standard_normal(u.size)
        eps = 1e-6
        problem.B, problem.C = B, C
        fd = (problem.residual(u + eps * d) - problem.residual(u - eps * d)) / (2 * eps)
        np.testing.assert_allclose(J @ d, fd, rtol=1e-5, atol=1e-6 * np.abs(fd).max())


def test_second_derivatives_taken_together_are_those_taken_one_by_one():
    """second_many (one field evaluation for all displaced points) against second per direction, and
    a direction that moves the parameters (evaluated apart) against central differences of the
    cycle Jacobian's rows."""
    system = torus_two_parameter()
    mesh = Mesh.uniform(8, 3)
    problem = CycleCurveProblem(system, "NS", mesh, np.ones(system.n), 2 * np.pi, np.ones(2))
    u = np.concatenate([circle(mesh, 1.0, system.n).ravel(), [2 * np.pi, 0.04, 0.2, 0.3]])
    problem.cycle.accept(problem.cycle_u(u))
    rng = np.random.default_rng(11)
    u = u + 1e-3 * rng.standard_normal(u.size)
    pairs = []
    for moves in (False, False, True):
        d = rng.standard_normal(u.size)
        if not moves:
            d[problem.n_x + 1:] = 0.0
        pairs.append((d, rng.standard_normal(problem.n_coll)))
    together = problem.second_many(u, pairs[:2]) + problem.second_many(u, pairs[2:])  # one call, then apart
    mixed = problem.second_many(u, pairs)  # a direction moves the parameters: every point apart
    for (d, w), row, other in zip(pairs, together, mixed):
        np.testing.assert_allclose(other, row, rtol=0, atol=1e-12 * np.abs(row).max())
        np.testing.assert_allclose(row, problem.second(u, d, w), rtol=0, atol=1e-12 * np.abs(row).max())
        eps = 1e-6
        J_plus = problem.cycle_jacobian(u + eps * d)[:problem.n_coll].T @ w
        J_minus = problem.cycle_jacobian(u - eps * d)[:problem.n_coll].T @ w
        fd = (J_plus - J_minus) / (2 * eps)
        np.testing.assert_allclose(row[:fd.size], fd, rtol=0, atol=1e-6 * np.abs(fd).max())


def test_fold_of_cycles_curve_of_the_bautin_normal_form():
    """From the located LPC of a one-parameter branch to b1 = -b2^2 / 4, ending at GH (0, 0)."""
    system = bautin()
    options = PeriodicOptions(ntst=20, ncol=4)
    guess, shape = hopf_guess(np.zeros(2), 0.0, 1.0, np.array([1.0, -1j]), Mesh.uniform(20, 4), 0.0)
    branch = periodic_branch(system.at(1.0), guess, p_range=(-1.0, 1.0), options=options, scale=np.ones(2), p_scale=1.0,
                             direction=shape)
    lpc = [s for s in branch.special_points if s.kind == "LPC"]
    assert len(lpc) == 1 and abs(lpc[0].p + 0.25) < 1e-8
    curve = cycle_curve(system, "LPC", lpc[0].solution, 1.0, box=BOX, scale=np.ones(2), p_scale=(1.0, 1.0))
    b1, b2 = curve.p[:, 0], curve.p[:, 1]
    assert len(b1) > 10
    np.testing.assert_allclose(b1, -b2 ** 2 / 4, atol=1e-8)
    np.testing.assert_allclose(curve.period, 2 * np.pi, rtol=1e-9)
    np.testing.assert_allclose(curve.x_max[:, 0], np.sqrt(b2 / 2), atol=1e-6)
    ends = kinds(curve, "ZA")
    assert len(ends) == 1 and abs(ends[0].p) < 1e-6 and abs(ends[0].data["p2"]) < 1e-3, curve.stop_reasons
    assert any("amplitude shrank to zero" in r for r in curve.stop_reasons)
    edge = kinds(curve, "EP")
    assert len(edge) == 1 and edge[0].data["p2"] == pytest.approx(1.0, abs=1e-9)
    assert edge[0].p == pytest.approx(-0.25, abs=1e-8)
    mu = np.abs(curve.multipliers[:, 1])  # the fold's multiplier stays at 1 along the curve
    np.testing.assert_allclose(mu[b2 > 0.05], 1.0, atol=1e-6)


def test_cusp_of_cycles_is_located_on_the_fold_curve():
    system = cusp_of_cycles()
    s0 = 0.3
    curve = cycle_curve(system, "LPC", start(Mesh.uniform(20, 4), math.sqrt(1 + s0), 2, -2 * s0 ** 3), 3 * s0 ** 2,
                        box=((-1.0, 1.0), (-1.0, 1.0)), scale=np.ones(2), p_scale=(1.0, 1.0))
    s = curve.x_max[:, 0] ** 2 - 1.0
    np.testing.assert_allclose(curve.p[:, 0], -2 * s ** 3, atol=1e-8)
    np.testing.assert_allclose(curve.p[:, 1], 3 * s ** 2, atol=1e-8)
    cusps = kinds(curve, "CPC")
    assert len(cusps) == 1
    assert abs(cusps[0].p) < 1e-8 and abs(cusps[0].data["p2"]) < 1e-6
    assert len(kinds(curve, "EP")) == 2  # both halves leave the box at b2 = 1


def test_torus_curve_with_its_strong_resonances():
    """p1 = p2^2, kappa = cos(2 pi (0.3 + 0.1 p2)): R4 at p2 = -0.5, R3 at p2 = 1/3."""
    system = torus_two_parameter()
    curve = cycle_curve(system, "NS", start(Mesh.uniform(20, 4), 1.0, 4, 0.0), 0.0, box=((-1.0, 2.0), (-1.0, 1.0)),
                        scale=np.ones(4), p_scale=(1.0, 1.0), kappa=math.cos(0.6 * math.pi))
    p1, p2 = curve.p[:, 0], curve.p[:, 1]
    np.testing.assert_allclose(p1, p2 ** 2, atol=1e-8)
    np.testing.assert_allclose(curve.kappa, np.cos(2 * np.pi * (0.3 + 0.1 * p2)), atol=1e-8)
    assert p2.min() == pytest.approx(-1.0) and p2.max() == pytest.approx(1.0)
    r3, r4 = kinds(curve, "R3"), kinds(curve, "R4")
    # one Newton solve with kappa held at the resonance's value: on the curve to the corrector's tolerance
    assert len(r3) == 1 and r3[0].located and r3[0].data["p2"] == pytest.approx(1 / 3, abs=1e-9)
    assert len(r4) == 1 and r4[0].located and r4[0].data["p2"] == pytest.approx(-0.5, abs=1e-9)
    assert r3[0].data["kappa"] == pytest.approx(-0.5, abs=1e-14) and r4[0].data["kappa"] == pytest.approx(0.0, abs=1e-14)
    assert not kinds(curve, "R1") and not kinds(curve, "R2")
    assert np.all(np.diff(p2) > 0)  # one curve, ordered along it


def test_a_resonance_test_told_by_an_earlier_points_value_is_searched_not_solved(monkeypatch):
    """The test values before a step may be an earlier point's (a new mesh moves the point, and kappa
    with it): a sign change of kappa - value there with kappa on one side at both ends of the step
    is not one Newton solve's (point_at refuses it) but the search's, and the curve goes on (it was
    dropped whole: "not continued")."""
    from shimmy.continuation.cycle_curves import codim2, tracing

    system = torus_two_parameter()
    told = []
    original = codim2.codim2_points

    def stale(problem, prev, new, before, after, *args, **kwargs):
        level = problem.kappa_index
        if not told and prev.u[level] < 0.0 and new.u[level] < 0.0:  # a step before R4 (kappa rises to 0)
            before = {**before, "R4": -after["R4"]}  # as if the point before had kappa > 0
            told.append(new.u[level])
        return original(problem, prev, new, before, after, *args, **kwargs)

    monkeypatch.setattr(tracing.codim2, "codim2_points", stale)
    curve = cycle_curve(system, "NS", start(Mesh.uniform(20, 4), 1.0, 4, 0.0), 0.0, box=((-1.0, 2.0), (-1.0, 1.0)),
                        scale=np.ones(4), p_scale=(1.0, 1.0), kappa=math.cos(0.6 * math.pi), directions=(-1,))
    assert told  # the stale value was told
    assert curve.p[:, 1].min() == pytest.approx(-1.0)  # traced on to the box's edge
    r4 = kinds(curve, "R4")
    assert any(pt.located and pt.data["p2"] == pytest.approx(-0.5, abs=1e-9) for pt in r4)


def test_after_a_new_mesh_a_step_compares_tests_of_one_discretisation(monkeypatch):
    """The signs a step compares are the tests at both ends on the step's own mesh: after the mesh is
    adapted, the tests at the point are taken again on the new one (before, the values of the old mesh
    were compared with the new mesh's, a difference of discretisations that could read as a crossing)."""
    from shimmy.continuation.cycle_curves import codim2, tracing

    system = torus_two_parameter()
    compared = []
    original = codim2.codim2_points

    def check(problem, prev, new, before, after, reference, *args, **kwargs):
        again = codim2.monitors(problem, prev, problem.multipliers(prev.u), reference)
        carried = args[-1] if args else kwargs.get("carried", frozenset())
        compared.append(max((abs(before[k] - again[k]) for k in again
                             if k not in carried and np.isfinite(again[k]) and np.isfinite(before[k])), default=0.0))
        return original(problem, prev, new, before, after, reference, *args, **kwargs)

    monkeypatch.setattr(tracing.codim2, "codim2_points", check)
    # a coarse uniform first mesh: the adapted meshes (every second step) move the points
    curve = cycle_curve(system, "NS", start(Mesh.uniform(6, 3), 1.0, 4, 0.0), 0.0, box=((-1.0, 2.0), (-1.0, 1.0)),
                        scale=np.ones(4), p_scale=(1.0, 1.0), kappa=math.cos(0.6 * math.pi), ncol=3,
                        options=CycleCurveOptions(adapt_every=2), directions=(1,))
    assert len(compared) >= 6 and curve.p[:, 1].max() == pytest.approx(1.0)
    assert max(compared) <= 1e-12, compared


def test_period_doubling_curve():
    system = flip_two_parameter()
    curve = cycle_curve(system, "PD", start(Mesh.uniform(20, 4), 1.0, 4, 0.0), 0.0, box=((-1.0, 2.0), (-1.0, 1.0)),
                        scale=np.ones(4), p_scale=(1.0, 1.0))
    np.testing.assert_allclose(curve.p[:, 0], curve.p[:, 1] ** 2, atol=1e-8)
    critical = np.min(np.abs(curve.multipliers[:, 1:] + 1.0), axis=1)
    np.testing.assert_allclose(critical, 0.0, atol=1e-6)
    assert len(kinds(curve, "EP")) == 2


def test_a_torus_start_needs_kappa_in_range_and_the_box_its_order():
    system = torus_two_parameter()
    with pytest.raises(InvalidInputError, match="kappa"):
        cycle_curve(system, "NS", start(Mesh.uniform(20, 4), 1.0, 4, 0.0), 0.0, box=BOX, scale=np.ones(4),
                    p_scale=(1.0, 1.0), kappa=1.5)
    with pytest.raises(InvalidInputError, match="p2 range"):
        cycle_curve(system, "PD", start(Mesh.uniform(20, 4), 1.0, 4, 0.0), 0.0, box=((-1, 1), (1, -1)),
                    scale=np.ones(4), p_scale=(1.0, 1.0))


@pytest.mark.parametrize("ds_max", [0.5, 2.0])
def test_a_fold_and_two_torus_points_in_one_step_are_all_found(ds_max):
    """Torus points 1e-3 and 2e-3 from a fold in p: one default step crosses all three; each is
    typed and located (three multipliers leave the unit circle across the fold)."""
    system = fold_near_torus(1e-3, second_gap=2e-3)
    mesh = Mesh.uniform(20, 4)
    guess = OrbitGuess(mesh, circle(mesh, math.sqrt(0.7), system.n), 2 * np.pi, -0.21)
    options = PeriodicOptions(ntst=20, ncol=4, continuation=ContinuationOptions(ds_max=ds_max))
    branch = periodic_branch(system, guess, p_range=(-0.3, -0.2), options=options, scale=np.ones(system.n), p_scale=1.0,
                             p_direction=-1)
    found = [(s.kind, s.p) for s in branch.special_points if s.kind != "EP"]
    assert [k for k, _ in found] == ["LPC", "NS", "NS"], found
    np.testing.assert_allclose([p for _, p in found], [-0.25, -0.249, -0.248], atol=1e-6)
    assert len(branch.p) < 12  # the steps were not made small to find them


def swapped(system):
    """The same field with p1 and p2 exchanged."""
    from shimmy.continuation import TwoParameterField
    return TwoParameterField(system.n, lambda x, p: system.f(x, p[::-1]), lambda x, p: system.dfdx(x, p[::-1]),
                                   lambda x, p: system.dfdp(x, p[::-1])[::-1], "swapped " + system.name)


def test_turning_points_in_p2_and_crossings_of_marked_loads_are_located():
    """With the torus system's parameters exchanged the curve is p2 = p1^2: a minimum of p2 at
    p1 = 0 and crossings of p2 = 0.25 at p1 = +-0.5."""
    system = swapped(torus_two_parameter())
    curve = cycle_curve(system, "NS", start(Mesh.uniform(20, 4), 1.0, 4, 0.3), 0.09, box=((-1.0, 1.0), (-1.0, 2.0)),
                        scale=np.ones(4), p_scale=(1.0, 1.0), kappa=math.cos(2 * math.pi * 0.33), p2_marks=(0.25,))
    np.testing.assert_allclose(curve.p[:, 1], curve.p[:, 0] ** 2, atol=1e-8)
    turns = kinds(curve, "P2_TURN")
    assert len(turns) == 1 and turns[0].data["turn"] == "min"
    assert abs(turns[0].p) < 1e-7 and abs(turns[0].data["p2"]) < 1e-7
    marks = sorted(s.p for s in kinds(curve, "P2_MARK"))
    np.testing.assert_allclose(marks, [-0.5, 0.5], atol=1e-8)


def test_a_marked_load_crossed_twice_in_a_step_around_a_turn_gives_both_crossings():
    """p2 = p1^2 traced in long steps (chord tolerance 1: a coarse polyline): the step across the
    minimum at p1 = 0 has both ends above a load the curve crosses twice inside it, marked at half
    the lower end's p2; both crossings are located, on either side of the located turn."""
    system = swapped(torus_two_parameter())
    options = CycleCurveOptions(chord_tol=1.0, continuation=ContinuationOptions(ds=0.2, ds_max=0.5, max_steps=300))

    def trace(marks):
        return cycle_curve(system, "NS", start(Mesh.uniform(20, 4), 1.0, 4, 0.3), 0.09,
                           box=((-1.0, 1.0), (-1.0, 2.0)), scale=np.ones(4), p_scale=(1.0, 1.0),
                           kappa=math.cos(2 * math.pi * 0.33), p2_marks=marks, options=options)

    p1 = trace(()).p[:, 0]
    k = next(k for k in range(len(p1) - 1) if p1[k] < 0 < p1[k + 1])
    mark = 0.5 * min(p1[k], p1[k + 1], key=abs) ** 2
    curve = trace((mark,))
    np.testing.assert_array_equal(curve.p[:, 0], p1)  # the same steps: the mark moves none
    turn = kinds(curve, "P2_TURN")
    assert len(turn) == 1 and abs(turn[0].p) < 1e-7
    marks = sorted(s.p for s in kinds(curve, "P2_MARK"))
    np.testing.assert_allclose(marks, [-math.sqrt(mark), math.sqrt(mark)], atol=1e-8)


def test_double_hopf_point_of_two_uncoupled_oscillators_is_located_on_the_hopf_curve():
    """x' = (p1 + i) x - |x|^2 x, y' = (p2 + 2i) y - |y|^2 y (complex x, y): the Hopf curve p1 = 0 has
    a double-Hopf point at p2 = 0 with frequencies 1 and 2."""
    from shimmy.continuation import PointKind, TwoParameterField, hopf_curve

    def parts(z):
        return z[0] + 1j * z[1], z[2] + 1j * z[3]

    def f(z, p):
        x, y = parts(z)
        fx, fy = (p[0] + 1j) * x - abs(x) ** 2 * x, (p[1] + 2j) * y - abs(y) ** 2 * y
        return np.array([fx.real, fx.imag, fy.real, fy.imag])

    def block(a, w, u, v):  # Jacobian of (a + i w) z - |z|^2 z in (Re z, Im z)
        return np.array([[a - 3 * u * u - v * v, -w - 2 * u * v], [w - 2 * u * v, a - u * u - 3 * v * v]])

    def dfdx(z, p):
        J = np.zeros((4, 4), dtype=np.result_type(z, float))
        J[:2, :2] = block(p[0], 1.0, z[0], z[1])
        J[2:, 2:] = block(p[1], 2.0, z[2], z[3])
        return J

    def dfdp(z, p):
        return np.array([[z[0], z[1], 0.0, 0.0], [0.0, 0.0, z[2], z[3]]])

    curve = hopf_curve(TwoParameterField(4, f, dfdx, dfdp), np.zeros(4), np.array([0.0, 0.5]), box=((-1, 1), (-1, 1)),
                       scale=np.ones(4), p_scale=np.ones(2))
    np.testing.assert_allclose(curve.p[:, 0], 0.0, atol=1e-10)
    assert len(curve.points_of(PointKind.DOUBLE_HOPF)) == 1
    hh = curve.points_of(PointKind.DOUBLE_HOPF)[0]
    assert abs(hh.p[1]) < 1e-8 and hh.located
    assert hh.data["omega"] == pytest.approx(1.0) and hh.data["omega2"] == pytest.approx(2.0)


def test_fold_curve_started_beside_the_generalised_hopf_point():
    """Bautin: from the Hopf point at (b1, b2) = (0, 0.05), just beside GH (0, 0), the small cycle's
    first fold starts the fold curve b1 = -b2^2/4, which then runs out to the box."""
    from shimmy.continuation import start_beside

    system = bautin()
    point, ncol = start_beside(system, "LPC", np.zeros(2), np.array([0.0, 0.05]), p_range=(-1.0, 1.0),
                               options=PeriodicOptions(ntst=20, ncol=4), scale=np.ones(2), p_scale=1.0)
    assert point is not None and point.p == pytest.approx(-0.05 ** 2 / 4, abs=1e-9)
    curve = cycle_curve(system, "LPC", point.solution, 0.05, box=BOX, scale=np.ones(2), p_scale=(1.0, 1.0), ncol=ncol)
    np.testing.assert_allclose(curve.p[:, 0], -curve.p[:, 1] ** 2 / 4, atol=1e-8)
    assert curve.p[:, 1].max() == pytest.approx(1.0) and curve.p[:, 1].min() < 1e-3


def coupled_oscillators(w2: float = 2.3):
    """The double-Hopf amplitude equations in complex x, y: x' = (p1 + i) x - |x|^2 x,
    y' = (p2 + i w2) y + (|x|^2 - |y|^2) y. A double-Hopf point at (0, 0); the cycle |x|^2 = p1
    (T = 2 pi, y = 0) has the fibre multipliers exp(2 pi (p2 + p1)) exp(+-2 pi i w2): the torus curve
    p2 = -p1, p1 > 0, born at the double-Hopf point, kappa = cos(2 pi w2)."""
    from shimmy.continuation import TwoParameterField

    def f(z, p):
        x, y = z[0] + 1j * z[1], z[2] + 1j * z[3]
        fx = (p[0] + 1j) * x - abs(x) ** 2 * x
        fy = (p[1] + 1j * w2) * y + (abs(x) ** 2 - abs(y) ** 2) * y
        return np.stack([fx.real, fx.imag, fy.real, fy.imag])

    def dfdx(z, p):
        u, v, c, d = z[0], z[1], z[2], z[3]
        rx = u * u + v * v
        a = p[1] + rx
        rows = [[p[0] - 3 * u * u - v * v, -1.0 - 2 * u * v, 0 * u, 0 * u],
                [1.0 - 2 * u * v, p[0] - u * u - 3 * v * v, 0 * u, 0 * u],
                [2 * u * c, 2 * v * c, a - 3 * c * c - d * d, -w2 - 2 * c * d],
                [2 * u * d, 2 * v * d, w2 - 2 * c * d, a - c * c - 3 * d * d]]
        J = np.empty(np.shape(z)[1:] + (4, 4))
        for i, row in enumerate(rows):
            for j, value in enumerate(row):
                J[..., i, j] = value
        return J

    def dfdp(z, p):
        zero = 0.0 * z[0]
        return np.stack([np.stack([z[0], z[1], zero, zero]), np.stack([zero, zero, z[2], z[3]])])

    return TwoParameterField(4, f, dfdx, dfdp, "coupled_oscillators")


def test_coupled_oscillators_have_exact_jacobians():
    system = coupled_oscillators()
    rng = np.random.default_rng(3)
    x, p, eps = rng.standard_normal(4), np.array([0.2, -0.3]), 1e-6
    for j in range(4):
        e = np.zeros(4)
        e[j] = eps
        np.testing.assert_allclose(system.dfdx(x, p)[:, j], (system.f(x + e, p) - system.f(x - e, p)) / (2 * eps),
                                   atol=1e-7)


def test_torus_curve_started_beside_the_double_hopf_point():
    from shimmy.continuation import start_beside

    system = coupled_oscillators()
    point, ncol = start_beside(system, "NS", np.zeros(4), np.array([0.0, -0.02]), p_range=(-1.0, 1.0),
                               options=PeriodicOptions(ntst=20, ncol=4), scale=np.ones(4), p_scale=1.0)
    assert point is not None and point.p == pytest.approx(0.02, abs=1e-8)
    curve = cycle_curve(system, "NS", point.solution, -0.02, box=((-1.0, 0.5), (-1.0, 1.0)), scale=np.ones(4),
                        p_scale=(1.0, 1.0), kappa=math.cos(point.data["torus_angle"]), ncol=ncol)
    np.testing.assert_allclose(curve.p[:, 1], -curve.p[:, 0], atol=1e-8)
    np.testing.assert_allclose(curve.kappa, math.cos(2 * math.pi * 2.3), atol=1e-8)
    assert curve.p[:, 0].max() == pytest.approx(0.5) and curve.p[:, 0].min() < 1e-3
    assert any("amplitude shrank to zero" in r for r in curve.stop_reasons)  # ends at the double-Hopf point


@pytest.mark.parametrize("name, value", [("chord_tol", 0.0), ("chord_tol", 2.0), ("chord_tol", math.nan),
                                         ("amplitude_min", 1.0), ("adapt_every", -1)])
def test_bad_curve_options_name_the_field(name, value):
    from shimmy.continuation import CycleCurveOptions

    with pytest.raises(InvalidInputError) as info:
        CycleCurveOptions(**{name: value})
    assert info.value.field == name


def test_remembered_collocation_blocks_follow_the_second_parameter():
    """The cycle's blocks are remembered for the last (x, T, p1); a change of p2 alone changes the
    field, so the curve problem's Jacobian at the new p2 equals a fresh problem's."""
    system = bautin()
    mesh = Mesh.uniform(6, 3)
    u = np.concatenate([circle(mesh, 0.7, system.n).ravel(), [2 * np.pi, -0.25, 1.0]])
    problem = CycleCurveProblem(system, "LPC", mesh, np.ones(system.n), 2 * np.pi, np.ones(2))
    problem.cycle.accept(problem.cycle_u(u))
    before = problem.cycle_jacobian(u).toarray()
    moved = u.copy()
    moved[-1] = 1.5
    fresh = CycleCurveProblem(system, "LPC", mesh, np.ones(system.n), 2 * np.pi, np.ones(2))
    fresh.cycle.accept(fresh.cycle_u(u))
    after = problem.cycle_jacobian(moved).toarray()
    np.testing.assert_array_equal(after, fresh.cycle_jacobian(moved).toarray())
    assert np.abs(after - before).max() > 1e-3


@pytest.mark.parametrize("case", ["torus, both ends on the box", "fold, ending at GH"])
def test_two_halves_traced_apart_join_into_the_curve_traced_both_ways(case):
    """join_halves: the halves traced from one start in separate calls (as two processes do) give
    the curve cycle_curve traces both ways: the same points to the Newton tolerance, in the same
    order, the same special points at the same indices, both stops."""
    from shimmy.continuation.cycle_curves.tracing import join_halves

    if case.startswith("torus"):
        system = torus_two_parameter()
        args = (system, "NS", start(Mesh.uniform(20, 4), 1.0, 4, 0.0), 0.0)
        kw = dict(box=((-1.0, 2.0), (-1.0, 1.0)), scale=np.ones(4), p_scale=(1.0, 1.0), kappa=math.cos(0.6 * math.pi),
                  p2_marks=(0.25, -0.75))
    else:
        system = bautin()
        options = PeriodicOptions(ntst=20, ncol=4)
        guess, shape = hopf_guess(np.zeros(2), 0.0, 1.0, np.array([1.0, -1j]), Mesh.uniform(20, 4), 0.0)
        branch = periodic_branch(system.at(0.5), guess, p_range=(-1.0, 1.0), options=options, scale=np.ones(2),
                                 p_scale=1.0, direction=shape)
        lpc = [s for s in branch.special_points if s.kind == "LPC"]
        args = (system, "LPC", lpc[0].solution, 0.5)
        kw = dict(box=BOX, scale=np.ones(2), p_scale=(1.0, 1.0), p2_marks=(0.25,))
    whole = cycle_curve(*args, **kw)
    joined = join_halves(cycle_curve(*args, directions=(1,), **kw), cycle_curve(*args, directions=(-1,), **kw))
    assert len(joined.p) == len(whole.p) and joined.closed == whole.closed
    np.testing.assert_allclose(joined.p, whole.p, atol=1e-7)
    np.testing.assert_allclose(joined.x_max, whole.x_max, atol=1e-6)
    assert [(s.kind, s.index) for s in joined.special_points] == [(s.kind, s.index) for s in whole.special_points]
    for a, b in zip(joined.special_points, whole.special_points, strict=True):
        assert a.p == pytest.approx(b.p, abs=1e-7) and a.data["p2"] == pytest.approx(b.data["p2"], abs=1e-7)
    assert joined.stop_reasons == whole.stop_reasons and joined.steps == whole.steps
    assert len(joined.solutions) == len(joined.p)
    with pytest.raises(InvalidInputError, match="minus"):
        join_halves(cycle_curve(*args, directions=(1,), **kw), torus_or_flip(case))


def torus_or_flip(case):
    """A half of a curve of another kind (a period-doubling curve, or a torus curve)."""
    kind, system, kappa = (("PD", flip_two_parameter(), None) if case.startswith("torus")
                           else ("NS", torus_two_parameter(), math.cos(0.6 * math.pi)))
    return cycle_curve(system, kind, start(Mesh.uniform(20, 4), 1.0, 4, 0.0), 0.0, box=((-1.0, 2.0), (-1.0, 1.0)),
                       scale=np.ones(4), p_scale=(1.0, 1.0), kappa=kappa, directions=(1,))


def _bautin(c: float, d: float = 0.0):
    """The Bautin normal form with G = b1 + (b2 - d) rho - c rho^2: its fold of cycles curve is
    b1 = -(b2 - d)^2 / (4 c), the cycles' amplitude sqrt((b2 - d) / (2 c)), ending at GH (0, d);
    c and d are the "design"."""
    from textbook_systems import radial_two_parameter

    return radial_two_parameter(lambda rho, p: p[0] + (p[1] - d) * rho - c * rho ** 2,
                                lambda rho, p: (p[1] - d) - 2.0 * c * rho,
                                lambda rho, p: (np.ones_like(rho), rho), f"bautin c={c} d={d}")


def _guided_and_alone(c: float, d: float):
    """The Bautin fold curve traced at (c, d) from the middle point of the curve at (1, 0), following
    that curve's points and alone: (guided, alone, the guides, residuals evaluated by each)."""
    from shimmy.continuation.cycle_curves.guide import Guide, guide_points

    kw = dict(box=BOX, scale=np.ones(2), p_scale=(1.0, 1.0), p2_marks=(0.25,))
    guess, shape = hopf_guess(np.zeros(2), 0.0, 1.0, np.array([1.0, -1j]), Mesh.uniform(20, 4), 0.0)
    branch = periodic_branch(_bautin(1.0).at(0.5), guess, p_range=(-1.0, 1.0), options=PeriodicOptions(ntst=20, ncol=4),
                             scale=np.ones(2), p_scale=1.0, direction=shape)
    old = cycle_curve(_bautin(1.0), "LPC", [q for q in branch.special_points if q.kind == "LPC"][0].solution, 0.5, **kw)
    i = len(old.p) // 2
    points = guide_points(old, i, bool(old.p[i + 1, 1] > old.p[i - 1, 1]))
    assert [len(points[1]) + len(points[-1])] == [len(old.p) + 1]
    guides = {way: Guide(points[way], 4, 2) for way in (1, -1)}
    count = {"n": 0}
    residual = CycleCurveProblem.residual

    def counted(self, u):
        count["n"] += 1
        return residual(self, u)

    CycleCurveProblem.residual = counted
    try:
        guided = cycle_curve(_bautin(c, d), "LPC", old.solutions[i], float(old.p[i, 1]), guides=guides, **kw)
        with_guide, count["n"] = count["n"], 0
        alone = cycle_curve(_bautin(c, d), "LPC", old.solutions[i], float(old.p[i, 1]), **kw)
    finally:
        CycleCurveProblem.residual = residual
    return guided, alone, guides, (with_guide, count["n"])


@pytest.mark.parametrize("c, d", [(1.02, 0.0), (1.0, 0.05)])
def test_a_guided_trace_follows_the_nearby_curve_to_the_same_curve_and_points(c, d):
    """A fold curve traced at a new design following the points of the same curve at the old one
    (c = 1, d = 0; :mod:`~shimmy.continuation.cycle_curves.guide`): its points lie on the new curve
    to the Newton tolerance and it has the special points a trace without the guide finds (the load
    crossed, the box edge, the zero-amplitude end at GH). Where the curve moved little (c = 1.02)
    nearly every point is a guided one and the trace evaluates fewer residuals than the unguided
    one (100 against 124; the curvature predictor is nearly exact on this parabola). Where its end
    moved along it (GH to b2 = 0.05) the guide gives up at once and costs at most a few residuals
    (137 against 135; before it gave up, 222 against 135)."""
    guided, alone, guides, (with_guide, without) = _guided_and_alone(c, d)
    b1, b2 = guided.p[:, 0], guided.p[:, 1]
    np.testing.assert_allclose(b1, -(b2 - d) ** 2 / (4 * c), atol=1e-8)
    big = b2 - d > 0.05
    np.testing.assert_allclose(guided.x_max[big, 0], np.sqrt((b2[big] - d) / (2 * c)), atol=1e-6)
    assert [q.kind for q in guided.special_points] == [q.kind for q in alone.special_points]
    for a, b in zip(guided.special_points, alone.special_points, strict=True):
        if a.kind == "ZA":  # where a trace stops short of GH (0, d) depends on its steps
            assert abs(a.p) < 1e-6 and abs(a.data["p2"] - d) < 1e-3
        else:
            assert a.p == pytest.approx(b.p, abs=1e-7) and a.data["p2"] == pytest.approx(b.data["p2"], abs=1e-7)
    taken = sum(g.taken for g in guides.values())
    assert guided.guided == taken
    if d == 0.0:
        assert taken >= 0.8 * len(guided.p) and with_guide < 0.9 * without, (taken, with_guide, without)
    else:
        assert with_guide <= 1.1 * without, (with_guide, without)


def test_a_guided_trace_passes_over_old_points_its_chords_do_not_need():
    """A nearby curve traced with a tolerance 10x tighter (chord_tol 5e-4: 3x as many points) guides a trace
    at the default 5e-3: the trace passes over the old points its chords can do without (one step through
    several of them, :data:`~shimmy.continuation.cycle_curves.tracing.PASS_SHARE`), so it has fewer points
    than the guide, nearly all guided, and still every chord within the tolerance of the exact curve
    (b1 = -b2^2 / (4 c): its deviation from each chord at the chord's middle in b2), with the special points
    of the trace without a guide."""
    from shimmy.continuation.cycle_curves.guide import Guide, guide_points

    kw = dict(box=BOX, scale=np.ones(2), p_scale=(1.0, 1.0), p2_marks=(0.25,))
    guess, shape = hopf_guess(np.zeros(2), 0.0, 1.0, np.array([1.0, -1j]), Mesh.uniform(20, 4), 0.0)
    branch = periodic_branch(_bautin(1.0).at(0.5), guess, p_range=(-1.0, 1.0), options=PeriodicOptions(ntst=20, ncol=4),
                             scale=np.ones(2), p_scale=1.0, direction=shape)
    start = [q for q in branch.special_points if q.kind == "LPC"][0].solution
    turning = ContinuationOptions(ds=0.05, ds_max=0.5, max_steps=300, max_angle=0.3)  # the gear's curves' limit
    old = cycle_curve(_bautin(1.0), "LPC", start, 0.5, options=CycleCurveOptions(chord_tol=5e-4, continuation=turning),
                      **kw)
    i = len(old.p) // 2
    points = guide_points(old, i, bool(old.p[i + 1, 1] > old.p[i - 1, 1]))
    guides = {way: Guide(points[way], 4, 2) for way in (1, -1)}
    c = 1.02
    options = CycleCurveOptions(continuation=turning)
    guided = cycle_curve(_bautin(c), "LPC", old.solutions[i], float(old.p[i, 1]), guides=guides, options=options, **kw)
    alone = cycle_curve(_bautin(c), "LPC", old.solutions[i], float(old.p[i, 1]), options=options, **kw)
    assert len(guided.p) < 0.6 * len(old.p) and guided.guided >= 0.8 * len(guided.p), (len(guided.p), len(old.p))
    b1, b2 = guided.p[:, 0], guided.p[:, 1]
    np.testing.assert_allclose(b1, -b2 ** 2 / (4 * c), atol=1e-8)
    middle = 0.5 * (b2[1:] + b2[:-1])
    allowed = 5e-3 * np.maximum(np.maximum(np.abs(b1[1:]), np.abs(b1[:-1])), 0.1)
    assert np.all(np.abs(-middle ** 2 / (4 * c) - 0.5 * (b1[1:] + b1[:-1])) <= allowed)
    assert [q.kind for q in guided.special_points] == [q.kind for q in alone.special_points]
    for a, b in zip(guided.special_points, alone.special_points, strict=True):
        if a.kind != "ZA":  # (where a trace stops short of GH depends on its steps)
            assert a.p == pytest.approx(b.p, abs=1e-7) and a.data["p2"] == pytest.approx(b.data["p2"], abs=1e-7)



def test_a_guide_passes_over_points_only_where_allowed_and_retries_the_next_one():
    """Guide.next's bookkeeping with a given test: it goes to the last point before the first that does not
    pass (at most REACH ahead), the shift and ``at`` move to the point taken; after a refused step over points
    ``shorter`` goes back to the next point (once), and after a refused point it goes point by point."""
    from shimmy.continuation.core import CurvePoint
    from shimmy.continuation.cycle_curves.guide import REACH, Guide

    mesh = Mesh.uniform(2, 1)
    points = [(mesh.points, np.array([0.0, 0.0, 0.0, 0.0, 1.0, float(k), 0.0])) for k in range(12)]
    guide = Guide(points, 1, 1)
    guide.anchor(CurvePoint(points[0][1] + 0.5, np.zeros(7)), mesh)
    asked = []

    def passes(a, b):
        asked.append((a, b))
        return b - a <= 2  # passing over one point at a time

    predictor, _ = guide.next(mesh, passes)
    assert guide.k == 2 and asked == [(0, 2), (0, 3)] and predictor[5] == 2.0 + 0.5
    guide.took(CurvePoint(points[2][1] + 0.25, np.zeros(7)), mesh)
    assert (guide.at, guide.k) == (2, 3)
    predictor, _ = guide.next(mesh, lambda a, b: True)
    assert guide.k == 2 + REACH and predictor[5] == 2.0 + REACH + 0.25
    assert guide.shorter() and guide.k == 3 and not guide.shorter()
    guide.skip_behind(CurvePoint(points[3][1] + 0.25, np.eye(7)[5]), mesh, np.ones(7))  # refused: one by one
    assert guide.misses == 1 and guide.next(mesh, lambda a, b: True) is not None and guide.k == guide.at + 1

def test_a_point_moves_to_another_mesh_on_its_collocation_polynomials():
    """on_mesh: x on the source mesh's nodes evaluated at the target's, exactly for a polynomial of
    the collocation degree; the scalars after x kept; float32 encoding round-trips to 1e-7."""
    from shimmy.continuation.cycle_curves.guide import decode, encode, on_mesh

    source, target = Mesh(np.array([0.0, 0.2, 0.45, 0.7, 1.0]), 4), Mesh(np.linspace(0.0, 1.0, 7), 4)

    def poly(tau):
        return np.column_stack([1 + tau - 3 * tau ** 2 + tau ** 4, 2 * tau ** 3])

    u = np.concatenate([poly(source.node_times).ravel(), [6.0, 0.5, 0.25]])
    moved = on_mesh(u, source, target, 2)
    np.testing.assert_allclose(moved[:-3].reshape(-1, 2), poly(target.node_times), atol=1e-13)
    np.testing.assert_array_equal(moved[-3:], [6.0, 0.5, 0.25])
    assert on_mesh(u, source, Mesh(source.points.copy(), 4), 2) is u
    np.testing.assert_allclose(decode(encode(u)), u, rtol=1e-7)
