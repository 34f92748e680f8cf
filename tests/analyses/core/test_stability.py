import numpy as np
import pytest

from shimmy import InvalidParameterError, Parameters, simulate
from shimmy.model.configurations import ALL_CONFIGURATIONS
from shimmy.model.equations import build_model, jacobian
from shimmy.continuation.lyapunov import first_lyapunov_coefficient, hopf_eigenvectors
from shimmy.analyses.core.stability import Criticality, Linearisation, eigenvalues, hopf_points

PUBLISHED = {"original": (5.61, 93.43), "nes": (6.730, 71.255), "nes_pd": (6.410, 71.952)}


@pytest.mark.parametrize("config", sorted(PUBLISHED))
def test_calibrated_defaults_reproduce_the_published_hopf_points(config):
    result = hopf_points(config, 150e3, v_range=(1.0, 200.0))
    speeds = [h.V for h in result.hopf_points]
    assert len(speeds) == 2
    np.testing.assert_allclose(speeds, PUBLISHED[config], rtol=2e-3)
    assert result.unstable_intervals == [(speeds[0], speeds[1])]
    assert [h.destabilising for h in result.hopf_points] == [True, False]


@pytest.mark.parametrize("config", ALL_CONFIGURATIONS, ids=lambda c: c.value)
@pytest.mark.parametrize("Fz", [80e3, 150e3, 300e3, 302.8e3, 500e3])
def test_hopf_points_are_refined_and_none_is_missed(config, Fz):
    coarse = hopf_points(config, Fz, n_grid=12)
    fine = hopf_points(config, Fz, n_grid=20000)
    np.testing.assert_allclose([h.V for h in coarse.hopf_points], [h.V for h in fine.hopf_points], atol=1e-6)
    lin = Linearisation(build_model(config), Fz)
    for h in fine.hopf_points:
        ev = lin.eigenvalues(np.array([h.V - 1e-6, h.V, h.V + 1e-6]))
        crit = np.argmin(np.abs(ev[1] - 1j * h.omega))
        assert abs(ev[1, crit].real) < 1e-6
        # the critical real part changes sign within +-1e-6 m/s
        near = [e[np.argmin(np.abs(e - 1j * h.omega))].real for e in (ev[0], ev[2])]
        assert near[0] * near[1] < 0


def test_two_close_hopf_points_inside_one_grid_interval_are_found():
    # At 302.8 kN the lateral mode is unstable only for V in about [2.67, 3.08] m/s,
    # inside one interval of a 12-point grid: the extremum check must catch the pair.
    result = hopf_points("original", 302.8e3, n_grid=12)
    lateral = [h.V for h in result.hopf_points if h.frequency_hz > 15]
    assert len(lateral) == 3 and lateral[1] - lateral[0] < 0.5


def test_linearisation_is_exact_in_v_and_one_over_v():
    model = build_model("nes_pd")
    lin = Linearisation(model, 2e5)
    V = np.array([1.3, 33.0, 480.0])
    np.testing.assert_allclose(lin.at(V), jacobian(model, np.zeros((7, 3)), V, 2e5), rtol=1e-12, atol=1e-9)


def test_eigenvalues_shape_and_order():
    one = eigenvalues("nes", 30.0, 150e3)
    many = eigenvalues("nes", [10.0, 30.0], 150e3)
    assert one.shape == (7,) and many.shape == (2, 7)
    assert np.all(np.diff(one.real) <= 0)
    np.testing.assert_allclose(many[1], one)


def test_particle_damper_hopf_points_are_labelled_nonsmooth():
    for config in ("pd", "nes_pd"):
        for h in hopf_points(config, 150e3).hopf_points:
            assert h.criticality is Criticality.NONSMOOTH and h.lyapunov is None


def test_smooth_configurations_get_a_first_lyapunov_coefficient():
    for config in ("original", "nes"):
        for h in hopf_points(config, 150e3).hopf_points:
            assert h.criticality is Criticality.SUPERCRITICAL and h.lyapunov < 0


