"""Sensitivities by implicit differentiation against finite differences of re-solved points."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq, minimize_scalar

from shimmy.analyses.diagrams.bifurcation import STATE_SCALE, T_SCALE, V_SCALE, gear_field
from shimmy.analyses.decisions.sensitivity import (NOT_FITTED, ZERO_SLOPE, _model, _orbit_at, amplitude_sensitivity,
                                         coefficient_pairs, sensitivity)
from shimmy.analyses.core.stability import Linearisation, hopf_points
from shimmy.continuation import ContinuationOptions, correct
from shimmy.continuation.collocation import Mesh, PeriodicProblem
from shimmy.errors import InvalidParameterError
from shimmy.model.configurations import Configuration
from shimmy.model.equations import build_model
from shimmy.model.parameters import PARAMETER_SPECS, Parameters

#: Interior values for the particle density (its default is the range's lower end).
PARAMS = Parameters().with_overrides(rho_p=12000.0)
CHECKED = ("r2", "e_p", "k_s", "r3", "I_nes", "c_nes", "k_lam", "c_psi", "Iz", "L", "e", "I_pd")


def _fd_speeds(config, name, rel=1e-5, Fz=150e3):
    v = float(getattr(PARAMS, name))
    h = rel * v
    up = hopf_points(config, Fz, params=PARAMS.with_overrides({name: v + h}), v_range=(1, 200)).hopf_points
    down = hopf_points(config, Fz, params=PARAMS.with_overrides({name: v - h}), v_range=(1, 200)).hopf_points
    return [(a.V - b.V) / (2 * h) for a, b in zip(up, down, strict=True)]


@pytest.mark.parametrize("config", ["nes", "nes_pd", "original", "pd"])
def test_hopf_speed_derivatives_equal_central_differences_of_re_solved_points(config):
    s = sensitivity(config, 150e3, params=PARAMS, amplitude=False, min_shimmy=False)
    assert len(s.hopf) == 2
    for name in CHECKED:
        analytic = [h["dV_dp"][name] for h in s.hopf]
        if name in s.no_effect["hopf"]:
            assert analytic == [0.0, 0.0]
            continue
        fd = _fd_speeds(config, name)
        scale = max(abs(d) for d in fd)
        np.testing.assert_allclose(analytic, fd, rtol=1e-4, atol=1e-4 * scale, err_msg=name)


def test_frequency_derivatives_equal_central_differences():
    s = sensitivity("nes", 150e3, params=PARAMS, names=["k_s", "k_lam"], amplitude=False, min_shimmy=False)
    for name in ("k_s", "k_lam"):
        v = float(getattr(PARAMS, name))
        h = 1e-5 * v
        up = hopf_points("nes", 150e3, params=PARAMS.with_overrides({name: v + h}), v_range=(1, 200)).hopf_points
        down = hopf_points("nes", 150e3, params=PARAMS.with_overrides({name: v - h}), v_range=(1, 200)).hopf_points
        fd = [(a.omega - b.omega) / (2 * h) for a, b in zip(up, down, strict=True)]
        np.testing.assert_allclose([x["domega_dp"][name] for x in s.hopf], fd, rtol=1e-4,
                                   atol=1e-4 * max(map(abs, fd)))


def test_parameters_without_effect_are_exact_zeros_with_their_reason():
    s = sensitivity("pd", 150e3, params=PARAMS, amplitude=False, min_shimmy=False)
    for name in ("a_p", "rho_p", "e_r", "d_p"):
        assert s.no_effect["hopf"][name] == ZERO_SLOPE
        assert all(h["dV_dp"][name] == 0.0 for h in s.hopf)
    assert "I_pd" not in s.no_effect["hopf"]  # the added inertia does move the Hopf speeds
    o = sensitivity("original", 150e3, params=PARAMS, amplitude=False, min_shimmy=False)
    for name in ("r2", "k_s", "a_p", "I_pd"):
        assert o.no_effect["hopf"][name] == NOT_FITTED
    rows = o.tornado("hopf_V2")
    with_effect = [r for r in rows if r["reason"] is None]
    assert [r["name"] for r in rows[:len(with_effect)]] == [r["name"] for r in with_effect]  # reasons last
    sizes = [abs(r["per_percent"] or 0.0) for r in with_effect]
    assert sizes == sorted(sizes, reverse=True)
    for r in rows:
        spec = PARAMETER_SPECS[r["name"]]
        if r["value"] == 0.0:
            assert r["per_percent"] is None  # no relative change of a zero value
        else:
            assert r["per_percent"] == pytest.approx(r["derivative"] * 0.01 * r["value"])
        assert r["per_half_range"] == pytest.approx(r["derivative"] * 0.5 * (spec.high - spec.low))


def _independent_lowest_point(config, params):
    """min over V of the Hopf load Fz_H(V) (Re lambda = 0 by Brent in Fz), by a bounded scalar search."""
    model = build_model(config, params)

    def growth(V, Fz):
        return float(np.max(np.linalg.eigvals(Linearisation(model, Fz).at(V)).real))

    def hopf_load(V):
        return brentq(lambda f: growth(V, f), 2e4, 1.5e5, xtol=1e-10, rtol=1e-14)

    best = minimize_scalar(hopf_load, bounds=(12.0, 30.0), method="bounded", options={"xatol": 1e-7})
    return best.fun


def test_min_shimmy_load_on_a_speed_edge_moves_along_the_edge():
    """A design whose lowest Hopf point is the end of a curve on V = 1 m/s: the corner's derivative,
    against central differences of re-continued curves."""
    from shimmy.analyses.diagrams.hopf_curves import hopf_curves

    params = Parameters().with_overrides(L=0.1087, c_lam=554.4, k_a=0.502)
    low = sensitivity("original", 150e3, params=params, names=["k_lam", "c_psi"], amplitude=False).min_shimmy
    assert low["V"] == 1.0 and "speed edge" in low["source"]
    for name in ("k_lam", "c_psi"):
        v = float(getattr(params, name))
        h = 1e-4 * v
        up = hopf_curves("original", params=params.with_overrides({name: v + h})).fz_minimum["Fz"]
        down = hopf_curves("original", params=params.with_overrides({name: v - h})).fz_minimum["Fz"]
        assert low["dFz_dp"][name] == pytest.approx((up - down) / (2 * h), rel=1e-5), name


@pytest.mark.parametrize("config", ["nes", "pd"])
def test_min_shimmy_load_derivative_equals_differences_of_independently_solved_minima(config):
    s = sensitivity(config, 150e3, params=PARAMS, names=["k_s", "k_lam", "c_psi", "I_pd"], amplitude=False)
    low = s.min_shimmy
    assert low["source"] == "lowest point of the Hopf curves"
    assert low["Fz"] == pytest.approx(_independent_lowest_point(config, PARAMS), rel=1e-8)
    for name in ("k_lam", "c_psi") + (("k_s",) if config == "nes" else ("I_pd",)):
        v = float(getattr(PARAMS, name))
        h = 1e-4 * v
        fd = (_independent_lowest_point(config, PARAMS.with_overrides({name: v + h}))
              - _independent_lowest_point(config, PARAMS.with_overrides({name: v - h}))) / (2 * h)
        assert low["dFz_dp"][name] == pytest.approx(fd, rel=1e-4, abs=1e-6 * abs(low["Fz"] / v)), name


def _amplitude_at_fixed_speed(model, Fz, problem, u, coefficients):
    """max |psi| of the orbit re-solved by Newton at u's speed and mesh for other coefficients."""
    q = PeriodicProblem(gear_field(_model(model, coefficients), Fz), problem.mesh, STATE_SCALE[:model.n_states],
                        T_SCALE, V_SCALE)
    q.accept(u)
    e_V = np.zeros(u.size)
    e_V[-1] = 1.0
    options = ContinuationOptions(tol=1e-12, residual_tol=1e-11, max_newton=12)
    w = u
    for _ in range(4):
        w = correct(q, w, e_V / math.sqrt(q.weights[-1]), options)[0]
        q.accept(w)
    return _refined_peak(q, w)


