"""Disturbance margins on the map (shimmy.analyses.maps.margin_map): on a plane of 2 x 2 cells of `original`, the
cells where a torsional cycle coexists with another attractor get the margin the single-point analysis gives at the
cell's centre (the same numbers: the same diagram, runs and bisection), the others none; bad input is refused by
name before any work."""

from __future__ import annotations

import pytest

from shimmy.analyses.core.executors import InlineExecutor, open_executor
from shimmy.analyses.maps.margin_map import cell_centres, margin_map, worst_of
from shimmy.analyses.maps.margins import margins
from shimmy.errors import InvalidParameterError

#: Cells centred on V 60 and 100 m/s, Fz 600 and 800 kN: three of them bistable, (100 m/s, 800 kN) lateral only.
PLANE = {"v_range": (40.0, 120.0), "fz_range": (500e3, 900e3), "n_v": 2, "n_fz": 2}


@pytest.fixture(scope="module")
def mapped():
    with open_executor(max_workers=2) as pool:
        return margin_map("original", executor=pool, **PLANE)


def test_cells_are_asked_at_their_centres():
    assert cell_centres(40.0, 120.0, 2).tolist() == [60.0, 100.0]
    assert cell_centres(1.0, 200.0, 20)[0] == 5.975


def test_the_map_holds_the_single_point_margins_where_a_torsional_cycle_coexists(mapped):
    result = mapped.to_dict()
    assert result["V"] == [60.0, 100.0] and result["Fz"] == [600e3, 800e3]
    assert result["coexisting"] == [[2, 2], [2, 1]] and result["types"][1][1] == "Lateral"
    assert [(p["V"], p["Fz"]) for p in result["points"]] == [(60.0, 600e3), (100.0, 600e3), (60.0, 800e3)]
    counts = result["counts"]
    assert (counts["cells"], counts["multistable"], counts["bistable"], counts["computed"]) == (4, 3, 3, 3)
    assert "torsional limit cycle" in result["worst"] and result["unit"] == "rad" and result["direction"] == "psi"
    for point in result["points"]:
        assert point["type"] == "Bistable" and point["attractors"][point["worst"]]["mode"] == "torsional"
        assert 0.0 < point["margin"] < 0.4 and point["confirmed"] and point["lower"] < point["margin"] < point["upper"]
    for V, Fz in ((60.0, 600e3), (60.0, 800e3)):  # two cells against the single-point analysis
        single = margins("original", V, Fz, direction="psi", executor=InlineExecutor()).to_dict()
        torsional = single["attractors"][worst_of(single["attractors"])]["min_disturbance"]
        point = next(p for p in result["points"] if (p["V"], p["Fz"]) == (V, Fz))
        assert (point["margin"], point["lower"], point["upper"], point["tolerance"]) == \
            (torsional["value"], torsional["lower"], torsional["upper"], torsional["tolerance"])
        assert [a["min_kick"] for a in point["attractors"]] == \
            [a["min_disturbance"]["value"] for a in single["attractors"]]
    assert result["points"][0]["margin"] < result["points"][2]["margin"]  # a heavier load: a larger kick
    text = mapped.summary_text()
    assert "3 cells with two or more attractors (3 Bistable)" in text and "V \\ Fz (kN)" in text


def test_the_same_map_on_any_executor(mapped):
    inline = margin_map("original", executor=InlineExecutor(), **PLANE).to_dict()
    assert inline["points"] == mapped.to_dict()["points"]


@pytest.mark.parametrize("overrides, field", [
    ({"n_v": 1}, "n_v"), ({"n_fz": 100}, "n_fz"), ({"n_v": 2.5}, "n_v"), ({"v_range": (60.0, 40.0)}, "v_max"),
    ({"fz_range": (0.0, 5e5)}, "fz_min"), ({"direction": "energy"}, "direction"), ({"max_size": 5.0}, "max_size"),
    ({"rtol": 0.0}, "rtol"),
])
def test_bad_input_is_refused_naming_the_field(overrides, field):
    with pytest.raises(InvalidParameterError) as info:
        margin_map("original", executor=InlineExecutor(), **{**PLANE, **overrides})
    assert info.value.field == field


def test_an_unknown_configuration_is_refused():
    with pytest.raises(InvalidParameterError) as info:
        margin_map("gear", executor=InlineExecutor(), **PLANE)
    assert info.value.field == "config"
