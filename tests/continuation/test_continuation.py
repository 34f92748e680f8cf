"""The generic continuation engine on textbook systems with known answers.

Equilibria (:func:`shimmy.continuation.equilibrium_branch`): folds, Hopf and branch points
at their analytic places. Periodic orbits (:mod:`shimmy.continuation.periodic_orbits`): Hopf normal
forms (amplitude, period and Floquet multiplier in closed form), a subcritical branch with
a fold of cycles, Van der Pol against its published period and amplitude and against the
collocation order, and two constructed 4-D systems whose Neimark-Sacker and
period-doubling points are known exactly. Then the stop rules and option validation.

The systems and their known answers are in ``textbook_systems.py``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import minimize_scalar

from shimmy.continuation.collocation import Mesh, PeriodicProblem
from shimmy.continuation import ContinuationOptions, equilibrium_branch
from shimmy.continuation import ConvergenceError, InvalidInputError
from shimmy.continuation.periodic_orbits import (OrbitGuess, PeriodicOptions, hopf_guess, orbit_from_samples,
                                                 periodic_branch)
from textbook_systems import (ALL_SYSTEMS, VDP_AMPLITUDE_MU1, VDP_PERIOD_MU1, fold_1d, fold_2d, hopf_close_pair,
                              hopf_shear, hopf_subcritical_quintic, hopf_supercritical, hopf_twice, neimark_sacker,
                              period_doubling, pitchfork, transcritical, two_pairs, van_der_pol)

TWO_PI = 2.0 * math.pi


# --------------------------------------------------------------------------- helpers


def kinds(branch) -> list[str]:
    return [s.kind for s in branch.special_points]


def only(branch, kind: str):
    found = [s for s in branch.special_points if s.kind == kind]
    assert len(found) == 1, f"expected one {kind}, got {kinds(branch)}"
    return found[0]


def hopf_branch(system, omega: float, p0: float, p_min: float, p_max: float, options: PeriodicOptions | None = None,
                **kwargs):
    """Periodic branch of a planar normal form born at its Hopf point (x* = 0, p0)."""
    options = options or PeriodicOptions(ntst=20, ncol=4)
    q = np.array([1.0, -1j])  # J q = i omega q for J = [[g, -omega], [omega, g]] at g = 0
    np.testing.assert_allclose(system.dfdx(np.zeros(2), p0) @ q, 1j * omega * q, atol=1e-12)
    guess, shape = hopf_guess(np.zeros(2), p0, omega, q, Mesh.uniform(options.ntst, options.ncol), 0.0)
    return periodic_branch(system, guess, p_range=(p_min, p_max), options=options, scale=np.ones(2), p_scale=1.0,
                           direction=shape, **kwargs)


def node_radius(branch, i: int) -> np.ndarray:
    """|(x, y)| at every collocation node of point i (first two states)."""
    _, u = branch.solutions[i]
    X = u[:-2].reshape(-1, branch.x_max.shape[1])  # u = [node values, T, p]
    return np.hypot(X[:, 0], X[:, 1])


def unit_cycle_guess(ntst: int, n: int, p: float, radius: float = 1.0, sign: float = 1.0) -> OrbitGuess:
    """(radius cos t, sign radius sin t, 0, ...) over one period 2 pi, as node values."""
    mesh = Mesh.uniform(ntst, 4)
    theta = TWO_PI * mesh.node_times
    X = np.zeros((mesh.n_nodes, n))
    X[:, 0], X[:, 1] = radius * np.cos(theta), sign * radius * np.sin(theta)
    return OrbitGuess(mesh, X, TWO_PI, p)


def refined_max(system, branch, i: int, component: int = 0) -> float:
    """max over the orbit of one state, from the collocation polynomial (not the sampled x_max)."""
    mesh_points, u = branch.solutions[i]
    problem = PeriodicProblem(system, Mesh(mesh_points, branch.ncol), np.ones(system.n), 1.0, 1.0)
    X, _, _ = problem.unpack(u)
    tau, x = problem.sample(u, 50)
    k = int(np.argmax(x[:, component]))
    dt = 2.0 * float(np.max(np.diff(tau)))
    res = minimize_scalar(lambda s: -problem.evaluate(X, np.array([s]))[0, component],
                          bounds=(max(tau[k] - dt, 0.0), min(tau[k] + dt, 1.0)), method="bounded",
                          options={"xatol": 1e-12})
    return max(-float(res.fun), float(x[k, component]))


def central_jacobian(f, x: np.ndarray, p: float, h: float = 1e-6):
    """d f / d x as (m, n, n) for columns x (n, m), and d f / d p (n, m), by central differences."""
    n = x.shape[0]
    cols = [(f(x + h * np.eye(n)[:, [k]], p) - f(x - h * np.eye(n)[:, [k]], p)) / (2 * h) for k in range(n)]
    return np.moveaxis(np.stack(cols, axis=-1), 1, 0), (f(x, p + h) - f(x, p - h)) / (2 * h)


# --------------------------------------------------------------------------- Jacobians


@pytest.mark.parametrize("name", sorted(ALL_SYSTEMS))
def test_analytic_jacobians_match_central_differences(name):
    system = ALL_SYSTEMS[name]()
    n = system.n
    x = np.random.default_rng(1).normal(size=(n, 7))
    p = 0.37
    J_fd, Jp_fd = central_jacobian(system.f, x, p)
    J = system.dfdx(x, p)
    assert J.shape == (7, n, n)
    np.testing.assert_allclose(J, J_fd, rtol=1e-6, atol=1e-7)
    np.testing.assert_allclose(system.dfdp(x, p), Jp_fd, rtol=1e-6, atol=1e-7)
    # 1-D input gives (n,) and (n, n), equal to the column version
    assert system.f(x[:, 0], p).shape == (n,)
    np.testing.assert_array_equal(system.dfdx(x[:, 0], p), J[0])
    np.testing.assert_array_equal(system.dfdp(x[:, 0], p), system.dfdp(x, p)[:, 0])


def test_collocation_jacobian_matches_finite_differences_of_the_residual():
    system = period_doubling()
    mesh = Mesh(np.array([0.0, 0.2, 0.45, 0.7, 1.0]), 3)  # non-uniform
    problem = PeriodicProblem(system, mesh, np.ones(4), 1.0, 1.0)
    theta = TWO_PI * mesh.node_times
    rng = np.random.default_rng(2)
    X = np.column_stack([np.cos(theta), np.sin(theta), 0.3 * np.sin(2 * theta), 0.2 * np.cos(theta)])
    problem.accept(problem.pack(X, 6.0, 0.4))  # phase reference
    u = problem.pack(X + 0.05 * rng.normal(size=X.shape), 6.1, 0.45)
    J = problem.jacobian(u).toarray()
    assert J.shape == (problem.n_equations, u.size) and J.shape[0] == u.size - 1
    h = 1e-6
    J_fd = np.column_stack([(problem.residual(u + h * e) - problem.residual(u - h * e)) / (2 * h)
                            for e in np.eye(u.size)])
    np.testing.assert_allclose(J, J_fd, atol=1e-7 * np.abs(J_fd).max())


def test_tangent_refined_on_the_correctors_factors_equals_a_freshly_factored_one():
    """A step's tangent comes from iterative refinement on the chord factors of its corrector;
    it must equal the tangent of a fresh factorisation at the same point (to 1e-12) and, where
    the nearby factors are of a different bordering row, a fresh factorisation is used."""
    from shimmy.continuation.core import CurvePoint, _Bordered, correct, step, tangent, weighted_norm

    system = hopf_supercritical(omega=2.0)  # cycles r^2 = mu: the orbit and its Jacobian change along the step
    mesh = Mesh.uniform(12, 4)
    problem = PeriodicProblem(system, mesh, np.ones(2), 1.0, 1.0)
    theta = TWO_PI * mesh.node_times
    X = 0.5 * np.column_stack([np.cos(theta), np.sin(theta)])
    u0 = problem.pack(X, math.pi, 0.25)
    problem.accept(u0)
    e_p = np.zeros(u0.size)
    e_p[-1] = 1.0
    u0 = correct(problem, u0, e_p / weighted_norm(e_p, problem.weights), ContinuationOptions())[0]
    problem.accept(u0)
    t0 = tangent(problem, u0, e_p)
    options = ContinuationOptions()
    condensed = problem.factor_bordered
    problem.factor_bordered = None  # the general path: the assembled Jacobian, refined on nearby factors
    new = step(problem, CurvePoint(u0, t0), 0.3, options)
    assert new is not None
    fresh = tangent(problem, new.u, t0)
    np.testing.assert_allclose(new.tangent, fresh, atol=1e-12)
    problem.factor_bordered = condensed  # the collocation path: factored at the point without assembly
    np.testing.assert_allclose(tangent(problem, new.u, t0), fresh, atol=1e-12)
    assert abs(weighted_norm(new.tangent, problem.weights) - 1.0) < 1e-14
    # factors with another bordering row are not used for refinement
    other = _Bordered(problem.jacobian(u0), problem.weights * e_p)
    np.testing.assert_allclose(tangent(problem, new.u, t0, other), fresh, atol=1e-14)



class _Circle:
    """x^2 + y^2 = R^2 as a curve problem: curvature 1/R towards the centre, known everywhere."""

    def __init__(self, radius: float):
        self.R = radius
        self.weights = np.ones(2)

    def residual(self, u):
        return np.array([u @ u - self.R ** 2])

    def jacobian(self, u):
        return 2.0 * u[None, :]

    def accept(self, u):
        pass


def test_curvature_predictor_estimates_the_circles_curvature_and_keeps_its_points():
    """The Tracer's predictor bends with the curve: after one step on a circle of radius R its
    estimate of dt/ds points to the centre with size 1/R (to O(h)), orthogonal to the tangent;
    the point it converges to is the one the straight predictor converges to (same hyperplane),
    in fewer Newton iterations."""
    from shimmy.continuation.core import CurvePoint, Tracer, step

    R, h = 2.0, 0.2
    options = ContinuationOptions(ds=h, ds_max=h, tol=1e-12, residual_tol=1e-12)
    tracer = Tracer(_Circle(R), CurvePoint(np.array([R, 0.0]), np.array([0.0, 1.0])), options)
    assert tracer.curvature() is None  # no step yet: straight predictor
    tracer.advance()
    bend = tracer.curvature()
    u, t = tracer.point.u, tracer.point.tangent
    assert abs(bend @ t) < 1e-12
    np.testing.assert_allclose(bend, -u / R ** 2, rtol=0.0, atol=h / R ** 2)  # -u/R^2: 1/R towards 0
    curved = step(tracer.problem, tracer.point, h, options, curvature=bend)
    straight = step(tracer.problem, tracer.point, h, options)
    np.testing.assert_allclose(curved.u, straight.u, atol=1e-12)
    assert curved.iterations < straight.iterations
    # a point set from outside (a new mesh, say) has no curvature estimate until the next step
    tracer.point = CurvePoint(u.copy(), t.copy())
    assert tracer.curvature() is None

def test_point_at_a_level_of_one_unknown_is_the_circles_point_there():
    """point_at: between two points of a circle of radius R, the point where x = c is (c, sqrt(R^2 - c^2))
    (one Newton solve with x held), and where y = 0 across the turning point of x it is (R, 0); the
    tangent, when asked, is the circle's; a level not crossed between the two points is refused."""
    from shimmy.continuation.core import CurvePoint, point_at

    R = 2.0
    options = ContinuationOptions(tol=1e-12, residual_tol=1e-12)
    circle = _Circle(R)
    a = CurvePoint(np.array([R * np.cos(0.3), R * np.sin(0.3)]), np.array([-np.sin(0.3), np.cos(0.3)]))
    b = CurvePoint(np.array([R * np.cos(0.9), R * np.sin(0.9)]), np.array([-np.sin(0.9), np.cos(0.9)]))
    c = 1.5
    at = point_at(circle, a, b, 0, c, options)
    np.testing.assert_allclose(at.u, [c, np.sqrt(R * R - c * c)], rtol=0.0, atol=1e-12)
    assert at.tangent is a.tangent
    turned = point_at(circle, a, b, 0, c, options, with_tangent=True)
    np.testing.assert_allclose(turned.tangent, [-at.u[1] / R, at.u[0] / R], atol=1e-12)
    with pytest.raises(ValueError):
        point_at(circle, a, b, 0, 0.5, options)  # not crossed between a and b
    below = CurvePoint(np.array([R * np.cos(-0.3), R * np.sin(-0.3)]), np.array([np.sin(0.3), np.cos(0.3)]))
    np.testing.assert_allclose(point_at(circle, below, a, 1, 0.0, options).u, [R, 0.0], atol=1e-12)


