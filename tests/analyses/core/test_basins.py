"""The basin bookkeeping of shimmy.analyses.core.basins on textbook systems whose basins are known in closed
form: radial normal forms r' = r g(r) (plus a rotation), whose basin boundaries are circles (spheres) of
known radius, seen through a linear change of coordinates where the test needs an anisotropic boundary."""

from __future__ import annotations

import math

import numpy as np
import pytest

from shimmy.analyses.core.basins import (UNSETTLED, Ray, geometric_sizes, refine, sample_ball, scan,
                                          smallest_over_directions, sweep_directions, wilson)

MU = -0.2
R_UNSTABLE = math.sqrt((1 - math.sqrt(1 + 4 * MU)) / 2)  # the subcritical Hopf form's unstable cycle
R_STABLE = math.sqrt((1 + math.sqrt(1 + 4 * MU)) / 2)


def subcritical(r):
    """r' = r g(r), g = mu + r^2 - r^4: x = 0 stable, the cycle R_UNSTABLE unstable, R_STABLE stable."""
    return MU + r ** 2 - r ** 4


def three_cycles(r):
    """g = -(r - 1)(r - 2)(r - 3): x = 0 unstable, cycles r = 1 (stable), 2 (unstable), 3 (stable)."""
    return -(r - 1.0) * (r - 2.0) * (r - 3.0)


def radial_probe(g, targets, M=None, t_end=100.0, dt=0.05):
    """A probe for y' = g(|y|) y + W y (W: rotations in the planes (0, 1), (2, 3)), y = M x: RK4 on the
    whole batch at once; label k if the final radius is within 0.05 of targets[k]."""
    def rates(y):
        r = np.linalg.norm(y, axis=1)[:, None]
        w = np.zeros_like(y)
        w[:, 0], w[:, 1] = -y[:, 1], y[:, 0]
        if y.shape[1] == 4:
            w[:, 2], w[:, 3] = -0.7 * y[:, 3], 0.7 * y[:, 2]
        return g(r) * y + w

    def probe(points):
        y = np.asarray(points, float) @ (np.eye(points.shape[1]) if M is None else M).T
        for _ in range(int(t_end / dt)):
            k1 = rates(y)
            k2 = rates(y + 0.5 * dt * k1)
            k3 = rates(y + 0.5 * dt * k2)
            k4 = rates(y + dt * k3)
            y = y + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        r = np.linalg.norm(y, axis=1)
        labels = np.full(r.size, UNSETTLED)
        for k, target in enumerate(targets):
            labels[np.abs(r - target) < 0.05] = k
        return labels.tolist()
    return probe


def test_bisection_finds_the_unstable_cycle_of_the_subcritical_hopf_form_within_its_tolerance():
    """Along any direction the runs end at x = 0 below R_UNSTABLE and on the stable cycle above it."""
    probe = radial_probe(subcritical, [0.0, R_STABLE])
    rays = [Ray(u) for u in sweep_directions(2)]
    scan(rays, geometric_sizes(0.01, 1.5, 12), probe)
    rounds = refine(rays, probe, rtol=1e-3, width=2)
    assert rounds < 12
    for ray in rays:
        assert ray.reached() == [0, 1]
        zero, cycle = ray.threshold(0), ray.threshold(1)
        assert zero.lower == 0.0 and zero.value == 0.0  # the smallest disturbance decays
        assert cycle.lower < R_UNSTABLE <= cycle.upper and cycle.upper - cycle.lower <= 1e-3 * cycle.upper
        assert abs(cycle.value - R_UNSTABLE) <= cycle.tolerance and cycle.lower_label == 0


def test_two_stable_cycles_are_separated_at_the_unstable_one():
    """x = 0 unstable: the smallest disturbance ends on the inner cycle (threshold 0); the outer cycle from r = 2."""
    probe = radial_probe(three_cycles, [1.0, 3.0], t_end=40.0)
    rays = [Ray(np.array([0.6, 0.8]))]
    scan(rays, geometric_sizes(0.05, 3.5, 10), probe)
    refine(rays, probe, rtol=1e-4, width=3)
    inner, outer = rays[0].threshold(0), rays[0].threshold(1)
    assert inner.value == 0.0 and inner.tolerance == pytest.approx(0.05)
    assert outer.lower < 2.0 <= outer.upper and outer.upper - outer.lower <= 1e-4 * outer.upper


