"""Service pieces without a server: canonical requests, cache keys, the URL design state."""

import pytest

from shimmy.errors import InvalidParameterError
from shimmy.model.parameters import Parameters
from shimmy.service import cache, schemas


def test_canonical_request_fills_defaults_and_the_whole_design():
    req = schemas.validate("simulate", {"config": "nes", "V": 30, "Fz": 150000})
    assert req["t_end"] == 60.0 and req["include_series"] is False
    assert req["params"] == Parameters().to_dict()
    tungsten = schemas.validate("simulate", {"config": "nes", "V": 30, "Fz": 150000, "material": "tungsten"})
    assert tungsten["params"]["rho_p"] == 16500 and "material" not in tungsten


def test_equal_questions_have_equal_cache_keys():
    a = schemas.validate("hopf", {"config": "nes", "Fz": 150000, "params": {"r2": 0.08}})
    b = schemas.validate("hopf", {"config": "nes", "Fz": 150000.0, "v_min": 1, "params": {}})
    c = schemas.validate("hopf", {"config": "nes", "Fz": 150000, "params": {"r2": 0.081}})
    assert cache.key("hopf", a) == cache.key("hopf", b) != cache.key("hopf", c)
    assert cache.key("hopf", a) != cache.key("stability", a)


@pytest.mark.parametrize("body,field", [
    ({"config": "nes", "V": 30, "Fz": 150000, "params": {"r2": 0.2}}, "params.r2"),
    ({"config": "nes", "V": 30, "Fz": 150000, "params": {"n": 2.5}}, "params.n"),
    ({"config": "nes", "V": 30, "Fz": 150000, "params": {"zz": 1}}, "params.zz"),
    ({"config": "nes", "V": 30, "Fz": 150000, "t_end": 601}, "t_end"),
    ({"config": "nes", "V": 30, "Fz": 150000, "exact_nes": "yes"}, "exact_nes"),
    ({"config": "nes", "V": 30, "Fz": 150000, "material": 3}, "material"),
])
def test_refusals_name_the_field(body, field):
    with pytest.raises(InvalidParameterError) as info:
        schemas.validate("simulate", body)
    assert info.value.field == field


def test_openapi_fields_match_the_schemas():
    from shimmy.service.api import openapi_document

    doc = openapi_document()
    for name in ("simulate", "hopf", "stability", "devices"):
        props = doc["components"]["schemas"][f"{name}_request"]["properties"]
        assert set(props) == {f.name for f in schemas.SCHEMAS[name].fields}
    for name in schemas.JOB_ANALYSES:
        assert doc["components"]["schemas"][f"job_{name}"]["properties"]["analysis"]["enum"] == [name]


def test_url_design_state_round_trip_and_bad_keys():
    from ui import state

    material, values, problems = state.design_from_query({"r2": "0.085", "material": "tungsten", "V": "30"})
    assert material == "tungsten" and values["r2"] == 0.085 and values["rho_p"] == 16500 and not problems
    query = state.design_query(material, values)
    assert query == {"material": "tungsten", "r2": "0.085"}
    assert state.design_request(material, values) == {"material": "tungsten", "params": {"r2": 0.085}}
    material, values, problems = state.design_from_query({"r2": "9", "e_p": "x", "material": "gold"})
    assert material == "steel" and values["r2"] == 0.08 and len(problems) == 3