def test_the_corrector_stops_without_a_residual_after_a_correction_within_tolerance():
    """correct(): once F is within ``residual_tol`` and the correction within ``tol``, the corrected point
    is returned without F evaluated there again (one residual per iteration, not one more): on the
    circle, the point returned lies on it to the tolerance all the same."""
    from shimmy.continuation.core import correct

    class Counted(_Circle):
        calls = 0

        def residual(self, u):
            Counted.calls += 1
            return super().residual(u)

    circle = Counted(2.0)
    options = ContinuationOptions(tol=1e-9, residual_tol=1e-8)
    u, iterations, _ = correct(circle, np.array([2.05, 0.3]), np.array([0.0, 1.0]), options)
    assert Counted.calls == iterations and iterations >= 2
    assert abs(u @ u - 4.0) <= options.residual_tol and u[1] == pytest.approx(0.3, abs=1e-15)


def test_point_at_starts_from_the_cubic_through_both_points(monkeypatch):
    """point_at's Newton starts from the cubic through both points with their tangents, not from
    their chord: the same point (the circle's where x = c), in fewer iterations; a tangent that
    points against the chord (carried from an earlier point) leaves the chord's start."""
    from shimmy.continuation import core
    from shimmy.continuation.core import CurvePoint, point_at

    R = 2.0
    options = ContinuationOptions(tol=1e-12, residual_tol=1e-12)
    circle = _Circle(R)

    def on(angle):
        return CurvePoint(np.array([R * np.cos(angle), R * np.sin(angle)]), np.array([-np.sin(angle), np.cos(angle)]))

    a, b, c = on(0.2), on(1.0), 1.2
    cubic = point_at(circle, a, b, 0, c, options)
    np.testing.assert_allclose(cubic.u, [c, np.sqrt(R * R - c * c)], rtol=0.0, atol=1e-12)
    guess = core._hermite_at(a, b, 0, c, 0.5, circle.weights)
    assert abs(np.hypot(*guess) - R) < 1e-3 * R  # the cubic's point lies next to the circle
    assert abs(np.hypot(*(0.5 * (a.u + b.u))) - R) > 0.05 * R  # the chord's middle does not
    monkeypatch.setattr(core, "_hermite_at", lambda *args: None)
    chord = point_at(circle, a, b, 0, c, options)
    np.testing.assert_allclose(chord.u, cubic.u, rtol=0.0, atol=1e-12)
    assert cubic.iterations < chord.iterations
    monkeypatch.undo()
    assert core._hermite_at(a, CurvePoint(b.u, -b.tangent), 0, c, 0.5, circle.weights) is None


