"""Study curves: the continued Hopf speeds against the eigenvalue scan, the sampled study and the
sensitivities."""

import numpy as np
import pytest

from shimmy.analyses.core.stability import hopf_points
from shimmy.analyses.decisions.sensitivity import sensitivity
from shimmy.analyses.decisions.studies import study
from shimmy.analyses.decisions.study_curves import hopf_speed_curves, parameter_range
from shimmy.continuation import PointKind
from shimmy.errors import InvalidParameterError
from shimmy.model.parameters import Parameters

FZ = 150e3


@pytest.fixture(scope="module")
def nes_curves():
    return {name: hopf_speed_curves("nes", name, Fz=FZ) for name in ("r2", "e_p", "k_s", "r3")}


@pytest.mark.parametrize("config", ["nes", "nes_pd"])
@pytest.mark.parametrize("name", ["r2", "e_p"])
def test_every_hopf_speed_of_the_curves_is_one_of_the_eigenvalue_scan(config, name):
    """An independent check: at grid values and at values between them, the curves' Hopf speeds are
    all those the eigenvalue scan finds (1e-6 relative; observed ~1e-13)."""
    speeds = hopf_speed_curves(config, name, Fz=FZ)
    lo, hi = speeds.p_range
    start = speeds.study_curves()[0]
    for theta in [start.p[0], start.p[7], start.p[-1], lo + 0.37 * (hi - lo), lo + 0.81 * (hi - lo)]:
        ours = speeds.speeds_at(theta)
        scan = [h.V for h in hopf_points(config, FZ, params=Parameters().with_overrides({name: theta}),
                                         v_range=(1.0, 200.0)).hopf_points]
        assert len(ours) == len(scan) >= 2, (theta, ours, scan)
        np.testing.assert_allclose(ours, scan, rtol=1e-6)


def test_a_turn_in_the_parameter_is_where_two_hopf_points_are_born():
    """original against the tyre's relaxation length L: the located turn has two Hopf points more (or
    fewer) on one side than on the other, by the eigenvalue scan."""
    speeds = hopf_speed_curves("original", "L", Fz=FZ)
    turns = [e for e in speeds.events() if e["kind"] == PointKind.P2_TURN]
    assert turns
    for e in turns:
        counts = [len(hopf_points("original", FZ, params=Parameters().with_overrides(L=e["p"] * f),
                                  v_range=(1.0, 200.0)).hopf_points) for f in (1 - 1e-4, 1 + 1e-4)]
        assert abs(counts[0] - counts[1]) == 2, (e, counts)


def test_curves_equal_the_sampled_study_at_its_values():
    """The study's curves at its values equal its sampled rows (1e-6 relative)."""
    values = [0.0006, 0.0031]
    result = study("e_p", values, configs=["nes", "nes_pd"], Fz=FZ).to_dict()
    assert {(c["config"], c["quantity"]) for c in result["curves"]} == {
        (c, q) for c in ("nes", "nes_pd") for q in ("hopf_V_start", "hopf_V_end", "min_shimmy_Fz", "max_psi",
                                                    "double_hopf_Fz", "double_hopf_V")} | {("nes", "gh_Fz"), ("nes", "gh_V")}
    for c in result["curves"]:
        if c["quantity"] == "min_shimmy_Fz":  # tests/analyses/decisions/test_min_shimmy_curve.py
            assert c["unit"] == "N" and c["p"][0] == 0.0005 and c["p"][-1] == 0.005
            continue
        if c["quantity"] == "max_psi":  # the sampled rows themselves at their values (test_studies.py)
            assert c["unit"] == "rad" and c["p"][0] == 0.0005 and c["p"][-1] == 0.005
            for row in (r for r in result["rows"] if r["config"] == c["config"]):
                assert c["values"][c["p"].index(row["e_p"])] == row["max_psi"]
            continue
        if c["quantity"].startswith(("gh_", "double_hopf_")):  # tests/analyses/decisions/test_codim2_curve.py
            assert c["p"][0] == 0.0005 and c["p"][-1] == 0.005 and None not in c["values"] and c["point"] in (1, 2)
            continue
        assert c["p"][0] == 0.0005 and c["p"][-1] == 0.005 and c["unit"] == "m/s"
        assert c["p"] == sorted(c["p"]) and len(c["p"]) == len(c["values"]) > 20
        for row in (r for r in result["rows"] if r["config"] == c["config"]):
            sampled = row["hopf_start"] if c["quantity"] == "hopf_V_start" else row["hopf_end"]
            value = c["values"][c["p"].index(row["e_p"])]
            assert value == pytest.approx(sampled, rel=1e-6)


