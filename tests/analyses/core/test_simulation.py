import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from shimmy import InvalidParameterError, Parameters, SimulationOptions, simulate
from shimmy.model.configurations import ALL_CONFIGURATIONS
from shimmy.model.reference_model import make_rhs
from shimmy.analyses.core.response import ResponseType, dominant_frequency, peak_amplitude
from shimmy.analyses.core.stability import eigenvalues, hopf_points

A = (30.0, 150e3)


@pytest.mark.parametrize("config", ALL_CONFIGURATIONS, ids=lambda c: c.value)
def test_tightening_tolerances_tenfold_changes_amplitudes_below_half_a_percent(config):
    loose = simulate(config, *A)
    tight = simulate(config, *A, rtol=loose.options.rtol / 10, atol=loose.options.atol / 10)
    assert loose.success and tight.success
    for key in ("psi", "lateral"):
        assert loose.amplitude[key] == pytest.approx(tight.amplitude[key], rel=5e-3)
    assert loose.frequency_hz == pytest.approx(tight.frequency_hz, abs=0.01)


@pytest.mark.slow
@pytest.mark.parametrize("config", ["original", "nes_pd"])
def test_agrees_with_scipy_lsoda_on_the_plain_reference_rhs(config):
    ours = simulate(config, *A, t_end=40.0)
    x0 = np.zeros(ours.states.shape[0])
    x0[0] = 0.001
    sol = solve_ivp(make_rhs(config, *A), (0, 40.0), x0, method="LSODA", rtol=1e-9, atol=1e-12,
                    max_step=0.005, dense_output=True)
    window = ours.t >= 40.0 - ours.options.steady_window
    ref = sol.sol(ours.t[window])
    assert ours.amplitude["psi"] == pytest.approx(peak_amplitude(ref[0]), rel=5e-3)
    assert ours.amplitude["lateral"] == pytest.approx(2.5 * peak_amplitude(ref[2]), rel=5e-3)


def test_result_carries_series_measures_and_provenance():
    r = simulate("nes", *A, t_end=10.0)
    assert r.t[0] == 0.0 and r.t[-1] == pytest.approx(10.0)
    assert r.states.shape == (7, r.t.size)
    assert r.state("psi")[0] == 0.001 and np.all(r.states[1:, 0] == 0)
    np.testing.assert_allclose(r.lateral, 2.5 * r.state("delta"))
    d = r.to_dict()
    assert set(d["amplitude"]) >= {"psi", "lateral"} and d["response_type"] in {t.value for t in ResponseType}
    assert d["params"] == Parameters().to_dict() and d["counters"]["steps"] > 0
    assert "series" not in d and len(r.to_dict(include_series=True)["series"]["t"]) == r.t.size


def test_stable_point_decays_and_unstable_point_settles_on_a_torsional_cycle():
    stable = simulate("original", 170.0, 150e3)
    assert stable.response_type is ResponseType.STABLE and stable.steady
    assert np.isnan(stable.frequency_hz)
    shimmy = simulate("original", *A)
    assert shimmy.response_type is ResponseType.TORSION and shimmy.steady
    assert 10.0 < shimmy.frequency_hz < 13.0
    lateral = simulate("original", 110.0, 550e3)
    assert lateral.response_type is ResponseType.LATERAL and 15.0 < lateral.frequency_hz < 17.0


def test_decay_rate_matches_the_eigenvalue_of_the_torsional_mode():
    # Independent check linking simulation and linear stability: at small amplitude the
    # envelope of psi decays at the real part of the eigenvalue whose frequency it shows.
    V, Fz = 120.0, 150e3
    r = simulate("original", V, Fz, t_end=12.0, rtol=1e-10, atol=1e-16)
    psi, t = np.abs(r.state("psi")), r.t
    peaks = [(t[i], psi[i]) for i in range(1, t.size - 1) if psi[i] >= psi[i - 1] and psi[i] > psi[i + 1]]
    late = np.array([p for p in peaks if 4.0 < p[0] < 12.0])
    slope = np.polyfit(late[:, 0], np.log(late[:, 1]), 1)[0]
    omega = np.pi / np.median(np.diff(late[:, 0]))  # |psi| peaks twice per period
    ev = eigenvalues("original", V, Fz)
    mode = ev[np.argmin(np.abs(ev.imag - omega))]
    assert abs(mode.imag - omega) < 0.02 * omega
    assert slope == pytest.approx(mode.real, rel=0.01)


def test_cycle_near_a_supercritical_hopf_point_obeys_the_square_root_law():
    hopf = hopf_points("original", 150e3).hopf_points[0]
    amps = [simulate("original", hopf.V + dv, 150e3, t_end=300.0).amplitude["psi"] for dv in (0.1, 0.2)]
    assert amps[1] / amps[0] == pytest.approx(np.sqrt(2.0), rel=0.03)
    r = simulate("original", hopf.V + 0.1, 150e3, t_end=300.0)
    assert r.frequency_hz == pytest.approx(hopf.frequency_hz, abs=0.02)


def test_dominant_frequency_is_accurate_to_a_hundredth_of_a_hertz():
    dt, t = 0.001, np.arange(0, 20.0, 0.001)
    for f in (10.4321, 11.87, 16.0123, 13.3):
        signal = 0.02 * np.sin(2 * np.pi * f * t + 0.3) + 0.001 * np.sin(2 * np.pi * 3 * f * t)
        assert dominant_frequency([signal], dt) == pytest.approx(f, abs=0.01)