def test_advance_to_takes_a_guided_point_on_its_hyperplane_or_leaves_the_tracer_as_it_was():
    """Tracer.advance_to: from a predictor (a point of a nearby curve, a circle of radius 1.05 R) and
    a direction, the point of this curve (radius R) on the hyperplane through the predictor normal
    to the direction, with its tangent, the step length its distance; a predictor behind the
    current point, or a step that turns more than max_angle, is refused with the tracer unchanged."""
    from shimmy.continuation.core import CurvePoint, Tracer

    R = 2.0
    options = ContinuationOptions(ds=0.1, ds_max=1.0, tol=1e-12, residual_tol=1e-12, max_angle=0.5)
    tracer = Tracer(_Circle(R), CurvePoint(np.array([R, 0.0]), np.array([0.0, 1.0])), options)
    near = 1.05 * R
    predictor, direction = near * np.array([np.cos(0.3), np.sin(0.3)]), np.array([-np.sin(0.3), np.cos(0.3)])
    new, h = tracer.advance_to(predictor, direction)
    assert abs(new.u @ new.u - R * R) < 1e-10 and abs(direction @ (new.u - predictor)) < 1e-12
    np.testing.assert_allclose(new.tangent, [-new.u[1] / R, new.u[0] / R], atol=1e-12)
    assert h == pytest.approx(np.linalg.norm(new.u - np.array([R, 0.0]))) and tracer.h == pytest.approx(h)
    assert tracer.point is new
    before = tracer.point
    assert tracer.advance_to(near * np.array([1.0, 0.0]), np.array([0.0, 1.0])) is None  # behind
    assert tracer.advance_to(near * np.array([np.cos(1.2), np.sin(1.2)]), np.array([-np.sin(1.2), np.cos(1.2)])) is None
    assert tracer.point is before and tracer.h == pytest.approx(h)


def test_a_search_across_a_jump_ends_in_a_few_trials_and_a_smooth_one_is_unchanged():
    """locate_between with x_tol (a g that may jump: a multiplier test whose multiplier pairs off with
    another and leaves the real axis, the test then reading a third one): between angles 0.3 and 0.9 of
    the circle g goes from -4e-5 to +2e-5, but jumps to +3 on [0.6, 0.8) (the pair). The search bisects
    once a trial sees the jump (or at once, a step ending inside it) and gives up (None) when the bracket
    is 1e-4 of the step, in at most 20 trials (the secant search took over 200 on such a jump of the pd
    map); a smooth g finds the same point, through the same trials, with or without x_tol."""
    from shimmy.continuation.core import CurvePoint, locate_between

    R = 2.0
    options = ContinuationOptions(tol=1e-12, residual_tol=1e-12)
    circle = _Circle(R)
    a = CurvePoint(np.array([R * np.cos(0.3), R * np.sin(0.3)]), np.array([-np.sin(0.3), np.cos(0.3)]))
    b = CurvePoint(np.array([R * np.cos(0.9), R * np.sin(0.9)]), np.array([-np.sin(0.9), np.cos(0.9)]))
    trials = []

    def jump(q):
        angle = math.atan2(q.u[1], q.u[0])
        trials.append(angle)
        return 3.0 if 0.6 <= angle < 0.8 else 1e-4 * (angle - 0.7)

    assert locate_between(circle, a, b, jump, jump(a), jump(b), options, 1e-5, x_tol=1e-4) is None
    assert 3 < len(trials) - 2 <= 20
    assert abs(trials[-1] - 0.6) < 1e-3  # closed in on the jump
    inside = CurvePoint(np.array([R * np.cos(0.7), R * np.sin(0.7)]), np.array([-np.sin(0.7), np.cos(0.7)]))
    trials.clear()  # a step ending inside the jump (a half of a split step): jumping from its ends
    assert locate_between(circle, a, inside, jump, jump(a), jump(inside), options, 1e-5, x_tol=1e-4) is None
    assert len(trials) - 2 <= 20 and abs(trials[-1] - 0.6) < 1e-3

    def smooth(q):
        trials.append(q.u[0])
        return q.u[0] - 1.5

    found = []
    for x_tol in (None, 1e-4):
        trials.clear()
        hit = locate_between(circle, a, b, smooth, smooth(a), smooth(b), options, 1e-10, x_tol=x_tol)
        found.append((hit[0].u, list(trials)))
    np.testing.assert_allclose(found[0][0], [1.5, np.sqrt(R * R - 2.25)], atol=1e-9)
    assert np.array_equal(found[0][0], found[1][0]) and found[0][1] == found[1][1]


def test_a_step_leaving_the_range_ends_on_its_bound_and_one_starting_outside_does_not_fail():
    """advance_within: a step across the bound ends on the circle's point there (found with x held);
    a tracer already outside the range (a start moved past it) still gets an answer, not an error."""
    from shimmy.continuation.core import CurvePoint, Tracer

    R = 2.0
    options = ContinuationOptions(ds=0.3, ds_max=0.3, tol=1e-12, residual_tol=1e-12)
    start = CurvePoint(np.array([R * np.cos(0.3), R * np.sin(0.3)]), np.array([-np.sin(0.3), np.cos(0.3)]))
    prev, new, _, bound = Tracer(_Circle(R), start, options).advance_within(1.85, 2.5, 0)  # x: 1.91 -> 1.80
    assert bound == 1.85 and prev is start
    np.testing.assert_allclose(new.u, [1.85, np.sqrt(R * R - 1.85 ** 2)], atol=1e-12)
    np.testing.assert_allclose(new.tangent, [-new.u[1] / R, new.u[0] / R], atol=1e-12)
    outside = Tracer(_Circle(R), start, options).advance_within(1.0, 1.5, 0)  # x = 1.91 already above 1.5
    assert outside is not None and outside[3] == 1.5


def test_chord_control_bounds_how_far_each_drawn_step_strays_from_the_curve():
    """With a chord check (the cubic's midpoint deviation h/8 |t_a - t_b| over a tolerance) every
    accepted step of a circle of radius R has a sagitta R (1 - cos(angle / 2)) within the
    tolerance (to the estimate's O(h^4)), and the steps still use most of it; without the check
    the same options draw chords far off the circle."""
    from shimmy.continuation.core import CurvePoint, Tracer

    R, tol = 2.0, 1e-3
    options = ContinuationOptions(ds=0.05, ds_max=2.0, max_steps=100, tol=1e-12, residual_tol=1e-12)

    def sagittas(chord):
        tracer = Tracer(_Circle(R), CurvePoint(np.array([R, 0.0]), np.array([0.0, 1.0])), options, chord=chord)
        points = [tracer.point.u]
        for _ in range(30):
            tracer.advance()
            points.append(tracer.point.u)
        angles = [math.atan2(a[0] * b[1] - a[1] * b[0], a @ b) for a, b in zip(points[:-1], points[1:], strict=True)]
        return np.array([R * (1.0 - math.cos(0.5 * abs(a))) for a in angles])

    controlled = sagittas(lambda problem, a, b, h: 0.125 * h * float(np.linalg.norm(a.tangent - b.tangent)) / tol)
    assert controlled.max() <= 1.05 * tol
    assert controlled.max() >= 0.3 * tol
    assert sagittas(None).max() > 10 * tol


