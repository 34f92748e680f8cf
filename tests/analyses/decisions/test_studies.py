"""Parametric studies: rows checked against eigenvalues, the diagram, and what a parameter cannot change."""

import io

import numpy as np
import pytest

from shimmy.analyses.diagrams.bifurcation import BifurcationOptions, bifurcation
from shimmy.errors import InvalidParameterError
from shimmy.analyses.core.executors import InlineExecutor
from shimmy.model.parameters import Parameters
from shimmy.analyses.core.stability import eigenvalues
from shimmy.analyses.decisions.studies import study, study_grid


@pytest.fixture(scope="module")
def e_p_study():
    return study("e_p", [0.0005, 0.005], configs=["original", "nes"], Fz=150e3)


def test_hopf_speeds_of_a_row_are_where_the_growth_rate_changes_sign(e_p_study):
    for row in e_p_study.rows:
        params = Parameters().with_overrides({"e_p": row["e_p"]})
        for V, rising in ((row["hopf_start"], True), (row["hopf_end"], False)):
            below = eigenvalues(row["config"], V - 1e-3, 150e3, params=params).real.max()
            above = eigenvalues(row["config"], V + 1e-3, 150e3, params=params).real.max()
            assert (below < 0 < above) if rising else (above < 0 < below), (row, V)


def test_a_row_equals_the_diagram_of_that_design(e_p_study):
    row = next(r for r in e_p_study.rows if r["config"] == "nes" and r["e_p"] == 0.005)
    direct = bifurcation("nes", 150e3, v_range=(1.0, 200.0), params=Parameters().with_overrides({"e_p": 0.005}),
                         options=BifurcationOptions(mesh_check=False))
    assert row["max_psi"] == direct.max_psi and row["max_psi_V"] == direct.max_psi_V
    assert row["hopf_points"] == sorted(h.V for h in direct.hopf.hopf_points)


def test_the_nes_pre_stretch_changes_nes_rows_only(e_p_study):
    rows = {(r["config"], r["e_p"]): r for r in e_p_study.rows}
    same = ("hopf_start", "hopf_end", "max_psi")
    assert all(rows["original", 0.0005][k] == rows["original", 0.005][k] for k in same)
    # A stiffer NES (more pre-stretch) moves both Hopf points and lowers the amplitude.
    assert rows["nes", 0.005]["hopf_start"] > rows["nes", 0.0005]["hopf_start"]
    assert rows["nes", 0.005]["hopf_end"] < rows["nes", 0.0005]["hopf_end"]
    assert rows["nes", 0.005]["max_psi"] < rows["nes", 0.0005]["max_psi"]


