"""Design sessions (ui/designs.py): a design file round-trips, a bad one is refused naming each field,
value and range (nothing dropped, nothing clipped), saved entries are checked again when used, and
the comparison tables give each design's change against the first."""

import json

import pytest

from shimmy.errors import InvalidParameterError
from shimmy.model.parameters import PARAMETER_SPECS, Parameters
from shimmy.service import schemas
from shimmy.version import __version__
from ui import designs, state
from ui.designs import Design, DesignError


def _file(**changes):
    data = Design.make("A", "steel", {"r2": 0.085}).file()
    data.update(changes)
    return json.dumps(data)


def _refused(content, filename="bad.json") -> list[str]:
    with pytest.raises(DesignError) as info:
        designs.from_file(content, filename)
    assert info.value.what == filename
    return info.value.problems


def test_a_design_file_round_trips_to_the_same_design_and_the_same_file():
    design = Design.make("wide track, stiff spring", "tungsten", {"r2": 0.0853, "k_s": 1.31e6, "rho_p": 16500},
                         config="nes_pd")
    assert design.params == {"r2": 0.0853, "k_s": 1.31e6}  # rho_p is tungsten's own value
    text = design.text()
    data = json.loads(text)
    assert data["format"] == "shimmy design" and data["shimmy_version"] == __version__
    assert data["name"] == "wide track, stiff spring" and data["material"] == "tungsten"
    assert data["config"] == "nes_pd"
    assert set(data["parameters"]) == set(PARAMETER_SPECS)  # every value, not only the changes
    assert data["parameters"]["rho_p"] == 16500 and data["units"]["k_s"] == "N/m"
    again, notes = designs.from_file(text.encode(), "x.json")
    assert again == design and notes == []
    assert again.text() == text
    # and the service asks for exactly the same analysis
    body = {"config": "nes", "Fz": 150e3}
    assert (schemas.validate("bifurcation", {**body, **design.request()})
            == schemas.validate("bifurcation", {**body, **again.request()}))


def test_a_link_reopens_the_exact_values():
    """The address carries the values exactly (a slider's 0.07010000000000001 too), and the page's
    request from that address is the saved design's request: the same cache key, the same figures."""
    design = Design.make("B", "steel", {"r2": 0.07010000000000001, "e_p": 0.0012345678901234})
    query = {k: v for k, v in design.query().items() if v is not None}
    assert query == {"r2": "0.07010000000000001", "e_p": "0.0012345678901234"}
    material, values, problems = state.design_from_query(query)
    assert not problems and state.design_request(material, values) == design.request()
    # keys the design does not set are removed from the address, the configuration set when saved with one
    assert design.query()["k_s"] is None and design.query()["material"] is None
    assert Design.make("C", "tungsten", {}, config="pd").query()["config"] == "pd"


@pytest.mark.parametrize("change, expected", [
    ({"r2": 0.5}, "r2 = 0.5 m is out of range; allowed: a number in [0.07, 0.09] m"),
    ({"k_s": 9e5}, "k_s = 900000 N/m is out of range; allowed: a number in [1e+06, 1.4e+06] N/m"),
    ({"n": 2.5}, "n = 2.5 is not an integer; allowed: an integer in [1, 100]"),
    ({"e_p": "0.002"}, 'e_p = "0.002" is not a number; allowed: a number in [0.0005, 0.005] m'),
    ({"e_p": None}, "e_p = null is not a number; allowed: a number in [0.0005, 0.005] m"),
    ({"k_sx": 1.2e6}, "unknown parameter 'k_sx' (did you mean k_s, k_psi?)"),
])
def test_a_bad_value_is_refused_with_its_field_value_and_range_in_its_unit(change, expected):
    data = json.loads(_file())
    data["parameters"].update(change)
    problems = _refused(json.dumps(data))
    assert len(problems) == 1 and problems[0].startswith(expected)


def test_every_problem_of_a_file_is_named_and_nothing_is_applied():
    data = json.loads(_file())
    data["parameters"].update({"r2": 0.2, "a_p": 1.5, "bogus": 1})
    data["units"]["d_p"] = "mm"
    data["colour"] = "red"
    problems = _refused(json.dumps(data))
    text = " | ".join(problems)
    for part in ("r2 = 0.2 m is out of range", "a_p = 1.5 is out of range; allowed: a number in [0.5, 0.95]",
                 "unknown parameter 'bogus'", "units: d_p is given in 'mm', but shimmy takes it in 'm'",
                 "unknown key 'colour'"):
        assert part in text, part


