"""The minimum shimmy load as a curve in a design parameter, against the Hopf curves' own located
lowest point (two-parameter continuation in (V, Fz), an independent computation) at sampled values,
and its slope at the nominal design against the sensitivity's implicit derivative dFz/dp."""

import pytest

from shimmy.analyses.decisions.min_shimmy_curve import min_shimmy_curve
from shimmy.analyses.decisions.sensitivity import sensitivity
from shimmy.analyses.diagrams.hopf_curves import hopf_curves
from shimmy.analyses.decisions.study_curves import parameter_range
from shimmy.model.parameters import Parameters

SAMPLES = {"e_p": (0.0008, 0.003), "r2": (0.072, 0.087)}


@pytest.fixture(scope="module", params=[("nes", "e_p"), ("nes", "r2"), ("nes_pd", "e_p")])
def curve(request):
    config, name = request.param
    c, warnings = min_shimmy_curve(config, name, values=SAMPLES[name])
    return config, name, c, warnings


def test_the_curve_spans_the_whole_range_and_passes_the_samples(curve):
    config, name, c, warnings = curve
    lo, hi = parameter_range(name, Parameters())
    assert c.p[0] == lo and c.p[-1] == hi and None not in c.values and warnings == []
    for theta in SAMPLES[name]:
        low = hopf_curves(config, params=Parameters().with_overrides({name: theta}), v_range=(1.0, 200.0)).fz_minimum
        assert c.value_at(theta) == pytest.approx(low["Fz"], rel=1e-6)


def test_the_slope_at_the_nominal_design_is_the_sensitivity(curve):
    config, name, c, _ = curve
    theta = getattr(Parameters(), name)
    h = 1e-3 * (c.p[-1] - c.p[0])
    shifted, _ = min_shimmy_curve(config, name, values=(theta - h, theta + h), n=3)
    slope = (shifted.value_at(theta + h) - shifted.value_at(theta - h)) / (2 * h)
    derivative = sensitivity(config, 150e3, names=[name], amplitude=False).min_shimmy["dFz_dp"][name]
    assert slope == pytest.approx(derivative, rel=1e-4)


def test_the_study_carries_the_curve():
    from shimmy.analyses.decisions.studies import study

    out = study("e_p", [0.0008, 0.003], configs=["nes"]).to_dict()
    lowest = [c for c in out["curves"] if c["quantity"] == "min_shimmy_Fz"]
    assert len(lowest) == 1 and lowest[0]["unit"] == "N" and lowest[0]["config"] == "nes"
    assert 7.0e4 < min(lowest[0]["values"]) < max(lowest[0]["values"]) < 9.0e4