def test_the_max_psi_curve_passes_through_the_sampled_rows_and_is_a_diagram_at_each_grid_value(e_p_study):
    from shimmy.analyses.decisions.max_psi_curve import N_GRID, SUBSTEPS, grid

    for config in ("original", "nes"):
        curve = next(c for c in e_p_study.curves if c["config"] == config and c["quantity"] == "max_psi")
        assert curve["unit"] == "rad" and curve["p"] == sorted(curve["p"]) and len(curve["p"]) >= N_GRID
        assert curve["p"][0] == 0.0005 and curve["p"][-1] == 0.005  # the whole range, ends included
        for row in (r for r in e_p_study.rows if r["config"] == config):
            assert curve["values"][curve["p"].index(row["e_p"])] == row["max_psi"]  # the sampled row itself
    nes = next(c for c in e_p_study.curves if c["config"] == "nes" and c["quantity"] == "max_psi")
    on_grid = grid("e_p", Parameters(), [0.0005, 0.005])
    assert len(nes["p"]) == len(on_grid) + (len(on_grid) - 1) * (SUBSTEPS - 1)  # followed between all of them
    k = nes["p"].index(on_grid[len(on_grid) // 2])
    for theta in (nes["p"][k], nes["p"][k + 1], nes["p"][k + SUBSTEPS // 2]):  # a grid value, two followed ones
        direct = bifurcation("nes", 150e3, v_range=(1.0, 200.0), params=Parameters().with_overrides({"e_p": theta}),
                             options=BifurcationOptions(mesh_check=False))
        assert nes["values"][nes["p"].index(theta)] == pytest.approx(direct.max_psi, rel=1e-8), theta
    assert np.all(np.diff(nes["values"]) < 0)  # more pre-stretch, a stiffer NES: a smaller amplitude throughout
    original = next(c for c in e_p_study.curves if c["config"] == "original" and c["quantity"] == "max_psi")
    assert len(set(original["values"])) == 1 and original["special_points"] == []  # e_p is not in original
    assert original["p"] == on_grid  # nothing to follow where the parameter does not enter


def test_max_psi_switches_are_marked_where_the_maximum_jumps_or_cycles_vanish():
    from shimmy.analyses.decisions.max_psi_curve import max_psi_curve

    rows = [{"x": 0.0, "max_psi": 0.1, "max_psi_V": 10.0}, {"x": 1.0, "max_psi": 0.12, "max_psi_V": 12.0},
            {"x": 2.0, "max_psi": 0.15, "max_psi_V": 60.0}, {"x": 3.0, "max_psi": 0.0, "max_psi_V": None}]
    curve = max_psi_curve("nes", "x", rows[::-1], (1.0, 200.0))
    assert curve.p == [0.0, 1.0, 2.0, 3.0] and curve.values == [0.1, 0.12, 0.15, 0.0]
    assert [(s["bracket"], s["located"]) for s in curve.special_points] == [([1.0, 2.0], False), ([2.0, 3.0], False)]


def test_followed_maxima_take_the_larger_stable_value_and_narrow_a_switch_to_their_step():
    from shimmy.analyses.decisions.max_psi_curve import max_psi_curve

    rows = [{"x": 1.0, "max_psi": 0.12, "max_psi_V": 12.0}, {"x": 2.0, "max_psi": 0.15, "max_psi_V": 60.0}]
    ahead = {"points": [{"p": 1.25, "value": 0.125, "V": 12.5}, {"p": 1.5, "value": 0.13, "V": 13.0},
                        {"p": 1.75, "value": 0.135, "V": 13.5}, {"p": 2.0, "value": 0.14, "V": 14.0}], "stopped": None}
    back = {"points": [{"p": 1.75, "value": 0.145, "V": 59.0}, {"p": 1.5, "value": 0.128, "V": 58.0}],
            "stopped": "the cycle of the maximum is unstable at 1.25"}
    curve = max_psi_curve("nes", "x", rows, (1.0, 200.0), {(1.0, 2.0): ahead, (2.0, 1.0): back})
    assert curve.p == [1.0, 1.25, 1.5, 1.75, 2.0]
    assert curve.values == [0.12, 0.125, 0.13, 0.145, 0.15]  # the larger of the two where both exist
    assert [s["bracket"] for s in curve.special_points] == [[1.5, 1.75]]  # not [1, 2]: between followed points


def test_a_followed_maximum_is_the_diagrams_maximum_of_each_design_it_passes():
    from shimmy.analyses.decisions.max_psi_curve import follow_maximum, orbit_of, substeps

    options = BifurcationOptions(mesh_check=False)
    start = bifurcation("nes", 150e3, params=Parameters().with_overrides({"k_s": 1.0e6}), options=options)
    follow = follow_maximum(("nes", 150e3, "k_s", Parameters(), orbit_of(start), substeps(1.0e6, 1.2e6), options,
                             (1.0, 200.0)))
    assert follow["stopped"] is None and [q["p"] for q in follow["points"]] == substeps(1.0e6, 1.2e6)
    assert np.all(np.diff([q["value"] for q in follow["points"]]) < 0)
    for q in (follow["points"][1], follow["points"][-1]):
        direct = bifurcation("nes", 150e3, params=Parameters().with_overrides({"k_s": q["p"]}), options=options)
        assert q["value"] == pytest.approx(direct.max_psi, rel=1e-8)
        assert q["V"] == pytest.approx(direct.max_psi_V, rel=1e-5)  # a flat maximum: its speed to ~sqrt(tol)
    # a maximum beyond the study's speed range is no diagram's maximum: the follow stops there
    V = follow["points"][0]["V"]
    short = follow_maximum(("nes", 150e3, "k_s", Parameters(), orbit_of(start), substeps(1.0e6, 1.2e6), options,
                            (1.0, V - 0.01)))
    assert short["points"] == [] and "leaves the speed range" in short["stopped"]


def test_a_count_is_studied_at_whole_values_only():
    from shimmy.analyses.decisions.max_psi_curve import grid, substeps

    values = grid("n", Parameters(), [20, 24])
    assert values[0] == 1.0 and values[-1] == 100.0 and {20.0, 24.0} <= set(values)
    assert all(v == round(v) for v in values)
    for a, b in zip(values, values[1:]):
        inner = substeps(a, b, "n")[:-1]
        assert all(v == round(v) and min(a, b) < v < max(a, b) for v in inner)
        assert inner == substeps(b, a, "n")[:-1][::-1]


def test_follows_from_both_ends_of_an_interval_visit_the_same_values():
    from shimmy.analyses.decisions.max_psi_curve import SUBSTEPS, grid, substeps

    values = grid("e_p", Parameters(), [0.0005, 0.005])
    for a, b in zip(values, values[1:]):
        ahead, back = substeps(a, b), substeps(b, a)
        assert len(ahead) == SUBSTEPS and ahead[-1] == b and back[-1] == a
        assert ahead[:-1] == back[:-1][::-1]  # equal floats: the larger of two values taken at each


def test_two_parameter_grid_has_a_row_per_pair_and_configuration():
    result = study_grid(("e_p", "k_s"), ([0.0005, 0.005], [1.0e6, 1.4e6]), configs=["nes"], Fz=150e3,
                        executor=InlineExecutor())
    assert len(result.rows) == 4
    assert {(r["e_p"], r["k_s"]) for r in result.rows} == {(a, b) for a in (0.0005, 0.005) for b in (1.0e6, 1.4e6)}
    assert result.values == [[0.0005, 0.005], [1.0e6, 1.4e6]]
    buf = io.StringIO()
    result.write_csv(buf)
    lines = buf.getvalue().splitlines()
    assert lines[0].startswith("e_p,k_s,config,hopf_start_m_s") and len(lines) == 5
    # each grid row equals the one-parameter study at the same design
    one = study("k_s", [1.4e6], configs=["nes"], Fz=150e3, params=Parameters().with_overrides({"e_p": 0.005}),
                executor=InlineExecutor()).rows[0]
    grid_row = next(r for r in result.rows if r["e_p"] == 0.005 and r["k_s"] == 1.4e6)
    assert np.isclose(grid_row["max_psi"], one["max_psi"], rtol=0, atol=0)


@pytest.mark.parametrize("call, field", [
    (lambda: study("zeta", [1.0], configs=["nes"]), "parameter"),
    (lambda: study("e_p", [0.5], configs=["nes"]), "e_p"),
    (lambda: study("e_p", [], configs=["nes"]), "values"),
    (lambda: study("e_p", [0.001], configs=["gear"]), "config"),
    (lambda: study("e_p", [0.001], configs=[]), "configs"),
    (lambda: study("e_p", [0.001], configs=["nes"], Fz=5.0), "Fz"),
    (lambda: study_grid(("e_p", "e_p"), ([0.001], [0.002]), configs=["nes"]), "parameters"),
])
def test_bad_study_requests_name_the_field(call, field):
    with pytest.raises(InvalidParameterError) as err:
        call()
    assert err.value.field == field