# --------------------------------------------------------------------------- equilibria


def test_fold_1d_is_located_and_stability_changes_there():
    br = equilibrium_branch(fold_1d(), np.array([1.0]), 1.0, p_range=(-1.0, 1.0), direction=-1)
    lp = only(br, "LP")
    assert abs(lp.p) < 1e-7 and abs(lp.data["x"][0]) < 1e-7
    np.testing.assert_allclose(br.p, br.x[:, 0] ** 2, atol=1e-10)  # every point on p = x^2
    np.testing.assert_allclose(br.eigenvalues[:, 0].real, -2.0 * br.x[:, 0], atol=1e-10)
    # x > 0 (before the fold) stable, x < 0 (after) unstable
    assert br.stable[:lp.index].all() and not br.stable[lp.index + 1:].any()
    assert np.all(br.stable == (br.x[:, 0] > 0))
    # back up the lower half to the bound: an end point exactly there
    ep = br.special_points[-1]
    assert ep.kind == "EP" and abs(ep.p - 1.0) <= 1e-9 and abs(br.p[-1] - 1.0) <= 1e-9
    assert abs(br.x[-1, 0] + 1.0) < 1e-8
    assert "bound p = 1" in br.stop_reason


def test_fold_2d_is_located_at_the_analytic_point():
    c = 0.3
    br = equilibrium_branch(fold_2d(c), np.array([1.0, 1.0]), 1.0 + c, p_range=(-1.0, 1.3), direction=-1)
    lp = only(br, "LP")
    assert abs(lp.p + c ** 2 / 4) < 1e-7
    np.testing.assert_allclose(lp.data["x"], [-c / 2, -c / 2], atol=1e-7)
    np.testing.assert_allclose(br.p, br.x[:, 0] ** 2 + c * br.x[:, 0], atol=1e-10)
    np.testing.assert_allclose(br.x[:, 0], br.x[:, 1], atol=1e-10)
    assert np.all(br.stable == (br.x[:, 0] > -c / 2))
    assert np.all(br.n_unstable == np.where(br.x[:, 0] > -c / 2, 0, 1))
    assert kinds(br) == ["LP", "EP"] and abs(br.p[-1] - 1.3) <= 1e-9


def test_hopf_point_of_the_normal_form():
    br = equilibrium_branch(hopf_supercritical(omega=2.0), np.zeros(2), -1.0, p_range=(-1.0, 1.0))
    h = only(br, "H")
    assert abs(h.p) < 1e-9 and abs(h.data["omega"] - 2.0) < 1e-9
    np.testing.assert_allclose(br.x, 0.0, atol=1e-14)
    np.testing.assert_allclose(br.eigenvalues[:, 0], br.p + 2j * np.sign(br.eigenvalues[:, 0].imag), atol=1e-12)
    assert np.all(br.stable == (br.p < 0)) and kinds(br) == ["H", "EP"]
    assert abs(br.p[-1] - 1.0) <= 1e-9


def test_two_hopf_points_of_a_growth_rate_mu_one_minus_mu():
    br = equilibrium_branch(hopf_twice(), np.zeros(2), -1.0, p_range=(-1.0, 2.0))
    assert kinds(br) == ["H", "H", "EP"]
    np.testing.assert_allclose([s.p for s in br.special_points[:2]], [0.0, 1.0], atol=1e-8)
    np.testing.assert_allclose([s.data["omega"] for s in br.special_points[:2]], 1.0, atol=1e-9)
    assert np.all(br.stable == ((br.p < 0) | (br.p > 1)))


@pytest.mark.parametrize("delta", [1e-2, 1e-3, 1e-4])
def test_two_hopf_points_inside_one_step_are_both_found(delta):
    """Both crossings within one step: the unstable count agrees at the step's ends, yet the
    pair is detected (eigenvalue slopes at the ends) and each point located."""
    options = ContinuationOptions(ds=0.2, ds_max=0.5)
    br = equilibrium_branch(hopf_close_pair(delta), np.zeros(2), 0.0, p_range=(0.0, 1.0), options=options)
    assert np.diff(br.p).max() > 10 * delta  # the steps are much longer than the gap
    assert kinds(br) == ["H", "H", "EP"]
    # located to the test-function tolerance: |Re lambda| = |(p - 1/2)^2 - delta^2| <= locate_tol
    p_h = np.array([s.p for s in br.special_points[:2]])
    assert np.all(np.abs((p_h - 0.5) ** 2 - delta ** 2) <= options.locate_tol)
    np.testing.assert_allclose(p_h, [0.5 - delta, 0.5 + delta], atol=options.locate_tol / delta)
    assert all(s.located for s in br.special_points[:2])


def test_two_pairs_crossing_within_one_step_give_two_hopf_points():
    """The unstable count jumps by four in one step: each pair's crossing is located."""
    options = ContinuationOptions(ds=0.2, ds_max=0.5)
    br = equilibrium_branch(two_pairs(1e-3), np.zeros(4), 0.0, p_range=(0.0, 1.0), options=options)
    assert kinds(br) == ["H", "H", "EP"]
    np.testing.assert_allclose([s.p for s in br.special_points[:2]], [0.5, 0.501], atol=1e-9)
    np.testing.assert_allclose([s.data["omega"] for s in br.special_points[:2]], [1.0, 2.0], atol=1e-9)


@pytest.mark.parametrize("make, x0", [(pitchfork, np.zeros(2)), (transcritical, np.zeros(1))],
                         ids=["pitchfork", "transcritical"])
def test_branch_point_on_the_trivial_branch(make, x0):
    br = equilibrium_branch(make(), x0, -1.0, p_range=(-1.0, 1.0))
    bp = only(br, "BP")
    assert abs(bp.p) < 1e-9
    assert kinds(br) == ["BP", "EP"]
    np.testing.assert_allclose(br.x, 0.0, atol=1e-14)
    assert np.all(br.stable == (br.p < 0))


# Regression: the secant in locate() used to land (to rounding) on the branch point, where the
# bordered Jacobian is singular, and the BP was dropped. locate() now nudges off a failed trial.


def test_branch_point_on_the_nontrivial_transcritical_branch():
    # x' = p x - x^2 on x = p: eigenvalue -p changes sign at p = 0, where x = 0 crosses.
    br = equilibrium_branch(transcritical(), np.array([-1.0]), -1.0, p_range=(-1.0, 1.0))
    np.testing.assert_allclose(br.x[:, 0], br.p, atol=1e-10)  # stays on x = p (this part passes)
    assert np.all(br.stable == (br.p > 0))
    bp = only(br, "BP")
    assert abs(bp.p) < 1e-7


def test_branch_point_of_the_pitchfork_followed_downward():
    # The same trivial branch as above, from p = 0.5 towards p = -0.7: the secant hits p = 0.0 exactly.
    br = equilibrium_branch(pitchfork(), np.zeros(2), 0.5, p_range=(-0.7, 1.0), direction=-1)
    assert np.all(br.stable == (br.p < 0))  # (passes)
    bp = only(br, "BP")
    assert abs(bp.p) < 1e-9