def test_the_rules_across_fields_are_the_models_own():
    data = json.loads(_file())
    data["parameters"].update({"r1": 0.2, "r2": 0.07, "r3": 0.005})
    (problem,) = _refused(json.dumps(data))
    with pytest.raises(InvalidParameterError) as model:
        Parameters().with_overrides({"r1": 0.2, "r2": 0.07, "r3": 0.005})
    assert model.value.allowed in problem and "leave its track" in problem
    assert "r1 = 0.2 m" in problem and "r2 = 0.07 m" in problem  # what the design moved
    # a combination valid as a whole is accepted, though r1 alone would break the rule
    assert Design.make("ok", "steel", {"r1": 0.135, "r3": 0.02}).params == {"r1": 0.135, "r3": 0.02}


@pytest.mark.parametrize("content, expected", [
    ("", "is not JSON (Expecting value at line 1, column 1)"),
    ("{", "is not JSON"),
    ("[1, 2]", "holds a JSON list, not a design"),
    (b"\xff\xfe\x00", "is not UTF-8 text"),
    ('{"format": "shimmy design", "parameters": {"r2": NaN}}', "NaN is not a number"),
    ('{"format": "something else", "parameters": {}}', "format = 'something else', not 'shimmy design'"),
    ('{"name": "x", "parameters": {}}', 'has no "format"'),
    ('{"format": "shimmy design", "format_version": 2}', "format_version = 2: this shimmy reads design files of "
                                                         "version 1"),
    ('{"format": "shimmy design", "parameters": [1]}', "parameters is a JSON list"),
    ('{"format": "shimmy design", "material": "gold"}', "material = 'gold' is not one of steel, tungsten"),
    ('{"format": "shimmy design", "config": "both"}', "config = 'both' is not one of original, nes, pd, nes_pd"),
    ('{"format": "shimmy design", "name": ""}', "name = '' is not a name"),
    ("x" * (designs.MAX_FILE_BYTES + 1), "a design file is a few kB (at most 32 kB)"),
])
def test_what_is_not_a_design_file_is_refused_saying_why(content, expected):
    problems = _refused(content)
    assert any(expected in p for p in problems), problems


def test_a_partial_file_says_what_it_leaves_to_the_preset():
    design, notes = designs.from_file('{"format": "shimmy design", "shimmy_version": "0.0.9", '
                                      '"parameters": {"r2": 0.085}}', "mine.json")
    assert design == Design("mine", "steel", {"r2": 0.085})
    assert "no material given: steel" in notes and "no name given: named 'mine'" in notes
    assert any(n.startswith("37 parameters not given") and n.endswith("the steel values") for n in notes)
    assert "written by shimmy 0.0.9; this is shimmy " + __version__ in notes


def test_saved_designs_save_replace_rename_delete():
    a, b = Design.make("A", "steel", {"r2": 0.085}), Design.make("B", "steel", {"k_s": 1.3e6})
    saved, id_a, said = designs.save(None, a)
    assert said == "Saved 'A' in this browser (1 saved)."
    saved, id_b, _ = designs.save(saved, b)
    assert [e["name"] for e in designs.saved_list(saved)] == ["A", "B"] and id_a != id_b
    saved, same_id, said = designs.save(saved, Design.make("A", "steel", {"r2": 0.086}))
    assert same_id == id_a and said == "Replaced the saved design 'A'."
    assert designs.from_entry(designs.find(saved, id_a)).params == {"r2": 0.086}
    saved, said = designs.rename(saved, id_b, "  B stiff ")
    assert said == "Renamed 'B' to 'B stiff'." and designs.find(saved, id_b)["name"] == "B stiff"
    with pytest.raises(DesignError, match="'A' is the name of another saved design"):
        designs.rename(saved, id_b, "A")
    with pytest.raises(DesignError, match="is not a name"):
        designs.rename(saved, id_b, "   ")
    saved, said = designs.delete(saved, id_a)
    assert said == "Deleted 'A'." and [e["id"] for e in designs.saved_list(saved)] == [id_b]
    full = None
    for k in range(designs.MAX_SAVED):
        full, _, _ = designs.save(full, Design.make(f"d{k}", "steel", {}))
    with pytest.raises(DesignError, match=f"{designs.MAX_SAVED} designs are saved"):
        designs.save(full, a)


