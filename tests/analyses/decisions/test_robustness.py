"""Robustness samples: the minimum shimmy load of a sample is the lowest point of its own Hopf curves."""

import math

import pytest

from shimmy.analyses.diagrams.hopf_curves import hopf_curves
from shimmy.analyses.decisions.robustness import _sample_unit, robustness
from shimmy.errors import InvalidParameterError
from shimmy.model.parameters import Parameters


def test_a_sample_whose_newton_start_leads_out_of_the_box_gets_its_lowest_point_from_the_curves():
    """c_psi 10 % low: Newton from the nominal lowest point of nes_pd converged to a turning point at
    Fz = -114 kN (it was counted as that sample's minimum shimmy load); the continued curves give 88.8 kN."""
    nominal = hopf_curves("nes_pd").fz_minimum
    values = {"k_lam": 0.002060511150458794, "c_psi": 372.79458563720874, "k_s": 1215303.0631318688}
    start = (nominal["V"], nominal["Fz"], 2 * math.pi * nominal["frequency_hz"])
    task = ("nes_pd", Parameters().to_dict(), list(values), [list(values.values())], 150e3, start)
    (entry,) = _sample_unit(task)
    expected = hopf_curves("nes_pd", params=Parameters().with_overrides(values)).fz_minimum["Fz"]
    assert entry["min_shimmy_Fz"] == pytest.approx(expected, rel=1e-6) and expected > 8e4
    assert entry["min_recomputed"]


def test_a_sample_whose_newton_start_reaches_another_mode_gets_its_lowest_point_from_the_curves():
    """Newton from the nominal lowest point reached a turning point of a 16 Hz mode at 227 kN (inside the
    box); the lowest point of this sample's curves is at 87.8 kN, on the 10 Hz mode."""
    nominal = hopf_curves("nes_pd").fz_minimum
    values = {"k_lam": 0.00196, "c_psi": 367.745226, "k_s": 1152470.611408}
    start = (nominal["V"], nominal["Fz"], 2 * math.pi * nominal["frequency_hz"])
    (entry,) = _sample_unit(("nes_pd", Parameters().to_dict(), list(values), [list(values.values())], 150e3, start))
    expected = hopf_curves("nes_pd", params=Parameters().with_overrides(values)).fz_minimum["Fz"]
    assert entry["min_shimmy_Fz"] == pytest.approx(expected, rel=1e-6) and expected < 1e5


def test_a_disturbance_counts_every_attractor_it_reaches_beside_linear_shimmy():
    """With a yaw disturbance of up to 0.05 rad, `original` (k_psi +-5 %) shimmies wherever straight rolling is
    unstable and also reaches torsional shimmy at (50 m/s, 550 kN), whose yaw margin is 0.0165 rad, but not at
    (110 m/s, 550 kN), whose margin is 0.080 rad: the count covers the linear one and says which mode."""
    result = robustness("original", ["k_psi=0.05"], samples=2, disturbance=0.05)
    d = result.to_dict()
    assert d["disturbance"] == {"size": 0.05, "unit": "rad", "direction": "psi"}
    for point, share in d["p_shimmy_disturbed"].items():
        assert share["p"] >= d["p_shimmy"][point] and share["samples"] == 2
        assert share["linearly_unstable"] == round(2 * d["p_shimmy"][point])
        assert share["ci95"][0] <= share["p"] <= share["ci95"][1]
    G, H, C = (d["p_shimmy_disturbed"][p] for p in "GHC")
    assert G["modes"]["torsional"]["p"] == 1.0 and G["modes"]["lateral"]["p"] == 1.0  # both cycles within reach
    assert H["modes"]["torsional"]["p"] == 0.0 and H["modes"]["lateral"]["p"] == 1.0
    assert C["p"] == 0.0 and d["p_shimmy"]["C"] == 0.0  # stable straight rolling and nothing beside it
    assert "p_shimmy_disturbed" in d["methods"] and "after a disturbance up to 0.05 rad" in result.summary_text()
    assert all(lo <= d["p_shimmy"][p] <= hi for p, (lo, hi) in d["p_shimmy_ci95"].items())


@pytest.mark.parametrize("options, field, message", [
    ({"disturbance": 0.001}, "disturbance", r"disturbance=0.001 is out of range; allowed: a number in \[0.002, 1\]"),
    ({"disturbance": 0.1, "disturbance_direction": "yaw"}, "disturbance_direction", "unknown disturbance_direction"),
])
def test_bad_disturbances_are_refused(options, field, message):
    with pytest.raises(InvalidParameterError, match=message) as err:
        robustness("original", ["k_psi=0.05"], samples=2, **options)
    assert err.value.field == field