def test_equilibrium_branch_downward_and_stop_rules():
    br = equilibrium_branch(pitchfork(), np.zeros(2), 0.5, p_range=(-0.7, 1.0), direction=-1)
    assert np.all(np.diff(br.p) < 0)
    assert br.special_points[-1].kind == "EP" and abs(br.p[-1] + 0.7) <= 1e-9
    assert "p = -0.7" in br.stop_reason
    short = equilibrium_branch(pitchfork(), np.zeros(2), 0.5, p_range=(-10.0, 10.0),
                               options=ContinuationOptions(max_steps=3))
    assert short.steps == 3 and len(short.p) == 4 and "step budget of 3" in short.stop_reason
    with pytest.raises(ValueError, match="no equilibrium"):
        equilibrium_branch(fold_1d(), np.array([0.5]), -1.0, p_range=(-2.0, 2.0))  # p - x^2 = 0 has no root at p = -1


# --------------------------------------------------------------------------- Hopf normal forms


def test_supercritical_hopf_branch_amplitude_period_and_multipliers():
    omega = 2.0
    br = hopf_branch(hopf_supercritical(omega), omega, 0.0, -1.0, 1.0)
    T = math.pi
    assert np.all(np.diff(br.p) > 0) and br.p[0] > 0
    for i in range(len(br.p)):  # r^2 = mu at every node
        np.testing.assert_allclose(node_radius(br, i), math.sqrt(br.p[i]), atol=1e-9)
    np.testing.assert_allclose(br.x_max[:, 0], np.sqrt(br.p), rtol=1e-4)  # x_max is sampled (12 per interval)
    np.testing.assert_allclose(br.period, T, atol=1e-9)
    assert br.stable.all()
    # Floquet: trivial 1, radial exp(-2 mu T)
    assert br.trivial_error < 1e-8
    np.testing.assert_allclose(br.multipliers[:, 1], np.exp(-2.0 * br.p * T), atol=1e-9)
    assert kinds(br) == ["EP"] and abs(br.p[-1] - 1.0) <= 1e-9 and "bound p = 1" in br.stop_reason


def test_points_between_steps_lie_on_the_branch_where_the_chord_in_p_does_not():
    """PeriodicBranch.between: the cubic in arclength through two points and their rates. On the
    normal form r = mu^(1/2) (steep at the Hopf point) its midpoints are within 2e-4 of the exact
    amplitude (x_max is sampled, 12 per interval: 1e-4 of itself), where the straight segment in
    p misses by up to ~3 % next to the Hopf point; rates against finite differences of x_max."""
    br = hopf_branch(hopf_supercritical(2.0), 2.0, 0.0, -1.0, 1.0)
    assert br.rates.shape == (br.p.size, 2 + 2 * 2) and br.lengths[0] == 0.0 and np.all(br.lengths[1:] > 0)
    cubic, chord = [], []
    for i in range(br.p.size - 1):
        p, T, x_max, x_min = br.between(i, np.array([0.0, 0.5, 1.0]))
        np.testing.assert_allclose(p[[0, 2]], br.p[i:i + 2], rtol=0, atol=1e-15)  # through both points
        np.testing.assert_allclose(T, math.pi, atol=1e-9)
        exact = math.sqrt(p[1])
        cubic.append(abs(x_max[1, 0] - exact) / exact)
        cubic.append(abs(-x_min[1, 1] - exact) / exact)
        chord.append(abs(np.interp(p[1], br.p[i:i + 2], br.x_max[i:i + 2, 0]) - exact) / exact)
    assert max(cubic) < 2e-4, max(cubic)
    assert max(chord) > 1e-2, max(chord)  # the step control alone leaves the chord this far off
    # rates: d p / ds and d x_max / ds against centred differences over the neighbours (their error,
    # second order in the long steps of this branch, is up to 1 % of the largest rate)
    s = np.cumsum(br.lengths)
    middle = slice(1, br.p.size - 1)
    for column, values in ((0, br.p), (2, br.x_max[:, 0])):
        a, b, c = values[:-2], values[1:-1], values[2:]
        ha, hb = s[1:-1] - s[:-2], s[2:] - s[1:-1]
        centred = (hb / ha * (b - a) + ha / hb * (c - b)) / (ha + hb)
        np.testing.assert_allclose(br.rates[middle, column], centred, atol=2e-2 * np.abs(br.rates[:, column]).max())


def test_points_between_steps_through_a_fold_of_cycles():
    """Across the fold of the quintic normal form (p turns inside a step of arclength 0.16) the
    cubic in arclength stays near the branch: p + r^2 - r^4 = 0 at every step's midpoint to 3e-3 of
    r^2 (the error of the cubic, fourth order in the step, is largest at the fold), against
    1.5e-2 for the midpoint of the straight segment there."""
    br = hopf_branch(hopf_subcritical_quintic(1.0), 1.0, 0.0, -1.0, 1.0, PeriodicOptions(ntst=40, ncol=4))
    cubic, chord = [], []
    for i in range(br.p.size - 1):
        p, _, x_max, _ = br.between(i, np.array([0.5]))
        for where, q, r in ((cubic, p[0], x_max[0, 0]), (chord, br.p[i:i + 2].mean(), br.x_max[i:i + 2, 0].mean())):
            where.append(abs(q + r ** 2 - r ** 4) / r ** 2)
    assert max(cubic) < 3e-3 and max(chord) > 5 * max(cubic), (max(cubic), max(chord))


@pytest.mark.parametrize("mu", [0.1, 0.5, 2.0])
def test_multipliers_of_the_exact_circle(mu):
    """PeriodicProblem.multipliers on the exact orbit (no continuation): [1, exp(-2 mu T)]."""
    omega, T = 2.0, math.pi
    mesh = Mesh.uniform(40, 4)
    theta = TWO_PI * mesh.node_times
    problem = PeriodicProblem(hopf_supercritical(omega), mesh, np.ones(2), 1.0, 1.0)
    u = problem.pack(math.sqrt(mu) * np.column_stack([np.cos(theta), np.sin(theta)]), T, mu)
    mult = problem.multipliers(u)
    np.testing.assert_allclose(mult, [1.0, math.exp(-2.0 * mu * T)], atol=1e-8)


def test_subcritical_quintic_fold_of_cycles():
    br = hopf_branch(hopf_subcritical_quintic(1.0), 1.0, 0.0, -1.0, 1.0, PeriodicOptions(ntst=40, ncol=4))
    r2 = np.array([np.mean(node_radius(br, i) ** 2) for i in range(len(br.p))])
    np.testing.assert_allclose(br.p + r2 - r2 ** 2, 0.0, atol=1e-9)  # G(mu, r^2) = 0 on every cycle
    np.testing.assert_allclose(br.period, TWO_PI, atol=1e-9)
    lpc = only(br, "LPC")
    assert abs(lpc.p + 0.25) < 1e-8
    assert abs(lpc.data["x_max"][0] ** 2 - 0.5) < 2e-4  # sampled x_max
    assert kinds(br) == ["LPC", "EP"]
    # born at mu = 0 going to mu < 0 on the inner (unstable) cycle, then the outer stable one
    assert br.p[1] < 0 and np.all(np.diff(br.p[:lpc.index]) < 0)
    assert not br.stable[:lpc.index].any() and br.stable[lpc.index + 1:].all()
    np.testing.assert_allclose(r2[lpc.index + 1:], (1 + np.sqrt(1 + 4 * br.p[lpc.index + 1:])) / 2, atol=1e-9)
    np.testing.assert_allclose(r2[:lpc.index], (1 - np.sqrt(1 + 4 * br.p[:lpc.index])) / 2, atol=1e-9)
    exact = np.exp(2 * r2 * (1 - 2 * r2) * TWO_PI)
    np.testing.assert_allclose(np.abs(br.multipliers[:, 1]), exact, rtol=1e-7, atol=1e-12)
    assert br.trivial_error < 1e-8
    assert abs(br.p[-1] - 1.0) <= 1e-9


