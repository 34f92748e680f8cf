"""The pages' fields (ui/fields.py): limits from the request schemas, refusals in the unit shown,
nothing replaced by a default without a word; and the small definitions the pages rely on."""

import pytest

from shimmy.errors import InvalidParameterError
from shimmy.model.configurations import affects
from shimmy.service import schemas
from ui import fields, formats
from ui.fields import Quantity

FZ = Quantity("bifurcation", "Fz", "Fz", "kN", 1e3)
SLICES = Quantity("map", "resolution", "Fz slices", "")
T_END = Quantity("simulate", "t_end", "simulated time", "s")


def test_limits_come_from_the_schema_in_the_unit_shown():
    assert (FZ.low, FZ.high) == (10, 900) and FZ.allowed == "a number in [10, 900] kN"
    assert (SLICES.low, SLICES.high) == (2, schemas.SCHEMAS["map"].field("resolution").high) == (2, 80)
    assert (T_END.low, T_END.high) == (0.1, 600)


@pytest.mark.parametrize("quantity, value, message", [
    (FZ, 5, "Fz = 5 kN is outside [10, 900] kN"),
    (FZ, 5000, "Fz = 5000 kN is outside [10, 900] kN"),
    (FZ, None, "Fz is empty or not a number; enter a number in [10, 900] kN"),
    (FZ, "abc", "Fz = abc is not a number; enter a number in [10, 900] kN"),
    (FZ, float("nan"), "Fz = nan is not finite; enter a number in [10, 900] kN"),
    (SLICES, 1, "Fz slices = 1 is outside [2, 80]"),
    (SLICES, 2.5, "Fz slices = 2.5 is not a whole number; enter an integer in [2, 80]"),
    (SLICES, 1000, "Fz slices = 1000 is outside [2, 80]"),
    (T_END, 0, "simulated time = 0 s is outside [0.1, 600] s"),
    (T_END, 100000, "simulated time = 100000 s is outside [0.1, 600] s"),
])
def test_refusals_quote_what_was_typed_in_its_unit(quantity, value, message):
    with pytest.raises(InvalidParameterError, match=r"^" + message.replace("[", r"\[").replace("]", r"\]") + "$"):
        quantity.read(value)


def test_accepted_values_come_back_in_si_units():
    assert FZ.read(150) == 150e3
    assert SLICES.read(40.0) == 40 and isinstance(SLICES.read(40.0), int)


def test_address_values_are_refused_with_a_reason_never_replaced_silently():
    assert FZ.from_url("Fz", None, 150) == (150, None)
    assert FZ.from_url("Fz", "200", 150) == (200.0, None)
    value, why = FZ.from_url("Fz", "5000", 150)
    assert value == 5000 and why == "The address gives Fz=5000: Fz = 5000 kN is outside [10, 900] kN."
    value, why = FZ.from_url("V", "abc", 30)
    assert value is None and "V=abc, which is not a number" in why
    assert fields.choice("config", "foo", ["original", "nes"], "nes", "a configuration") == (
        "nes", "The address gives config=foo, which is not a configuration (original, nes); showing nes.")
    chosen, why = fields.choices_list("configs", "nes,bar", ["original", "nes"], ["original"], "a configuration")
    assert chosen == ["nes"] and "bar is not a configuration" in why


def test_percentages_and_signed_numbers_never_read_minus_zero():
    assert formats.signed_percent(-0.0001, 3) == "0.000 %" and formats.signed_percent(-0.04, 1) == "0.0 %"
    assert formats.signed_percent(1.23456, 1) == "+1.2 %" and formats.signed_percent(-9.8, 1) == "-9.8 %"
    assert formats.signed(-0.0) == "0" and formats.signed(1.1234) == "+1.12"


def test_each_number_format_is_one_named_function():
    """The tables' significant digits, the comparisons' whole numbers, the short exponents of the slider ends."""
    assert formats.significant(11300.0) == "1.13e+04" and formats.significant(None) == "–"
    assert formats.significant_or_whole(11300.0) == "11300" and formats.significant_or_whole(0.012345) == "0.01235"
    assert formats.signed_or_whole(1250.4) == "+1250" and formats.signed_or_whole(-0.0001234) == "-0.000123"
    assert formats.compact(1.4e6) == "1.4e6" and formats.compact(2.5e-7) == "2.5e-7" and formats.compact(0.08) == "0.08"


