import pytest

from shimmy import Parameters, simulate
from shimmy.analyses.core.calibration import AMPLITUDE_TARGET, FITTED, HOPF_TARGETS, calibrate, format_report
from shimmy.model.parameters import CALIBRATED, PARAMETER_SPECS


@pytest.fixture(scope="module")
def fit():
    return calibrate()


def test_defaults_are_the_rounded_output_of_the_fit(fit):
    for name in FITTED:
        assert PARAMETER_SPECS[name].default == pytest.approx(fit.values[name], rel=1e-4), name
        assert PARAMETER_SPECS[name].provenance == CALIBRATED


def test_fit_reproduces_the_published_hopf_points_to_0_2_percent(fit):
    for config, errors in fit.hopf_relative_errors.items():
        assert len(errors) == len(HOPF_TARGETS[config])
        assert max(abs(e) for e in errors) < 2e-3, config


def test_fit_does_not_depend_on_its_starting_point(fit):
    start = Parameters().with_overrides(k_lam=0.0017, I_nes=6.0, c_nes=60.0, I_pd=2.0, g_p=1.0, f=10.0)
    again = calibrate(start)
    for name in FITTED:
        assert again.values[name] == pytest.approx(fit.values[name], rel=1e-5), name


def test_pd_amplitude_target_is_out_of_reach_and_the_closest_value_is_kept(fit):
    # Documented misfit: even g_p = 5 and f = 30 (tops of their published ranges) leave
    # the nes_pd amplitude at V = 30 m/s about 16 % above the published 0.017 rad.
    assert not fit.pd_target_met
    assert (fit.values["g_p"], fit.values["f"]) == (5.0, 30.0)
    assert AMPLITUDE_TARGET["psi"] < fit.amplitude_computed < 1.2 * AMPLITUDE_TARGET["psi"]
    assert "not reachable" in format_report(fit)


def test_sanity_checks_of_reference_md():
    # a_p 0.8 -> 0.9 lowers the nes_pd amplitude by roughly 10 %; tungsten damps more than steel
    p = Parameters()
    amp = {ap: simulate("nes_pd", 30.0, 150e3, params=p.with_overrides(a_p=ap), t_end=120).amplitude["psi"]
           for ap in (0.8, 0.9)}
    assert 0.05 < 1 - amp[0.9] / amp[0.8] < 0.15
    tungsten = simulate("nes_pd", 30.0, 150e3, params=p.with_material("tungsten"), t_end=120).amplitude["psi"]
    assert tungsten < amp[0.9]
