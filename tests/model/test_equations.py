import numpy as np
import pytest

from shimmy import Parameters
from shimmy.model.configurations import ALL_CONFIGURATIONS
from shimmy.model.equations import (build_model, effective_caster, field_and_derivatives, jacobian,
                                    parameter_jacobian, rhs)
from shimmy.model.integrator import N_FULL, _f
from shimmy.model.reference_model import make_rhs

RNG = np.random.default_rng(7)
SCALES = np.array([0.05, 1.0, 0.01, 0.5, 0.02, 0.05, 1.0])  # typical state magnitudes


def random_states(n, m=6):
    return RNG.standard_normal((n, m)) * SCALES[:n, None]


def test_effective_caster_nominal():
    assert effective_caster(0.362, 0.1571, 0.12) == pytest.approx(0.17884, abs=5e-6)


@pytest.mark.parametrize("config", ALL_CONFIGURATIONS, ids=lambda c: c.value)
def test_straight_rolling_is_an_equilibrium_everywhere(config):
    model = build_model(config)
    V = np.array([1.0, 30.0, 500.0])
    Fz = np.array([1e4, 150e3, 9e5])
    assert np.all(rhs(model, np.zeros((model.n_states, 3)), V, Fz) == 0.0)


@pytest.mark.parametrize("config", ALL_CONFIGURATIONS, ids=lambda c: c.value)
def test_vector_field_is_odd(config):
    # every nonlinearity (sin, atan, cubic, |w| w, cos(delta) ddelta) is odd in the state
    model = build_model(config)
    x = random_states(model.n_states)
    np.testing.assert_allclose(rhs(model, -x, 40.0, 2e5), -rhs(model, x, 40.0, 2e5), rtol=1e-13, atol=1e-13)