def test_lyapunov_coefficient_of_the_hopf_normal_form():
    # x' = -w y + s x r^2, y' = w x + s y r^2: l1 = 2 s / w with <q, q> = 1 (hand calculation:
    # C(q, q, qbar) = 2 s [2 q (q . qbar) + qbar (q . q)] = 4 s q, B = 0).
    w = 3.0
    for s in (-0.7, 0.4):
        def J(x):
            x1, x2 = x
            r2 = x1 * x1 + x2 * x2
            return np.array([[s * (r2 + 2 * x1 * x1), -w + 2 * s * x1 * x2],
                             [w + 2 * s * x1 * x2, s * (r2 + 2 * x2 * x2)]])
        assert first_lyapunov_coefficient(J, 2) == pytest.approx(2 * s / w, rel=1e-8)


def test_lyapunov_coefficient_agrees_with_the_planar_formula_including_quadratic_terms():
    # Guckenheimer & Holmes (3.4.11): for x' = -w y + f, y' = w x + g,
    # a = [f_xxx + f_xyy + g_xxy + g_yyy]/16
    #     + [f_xy (f_xx + f_yy) - g_xy (g_xx + g_yy) - f_xx g_xx + f_yy g_yy] / (16 w),
    # and Kuznetsov's l1 in our normalisation is 2 a / w.
    rng = np.random.default_rng(3)
    w = 1.7
    for _ in range(5):
        fa, fb, fc, ga, gb, gc = rng.standard_normal(6)  # quadratic: f = fa x^2 + fb x y + fc y^2
        fd, fe, gd, ge = rng.standard_normal(4)  # cubic: f = fd x^3 + fe x y^2, g = gd x^2 y + ge y^3

        def J(x):
            x1, x2 = x
            return np.array([
                [2 * fa * x1 + fb * x2 + 3 * fd * x1 ** 2 + fe * x2 ** 2,
                 -w + fb * x1 + 2 * fc * x2 + 2 * fe * x1 * x2],
                [w + 2 * ga * x1 + gb * x2 + 2 * gd * x1 * x2,
                 gb * x1 + 2 * gc * x2 + gd * x1 ** 2 + 3 * ge * x2 ** 2]])

        f_xx, f_xy, f_yy, g_xx, g_xy, g_yy = 2 * fa, fb, 2 * fc, 2 * ga, gb, 2 * gc
        f_xxx, f_xyy, g_xxy, g_yyy = 6 * fd, 2 * fe, 2 * gd, 6 * ge
        a = ((f_xxx + f_xyy + g_xxy + g_yyy) / 16
             + (f_xy * (f_xx + f_yy) - g_xy * (g_xx + g_yy) - f_xx * g_xx + f_yy * g_yy) / (16 * w))
        assert first_lyapunov_coefficient(J, 2) == pytest.approx(2 * a / w, rel=1e-6, abs=1e-9)


def test_lyapunov_coefficient_predicts_the_simulated_cycle_amplitude():
    # Normal form: |z|^2 = -Re(lambda) / (l1 w), psi amplitude ~ 2 |q_psi| |z| near the Hopf point.
    Fz = 150e3
    h = hopf_points("original", Fz).hopf_points[0]
    model = build_model("original")
    _, q, _ = hopf_eigenvectors(jacobian(model, np.zeros(5), h.V, Fz))
    V = h.V + 0.1
    ev = eigenvalues("original", V, Fz)[0]
    predicted = 2 * abs(q[0]) * np.sqrt(-ev.real / (h.lyapunov * h.omega))
    simulated = simulate("original", V, Fz, t_end=300.0).amplitude["psi"]
    assert simulated == pytest.approx(predicted, rel=0.03)


@pytest.mark.parametrize("kwargs,match", [
    (dict(Fz=5e3), r"Fz=5000.0 is out of range"),
    (dict(v_range=(50.0, 20.0)), r"v_max=20.0 must exceed v_min"),
    (dict(v_range=(1.0, float("inf"))), r"v_max=inf is not finite"),
    (dict(n_grid=3), r"n_grid=3 is out of range"),
    (dict(v_tol=0.1), r"v_tol=0.1 is out of range"),
])
def test_bad_hopf_requests_are_refused(kwargs, match):
    args = {"config": "original", "Fz": 150e3, **kwargs}
    with pytest.raises(InvalidParameterError, match=match):
        hopf_points(**args)


def test_result_serialises_with_the_cli_fields():
    d = hopf_points("nes", 150e3, params=Parameters().with_overrides(e_p=0.002)).to_dict()
    assert d["config"] == "nes" and d["Fz"] == 150e3 and d["params"]["e_p"] == 0.002
    assert {"V", "frequency_hz", "criticality"} <= set(d["hopf_points"][0])