@pytest.mark.parametrize("p0, p_end", [(0.0, 1.0), (1.0, 0.0)])
def test_branch_between_two_hopf_points_ends_at_the_second(p0, p_end):
    br = hopf_branch(hopf_twice(1.0), 1.0, p0, -1.0, 2.0)
    h = br.special_points[-1]
    assert h.kind == "H" and abs(h.p - p_end) < 1e-2
    assert "Hopf point" in br.stop_reason
    for i in range(len(br.p)):  # r^2 = mu (1 - mu)
        np.testing.assert_allclose(node_radius(br, i) ** 2, br.p[i] * (1 - br.p[i]), atol=1e-9)
    assert br.stable.all() and br.trivial_error < 1e-8


# --------------------------------------------------------------------------- Van der Pol


@pytest.fixture(scope="module")
def vdp_orbit_mu1():
    """One period of the Van der Pol cycle at mu = 1 (tight-tolerance integration), and int (1 - x^2) dt."""
    system = van_der_pol()

    def rhs(t, z):
        return np.append(system.f(z[:2], 1.0), 1.0 - z[0] ** 2)

    sol = solve_ivp(rhs, (0.0, VDP_PERIOD_MU1), [VDP_AMPLITUDE_MU1, 0.0, 0.0], method="DOP853", rtol=1e-12,
                    atol=1e-12, dense_output=True)
    t = np.linspace(0.0, VDP_PERIOD_MU1, 400)
    return t, sol.sol(t)[:2].T, sol.y[:, -1]


def test_van_der_pol_reference_values_close_the_orbit(vdp_orbit_mu1):
    """The published (T, max x) at mu = 1: starting at (max x, 0) the flow returns there after T."""
    _, _, end = vdp_orbit_mu1
    np.testing.assert_allclose(end[:2], [VDP_AMPLITUDE_MU1, 0.0], atol=1e-9)


def test_van_der_pol_branch_to_mu_1(vdp_orbit_mu1):
    # The Hopf point of Van der Pol at mu = 0 is degenerate (the system is linear there: every circle is
    # an orbit), so the branch is started on the cycle near the circle of radius 2 at mu = 0.2.
    system = van_der_pol()
    br = periodic_branch(system, unit_cycle_guess(40, 2, 0.2, radius=2.0, sign=-1.0), p_range=(0.1, 1.0),
                         options=PeriodicOptions(ntst=40, ncol=4), scale=np.ones(2), p_scale=1.0, p_direction=1)
    assert kinds(br) == ["EP"] and abs(br.p[-1] - 1.0) <= 1e-9 and "bound p = 1" in br.stop_reason
    assert abs(br.p[0] - 0.2) < 1e-14 and np.all(np.diff(br.p) > 0)
    # Lindstedt: omega = 1 - mu^2/16 + 17 mu^4/3072 + 35 mu^6/884736 + O(mu^8)
    mu = 0.2
    omega = 1 - mu ** 2 / 16 + 17 * mu ** 4 / 3072 + 35 * mu ** 6 / 884736
    assert abs(br.period[0] * omega / TWO_PI - 1.0) < 1e-8
    assert np.all(np.diff(br.period) > 0)
    # published values at mu = 1
    assert abs(br.period[-1] / VDP_PERIOD_MU1 - 1.0) < 1e-6
    assert abs(refined_max(system, br, len(br.p) - 1) / VDP_AMPLITUDE_MU1 - 1.0) < 1e-6
    assert abs(br.x_max[-1, 0] / VDP_AMPLITUDE_MU1 - 1.0) < 2e-5  # sampled maximum
    # multipliers: stable cycle; Liouville: the nontrivial one is exp(int_0^T mu (1 - x^2) dt)
    assert br.stable.all() and br.trivial_error < 1e-8
    liouville = math.exp(vdp_orbit_mu1[2][2])
    assert abs(br.multipliers[-1, 1].real / liouville - 1.0) < 1e-6 and br.multipliers[-1, 1].imag == 0


@pytest.mark.parametrize("ncol", [2, 3, 4])
def test_van_der_pol_period_converges_at_order_2_ncol(vdp_orbit_mu1, ncol):
    """Period at mu = 1 on uniform meshes (first point of a branch: solved with p held at 1 exactly).

    Gauss collocation is superconvergent: the error of the period is O(h^(2 ncol)).
    """
    t, x, _ = vdp_orbit_mu1
    ntsts = (20, 40, 80)
    errors = []
    for ntst in ntsts:
        opts = PeriodicOptions(ntst=ntst, ncol=ncol, adapt_every=0,
                               continuation=ContinuationOptions(max_steps=1, tol=1e-12, residual_tol=1e-11))
        guess = orbit_from_samples(t, x, 1.001 * VDP_PERIOD_MU1, 1.0, Mesh.uniform(ntst, ncol))
        br = periodic_branch(van_der_pol(), guess, p_range=(0.5, 1.5), options=opts, scale=np.ones(2), p_scale=1.0,
                             p_direction=1)
        assert br.p[0] == 1.0
        errors.append(abs(br.period[0] - VDP_PERIOD_MU1))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(orders > 2 * ncol - 0.5), (errors, orders)
    if ncol == 4:
        assert errors[1] / VDP_PERIOD_MU1 < 1e-8  # ntst 40, ncol 4


# --------------------------------------------------------------------------- constructed 4-D systems


@pytest.mark.parametrize("name, p", [("neimark_sacker", 0.2), ("neimark_sacker", 0.8), ("period_doubling", 0.2),
                                     ("period_doubling", 0.8)])