def anisotropic_map() -> np.ndarray:
    """y = M x with singular values 2.5, 1.4, 1, 0.6 and the largest one's right singular vector off every
    axis and diagonal of the sweep."""
    rng = np.random.default_rng(7)
    q1, _ = np.linalg.qr(rng.standard_normal((4, 4)))
    q2, _ = np.linalg.qr(np.column_stack([[0.3, 0.5, 0.7, -0.4], rng.standard_normal((4, 3))]))
    return q1 @ np.diag([2.5, 1.4, 1.0, 0.6]) @ q2.T


def test_the_smallest_threshold_over_all_directions_is_the_nearest_point_of_the_basin_boundary():
    """The boundary |M x| = R_UNSTABLE is nearest the origin at R_UNSTABLE / s_max, along the right singular
    vector of the largest singular value s_max; the sweep and the pattern search find both."""
    M = anisotropic_map()
    _, s, vt = np.linalg.svd(M)
    exact = R_UNSTABLE / s[0]
    probe = radial_probe(subcritical, [0.0, R_STABLE], M, dt=0.1)
    sweep = sweep_directions(4)
    assert np.max(np.abs(sweep @ vt[0])) < math.cos(math.radians(15))  # no swept direction is near the answer
    rays, best = smallest_over_directions(probe, 4, geometric_sizes(0.02, 0.8, 10), rtol=2e-3, width=2)
    assert len(rays) == 16 and set(best) == {0, 1}
    assert best[0].threshold.value == 0.0
    found = best[1]
    assert found.threshold.lower < R_UNSTABLE / np.linalg.norm(M @ found.direction) <= found.threshold.upper
    assert abs(found.threshold.value - exact) <= 0.01 * exact  # the minimum itself, within 1 %
    swept = min(R_UNSTABLE / np.linalg.norm(M @ u) for u in sweep)
    assert swept > 1.05 * exact  # the pattern search, not the sweep, found it
    angle = math.degrees(math.acos(min(1.0, abs(float(found.direction @ vt[0])))))
    assert angle < 10.0, angle


def test_basin_fractions_cover_a_brute_force_count():
    """Uniform samples in the ball of radius 0.5: the 95 % Wilson intervals of the simulated shares cover the
    share of 200 000 points inside the boundary |M x| < R_UNSTABLE (the exact basin of x = 0)."""
    M = anisotropic_map()
    radius = 0.5
    brute = sample_ball(4, radius, 200_000, seed=1)
    share = float(np.mean(np.linalg.norm(brute @ M.T, axis=1) < R_UNSTABLE))
    assert 0.15 < share < 0.85
    points = sample_ball(4, radius, 400, seed=0)
    np.testing.assert_array_equal(points, sample_ball(4, radius, 400, seed=0))  # reproducible
    assert np.all(np.linalg.norm(points, axis=1) <= radius)
    labels = np.array(radial_probe(subcritical, [0.0, R_STABLE], M)(points))
    radii = np.linalg.norm(points @ M.T, axis=1)
    near = np.abs(radii - R_UNSTABLE) < 1e-3
    np.testing.assert_array_equal(labels[~near], np.where(radii < R_UNSTABLE, 0, 1)[~near])
    for label, exact in ((0, share), (1, 1 - share)):
        low, high = wilson(int(np.sum(labels == label)), labels.size)
        assert low <= exact <= high, (label, low, exact, high)
        assert high - low < 0.1


def test_wilson_interval_matches_the_textbook_values():
    """Agresti & Coull (1998): 0 of 10 gives [0, 0.2775]; 5 of 10 gives [0.2366, 0.7634]."""
    assert wilson(0, 10) == pytest.approx((0.0, 0.27753), abs=1e-5)
    assert wilson(5, 10) == pytest.approx((0.23659, 0.76341), abs=1e-5)
    assert wilson(10, 10)[1] == pytest.approx(1.0) and wilson(10, 10)[0] == pytest.approx(1 - 0.27753, abs=1e-5)
