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
            ground_run._requests("original", "takeoff", [], [], [], psi, lateral, *no_kick, {})
        assert text in str(err.value)
    request = ground_run._requests("original", "takeoff", [], [], [], 0.02, 2.0, *no_kick, {})[0]
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
            ground_run._requests("original", "takeoff", [], [], [], 0.01, 1.0, *kick, {})
        assert text in str(err.value)
    request = ground_run._requests("nes", "runway_joint", [], [], [], 0.01, 1.0, "dpsi", 2.0, "speed", 50.0, {})[0]
    assert request["preset"] == "takeoff"  # the page sends the scenario's preset and the boxes' kick
    assert (request["kick"], request["kick_size"], request["kick_at_speed"]) == ("dpsi", 2.0, 50.0)
    assert ground_run.scenario_kick("touchdown_yaw")[:4] == ("psi", 0.05, "time", 0.0)
    assert ground_run.kick_outcome(None) == "– (no kick)"