def _refined_peak(problem, u):
    """max |psi| on the collocation polynomial: 50 samples per interval, then Brent on the best one's
    neighbourhood (independent of the module's own search)."""
    from scipy.optimize import minimize_scalar

    X = problem.unpack(u)[0]
    tau = np.linspace(0.0, 1.0, 50 * problem.mesh.ntst + 1)
    psi = problem.evaluate(X, tau)[:, 0]
    k = int(np.argmax(np.abs(psi)))
    s = np.sign(psi[k])
    lo, hi = tau[max(k - 1, 0)], tau[min(k + 1, tau.size - 1)]
    r = minimize_scalar(lambda t: -s * problem.evaluate(X, np.array([t]))[0, 0], bounds=(lo, hi), method="bounded",
                        options={"xatol": 1e-14})
    return float(max(-r.fun, abs(psi[k])))


@pytest.mark.slow
@pytest.mark.parametrize("config", ["nes", "nes_pd"])
def test_amplitude_derivative_equals_differences_of_re_solved_orbits(config):
    from shimmy.analyses.diagrams.bifurcation import BifurcationOptions, bifurcation

    Fz = 150e3
    model = build_model(config, PARAMS)
    result = bifurcation(config, Fz, v_range=(1, 200), params=PARAMS, options=BifurcationOptions(mesh_check=False))
    names = ["e_p", "k_s", "a_p", "k_lam", "c_nes"]
    pairs = coefficient_pairs(Configuration(config), PARAMS, names)
    amp = amplitude_sensitivity(model, Fz, pairs, result=result)
    assert amp["where"] == "interior maximum"
    assert amp["value"] == pytest.approx(result.max_psi, rel=1e-6)
    raw, i = _orbit_at(result, amp["V"], amp["value"])
    problem = PeriodicProblem(gear_field(model, Fz), Mesh(raw.solutions[i][0], raw.ncol),
                              STATE_SCALE[:model.n_states], T_SCALE, V_SCALE)
    u = raw.solutions[i][1].copy()
    u[-1] = amp["V"]
    from shimmy.model.equations import model_coefficients
    from shimmy.analyses.decisions.sensitivity import design_with

    for name in names:
        v = float(getattr(PARAMS, name))
        h = 1e-4 * v
        up = _amplitude_at_fixed_speed(model, Fz, problem, u,
                                       model_coefficients(model.config, design_with(PARAMS, name, v + h)))
        down = _amplitude_at_fixed_speed(model, Fz, problem, u,
                                         model_coefficients(model.config, design_with(PARAMS, name, v - h)))
        assert amp["dA_dp"][name] == pytest.approx((up - down) / (2 * h), rel=2e-4, abs=1e-9 / v), name
    # The envelope in V: the derivative at fixed speed is that of the diagram's maximum (whole
    # diagrams re-computed, 1 % steps: their own mesh and refinement noise limits the comparison).
    v = float(PARAMS.e_p)
    h = 0.01 * v
    up = bifurcation(config, Fz, v_range=(1, 200), params=PARAMS.with_overrides(e_p=v + h),
                     options=BifurcationOptions(mesh_check=False))
    down = bifurcation(config, Fz, v_range=(1, 200), params=PARAMS.with_overrides(e_p=v - h),
                       options=BifurcationOptions(mesh_check=False))
    assert amp["dA_dp"]["e_p"] == pytest.approx((up.max_psi - down.max_psi) / (2 * h), rel=2e-2)


def test_bad_input_is_refused_naming_the_field():
    with pytest.raises(InvalidParameterError, match="Fz"):
        sensitivity("nes", 5.0, amplitude=False)
    with pytest.raises(InvalidParameterError, match="k_sx"):
        sensitivity("nes", 150e3, names=["k_sx"], amplitude=False)
    with pytest.raises(InvalidParameterError, match="quantity"):
        sensitivity("nes", 150e3, amplitude=False, min_shimmy=False).tornado("nothing")