def test_constructed_multipliers_by_integration(name, p):
    """The claimed multipliers of the unit cycle, from the variational equation (independent of the engine)."""
    system = ALL_SYSTEMS[name]()

    def rhs(t, z):
        M = z[4:].reshape(4, 4)
        return np.concatenate([system.f(z[:4], p), (system.dfdx(z[:4], p) @ M).ravel()])

    sol = solve_ivp(rhs, (0.0, TWO_PI), np.concatenate([[1.0, 0, 0, 0], np.eye(4).ravel()]), method="DOP853",
                    rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(sol.y[:4, -1], [1, 0, 0, 0], atol=1e-9)
    a = (p - 0.5) * TWO_PI
    if name == "neimark_sacker":
        rot = np.exp(1j * math.sqrt(2) * TWO_PI)
        claimed = [1.0, math.exp(-2 * TWO_PI), math.exp(a) * rot, math.exp(a) * np.conj(rot)]
    else:
        claimed = [1.0, math.exp(-2 * TWO_PI), -math.exp(a), -math.exp(-TWO_PI)]
    mult = np.linalg.eigvals(sol.y[4:, -1].reshape(4, 4))
    np.testing.assert_allclose(np.sort_complex(mult), np.sort_complex(np.array(claimed, complex)), atol=1e-8)


def test_neimark_sacker_point_of_the_constructed_system():
    beta, w2 = 0.5, math.sqrt(2.0)
    br = periodic_branch(neimark_sacker(beta=beta, w2=w2), unit_cycle_guess(40, 4, 0.2), p_range=(0.0, 1.0),
                         options=PeriodicOptions(ntst=40, ncol=4), scale=np.ones(4), p_scale=1.0, p_direction=1)
    assert kinds(br) == ["NS", "EP"]
    ns = br.special_points[0]
    assert abs(ns.p - beta) < 1e-8
    angle = abs(np.angle(np.exp(1j * w2 * TWO_PI)))  # w2 T mod 2 pi folded to [0, pi]: 2 pi (sqrt 2 - 1)
    assert abs(ns.data["torus_angle"] - angle) < 1e-7
    np.testing.assert_allclose(ns.data["multipliers_abs"][:2], 1.0, atol=1e-8)
    assert np.all(br.stable == (br.p < beta))
    np.testing.assert_allclose(br.period, TWO_PI, atol=1e-9)
    assert br.trivial_error < 1e-8
    a = (br.p - beta) * TWO_PI
    pair = np.exp(a) * np.exp(1j * w2 * TWO_PI)
    np.testing.assert_allclose(np.sort_complex(br.multipliers[:, 1:3]),
                               np.sort_complex(np.column_stack([pair, pair.conj()])), atol=1e-8)
    np.testing.assert_allclose(br.multipliers[:, 3], math.exp(-2 * TWO_PI), atol=1e-9)


def test_period_doubling_point_of_the_constructed_system():
    beta = 0.5
    br = periodic_branch(period_doubling(beta=beta), unit_cycle_guess(40, 4, 0.2), p_range=(0.0, 1.0),
                         options=PeriodicOptions(ntst=40, ncol=4), scale=np.ones(4), p_scale=1.0, p_direction=1)
    assert kinds(br) == ["PD", "EP"]
    pd = br.special_points[0]
    assert abs(pd.p - beta) < 1e-8
    assert abs(pd.data["multipliers_abs"][0] - 1.0) < 1e-8
    assert np.all(br.stable == (br.p < beta))
    # the critical multiplier is real and equal to -exp((p - beta) T): it passes through -1 at beta
    mult = br.multipliers
    np.testing.assert_allclose(mult[:, 1], -np.exp((br.p - beta) * TWO_PI), rtol=1e-8)
    assert np.all(mult[:, 1].imag == 0)
    np.testing.assert_allclose(mult[:, 2], -math.exp(-TWO_PI), atol=1e-9)
    np.testing.assert_allclose(node_radius(br, len(br.p) - 1), 1.0, atol=1e-9)
    assert br.trivial_error < 1e-8


# --------------------------------------------------------------------------- stop rules


def test_periodic_step_budget():
    opts = PeriodicOptions(ntst=20, ncol=4, continuation=ContinuationOptions(max_steps=3))
    br = hopf_branch(hopf_supercritical(2.0), 2.0, 0.0, -1.0, 2.0, opts)
    assert br.steps == 3 and len(br.p) == 4
    assert "step budget of 3 steps" in br.stop_reason and kinds(br) == []


def test_periodic_period_limit():
    # rotation W = 2 - r^2 and r^2 = mu: T = 2 pi / (2 - mu) grows; T = 5 at mu = 2 - 2 pi / 5
    br = hopf_branch(hopf_shear(2.0, -1.0), 2.0, 0.0, -1.0, 2.0, PeriodicOptions(ntst=20, ncol=4, period_max=5.0))
    np.testing.assert_allclose(br.period, TWO_PI / (2.0 - br.p), rtol=1e-9)
    assert "period" in br.stop_reason and "limit 5" in br.stop_reason
    assert np.all(br.period <= 5.0) and br.p[-1] < 2.0 - TWO_PI / 5.0
    # the message names where the limit was passed: just beyond the last orbit kept
    p_stop = float(br.stop_reason.split("at p = ")[1].split()[0])
    assert br.p[-1] < p_stop and TWO_PI / (2.0 - p_stop) > 5.0
    assert br.p[-1] > 0.5  # it did go most of the way


def test_periodic_limits_callback_message_is_the_stop_reason():
    calls = []

    def limits(x_max, x_min, T, p):
        calls.append((np.array(x_max), np.array(x_min), T, p))
        return "amplitude above 0.5" if x_max[0] > 0.5 else None

    br = hopf_branch(hopf_supercritical(2.0), 2.0, 0.0, -1.0, 2.0, limits=limits)
    assert br.stop_reason == "amplitude above 0.5"
    assert br.x_max[-1, 0] > 0.5 and np.all(br.x_max[:-1, 0] <= 0.5)
    x_max, x_min, T, p = calls[-1]
    np.testing.assert_array_equal(x_max, br.x_max[-1])
    np.testing.assert_array_equal(x_min, br.x_min[-1])
    assert T == br.period[-1] and p == br.p[-1]


def test_no_orbit_near_the_guess_raises_convergence_error():
    # r' = r (mu - r^2) has no cycle at mu = -0.5: a unit circle does not converge
    guess = unit_cycle_guess(10, 2, -0.5)
    with pytest.raises(ConvergenceError, match="no periodic orbit"):
        periodic_branch(hopf_supercritical(2.0), guess, p_range=(-1.0, 1.0), options=PeriodicOptions(ntst=10),
                        scale=np.ones(2), p_scale=1.0)


# --------------------------------------------------------------------------- options


@pytest.mark.parametrize("cls, kwargs, name", [
    (ContinuationOptions, {"ds": -1.0}, "ds"),
    (ContinuationOptions, {"ds": 0.6}, "ds"),  # above ds_max
    (ContinuationOptions, {"ds_min": 0.0}, "ds_min"),
    (ContinuationOptions, {"tol": math.nan}, "tol"),
    (ContinuationOptions, {"residual_tol": math.inf}, "residual_tol"),
    (ContinuationOptions, {"max_steps": 0}, "max_steps"),
    (ContinuationOptions, {"max_newton": 2.5}, "max_newton"),
    (PeriodicOptions, {"ntst": 1}, "ntst"),
    (PeriodicOptions, {"ntst": 40.0}, "ntst"),
    (PeriodicOptions, {"ncol": 8}, "ncol"),
    (PeriodicOptions, {"ncol": 1}, "ncol"),
])
def test_bad_options_raise_invalid_parameter_error_naming_the_field(cls, kwargs, name):
    with pytest.raises(InvalidInputError) as info:
        cls(**kwargs)
    assert info.value.field == name
    assert name in str(info.value)


def test_closed_loop_of_cycles_is_traversed_once():
    """An isola: G = 1 - p^2 - (r^2 - 2)^2 gives cycles r^2 = 2 +- sqrt(1 - p^2) for |p| <= 1, a
    closed curve with folds (LPC) at p = +-1; x = 0 is stable for every p (no Hopf point), so
    only a start on an orbit finds it. The branch must stop after one lap, not run its budget."""
    from textbook_systems import planar_normal_form

    system = planar_normal_form(g=lambda p: -3.0 - p * p, dg=lambda p: -2.0 * p, a1=4.0, a2=-1.0, name="isola")
    guess = unit_cycle_guess(40, 2, 0.0, radius=math.sqrt(3.0))
    br = periodic_branch(system, guess, p_range=(-5.0, 5.0),
                         options=PeriodicOptions(ntst=40, continuation=ContinuationOptions(ds=0.05, ds_max=0.2,
                                                                                   max_steps=400)),
                         scale=np.ones(2), p_scale=1.0)
    assert br.stop_reason.startswith("closed branch")
    assert br.steps < 200
    folds = sorted(s.p for s in br.special_points if s.kind == "LPC")
    assert len(folds) == 2
    np.testing.assert_allclose(folds, [-1.0, 1.0], atol=1e-6)
    r2 = node_radius(br, 0) ** 2
    assert abs(r2.mean() - 3.0) < 1e-6
    # Outer half (r^2 > 2) stable, inner half unstable: exponent 2 r^2 (4 - 2 r^2).
    radius2 = np.array([node_radius(br, i).mean() ** 2 for i in range(br.p.size)])
    away = np.abs(radius2 - 2.0) > 0.05
    assert np.all(br.stable[away] == (radius2[away] > 2.0))


@pytest.mark.parametrize("phase", [0.0, 0.3217, 0.999])
def test_peak_of_an_orbit_is_located_on_the_collocation_polynomial(phase):
    """x(tau) = -1.7 cos(2 pi s) + 0.3 cos(4 pi s), s = tau - phase, on an uneven mesh: the largest |x|
    is 2 at tau = phase + 1/2 (mod 1), whatever sample is nearest (|x| = 1.4 at s = 0); sign +."""
    system = ALL_SYSTEMS["hopf_supercritical"]()  # the field does not enter: only the node values
    points = np.sort(np.concatenate([[0.0, 1.0], np.random.default_rng(1).uniform(0.02, 0.98, 29)]))
    mesh = Mesh(points, 4)
    problem = PeriodicProblem(system, mesh, np.ones(system.n), 1.0, 1.0)
    X = np.zeros((mesh.n_nodes, system.n))
    s = mesh.node_times - phase
    X[:, 0] = -1.7 * np.cos(2 * np.pi * s) + 0.3 * np.cos(4 * np.pi * s)
    tau, sign, amplitude = problem.peak(problem.pack(X, 1.0, 0.0), 0)
    assert amplitude == pytest.approx(2.0, rel=1e-4)  # interpolation error of degree 4 on intervals up to ~0.1
    dense = np.abs(problem.evaluate(X, np.linspace(0.0, 1.0, 200001))[:, 0]).max()  # the polynomial's own maximum
    assert amplitude == pytest.approx(dense, rel=1e-9)
    assert sign == 1.0
    offset = (tau - phase - 0.5) % 1.0
    assert min(offset, 1.0 - offset) == pytest.approx(0.0, abs=1e-4)
    sampled = np.abs(problem.sample(problem.pack(X, 1.0, 0.0))[1][:, 0]).max()
    assert amplitude >= sampled


@pytest.mark.parametrize("phase", [0.0, 0.3217, 0.999])
def test_extremes_of_an_orbit_are_its_polynomials_largest_and_smallest_values(phase):
    """x(tau) = 0.4 + 1.1 sin(2 pi s) + 0.5 cos(6 pi s), s = tau - phase, on an uneven mesh: no symmetry,
    max and min at no sample; against the polynomials evaluated on a dense grid (their own extremes)."""
    system = ALL_SYSTEMS["hopf_supercritical"]()  # the field does not enter: only the node values
    points = np.sort(np.concatenate([[0.0, 1.0], np.random.default_rng(2).uniform(0.02, 0.98, 23)]))
    mesh = Mesh(points, 4)
    problem = PeriodicProblem(system, mesh, np.ones(system.n), 1.0, 1.0)
    X = np.zeros((mesh.n_nodes, system.n))
    s = mesh.node_times - phase
    X[:, 1] = 0.4 + 1.1 * np.sin(2 * np.pi * s) + 0.5 * np.cos(6 * np.pi * s)
    u = problem.pack(X, 1.0, 0.0)
    high, low = problem.extremes(u, 1)
    dense = problem.evaluate(X, np.linspace(0.0, 1.0, 400001))[:, 1]
    assert high == pytest.approx(dense.max(), rel=1e-10) and low == pytest.approx(dense.min(), rel=1e-10)
    sampled = problem.sample(u)[1][:, 1]
    assert high >= sampled.max() and low <= sampled.min()
    assert high > sampled.max() + 1e-7 or low < sampled.min() - 1e-7  # the samples miss them


class _FlatWithNoise:
    """One equation 1e-8 (u0 - 1) = 0 whose evaluation carries rounding-like noise of size
    ``noise`` that flips sign at every call: Newton's corrections are noise / 1e-8."""

    def __init__(self, noise: float):
        self.noise, self.calls = noise, 0
        self.weights = np.ones(2)

    def residual(self, u):
        self.calls += 1
        return np.array([1e-8 * (u[0] - 1.0) + self.noise * (-1.0) ** self.calls])

    def jacobian(self, u):
        return np.array([[1e-8, 0.0]])

    def accept(self, u):
        pass


def test_newton_at_the_noise_floor_is_converged_and_a_stalled_large_residual_is_not():
    """A nearly flat equation turns rounding noise in F into corrections above ``tol`` that never
    shrink (a fold-of-cycles test function near a Hopf point): with |F| already ~6e-17 and
    corrections ~6e-9 the point is converged. The same stall with |F| at 1e-9 (only 10x below
    residual_tol), or with corrections of 1e-5 (the point not known to better than that), fails."""
    from shimmy.continuation.core import correct

    options = ContinuationOptions()
    out = correct(_FlatWithNoise(3e-17), np.array([1.0, 0.0]), np.array([0.0, 1.0]), options)
    assert out is not None and abs(out[0][0] - 1.0) < 1e-8
    assert correct(_FlatWithNoise(1e-9), np.array([1.0, 0.0]), np.array([0.0, 1.0]), options) is None
    assert correct(_FlatWithNoise(1e-13), np.array([1.0, 0.0]), np.array([0.0, 1.0]), options) is None


def test_a_seeded_branch_shrinking_to_the_equilibrium_ends_at_the_hopf_point():
    """A branch started from an orbit (not at a Hopf point) at its largest amplitude, followed
    towards the Hopf point: r^2 = mu shrinks to zero at mu = 0. It ends there with an H point; it
    must not pass through x = 0 and go on along the constant 'orbits' x = 0 (any period), where
    the equilibrium's eigenvalues would be reported as spurious folds and torus points."""
    omega = 2.0
    system = hopf_supercritical(omega)
    mesh = Mesh.uniform(20, 4)
    theta = 2 * np.pi * mesh.node_times
    guess = OrbitGuess(mesh, 0.5 * np.column_stack([np.cos(theta), np.sin(theta)]), math.pi, 0.25)
    br = periodic_branch(system, guess, p_range=(-1.0, 1.0), options=PeriodicOptions(ntst=20), scale=np.ones(2),
                         p_scale=1.0, p_direction=-1)
    assert "amplitude returned to zero" in br.stop_reason, br.stop_reason
    assert kinds(br) == ["H"] and 0.0 <= br.p[-1] < 0.01
    assert br.x_max[:, 0].min() > 1e-5 and br.p.min() > 0.0  # stopped just below 1e-3 of the peak, not at 0


class _DoubleRoot:
    """1e-2 (u0 - 1)^2 = 0: Newton converges linearly, each correction half the last."""

    weights = np.ones(2)

    def residual(self, u):
        return np.array([1e-2 * (u[0] - 1.0) ** 2])

    def jacobian(self, u):
        return np.array([[2e-2 * (u[0] - 1.0), 0.0]])

    def accept(self, u):
        pass


def test_newton_converging_at_rate_one_half_is_not_taken_for_noise():
    from shimmy.continuation.core import correct

    out = correct(_DoubleRoot(), np.array([1.0 + 1e-6, 0.0]), np.array([0.0, 1.0]), ContinuationOptions())
    assert out is not None and abs(out[0][0] - 1.0) < 5e-9  # the rule stopping it gave 2e-8