@pytest.mark.parametrize("config", ALL_CONFIGURATIONS, ids=lambda c: c.value)
def test_vectorised_field_matches_the_plain_reference_and_the_compiled_kernel(config):
    model = build_model(config)
    x = random_states(model.n_states)
    V, Fz = 45.0, 3.3e5
    got = rhs(model, x, V, Fz)
    ref = make_rhs(config, V, Fz)
    compiled = np.empty(N_FULL)
    for j in range(x.shape[1]):
        np.testing.assert_allclose(got[:, j], ref(0.0, x[:, j]), rtol=1e-12, atol=1e-12)
        full = np.zeros(N_FULL)
        full[:model.n_states] = x[:, j]
        _f(full, compiled, V, Fz, model.coefficients, *model.flags)
        np.testing.assert_allclose(compiled[:model.n_states], got[:, j], rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("exact_nes", [False, True])
@pytest.mark.parametrize("config", ALL_CONFIGURATIONS, ids=lambda c: c.value)
def test_analytic_jacobian_matches_central_differences(config, exact_nes):
    model = build_model(config, exact_nes=exact_nes)
    n = model.n_states
    x = random_states(n)
    V = np.linspace(5.0, 200.0, x.shape[1])
    Fz = np.linspace(5e4, 8e5, x.shape[1])
    J = jacobian(model, x, V, Fz)
    assert J.shape == (x.shape[1], n, n)
    fd = np.empty_like(J)
    for k in range(n):
        h = 1e-6 * SCALES[k]
        e = np.zeros((n, 1))
        e[k] = h
        fd[:, :, k] = ((rhs(model, x + e, V, Fz) - rhs(model, x - e, V, Fz)) / (2 * h)).T
    scale = np.abs(J).max(axis=(1, 2), keepdims=True)
    np.testing.assert_allclose(J, fd, rtol=1e-6, atol=1e-7 * scale.max())
    # one column at a time gives the same as the batch
    np.testing.assert_array_equal(jacobian(model, x[:, 2], V[2], Fz[2]), J[2])


@pytest.mark.parametrize("config", ALL_CONFIGURATIONS, ids=lambda c: c.value)
def test_parameter_jacobian_matches_central_differences(config):
    model = build_model(config)
    x = random_states(model.n_states)
    V, Fz = 37.0, 2.4e5
    dV, dFz = parameter_jacobian(model, x, V, Fz)
    hV, hF = 1e-5, 1.0
    np.testing.assert_allclose(dV, (rhs(model, x, V + hV, Fz) - rhs(model, x, V - hV, Fz)) / (2 * hV),
                               rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(dFz, (rhs(model, x, V, Fz + hF) - rhs(model, x, V, Fz - hF)) / (2 * hF),
                               rtol=1e-6, atol=1e-12)


def test_pd_jacobian_at_rest_equals_the_bare_gear_with_added_inertia():
    # M_pd has zero slope at dpsi = 0: the PD enters the linearisation only through I_pd.
    p = Parameters()
    zero = np.zeros(5)
    with_pd = jacobian(build_model("pd", p), zero, 30.0, 150e3)
    without = jacobian(build_model("original", p.with_overrides(Iz=p.Iz + p.I_pd)), zero, 30.0, 150e3)
    np.testing.assert_allclose(with_pd, without, rtol=1e-15)


def test_wrong_state_length_is_refused():
    with pytest.raises(ValueError, match="state has 5 rows; configuration nes has 7 states"):
        rhs(build_model("nes"), np.zeros(5), 30.0, 150e3)


@pytest.mark.parametrize("exact_nes", [False, True])
@pytest.mark.parametrize("config", ALL_CONFIGURATIONS, ids=lambda c: c.value)
def test_one_pass_evaluation_equals_the_separate_functions(config, exact_nes):
    """field_and_derivatives (the continuation engine's compiled pass) gives exactly what rhs,
    jacobian and parameter_jacobian give, for columns, one state, and broadcast speeds."""
    model = build_model(config, exact_nes=exact_nes)
    x = random_states(model.n_states)
    for V, Fz, states in ((52.0, 3.1e5, x), (52.0, 3.1e5, x[:, 1]), (np.linspace(5.0, 90.0, x.shape[1]), 2e5, x)):
        f, J, dV, dFz = field_and_derivatives(model, states, V, Fz)
        np.testing.assert_array_equal(f, rhs(model, states, V, Fz))
        np.testing.assert_array_equal(J, jacobian(model, states, V, Fz))
        ref_dV, ref_dFz = parameter_jacobian(model, states, V, Fz)
        np.testing.assert_array_equal(dV, ref_dV)
        np.testing.assert_array_equal(dFz, ref_dFz)


@pytest.mark.parametrize("exact_nes", [False, True])
@pytest.mark.parametrize("config", ALL_CONFIGURATIONS, ids=lambda c: c.value)
def test_one_state_path_equals_the_columns_path(config, exact_nes):
    """One real state at one speed and load (a compiled path of its own, for speed) gives exactly
    what the same state as a column gives; the other shapes (a complex state, an integer speed, a
    state of the wrong length) still take the general path."""
    model = build_model(config, exact_nes=exact_nes)
    x = random_states(model.n_states)
    for k in range(x.shape[1]):
        one = np.ascontiguousarray(x[:, k])
        f, J, dV, dFz = field_and_derivatives(model, one, 52.0, 3.1e5)
        fc, Jc, dVc, dFzc = field_and_derivatives(model, x[:, k:k + 1], 52.0, 3.1e5)
        assert f.shape == dV.shape == dFz.shape == (model.n_states,) and J.shape == (model.n_states,) * 2
        np.testing.assert_array_equal(f, fc[:, 0])
        np.testing.assert_array_equal(J, Jc[0])
        np.testing.assert_array_equal(dV, dVc[:, 0])
        np.testing.assert_array_equal(dFz, dFzc[:, 0])
        np.testing.assert_array_equal(rhs(model, one, 52, 310000), fc[:, 0])
        np.testing.assert_array_equal(jacobian(model, one, np.float64(52.0), 3.1e5), Jc[0])
    assert jacobian(model, x[:, 0].astype(complex), 52.0, 3.1e5).dtype == complex


@pytest.mark.parametrize("config", ALL_CONFIGURATIONS, ids=lambda c: c.value)
def test_complex_step_in_v_of_the_field_gives_its_v_derivative(config):
    """The compiled loop runs on complex states and speeds (the stability module's complex steps):
    Im f(x, V + ih) / h equals the analytic d f / d V to rounding, away from the PD's |dpsi| kink."""
    model = build_model(config)
    x = random_states(model.n_states)
    V, Fz, h = 41.0, 2.7e5, 1e-20
    dV, _ = parameter_jacobian(model, x, V, Fz)
    np.testing.assert_allclose(rhs(model, x, complex(V, h), Fz).imag / h, dV, rtol=1e-12, atol=1e-14)
    J_c = jacobian(model, x.astype(complex), complex(V, h), Fz)
    assert J_c.dtype == complex
    np.testing.assert_allclose(J_c.real, jacobian(model, x, V, Fz), rtol=1e-14, atol=1e-14)