def test_a_saved_entry_is_checked_again_when_used():
    """The store is the browser's: an entry changed there (or saved under other ranges) is refused by name."""
    saved, entry_id, _ = designs.save(None, Design.make("A", "steel", {"r2": 0.085}))
    designs.find(saved, entry_id)["params"]["r2"] = 0.5
    assert designs.usable(designs.find(saved, entry_id)).startswith("r2 = 0.5 m is out of range")
    with pytest.raises(DesignError, match="saved design 'A'"):
        designs.compared([entry_id, designs.CURRENT], saved, {"material": "steel", "params": {}})
    assert designs.saved_list({"designs": [1, {"name": "no id"}, "x"]}) == []
    assert designs.saved_list("junk") == []


def test_the_current_design_is_recognised_among_the_saved():
    saved, entry_id, _ = designs.save(None, Design.make("A", "tungsten", {"r2": 0.085}))
    current = designs.current_design({"material": "tungsten", "params": {"r2": 0.085}})
    assert designs.matching(saved, current)["id"] == entry_id
    assert designs.matching(saved, designs.current_design({"material": "steel", "params": {"r2": 0.085}})) is None


def test_a_comparison_takes_two_to_four_different_designs_current_first():
    saved, id_a, _ = designs.save(None, Design.make("A", "steel", {"r2": 0.085}))
    saved, id_b, _ = designs.save(saved, Design.make("B", "steel", {"r2": 0.075}))
    current = {"material": "steel", "params": {"k_s": 1.3e6}}
    chosen = designs.compared([id_b, designs.CURRENT, id_a, "gone"], saved, current)
    assert [d.name for d in chosen] == ["current design", "A", "B"]
    with pytest.raises(DesignError, match="1 design ticked; tick 2 to 4"):
        designs.compared([id_a], saved, current)
    with pytest.raises(DesignError, match="'current design' and 'A' are the same design"):
        designs.compared([designs.CURRENT, id_a], saved, {"material": "steel", "params": {"r2": 0.085}})
    for k in range(3):
        saved, _, _ = designs.save(saved, Design.make(f"X{k}", "steel", {"e_p": 0.002 + k * 1e-4}))
    every = [e["id"] for e in designs.saved_list(saved)]
    with pytest.raises(DesignError, match="5 designs ticked"):
        designs.compared(every, saved, current)


def _metrics(min_fz, lateral, area, hopf, hull, psi, psi_v):
    return {"min_shimmy_Fz": min_fz, "lateral_min_Fz": lateral, "torsion_area": area,
            "at_Fz": {"Fz": 150e3, "hopf_points": hopf, "shimmy_speed_range": hull, "max_psi": psi,
                      "max_psi_V": psi_v}}


def test_the_figures_of_merit_table_gives_each_change_against_the_first():
    first = _metrics(100e3, 218.5e3, 11300.0, [6.7, 71.3], [6.7, 71.3], 0.18, 12.5)
    second = _metrics(120e3, 218.5e3, 9040.0, [7.2, 70.0], [7.2, 70.0], 0.09, 13.0)
    third = _metrics(None, 200e3, 0.0, [], None, None, None)
    table = designs.comparison(["A", "B", "C"], [first, second, third], designs.merit_figures(150e3))
    assert table["columns"] == ["figure", "A", "B", "C"]
    rows = {row[0]: row[1:] for row in table["rows"]}
    low = rows["lowest shimmy load, min_shimmy_Fz (kN)"]
    assert [c.text for c in low] == ["100", "120", "–"]
    assert low[0].change is None
    assert low[1].delta == pytest.approx(20) and low[1].change == "+20 kN (+20.0 %)"
    assert low[2].change == "100 → –"
    lateral = rows["lateral Hopf curve's lowest load, lateral_min_Fz (kN)"]
    assert lateral[1].change == "same" and lateral[2].change == "-18.5 kN (-8.5 %)"
    area = rows["pure-torsion area, Fz ≤ 250 kN ((m/s) kN)"]
    assert [c.text for c in area] == ["11300", "9040", "0"] and area[1].change == "-2260 (-20.0 %)"
    hopf = rows["Hopf speeds at 150 kN (m/s)"]
    assert hopf[1].text == "7.2, 70" and hopf[1].delta == pytest.approx([0.5, -1.3])
    assert hopf[1].change == "+0.5, -1.3 m/s" and hopf[2].change == "2 → 0 points"
    hull = rows["shimmy speed range at 150 kN (m/s)"]
    assert hull[0].text == "6.7 – 71.3" and hull[1].change == "onset +0.5, end -1.3 m/s"
    assert hull[2].text == "none" and hull[2].change == "6.7 – 71.3 → none"
    psi = rows["largest stable |psi| at 150 kN (rad)"]
    assert psi[1].change == "-0.09 rad (-50.0 %)"
    assert rows["speed of that largest |psi| at 150 kN (m/s)"][1].change == "+0.5 m/s"  # no per cent of a speed
    columns, csv_rows = designs.comparison_csv(table)
    assert columns == ["figure", "A", "B", "B: change", "C", "C: change"]
    assert csv_rows[0] == ["lowest shimmy load, min_shimmy_Fz (kN)", "100", "120", "+20 kN (+20.0 %)", "–",
                           "100 → –"]


