"""Robustness samples: the minimum shimmy load of a sample is the lowest point of its own Hopf curves."""

import math

import pytest

from shimmy.analyses.diagrams.hopf_curves import hopf_curves
from shimmy.analyses.decisions.robustness import _sample_unit
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