def test_a_device_parameter_affects_only_the_configurations_with_that_device():
    assert [c for c in ("original", "nes", "pd", "nes_pd") if affects("e_p", c)] == ["nes", "nes_pd"]
    assert [c for c in ("original", "nes", "pd", "nes_pd") if affects("a_p", c)] == ["pd", "nes_pd"]
    assert all(affects("k_psi", c) for c in ("original", "nes", "pd", "nes_pd"))
    with pytest.raises(InvalidParameterError, match="unknown parameter 'zeta'"):
        affects("zeta", "nes")


def test_simulate_takes_a_start_and_reports_it():
    from shimmy.service import analyses

    request = schemas.validate("simulate", {"config": "original", "V": 50, "Fz": 850e3, "t_end": 2, "psi0": 0.2})
    assert request["psi0"] == 0.2 and request["lateral0"] == 0.0
    result = analyses.simulate(request)
    assert result["start"] == {"psi0": 0.2, "lateral0": 0.0}
    with pytest.raises(InvalidParameterError, match=r"psi0=0.6 is out of range; allowed: a number in \[-0.5, 0.5\]"):
        schemas.validate("simulate", {"config": "original", "V": 50, "Fz": 850e3, "psi0": 0.6})


def test_ground_run_thresholds_are_refused_in_the_boxes_unit_never_defaulted():
    import app  # noqa: F401 - registers the pages
    from pages import ground_run

    no_kick = ("none", None, "time", None)
    for psi, lateral, text in ((None, 1.0, "threshold |psi| is empty"), (0.01, 5000.0, "5000 mm is outside")):
        with pytest.raises(InvalidParameterError) as err:
            ground_run._requests("original", "takeoff", [], [], [], psi, lateral, "cubic", *no_kick, {})
        assert text in str(err.value)
    request = ground_run._requests("original", "takeoff", [], [], [], 0.02, 2.0, "cubic", *no_kick, {})[0]
    assert request["psi_threshold"] == 0.02 and request["lateral_threshold"] == pytest.approx(0.002)
    assert "kick" not in request


def test_ground_run_kick_boxes_are_refused_in_their_unit_and_a_scenario_fills_them():
    import app  # noqa: F401 - registers the pages
    from pages import ground_run

    for kick, text in ((("psi", 0.8, "time", 3.0), "kick size (yaw angle psi) = 0.8 rad is outside [-0.5, 0.5] rad"),
                       (("dpsi", 80, "time", 3.0), "= 80 rad/s is outside [-50, 50] rad/s"),
                       (("dpsi", None, "time", 3.0), "kick size (yaw rate dpsi) is empty"),
                       (("psi", 0.1, "speed", "abc"), "the kick's speed = abc is not a number"),
                       (("psi", 0.1, "speed", 600), "the kick's speed = 600 m/s is outside [1, 500] m/s")):
        with pytest.raises(InvalidParameterError) as err:
            ground_run._requests("original", "takeoff", [], [], [], 0.01, 1.0, "cubic", *kick, {})
        assert text in str(err.value)
    request = ground_run._requests("nes", "runway_joint", [], [], [], 0.01, 1.0, "cubic", "dpsi", 2.0, "speed", 50.0,
                                   {})[0]
    assert request["preset"] == "takeoff"  # the page sends the scenario's preset and the boxes' kick
    assert (request["kick"], request["kick_size"], request["kick_at_speed"]) == ("dpsi", 2.0, 50.0)
    assert ground_run.scenario_kick("touchdown_yaw")[:4] == ("psi", 0.05, "time", 0.0)
    assert ground_run.kick_outcome(None) == "– (no kick)"
    assert ground_run.kick_size_refusal("psi", 0.8).startswith("the kick size (yaw angle psi) = 0.8 rad is outside")
    assert ground_run.kick_size_refusal("dpsi", 0.8) == "" and ground_run.kick_size_refusal("none", "abc") == ""
    assert "the kick's time = -1e+06 s is outside" in ground_run.kick_moment_refusal("psi", "time", -1e6)