def test_rounding_noise_is_no_change():
    a, b = _metrics(100e3, 2e5, 1.0, [1.0], [1.0, 2.0], 0.1, 1.0), _metrics(100e3 - 4.66e-8, 2e5, 1.0, [1.0],
                                                                             [1.0, 2.0 + 1e-12], 0.1, 1.0)
    rows = designs.comparison(["A", "B"], [a, b], designs.merit_figures(150e3))["rows"]
    assert all(row[2].change == "same" for row in rows), [(row[0], row[2].change) for row in rows]


def test_hopf_intervals_and_bifurcation_figures_side_by_side():
    def stability(intervals):
        return {"configs": {"nes": {"unstable_intervals": intervals}}}

    table = designs.comparison(["A", "B", "C"], [stability([[6.7, 71.3]]), stability([[6.9, 70.1]]),
                                                 stability([])], designs.hopf_figures(["nes"], {"nes": "NES"}))
    (row,) = table["rows"]
    assert row[0] == "NES: x = 0 unstable for V in (m/s)"
    assert [c.text for c in row[1:]] == ["6.7 – 71.3", "6.9 – 70.1", "none"]
    assert row[2].change == "onset +0.2, end -1.2 m/s" and row[3].change == "1 → 0 intervals"

    def diagram(hopf, psi, lpc):
        return {"hopf_points": [{"V": v, "criticality": "supercritical"} for v in hopf], "max_psi": psi,
                "max_psi_V": 12.0, "warnings": [],
                "branches": [{"kind": "periodic", "special_points": [{"kind": "LPC", "V": v} for v in lpc]}]}

    table = designs.comparison(["A", "B"], [diagram([6.7, 71.3], 0.18, []), diagram([6.8], 0.2, [40.0])],
                               designs.bifurcation_figures())
    rows = {row[0]: row[1:] for row in table["rows"]}
    assert rows["Hopf points V (m/s)"][1].change == "2 → 1 point"
    assert rows["largest stable |psi| (rad)"][1].change == "+0.02 rad (+11.1 %)"
    assert rows["folds of cycles (LPC) V (m/s)"][1].text == "40" and rows["their criticality"][1].change == "differs"


def test_the_configuration_of_a_page_address():
    assert designs.config_from_search("?config=nes&V=30") == "nes"
    assert designs.config_from_search("?configs=nes,pd") is None
    assert designs.config_from_search("?config=both") is None and designs.config_from_search(None) is None