@pytest.mark.parametrize("name", ["r2", "e_p", "k_s", "r3"])
def test_slopes_at_the_nominal_design_equal_the_sensitivities(nes_curves, name):
    """Central differences of the curves (step 1e-3 of the range: truncation ~1e-6 of the slope,
    the Newton tolerance 1e-12 of V adds < 1e-7) against the implicit derivatives dV/dp; bar 1e-4."""
    speeds = nes_curves[name]
    theta = getattr(Parameters(), name)
    h = 1e-3 * (speeds.p_range[1] - speeds.p_range[0])
    up, down = speeds.speeds_at(theta + h), speeds.speeds_at(theta - h)
    slopes = [(a - b) / (2 * h) for a, b in zip(up, down, strict=True)]
    derivative = [x["dV_dp"][name] for x in
                  sensitivity("nes", FZ, names=[name], amplitude=False, min_shimmy=False).hopf]
    assert len(slopes) == len(derivative) == 2
    for s, d in zip(slopes, derivative, strict=True):
        assert s == pytest.approx(d, rel=1e-4, abs=1e-6 * abs(max(derivative, key=abs)))


def test_the_nes_radii_range_keeps_the_roller_on_its_track():
    lo, hi = parameter_range("r1", Parameters())
    assert lo == 0.05 and hi < 0.2
    assert 0.09 > (hi + Parameters().r2) * np.sqrt(3) / 4 > 0.09 - 1e-3 * 0.15 * 1.01


def test_bad_input_names_the_field_the_value_and_the_range():
    with pytest.raises(InvalidParameterError, match="r22"):
        hopf_speed_curves("nes", "r22")
    with pytest.raises(InvalidParameterError, match="Fz"):
        hopf_speed_curves("nes", "r2", Fz=5.0)
    with pytest.raises(InvalidParameterError, match="p_max"):
        hopf_speed_curves("nes", "r2", p_range=(0.07, 0.1))


def test_a_count_is_studied_at_its_whole_values_only():
    """The particle damper's segment count n is an integer: its study curves take whole values only (1 to 100),
    each exact there (the Hopf speeds against hopf_points of that design), and a special point between two
    counts is reported at the next one, not located."""
    from shimmy.analyses.decisions.study_curves import StudyCurve, on_whole_values

    start, end = hopf_speed_curves("nes_pd", "n").study_curves(values=[24.0])
    assert start.p == [float(k) for k in range(1, 101)] and end.p == start.p
    for n in (1.0, 24.0, 57.0):
        found = [h.V for h in hopf_points("nes_pd", 150e3, params=Parameters().with_overrides({"n": n}),
                                          v_range=(1.0, 200.0)).hopf_points]
        assert start.value_at(n) == pytest.approx(min(found), rel=1e-9)
        assert end.value_at(n) == pytest.approx(max(found), rel=1e-9)
    curve = StudyCurve("nes_pd", "hopf_V_start", "n", [1.0, 1.5, 2.0, 3.0], [5.0, 5.5, 6.0, 7.0],
                       [{"kind": "hopf", "p": 2.4, "value": 6.4, "located": True},
                        {"kind": "end", "p": 3.0, "value": 7.0}])
    whole = on_whole_values(curve)
    assert whole.p == [1.0, 2.0, 3.0] and whole.values == [5.0, 6.0, 7.0]
    assert whole.special_points[0] == {"kind": "hopf", "p": 3.0, "value": 7.0, "located": False,
                                       "between": [2.0, 3.0]}
    assert whole.special_points[1] == {"kind": "end", "p": 3.0, "value": 7.0}