def test_peak_amplitude_refines_between_samples():
    t = np.arange(0, 0.05, 0.005)
    signal = 0.7 * np.cos(2 * np.pi * 13 * (t - 0.0025))  # the peak falls between two samples
    raw_error = 0.7 - np.abs(signal).max()
    assert raw_error > 1e-3
    assert abs(peak_amplitude(signal) - 0.7) < 0.05 * raw_error


def test_exact_nes_torque_agrees_with_the_cubic_at_small_amplitude():
    cubic = simulate("nes", *A, t_end=20.0)
    exact = simulate("nes", *A, t_end=20.0, exact_nes=True)
    assert exact.success
    assert exact.amplitude["psi"] == pytest.approx(cubic.amplitude["psi"], rel=0.01)


def test_exact_nes_leaving_its_track_is_reported_not_extrapolated():
    x0 = np.zeros(7)
    x0[0] = 0.6  # far beyond pi/6 relative rotation after the first swing
    r = simulate("nes", 30.0, 150e3, t_end=5.0, x0=x0, exact_nes=True)
    assert not r.success and "pi/6" in r.message
    assert r.t[-1] < 5.0


def test_step_budget_is_reported():
    r = simulate("original", *A, t_end=5.0, max_steps=50)
    assert not r.success and "step budget" in r.message


@pytest.mark.parametrize("kwargs,match", [
    (dict(t_end=1e5), r"t_end=100000.0 is out of range; allowed: a number in \[0.1, 3600\] s"),
    (dict(t_end=float("nan")), r"t_end=nan is not finite"),
    (dict(rtol=1.0), r"rtol=1.0 is out of range"),
    (dict(x0=[0.1, 0.0]), r"x0=\[0.1, 0.0\] has the wrong length; allowed: 5 numbers"),
    (dict(x0=[np.nan, 0, 0, 0, 0]), r"x0=.* is not finite"),
    (dict(V=0.0), r"V=0.0 is out of range"),
])
def test_bad_options_are_refused_with_the_field_named(kwargs, match):
    args = {"config": "original", "V": 30.0, "Fz": 150e3, **kwargs}
    with pytest.raises(InvalidParameterError, match=match):
        simulate(**args)


def test_unknown_configuration_is_refused():
    allowed = "allowed: one of original, nes, pd, nes_pd"
    with pytest.raises(InvalidParameterError, match=r"unknown config 'nes\+pd'.*" + allowed):
        simulate("nes+pd", *A)


def test_options_are_frozen_and_validated():
    with pytest.raises(InvalidParameterError, match="dt_out"):
        SimulationOptions(dt_out=1.0)


@pytest.mark.parametrize("energies,expected", [
    ((1.0, 1e-9, 1e-9, 1.0), ResponseType.STABLE),      # decayed to below 1e-3 of the start
    ((1.0, 0.5, 0.01, 0.6), ResponseType.STABLE),       # below the start and still falling
    ((1.0, 50.0, 1.0, 51.0), ResponseType.TORSION),
    ((1.0, 1.0, 50.0, 51.0), ResponseType.LATERAL),
    ((1.0, 20.0, 30.0, 50.0), ResponseType.BOTH),
    ((1.0, 0.5, 0.0, 0.5), ResponseType.TORSION),       # small but not decaying: a small cycle
])
def test_response_type_criteria(energies, expected):
    from shimmy.analyses.core.response import classify_run
    assert classify_run(*energies) is expected


@pytest.mark.parametrize("config,V,Fz", [("original", 30.0, 150e3), ("nes_pd", 30.0, 150e3),
                                         ("original", 110.0, 550e3)])
def test_spectral_frequency_agrees_with_the_zero_crossing_period(config, V, Fz):
    r = simulate(config, V, Fz)
    window = r.t >= r.t[-1] - r.options.steady_window
    t = r.t[window]
    signal = r.state("psi")[window] if r.response_type is ResponseType.TORSION else r.state("delta")[window]
    up = np.nonzero((signal[:-1] < 0) & (signal[1:] >= 0))[0]
    crossings = t[up] - signal[up] * (t[up + 1] - t[up]) / (signal[up + 1] - signal[up])
    period = (crossings[-1] - crossings[0]) / (crossings.size - 1)
    assert r.frequency_hz == pytest.approx(1.0 / period, abs=0.01)


def test_the_spectrum_can_be_skipped_and_nothing_else_changes():
    """frequency=False (a diagram's seeds need only the settled state) leaves every other measure as it is."""
    full = simulate("original", 60.0, 150e3, t_end=6.0)
    bare = simulate("original", 60.0, 150e3, t_end=6.0, frequency=False)
    assert math.isfinite(full.frequency_hz) and math.isnan(bare.frequency_hz)
    np.testing.assert_array_equal(full.states, bare.states)
    assert (full.amplitude, full.steady, full.response_type) == (bare.amplitude, bare.steady, bare.response_type)


def test_a_start_kicked_in_a_rate_only_is_judged_by_its_energy():
    """A start with psi = delta = 0 and a yaw rate (a margin's kick along dpsi) has energy: it ends torsional at
    original (50 m/s, 550 kN) from dpsi0 = 1.6 rad/s (the margin along dpsi is 1.569 rad/s) and decays at 5 m/s,
    150 kN (below the first Hopf speed), each judged as from a yaw angle of the same energy."""
    run = simulate("original", 50.0, 550e3, x0=[0.0, 1.6, 0.0, 0.0, 0.0], t_end=60.0)
    assert run.response_type is ResponseType.TORSION and run.steady
    assert run.amplitude["psi"] == pytest.approx(0.187, rel=0.02)
    quiet = simulate("original", 5.0, 150e3, x0=[0.0, 1.6, 0.0, 0.0, 0.0], t_end=60.0)
    assert quiet.response_type is ResponseType.STABLE