def test_the_page_figures_name_each_design_in_its_colour():
    import app  # noqa: F401 - registers the pages
    from pages import bifurcation, overview, stability_map
    from ui import compare

    def diagram(shift):
        points = [{"V": v, "stable": v < 6 + shift or v > 70, "period": None, "max_psi": 0.0, "max_lateral": 0.0,
                   "mode": None} for v in (1.0, 6 + shift, 70.0, 200.0)]
        cycle = [{"V": v, "stable": True, "period": 0.1, "max_psi": 0.1, "max_lateral": 0.001, "mode": "torsional"}
                 for v in (6 + shift, 40.0, 70.0)]
        return {"config": "nes", "Fz": 150e3, "hopf_points": [{"V": 6 + shift, "frequency_hz": 10.0,
                                                               "criticality": "supercritical"}],
                "branches": [{"kind": "equilibrium", "points": points,
                              "special_points": [{"kind": "H", "V": 6 + shift}, {"kind": "H", "V": 70.0}]},
                             {"kind": "periodic", "points": cycle, "special_points": []}]}

    names = ["A wide track", "B stiff"]
    series = compare.series(names)
    assert series == [("A wide track", "#1A1A1A"), ("B stiff", "#D55E00")]
    assert compare.series(["<b>x</b> & y"])[0][0] == "&lt;b&gt;x&lt;/b&gt; &amp; y"  # shown as typed by Plotly
    fig = bifurcation.figure([diagram(0.0), diagram(1.0)], series, what="design").to_dict()
    keys = [(t["name"], t["line"]["color"]) for t in fig["data"] if t.get("legend", "legend") == "legend"
            and t.get("showlegend")]
    assert keys == series
    assert fig["layout"]["legend"]["title"]["text"] == "design (colour):"
    assert fig["layout"]["yaxis3"]["categoryarray"] == names[::-1]  # one x = 0 strip per design
    strip = [(t["x"][0], t["x"][-1], t["line"]["dash"]) for t in fig["data"] if t.get("y") and t["y"][0] == names[0]
             and t.get("mode") == "lines"]
    assert strip == [(1.0, 6.0, "solid"), (6.0, 70.0, "dash"), (70.0, 200.0, "solid")]  # changes at the Hopf points
    assert fig["layout"]["xaxis3"]["title"]["text"] == "forward speed V (m/s)"

    curve = [{"V": 10.0, "Fz": 100e3}, {"V": 50.0, "Fz": 300e3}]

    def smap(shift):
        return {"config": "nes", "V": [1.0, 200.0], "Fz": [100e3, 400e3], "types": [["Stable", "Torsion"]] * 2,
                "regions": [], "hopf_curves": [[{"V": p["V"] + shift, "Fz": p["Fz"]} for p in curve]],
                "fold_curves": [curve], "torus_curves": [], "gh_points": [], "double_hopf_points": []}

    fig = stability_map.figure([smap(0.0), smap(5.0)], series, what="design").to_dict()
    keys = [(t["name"], t["line"]["color"]) for t in fig["data"] if t.get("legend", "legend") == "legend"
            and t.get("showlegend")]
    assert keys == series
    hopf = [t for t in fig["data"] if t.get("name", "").endswith(": Hopf")]
    assert [(t["name"], t["line"]["color"], t["x"][0]) for t in hopf] == [
        ("A wide track: Hopf", series[0][1], 10.0), ("B stiff: Hopf", series[1][1], 15.0)]
    assert fig["layout"]["title"]["text"] == "NES: curves of 2 designs"
    assert fig["layout"]["title"]["subtitle"]["text"] == "shimmy type of A wide track (shaded)"
    assert (fig["layout"]["xaxis"]["title"]["text"], fig["layout"]["yaxis"]["title"]["text"]) == (
        "forward speed V (m/s)", "vertical load Fz (kN)")

    def stability(a):
        return {"Fz": 150e3, "V": [1.0, 200.0], "configs": {
            c: {"unstable_intervals": [[a, 70.0]], "hopf_points": [{"V": a}, {"V": 70.0}]}
            for c in overview.CONFIGS}}

    fig = overview.intervals_figure([stability(6.0), stability(7.0)], names).to_dict()
    keys = [t["name"] for t in fig["data"] if t.get("showlegend") and t.get("legend", "legend") == "legend"]
    assert keys == names
    assert fig["layout"]["xaxis4"]["title"]["text"] == "forward speed V (m/s)"


def test_compared_designs_that_share_a_cached_result_are_each_asked_for():
    """Two NES designs compared on the original gear's map ask one cached answer (e_p does not enter it)
    but are two requests of the page: each keeps its label, its design and its place."""
    import app  # noqa: F401 - registers the pages
    from ui import jobs

    asked = jobs.canonical("map", [{"config": "original", "params": {"e_p": 0.002}},
                                   {"config": "original", "params": {"e_p": 0.003}},
                                   {"config": "original", "params": {"e_p": 0.003}}])
    assert [r["params"]["e_p"] for r in asked] == [0.002, 0.003]