def _number_boxes(component):
    """Every number box of a layout (a Dash component tree)."""
    from dash import dcc

    found = []

    def walk(c):
        if isinstance(c, dcc.Input) and getattr(c, "type", None) == "number":
            found.append(c)
        children = getattr(c, "children", None)
        for child in children if isinstance(children, (list, tuple)) else [children]:
            if child is not None and hasattr(child, "to_plotly_json"):
                walk(child)

    walk(component)
    return found


@pytest.mark.parametrize("module", ["ground_run", "time_history", "bifurcation", "stability_map", "study", "overview"])
def test_every_number_box_refuses_at_its_field_on_enter_or_leaving_it(module):
    """Each box of the page sends its value on Enter or blur (debounce) and has the line under it that a
    callback fills with the refusal, in the box's unit (the design panel's boxes have their own)."""
    import importlib

    import app  # noqa: F401 - registers the pages
    import dash

    page = importlib.import_module(f"pages.{module}")
    boxes = [b for b in _number_boxes(page.layout()) if isinstance(b.id, str)]
    assert boxes, module
    callbacks = {**app.app.callback_map, **dash._callback.GLOBAL_CALLBACK_MAP}
    outputs = {o for cb in callbacks for o in cb.strip(".").split("..")}
    for box in boxes:
        assert box.debounce is True, box.id
        assert f"{fields.error_id(box.id)}.children" in outputs, box.id


def test_a_ground_run_threshold_is_refused_at_its_box_in_its_unit():
    import app  # noqa: F401 - registers the pages
    from pages import ground_run

    assert fields.refusal(ground_run.PSI_THR.read, 5) == \
        "the shimmy threshold |psi| = 5 rad is outside [1e-06, 1] rad"
    assert fields.refusal(ground_run.LAT_THR.read, 5000) == \
        "the shimmy threshold |l_g delta| = 5000 mm is outside [0.0001, 1000] mm"
    assert fields.refusal(ground_run.PSI_THR.read, 0.02) == ""


def test_table_cells_are_refused_by_row_and_column_as_typed_in_the_columns_unit():
    import app  # noqa: F401 - registers the pages
    from pages import ground_run

    rows = [{"t": 0, "V": 10, "Fz": 150}, {"t": 1, "V": 600, "Fz": "abc"}, {"t": 2, "V": 20, "Fz": 5}]
    refused = fields.cell_refusals(rows, ground_run.PROFILE_COLUMNS)
    assert refused == [(1, "V", "row 2: V = 600 m/s is outside [1, 500] m/s"),
                       (1, "Fz", "row 2: Fz = abc is not a number; enter a number in [10, 900] kN"),
                       (2, "Fz", "row 3: Fz = 5 kN is outside [10, 900] kN")]
    message, marks = ground_run.check_table(rows)
    assert "row 2: V = 600 m/s" in message and {"row_index": 2, "column_id": "Fz"} in [m["if"] for m in marks]


def test_the_ground_run_settings_show_and_refuse_loads_in_kn():
    import app  # noqa: F401 - registers the pages
    from pages import ground_run

    rows = ground_run.preset_settings("takeoff")
    static = next(r for r in rows if r["name"] == "Fz_static")
    assert (static["value"], static["unit"], static["range"]) == (150.0, "kN", "20 – 900")
    assert ground_run._settings(rows)["Fz_static"] == 150e3  # the request keeps N
    static["value"] = 5000
    assert ground_run.preset_table(rows, None, "takeoff")[3] == "Fz_static = 5000 kN is outside [20, 900] kN"
    static["value"] = 150
    next(r for r in rows if r["name"] == "Fz_rotate")["value"] = 200
    assert ground_run.preset_table(rows, None, "takeoff")[3] == (
        "Fz_rotate = 200 kN is refused; allowed: a number up to Fz_static = 150 kN")


def test_a_preset_table_steps_by_exactly_its_dt():
    import numpy as np

    from shimmy.analyses.ground.ground_profiles import preset

    for name in ("takeoff", "landing", "taxi"):
        p = preset(name)
        steps = np.diff(p.t)
        assert np.allclose(steps[:-1], 0.5) and 0 < steps[-1] <= 0.5 + 1e-12, name
    assert preset("landing").t[-1] == pytest.approx((65 - 8) / 2.5)  # ends where the roll ends
